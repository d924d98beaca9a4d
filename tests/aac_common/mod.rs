//! Shared by the AAC tests: spawning AAC processes, a blocking raw client,
//! and a conformance suite any AAC must pass (`mcl mock-aac` and the Python
//! reference, `clients/python/mcl_aac.py`).

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mcl_runtime::trace::{Record, RecordKind};
use serde_json::{json, Value};

pub const STEP: Duration = Duration::from_secs(10);

pub fn mcl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mcl"))
}

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch folder.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mcl-aac-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A server process that prints `listening on ADDR` first on stdout; its
/// standard error is collected line by line. Killed when dropped.
pub struct Proc {
    pub child: Child,
    pub addr: String,
    pub stderr: Arc<Mutex<Vec<String>>>,
}

impl Proc {
    pub fn spawn(mut cmd: Command) -> Proc {
        cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).stdin(Stdio::null());
        let mut child = cmd.spawn().expect("cannot start the AAC process");
        let stdout = child.stdout.take().unwrap();
        let stderr = child.stderr.take().unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                l.lock().unwrap().push(line);
            }
        });
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            let mut first = String::new();
            let _ = r.read_line(&mut first);
            let _ = tx.send(first);
            let mut rest = Vec::new();
            let _ = r.read_to_end(&mut rest);
        });
        let first = match rx.recv_timeout(STEP) {
            Ok(f) => f,
            Err(_) => {
                let _ = child.kill();
                panic!("no `listening on` line within {STEP:?}; stderr: {:?}", lines.lock().unwrap());
            }
        };
        let Some(addr) = first.trim().strip_prefix("listening on ") else {
            let _ = child.kill();
            let _ = child.wait();
            panic!("unexpected first line {first:?}; stderr: {:?}", lines.lock().unwrap());
        };
        Proc { child, addr: addr.to_string(), stderr: lines }
    }

    pub fn log(&self) -> Vec<String> {
        self.stderr.lock().unwrap().clone()
    }

    /// Waits until a stderr line satisfies `f` (bounded).
    pub fn wait_log(&self, what: &str, f: impl Fn(&str) -> bool) {
        let deadline = Instant::now() + STEP;
        while Instant::now() < deadline {
            if self.log().iter().any(|l| f(l)) {
                return;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        panic!("never logged {what}; stderr:\n{}", self.log().join("\n"));
    }

    /// The seqs of the `executed seq=N` lines.
    pub fn executed(&self) -> Vec<u64> {
        seqs(&self.log(), "executed seq=")
    }

    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        self.kill();
    }
}

pub fn seqs(lines: &[String], marker: &str) -> Vec<u64> {
    lines
        .iter()
        .filter_map(|l| {
            let rest = &l[l.find(marker)? + marker.len()..];
            rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()
        })
        .collect()
}

/// Runs a command to completion within `limit`, returning (status code, stdout, stderr).
pub fn run_bounded(mut cmd: Command, limit: Duration) -> (Option<i32>, String, String) {
    cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).stdin(Stdio::null());
    let mut child = cmd.spawn().expect("cannot start command");
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let to = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let te = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let deadline = Instant::now() + limit;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            let (o, e) = (to.join().unwrap(), te.join().unwrap());
            panic!("command did not finish within {limit:?}\nstdout:\n{o}\nstderr:\n{e}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    (status, to.join().unwrap(), te.join().unwrap())
}

/// A blocking JSON-lines client.
pub struct Raw {
    rd: BufReader<TcpStream>,
    wr: TcpStream,
}

impl Raw {
    pub fn connect(addr: &str) -> Raw {
        let s = TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(STEP)).unwrap();
        Raw { rd: BufReader::new(s.try_clone().unwrap()), wr: s }
    }

    pub fn send_raw(&mut self, b: &[u8]) {
        self.wr.write_all(b).unwrap();
    }

    pub fn send(&mut self, v: Value) {
        let mut s = v.to_string();
        s.push('\n');
        self.send_raw(s.as_bytes());
    }

    /// The next message; None when the peer closed.
    pub fn recv(&mut self) -> Option<Value> {
        let mut line = String::new();
        match self.rd.read_line(&mut line) {
            Ok(0) => None,
            Ok(_) => Some(serde_json::from_str(line.trim_end()).unwrap_or_else(|e| panic!("{e}: {line:?}"))),
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => None,
            Err(e) => panic!("no message within {STEP:?}: {e}"),
        }
    }

    /// The next message that is not an event or a perception.
    pub fn recv_reply(&mut self) -> Option<Value> {
        loop {
            let m = self.recv()?;
            if m["type"] != "event" && m["type"] != "perception" {
                return Some(m);
            }
        }
    }

    pub fn hello(&mut self, fields: Value) -> Value {
        let mut h = json!({"type":"hello","version":1,"player":"conformance","mission":"mission","run":"conf"});
        for (k, v) in fields.as_object().unwrap() {
            h[k] = v.clone();
        }
        self.send(h);
        self.recv().expect("closed after hello")
    }
}

