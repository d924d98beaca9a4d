//! Bad input through the real binary: deeply nested programs, byte order
//! marks, and the recovery of a few classic mistakes. The binary must end
//! with a status (1 for errors), never with a signal (a stack overflow is
//! SIGSEGV/SIGABRT), on the ordinary 8 MB main-thread stack.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-robustness-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Runs `mcl ARGS` in `dir` with an 8 MB stack for its main thread (what
/// most systems give by default), whatever the test runner was given.
fn mcl(dir: &Path, args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mcl"));
    cmd.args(args).current_dir(dir);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: setrlimit is async-signal-safe and only touches the child.
        unsafe {
            cmd.pre_exec(|| {
                let lim = libc::rlimit { rlim_cur: 8 << 20, rlim_max: libc::RLIM_INFINITY };
                let mut old = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
                if libc::getrlimit(libc::RLIMIT_STACK, &mut old) == 0 {
                    let lim = libc::rlimit { rlim_cur: lim.rlim_cur.min(old.rlim_max), rlim_max: old.rlim_max };
                    libc::setrlimit(libc::RLIMIT_STACK, &lim);
                }
                Ok(())
            });
        }
    }
    cmd.output().expect("run mcl")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The exit code; a death by signal (a stack overflow) fails the test.
fn code(o: &Output) -> i32 {
    match o.status.code() {
        Some(c) => c,
        None => panic!("mcl was killed by a signal ({:?}); stderr: {}", o.status, stderr(o)),
    }
}

const N: usize = 100_000;

/// Deeply nested programs, each a mission of the standard library's `Void`.
fn deep_programs() -> Vec<(&'static str, String)> {
    let rep = |s: &str, n: usize| s.repeat(n);
    vec![
        ("braces", format!("mission {{ {}Void(){} }}\n", rep("{ ", N), rep(" }", N))),
        ("parens", format!("mission {{ {}Void(){} }}\n", rep("( ", N), rep(" )", N))),
        ("not", format!("mission {{ {}Void(){} }}\n", rep("not ( ", N), rep(" )", N))),
        ("try", format!("mission {{ {}Void(){} }}\n", rep("try { ", N), rep(" } catch { Void() }", N))),
        ("if_bare", format!("mission {{ {}Void(){} }}\n", rep("if ", N), rep(" then { Void() }", N))),
        ("while_bare", format!("mission {{ {}Void(){} }}\n", rep("while ", N), rep(" do { Void() }", N))),
        ("lists", format!("mission {{ Void( {}1{} ) }}\n", rep("[", N), rep("]", N))),
        ("unclosed", format!("mission {{ {}Void()\n", rep("not ( ", N))),
    ]
}

#[test]
fn deep_nesting_is_one_error_not_a_crash() {
    let dir = tmp("deep");
    for (name, src) in deep_programs() {
        let file = format!("{name}.mcl");
        std::fs::write(dir.join(&file), &src).unwrap();
        let o = mcl(&dir, &["check", "--color", "never", &file]);
        let out = stdout(&o);
        assert_eq!(code(&o), 1, "{name}: {out}{}", stderr(&o));
        assert!(out.contains("error[E0016]"), "{name}: {out}");
        assert_eq!(out.matches("error[E0016]").count(), 1, "{name}: one nesting error: {out}");
        assert_eq!(out.matches("error[").count(), 1, "{name}: nothing but the nesting error: {out}");
        // The other commands refuse the file the same way.
        let o = mcl(&dir, &["compile", &file, "-o", "out.pnml"]);
        assert_ne!(code(&o), 0, "{name}: compile");
        let o = mcl(&dir, &["fmt", "--check", &file]);
        assert_ne!(code(&o), 0, "{name}: fmt");
        let o = mcl(&dir, &["check", "--format", "json", &file]);
        assert_eq!(code(&o), 1, "{name}: json");
    }
}

#[test]
fn the_nesting_error_points_at_the_first_level_too_deep() {
    let dir = tmp("deep-where");
    let depth = mcl_syntax::parser::MAX_NESTING;
    // The mission's body is the first level: the parenthesis number `depth`
    // is one level too many.
    let src = format!("mission {{\n{}Void(){}\n}}\n", "not ( ".repeat(depth), " )".repeat(depth));
    std::fs::write(dir.join("m.mcl"), &src).unwrap();
    let o = mcl(&dir, &["check", "--format", "json", "m.mcl"]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let diags = v.as_array().unwrap();
    assert_eq!(diags.len(), 1, "{v:#}");
    assert_eq!(diags[0]["code"], "E0016");
    let col = 1 + "not ( ".len() * (depth - 1) + "not ".len();
    assert_eq!(diags[0]["range"]["start"], serde_json::json!({"line": 2, "column": col}), "{v:#}");
}

#[test]
fn nesting_just_below_the_limit_checks_compiles_and_formats() {
    let dir = tmp("deep-ok");
    let depth = mcl_syntax::parser::MAX_NESTING - 1;
    let src = format!("mission {{\n{}Void(){}\n}}\n", "not ( ".repeat(depth - 1), " )".repeat(depth - 1));
    std::fs::write(dir.join("m.mcl"), &src).unwrap();
    let o = mcl(&dir, &["check", "--color", "never", "m.mcl"]);
    assert_eq!(code(&o), 0, "{}{}", stdout(&o), stderr(&o));
    let o = mcl(&dir, &["compile", "m.mcl", "-o", "m.pnml"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let o = mcl(&dir, &["fmt", "m.mcl"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let o = mcl(&dir, &["check", "m.mcl"]);
    assert_eq!(code(&o), 0, "the formatted file still checks: {}", stdout(&o));
}

#[test]
fn a_byte_order_mark_is_skipped() {
    let dir = tmp("bom");
    std::fs::write(dir.join("m.mcl"), "\u{feff}mission { Void() ; Nope() }\n").unwrap();
    let o = mcl(&dir, &["check", "--format", "json", "m.mcl"]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let diags = v.as_array().unwrap();
    assert_eq!(diags.len(), 1, "only the undefined task: {v:#}");
    assert_eq!(diags[0]["code"], "E0101");
    assert_eq!(diags[0]["range"]["start"], serde_json::json!({"line": 1, "column": 20}), "{v:#}");
    std::fs::write(dir.join("ok.mcl"), "\u{feff}mission { Void() }\n").unwrap();
    let o = mcl(&dir, &["check", "ok.mcl"]);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    let o = mcl(&dir, &["check", "--color", "never", "m.mcl"]);
    assert!(stdout(&o).contains("m.mcl:1:20"), "{}", stdout(&o));
}
