//! Formats standard input to standard output (for trying the layout by hand).
use std::io::Read;
fn main() {
    let mut s = String::new();
    if std::io::stdin().read_to_string(&mut s).is_err() {
        std::process::exit(2);
    }
    match leeway_format::format(&s) {
        Ok(t) => print!("{t}"),
        Err(d) => {
            eprintln!("{d:?}");
            std::process::exit(1)
        }
    }
}
