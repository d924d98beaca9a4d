//! Shared by the tests of coordinated AUV/ASC runs of several processes
//! (`tests/coord_fault.rs` over TCP, `tests/zenoh.rs` over Zenoh): what a
//! trace says about calls and coordination messages, the dry run they are
//! compared with, and every check of a run (constraints held, messages
//! taken once and in order).

#![allow(dead_code)]

use mcl_runtime::trace::{Record, RecordKind};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// The coordinated file and its scenario, relative to the repository.
pub const AUV_ASC: &str = "examples/auv-asc.mcl";
pub const SCENARIO: &str = "examples/scenarios/auv-asc.toml";

/// The fire records of the start (`callN.start`) and end (`callN.release`)
/// of the calls labelled `label`, as indices in the trace.
pub fn call(tr: &[Record], label: &str, what: &str) -> Vec<usize> {
    tr.iter()
        .enumerate()
        .filter(|(_, r)| match &r.kind {
            RecordKind::Fire { transition: t, call, .. } => {
                call.label.as_deref() == Some(label) && t.starts_with("call") && t.ends_with(what)
            }
            _ => false,
        })
        .map(|(i, _)| i)
        .collect()
}

/// The transition of a `fire` record.
pub fn fired(r: &Record) -> &str {
    match &r.kind {
        RecordKind::Fire { transition, .. } => transition,
        k => panic!("not a firing: {k:?}"),
    }
}

/// The `transition` of every `coord_send`.
pub fn sends(tr: &[Record]) -> Vec<&str> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::CoordSend { transition, .. } => Some(transition.as_str()),
            _ => None,
        })
        .collect()
}

/// (`from`, `transition`) of every `coord_receive`.
pub fn receives(tr: &[Record]) -> Vec<(&str, &str)> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::CoordReceive { from, transition, .. } => Some((from.as_str(), transition.as_str())),
            _ => None,
        })
        .collect()
}

/// The first `coord_receive` of `transition` from `from`.
pub fn received(tr: &[Record], from: &str, transition: &str) -> Option<usize> {
    tr.iter().position(
        |r| matches!(&r.kind, RecordKind::CoordReceive { from: f, transition: t, .. } if f == from && t == transition),
    )
}

/// Enable and disable actions per primitive and call site, in order.
pub fn actions(tr: &[Record]) -> BTreeMap<String, Vec<String>> {
    let mut out: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for r in tr {
        if let RecordKind::Action { primitive, command, call, .. } = &r.kind {
            out.entry(format!("{primitive}@{:?}", call.call_site)).or_default().push(command.clone());
        }
    }
    out
}

/// The reference: enable actions of each vehicle in a run without crash
/// (virtual time, same scenario: the same calls happen).
pub fn reference(root: &Path, tp: &Path) -> BTreeMap<String, BTreeMap<String, usize>> {
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--virtual-time", AUV_ASC, "--scenario", SCENARIO, "-q", "--trace"])
        .arg(tp)
        .current_dir(root)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let tr: Vec<Record> = std::fs::read_to_string(tp)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let mut by = BTreeMap::new();
    for m in ["auv", "asc"] {
        let mine: Vec<Record> = tr.iter().filter(|r| r.mission.as_deref() == Some(m)).cloned().collect();
        let counts =
            actions(&mine).into_iter().map(|(k, v)| (k, v.iter().filter(|c| *c == "enable").count())).collect();
        by.insert(m.to_string(), counts);
    }
    by
}

/// Every check of a crashed and resumed AUV/ASC run.
pub fn check(
    runs: &[(i32, Vec<Record>, Vec<Value>); 2],
    reference: &BTreeMap<String, BTreeMap<String, usize>>,
    tag: &str,
) {
    let [(ca, auv, ja), (cc, asc, jc)] = runs;
    assert_eq!((*ca, *cc), (0, 0), "{tag}: both end ok");
    for (m, tr) in [("auv", auv), ("asc", asc)] {
        let o: Vec<&str> = tr
            .iter()
            .filter_map(|r| match &r.kind {
                RecordKind::Outcome { result, .. } => Some(result.as_str()),
                _ => None,
            })
            .collect();
        assert_eq!(o, ["ok"], "{tag}: {m} ends once, ok");
        // The calls of the dry run, each enabled and never twice in a row.
        // How many times a call inside the ASC's loop runs depends on when
        // the AUV's message comes, which wall-clock scheduling decides in a
        // real-time run (a stall of a loaded machine is seconds of mission
        // time at --speed 50): counts are compared only outside loops, where
        // the dry run gives exactly one.
        let got = actions(tr);
        let calls: Vec<&String> = got.keys().collect();
        let want: Vec<&String> = reference[m].keys().collect();
        assert_eq!(calls, want, "{tag}: {m}: the calls of the dry run");
        for (k, cmds) in got.iter() {
            for w in cmds.windows(2) {
                assert!(!(w[0] == "enable" && w[1] == "enable"), "{tag}: {m} {k} enabled twice: {cmds:?}");
            }
            let enables = cmds.iter().filter(|c| *c == "enable").count();
            if reference[m][k] == 1 {
                assert_eq!(enables, 1, "{tag}: {m} {k}: {cmds:?}");
            } else {
                assert!(enables >= 1, "{tag}: {m} {k}: {cmds:?}");
            }
        }
    }
    // order { asc:deploy_auv, auv:deploy_auv }: asc's call ended, told auv,
    // and only then did auv's call start.
    let (asc_end, auv_start) = (call(asc, "deploy_auv", ".release"), call(auv, "deploy_auv", ".start"));
    assert_eq!((asc_end.len(), auv_start.len()), (1, 1), "{tag}");
    let tr_end = fired(&asc[asc_end[0]]);
    let got = received(auv, "asc", tr_end).unwrap_or_else(|| panic!("{tag}: auv never heard of asc's {tr_end}"));
    assert!(got < auv_start[0], "{tag}: auv's deploy_auv started before asc's ended");
    // sync { auv:send_data, asc:send_data }: each starts once, after the
    // other's arrival message.
    for (me, other, tr_me) in [("auv", "asc", auv), ("asc", "auv", asc)] {
        let starts = call(tr_me, "send_data", ".start");
        assert_eq!(starts.len(), 1, "{tag}: {me}'s send_data starts once");
        assert!(
            receives(&tr_me[..starts[0]]).iter().any(|(from, _)| *from == other),
            "{tag}: {me}'s send_data started without a message from {other}"
        );
    }
    // Exactly once: every message sent is journaled once by its receiver,
    // numbered 1, 2, … on each link; what one sends the other receives.
    for (from, to, jto) in [("auv", "asc", jc), ("asc", "auv", ja)] {
        let seqs: Vec<u64> = jto
            .iter()
            .filter(|e| e["j"] == "coord_receive" && e["from"] == from)
            .map(|e| e["seq"].as_u64().unwrap())
            .collect();
        assert_eq!(seqs, (1..=seqs.len() as u64).collect::<Vec<_>>(), "{tag}: {from} -> {to}");
        let tr_from = if from == "auv" { auv } else { asc };
        let tr_to = if to == "auv" { auv } else { asc };
        let sent = sends(tr_from);
        let got: Vec<&str> = receives(tr_to).into_iter().filter(|(f, _)| *f == from).map(|(_, t)| t).collect();
        assert_eq!(sent, got, "{tag}: {from} -> {to}");
        assert!(!got.is_empty(), "{tag}: {from} -> {to} carried messages");
    }
}
