//! Bounded resources on every input, and traces that survive, through the
//! real binary: devices, FIFOs and sockets as imports and as arguments end
//! with a clear error (never a hang), files over the size limit are refused,
//! `mcl check DIR` goes on after a file it cannot read, a 10 MB identifier
//! gives a short report, an exploding PDDL action stops grounding with exit
//! status 2, and SIGTERM or SIGKILL of `mcl run` leaves a trace of whole
//! lines.

#![cfg(unix)]

use mcl_runtime::trace::{Record, RecordKind};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-inputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// What a finished `mcl` gave.
struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Runs `mcl ARGS` in `dir`, killing it (and failing the test) if it has not
/// ended after 60 s: a hang on a FIFO fails rather than blocks.
fn mcl(dir: &Path, args: &[&str]) -> Run {
    let out = dir.join(format!(".out-{}", std::process::id()));
    let err = dir.join(format!(".err-{}", std::process::id()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("run mcl");
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if started.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("`mcl {}` did not end within 60 s", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    let run = Run {
        code: status.code().unwrap_or_else(|| panic!("mcl killed by a signal: {status:?}")),
        stdout: read(&out),
        stderr: read(&err),
    };
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(err);
    run
}

/// A folder with a FIFO `fifo`, a listening socket `sock` (kept open by the
/// returned listener) and a symlink `zero` to `/dev/zero`, each also under a
/// name that ends in `.mcl`, `.pnml` and `.pddl`.
fn special_files(name: &str) -> (PathBuf, Vec<std::os::unix::net::UnixListener>) {
    let dir = tmp(name);
    let mut listeners = Vec::new();
    for ext in ["mcl", "pnml", "pddl"] {
        let fifo = dir.join(format!("fifo.{ext}"));
        let ok = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo").success();
        assert!(ok, "mkfifo failed");
        listeners.push(std::os::unix::net::UnixListener::bind(dir.join(format!("sock.{ext}"))).unwrap());
        std::os::unix::fs::symlink("/dev/zero", dir.join(format!("zero.{ext}"))).unwrap();
    }
    (dir, listeners)
}

const KINDS: [(&str, &str); 3] = [("fifo", "FIFO"), ("sock", "socket"), ("zero", "character device")];

#[test]
fn special_files_as_imports_are_errors_at_the_import() {
    let (dir, _l) = special_files("imports");
    let paths = KINDS.iter().map(|(name, what)| (format!("{name}.mcl"), *what));
    for (path, what) in paths.chain([("/dev/zero".to_string(), "character device")]) {
        {
            let src = format!("import \"{path}\";\nmission {{ Void() }}\n");
            std::fs::write(dir.join("m.mcl"), src).unwrap();
            let r = mcl(&dir, &["check", "--format", "json", "m.mcl"]);
            assert_eq!(r.code, 1, "{}", r.stderr);
            let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
            let e = v.as_array().unwrap().iter().find(|d| d["code"] == "E0501").unwrap_or_else(|| panic!("{v:#}"));
            let msg = e["message"].as_str().unwrap();
            assert!(msg.contains(what) && msg.contains(&path), "{msg}");
            assert_eq!(e["range"]["start"]["line"], 1, "at the import: {e:#}");
            let r = mcl(&dir, &["compile", "m.mcl"]);
            assert_eq!(r.code, 1, "{}", r.stderr);
            assert!(r.stderr.contains(what), "{}", r.stderr);
        }
    }
}

#[test]
fn special_files_as_arguments_are_errors_naming_them() {
    let (dir, _l) = special_files("arguments");
    for (name, what) in KINDS {
        let mcl_file = format!("{name}.mcl");
        let pnml = format!("{name}.pnml");
        let pddl = format!("{name}.pddl");
        let runs = [
            mcl(&dir, &["check", &mcl_file]),
            mcl(&dir, &["compile", &mcl_file]),
            mcl(&dir, &["analyze", &pnml]),
            mcl(&dir, &["plan", "--domain", &pddl, "--problem", &pddl]),
            mcl(&dir, &["run", "--mock", "--virtual-time", &mcl_file]),
        ];
        for r in runs {
            assert_eq!(r.code, 2, "{}", r.stderr);
            assert!(r.stderr.contains(what) && r.stderr.contains(name), "{name}: {}", r.stderr);
        }
    }
    let r = mcl(&dir, &["analyze", "/dev/zero"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("cannot read `/dev/zero`: it is a character device, not a regular file"), "{}", r.stderr);
}

#[test]
fn files_over_the_size_limit_are_refused() {
    let dir = tmp("large");
    let big = vec![b' '; (16 << 20) + 1];
    std::fs::write(dir.join("big.mcl"), &big).unwrap();
    std::fs::write(dir.join("big.pnml"), &big).unwrap();
    std::fs::write(dir.join("m.mcl"), "import \"big.mcl\";\nmission { Void() }\n").unwrap();
    let r = mcl(&dir, &["check", "big.mcl"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("`big.mcl`: it is larger than the limit of 16 MiB"), "{}", r.stderr);
    let r = mcl(&dir, &["check", "--color", "never", "m.mcl"]);
    assert_eq!(r.code, 1);
    assert!(r.stdout.contains("cannot import `big.mcl`: it is larger than the limit of 16 MiB"), "{}", r.stdout);
    let r = mcl(&dir, &["analyze", "big.pnml"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("larger than the limit"), "{}", r.stderr);
    // 33 MB of test files: not left behind.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_dir_reports_unreadable_files_and_checks_the_others() {
    let dir = tmp("check-dir");
    std::fs::write(dir.join("a.mcl"), [b'm', 0xff, 0xfe, b'\n']).unwrap();
    std::fs::write(dir.join("b.mcl"), "mission { Undefined() }\n").unwrap();
    std::fs::write(dir.join("c.mcl"), "tasks { Void(): Instant { } }\nmission { Void() }\n").unwrap();
    for args in [&["check", "--color", "never", "."][..], &["check", "--color", "never"][..]] {
        let r = mcl(&dir, args);
        assert_eq!(r.code, 2, "{}", r.stderr);
        assert!(r.stderr.contains("a.mcl`: it is not UTF-8 text"), "{}", r.stderr);
        assert!(r.stdout.contains("E0101"), "b.mcl is checked: {}", r.stdout);
        assert!(r.stdout.contains("checked 2 files: 1 error"), "{}", r.stdout);
        assert!(r.stdout.contains("1 file could not be read"), "{}", r.stdout);
    }
}

#[test]
fn a_ten_megabyte_identifier_gives_a_short_report() {
    let dir = tmp("identifier");
    let name = format!("T{}", "x".repeat(10_000_000));
    std::fs::write(dir.join("m.mcl"), format!("mission {{ {name}() }}\n")).unwrap();
    for format in ["human", "json"] {
        let r = mcl(&dir, &["check", "--color", "never", "--format", format, "m.mcl"]);
        assert_eq!(r.code, 1, "{}", r.stderr);
        assert!(r.stdout.contains("E0101"), "{}", &r.stdout[..r.stdout.len().min(2000)]);
        assert!(r.stdout.len() < 20_000, "{format}: {} bytes of diagnostics", r.stdout.len());
        assert!(r.stdout.contains("xxxx…"), "{}", &r.stdout[..r.stdout.len().min(2000)]);
    }
    let r = mcl(&dir, &["check", "--color", "never", "m.mcl"]);
    assert!(r.stdout.contains("m.mcl:1 has 10000015 characters: shown cut to 240 from column"), "{}", r.stdout);
}

#[test]
fn an_exploding_pddl_action_stops_grounding_with_exit_2() {
    let dir = tmp("pddl");
    let vars: Vec<String> = (0..8).map(|i| format!("?v{i}")).collect();
    let domain = format!(
        "(define (domain boom) (:requirements :strips) (:predicates (done))\n\
         (:action explode :parameters ({}) :precondition () :effect (done)))",
        vars.join(" ")
    );
    let objects: Vec<String> = (0..60).map(|i| format!("o{i}")).collect();
    let problem =
        format!("(define (problem boom) (:domain boom) (:objects {}) (:init) (:goal (done)))", objects.join(" "));
    std::fs::write(dir.join("d.pddl"), domain).unwrap();
    std::fs::write(dir.join("p.pddl"), problem).unwrap();
    let r = mcl(&dir, &["plan", "--domain", "d.pddl", "--problem", "p.pddl", "--max-states", "1000"]);
    assert_eq!(r.code, 2, "{}{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("grounding gave up on action `explode`"), "{}", r.stderr);
    assert!(r.stderr.contains("8 parameters"), "{}", r.stderr);
}

/// The names of the actions and events of a trace, in order.
fn steps(records: &[Record]) -> Vec<String> {
    records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Action { action, .. } => Some(action.clone()),
            RecordKind::Event { event, .. } => Some(format!("!{event}")),
            _ => None,
        })
        .collect()
}

/// Every line of a trace, each a whole record.
fn whole_lines(path: &Path) -> Vec<Record> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.is_empty() || text.ends_with('\n'), "the trace ends with a whole line");
    text.lines().map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("cut line {l:?}: {e}"))).collect()
}

/// Starts a real-time run of the survey (133 s of mission at speed 20:
/// about 7 s) and waits until its trace has a few records.
fn survey_in_real_time(trace: &Path) -> std::process::Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--speed", "20", "-q", "examples/survey.mcl"])
        .args(["--scenario", "examples/scenarios/survey-nominal.toml", "--trace"])
        .arg(trace)
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while std::fs::read_to_string(trace).unwrap_or_default().lines().count() < 3 {
        assert!(started.elapsed() < Duration::from_secs(30), "no records in the trace after 30 s");
        assert!(child.try_wait().unwrap().is_none(), "the run ended too soon");
        std::thread::sleep(Duration::from_millis(20));
    }
    child
}

