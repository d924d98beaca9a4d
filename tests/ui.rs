//! UI tests of `mcl check` through the real binary.
//!
//! Every `tests/ui/*.mcl` file (not the helper files of `tests/ui/multi/`)
//! is checked with `mcl check --color never tests/ui/NAME.mcl`, run from the
//! repository root so that the paths in the output are relative and stable,
//! and its standard output is compared with `tests/snapshots/ui__NAME.snap`.
//! Create or update the snapshots with `INSTA_UPDATE=always cargo test --test
//! ui` (or `cargo insta review`) and read each one: it must show the right
//! line, code and message.
//!
//! The other tests cover the exit status (0 with warnings only, 1 with
//! errors, 2 for a usage error), the JSON format of `--format json`, and that
//! every diagnostic code is exercised somewhere.

use mcl_compiler::codes;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root, canonical so that the binary's current folder and the
/// canonical paths of the files it reads share their prefix.
fn root() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    dir.canonicalize().unwrap_or(dir)
}

/// Runs `mcl ARGS` from the repository root.
fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(args)
        .current_dir(root())
        .env_remove("NO_COLOR")
        .env_remove("CLICOLOR_FORCE")
        .output()
        .expect("run the mcl binary")
}

fn status(o: &Output) -> i32 {
    o.status.code().expect("mcl exited normally")
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("stdout is UTF-8")
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("stderr is UTF-8")
}

/// Replaces the absolute path of the repository (which some messages show)
/// with `[ROOT]`, so that snapshots do not depend on where the checkout is.
fn redact(s: &str) -> String {
    let root = root().display().to_string();
    s.replace(&root, "[ROOT]").replace('\\', "/")
}

/// The UI inputs, sorted: `tests/ui/*.mcl`, by stem.
fn ui_cases() -> Vec<String> {
    let dir = root().join("tests/ui");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("tests/ui exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "mcl"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn snapshot_dir() -> PathBuf {
    root().join("tests/snapshots")
}

/// The text of every UI snapshot, by case name.
fn ui_snapshots() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(snapshot_dir()) else {
        return out;
    };
    for e in entries {
        let p = e.expect("readable entry").path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if let Some(case) = name.strip_prefix("ui__").and_then(|n| n.strip_suffix(".snap")) {
            out.push((case.to_string(), std::fs::read_to_string(&p).expect("readable snapshot")));
        }
    }
    out.sort();
    out
}

#[test]
fn ui_snapshots_match() {
    let cases = ui_cases();
    assert!(cases.len() >= codes::ALL.len(), "expected at least one UI case per code, found {}", cases.len());
    let mut failures = Vec::new();
    for name in &cases {
        let rel = format!("tests/ui/{name}.mcl");
        let out = mcl(&["check", "--color", "never", &rel]);
        let text = redact(&stdout(&out));
        let err = stderr(&out);

        // Checks that hold for every case, whatever the snapshot says.
        let mut problems = Vec::new();
        if !err.is_empty() {
            problems.push(format!("unexpected stderr: {err}"));
        }
        if text.contains('\u{1b}') {
            problems.push("`--color never` printed escape sequences".to_string());
        }
        let summary = text.lines().last().unwrap_or("");
        if !summary.starts_with("checked ") {
            problems.push(format!("the last line is not the summary: {summary:?}"));
        }
        let has_errors = !summary.contains(": 0 errors");
        let expected_status = i32::from(has_errors);
        if status(&out) != expected_status {
            problems.push(format!("exit status {} but the summary says {summary:?}", status(&out)));
        }
        if !problems.is_empty() {
            failures.push(format!("{rel}:\n  {}", problems.join("\n  ")));
        }

        let mut settings = insta::Settings::clone_current();
        settings.set_snapshot_path(snapshot_dir());
        settings.set_description(format!("mcl check --color never {rel}"));
        settings.set_omit_expression(true);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            settings.bind(|| insta::assert_snapshot!(name.as_str(), text));
        }));
        if result.is_err() {
            failures.push(format!("{rel}: the output does not match tests/snapshots/ui__{name}.snap"));
        }
    }
    assert!(failures.is_empty(), "{} UI case(s) failed:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn no_orphan_snapshots() {
    let cases = ui_cases();
    let orphans: Vec<String> = ui_snapshots().into_iter().map(|(c, _)| c).filter(|c| !cases.contains(c)).collect();
    assert!(orphans.is_empty(), "snapshots without a tests/ui/NAME.mcl: {orphans:?}");
}

