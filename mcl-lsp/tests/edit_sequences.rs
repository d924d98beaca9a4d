//! Fuzzing the analysis with edit sequences, as an editor sends them: random
//! damage and repairs applied one after the other to one database. No edit
//! may panic any feature, and after the sequence the diagnostics are exactly
//! those of a fresh analysis of the final text (incremental = from scratch).

use mcl_compiler::{check_file, Database, Db};
use mcl_lsp::analysis::{completion, diagnostics, hover, navigation, outline, semantic, Analysis, DocInfo, World};
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::PathBuf;
use tower_lsp_server::ls_types::Uri;

type Edit = (prop::sample::Index, usize, &'static str);

/// One edit: replace `del` bytes at a position (a fraction of the text) with a piece.
fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let pieces = prop::sample::select(mcl_syntax::gen::EDIT_PIECES.to_vec());
    prop::collection::vec((any::<prop::sample::Index>(), 0usize..8, pieces), 1..12)
}

fn apply(text: &mut String, (at, del, ins): &Edit) -> usize {
    let mut i = at.index(text.len() + 1);
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    let mut j = (i + del).min(text.len());
    while !text.is_char_boundary(j) {
        j += 1;
    }
    text.replace_range(i..j, ins);
    i
}

fn world(path: &PathBuf) -> World {
    let mut w = World::default();
    let uri = Uri::from_file_path(path).unwrap();
    w.by_uri.insert(uri.as_str().to_string(), path.clone());
    w.docs.insert(path.clone(), DocInfo { uri, path: path.clone(), version: 1 });
    w
}

proptest! {
    #![proptest_config(Config { cases: 48, failure_persistence: None, ..Config::default() })]

    #[test]
    fn edit_sequences_match_a_fresh_analysis(seed in 0u64..20, lines in 40usize..160, seq in edits()) {
        let path = PathBuf::from("/fuzz/edits/program.mcl");
        let w = world(&path);
        let mut text = mcl_syntax::gen::program(lines, seed);
        let mut db = Database::new();
        let f = db.set_text(&path, text.clone());
        let _ = check_file(&db, f);
        for e in &seq {
            let at = apply(&mut text, e);
            db.set_text(&path, text.clone());
            let a = Analysis::new(&db, &w);
            let _ = diagnostics::syntax(&a, f);
            let _ = check_file(&db, f);
            // Requests at the edit, on the edited text.
            let _ = hover::hover(&a, f, at);
            let _ = navigation::goto_definition(&a, f, at);
            let _ = completion::completion(&a, f, at, true);
            let _ = outline::document_symbols(&a, f);
            let _ = semantic::semantic_tokens(&a, f);
        }
        let incremental: Vec<_> = check_file(&db, f).iter().map(|d| d.diag.clone()).collect();
        let mut fresh_db = Database::new();
        let g = fresh_db.set_text(&path, text.clone());
        let fresh: Vec<_> = check_file(&fresh_db, g).iter().map(|d| d.diag.clone()).collect();
        prop_assert_eq!(&incremental, &fresh, "final text:\n{}", text);
        // The whole-file view assembled from items is the parser's own result.
        prop_assert_eq!(mcl_compiler::parse(&db, f), &mcl_syntax::parse(&text));
        let a = Analysis::new(&db, &w);
        let b = Analysis::new(&fresh_db, &w);
        prop_assert_eq!(diagnostics::full(&a, f), diagnostics::full(&b, g));
        let _ = db.file(&path);
    }
}
