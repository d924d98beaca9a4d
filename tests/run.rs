//! `mcl run` and `mcl chronogram`, end to end through the binary: the
//! seed's missions against the mock vehicle, with the exact order of the
//! actions and events in the trace.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-run-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(root()).output().expect("run mcl")
}

fn trace(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad trace line {l}: {e}")))
        .collect()
}

fn fmt_t(t: f64) -> String {
    format!("{t}")
}

/// Actions as "t action" and events as "t !event", in trace order.
fn actions_and_events(tr: &[Value]) -> Vec<String> {
    tr.iter()
        .filter_map(|r| {
            let t = fmt_t(r["t"].as_f64().unwrap());
            match r["kind"].as_str().unwrap() {
                "action" => Some(format!("{t} {}", r["action"].as_str().unwrap())),
                "event" => Some(format!("{t} !{}", r["event"].as_str().unwrap())),
                _ => None,
            }
        })
        .collect()
}

fn outcome(tr: &[Value]) -> String {
    let o: Vec<&Value> = tr.iter().filter(|r| r["kind"] == "outcome").collect();
    assert_eq!(o.len(), 1, "one outcome record");
    o[0]["result"].as_str().unwrap().to_string()
}

/// Runs `mcl run --mock --virtual-time` with `extra` arguments and returns
/// (exit status, trace).
fn run_virtual(file: &str, extra: &[&str], trace_name: &str) -> (i32, Vec<Value>, Output) {
    let tp = tmp(trace_name);
    let tps = tp.to_str().unwrap();
    let mut args = vec!["run", "--mock", "--virtual-time", "--quiet", file, "--trace", tps];
    args.extend_from_slice(extra);
    let out = mcl(&args);
    let code = out.status.code().unwrap_or(-1);
    let tr = if tp.exists() { trace(&tp) } else { Vec::new() };
    (code, tr, out)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn survey_nominal_in_virtual_time() {
    let (code, tr, out) = run_virtual("examples/survey.mcl", &[], "survey.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        actions_and_events(&tr),
        [
            "0 enableAlarm",
            "0 enableInitializeVehicle",
            "5 !eventInitializeVehicleOk",
            "5 disableInitializeVehicle",
            "5 enableAltitude",
            "10 !eventAltitudeOk",
            "10 disableAltitude",
            "10 enableTakeImages",
            "10 enableTrajectory",
            "10 enableAltitude",
            "15 !eventTakeImagesOk",
            "15 disableTakeImages",
            "15 disableTrajectory",
            "15 disableAltitude",
            "15 enableSurface",
            "20 !eventSurfaceOk",
            "20 disableSurface",
            "20 enableStopVehicle",
            "25 !eventStopVehicleOk",
            "25 disableStopVehicle",
            "25 disableAlarm",
        ]
    );
    assert_eq!(outcome(&tr), "ok");
    // Parameters are resolved from each call's arguments.
    let alts: Vec<&Value> = tr.iter().filter(|r| r["action"] == "enableAltitude").collect();
    assert_eq!(alts[0]["params"]["mode"], "achieve");
    assert_eq!(alts[1]["params"]["mode"], "keep");
    assert_eq!(alts[1]["params"]["altitude"], "altitude", "an unset symbol is sent as is");
    let traj = tr.iter().find(|r| r["action"] == "enableTrajectory").unwrap();
    assert_eq!(traj["params"]["path"][1], serde_json::json!([20, 0]));
    assert_eq!(traj["task"], "Trajectory");
    assert_eq!(traj["src"], "examples/survey.mcl:18");
    // Sequence numbers increase by one.
    let seqs: Vec<u64> = tr.iter().filter(|r| r["kind"] == "action").map(|r| r["seq"].as_u64().unwrap()).collect();
    assert_eq!(seqs, (1..=seqs.len() as u64).collect::<Vec<_>>());
    // The unresolved `timeout` is reported once, with the default used.
    let warnings: Vec<&Value> = tr.iter().filter(|r| r["kind"] == "warning").collect();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0]["message"].as_str().unwrap().contains("using 60 s"));
    // An anonymous mission has no `mission` field.
    assert!(tr.iter().all(|r| r.get("mission").is_none()));
}

