//! Where the time of `check_file` goes on generated programs: lexing, the
//! item split, parsing every item, then the checks, each from scratch.
//! `cargo run --release -p mcl-compiler --example check_split [LINES...]`
//! (default 10000 100000). Prints the best of 5 runs of each phase.
use mcl_compiler::{check_file, Database};
use std::path::Path;
use std::time::{Duration, Instant};

fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed()
        })
        .min()
        .unwrap_or_default()
}

fn main() {
    // MCL_ONLY=check or MCL_ONLY=parse: loop on one phase (for a profiler).
    if let Ok(only) = std::env::var("MCL_ONLY") {
        let lines = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
        let text = mcl_syntax::gen::program(lines, 7);
        for _ in 0..20 {
            if only == "parse" {
                std::hint::black_box(mcl_syntax::parse(&text));
            } else {
                let mut db = Database::new();
                let f = db.set_text(Path::new("/virtual/gen.mcl"), text.as_str());
                std::hint::black_box(check_file(&db, f).len());
            }
        }
        return;
    }
    let args: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sizes = if args.is_empty() { vec![10_000, 100_000] } else { args };
    let empty = best(5, || (0..1000).map(|_| mcl_syntax::parse_item("", None).errors.len()).sum::<usize>());
    println!("parse_item of an empty text (grammar built, nothing parsed): {:.2?}", empty / 1000);
    for lines in sizes {
        let text = mcl_syntax::gen::program(lines, 7);
        let lex = best(5, || mcl_syntax::lexer::lex(&text).tokens.len());
        let split = best(5, || mcl_syntax::split_items(&text).len());
        let bounds = mcl_syntax::split_items(&text);
        let items = best(5, || {
            bounds.iter().map(|b| mcl_syntax::parse_item(&text[b.start..b.end], b.next).file.items.len()).sum::<usize>()
        });
        let whole = best(5, || mcl_syntax::parse(&text).file.items.len());
        let check = best(5, || {
            let mut db = Database::new();
            let f = db.set_text(Path::new("/virtual/gen.mcl"), text.as_str());
            check_file(&db, f).len()
        });
        println!(
            "{lines:>7} lines ({} items): lex {lex:.2?}, split {split:.2?}, parse items {items:.2?}, parse whole {whole:.2?}, check_file {check:.2?}",
            bounds.len()
        );
    }
}
