//! `mcl run --mcap` and `mcl trace-to-mcap` read back by an independent
//! reader, the `mcap` package from PyPI (`tests/mcap/read.py`): the
//! channels and schemas of docs/mcap.md, JSON messages at their mission
//! time, and as many messages on each channel as the trace has records of
//! its kinds.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use mcl_testutil::{have_tool, runs};
use serde_json::Value;

const MCL: &str = env!("CARGO_BIN_EXE_mcl");

/// docs/mcap.md: topic, schema name, record kinds.
const CHANNELS: [(&str, &str, &[&str]); 9] = [
    ("/mcl/actions", "mcl.Action", &["action"]),
    ("/mcl/events", "mcl.Event", &["event", "unexpected_event", "stale_event"]),
    ("/mcl/firings", "mcl.Firing", &["fire", "timer"]),
    ("/mcl/perceptions", "mcl.Perception", &["perception"]),
    ("/mcl/poses", "mcl.Pose", &["pose"]),
    ("/mcl/outcomes", "mcl.Outcome", &["outcome", "coord_summary"]),
    ("/mcl/coordination", "mcl.Coordination", &["coord_send", "coord_receive", "coord_reject"]),
    ("/mcl/log", "mcl.Log", &["warning", "link"]),
    ("/mcl/other", "mcl.Record", &[]),
];

fn have_mcap() -> bool {
    have_tool("mcap", runs("python3", &["-c", "import mcap.reader"]), "python3 -m pip install mcap")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mcl-mcap-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// What the Python reader says of `file`.
fn read(file: &Path) -> Value {
    let out = Command::new("python3").arg("tests/mcap/read.py").arg(file).output().unwrap();
    assert!(out.status.success(), "read.py: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The records of a trace, counted by kind.
fn kinds(trace: &Path) -> BTreeMap<String, u64> {
    let mut n = BTreeMap::new();
    for l in std::fs::read_to_string(trace).unwrap().lines().filter(|l| !l.trim().is_empty()) {
        let v: Value = serde_json::from_str(l).unwrap();
        *n.entry(v["kind"].as_str().unwrap().to_string()).or_insert(0) += 1;
    }
    n
}

/// The file has every channel with its schema, and each channel as many
/// messages as the trace has records of its kinds.
fn check(mcap: &Path, trace: &Path) {
    let got = read(mcap);
    let kinds = kinds(trace);
    assert!(got["bad"].as_array().unwrap().is_empty(), "{}", got["bad"]);
    let topics = got["topics"].as_object().unwrap();
    assert_eq!(topics.len(), CHANNELS.len(), "{got}");
    let mut total = 0;
    for (topic, schema, ks) in CHANNELS {
        let t = &topics[topic];
        assert_eq!((t["schema"].as_str(), t["schema_encoding"].as_str()), (Some(schema), Some("jsonschema")), "{t}");
        assert_eq!(t["message_encoding"], "json");
        assert_eq!(t["schema_is_json"], true);
        let expected: u64 = if ks.is_empty() {
            kinds.iter().filter(|(k, _)| !CHANNELS.iter().any(|c| c.2.contains(&k.as_str()))).map(|(_, n)| n).sum()
        } else {
            ks.iter().map(|k| kinds.get(*k).copied().unwrap_or(0)).sum()
        };
        assert_eq!(t["count"].as_u64(), Some(expected), "{topic}: {t} (trace: {kinds:?})");
        total += expected;
    }
    assert_eq!(got["message_count"].as_u64(), Some(total), "the summary's statistics");
    for k in ["action", "event", "fire", "outcome"] {
        assert!(kinds.get(k).copied().unwrap_or(0) > 0, "the run has {k} records: {kinds:?}");
    }
}

#[test]
fn run_and_trace_to_mcap_are_read_by_the_mcap_package() {
    if !have_mcap() {
        return;
    }
    let d = dir("survey");
    let (trace, live, converted) = (d.join("T.jsonl"), d.join("run.mcap"), d.join("converted.mcap"));
    let status = Command::new(MCL)
        .args(["run", "--mock", "--virtual-time", "-q", "examples/survey.mcl", "--trace"])
        .arg(&trace)
        .arg("--mcap")
        .arg(&live)
        .status()
        .unwrap();
    assert!(status.success(), "mcl run: {status}");
    check(&live, &trace);
    let out = Command::new(MCL).arg("trace-to-mcap").arg(&trace).arg("-o").arg(&converted).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    check(&converted, &trace);
    // The same messages either way.
    assert_eq!(read(&live)["topics"], read(&converted)["topics"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_simulated_run_has_poses() {
    if !have_mcap() {
        return;
    }
    let d = dir("sim");
    let (trace, file) = (d.join("T.jsonl"), d.join("sim.mcap"));
    let status = Command::new(MCL)
        .args(["run", "--sim", "--virtual-time", "-q", "examples/survey.mcl", "--trace"])
        .arg(&trace)
        .arg("--mcap")
        .arg(&file)
        .status()
        .unwrap();
    assert!(status.code().is_some(), "mcl run --sim: {status}");
    check(&file, &trace);
    assert!(kinds(&trace).get("pose").copied().unwrap_or(0) > 0, "a simulated run traces poses");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_traces_are_refused() {
    let d = dir("bad");
    let (trace, file) = (d.join("bad.jsonl"), d.join("bad.mcap"));
    std::fs::write(&trace, "{\"t\":0,\"kind\":\"action\"}\nnot json\n").unwrap();
    let out = Command::new(MCL).arg("trace-to-mcap").arg(&trace).arg("-o").arg(&file).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.jsonl:2: "), "{err}");
    assert!(!file.exists(), "no half-written file");
    let out = Command::new(MCL).args(["trace-to-mcap", "no/such/trace.jsonl", "-o"]).arg(&file).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&d);
}