/// Seed figure 8.6: the alarm (the monitor's condition) at t = 120 aborts
/// everything that runs; every running primitive is disabled before
/// EmergencySurface is enabled.
#[test]
fn survey_alarm_disables_everything_before_emergency_surface() {
    let (code, tr, out) =
        run_virtual("examples/survey.mcl", &["--scenario", "examples/scenarios/survey-alarm.toml"], "alarm.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    let seq = actions_and_events(&tr);
    assert_eq!(
        seq,
        [
            "0 enableInitializeVehicle",
            "0 enableAlarm",
            "10 !eventInitializeVehicleOk",
            "10 disableInitializeVehicle",
            "10 enableAltitude",
            "18 !eventAltitudeOk",
            "18 disableAltitude",
            "18 enableTrajectory",
            "18 enableTakeImages",
            "18 enableAltitude",
            "120 !eventAlarmOk",
            "120 disableAlarm",
            "120 disableAltitude",
            "120 disableTakeImages",
            "120 disableTrajectory",
            "120 enableEmergencySurface",
            "150 !eventEmergencySurfaceOk",
            "150 disableEmergencySurface",
        ]
    );
    // The property itself: at the moment EmergencySurface is enabled, no
    // other primitive is enabled.
    let mut enabled: Vec<String> = Vec::new();
    for r in tr.iter().filter(|r| r["kind"] == "action") {
        let p = r["primitive"].as_str().unwrap().to_string();
        match r["command"].as_str().unwrap() {
            "enable" if p == "EmergencySurfacePrimitive" => {
                assert!(enabled.is_empty(), "still enabled when EmergencySurface starts: {enabled:?}");
            }
            "enable" => enabled.push(p),
            "disable" => enabled.retain(|x| *x != p),
            c => panic!("unexpected command {c}"),
        }
    }
    let alarm = tr.iter().find(|r| r["kind"] == "event").filter(|_| true);
    assert!(alarm.is_some());
    let ev = tr.iter().find(|r| r["event"] == "eventAlarmOk").unwrap();
    assert_eq!(ev["task"], "Alarm");
    assert_eq!(outcome(&tr), "ok");
}

/// The dam inspection whose wall inspection fails: the catch block runs
/// (Surface, StopVehicle).
#[test]
fn dam_inspection_failure_runs_the_catch_block() {
    let (code, tr, out) = run_virtual(
        "examples/dam-inspection.mcl",
        &["--scenario", "examples/scenarios/dam-wall-failure.toml"],
        "dam.jsonl",
    );
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        actions_and_events(&tr),
        [
            "0 enableInitializeVehicle",
            "0 enableAlarm",
            "5 !eventInitializeVehicleOk",
            "5 disableInitializeVehicle",
            "5 enableGoto",
            "30 !eventGotoOk",
            "30 disableGoto",
            "30 enableDistance",
            "30 enableHeading",
            "35 !eventHeadingOk",
            "35 disableHeading",
            "42 !eventDistanceOk",
            "42 disableDistance",
            "42 enableTakeImages",
            "42 enableWallInspection",
            "42 enableHeading",
            "42 enableDistance",
            "82 !eventWallInspectionFail",
            "82 disableWallInspection",
            "82 disableDistance",
            "82 disableHeading",
            "82 disableTakeImages",
            "82 enableSurface",
            "97 !eventSurfaceOk",
            "97 disableSurface",
            "97 enableStopVehicle",
            "102 !eventStopVehicleOk",
            "102 disableStopVehicle",
            "102 disableAlarm",
        ]
    );
    // The recovery Goto of the try block never ran.
    assert_eq!(tr.iter().filter(|r| r["action"] == "enableGoto").count(), 1);
    // The catch block's calls are the ones that ran Surface and StopVehicle.
    let surface = tr.iter().find(|r| r["action"] == "enableSurface").unwrap();
    assert_eq!(surface["src"], "examples/dam-inspection.mcl:41");
    assert_eq!(outcome(&tr), "ok");
}

/// A parallel-or: the first branch to end aborts the others, whose disable
/// actions come before the parallel's successor starts.
#[test]
fn parallel_or_aborts_the_other_branches_first() {
    let (code, tr, out) =
        run_virtual("tests/run/parallel-or.mcl", &["--scenario", "tests/run/parallel-or.toml"], "por.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        actions_and_events(&tr),
        [
            "0 enableTakeImages",
            "0 enableDepth",
            "0 enableGoto",
            "10 !eventGotoOk",
            "10 disableGoto",
            "10 disableDepth",
            "10 disableTakeImages",
            "10 enableSurface",
            "15 !eventSurfaceOk",
            "15 disableSurface",
        ]
    );
}

