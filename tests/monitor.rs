//! The monitor (docs/monitor.md), end to end through the binary: `mcl run
//! --monitor`'s state endpoint and operator control over HTTP, and the page
//! itself in a real headless Chromium driven over the DevTools protocol
//! (live run, replay of a trace with a failure, a fleet with its map). The
//! browser tests take the screenshots of docs/monitor.md
//! (docs/pictures/monitor-*.png).

mod monitor {
    pub mod cdp;
    pub mod http;
}
mod aac_common;

use monitor::cdp::Browser;
use monitor::http;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-monitor-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A running `mcl` that serves the monitor, killed on drop.
struct Served {
    child: Child,
    url: String,
    stderr: mpsc::Receiver<String>,
}

impl Served {
    /// Starts `mcl ARGS` in the repository and waits for the `monitor: URL` line on stderr.
    fn start(args: &[&str]) -> Served {
        let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
            .args(args)
            .current_dir(root())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run mcl");
        let (tx, rx) = mpsc::channel();
        let err = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        let url = loop {
            let line = rx.recv_timeout(Duration::from_secs(60)).expect("mcl printed no monitor URL");
            if let Some(u) = line.strip_prefix("monitor: ") {
                break u.split_whitespace().next().unwrap().to_string();
            }
        };
        assert!(url.starts_with("http://127.0.0.1:"), "{url}");
        Served { child, url, stderr: rx }
    }

    fn state(&self) -> Value {
        let (code, body) = http::get(&format!("{}api/state", self.url));
        assert_eq!(code, 200, "{body}");
        serde_json::from_str(&body).unwrap()
    }

