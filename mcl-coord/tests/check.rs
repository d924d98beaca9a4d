//! Coordination diagnostics (`mcl_coord::check`): E0408 for constraints
//! that conflict by construction, E0406 for constraints that
//! deadlock, W0407 when the analysis cannot conclude, nothing for a program
//! with errors or without constraints; the explanations of both codes (their
//! example triggers the code, their fix removes it), and the incremental
//! query.

use std::path::PathBuf;

use mcl_compiler::{codes, Database, FileDiagnostic};
use mcl_coord::check::{coordination_diagnostics, diagnostics_with};
use mcl_coord::verify::VerifyOptions;
use mcl_coord::AnalyzeOptions;
use mcl_syntax::Severity;

const VEHICLE: &str = include_str!("../../examples/vehicle.mcl");

fn dir(name: &str) -> PathBuf {
    let root = if cfg!(windows) { PathBuf::from(r"C:\mcl-coord-virtual") } else { PathBuf::from("/mcl-coord-virtual") };
    root.join(name)
}

fn db_with(name: &str, src: &str) -> (Database, mcl_compiler::SourceFile) {
    let mut db = Database::new();
    let d = dir(name);
    db.set_text(&d.join("vehicle.mcl"), VEHICLE);
    let f = db.set_text(&d.join("m.mcl"), src);
    (db, f)
}

fn text_at(src: &str, d: &FileDiagnostic) -> String {
    src[d.diag.span.start as usize..d.diag.span.end as usize].to_string()
}

const FIG_6_9A: &str = "import \"vehicle.mcl\";

mission : v1 {
    GotoTarget() : p2 ;
    Surface()
}

mission : v2 {
    Deploy() : p5 ;
    Surface()
}

constraints {
    order { v1:p2, v2:p5 }
    order { v2:p5, v1:p2 }
}
";

#[test]
fn figure_6_9a_in_mcl_is_an_error_on_both_orders_with_a_counterexample() {
    let (db, f) = db_with("fig69a", FIG_6_9A);
    assert!(mcl_compiler::check_file(&db, f).is_empty(), "the program itself is clean");
    let all = coordination_diagnostics(&db, f);
    // The orders conflict by construction (E0408, first), and the analysis
    // proves the deadlock (E0406).
    assert_eq!(
        all.iter().map(|d| d.diag.code).collect::<Vec<_>>(),
        [codes::CONFLICTING_CONSTRAINTS, codes::DEADLOCKING_CONSTRAINTS]
    );
    let c = &all[0].diag;
    assert_eq!(text_at(FIG_6_9A, &all[0]), "order { v1:p2, v2:p5 }");
    let labelled: Vec<&str> = c.labels.iter().map(|l| &FIG_6_9A[l.span.start as usize..l.span.end as usize]).collect();
    assert_eq!(labelled, ["order { v1:p2, v2:p5 }", "order { v2:p5, v1:p2 }"]);
    assert!(c.message.contains("constraints 1 and 2 conflict"), "{}", c.message);
    assert!(
        c.notes[0].contains("`v1:p2` ends before `v2:p5` starts, `v2:p5` ends before `v1:p2` starts"),
        "{:?}",
        c.notes
    );
    let diags = &all[1..];
    let d = &diags[0].diag;
    assert_eq!(d.code, codes::DEADLOCKING_CONSTRAINTS);
    assert_eq!(d.severity, Severity::Error);
    assert!(d.message.contains("`v1:p2`") && d.message.contains("`v2:p5`"), "{}", d.message);
    // Primary span: the first order; a label on each order.
    assert_eq!(text_at(FIG_6_9A, &diags[0]), "order { v1:p2, v2:p5 }");
    let labelled: Vec<&str> = d.labels.iter().map(|l| &FIG_6_9A[l.span.start as usize..l.span.end as usize]).collect();
    assert_eq!(labelled, ["order { v1:p2, v2:p5 }", "order { v2:p5, v1:p2 }"]);
    assert!(d.labels[0].message.contains("constraint 1 holds `v2:p5`"), "{:?}", d.labels);
    assert!(d.labels[1].message.contains("constraint 2 holds `v1:p2`"), "{:?}", d.labels);
    // Notes: the calls reached, and who waits for whom.
    let notes = d.notes.join("\n");
    assert!(notes.contains("counterexample:"), "{notes}");
    assert!(notes.contains("v1 `GotoTarget() : p2` is reached"), "{notes}");
    assert!(notes.contains("v2 `Deploy() : p5` is reached"), "{notes}");
    assert!(notes.contains("`v1` waits at `v1:p2` (held by constraint 2)"), "{notes}");
    assert!(notes.contains("`v2` waits at `v2:p5` (held by constraint 1)"), "{notes}");
    assert!(notes.contains("no supervisor can avoid it"), "{notes}");
    assert!(d.help.as_deref().is_some_and(|h| h.contains("one of these constraints")), "{:?}", d.help);
}