/// A timed task (stdlib AchieveOneGoalTimed) whose primitive never answers
/// fails by time-out; the delay comes from a number, then from a symbol.
#[test]
fn timed_task_fails_by_time_out() {
    let (code, tr, out) = run_virtual(
        "tests/run/timeout.mcl",
        &["--scenario", "tests/run/timeout.toml", "--set", "limit=7"],
        "timeout.jsonl",
    );
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        actions_and_events(&tr),
        [
            "0 enableScan",
            "4 !eventScanOk",
            "4 disableScan",
            "4 enableScan",
            "11 disableScan",
            "11 enableSurface",
            "16 !eventSurfaceOk",
            "16 disableSurface",
        ]
    );
    let timers: Vec<(f64, f64)> = tr
        .iter()
        .filter(|r| r["kind"] == "timer")
        .map(|r| (r["t"].as_f64().unwrap(), r["deadline"].as_f64().unwrap()))
        .collect();
    assert_eq!(timers, [(0.0, 10.0), (4.0, 11.0)], "the 1st timer uses 10, the 2nd the symbol limit = 7");
    let to: Vec<f64> = tr
        .iter()
        .filter(|r| r["kind"] == "fire" && r["transition"] == "task.Scan.TO")
        .map(|r| r["t"].as_f64().unwrap())
        .collect();
    assert_eq!(to, [11.0], "only the second scan times out");
    assert!(tr.iter().all(|r| r["kind"] != "warning"));

    // Without the symbol, the default delay (60 s) is used, with a warning.
    let (code, tr, _) = run_virtual("tests/run/timeout.mcl", &["--scenario", "tests/run/timeout.toml"], "t60.jsonl");
    assert_eq!(code, 0);
    assert!(actions_and_events(&tr).contains(&"64 disableScan".to_string()));
    assert!(tr.iter().any(|r| r["kind"] == "warning" && r["message"].as_str().unwrap().contains("--set limit=")));
}

#[test]
fn same_seed_same_trace() {
    let args = ["--scenario", "examples/scenarios/random-failures.toml"];
    let (c1, _, _) = run_virtual("examples/survey.mcl", &args, "d1.jsonl");
    let (c2, _, _) = run_virtual("examples/survey.mcl", &args, "d2.jsonl");
    assert_eq!(c1, c2);
    let a = std::fs::read(tmp("d1.jsonl")).unwrap();
    let b = std::fs::read(tmp("d2.jsonl")).unwrap();
    assert!(!a.is_empty());
    assert_eq!(a, b, "same seed, same trace");
    // The scenario's perceptions are traced.
    let tr = trace(&tmp("d1.jsonl"));
    assert!(tr.iter().any(|r| r["kind"] == "perception" && r["name"] == "battery"));
    // Other seeds choose other interleavings of the concurrent branches.
    let mut orders = std::collections::BTreeSet::new();
    for seed in 0..6 {
        let s = seed.to_string();
        let (_, tr, _) = run_virtual("examples/survey.mcl", &["--seed", &s], &format!("seed{seed}.jsonl"));
        orders.insert(actions_and_events(&tr));
    }
    assert!(orders.len() > 1, "the seed changes the random choices");
}