/// `## Example` with a ```mcl block: the explain test checks that it triggers the code.
fn has_explain_example(info: &codes::CodeInfo) -> bool {
    info.explanation.split("\n## ").any(|s| s.starts_with("Example") && s.contains("```mcl"))
}

#[test]
fn every_code_is_exercised() {
    let snapshots = ui_snapshots();
    let mut missing = Vec::new();
    let mut not_in_ui = Vec::new();
    for info in codes::ALL {
        let tag = format!("[{}]", info.code);
        let in_ui = snapshots.iter().any(|(_, text)| text.contains(&tag));
        // `mcl compile --frame-bytes` codes (codes::LINK) are not `mcl
        // check` diagnostics: mcl-coord/tests/link_report.rs and
        // tests/acoustic_link.rs exercise them.
        if !in_ui && !codes::LINK.contains(&info.code) {
            not_in_ui.push(info.code);
        }
        if !in_ui && !has_explain_example(info) {
            missing.push(info.code);
        }
    }
    assert!(missing.is_empty(), "codes in no UI snapshot and no explain example: {missing:?}");
    // The corpus is meant to cover every code by itself too.
    assert!(not_in_ui.is_empty(), "codes in no UI snapshot: {not_in_ui:?}");
}

// ---------------------------------------------------------------------------
// Exit status.

#[test]
fn exit_status_is_0_without_diagnostics() {
    let out = mcl(&["check", "--color", "never", "tests/ui/clean_extract_5_4.mcl"]);
    assert_eq!(status(&out), 0, "{}", stdout(&out));
    assert_eq!(stdout(&out), "checked 2 files: 0 errors, 0 warnings\n");
}

#[test]
fn exit_status_is_0_with_warnings_only() {
    for case in ["w0901_unused", "w0902_unused_parameter", "w0015_if_then_then"] {
        let out = mcl(&["check", "--color", "never", &format!("tests/ui/{case}.mcl")]);
        assert_eq!(status(&out), 0, "{case}: {}", stdout(&out));
        let text = stdout(&out);
        assert!(text.contains("Warning"), "{case}: {text}");
        assert!(text.trim_end().ends_with("warning") || text.trim_end().ends_with("warnings"), "{case}: {text}");
        assert!(text.contains(": 0 errors,"), "{case}: {text}");
    }
}

#[test]
fn exit_status_is_1_with_errors() {
    for case in ["e0101_did_you_mean", "e0011_missing_brace_depth1", "e0502_import_cycle", "e0102_undefined_action"] {
        let out = mcl(&["check", "--color", "never", &format!("tests/ui/{case}.mcl")]);
        assert_eq!(status(&out), 1, "{case}: {}", stdout(&out));
        assert!(stderr(&out).is_empty(), "{case}: {}", stderr(&out));
    }
    // Several files: one with errors is enough.
    let out = mcl(&["check", "--color", "never", "tests/ui/clean_extract_5_4.mcl", "tests/ui/e0101_did_you_mean.mcl"]);
    assert_eq!(status(&out), 1);
    // The JSON format has the same status.
    let out = mcl(&["check", "--format", "json", "tests/ui/e0101_did_you_mean.mcl"]);
    assert_eq!(status(&out), 1);
}