    /// Polls `/api/state` until `done` holds (a minute at most).
    fn state_until(&self, what: &str, done: impl Fn(&Value) -> bool) -> Value {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let s = self.state();
            if done(&s) {
                return s;
            }
            assert!(Instant::now() < deadline, "waited a minute for {what}; state: {s}");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn command(&self, token: Option<&str>, body: &str) -> (u16, String) {
        let auth = token.map(|t| format!("Bearer {t}"));
        let headers: Vec<(&str, &str)> = auth.iter().map(|a| ("Authorization", a.as_str())).collect();
        http::request("POST", &format!("{}api/operator", self.url), &headers, body)
    }

    fn wait(mut self) -> (ExitStatus, Vec<String>) {
        let status = self.child.wait().unwrap();
        (status, self.stderr.try_iter().collect())
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Line `n` (1-based) of a file of the repository.
fn source_line(file: &str, n: u64) -> String {
    let text = std::fs::read_to_string(root().join(file)).unwrap();
    text.lines().nth(n as usize - 1).unwrap_or_default().to_string()
}

#[test]
fn api_state_lists_the_running_calls_with_their_lines() {
    let run = Served::start(&[
        "run",
        "--mock",
        "examples/survey.mcl",
        "--speed",
        "20",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "30",
        "-q",
    ]);
    let s = run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    assert!(s["outcome"].is_null(), "{s}");
    assert!(s["t"].as_f64().is_some(), "{s}");
    for c in s["running"].as_array().unwrap() {
        assert_eq!(c["file"], "examples/survey.mcl", "{c}");
        assert_eq!(c["mission"], "mission", "{c}");
        let task = c["task"].as_str().unwrap();
        let line = source_line("examples/survey.mcl", c["line"].as_u64().unwrap());
        assert!(line.contains(&format!("{task}(")), "line {} is not a call of {task}: {line}", c["line"]);
    }
    // The alarm's condition runs for the whole mission, at line 30.
    let done = run.state_until("the outcome", |s| s["finished"] == true);
    assert_eq!(done["outcome"], "ok", "{done}");
    assert_eq!(done["running"], Value::Array(vec![]));
    let calls = done["calls"].as_array().unwrap();
    let at = |line: u64| calls.iter().find(|c| c["line"] == line).unwrap_or_else(|| panic!("no call at {line}"));
    assert_eq!((at(15)["task"].as_str(), at(15)["status"].as_str()), (Some("InitializeVehicle"), Some("ok")));
    assert_eq!(at(30)["status"], "stopped", "the alarm is disabled when the mission ends");
    // Operator control is off without --operator-token.
    let (code, body) = run.command(Some("anything"), r#"{"command":"abort"}"#);
    assert_eq!(code, 403, "{body}");
}

#[test]
fn operator_abort_needs_the_token_and_is_traced_and_journaled() {
    let trace = tmp("abort.jsonl");
    let journal = tmp("abort.journal");
    let run = Served::start(&[
        "run",
        "--mock",
        "examples/survey.mcl",
        "--speed",
        "1",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "2",
        "--operator-token",
        "s3cret",
        "--trace",
        trace.to_str().unwrap(),
        "--journal",
        journal.to_str().unwrap(),
        "-q",
    ]);
    run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    let abort = r#"{"command":"abort"}"#;
    assert_eq!(run.command(None, abort).0, 401, "no token");
    assert_eq!(run.command(Some("s3creT"), abort).0, 401, "another token");
    assert_eq!(run.command(Some("s3cret"), "{\"command\":\"explode\"}").0, 400, "not a command");
    assert!(run.state()["outcome"].is_null(), "refused commands change nothing");
    // Paused, the operator answers for InitializeVehicle (line 15, 5 s long).
    assert_eq!(run.command(Some("s3cret"), r#"{"command":"pause"}"#).0, 202);
    run.state_until("the pause", |s| s["paused"] == true);
    let answer = r#"{"command":"answer","event":"eventInitializeVehicleOk"}"#;
    assert_eq!(run.command(Some("s3cret"), answer).0, 202);
    let s = run.state_until("the answer", |s| {
        s["calls"].as_array().is_some_and(|c| c.iter().any(|c| c["line"] == 15 && c["status"] == "ok"))
    });
    assert!(s["running"].as_array().unwrap().iter().any(|c| c["line"] == 16), "Altitude starts: {s}");
    let (code, body) = run.command(Some("s3cret"), abort);
    assert_eq!(code, 202, "{body}");
    let s = run.state_until("the outcome", |s| !s["outcome"].is_null());
    assert_eq!(s["outcome"], "aborted", "{s}");
    assert_eq!(s["running"], Value::Array(vec![]), "the abort stopped every call");
    let (status, stderr) = run.wait();
    assert_eq!(status.code(), Some(3), "{stderr:?}");
    assert!(stderr.iter().any(|l| l.contains("ABORTED")), "{stderr:?}");
    let records = mcl_runtime::trace::read_trace(&trace).unwrap();
    let ops: Vec<&mcl_runtime::operator::Command> = records
        .iter()
        .filter_map(|r| match &r.kind {
            mcl_runtime::trace::RecordKind::Operator { command } => Some(command),
            _ => None,
        })
        .collect();
    use mcl_runtime::operator::Command as Op;
    assert_eq!(ops, [&Op::Pause, &Op::Answer { event: "eventInitializeVehicleOk".into() }, &Op::Abort]);
    let entries = mcl_runtime::journal::read_journal(&journal).unwrap();
    let k = entries
        .iter()
        .position(|e| {
            matches!(e, mcl_runtime::journal::Entry::Operator { command: mcl_runtime::operator::Command::Abort, .. })
        })
        .expect("the abort is journaled");
    assert!(
        matches!(&entries[k + 1], mcl_runtime::journal::Entry::Event { event, .. } if event == mcl_runtime::operator::ABORT_EVENT),
        "then the event input that --resume replays: {:?}",
        entries.get(k + 1)
    );
    // Resumed (with the same --operator-token: the abort hook is part of the net), the run replays the abort.
    let resumed = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "examples/survey.mcl", "--resume", journal.to_str().unwrap(), "-q"])
        .args(["--monitor=127.0.0.1:0", "--operator-token", "s3cret"])
        .current_dir(root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("mission `mission`: ABORTED"), "{stderr}");
}

/// The class of line `line` of `file` on the page.
fn line_class(file: &str, line: u32) -> String {
    format!("(document.querySelector('.line[data-file=\"{file}\"][data-line=\"{line}\"]') || {{}}).className")
}

#[test]
fn the_page_follows_a_run_and_marks_each_call_when_it_ends() {
    if !mcl_testutil::browser::have_chromium() {
        return;
    }
    let run = Served::start(&[
        "run",
        "--mock",
        "examples/survey.mcl",
        "--speed",
        "4",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "60",
        "--operator-token",
        "s3cret",
        "-q",
    ]);
    // Paused while the browser starts: InitializeVehicle (line 15) runs.
    run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    assert_eq!(run.command(Some("s3cret"), r#"{"command":"pause"}"#).0, 202);
    let s = run.state_until("the pause", |s| s["paused"] == true);
    assert!(s["running"].as_array().unwrap().iter().any(|c| c["line"] == 15), "{s}");
    let mut b = Browser::start(&tmp("chromium-live"));
    b.open(&format!("{}#token=s3cret", run.url));
    let running15 = format!("{} === 'line running'", line_class("examples/survey.mcl", 15));
    b.wait_for(&running15, "line 15 highlighted as running");
    b.wait_for("!document.getElementById('paused').hidden", "the paused badge");
    // The operator's buttons work from the page.
    b.eval("document.getElementById('op-resume').click()");
    b.wait_for(&format!("{} === 'line ok'", line_class("examples/survey.mcl", 15)), "line 15 marked ok");
    b.wait_for(&format!("{} === 'line running'", line_class("examples/survey.mcl", 18)), "the trajectory running");
    b.screenshot(&root().join("docs/pictures/monitor-live.png"));
    b.wait_for("document.getElementById('outcome').textContent === 'ok'", "the outcome");
    b.wait_for("document.querySelector('#log tr.ok') !== null", "the log");
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
}

#[test]
fn the_replay_page_jumps_to_a_failure() {
    if !mcl_testutil::browser::have_chromium() {
        return;
    }
    let trace = tmp("dam.jsonl");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--virtual-time", "--scenario", "examples/scenarios/dam-wall-failure.toml"])
        .args(["examples/dam-inspection.mcl", "-q", "--trace", trace.to_str().unwrap()])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let served = Served::start(&["monitor", trace.to_str().unwrap(), "--listen", "127.0.0.1:0"]);
    let s = served.state();
    assert_eq!((s["mode"].as_str(), s["outcome"].as_str()), (Some("replay"), Some("ok")));
    let mut b = Browser::start(&tmp("chromium-replay"));
    b.open(&served.url);
    b.wait_for("document.getElementById('time').textContent === '0.000'", "the start of the replay");
    b.eval("document.getElementById('next-failure').click()");
    // WallInspect (line 27) fails at t = 82 s; its catch (line 18) starts.
    b.wait_for("document.getElementById('time').textContent === '82.000'", "the jump to the failure");
    let jump = b.eval("document.getElementById('jump').textContent");
    assert!(jump.as_str().unwrap().starts_with("failure at t=82.000: event eventWallInspectionFail"), "{jump}");
    b.wait_for(&format!("{} === 'line fail'", line_class("examples/dam-inspection.mcl", 27)), "line 27 marked failed");
    b.wait_for("document.querySelector('#log tr.current') !== null", "the failure in the log");
    // The control-structure tree shows the same states.
    let tree = |line: u32, kind: &str| {
        format!("(document.querySelector('#tree .node[data-line=\"{line}\"][data-kind=\"{kind}\"] .st') || {{}}).textContent")
    };
    b.wait_for(&format!("{} === 'fail'", tree(27, "call")), "WallInspect failed in the tree");
    assert_eq!(b.eval(&tree(41, "call")), "running", "the catch's Surface runs");
    assert_eq!(b.eval("document.querySelector('#tree .node[data-kind=\"try-catch\"]') !== null"), true);
    b.screenshot(&root().join("docs/pictures/monitor-replay.png"));
    b.eval("document.getElementById('next-failure').click()");
    b.wait_for("document.getElementById('jump').textContent.startsWith('failure at t=82.000: fire')", "the catch");
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
}

#[test]
fn a_fleet_replay_draws_every_vehicle_on_the_map() {
    if !mcl_testutil::browser::have_chromium() {
        return;
    }
    let trace = tmp("fleet.jsonl");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--sim", "--virtual-time", "examples/sim/fleet8.mcl", "--world", "examples/sim/fleet8.toml"])
        .args(["-q", "--trace", trace.to_str().unwrap()])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let served = Served::start(&["monitor", trace.to_str().unwrap(), "--listen", "127.0.0.1:0"]);
    let mut b = Browser::start(&tmp("chromium-fleet"));
    b.open(&served.url);
    // Half way through the run.
    b.eval("const s = document.getElementById('slider'); s.value = 500; s.dispatchEvent(new Event('input'))");
    b.wait_for("document.querySelectorAll('#map polyline').length === 8", "eight tracks on the map");
    b.wait_for("document.querySelectorAll('.line.running').length > 0", "running calls in the source");
    b.screenshot(&root().join("docs/pictures/monitor-fleet.png"));
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
}

/// The operator's commands in a trace, with their missions.
fn operator_records(trace: &std::path::Path) -> Vec<(Option<String>, mcl_runtime::operator::Command)> {
    mcl_runtime::trace::read_trace(trace)
        .unwrap()
        .into_iter()
        .filter_map(|r| match r.kind {
            mcl_runtime::trace::RecordKind::Operator { command } => Some((r.mission, command)),
            _ => None,
        })
        .collect()
}

/// Whether every running call of `s` is a call of its task on its line of `file`.
fn running_calls_on_their_lines(s: &Value, file: &str) {
    for c in s["running"].as_array().unwrap() {
        assert_eq!(c["file"], file, "{c}");
        let task = c["task"].as_str().unwrap();
        let line = source_line(file, c["line"].as_u64().unwrap());
        assert!(line.contains(&format!("{task}(")), "line {} is not a call of {task}: {line}", c["line"]);
    }
}

#[test]
fn a_coordinated_run_lists_each_vehicles_calls_and_is_aborted_by_the_operator() {
    let trace = tmp("coord-abort.jsonl");
    let run = Served::start(&[
        "run",
        "--mock",
        "examples/auv-asc.mcl",
        "--speed",
        "2",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "2",
        "--operator-token",
        "fleet-k3y",
        "--trace",
        trace.to_str().unwrap(),
        "-q",
    ]);
    let (code, info) = http::get(&format!("{}api/info", run.url));
    assert_eq!(code, 200, "{info}");
    let info: Value = serde_json::from_str(&info).unwrap();
    assert_eq!(info["vehicles"], serde_json::json!(["auv", "asc"]), "{info}");
    // Both vehicles have run calls; the AUV's run now, each on its line.
    let missions = |s: &Value, key: &str| -> Vec<String> {
        let mut m: Vec<String> =
            s[key].as_array().unwrap().iter().map(|c| c["mission"].as_str().unwrap().to_string()).collect();
        m.sort();
        m.dedup();
        m
    };
    let s = run.state_until("calls of both vehicles", |s| missions(s, "calls") == ["asc", "auv"]);
    assert!(s["outcome"].is_null(), "{s}");
    let s = run.state_until("a running call of the AUV", |s| missions(s, "running").contains(&"auv".to_string()));
    running_calls_on_their_lines(&s, "examples/auv-asc.mcl");
    // Refused without the token, or naming no vehicle of the run.
    let abort = r#"{"command":"abort"}"#;
    assert_eq!(run.command(None, abort).0, 401, "no token");
    assert_eq!(run.command(Some("fleet-k3Y"), abort).0, 401, "another token");
    assert_eq!(run.command(Some("fleet-k3y"), r#"{"command":"abort","vehicle":"rov"}"#).0, 400, "no such vehicle");
    let (code, body) = run.command(Some("fleet-k3y"), r#"{"command":"answer","event":"eventVoidOk"}"#);
    assert_eq!(code, 400, "an answer names its vehicle: {body}");
    assert!(run.state()["outcome"].is_null(), "refused commands change nothing");
    // The abort goes to every vehicle; each mission's abort cascades.
    let (code, body) = run.command(Some("fleet-k3y"), abort);
    assert_eq!(code, 202, "{body}");
    let s = run.state_until("the outcome", |s| s["finished"] == true);
    assert_eq!(s["outcome"], "aborted", "{s}");
    assert_eq!(s["outcomes"], serde_json::json!({"asc": "aborted", "auv": "aborted"}), "{s}");
    assert_eq!(s["running"], Value::Array(vec![]), "the aborts stopped every call");
    let (code, _) = run.command(Some("fleet-k3y"), abort);
    assert_eq!(code, 409, "the run is over");
    let (status, stderr) = run.wait();
    assert_eq!(status.code(), Some(3), "{stderr:?}");
    for m in ["auv", "asc"] {
        assert!(stderr.iter().any(|l| l.starts_with(&format!("mission `{m}`: ABORTED"))), "{stderr:?}");
    }
    use mcl_runtime::operator::Command as Op;
    let mut ops = operator_records(&trace);
    ops.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(ops, [(Some("asc".into()), Op::Abort), (Some("auv".into()), Op::Abort)]);
}

#[test]
fn a_sim_run_is_paused_and_resumed_by_the_operator_and_journals_it() {
    let trace = tmp("sim-pause.jsonl");
    let journal = tmp("sim-pause.journal");
    let run = Served::start(&[
        "run",
        "--sim",
        "examples/survey.mcl",
        "--speed",
        "10",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "1",
        "--operator-token",
        "s3cret",
        "--trace",
        trace.to_str().unwrap(),
        "--journal",
        journal.to_str().unwrap(),
        "-q",
    ]);
    run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    assert_eq!(run.command(None, r#"{"command":"pause"}"#).0, 401, "no token");
    assert_eq!(run.command(Some("s3cret"), r#"{"command":"pause"}"#).0, 202);
    let paused = run.state_until("the pause", |s| s["paused"] == true);
    // Paused, the simulated mission stands still: no record comes.
    std::thread::sleep(Duration::from_millis(500));
    let still = run.state();
    assert_eq!((&still["records"], &still["t"]), (&paused["records"], &paused["t"]), "{paused} then {still}");
    assert_eq!(run.command(Some("s3cret"), r#"{"command":"resume","vehicle":"mission"}"#).0, 202);
    let s = run.state_until("the outcome", |s| s["finished"] == true);
    assert_eq!((s["outcome"].as_str(), &s["paused"]), (Some("ok"), &Value::Bool(false)), "{s}");
    let (status, stderr) = run.wait();
    assert_eq!(status.code(), Some(0), "{stderr:?}");
    use mcl_runtime::operator::Command as Op;
    let ops: Vec<Op> = operator_records(&trace).into_iter().map(|(_, c)| c).collect();
    assert_eq!(ops, [Op::Pause, Op::Resume]);
    let journaled: Vec<Op> = mcl_runtime::journal::read_journal(&journal)
        .unwrap()
        .into_iter()
        .filter_map(|e| match e {
            mcl_runtime::journal::Entry::Operator { command, .. } => Some(command),
            _ => None,
        })
        .collect();
    assert_eq!(journaled, [Op::Pause, Op::Resume]);
}

#[test]
fn an_aac_run_shows_its_running_calls_and_outcome() {
    let found = mcl_testutil::runs("python3", &["--version"]);
    if !mcl_testutil::have_tool("python3", found, "apt-get install python3") {
        return;
    }
    // The reference AAC: each primitive ends ok after 0.3 s, the alarm and the camera never.
    let map = tmp("aac-map.json");
    std::fs::write(&map, r#"{"AlarmPrimitive": "", "TakeImagesPrimitive": ""}"#).unwrap();
    let mut aac = Command::new("python3");
    aac.arg(root().join("clients/python/mcl_aac.py")).args(["--listen", "127.0.0.1:0", "--token", "tok"]);
    aac.args(["--map-file", map.to_str().unwrap(), "--map", "AltitudePrimitive=eventAltitudeOk", "--delay", "0.3"]);
    let aac = aac_common::Proc::spawn(aac);
    let run = Served::start(&[
        "run",
        "--aac",
        &aac.addr,
        "--token",
        "tok",
        "examples/survey.mcl",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "30",
        "-q",
    ]);
    let s = run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    running_calls_on_their_lines(&s, "examples/survey.mcl");
    let done = run.state_until("the outcome", |s| s["finished"] == true);
    assert_eq!(done["outcome"], "ok", "{done}; AAC: {:?}", aac.log());
    assert_eq!(done["running"], Value::Array(vec![]));
    let calls = done["calls"].as_array().unwrap();
    assert!(calls.iter().any(|c| c["line"] == 15 && c["status"] == "ok"), "InitializeVehicle ended ok: {done}");
}

#[test]
fn the_page_follows_a_coordinated_run() {
    if !mcl_testutil::browser::have_chromium() {
        return;
    }
    let run = Served::start(&[
        "run",
        "--mock",
        "examples/auv-asc.mcl",
        "--speed",
        "2",
        "--monitor=127.0.0.1:0",
        "--monitor-linger",
        "60",
        "--operator-token",
        "k",
        "-q",
    ]);
    // Paused while the browser starts: each vehicle's running calls stay.
    run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    assert_eq!(run.command(Some("k"), r#"{"command":"pause"}"#).0, 202);
    run.state_until("the pause", |s| s["paused"] == true);
    let mut b = Browser::start(&tmp("chromium-coord"));
    b.open(&format!("{}#token=k", run.url));
    b.wait_for("document.querySelectorAll('.line.running').length > 0", "a running line highlighted");
    // Each vehicle paused itself by now: the calls that run are highlighted.
    let s = run.state();
    let running = s["running"].as_array().unwrap();
    assert!(!running.is_empty(), "{s}");
    for c in running {
        let line = c["line"].as_u64().unwrap() as u32;
        b.wait_for(&format!("{} === 'line running'", line_class("examples/auv-asc.mcl", line)), "a running line");
    }
    assert_eq!(b.eval("document.getElementById('op-vehicle').hidden"), false, "a vehicle picker");
    assert_eq!(b.eval("document.getElementById('op-vehicle').options.length"), 3, "every vehicle, auv, asc");
    // Aborted from the page: the commands go to every vehicle.
    b.eval("document.getElementById('op-abort').click()");
    b.wait_for("document.getElementById('outcome').textContent === 'aborted'", "the outcome");
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
}

/// A free loopback port (bound then released).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

#[test]
fn each_vehicle_in_its_own_process_is_aborted_through_its_own_monitor() {
    let (pa, pb) = (free_port(), free_port());
    let journal = |me: &str| tmp(&format!("proc-{me}.journal"));
    let start = |me: &str, listen: u16, peer: &str, port: u16| {
        let j = journal(me);
        let (listen, peer) = (format!("127.0.0.1:{listen}"), format!("{peer}=127.0.0.1:{port}"));
        Served::start(&[
            "run",
            "--mock",
            "examples/auv-asc.mcl",
            "--vehicle",
            me,
            "--coord-listen",
            &listen,
            "--coord-peer",
            &peer,
            "--speed",
            "2",
            "--time-limit",
            "600",
            "--monitor=127.0.0.1:0",
            "--operator-token",
            "k",
            "--journal",
            j.to_str().unwrap(),
            "-q",
        ])
    };
    let auv = start("auv", pa, "asc", pb);
    let asc = start("asc", pb, "auv", pa);
    for (run, me) in [(&auv, "auv"), (&asc, "asc")] {
        let (_, info) = http::get(&format!("{}api/info", run.url));
        assert_eq!(serde_json::from_str::<Value>(&info).unwrap()["vehicles"], serde_json::json!([me]));
        run.state_until("a running call", |s| s["running"].as_array().is_some_and(|r| !r.is_empty()));
    }
    assert_eq!(auv.command(None, r#"{"command":"abort"}"#).0, 401, "no token");
    assert_eq!(auv.command(Some("k"), r#"{"command":"abort","vehicle":"asc"}"#).0, 400, "asc is not in this process");
    assert_eq!(auv.command(Some("k"), r#"{"command":"abort","vehicle":"auv"}"#).0, 202);
    assert_eq!(asc.command(Some("k"), r#"{"command":"abort"}"#).0, 202);
    // Each aborted mission ends once nothing more happens in it, and tells its peer.
    for (run, me) in [(auv, "auv"), (asc, "asc")] {
        let (status, stderr) = run.wait();
        assert_eq!(status.code(), Some(3), "{me}: {stderr:?}");
        assert!(stderr.iter().any(|l| l.starts_with(&format!("mission `{me}`: ABORTED"))), "{stderr:?}");
        let entries = mcl_runtime::journal::read_journal(&journal(me)).unwrap();
        assert!(
            entries.iter().any(|e| matches!(
                e,
                mcl_runtime::journal::Entry::Operator { command: mcl_runtime::operator::Command::Abort, .. }
            )),
            "{me}: the abort is journaled"
        );
    }
}