#[test]
fn unexpected_events_are_traced_and_not_fatal() {
    let sc = tmp("unexpected.toml");
    std::fs::write(
        &sc,
        "[[events]]\nat = 1\nevent = \"eventSurfaceOk\"\n[[events]]\nat = 2\nevent = \"noSuchEvent\"\n",
    )
    .unwrap();
    let (code, tr, out) = run_virtual("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "unexp.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    let unexpected: Vec<(f64, &str)> = tr
        .iter()
        .filter(|r| r["kind"] == "unexpected_event")
        .map(|r| (r["t"].as_f64().unwrap(), r["event"].as_str().unwrap()))
        .collect();
    assert_eq!(unexpected, [(1.0, "eventSurfaceOk"), (2.0, "noSuchEvent")]);
    assert_eq!(outcome(&tr), "ok");
    assert!(stderr(&out).contains("2 unexpected events"));
}

#[test]
fn stuck_missions_exit_3() {
    // The mock never answers InitializeVehicle: nothing more can happen.
    let sc = tmp("never.toml");
    std::fs::write(&sc, "[tasks.InitializeVehicle]\noutcome = \"never\"\n").unwrap();
    let (code, tr, _) = run_virtual("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "never.jsonl");
    assert_eq!(code, 3);
    let o = tr.iter().find(|r| r["kind"] == "outcome").unwrap();
    assert_eq!(o["result"], "stuck");
    let reason = o["reason"].as_str().unwrap();
    assert!(reason.contains("eventInitializeVehicleOk"), "{reason}");

    // A net in which nothing can fire any more (the player's own verdict).
    let mut b = mcl_net::NetBuilder::new("deadend");
    let begin = b.add_place(mcl_net::Place::new("mission.begin").with_tokens(1));
    let dead = b.add_place(mcl_net::Place::new("dead"));
    let ok = b.add_place(mcl_net::Place::new("mission.ok"));
    let t = b.add_transition(mcl_net::Transition::new("go"));
    let never = b.add_transition(mcl_net::Transition::new("never"));
    b.add_input(begin, t, 1).add_output(t, dead, 1);
    b.add_input(dead, never, 1).add_input(ok, never, 1);
    let net = b.build().unwrap();
    let pnml = tmp("deadend.pnml");
    std::fs::write(&pnml, mcl_net::write_pnml(&net).unwrap()).unwrap();
    let (code, tr, _) = run_virtual(pnml.to_str().unwrap(), &[], "deadend.jsonl");
    assert_eq!(code, 3);
    assert_eq!(outcome(&tr), "stuck");
    assert_eq!(tr.iter().find(|r| r["kind"] == "outcome").unwrap()["mission"], "deadend");

    // The time limit.
    let (code, tr, _) = run_virtual("examples/survey.mcl", &["--time-limit", "12"], "limit.jsonl");
    assert_eq!(code, 3);
    let o = tr.iter().find(|r| r["kind"] == "outcome").unwrap();
    assert_eq!((o["result"].as_str(), o["t"].as_f64()), (Some("time_limit"), Some(12.0)));
}

#[test]
fn exit_status_1_when_the_mission_fails() {
    let sc = tmp("fail.toml");
    std::fs::write(&sc, "[tasks.StopVehicle]\noutcome = \"fail\"\n").unwrap();
    let (code, tr, _) = run_virtual("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "fail.jsonl");
    assert_eq!(code, 1);
    assert_eq!(outcome(&tr), "fail");
    // The catch block ran StopVehicle a second time, which failed too.
    assert_eq!(tr.iter().filter(|r| r["action"] == "enableStopVehicle").count(), 2);
}

#[test]
fn usage_and_compile_errors_exit_2() {
    let out = mcl(&["run", "examples/survey.mcl"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--mock"));
    let out = mcl(&["run", "--aac", "127.0.0.1:1", "--virtual-time", "examples/survey.mcl"]);
    assert_eq!(out.status.code(), Some(2));

    let bad = tmp("bad.mcl");
    std::fs::write(&bad, "mission { Nope() }\n").unwrap();
    let out = mcl(&["run", "--mock", "--virtual-time", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("E0101"), "{}", stderr(&out));

    let sc = tmp("bad.toml");
    std::fs::write(&sc, "default_duration = 3\n[tasks.Goto]\ndelai = 4\n").unwrap();
    let out = mcl(&["run", "--mock", "--virtual-time", "examples/survey.mcl", "--scenario", sc.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("bad.toml:3:1: unknown field `delai`"), "{}", stderr(&out));

    // Scenarios naming tasks the mission never calls are reported.
    std::fs::write(&sc, "[tasks.Gotoo]\ndelay = 4\n").unwrap();
    let out =
        mcl(&["run", "--mock", "--virtual-time", "-q", "examples/survey.mcl", "--scenario", sc.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert!(stderr(&out).contains("never calls task `Gotoo`"));
}

#[test]
fn several_missions_and_compiled_nets() {
    // Without --mission, every mission runs, coordinated (tests/coord_run.rs).
    let (code, tr, out) = run_virtual("examples/auv-asc.mcl", &[], "auv.jsonl");
    assert_eq!(code, 0);
    assert!(stderr(&out).contains("coordination: 2 missions"));
    assert!(tr.iter().any(|r| r["mission"] == "auv") && tr.iter().any(|r| r["mission"] == "asc"));
    let (code, tr, _) = run_virtual("examples/auv-asc.mcl", &["--mission", "auv"], "auv.jsonl");
    assert_eq!(code, 0);
    assert!(tr.iter().all(|r| r["mission"] == "auv"));
    let (code, tr, _) = run_virtual("examples/auv-asc.mcl", &["--mission", "asc"], "asc.jsonl");
    assert_eq!(code, 0);
    assert!(tr.iter().all(|r| r["mission"] == "asc"));

    // A compiled .pnml runs like its source.
    let pnml = tmp("survey.pnml");
    let out = mcl(&["compile", "examples/survey.mcl", "-o", pnml.to_str().unwrap()]);
    assert!(out.status.success());
    let (code, from_pnml, _) = run_virtual(pnml.to_str().unwrap(), &[], "from-pnml.jsonl");
    let (_, from_mcl, _) = run_virtual("examples/survey.mcl", &[], "from-mcl.jsonl");
    assert_eq!(code, 0);
    assert_eq!(actions_and_events(&from_pnml), actions_and_events(&from_mcl));
}

/// The live log shows time, action or event, task and the call's line.
#[test]
fn live_log() {
    let out = mcl(&["run", "--mock", "--virtual-time", "examples/survey.mcl", "--set", "timeout=100"]);
    assert_eq!(out.status.code(), Some(0));
    let log = String::from_utf8_lossy(&out.stdout);
    let line = log.lines().find(|l| l.contains("eventAltitudeOk")).unwrap();
    assert!(line.contains("[    10.000] event    eventAltitudeOk  task=Altitude  at examples/survey.mcl:16"), "{line}");
    assert!(log.lines().last().unwrap().contains("MISSION OK"));
}

/// Crash (abort right after a journal sync, before the actions are sent)
/// and resume, in virtual time, at every point of the mission and twice in
/// a row: the trace equals the uninterrupted run's.
#[test]
fn resume_after_a_crash_gives_the_same_trace() {
    let sc = "examples/scenarios/survey-alarm.toml";
    let (code, _, _) = run_virtual("examples/survey.mcl", &["--scenario", sc], "whole.jsonl");
    assert_eq!(code, 0);
    let whole = std::fs::read(tmp("whole.jsonl")).unwrap();
    for n in 1..=4 {
        let j = tmp(&format!("crash{n}.journal"));
        let js = j.to_str().unwrap();
        let out = mcl(&[
            "run",
            "--mock",
            "--virtual-time",
            "-q",
            "examples/survey.mcl",
            "--scenario",
            sc,
            "--journal",
            js,
            "--crash-after",
            &n.to_string(),
        ]);
        assert!(!out.status.success() && out.status.code().is_none(), "the process was killed by a signal");
        // Resume, crash again after one more input, resume again.
        let out = mcl(&[
            "run",
            "--mock",
            "--virtual-time",
            "-q",
            "examples/survey.mcl",
            "--resume",
            js,
            "--crash-after",
            "1",
        ]);
        assert!(out.status.code().is_none() || out.status.success(), "{}", stderr(&out));
        let resumed = tmp(&format!("resumed{n}.jsonl"));
        let out = mcl(&[
            "run",
            "--mock",
            "--virtual-time",
            "-q",
            "examples/survey.mcl",
            "--resume",
            js,
            "--trace",
            resumed.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        assert_eq!(std::fs::read(&resumed).unwrap(), whole, "crash after {n} inputs");
    }
    // A journal of another mission is refused.
    let out = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        "examples/dam-inspection.mcl",
        "--resume",
        tmp("crash1.journal").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("another mission"), "{}", stderr(&out));
}

/// kill -9 of a real-time run (in-process mock, high speed), then resume:
/// the same actions and events in the same order as an uninterrupted run.
#[test]
fn kill_9_in_real_time_and_resume() {
    let sc = "examples/scenarios/survey-nominal.toml";
    let (code, reference, _) = run_virtual("examples/survey.mcl", &["--scenario", sc], "rt-ref.jsonl");
    assert_eq!(code, 0);
    let j = tmp("rt.journal");
    let js = j.to_str().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--speed", "40", "-q", "examples/survey.mcl", "--scenario", sc, "--journal", js])
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the trajectory has started (t = 18 s, 0.45 s of real time), then kill -9.
    let started = Instant::now();
    loop {
        let text = std::fs::read_to_string(&j).unwrap_or_default();
        if text.contains("\"event\":\"eventAltitudeOk\"") {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(20), "the run did not progress");
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be killed");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let resumed = tmp("rt-resumed.jsonl");
    let out = mcl(&[
        "run",
        "--mock",
        "--speed",
        "40",
        "-q",
        "examples/survey.mcl",
        "--resume",
        js,
        "--trace",
        resumed.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let tr = trace(&resumed);
    let names = |tr: &[Value]| -> Vec<String> {
        actions_and_events(tr).iter().map(|s| s.split_once(' ').unwrap().1.to_string()).collect()
    };
    assert_eq!(names(&tr), names(&reference));
    assert_eq!(outcome(&tr), "ok");
    // Event times are not compared: real time on a shared machine drifts by
    // an unbounded amount, and tests never assert timings.
}

/// Real time with the in-process mock plays the same mission as virtual time.
#[test]
fn real_time_matches_virtual_time() {
    let sc = "examples/scenarios/survey-nominal.toml";
    let (_, reference, _) = run_virtual("examples/survey.mcl", &["--scenario", sc], "rt2-ref.jsonl");
    let tp = tmp("rt2.jsonl");
    let started = Instant::now();
    let out = mcl(&[
        "run",
        "--mock",
        "--speed",
        "100",
        "-q",
        "examples/survey.mcl",
        "--scenario",
        sc,
        "--trace",
        tp.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let took = started.elapsed();
    assert!(took >= Duration::from_millis(1300), "133 s at speed 100 took {took:?}");
    let tr = trace(&tp);
    let names = |tr: &[Value]| -> Vec<String> {
        actions_and_events(tr).iter().map(|s| s.split_once(' ').unwrap().1.to_string()).collect()
    };
    assert_eq!(names(&tr), names(&reference));
}

fn png_size(path: &Path) -> Option<(u32, u32, u64)> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() < 24 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let w = u32::from_be_bytes(bytes[16..20].try_into().ok()?);
    let h = u32::from_be_bytes(bytes[20..24].try_into().ok()?);
    Some((w, h, bytes.len() as u64))
}

fn screenshot(svg: &Path, png: &Path) -> bool {
    let profile = tmp(&format!("chromium-{}", png.file_stem().unwrap().to_string_lossy()));
    let status = Command::new("/usr/bin/chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--screenshot={}", png.display()),
            "--window-size=1600,900",
            &format!("file://{}", svg.display()),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    status.is_ok_and(|s| s.success())
}

/// The chronogram of the dam inspection renders in a real browser.
#[test]
fn chronogram_renders_in_a_browser() {
    let svg = tmp("dam.svg");
    let tp = tmp("dam-chrono.jsonl");
    let out = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        "-q",
        "examples/dam-inspection.mcl",
        "--scenario",
        "examples/scenarios/dam-wall-failure.toml",
        "--trace",
        tp.to_str().unwrap(),
        "--chronogram",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
    for row in ["WallInspectionPrimitive", "SurfacePrimitive", "StopVehiclePrimitive", "mission OK"] {
        assert!(text.contains(row), "{row}");
    }
    // `mcl chronogram` renders the same picture from the trace.
    let svg2 = tmp("dam2.svg");
    let out = mcl(&["chronogram", tp.to_str().unwrap(), "-o", svg2.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&svg2).unwrap(), text);

    if !Path::new("/usr/bin/chromium").exists() {
        println!(
            "note: /usr/bin/chromium is absent; the browser rendering check is skipped (apt-get install chromium)"
        );
        return;
    }
    let png = tmp("dam.png");
    assert!(screenshot(&svg, &png), "chromium failed");
    let (w, h, size) = png_size(&png).expect("a PNG");
    assert_eq!((w, h), (1600, 900));
    // A blank page of the same size, for comparison.
    let blank = tmp("blank.svg");
    std::fs::write(&blank, r##"<svg xmlns="http://www.w3.org/2000/svg" width="1600" height="900"><rect width="1600" height="900" fill="#fff"/></svg>"##).unwrap();
    let blank_png = tmp("blank.png");
    assert!(screenshot(&blank, &blank_png));
    let (_, _, blank_size) = png_size(&blank_png).expect("a PNG");
    assert!(size > 4 * blank_size, "the screenshot looks blank: {size} bytes vs {blank_size} for a blank page");
}
