//! The Python reference AAC (`clients/python/mcl_aac.py`, standard library
//! only) against the Rust side: protocol conformance over the wire, and a
//! whole mission played by `mcl run --aac`.

mod aac_common;

use std::process::Command;
use std::time::Duration;

use aac_common::*;

/// `python3`, or None: the test is then skipped, unless
/// `MCL_REQUIRE_PYTHON3=1` (CI) makes a missing python3 a failure.
fn python() -> Option<Command> {
    let found = mcl_testutil::runs("python3", &["--version"]);
    mcl_testutil::have_tool("python3", found, "apt-get install python3").then(|| Command::new("python3"))
}

fn python_aac(args: &[&str]) -> Option<Proc> {
    let mut cmd = python()?;
    cmd.arg(at_root("clients/python/mcl_aac.py")).args(["--listen", "127.0.0.1:0"]).args(args);
    Some(Proc::spawn(cmd))
}

/// The reference client's own unit tests (clients/python/test_mcl_aac.py):
/// message checks (a JSON `true` is not a version), activations of the
/// trivial vehicle's answers, and a disabled run staying silent.
#[test]
fn python_unit_tests() {
    let Some(mut cmd) = python() else { return };
    let out = cmd
        .args(["-m", "unittest", "discover", "-s"])
        .arg(at_root("clients/python"))
        .args(["-p", "test_*.py"])
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("OK"), "{err}");
}

#[test]
fn python_aac_conforms_to_the_protocol() {
    let Some(aac) = python_aac(&["--token", "s3cret"]) else { return };
    conformance(&aac, "s3cret", "python-conformance");
}

#[test]
fn mission_completes_against_the_python_aac() {
    let Some(aac) = python_aac(&["--token", "tok", "--delay", "0.05"]) else { return };
    let mut cmd = mcl();
    cmd.arg("run").args(["--aac", &aac.addr, "--token", "tok"]).arg(at_root("examples/extract-5-4.mcl"));
    let (code, out, err) = run_bounded(cmd, Duration::from_secs(60));
    let ctx = format!("stdout:\n{out}\nstderr:\n{err}\nAAC:\n{}", aac.log().join("\n"));
    assert_eq!(code, Some(0), "{ctx}");
    assert!(err.contains("mission `mission`: OK"), "{ctx}");
    // Every action executed exactly once.
    let executed = aac.executed();
    let mut unique = executed.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), executed.len(), "{ctx}");
    assert_eq!(unique, (1..=executed.len() as u64).collect::<Vec<_>>(), "{ctx}");
}

/// The survey mission, whose alarm monitor must never answer: mapped to
/// nothing with --map-file, the others by the default naming.
#[test]
fn python_aac_event_mapping_from_a_file() {
    let dir = scratch("python-map");
    let map = dir.join("map.json");
    std::fs::write(&map, r#"{"AlarmPrimitive": "", "TakeImagesPrimitive": ""}"#).unwrap();
    let Some(aac) = python_aac(&[
        "--map-file",
        map.to_str().unwrap(),
        "--map",
        "AltitudePrimitive=eventAltitudeOk",
        "--delay",
        "0.05",
    ]) else {
        return;
    };
    let mut cmd = mcl();
    cmd.arg("run").args(["--aac", &aac.addr]).arg(at_root("examples/survey.mcl")).args([
        "--set",
        "timeout=60",
        "--set",
        "altitude=2.5",
        "--set",
        "velocity=0.5",
    ]);
    let (code, out, err) = run_bounded(cmd, Duration::from_secs(60));
    let ctx = format!("stdout:\n{out}\nstderr:\n{err}\nAAC:\n{}", aac.log().join("\n"));
    assert_eq!(code, Some(0), "{ctx}");
    assert!(!out.contains("EmergencySurfacePrimitive enable"), "the alarm never fires\n{ctx}");
}

/// The actions and events of a trace, sorted: the reference AAC answers
/// Goto and Altitude at the same time, in either order.
fn sorted_calls(trace: &std::path::Path) -> Vec<String> {
    let mut v = calls(trace);
    v.sort();
    v
}

/// The player killed at several moments against the running Python
/// reference AAC (which answers meanwhile), then resumed with `--resume`:
/// the mission ends ok with the actions and events of an uninterrupted
/// run, every action executed exactly once.
#[test]
fn player_killed_and_resumed_against_the_python_aac() {
    if python().is_none() {
        return;
    }
    let dir = scratch("python-resume");
    let file = resume_mission(&dir);
    let mut reference = reference_calls(&dir, &file, "default_duration = 1\n");
    reference.sort();
    for (i, kill) in [Kill::After(1), Kill::After(3), Kill::When("eventDepthOk")].into_iter().enumerate() {
        let Some(aac) = python_aac(&["--delay", "0.3"]) else { return };
        let journal = dir.join(format!("j{i}.jsonl"));
        let trace = dir.join(format!("t{i}.jsonl"));
        crashed_run(&aac.addr, &file, &journal, &[], kill);
        // The vehicle goes on while the player is down.
        std::thread::sleep(Duration::from_millis(800));
        let (code, ctx) = resumed_run(&aac.addr, &file, &journal, &trace, &["-q"]);
        let ctx = format!("{kill:?}\n{ctx}\nAAC:\n{}", aac.log().join("\n"));
        assert_eq!(code, Some(0), "{ctx}");
        assert_eq!(sorted_calls(&trace), reference, "{ctx}");
        assert_eq!(odd_events(&trace), Vec::new(), "{ctx}");
        let mut executed = aac.executed();
        assert!(unique(&executed), "an action was executed twice\n{ctx}");
        executed.sort_unstable();
        let mut sent = sent(&trace);
        sent.sort_unstable();
        assert_eq!(executed, sent, "{ctx}");
    }
}

/// The Python reference AAC keeps no state: killed and restarted while the
/// player is down, it welcomes the resumed run in a new session; the player
/// restarts the primitives its marking says run, and the mission ends ok.
#[test]
fn python_aac_restarted_while_the_player_is_down() {
    let dir = scratch("python-restart");
    let file = resume_mission(&dir);
    let Some(mut first) = python_aac(&["--delay", "0.3"]) else { return };
    let addr = first.addr.clone();
    let journal = dir.join("j.jsonl");
    let trace = dir.join("t.jsonl");
    crashed_run(&addr, &file, &journal, &[], Kill::After(2));
    first.kill();
    let Some(second) = python_aac(&["--delay", "0.3", "--listen", &addr]) else { return };
    let (code, ctx) = resumed_run(&addr, &file, &journal, &trace, &["-q"]);
    let ctx = format!("{ctx}\nfirst AAC:\n{}\nsecond AAC:\n{}", first.log().join("\n"), second.log().join("\n"));
    assert_eq!(code, Some(0), "{ctx}");
    assert!(std::fs::read_to_string(&trace).unwrap().contains("lost its state"), "{ctx}");
    let (one, two) = (first.executed(), second.executed());
    assert!(two.iter().all(|s| one.iter().all(|o| s > o)), "no sequence number executed twice\n{ctx}");
}
