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

/// Deep enough to overflow any stack without the nesting limit (debug frames
/// of the recursive parser are several hundred bytes).
const N: usize = 20_000;

/// The codes of the errors of a `mcl check --format json` output (the
/// tasks of `VOID` may be unused: warnings).
fn errors(v: &serde_json::Value) -> Vec<&str> {
    v.as_array().unwrap().iter().filter(|d| d["severity"] == "error").map(|d| d["code"].as_str().unwrap()).collect()
}

/// A task that does nothing (the standard library has its pattern).
const VOID: &str = "tasks { Void(): Instant { } Take( x ): Instant { } }\n";

/// Deeply nested programs; the second part of each is whether the text
/// also has a syntax error of its own (a block `{ ... }` is no statement,
/// a missing `}`).
fn deep_programs() -> Vec<(&'static str, String, bool)> {
    let rep = |s: &str, n: usize| s.repeat(n);
    vec![
        ("braces", format!("{VOID}mission {{ {}Void(){} }}\n", rep("{ ", N), rep(" }", N)), true),
        ("parens", format!("{VOID}mission {{ {}Void(){} }}\n", rep("( ", N), rep(" )", N)), true),
        ("not", format!("{VOID}mission {{ {}Void(){} }}\n", rep("not ( ", N), rep(" )", N)), false),
        ("try", format!("{VOID}mission {{ {}Void(){} }}\n", rep("try { ", N), rep(" } catch { Void() }", N)), false),
        ("if_bare", format!("{VOID}mission {{ {}Void(){} }}\n", rep("if ", N), rep(" then { Void() }", N)), false),
        ("while_bare", format!("{VOID}mission {{ {}Void(){} }}\n", rep("while ", N), rep(" do { Void() }", N)), false),
        ("lists", format!("{VOID}mission {{ Take( {}1{} ) }}\n", rep("[", N), rep("]", N)), false),
        ("unclosed", format!("{VOID}mission {{ {}Void()\n", rep("not ( ", N)), true),
    ]
}

