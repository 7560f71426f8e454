//! Compiles a model and prints the structure report and diagnostics.
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).cloned().unwrap_or_default();
    let aggregate = args.iter().any(|a| a == "--aggregate");
    let src = std::fs::read_to_string(&path).unwrap_or_default();
    let t = std::time::Instant::now();
    let c = leeway_structure::compile(
        &src,
        &leeway_structure::CompileOptions {
            aggregate,
            patterns: None,
            centring: None,
        },
    );
    let el = t.elapsed();
    if let Some(ir) = &c.ir {
        print!("{}", leeway_structure::render::render(ir));
    }
    print!(
        "{}",
        leeway_structure::grammar::render(
            &c.diagnostics,
            &path,
            &src,
            leeway_structure::grammar::RenderStyle::Plain
        )
    );
    eprintln!("compile: {el:?}");
}
