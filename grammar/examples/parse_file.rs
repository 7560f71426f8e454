//! Parses a file and prints the tree or the rendered error.
fn main() {
    let path = std::env::args().nth(1).unwrap_or_default();
    let src = std::fs::read_to_string(&path).unwrap_or_default();
    let (m, d) = leeway_grammar::parse(&src);
    if let Some(m) = m {
        println!("{} items", m.items.len());
    }
    print!(
        "{}",
        leeway_grammar::render(&d, &path, &src, leeway_grammar::RenderStyle::Plain)
    );
}
