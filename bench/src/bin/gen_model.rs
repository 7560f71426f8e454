//! Prints a generated `.som` model (`leeway_bench::models`) on stdout, for
//! timing `leeway check` on large models:
//!
//! `cargo run --release -p leeway-bench --bin gen-model -- media 100 1 > m.som`
//!
//! Kinds: `states N [medium]`, `media N [UNMEASURED]`, `wide N`,
//! `constants N`, `repeated N`.

use leeway_bench::models;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: usize| -> usize {
        args.get(i).and_then(|a| a.parse().ok()).unwrap_or(default)
    };
    let text = match args.first().map(String::as_str) {
        Some("states") => models::many_states(number(1, 10_000), args.get(2).is_some()),
        Some("media") => models::many_media(number(1, 100), number(2, 1)),
        Some("wide") => models::wide_common(number(1, 500)),
        Some("constants") => models::many_constants(number(1, 500)),
        Some("repeated") => models::repeated_declarations(number(1, 4000)),
        _ => {
            eprintln!("usage: gen-model states|media|wide|constants|repeated N [..]");
            std::process::exit(2);
        }
    };
    print!("{text}");
}
