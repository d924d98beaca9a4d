//! The language server's features on deeply nested documents. The server
//! answers requests on tokio's blocking threads, whose stacks are 2 MB: the
//! parser's nesting limit (E0016) must keep every feature (diagnostics,
//! hover, navigation, completion, symbols, semantic tokens, formatting)
//! within such a stack, on text nested far too deep and on text nested just
//! below the limit.

use mcl_compiler::{check_file, Database};
use mcl_lsp::analysis::{completion, diagnostics, hover, navigation, outline, semantic, Analysis, DocInfo, World};
use std::path::PathBuf;
use tower_lsp_server::ls_types::Uri;

/// A task that does nothing (the standard library has its pattern).
const VOID: &str = "tasks { Void(): Instant { } Take( x ): Instant { } }\n";

fn world(path: &PathBuf) -> World {
    let mut w = World::default();
    let uri = Uri::from_file_path(path).unwrap();
    w.by_uri.insert(uri.as_str().to_string(), path.clone());
    w.docs.insert(path.clone(), DocInfo { uri, path: path.clone(), version: 1 });
    w
}

/// Runs every feature on `text`, at a few offsets; returns the codes of the
/// errors.
fn analyse(text: String) -> Vec<&'static str> {
    let path = PathBuf::from("/deep/nesting/mission.mcl");
    let w = world(&path);
    let mut db = Database::new();
    let f = db.set_text(&path, text.clone());
    let a = Analysis::new(&db, &w);
    // Errors only: the tasks of `VOID` may be unused (warnings).
    let codes: Vec<&'static str> =
        check_file(&db, f).iter().filter(|d| d.diag.is_error()).map(|d| d.diag.code).collect();
    let _ = diagnostics::full(&a, f);
    for at in [0, text.len() / 3, text.len() / 2, text.len().saturating_sub(8), text.len()] {
        let mut at = at;
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        let _ = hover::hover(&a, f, at);
        let _ = navigation::goto_definition(&a, f, at);
        let _ = navigation::references(&a, f, at, true);
        let _ = completion::completion(&a, f, at, true);
    }
    let _ = outline::document_symbols(&a, f);
    let _ = semantic::semantic_tokens(&a, f);
    let _ = mcl_syntax::format::format(&text);
    codes
}

/// Runs `analyse` on a thread with the stack of tokio's blocking pool.
fn on_a_small_stack(text: String) -> Vec<&'static str> {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || analyse(text))
        .expect("spawn")
        .join()
        .expect("the analysis ends normally")
}

#[test]
fn features_survive_nesting_far_too_deep() {
    // Far beyond what a 2 MB stack survives without the limit, and small
    // enough for the debug build's features to answer quickly.
    let n = 3_000;
    for (open, close) in [("{ ", " }"), ("not ( ", " )"), ("if ", " then { Void() }"), ("[", "]")] {
        let text = if open == "[" {
            format!("{VOID}mission {{ Take( {}1{} ) }}\n", open.repeat(n), close.repeat(n))
        } else {
            format!("{VOID}mission {{ {}Void(){} }}\n", open.repeat(n), close.repeat(n))
        };
        let codes = on_a_small_stack(text);
        assert_eq!(codes.iter().filter(|c| **c == "E0016").count(), 1, "{open}: {codes:?}");
        // A block `{ ... }` is no statement: that is the braces' own error.
        assert!(codes.iter().all(|c| *c == "E0016" || (open == "{ " && *c == "E0010")), "{open}: {codes:?}");
    }
}

#[test]
fn features_work_just_below_the_limit() {
    // 60 levels, the mission's body, a branch of the parallel, a call's
    // parentheses: 63.
    let depth = mcl_syntax::parser::MAX_NESTING - 4;
    let text = format!(
        "{VOID}mission {{\n{}Void() ; parallel {{ Void() }} and {{ Void() }}{}\n}}\n",
        "try { not ( ".repeat(depth / 2),
        " ) } catch { Void() }".repeat(depth / 2)
    );
    let codes = on_a_small_stack(text);
    assert!(codes.is_empty(), "{codes:?}");
}