#[test]
fn one_order_is_free_and_editing_the_file_updates_the_query() {
    let fixed = FIG_6_9A.replace("    order { v2:p5, v1:p2 }\n", "");
    let (mut db, f) = db_with("edit", &fixed);
    assert!(coordination_diagnostics(&db, f).is_empty());
    // The editor's path: the same database, new text.
    db.set_text(&dir("edit").join("m.mcl"), FIG_6_9A);
    let diags = coordination_diagnostics(&db, f);
    assert_eq!(
        diags.iter().map(|d| d.diag.code).collect::<Vec<_>>(),
        [codes::CONFLICTING_CONSTRAINTS, codes::DEADLOCKING_CONSTRAINTS]
    );
    db.set_text(&dir("edit").join("m.mcl"), fixed.as_str());
    assert!(coordination_diagnostics(&db, f).is_empty());
}

#[test]
fn an_order_on_a_call_that_a_failure_skips_deadlocks() {
    // v1 may fail at Surface() and end without running p2: v2 waits for ever.
    let src = "import \"vehicle.mcl\";
mission : v1 { Surface() ; GotoTarget() : p2 }
mission : v2 { Deploy() : p5 }
constraints { order { v1:p2, v2:p5 } }
";
    let (db, f) = db_with("skip", src);
    let diags = coordination_diagnostics(&db, f);
    assert_eq!(diags.len(), 1, "{diags:#?}");
    let d = &diags[0].diag;
    assert_eq!(text_at(src, &diags[0]), "order { v1:p2, v2:p5 }");
    assert_eq!(d.labels.len(), 1);
    let notes = d.notes.join("\n");
    assert!(notes.contains("v1 `Surface()` fails"), "{notes}");
    assert!(notes.contains("`v1` has ended"), "{notes}");
    assert!(notes.contains("`v2` waits at `v2:p5` (held by constraint 1)"), "{notes}");
}

#[test]
fn nothing_without_constraints_or_with_errors() {
    let (db, f) = db_with("none", "import \"vehicle.mcl\";\nmission : v1 { Surface() }\n");
    assert!(coordination_diagnostics(&db, f).is_empty());
    // An unknown label is the checker's E0402, not a coordination problem.
    let bad = FIG_6_9A.replace("order { v2:p5, v1:p2 }", "order { v2:p6, v1:p2 }");
    let (db, f) = db_with("errors", &bad);
    assert!(mcl_compiler::check_file(&db, f).iter().any(|d| d.diag.code == codes::UNKNOWN_LABEL));
    assert!(coordination_diagnostics(&db, f).is_empty());
}

#[test]
fn a_cap_reached_is_a_warning_on_the_constraints_block() {
    let src = codes::lookup("W0407").map(|c| example(c.explanation, "Example")).unwrap();
    let (db, f) = db_with("w0407", &src);
    let diags = diagnostics_with(&db, f, &small_caps());
    assert_eq!(diags.len(), 1, "{diags:#?}");
    let d = &diags[0].diag;
    assert_eq!((d.code, d.severity), (codes::COORDINATION_INCONCLUSIVE, Severity::Warning));
    assert_eq!(text_at(&src, &diags[0]), "constraints");
    assert!(d.notes.iter().any(|n| n.contains("more than 25000 states")), "{:?}", d.notes);
}

/// Caps small enough for the W0407 example to reach them.
fn small_caps() -> AnalyzeOptions {
    AnalyzeOptions {
        verify: VerifyOptions { max_product_states: 25_000, ..VerifyOptions::default() },
        structure: false,
        ..AnalyzeOptions::default()
    }
}

/// The one ```mcl block of a `## name` section.
fn example(md: &str, name: &str) -> String {
    let start = md.find(&format!("\n## {name}\n")).unwrap_or_else(|| panic!("no ## {name}"));
    let rest = &md[start + 1..];
    let rest = &rest[rest.find("```mcl\n").expect("an mcl block") + 7..];
    rest[..rest.find("```").expect("closed block")].to_string()
}