#[test]
fn exit_status_is_2_for_a_missing_path() {
    let out = mcl(&["check", "--color", "never", "tests/ui/no_such_mission.mcl"]);
    assert_eq!(status(&out), 2);
    assert!(stdout(&out).is_empty(), "{}", stdout(&out));
    assert!(stderr(&out).contains("tests/ui/no_such_mission.mcl"), "{}", stderr(&out));
    // Even next to a good file.
    let out = mcl(&["check", "tests/ui/clean_extract_5_4.mcl", "tests/ui/no_such_mission.mcl"]);
    assert_eq!(status(&out), 2);
    // And for a usage error (`mcl check` alone checks the current folder:
    // tests/inputs.rs).
    let out = mcl(&["check", "--format", "yaml", "tests/ui/clean_extract_5_4.mcl"]);
    assert_eq!(status(&out), 2);
}

#[test]
fn explain() {
    let out = mcl(&["explain", "e101"]);
    assert_eq!(status(&out), 0);
    assert!(stdout(&out).starts_with("# E0101: undefined task\n"), "{}", stdout(&out));
    assert!(stdout(&out).contains("## Example") && stdout(&out).contains("## Fix"));

    let out = mcl(&["explain", "W0901"]);
    assert_eq!(status(&out), 0);
    assert!(stdout(&out).starts_with("# W0901: unused definition\n"));

    let out = mcl(&["explain", "E9999"]);
    assert_eq!(status(&out), 2);
    assert!(stdout(&out).is_empty());
    assert!(stderr(&out).contains("E9999"), "{}", stderr(&out));

    let out = mcl(&["explain"]);
    assert_eq!(status(&out), 0);
    let list = stdout(&out);
    assert_eq!(list.lines().count(), codes::ALL.len());
    for info in codes::ALL {
        assert!(list.contains(&format!("{}  {}", info.code, info.title)), "{} is not listed", info.code);
    }
}

// ---------------------------------------------------------------------------
// JSON.

fn check_json(rel: &str) -> (i32, Vec<Value>) {
    let out = mcl(&["check", "--format", "json", rel]);
    assert!(stderr(&out).is_empty(), "{}", stderr(&out));
    let v: Value =
        serde_json::from_str(&stdout(&out)).unwrap_or_else(|e| panic!("{rel}: not JSON ({e}): {}", stdout(&out)));
    let Value::Array(items) = v else { panic!("{rel}: not one JSON array") };
    (status(&out), items)
}

fn pos(v: &Value, which: &str) -> (u64, u64) {
    let p = &v["range"][which];
    let line = p["line"].as_u64().unwrap_or_else(|| panic!("no range.{which}.line in {v}"));
    let column = p["column"].as_u64().unwrap_or_else(|| panic!("no range.{which}.column in {v}"));
    (line, column)
}

/// Asserts the documented shape of one diagnostic.
fn assert_shape(d: &Value) {
    let severity = d["severity"].as_str().unwrap_or_else(|| panic!("no severity: {d}"));
    assert!(["error", "warning", "info", "hint"].contains(&severity), "{d}");
    let code = d["code"].as_str().unwrap_or_else(|| panic!("no code: {d}"));
    assert!(codes::lookup(code).is_some_and(|c| c.code == code), "unknown code {code}");
    assert_eq!(severity == "warning", code.starts_with('W'), "{d}");
    assert!(d["message"].as_str().is_some_and(|m| !m.is_empty()), "{d}");
    let file = d["file"].as_str().unwrap_or_else(|| panic!("no file: {d}"));
    assert!(!Path::new(file).is_absolute() && file.ends_with(".mcl"), "{d}");
    let (sl, sc) = pos(d, "start");
    let (el, ec) = pos(d, "end");
    assert!(sl >= 1 && sc >= 1 && el >= 1 && ec >= 1, "lines and columns are 1-based: {d}");
    assert!((sl, sc) <= (el, ec), "{d}");
    for l in d["labels"].as_array().unwrap_or_else(|| panic!("no labels: {d}")) {
        assert!(l["file"].as_str().is_some() && l["message"].as_str().is_some(), "{l}");
        let (sl, sc) = pos(l, "start");
        assert!(sl >= 1 && sc >= 1, "{l}");
    }
}

/// 1-based line and character column of the first `needle` in `text`.
fn line_col_of(text: &str, needle: &str) -> (u64, u64) {
    let offset = text.find(needle).unwrap_or_else(|| panic!("{needle:?} not found"));
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..offset].chars().count() + 1;
    (line as u64, column as u64)
}