#[test]
fn deep_nesting_is_one_error_not_a_crash() {
    let dir = tmp("deep");
    for (name, src, own_error) in deep_programs() {
        let file = format!("{name}.mcl");
        std::fs::write(dir.join(&file), &src).unwrap();
        // JSON: the human report would print the 600 kB line once per error.
        let o = mcl(&dir, &["check", "--format", "json", &file]);
        assert_eq!(code(&o), 1, "{name}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let codes: Vec<&str> = errors(&v);
        assert_eq!(codes.iter().filter(|c| **c == "E0016").count(), 1, "{name}: one nesting error: {codes:?}");
        let others = codes.len() - 1;
        assert!(others <= usize::from(own_error), "{name}: nothing but the nesting error: {codes:?}");
        // The other commands refuse the file the same way.
        let o = mcl(&dir, &["compile", &file, "-o", "out.pnml"]);
        assert_ne!(code(&o), 0, "{name}: compile");
        let o = mcl(&dir, &["fmt", "--check", &file]);
        assert_ne!(code(&o), 0, "{name}: fmt");
    }
}

#[test]
fn the_nesting_error_points_at_the_first_level_too_deep() {
    let dir = tmp("deep-where");
    let depth = mcl_syntax::parser::MAX_NESTING;
    // The mission's body is the first level: the parenthesis number `depth`
    // is one level too many.
    let src = format!("mission {{\n{}Void(){}\n}}\n{VOID}", "not ( ".repeat(depth), " )".repeat(depth));
    std::fs::write(dir.join("m.mcl"), &src).unwrap();
    let o = mcl(&dir, &["check", "--format", "json", "m.mcl"]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let diags: Vec<&serde_json::Value> = v.as_array().unwrap().iter().filter(|d| d["severity"] == "error").collect();
    assert_eq!(diags.len(), 1, "{v:#}");
    assert_eq!(diags[0]["code"], "E0016");
    let col = 1 + "not ( ".len() * (depth - 1) + "not ".len();
    assert_eq!(diags[0]["range"]["start"], serde_json::json!({"line": 2, "column": col}), "{v:#}");
}

#[test]
fn nesting_just_below_the_limit_checks_compiles_and_formats() {
    let dir = tmp("deep-ok");
    let depth = mcl_syntax::parser::MAX_NESTING - 1;
    let src = format!("mission {{\n{}Void(){}\n}}\n{VOID}", "not ( ".repeat(depth - 1), " )".repeat(depth - 1));
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
    std::fs::write(dir.join("m.mcl"), format!("\u{feff}mission {{ Void() ; Nope() }}\n{VOID}")).unwrap();
    let o = mcl(&dir, &["check", "--format", "json", "m.mcl"]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let diags: Vec<&serde_json::Value> = v.as_array().unwrap().iter().filter(|d| d["severity"] == "error").collect();
    assert_eq!(diags.len(), 1, "only the undefined task: {v:#}");
    assert_eq!(diags[0]["code"], "E0101");
    assert_eq!(diags[0]["range"]["start"], serde_json::json!({"line": 1, "column": 20}), "{v:#}");
    std::fs::write(dir.join("ok.mcl"), format!("\u{feff}mission {{ Void() }}\n{VOID}")).unwrap();
    let o = mcl(&dir, &["check", "ok.mcl"]);
    assert_eq!(code(&o), 0, "{}", stdout(&o));
    let o = mcl(&dir, &["check", "--color", "never", "m.mcl"]);
    assert!(stdout(&o).contains("m.mcl:1:20"), "{}", stdout(&o));
}

/// The ```mcl block of a `## name` section of an explanation.
fn explain_block(md: &str, name: &str) -> Option<String> {
    let heading = format!("## {name}");
    let mut lines = md.lines().skip_while(|l| l.trim_end() != heading).skip(1);
    let mut block = String::new();
    let mut inside = false;
    for l in lines.by_ref() {
        if l.starts_with("## ") {
            break;
        }
        if !inside && l.trim_start().starts_with("```mcl") {
            inside = true;
        } else if inside && l.trim_start().starts_with("```") {
            return Some(block);
        } else if inside {
            block.push_str(l);
            block.push('\n');
        }
    }
    None
}

/// `mcl explain CODE` for every code that `mcl explain` lists: its
/// "Example" program, checked by `mcl check` next to `examples/vehicle.mcl`,
/// produces CODE, and its "Fix" program checks without any error (the
/// coordination codes included: `mcl check` runs that analysis too).
#[test]
fn every_explanation_shows_an_error_and_a_fix_that_checks_clean() {
    let dir = tmp("explain");
    let vehicle = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/vehicle.mcl")).unwrap();
    let list = mcl(&dir, &["explain"]);
    assert_eq!(code(&list), 0);
    // `mcl compile --frame-bytes` codes (`codes::LINK`) are not `mcl check`
    // diagnostics: mcl-coord/tests/link_report.rs checks their example and fix.
    let codes: Vec<String> = stdout(&list)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| !mcl_compiler::codes::LINK.contains(&c.as_str()))
        .collect();
    assert!(codes.len() > 40, "{codes:?}");
    let mut files: Vec<(String, String, String)> = Vec::new(); // code, section, relative path
    for c in &codes {
        let o = mcl(&dir, &["explain", c]);
        assert_eq!(code(&o), 0, "{c}");
        let md = stdout(&o);
        for section in ["Example", "Fix"] {
            let src = explain_block(&md, section).unwrap_or_else(|| panic!("{c}: no ```mcl block in `## {section}`"));
            let first = src.lines().next().unwrap_or("").trim();
            let name = match first.strip_prefix("//").map(str::trim) {
                Some(n) if n.ends_with(".mcl") && !n.contains(char::is_whitespace) => n.to_string(),
                _ => "mission.mcl".to_string(),
            };
            let sub = dir.join(c).join(section.to_ascii_lowercase());
            std::fs::create_dir_all(&sub).unwrap();
            std::fs::write(sub.join("vehicle.mcl"), &vehicle).unwrap();
            std::fs::write(sub.join(&name), &src).unwrap();
            files.push((c.clone(), section.to_string(), format!("{c}/{}/{name}", section.to_ascii_lowercase())));
        }
    }
    // One `mcl check` for all the examples, one for all the fixes.
    let mut problems = Vec::new();
    for section in ["Example", "Fix"] {
        let paths: Vec<&str> = files.iter().filter(|f| f.1 == section).map(|f| f.2.as_str()).collect();
        let mut args = vec!["check", "--format", "json"];
        args.extend(&paths);
        let o = mcl(&dir, &args);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|_| panic!("{}", stderr(&o)));
        for (c, _, path) in files.iter().filter(|f| f.1 == section) {
            let folder = path.rsplit_once('/').map_or("", |x| x.0);
            let diags: Vec<&serde_json::Value> = v
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["file"].as_str().is_some_and(|f| f.replace('\\', "/").starts_with(folder)))
                .collect();
            let shown = || diags.iter().map(|d| format!("{} {}", d["code"], d["message"])).collect::<Vec<_>>();
            if section == "Example" && !diags.iter().any(|d| d["code"] == c.as_str()) {
                problems.push(format!("{c}: the example does not produce {c}: {:?}", shown()));
            }
            if section == "Fix" && diags.iter().any(|d| d["code"] == c.as_str() || d["severity"] == "error") {
                problems.push(format!("{c}: the fix does not check clean: {:?}", shown()));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
