//! The AAC protocol documentation suffices: `tests/stranger_aac/aac.py`, an
//! AAC written from `docs/aac-protocol.md` alone (no other AAC read), runs
//! the bundled single-vehicle missions to `ok` along their nominal path.
//!
//! The AAC answers every enabled primitive with the `ok` event of the
//! action's task from `hello.events`, except keep modes (`"mode": "keep"`)
//! and the calls `hello.events` lists with role `condition` (a monitor's
//! condition, `eventAlarmOk`: answering it would raise the alarm in survey,
//! or loop for ever in cable-tracking's `InvalidPositioning`). It reads
//! nothing but the protocol (no `mcl interface`).

use std::net::TcpListener;
use std::process::{Child, Command, Stdio};

use mcl_testutil::{have_tool, runs};

const MCL: &str = env!("CARGO_BIN_EXE_mcl");

/// Kills the Python AAC when the case ends, pass or fail.
struct Aac(Child);

impl Drop for Aac {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn run_against_stranger(file: &str) {
    assert!(std::path::Path::new(file).exists(), "{file} is missing");
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let args = ["tests/stranger_aac/aac.py".to_string(), addr.clone()];
    let _aac = Aac(Command::new("python3")
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("python3 tests/stranger_aac/aac.py"));
    // The player retries until the AAC listens (--connect-timeout).
    let dir = std::env::temp_dir().join(format!("mcl-stranger-{}-{port}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let trace = dir.join("T.jsonl");
    let status = Command::new(MCL)
        .args(["run", "--aac", &addr, file, "--speed", "50", "--connect-timeout", "20", "--time-limit", "5000"])
        .arg("--trace")
        .arg(&trace)
        .arg("-q")
        .stdin(Stdio::null())
        .status()
        .unwrap();
    let text = std::fs::read_to_string(&trace).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(status.success(), "{file}: mcl run exited with {status}");
    let records: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let outcomes: Vec<_> = records.iter().filter(|r| r["kind"] == "outcome").collect();
    assert_eq!(outcomes.len(), 1, "{file}: one outcome record");
    assert_eq!(outcomes[0]["result"], "ok", "{file}: {}", outcomes[0]);
    // The nominal path: no monitor's `do` block ran (no emergency surface).
    assert!(outcomes[0].get("via").is_none(), "{file}: ended through a monitor: {}", outcomes[0]);
    let emergency = records.iter().filter(|r| r["kind"] == "action" && r["task"] == "EmergencySurface").count();
    assert_eq!(emergency, 0, "{file}: no EmergencySurface action");
    let events = records.iter().filter(|r| r["kind"] == "event").count();
    assert!(events > 0, "{file}: the AAC answered");
}

fn have_python() -> bool {
    have_tool("python3", runs("python3", &["--version"]), "apt-get install python3")
}

#[test]
fn survey_runs_ok_against_a_docs_only_aac() {
    if have_python() {
        run_against_stranger("examples/survey.mcl");
    }
}

#[test]
fn dam_inspection_runs_ok_against_a_docs_only_aac() {
    if have_python() {
        run_against_stranger("examples/dam-inspection.mcl");
    }
}

#[test]
fn cable_tracking_runs_ok_against_a_docs_only_aac() {
    if have_python() {
        run_against_stranger("examples/cable-tracking.mcl");
    }
}
