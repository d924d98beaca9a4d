//! Property test of the whole front end on broken programs: every program of
//! the corpus (examples/, tests/ui/, mcl-syntax/tests/bad/) is mutated at
//! random (bytes or tokens deleted, duplicated, swapped, keywords and braces
//! inserted), then parsed, checked with the salsa database exactly as `mcl
//! check` does (`check_file`: imports, names, tasks, patterns, missions,
//! constraints, block verification) and formatted. Nothing may panic, and
//! every diagnostic's span (and every label's in the same file) must lie in
//! the text, on character boundaries.
//!
//! One database serves every case (as the language server's does across
//! edits), so the checks of unchanged definitions are reused and the test
//! stays within a couple of seconds.

use mcl_compiler::{check_file, Database};
use mcl_syntax::gen::MUTATION_PIECES as PIECES;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The corpus: every `.mcl` file of these folders (not recursive).
fn corpus() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for dir in ["examples", "tests/ui", "mcl-syntax/tests/bad"] {
        let Ok(entries) = std::fs::read_dir(repo().join(dir)) else { continue };
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for p in paths {
            if p.extension().is_some_and(|x| x == "mcl") {
                if let Ok(text) = std::fs::read_to_string(&p) {
                    out.push((p.file_name().unwrap().to_string_lossy().into_owned(), text));
                }
            }
        }
    }
    assert!(out.len() > 20, "the corpus is there: {}", out.len());
    out
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete {
        at: usize,
        len: usize,
    },
    Duplicate {
        at: usize,
        len: usize,
    },
    Swap {
        a: usize,
        b: usize,
        len: usize,
    },
    Insert {
        at: usize,
        piece: usize,
    },
    /// Deletes the token-like run (word or punctuation) at `at`.
    DeleteWord {
        at: usize,
    },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = any::<prop::sample::Index>();
    prop_oneof![
        (pos.clone(), 1usize..12).prop_map(|(at, len)| Mutation::Delete { at: at.index(1 << 20), len }),
        (pos.clone(), 1usize..40).prop_map(|(at, len)| Mutation::Duplicate { at: at.index(1 << 20), len }),
        (pos.clone(), pos.clone(), 1usize..20).prop_map(|(a, b, len)| Mutation::Swap {
            a: a.index(1 << 20),
            b: b.index(1 << 20),
            len
        }),
        (pos.clone(), 0..PIECES.len()).prop_map(|(at, piece)| Mutation::Insert { at: at.index(1 << 20), piece }),
        pos.prop_map(|at| Mutation::DeleteWord { at: at.index(1 << 20) }),
    ]
}

/// The char boundary at or before `i` (clamped to the text).
fn floor(s: &str, i: usize) -> usize {
    let mut i = i % (s.len() + 1);
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(s: &str, m: &Mutation) -> String {
    let end = |at: usize, len: usize| floor(s, (at + len).min(s.len()));
    match *m {
        Mutation::Delete { at, len } => {
            let a = floor(s, at);
            let b = end(a, len);
            format!("{}{}", &s[..a], &s[b..])
        }
        Mutation::Duplicate { at, len } => {
            let a = floor(s, at);
            let b = end(a, len);
            format!("{}{}{}", &s[..b], &s[a..b], &s[b..])
        }
        Mutation::Swap { a, b, len } => {
            let (a, b) = (floor(s, a), floor(s, b));
            let (a, b) = (a.min(b), a.max(b));
            let a2 = end(a, len).min(b);
            let b2 = end(b, len);
            format!("{}{}{}{}{}", &s[..a], &s[b..b2], &s[a2..b], &s[a..a2], &s[b2..])
        }
        Mutation::Insert { at, piece } => {
            let a = floor(s, at);
            format!("{} {} {}", &s[..a], PIECES[piece], &s[a..])
        }
        Mutation::DeleteWord { at } => {
            let a = floor(s, at);
            let word = |c: char| c.is_alphanumeric() || c == '_';
            let b = a + s[a..]
                .find(|c: char| !word(c))
                .unwrap_or(s.len() - a)
                .max(s[a..].chars().next().map_or(0, char::len_utf8));
            format!("{}{}", &s[..a], &s[b.min(s.len())..])
        }
    }
}

fn assert_span_ok(text: &str, what: &str, start: u32, end: u32) -> Result<(), TestCaseError> {
    let (s, e) = (start as usize, end as usize);
    prop_assert!(s <= e && e <= text.len(), "{what}: span {s}..{e} outside a text of {} bytes", text.len());
    prop_assert!(text.is_char_boundary(s) && text.is_char_boundary(e), "{what}: span {s}..{e} not on char boundaries");
    Ok(())
}

#[test]
fn mutated_corpus_never_panics_and_spans_stay_in_the_text() {
    let corpus = corpus();
    let vehicle = std::fs::read_to_string(repo().join("examples/vehicle.mcl")).unwrap();
    let dir = if cfg!(windows) { PathBuf::from(r"C:\mcl-mutated") } else { PathBuf::from("/mcl-mutated") };
    let mut db = Database::new();
    db.set_text(&dir.join("vehicle.mcl"), vehicle.as_str());
    let mut runner = TestRunner::new(Config { cases: 160, failure_persistence: None, ..Config::default() });
    let strategy = (0..corpus.len(), prop::collection::vec(mutation(), 1..4));
    let db = std::cell::RefCell::new(db);
    let result = runner.run(&strategy, |(which, mutations)| {
        let mut db = db.borrow_mut();
        let (name, original) = &corpus[which];
        let mut text = original.clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        // The syntax layer alone, then the formatter (refuses or formats).
        let parsed = mcl_syntax::parse(&text);
        for d in &parsed.errors {
            assert_span_ok(&text, &format!("{name}: syntax {}", d.code), d.span.start, d.span.end)?;
        }
        let _ = mcl_syntax::format::format(&text);
        // The whole check, as `mcl check` runs it.
        let file = db.set_text(&dir.join("mission.mcl"), text.as_str());
        for fd in check_file(&*db, file).iter() {
            let t = fd.file.text(&*db).as_deref().unwrap_or("").to_string();
            let d = &fd.diag;
            assert_span_ok(&t, &format!("{name}: {} {}", d.code, d.message), d.span.start, d.span.end)?;
            for l in d.labels.iter().filter(|l| l.file.is_none()) {
                assert_span_ok(&t, &format!("{name}: label of {}", d.code), l.span.start, l.span.end)?;
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
}