fn assert_error(m: &Option<Value>, code: &str, ctx: &str) {
    let m = m.as_ref().unwrap_or_else(|| panic!("{ctx}: connection closed, expected error {code}"));
    assert_eq!((m["type"].as_str(), m["code"].as_str()), (Some("error"), Some(code)), "{ctx}: {m}");
    assert!(m["message"].as_str().is_some_and(|s| !s.is_empty()), "{ctx}: {m}");
}

/// The protocol rules every AAC must follow, checked over the wire. `token`
/// is the server's token; `aac.executed()` must list executed seqs.
/// `run` names the session used (fresh for each call).
pub fn conformance(aac: &Proc, token: &str, run: &str) {
    let addr = aac.addr.as_str();
    // Version mismatch: error, then the AAC closes.
    let mut c = Raw::connect(addr);
    let e = c.hello(json!({"version": 99, "token": token, "run": run}));
    assert_error(&Some(e), "version", "version 99");
    assert_eq!(c.recv(), None, "closed after a version error");
    // Token refusal.
    for bad in [json!({"run": run}), json!({"token": "wrong", "run": run})] {
        let mut c = Raw::connect(addr);
        let e = c.hello(bad.clone());
        assert_error(&Some(e), "unauthorized", &bad.to_string());
        assert_eq!(c.recv(), None, "closed after unauthorized");
    }
    // Before hello: errors, connection kept.
    let mut c = Raw::connect(addr);
    // A version that is not an integer (JSON `true` is no 1).
    c.send(json!({"type":"hello","version":true,"token":token,"run":run}));
    assert_error(&c.recv(), "malformed", "hello with version true");
    c.send_raw(b"{\"type\":\"action\",\"seq\":1,\"action\":\"a\",\"primitive\":\"P\",\"command\":\"enable\"}\n");
    assert_error(&c.recv(), "unexpected", "action before hello");
    let w = c.hello(json!({"token": token, "run": run}));
    assert_eq!(w["type"], "welcome", "{w}");
    assert_eq!((w["version"].as_u64(), w["last_seq"].as_u64()), (Some(1), Some(0)), "{w}");
    assert!(w["session"].as_str().is_some_and(|s| !s.is_empty()), "{w}");
    // Malformed input: one error each, the session survives.
    for (line, code) in [
        (&b"{this is not json\n"[..], "malformed"),
        (b"42\n", "malformed"),
        (b"{\"seq\":3}\n", "malformed"),
        (b"{\"type\":\"warp\"}\n", "unknown_type"),
        (b"{\"type\":\"action\",\"seq\":9}\n", "malformed"),
        (b"{\"type\":\"welcome\",\"version\":1,\"last_seq\":0}\n", "unexpected"),
    ] {
        c.send_raw(line);
        assert_error(&c.recv_reply(), code, &String::from_utf8_lossy(line));
    }
    // A line over 64 KiB: error, discarded, the session survives.
    let big = format!("{{\"type\":\"ping\",\"pad\":\"{}\"}}\n", "z".repeat(100_000));
    c.send_raw(big.as_bytes());
    assert_error(&c.recv_reply(), "too_long", "100 kB line");
    c.send(json!({"type":"ping"}));
    assert_eq!(c.recv_reply().unwrap(), json!({"type":"pong"}));
    // Duplicates: acknowledged, executed once.
    let before = aac.executed().len();
    let act = |seq: u64| {
        json!({"type":"action","seq":seq,"action":"enableGoto","primitive":"GotoPrimitive","command":"enable",
               "params":{"way-point":[1,2]},"task":"Goto","call_site":3})
    };
    for seq in [1, 1, 2, 1, 2] {
        c.send(act(seq));
        assert_eq!(c.recv_reply().unwrap(), json!({"type":"ack","seq":seq}));
    }
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(aac.executed().len() - before, 2, "each seq executed once:\n{}", aac.log().join("\n"));
    drop(c);
    // Same run again: the session is resumed, last_seq remembered.
    let mut c = Raw::connect(addr);
    let w = c.hello(json!({"token": token, "run": run}));
    assert_eq!(w["last_seq"], 2, "{w}");
    c.send(act(2));
    assert_eq!(c.recv_reply().unwrap(), json!({"type":"ack","seq":2}));
    c.send(json!({"type":"action","seq":3,"action":"disableGoto","primitive":"GotoPrimitive","command":"disable","task":"Goto"}));
    assert_eq!(c.recv_reply().unwrap(), json!({"type":"ack","seq":3}));
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(aac.executed().len() - before, 3, "{}", aac.log().join("\n"));
    drop(c);
    // A hello without `run` resumes nothing (§2): a new session each time,
    // whose actions are executed from seq 1.
    let mut sessions = Vec::new();
    for _ in 0..2 {
        let mut c = Raw::connect(addr);
        let w = c.hello(json!({"token": token, "run": null}));
        assert_eq!((w["type"].as_str(), w["last_seq"].as_u64()), (Some("welcome"), Some(0)), "{w}");
        sessions.push(w["session"].clone());
        c.send(act(1));
        assert_eq!(c.recv_reply().unwrap(), json!({"type":"ack","seq":1}));
    }
    assert_ne!(sessions[0], sessions[1], "two run-less hellos, two sessions");
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(aac.executed().len() - before, 5, "{}", aac.log().join("\n"));
}