/// The actions and events of an uninterrupted run of the survey.
fn survey_reference(dir: &Path) -> Vec<String> {
    let t = dir.join("reference.jsonl");
    let r = mcl(
        &root(),
        &[
            "run",
            "--mock",
            "--virtual-time",
            "-q",
            "examples/survey.mcl",
            "--scenario",
            "examples/scenarios/survey-nominal.toml",
            "--trace",
            t.to_str().unwrap(),
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    steps(&whole_lines(&t))
}

#[test]
fn sigterm_of_a_real_time_run_flushes_its_trace() {
    let dir = tmp("sigterm");
    let reference = survey_reference(&dir);
    for (signal, code) in [(libc::SIGTERM, 143), (libc::SIGINT, 130)] {
        let trace = dir.join(format!("run-{signal}.jsonl"));
        let mut child = survey_in_real_time(&trace);
        std::thread::sleep(Duration::from_millis(300));
        // SAFETY: sending a signal to our own child process.
        assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{status:?}");
        let records = whole_lines(&trace);
        let got = steps(&records);
        assert!(got.len() >= 2 && got.len() < reference.len(), "{got:?}");
        assert_eq!(got[..], reference[..got.len()], "the records so far, in order");
        assert!(!records.iter().any(|r| matches!(r.kind, RecordKind::Outcome { .. })), "the run was interrupted");
    }
}

#[test]
fn sigkill_of_a_real_time_run_leaves_whole_lines_that_chronogram_reads() {
    let dir = tmp("sigkill");
    let trace = dir.join("run.jsonl");
    let mut child = survey_in_real_time(&trace);
    std::thread::sleep(Duration::from_millis(1500));
    child.kill().unwrap();
    let _ = child.wait();
    let records = whole_lines(&trace);
    assert!(steps(&records).len() >= 2);
    let svg = dir.join("run.svg");
    let r = mcl(&dir, &["chronogram", trace.to_str().unwrap(), "-o", svg.to_str().unwrap()]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    // A line cut all the same (a crash in the middle of a write) is ignored.
    let mut text = std::fs::read_to_string(&trace).unwrap();
    text.push_str("{\"t\":1.5,\"kind\":\"act");
    std::fs::write(&trace, text).unwrap();
    let r = mcl(&dir, &["chronogram", trace.to_str().unwrap(), "-o", svg.to_str().unwrap()]);
    assert_eq!(r.code, 0, "{}", r.stderr);
}
