//! Prints the tree and errors of a file: `cargo run -p mcl-syntax --example dump FILE`.
fn main() {
    let path = std::env::args().nth(1).expect("usage: dump FILE");
    let text = std::fs::read_to_string(&path).expect("readable file");
    let p = mcl_syntax::parse(&text);
    if std::env::args().any(|a| a == "--tree") {
        println!("{:#?}", p.file);
    }
    let idx = mcl_syntax::LineIndex::new(&text);
    for e in &p.errors {
        let lc = idx.line_col(&text, e.span.start as usize);
        println!("{}:{}: {} {}: {} {:?}", lc.line, lc.column, e.severity.as_str(), e.code, e.message, e.help);
    }
    println!("{} items, {} errors", p.file.items.len(), p.errors.len());
}
