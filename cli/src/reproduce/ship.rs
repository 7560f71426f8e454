//! The paper's ship, compiled into the binary at build time (about 12×
//! faster than interpreting its IR).

#![allow(dead_code)] // the macro emits the whole API; the study uses the model only

leeway::include_model!("../../../examples/models/ship.som");

/// The model file the binary was built with.
pub const MODEL_FILE: &str = "examples/models/ship.som";
