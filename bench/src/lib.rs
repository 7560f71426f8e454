//! leeway-bench: benchmarks that need the whole stack (the facade, its macros
//! and the runtime), kept out of the facade so that trybuild, which compiles
//! every dev-dependency of the facade, never builds criterion. The library
//! holds the model generators shared by the binaries (`gen-model`,
//! `fuzz-check`); the benchmarks are in `benches/`.

pub mod models;