#[test]
fn explanations_examples_trigger_and_fixes_remove_their_code() {
    for &code in codes::COORDINATION {
        let info = codes::lookup(code).unwrap();
        // W0407's example passes the default caps after 4 million states:
        // it is checked with small ones, to run fast (see its Notes).
        let opts = if code == codes::COORDINATION_INCONCLUSIVE {
            small_caps()
        } else {
            AnalyzeOptions { structure: false, ..AnalyzeOptions::default() }
        };
        for (section, expect) in [("Example", true), ("Fix", false)] {
            let src = example(info.explanation, section);
            let (db, f) = db_with(&format!("{code}-{section}"), &src);
            let plain = mcl_compiler::check_file(&db, f);
            assert!(plain.is_empty(), "{code} {section}: {plain:#?}");
            let diags = diagnostics_with(&db, f, &opts);
            assert_eq!(diags.iter().any(|d| d.diag.code == code), expect, "{code} {section}: {diags:#?}");
            if !expect {
                assert!(diags.is_empty(), "{code} {section}: {diags:#?}");
            }
        }
    }
}

#[test]
fn appendix_c_constraints_are_analysed_and_free() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/appendix-c.mcl");
    let db = Database::new();
    let f = mcl_compiler::Db::file(&db, &path);
    let (ms, cs) = mcl_coord::source::load(&db, f).expect("appendix-c.mcl compiles");
    assert_eq!((ms.len(), cs.len()), (2, 3));
    let r =
        mcl_coord::analyze_with(&ms, &cs, &AnalyzeOptions { structure: false, ..AnalyzeOptions::default() }).unwrap();
    assert_eq!(r.verdict, mcl_coord::Verdict::Free, "{:#?}", r.problems);
    assert!(coordination_diagnostics(&db, f).is_empty());
}

#[test]
fn conflicts_by_construction_point_at_each_constraint() {
    // A sync with a mutex of bound 1 on the same calls; an order inside a
    // sync (a cycle of one order); and a longer cycle through a sync.
    let src = "import \"vehicle.mcl\";
mission : auv { SendData() : s ; Surface() : a ; Surface() : b }
mission : asc { ReceiveData() : s ; StopVehicle() : c }
constraints {
    sync { auv:s, asc:s }
    mutex { auv:s, asc:s } = 1
    order { auv:s, asc:s }
    order { auv:b, asc:c }
    sync { asc:c, auv:a }
    order { auv:a, auv:b }
    mutex { auv:s, asc:s } = 2
}
";
    let (db, f) = db_with("conflicts", src);
    assert!(mcl_compiler::check_file(&db, f).is_empty());
    let diags = coordination_diagnostics(&db, f);
    let e: Vec<&FileDiagnostic> = diags.iter().filter(|d| d.diag.code == codes::CONFLICTING_CONSTRAINTS).collect();
    assert_eq!(e.len(), 3, "{e:#?}");
    let labels = |d: &FileDiagnostic| -> Vec<String> {
        d.diag.labels.iter().map(|l| src[l.span.start as usize..l.span.end as usize].to_string()).collect()
    };
    // Sync and mutex (the bound 2 mutex is fine).
    assert_eq!(e[0].diag.severity, Severity::Error);
    assert_eq!(text_at(src, e[0]), "sync { auv:s, asc:s }");
    assert_eq!(labels(e[0]), ["sync { auv:s, asc:s }", "mutex { auv:s, asc:s } = 1"]);
    assert!(e[0].diag.message.contains("constraints 1 and 2 conflict"), "{}", e[0].diag.message);
    // An order between two calls of a sync.
    assert_eq!(labels(e[1]), ["sync { auv:s, asc:s }", "order { auv:s, asc:s }"]);
    assert!(e[1].diag.notes[0].contains("calls of a sync start together"), "{:?}", e[1].diag.notes);
    // Two orders and a sync.
    assert_eq!(labels(e[2]), ["order { auv:b, asc:c }", "sync { asc:c, auv:a }", "order { auv:a, auv:b }"]);
    assert!(e[2].diag.message.contains("constraints 4, 5 and 6 conflict"), "{}", e[2].diag.message);
    // Without them, nothing conflicts.
    let fine = "import \"vehicle.mcl\";
mission : auv { SendData() : s ; Surface() : a }
mission : asc { ReceiveData() : s ; StopVehicle() : c }
constraints {
    sync { auv:s, asc:s }
    mutex { auv:s, asc:s } = 2
    order { auv:s, asc:c }
}
";
    let (db, f) = db_with("no-conflicts", fine);
    assert!(coordination_diagnostics(&db, f).iter().all(|d| d.diag.code != codes::CONFLICTING_CONSTRAINTS));
}