/// The path of a file under the repository root.
pub fn at_root(p: &str) -> PathBuf {
    root().join(p)
}

pub fn exists(p: &Path) -> bool {
    p.exists()
}

// ---------------------------------------------------------------------------
// The player killed and resumed (`--journal`, `--resume`) against an AAC
// ---------------------------------------------------------------------------

/// Dive; then go to a way-point while reaching an altitude (the altitude
/// first, the way-point later); then surface. Written in `dir`, importing
/// the examples' vehicle.
pub fn resume_mission(dir: &Path) -> PathBuf {
    let vehicle = at_root("examples/vehicle.mcl");
    let text = format!(
        "import {:?};\n\nmission {{\n    Depth( 15, \"achieve\" ) ;\n    parallel {{\n        Goto( [24, 12] )\n    }} and {{\n        Altitude( 2.5, 60, \"achieve\" )\n    }} ;\n    Depth( 0, \"achieve\" )\n}}\n",
        vehicle.to_str().unwrap()
    );
    let p = dir.join("resume.mcl");
    std::fs::write(&p, text).unwrap();
    p
}

/// How the mock answers [`resume_mission`]: 2 s for each primitive, 4 s
/// for Goto. Its inputs: 1 the start, 2 the dive's end, 3 the altitude's
/// end (Goto still runs), 4 Goto's end, 5 the surface.
pub const RESUME_SCENARIO: &str = "default_duration = 2\n[tasks.Goto]\ndelay = 4\n";

