//! Parsing item by item (what the compiler's incremental queries do) gives
//! exactly what parsing the whole file gives: the same tree, comments and
//! errors, on the corpus, on generated programs and on random damage to them.

use mcl_syntax::{parse, parse_by_items, split_items};
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::Path;

fn corpus() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut out = Vec::new();
    for dir in ["examples", "examples/planning", "tests/ui", "mcl-syntax/tests/bad", "mcl-compiler/std"] {
        let Ok(rd) = std::fs::read_dir(root.join(dir)) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            if p.extension().is_some_and(|x| x == "mcl") {
                out.push((p.display().to_string(), std::fs::read_to_string(&p).unwrap()));
            }
        }
    }
    assert!(out.len() > 20, "corpus not found");
    out
}

fn same(src: &str) -> Result<(), String> {
    let whole = parse(src);
    let items = parse_by_items(src);
    if whole != items {
        return Err(format!("item-by-item parse differs\nwhole: {:#?}\nitems: {:#?}", whole.errors, items.errors));
    }
    Ok(())
}

#[test]
fn corpus_parses_the_same_item_by_item() {
    for (name, text) in corpus() {
        if let Err(e) = same(&text) {
            panic!("{name}: {e}");
        }
    }
}

#[test]
fn items_cover_the_file() {
    let text = mcl_syntax::gen::program(400, 7);
    let b = split_items(&text);
    assert_eq!(b[0].start, 0);
    assert_eq!(b.last().unwrap().end, text.len());
    for w in b.windows(2) {
        assert_eq!(w[0].end, w[1].start);
        assert!(w[0].next.is_some());
    }
    // The prelude, then one part per item of the parse.
    assert_eq!(b.len(), parse(&text).file.items.len() + 1);
}

#[test]
fn a_missing_brace_is_one_error_item_by_item() {
    let src = "events { a; b; }\nmission : m {\n    Goto( 1 ) \nmission : n { Goto( 2 ) }\n";
    let p = parse_by_items(src);
    assert_eq!(p, parse(src));
    assert_eq!(p.errors.len(), 1, "{:#?}", p.errors);
    assert_eq!(p.errors[0].code, "E0011");
}

/// Damage: delete, insert or replace a short range with text that matters to
/// the parser (delimiters, keywords, quotes, comment markers).
fn damaged() -> impl Strategy<Value = String> {
    let pieces = prop::sample::select(vec![
        "",
        "{",
        "}",
        "(",
        ")",
        "[",
        "]",
        ";",
        "\"",
        "/*",
        "*/",
        "//",
        "mission",
        "tasks {",
        "mission : x {",
        "import",
        "events",
        ",",
        ":",
        "->",
        "x",
        " ",
        "\n",
        "é",
        "constraints {",
        "mcl_plan_op",
        "5",
    ]);
    (0u64..40, 50usize..400, prop::collection::vec((any::<prop::sample::Index>(), 0usize..6, pieces), 1..4)).prop_map(
        |(seed, lines, edits)| {
            let mut s = mcl_syntax::gen::program(lines, seed);
            for (at, del, ins) in edits {
                let mut i = at.index(s.len() + 1);
                while !s.is_char_boundary(i) {
                    i -= 1;
                }
                let mut j = (i + del).min(s.len());
                while !s.is_char_boundary(j) {
                    j += 1;
                }
                s.replace_range(i..j, ins);
            }
            s
        },
    )
}

proptest! {
    #![proptest_config(Config { cases: 300, failure_persistence: None, ..Config::default() })]

    #[test]
    fn damaged_programs_parse_the_same_item_by_item(src in damaged()) {
        if let Err(e) = same(&src) {
            prop_assert!(false, "{}\n--- source ---\n{}", e, src);
        }
    }
}
