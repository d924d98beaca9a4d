//! Incrementality, observed through salsa's event log: after an edit inside
//! one mission, only that mission is parsed and checked again; the other
//! items' checks and the building-block verifications are reused, and the
//! diagnostics are those of a fresh analysis.

use mcl_compiler::{check_file, Database, FileDiagnostic};
use salsa::{Database as _, EventKind};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// The queries executed (by name) while `f` runs.
#[allow(clippy::type_complexity)]
fn executed(
    db: &mut Database,
    log: &Arc<Mutex<Vec<salsa::DatabaseKeyIndex>>>,
    f: impl FnOnce(&mut Database),
) -> Vec<String> {
    log.lock().unwrap().clear();
    f(db);
    let keys = std::mem::take(&mut *log.lock().unwrap());
    keys.iter().map(|k| db.ingredient_debug_name(k.ingredient_index()).to_string()).collect()
}

fn count(names: &[String], q: &str) -> usize {
    names.iter().filter(|n| n.as_str() == q).count()
}

fn logged_db() -> (Database, Arc<Mutex<Vec<salsa::DatabaseKeyIndex>>>) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let l = log.clone();
    let db = Database::with_events(move |e| {
        if let EventKind::WillExecute { database_key } = e.kind {
            l.lock().unwrap().push(database_key);
        }
    });
    (db, log)
}

fn fresh(path: &Path, text: &str) -> Vec<FileDiagnostic> {
    let mut db = Database::new();
    let f = db.set_text(path, text.to_string());
    check_file(&db, f).clone()
}

fn shown(d: &[FileDiagnostic]) -> Vec<mcl_syntax::Diagnostic> {
    d.iter().map(|x| x.diag.clone()).collect()
}

#[test]
fn an_edit_inside_a_mission_reuses_the_other_items() {
    let text = mcl_syntax::gen::program(600, 3);
    let missions = text.matches("\nmission").count();
    assert!(missions >= 5, "the generated program has missions");
    let path = Path::new("/incremental/program.mcl");
    let (mut db, log) = logged_db();
    let f = db.set_text(path, text.clone());
    let first = executed(&mut db, &log, |db| {
        check_file(db, f);
    });
    assert!(count(&first, "task_verdict") > 0, "blocks are verified: {first:?}");
    assert!(count(&first, "check_item") > missions);

    // One character inserted inside a mission's body (not the first one, so
    // that everything after it moves).
    let at = text.match_indices("\nmission").nth(2).unwrap().0 + 1;
    let at = at + text[at..].find('{').unwrap() + 1;
    let mut edited = text.clone();
    edited.insert(at, ' ');
    let second = executed(&mut db, &log, |db| {
        db.set_text(path, edited.clone());
        check_file(db, f);
    });
    assert_eq!(count(&second, "parse_item"), 1, "only the edited mission is parsed again: {second:?}");
    // The edited mission, and the constraints block (it reads every mission).
    assert_eq!(count(&second, "check_item"), 2, "only the edited mission is checked again: {second:?}");
    assert_eq!(count(&second, "task_verdict"), 0, "no block is verified again: {second:?}");
    assert_eq!(count(&second, "check_definitions"), 0, "definitions are not checked again: {second:?}");
    assert_eq!(count(&second, "local_scope"), 0, "the scope is not rebuilt: {second:?}");
    assert_eq!(shown(check_file(&db, f)), shown(&fresh(path, &edited)));

    // A call renamed to an unknown task: one new error, still one item checked.
    let call = edited[at..].find("    ").unwrap() + at + 4;
    let mut broken = edited.clone();
    broken.insert(call, 'Q');
    let third = executed(&mut db, &log, |db| {
        db.set_text(path, broken.clone());
        check_file(db, f);
    });
    assert_eq!(count(&third, "check_item"), 2, "{third:?}");
    assert_eq!(count(&third, "task_verdict"), 0, "{third:?}");
    let now = shown(check_file(&db, f));
    assert_eq!(now, shown(&fresh(path, &broken)));
    assert!(now.iter().any(|d| d.code == "E0101"), "{now:?}");
}

#[test]
fn a_comment_after_the_tasks_keeps_the_scope() {
    let text = mcl_syntax::gen::program(600, 5);
    let path = Path::new("/incremental/tasks.mcl");
    let (mut db, log) = logged_db();
    let f = db.set_text(path, text.clone());
    check_file(&db, f);
    // A comment added after the tasks block (in its part of the file): the
    // part's text changes, its definitions do not: the scope stays equal
    // (what reads the block's tasks, verdicts and calls, runs again).
    let tasks = text.find("tasks {").unwrap();
    let at = tasks + text[tasks..].find("\n}").unwrap() + 2;
    let mut edited = text.clone();
    edited.insert_str(at, " // note");
    let names = executed(&mut db, &log, |db| {
        db.set_text(path, edited.clone());
        check_file(db, f);
    });
    assert_eq!(count(&names, "local_scope"), 0, "{names:?}");
    assert_eq!(shown(check_file(&db, f)), shown(&fresh(path, &edited)));
}