/// Where the player dies.
#[derive(Clone, Copy, Debug)]
pub enum Kill {
    /// `--crash-after N`: aborts right after journaling its N-th input,
    /// before that input's actions leave.
    After(u64),
    /// SIGKILL as soon as the journal holds this text, wherever the player is.
    When(&'static str),
}

/// `mcl run --aac ADDR FILE --journal JOURNAL ARGS`, killed as `kill` says.
pub fn crashed_run(addr: &str, file: &Path, journal: &Path, args: &[&str], kill: Kill) {
    crashed_run_over(&["--aac", addr], file, journal, args, kill)
}

/// `mcl run PLAYER FILE --journal JOURNAL ARGS` (`PLAYER`: how it reaches
/// the vehicle, `--aac ADDR` or `--zenoh …`), killed as `kill` says.
pub fn crashed_run_over(player: &[&str], file: &Path, journal: &Path, args: &[&str], kill: Kill) {
    let mut cmd = mcl();
    cmd.arg("run").args(player).arg("-q").arg(file).arg("--journal").arg(journal).args(args);
    match kill {
        Kill::After(n) => {
            cmd.args(["--crash-after", &n.to_string()]);
            let (code, out, err) = run_bounded(cmd, Duration::from_secs(30));
            assert_eq!(code, None, "{kill:?}: the player must die of its abort\nstdout:\n{out}\nstderr:\n{err}");
        }
        Kill::When(text) => {
            cmd.stdout(Stdio::null()).stderr(Stdio::null()).stdin(Stdio::null());
            let mut child = cmd.spawn().unwrap();
            let deadline = Instant::now() + STEP;
            while !std::fs::read_to_string(journal).unwrap_or_default().contains(text) {
                assert!(Instant::now() < deadline, "{kill:?}: the journal never held {text}");
                assert!(child.try_wait().unwrap().is_none(), "{kill:?}: the run ended before it was killed");
                std::thread::sleep(Duration::from_millis(2));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// `mcl run --aac ADDR FILE --resume JOURNAL --trace TRACE ARGS`: its exit
/// status, standard output and standard error.
pub fn resumed_run(addr: &str, file: &Path, journal: &Path, trace: &Path, args: &[&str]) -> (Option<i32>, String) {
    resumed_run_over(&["--aac", addr], file, journal, trace, args)
}

/// `mcl run PLAYER FILE --resume JOURNAL --trace TRACE ARGS` (`PLAYER` as
/// in [`crashed_run_over`]).
pub fn resumed_run_over(
    player: &[&str],
    file: &Path,
    journal: &Path,
    trace: &Path,
    args: &[&str],
) -> (Option<i32>, String) {
    let mut cmd = mcl();
    cmd.arg("run").args(player).arg(file).arg("--resume").arg(journal).arg("--trace").arg(trace).args(args);
    let (code, out, err) = run_bounded(cmd, Duration::from_secs(30));
    (code, format!("resumed player stdout:\n{out}\nresumed player stderr:\n{err}"))
}

/// The records of a trace file.
pub fn records(trace: &Path) -> Vec<Record> {
    mcl_runtime::trace::read_trace(trace).unwrap_or_else(|e| panic!("{e}"))
}

/// Every action and event of a trace with the call it is credited to (no
/// times, no sequence numbers), and the outcome.
pub fn calls(trace: &Path) -> Vec<String> {
    records(trace)
        .iter()
        .filter_map(|r| match &r.kind {
            // Fields as JSON text (`"name"`, `null`, `{"x":1}`).
            RecordKind::Action { action, params, call, .. } => Some(format!(
                "action {} {} task {} call {}",
                json!(action),
                json!(params),
                json!(call.task),
                json!(call.call_site)
            )),
            RecordKind::Event { event, call, .. } => {
                Some(format!("event {} task {} call {}", json!(event), json!(call.task), json!(call.call_site)))
            }
            RecordKind::Outcome { result, .. } => Some(format!("outcome {}", json!(result))),
            _ => None,
        })
        .collect()
}

/// The sequence numbers of the actions of a trace.
pub fn sent(trace: &Path) -> Vec<u64> {
    records(trace)
        .iter()
        .filter_map(|r| match r.kind {
            RecordKind::Action { seq, .. } => Some(seq),
            _ => None,
        })
        .collect()
}

/// The unexpected and stale events of a trace.
pub fn odd_events(trace: &Path) -> Vec<Record> {
    records(trace)
        .into_iter()
        .filter(|r| matches!(r.kind, RecordKind::UnexpectedEvent { .. } | RecordKind::StaleEvent { .. }))
        .collect()
}

/// The messages of the warnings of a trace.
pub fn warnings(trace: &Path) -> Vec<String> {
    records(trace)
        .into_iter()
        .filter_map(|r| match r.kind {
            RecordKind::Warning { message } => Some(message),
            _ => None,
        })
        .collect()
}

/// [`calls`] of the uninterrupted run of `file` on the in-process mock, in
/// virtual time, with `scenario`.
pub fn reference_calls(dir: &Path, file: &Path, scenario: &str) -> Vec<String> {
    let sc = dir.join("reference.toml");
    std::fs::write(&sc, scenario).unwrap();
    let trace = dir.join("reference.jsonl");
    let mut cmd = mcl();
    cmd.args(["run", "--mock", "--virtual-time", "-q"]).arg(file).arg("--scenario").arg(&sc).arg("--trace").arg(&trace);
    let (code, _, err) = run_bounded(cmd, Duration::from_secs(30));
    assert_eq!(code, Some(0), "{err}");
    calls(&trace)
}

/// No duplicates in `v`.
pub fn unique(v: &[u64]) -> bool {
    v.iter().collect::<std::collections::BTreeSet<_>>().len() == v.len()
}
