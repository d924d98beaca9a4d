//! `mcl fmt` end to end: rewriting in place, `--check`, folders, standard
//! input, syntax errors and usage errors, with their exit statuses.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-fmt-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn mcl(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(dir).output().expect("run mcl")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const MESSY: &str = "mission{A();if B() then {C()}}\n";
const TIDY: &str = "mission {\n    A() ;\n    if ( B() ) {\n        C()\n    }\n}\n";

#[test]
fn rewrites_in_place_then_check_passes() {
    let dir = tmp("rewrite");
    std::fs::write(dir.join("a.mcl"), MESSY).unwrap();
    std::fs::write(dir.join("b.mcl"), TIDY).unwrap();
    let o = mcl(&dir, &["fmt", "--check", "a.mcl", "b.mcl"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(stdout(&o), "a.mcl\n", "only the unformatted file is listed");
    assert_eq!(std::fs::read_to_string(dir.join("a.mcl")).unwrap(), MESSY, "--check changes nothing");

    let o = mcl(&dir, &["fmt", "a.mcl", "b.mcl"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(dir.join("a.mcl")).unwrap(), TIDY);
    assert_eq!(std::fs::read_to_string(dir.join("b.mcl")).unwrap(), TIDY);

    let o = mcl(&dir, &["fmt", "--check", "."]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    assert_eq!(stdout(&o), "");
}

#[test]
fn folders_are_searched_for_mcl_files() {
    let dir = tmp("folders");
    std::fs::create_dir_all(dir.join("m/sub")).unwrap();
    std::fs::write(dir.join("m/sub/deep.mcl"), MESSY).unwrap();
    std::fs::write(dir.join("m/notes.txt"), MESSY).unwrap();
    let o = mcl(&dir, &["fmt", "--check", "m"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stdout(&o).trim_end(), Path::new("m/sub/deep.mcl").display().to_string());
    let o = mcl(&dir, &["fmt", "m"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(dir.join("m/sub/deep.mcl")).unwrap(), TIDY);
    assert_eq!(std::fs::read_to_string(dir.join("m/notes.txt")).unwrap(), MESSY, "only .mcl files");
}

#[test]
fn syntax_errors_are_reported_and_the_file_left_alone() {
    let dir = tmp("errors");
    let broken = "mission { A( }\n";
    std::fs::write(dir.join("bad.mcl"), broken).unwrap();
    std::fs::write(dir.join("ok.mcl"), MESSY).unwrap();
    for args in [&["fmt", "bad.mcl", "ok.mcl"][..], &["fmt", "--check", "bad.mcl"][..]] {
        let o = mcl(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert!(err.contains("E0011") && err.contains("bad.mcl"), "{err}");
        assert_eq!(std::fs::read_to_string(dir.join("bad.mcl")).unwrap(), broken);
    }
    // The other file was still formatted.
    assert_eq!(std::fs::read_to_string(dir.join("ok.mcl")).unwrap(), TIDY);
}

#[test]
fn usage_and_io_errors() {
    let dir = tmp("usage");
    let o = mcl(&dir, &["fmt", "missing.mcl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.mcl"));
    let o = mcl(&dir, &["fmt"]);
    assert_eq!(o.status.code(), Some(2), "a path is required");
    let o = mcl(&dir, &["fmt", "-", "x.mcl"]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::write(dir.join("latin1.mcl"), b"mission { A( \"\xe9\" ) }").unwrap();
    let o = mcl(&dir, &["fmt", "latin1.mcl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("UTF-8"), "{}", stderr(&o));
}

fn with_stdin(dir: &Path, args: &[&str], input: &str) -> Output {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run mcl");
    child.stdin.take().expect("stdin").write_all(input.as_bytes()).expect("write stdin");
    child.wait_with_output().expect("wait")
}

#[test]
fn standard_input_to_standard_output() {
    let dir = tmp("stdin");
    let o = with_stdin(&dir, &["fmt", "-"], MESSY);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(stdout(&o), TIDY);
    let o = with_stdin(&dir, &["fmt", "--check", "-"], MESSY);
    assert_eq!(o.status.code(), Some(1));
    let o = with_stdin(&dir, &["fmt", "--check", "-"], TIDY);
    assert_eq!(o.status.code(), Some(0));
    let o = with_stdin(&dir, &["fmt", "-"], "mission { A( }");
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stdout(&o), "");
    assert!(stderr(&o).contains("<stdin>"));
}

#[test]
fn the_examples_keep_checking_after_formatting() {
    // Format a copy of the example corpus, then check it: still no error.
    let dir = tmp("examples");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    copy_dir(&src, &dir.join("examples"));
    let o = mcl(&dir, &["fmt", "examples"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = mcl(&dir, &["fmt", "--check", "examples"]);
    assert_eq!(o.status.code(), Some(0), "idempotent: {}", stdout(&o));
    let o = mcl(&dir, &["check", "examples"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
}

#[test]
fn the_bundled_examples_are_formatted() {
    // `mcl fmt --check examples/` in the repository: what CI and the
    // pre-commit hook run (format them with `mcl fmt examples/`).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = mcl(root, &["fmt", "--check", "examples/"]);
    assert_eq!(o.status.code(), Some(0), "not formatted:\n{}{}", stdout(&o), stderr(&o));
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}