#[test]
fn json_columns_count_characters() {
    let rel = "tests/ui/non_ascii_columns.mcl";
    let src = std::fs::read_to_string(root().join(rel)).unwrap();
    // The file has non-ASCII characters on an earlier line and on the line of
    // the error, before it: byte and character columns differ.
    let first_line = src.lines().next().unwrap();
    assert!(first_line.len() > first_line.chars().count());
    let (status, items) = check_json(rel);
    assert_eq!(status, 1);
    assert_eq!(items.len(), 1, "{items:?}");
    let d = &items[0];
    assert_shape(d);
    assert_eq!(d["severity"], "error");
    assert_eq!(d["code"], "E0101");
    assert_eq!(d["message"], "cannot find task `Surfce`");
    assert_eq!(d["file"], rel);
    let (line, column) = line_col_of(&src, "Surfce");
    assert_eq!(pos(d, "start"), (line, column));
    assert_eq!(pos(d, "end"), (line, column + "Surfce".len() as u64));
    let error_line = src.lines().nth(line as usize - 1).unwrap();
    let byte_column = error_line.find("Surfce").unwrap() as u64 + 1;
    assert!(byte_column > column, "the line must hold non-ASCII characters before the error");
    assert_eq!((line, column), (5, 48));
    assert_eq!(d["help"], "did you mean `Surface`?");
}

#[test]
fn json_labels_in_other_files() {
    let rel = "tests/ui/e0110_cross_file_duplicate.mcl";
    let (status, items) = check_json(rel);
    assert_eq!(status, 1);
    assert_eq!(items.len(), 2, "{items:?}");
    items.iter().for_each(assert_shape);
    let task = items
        .iter()
        .find(|d| d["message"] == "the task `Surface` is defined more than once")
        .expect("E0110 for Surface");
    assert_eq!(task["code"], "E0110");
    assert_eq!(task["file"], rel);
    let src = std::fs::read_to_string(root().join(rel)).unwrap();
    assert_eq!(pos(task, "start"), line_col_of(&src, "Surface():"));
    let vehicle = std::fs::read_to_string(root().join("tests/ui/vehicle.mcl")).unwrap();
    let first = task["labels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["file"] == "tests/ui/vehicle.mcl")
        .expect("a label in the imported file");
    assert_eq!(first["message"], "first definition of `Surface`");
    assert_eq!(pos(first, "start"), line_col_of(&vehicle, "Surface():"));
}

#[test]
fn json_for_several_files_is_one_array() {
    // The import cycle reports in both files of the cycle.
    let (status, items) = check_json("tests/ui/e0502_import_cycle.mcl");
    assert_eq!(status, 1);
    items.iter().for_each(assert_shape);
    let mut files: Vec<&str> = items.iter().map(|d| d["file"].as_str().unwrap()).collect();
    files.sort();
    assert_eq!(files, ["tests/ui/e0502_import_cycle.mcl", "tests/ui/multi/cycle_b.mcl"]);
    assert!(items.iter().all(|d| d["code"] == "E0502"));
    assert!(items.iter().all(|d| d["notes"].as_array().is_some_and(|n| n.len() == 1)));
}

#[test]
fn json_warnings_and_clean_files() {
    let (status, items) = check_json("tests/ui/w0902_unused_parameter.mcl");
    assert_eq!(status, 0);
    assert_eq!(items.len(), 1);
    assert_shape(&items[0]);
    assert_eq!(items[0]["severity"], "warning");
    assert_eq!(items[0]["code"], "W0902");
    assert_eq!(pos(&items[0], "start"), (5, 28));

    let (status, items) = check_json("tests/ui/clean_extract_5_4.mcl");
    assert_eq!(status, 0);
    assert!(items.is_empty());
}

#[test]
fn json_for_every_ui_case_has_the_documented_shape() {
    for name in ui_cases() {
        let rel = format!("tests/ui/{name}.mcl");
        let (_, items) = check_json(&rel);
        for d in &items {
            assert_shape(d);
        }
    }
}
