//! `mcl run` and `mcl chronogram`, end to end through the binary: the
//! seed's missions against the mock vehicle, with the exact order of the
//! actions and events in the trace.

use mcl_runtime::trace::{Call, Ends, Record, RecordKind};
use mcl_testutil::browser;
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

fn trace(path: &Path) -> Vec<Record> {
    mcl_runtime::trace::read_trace(path).unwrap_or_else(|e| panic!("{e}"))
}

fn fmt_t(t: f64) -> String {
    format!("{t}")
}

/// An `action` record.
#[derive(Debug)]
struct Act<'a> {
    t: f64,
    mission: Option<&'a str>,
    seq: u64,
    action: &'a str,
    primitive: &'a str,
    command: &'a str,
    params: &'a mcl_runtime::params::Params,
    call: &'a Call,
    queued: bool,
}

/// The actions of a trace.
fn acts(tr: &[Record]) -> Vec<Act<'_>> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Action { seq, action, primitive, command, params, call, queued } => Some(Act {
                t: r.t,
                mission: r.mission.as_deref(),
                seq: *seq,
                action,
                primitive,
                command,
                params,
                call,
                queued: *queued,
            }),
            _ => None,
        })
        .collect()
}

/// The action named `name` (the first).
fn act<'a>(tr: &'a [Record], name: &str) -> Act<'a> {
    acts(tr).into_iter().find(|a| a.action == name).unwrap_or_else(|| panic!("no action {name}"))
}

/// An `outcome` record.
#[derive(Debug)]
struct End<'a> {
    t: f64,
    mission: Option<&'a str>,
    result: &'a str,
    reason: Option<&'a str>,
    via: Option<&'a str>,
}

/// The outcomes of a trace.
fn ends(tr: &[Record]) -> Vec<End<'_>> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Outcome { result, reason, via } => Some(End {
                t: r.t,
                mission: r.mission.as_deref(),
                result,
                reason: reason.as_deref(),
                via: via.as_deref(),
            }),
            _ => None,
        })
        .collect()
}

/// The messages of the warnings of a trace.
fn warnings(tr: &[Record]) -> Vec<&str> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Warning { message } => Some(message.as_str()),
            _ => None,
        })
        .collect()
}

/// The times at which `transition` fired.
fn fired(tr: &[Record], transition: impl Fn(&str) -> bool) -> Vec<f64> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Fire { transition: t, .. } if transition(t) => Some(r.t),
            _ => None,
        })
        .collect()
}

/// The unexpected and stale events of a trace.
fn odd_events(tr: &[Record]) -> Vec<&Record> {
    tr.iter().filter(|r| matches!(r.kind, RecordKind::UnexpectedEvent { .. } | RecordKind::StaleEvent { .. })).collect()
}

/// Actions as "t action" and events as "t !event", in trace order.
fn actions_and_events(tr: &[Record]) -> Vec<String> {
    tr.iter()
        .filter_map(|r| {
            let t = fmt_t(r.t);
            match &r.kind {
                RecordKind::Action { action, .. } => Some(format!("{t} {action}")),
                RecordKind::Event { event, .. } => Some(format!("{t} !{event}")),
                _ => None,
            }
        })
        .collect()
}

fn outcome(tr: &[Record]) -> String {
    let o = ends(tr);
    assert_eq!(o.len(), 1, "one outcome record");
    o[0].result.to_string()
}

/// Runs `mcl run --mock --virtual-time` with `extra` arguments and returns
/// (exit status, trace).
fn run_virtual(file: &str, extra: &[&str], trace_name: &str) -> (i32, Vec<Record>, Output) {
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

/// Actions as "t action call_site" and events as "t !event call_site", in trace order.
fn per_call(tr: &[Record]) -> Vec<String> {
    tr.iter()
        .filter_map(|r| {
            let t = fmt_t(r.t);
            let site = |c: &Call| c.call_site.map_or("null".to_string(), |n| n.to_string());
            match &r.kind {
                RecordKind::Action { action, call, .. } => Some(format!("{t} {action} @{}", site(call))),
                RecordKind::Event { event, call, .. } => Some(format!("{t} !{event} @{}", site(call))),
                _ => None,
            }
        })
        .collect()
}

/// Seed figure 8.5: the survey as planned. Initialization (10 s), the
/// altitude reached (8 s), then the trajectory with images and the altitude
/// kept: the trajectory ends the parallel-or at 108 s, which aborts the two
/// others; then surface (20 s) and stop.
#[test]
fn survey_nominal_in_virtual_time() {
    let (code, tr, out) = run_virtual(
        "examples/survey.mcl",
        &["--scenario", "examples/scenarios/survey-nominal.toml"],
        "survey-nominal.jsonl",
    );
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        per_call(&tr),
        [
            "0 enableInitializeVehicle @1",
            "0 enableAlarm @10",
            "10 !eventInitializeVehicleOk @1",
            "10 disableInitializeVehicle @1",
            "10 enableAltitude @2",
            "18 !eventAltitudeOk @2",
            "18 disableAltitude @2",
            "18 enableTrajectory @3",
            // The second Altitude call waits for its task's release (the
            // first call's task is at rest), so it starts last in the instant.
            "18 enableTakeImages @4",
            "18 enableAltitude @5",
            "108 !eventTrajectoryOk @3",
            "108 disableTrajectory @3",
            "108 disableAltitude @5",
            "108 disableTakeImages @4",
            "108 enableSurface @6",
            "128 !eventSurfaceOk @6",
            "128 disableSurface @6",
            "128 enableStopVehicle @7",
            "133 !eventStopVehicleOk @7",
            "133 disableStopVehicle @7",
            "133 disableAlarm @10",
        ]
    );
    assert_eq!(outcome(&tr), "ok");
    assert_eq!(ends(&tr)[0].t, 133.0);
    // The scenario's symbols are sent instead of the symbols' names.
    let alts: Vec<Act<'_>> = acts(&tr).into_iter().filter(|a| a.action == "enableAltitude").collect();
    assert_eq!((alts[0].params["mode"].as_str(), alts[0].params["altitude"].as_f64()), (Some("achieve"), Some(2.5)));
    assert_eq!(alts[1].params["mode"], "keep");
    assert_eq!(act(&tr, "enableTrajectory").params["velocity"], 0.5);
    // The time-outs (timeout = 200 s) never fire: no warning, no time-out.
    assert!(warnings(&tr).is_empty(), "{tr:?}");
    assert!(fired(&tr, |t| t.ends_with(".TO")).is_empty());
}

/// The survey with the mock's default answers (every task ok after 5 s).
#[test]
fn survey_with_default_answers() {
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
    let alts: Vec<Act<'_>> = acts(&tr).into_iter().filter(|a| a.action == "enableAltitude").collect();
    assert_eq!(alts[0].params["mode"], "achieve");
    assert_eq!(alts[1].params["mode"], "keep");
    assert_eq!(alts[1].params["altitude"], "altitude", "an unset symbol is sent as is");
    let traj = act(&tr, "enableTrajectory");
    assert_eq!(traj.params["path"][1], serde_json::json!([20, 0]));
    assert_eq!(traj.call.task.as_deref(), Some("Trajectory"));
    assert_eq!(traj.call.src.as_deref(), Some("examples/survey.mcl:18"));
    // Sequence numbers increase by one.
    let seqs: Vec<u64> = acts(&tr).iter().map(|a| a.seq).collect();
    assert_eq!(seqs, (1..=seqs.len() as u64).collect::<Vec<_>>());
    // The unresolved `timeout` is reported once, with the default used.
    let warnings = warnings(&tr);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("using 60 s"));
    // An anonymous mission has no `mission` field.
    assert!(tr.iter().all(|r| r.mission.is_none()));
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
    for a in acts(&tr) {
        let p = a.primitive.to_string();
        match a.command {
            "enable" if p == "EmergencySurfacePrimitive" => {
                assert!(enabled.is_empty(), "still enabled when EmergencySurface starts: {enabled:?}");
            }
            "enable" => enabled.push(p),
            "disable" => enabled.retain(|x| *x != p),
            c => panic!("unexpected command {c}"),
        }
    }
    let alarm = tr.iter().find_map(|r| match &r.kind {
        RecordKind::Event { event, call, .. } if event == "eventAlarmOk" => Some(call),
        _ => None,
    });
    assert_eq!(alarm.and_then(|c| c.task.as_deref()), Some("Alarm"));
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
    assert_eq!(acts(&tr).iter().filter(|a| a.action == "enableGoto").count(), 1);
    // The catch block's calls are the ones that ran Surface and StopVehicle.
    assert_eq!(act(&tr, "enableSurface").call.src.as_deref(), Some("examples/dam-inspection.mcl:41"));
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
        .filter_map(|r| match r.kind {
            RecordKind::Timer { deadline, .. } => Some((r.t, deadline)),
            _ => None,
        })
        .collect();
    assert_eq!(timers, [(0.0, 10.0), (4.0, 11.0)], "the 1st timer uses 10, the 2nd the symbol limit = 7");
    let to = fired(&tr, |t| t == "task.Scan.TO");
    assert_eq!(to, [11.0], "only the second scan times out");
    assert!(warnings(&tr).is_empty());

    // Without the symbol, the default delay (60 s) is used, with a warning.
    let (code, tr, _) = run_virtual("tests/run/timeout.mcl", &["--scenario", "tests/run/timeout.toml"], "t60.jsonl");
    assert_eq!(code, 0);
    assert!(actions_and_events(&tr).contains(&"64 disableScan".to_string()));
    assert!(warnings(&tr).iter().any(|m| m.contains("--set limit=")));
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
    assert!(tr.iter().any(|r| matches!(&r.kind, RecordKind::Perception { name, .. } if name == "battery")));
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
        "[[events]]\nat = 1\nevent = \"eventSurfaceOk\"\n[[events]]\nat = 2\nevent = \"noSuchEvent\"\nunexpected = true\n",
    )
    .unwrap();
    let (code, tr, out) = run_virtual("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "unexp.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    let unexpected: Vec<(f64, &str)> = tr
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::UnexpectedEvent { event, .. } => Some((r.t, event.as_str())),
            _ => None,
        })
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
    let o = &ends(&tr)[0];
    assert_eq!(o.result, "stuck");
    let reason = o.reason.unwrap();
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
    assert_eq!(ends(&tr)[0].mission, Some("deadend"));

    // The time limit.
    let (code, tr, _) = run_virtual("examples/survey.mcl", &["--time-limit", "12"], "limit.jsonl");
    assert_eq!(code, 3);
    let o = &ends(&tr)[0];
    assert_eq!((o.result, o.t), ("time_limit", 12.0));
}

#[test]
fn exit_status_1_when_the_mission_fails() {
    let sc = tmp("fail.toml");
    std::fs::write(&sc, "[tasks.StopVehicle]\noutcome = \"fail\"\n").unwrap();
    let (code, tr, _) = run_virtual("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "fail.jsonl");
    assert_eq!(code, 1);
    assert_eq!(outcome(&tr), "fail");
    // The catch block ran StopVehicle a second time, which failed too.
    assert_eq!(acts(&tr).iter().filter(|a| a.action == "enableStopVehicle").count(), 2);
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

    // A scenario is checked against the program when loaded: a task the
    // mission never calls, a label no call has, an event no transition
    // waits for are errors with their line and a did-you-mean; nothing runs.
    std::fs::write(
        &sc,
        "[tasks.Gotoo]\ndelay = 4\n[tasks.Altitude.label.nope]\noutcome = \"fail\"\n\n[[events]]\nat = 120.0\nevent = \"eventAlarmOkk\"\n\n[[perceptions]]\nafter = \"batteryLo\"\nname = \"battery\"\nvalue = 0.1\n",
    )
    .unwrap();
    let out =
        mcl(&["run", "--mock", "--virtual-time", "-q", "examples/survey.mcl", "--scenario", sc.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(err.contains("bad.toml:1:1: the mission never calls task `Gotoo`"), "{err}");
    assert!(err.contains("bad.toml:3:1: no call of `Altitude` is labelled `nope`"), "{err}");
    assert!(
        err.contains("bad.toml:8:9: event `eventAlarmOkk` at 120 s: no transition waits for it (add `unexpected = true` to send it on purpose); did you mean `eventAlarmOk`?"),
        "{err}"
    );
    assert!(err.contains("bad.toml:11:9: perception `battery` comes after event `batteryLo`"), "{err}");
    assert!(!err.contains("MISSION"), "nothing ran: {err}");
}

#[test]
fn several_missions_and_compiled_nets() {
    // Without --mission, every mission runs, coordinated (tests/coord_run.rs).
    let (code, tr, out) = run_virtual("examples/auv-asc.mcl", &[], "auv.jsonl");
    assert_eq!(code, 0);
    assert!(stderr(&out).contains("coordination: 2 missions"));
    let of = |r: &Record, m: &str| r.mission.as_deref() == Some(m);
    assert!(tr.iter().any(|r| of(r, "auv")) && tr.iter().any(|r| of(r, "asc")));
    let (code, tr, _) = run_virtual("examples/auv-asc.mcl", &["--mission", "auv"], "auv.jsonl");
    assert_eq!(code, 0);
    assert!(tr.iter().all(|r| of(r, "auv")));
    let (code, tr, _) = run_virtual("examples/auv-asc.mcl", &["--mission", "asc"], "asc.jsonl");
    assert_eq!(code, 0);
    assert!(tr.iter().all(|r| of(r, "asc")));

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
    assert!(
        line.contains("[    10.000] event    eventAltitudeOk  (ends ok)  task=Altitude  at examples/survey.mcl:16"),
        "{line}"
    );
    assert!(log.lines().last().unwrap().contains("MISSION OK"));
}

/// The outcome says how the mission got there when it left its nominal
/// path: through a catch (the dam inspection whose wall inspection fails),
/// or through a monitor's condition (the survey's alarm); a mission that
/// completes its plan says nothing more.
#[test]
fn the_outcome_says_how_the_mission_ended() {
    let (code, tr, out) = run_virtual(
        "examples/dam-inspection.mcl",
        &["--scenario", "examples/scenarios/dam-wall-failure.toml"],
        "via-catch.jsonl",
    );
    assert_eq!(code, 0, "{}", stderr(&out));
    let end = ends(&tr).pop().unwrap();
    assert_eq!(end.via, Some("the catch at examples/dam-inspection.mcl:18"), "{end:?}");
    assert!(tr.iter().any(|r| matches!(r.kind, RecordKind::Fire { ends: Some(Ends::Catch), .. })));
    assert!(stderr(&out).contains("OK through the catch at examples/dam-inspection.mcl:18"), "{}", stderr(&out));
    // The chronogram's title says it too.
    let svg = tmp("via-catch.svg");
    let t = tmp("via-catch.jsonl");
    let c = mcl(&["chronogram", t.to_str().unwrap(), "-o", svg.to_str().unwrap()]);
    assert!(c.status.success(), "{}", stderr(&c));
    let drawing = std::fs::read_to_string(&svg).unwrap();
    assert!(drawing.contains("OK through the catch at examples/dam-inspection.mcl:18 at 102 s"), "{drawing}");

    let (code, tr, out) = run_virtual(
        "examples/survey.mcl",
        &["--scenario", "examples/scenarios/survey-alarm.toml"],
        "via-condition.jsonl",
    );
    assert_eq!(code, 0, "{}", stderr(&out));
    let end = ends(&tr).pop().unwrap();
    assert_eq!(end.via, Some("the condition of the monitor at examples/survey.mcl:13"), "{end:?}");

    let (code, tr, out) = run_virtual("examples/survey.mcl", &[], "via-none.jsonl");
    assert_eq!(code, 0);
    let end = ends(&tr).pop().unwrap();
    assert!(end.via.is_none(), "{end:?}");
    assert!(!stderr(&out).contains("through"), "{}", stderr(&out));
}

/// A vehicle whose names follow no convention (`navReady`, `navLost`,
/// `mowDone`): what an event ends comes from the compiled net — the trace's
/// `ends`, the live log, the chronogram's colours — and a time-out shows in
/// the default live log.
#[test]
fn outcomes_come_from_the_net_not_from_names() {
    let file = tmp("odd-names.mcl");
    std::fs::write(
        &file,
        r#"
actions {
    startNav = NavPrimitive( c: enable );
    stopNav = NavPrimitive( c: disable );
    startMow = MowPrimitive( c: enable );
    stopMow = MowPrimitive( c: disable );
}
events { navReady; navLost; mowDone; mowStuck; }
tasks {
    Nav(): AchieveOneGoal { a: startNav -> T0; a: stopNav -> T1, T6, T7; e: navReady -> T2; e: navLost -> T3; }
    Mow( timeout ): AchieveOneGoalTimed { a: startMow -> T0; a: stopMow -> T1, T6, T7; e: mowDone -> T2; e: mowStuck -> T3; }
}
mission { Nav() ; try { Mow( 3 ) } catch { Mow( 100 ) } }
"#,
    )
    .unwrap();
    let trace = tmp("odd-names.jsonl");
    let svg = tmp("odd-names.svg");
    let out = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        file.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
        "--chronogram",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let log = String::from_utf8_lossy(&out.stdout);
    assert!(log.lines().any(|l| l.contains("event    navReady  (ends ok)  task=Nav")), "{log}");
    assert!(log.lines().any(|l| l.contains("[     8.000] TIME-OUT task.Mow.TO  task=Mow")), "{log}");
    let records = self::trace(&trace);
    let events: Vec<Option<Ends>> = records
        .iter()
        .filter_map(|r| match r.kind {
            RecordKind::Event { ends, .. } => Some(ends),
            _ => None,
        })
        .collect();
    assert!(!events.is_empty() && events.iter().all(|e| *e == Some(Ends::Ok)), "{events:?}");
    assert!(records.iter().any(|r| matches!(r.kind, RecordKind::Fire { ends: Some(Ends::Timeout), .. })));
    // Every bar of the chronogram ends ok (green) or timed out (orange);
    // none is left "aborted / running" (blue, then only in the legend).
    let drawing = std::fs::read_to_string(&svg).unwrap();
    assert!(drawing.contains("fill=\"#b7e2c0\"") && drawing.contains("fill=\"#f7d49a\""), "ok and time-out bars");
    assert_eq!(drawing.matches("fill=\"#b9d2ee\"").count(), 1, "no bar left blue, only the legend's box");
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
    // The same actions (with their parameters) and events, each credited to
    // the same call, and the same outcome. Times are not compared: real time
    // on a shared machine drifts by an unbounded amount, and tests never
    // assert timings.
    assert_eq!(attribution(&tr), attribution(&reference));
    assert_eq!(outcome(&tr), "ok");
    assert_eq!(odd_events(&tr), Vec::<&Record>::new());
}

/// Every action (with its parameters and sequence number) and every event
/// with the call it is credited to (task, call site, label), and the
/// outcome, per mission, without times. Coordination messages delivered as
/// events are left out (their place among a vehicle's records depends on
/// when they arrive).
fn attribution(tr: &[Record]) -> Vec<String> {
    let mut v: Vec<(String, String)> = tr
        .iter()
        .filter_map(|r| {
            let m = r.mission.as_deref().unwrap_or("");
            match &r.kind {
                RecordKind::Action { seq, action, params, call, .. } => Some(format!(
                    "{m} action #{seq} {action} {params:?} task {:?} call {:?} {:?}",
                    call.task, call.call_site, call.label
                )),
                // `activation`: the action whose primitive run raised the event.
                RecordKind::Event { event, call, activation, .. } if !event.contains('/') => Some(format!(
                    "{m} event {event} task {:?} call {:?} {:?} activation {activation:?}",
                    call.task, call.call_site, call.label
                )),
                RecordKind::Outcome { result, .. } => Some(format!("{m} outcome {result}")),
                _ => None,
            }
            .map(|line| (m.to_string(), line))
        })
        .collect();
    // Mission by mission: vehicles run concurrently.
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v.into_iter().map(|(_, line)| line).collect()
}

/// Every bundled example (but the vehicle definitions, which have no
/// mission) ends ok in virtual time and in real time with the in-process
/// mock, and real time credits every event to the same call as virtual time
/// (the audit found a late answer of an aborted call credited to the next
/// call of the same task), with no unexpected event.
#[test]
fn every_example_in_virtual_and_real_time() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mcl") && !p.ends_with("vehicle.mcl"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "{files:?}");
    for f in &files {
        let name = f.file_stem().unwrap().to_string_lossy().to_string();
        let file = f.to_str().unwrap();
        let (code, v, out) = run_virtual(file, &["--seed", "3"], &format!("all-v-{name}.jsonl"));
        assert_eq!(code, 0, "{name} in virtual time: {}", stderr(&out));
        let tp = tmp(&format!("all-r-{name}.jsonl"));
        let out = mcl(&["run", "--mock", "--speed", "50", "--seed", "3", "-q", file, "--trace", tp.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{name} in real time: {}", stderr(&out));
        let r = trace(&tp);
        assert_eq!(attribution(&r), attribution(&v), "{name}: real time differs from virtual time");
        assert_eq!(odd_events(&r), Vec::<&Record>::new(), "{name}");
        assert_eq!(odd_events(&v), Vec::<&Record>::new(), "{name}");
    }
}

/// Extract 5.4 in real time: the keep Depth's answer, due at the same
/// instant as Goto's, is not credited to the next Depth call (which would
/// end the mission at t = 10 instead of 15, with a disable of a primitive
/// that never answered).
#[test]
fn extract_5_4_in_real_time_credits_each_call() {
    let tp = tmp("x54-rt.jsonl");
    let out = mcl(&[
        "run",
        "--mock",
        "--speed",
        "20",
        "--seed",
        "3",
        "-q",
        "examples/extract-5-4.mcl",
        "--trace",
        tp.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let tr = trace(&tp);
    let events: Vec<String> = tr
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Event { event, call, activation, .. } => {
                let n = |x: Option<u64>| x.map_or("null".to_string(), |n| n.to_string());
                Some(format!("{event} @{} #{}", n(call.call_site.map(u64::from)), n(*activation)))
            }
            _ => None,
        })
        .collect();
    assert_eq!(events, ["eventDepthOk @1 #1", "eventGotoOk @3 #3", "eventDepthOk @4 #7"]);
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
    let names = |tr: &[Record]| -> Vec<String> {
        actions_and_events(tr).iter().map(|s| s.split_once(' ').unwrap().1.to_string()).collect()
    };
    assert_eq!(names(&tr), names(&reference));
}

/// `while ( not ( C() ) )`: the mock's default answer for C is ok, so that
/// the negated condition fails and the loop ends (under two `not`s, C fails
/// again). examples/appendix-c.mcl looped forever.
#[test]
fn negated_while_conditions_end_by_default() {
    let (code, tr, out) = run_virtual("tests/run/not-while.mcl", &[], "not-while.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    assert_eq!(
        actions_and_events(&tr),
        [
            "0 enableGetPositionFix",
            "5 !eventGetPositionFixOk",
            "5 disableGetPositionFix",
            "5 enableInvalidPositioning",
            "10 !eventInvalidPositioningFail",
            "10 disableInvalidPositioning",
            "10 enableSurface",
            "15 !eventSurfaceOk",
            "15 disableSurface",
        ]
    );
    // The AUV's `while ( not ( SurveyDone() ) )` ends and the AUV goes on
    // to its recovery way-point; both end ok.
    let (code, tr, out) = run_virtual("examples/appendix-c.mcl", &[], "appendix-c.jsonl");
    assert_eq!(code, 0, "{}", stderr(&out));
    let after_loop = acts(&tr).iter().any(|a| a.action == "enableGoto" && a.mission == Some("m1"));
    assert!(after_loop, "the AUV left its survey loop");
    let outcomes = ends(&tr);
    for m in ["m1", "m2"] {
        assert!(outcomes.iter().any(|o| o.result == "ok" && o.mission == Some(m)), "{outcomes:?}");
    }
}

/// A mission that loops forever stops at the default time limit of
/// virtual time (exit 3), with a message that says how to change it; a
/// loop whose tasks answer at once stops as a zero-time loop.
#[test]
fn looping_missions_stop_in_virtual_time() {
    let sc = tmp("loop.toml");
    std::fs::write(
        &sc,
        "default_duration = 400
[tasks.GetPositionFix]
outcome = \"ok\"
",
    )
    .unwrap();
    let (code, tr, out) = run_virtual("tests/run/loop.mcl", &["--scenario", sc.to_str().unwrap()], "loop.jsonl");
    assert_eq!(code, 3, "{}", stderr(&out));
    let o = ends(&tr);
    assert_eq!((o.len(), o[0].result, o[0].t), (1, "time_limit", 86_400.0));
    let reason = o[0].reason.unwrap();
    assert!(reason.contains("default time limit") && reason.contains("--time-limit"), "{reason}");
    assert!(stderr(&out).contains("TIME_LIMIT at t=86400.000 s"), "{}", stderr(&out));
    // --time-limit overrides it; `inf` removes it (the loop then needs the
    // zero-time guard or the user to stop it: not tried here).
    let (code, tr, _) =
        run_virtual("tests/run/loop.mcl", &["--scenario", sc.to_str().unwrap(), "--time-limit", "2000"], "loop2.jsonl");
    assert_eq!(code, 3);
    let o = ends(&tr);
    assert_eq!((o[0].t, o[0].reason), (2000.0, Some("the time limit of 2000 s passed")));

    // Answers at once: mission time never advances.
    std::fs::write(
        &sc,
        "default_duration = 0
[tasks.GetPositionFix]
outcome = \"ok\"
",
    )
    .unwrap();
    let out = mcl(&["run", "--mock", "--virtual-time", "tests/run/loop.mcl", "--scenario", sc.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    let log = String::from_utf8_lossy(&out.stdout);
    let last = log.lines().last().unwrap();
    assert!(last.contains("MISSION STUCK: zero-time loop"), "{last}");
}

/// The time reported at a time limit is the limit (the trace's), not the
/// time of the last input.
#[test]
fn time_limit_is_reported_at_the_limit() {
    let (code, tr, out) = run_virtual("examples/survey.mcl", &["--time-limit", "12"], "limit12.jsonl");
    assert_eq!(code, 3);
    assert_eq!(ends(&tr)[0].t, 12.0);
    assert!(stderr(&out).contains("TIME_LIMIT at t=12.000 s"), "{}", stderr(&out));
    let out = mcl(&["run", "--mock", "--virtual-time", "-q", "--time-limit", "-1", "examples/survey.mcl"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Against an AAC that cannot be reached: the live log says that actions
/// are queued, and shows every connection attempt with its backoff; at the
/// time limit the run ends at once, saying the actions were never sent (a
/// vehicle that never saw the run has nothing to stop).
#[test]
fn unreachable_aac_is_told_in_the_live_log() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let tp = tmp("unreachable.jsonl");
    let out = mcl(&[
        "run",
        "--aac",
        &addr,
        "--connect-timeout",
        "1.5",
        "examples/extract-5-4.mcl",
        "--trace",
        tp.to_str().unwrap(),
    ]);
    // Nobody answers: exit 2 after the connect timeout, and the mission never
    // started (no action queued, no time-out counting down meanwhile).
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let log = String::from_utf8_lossy(&out.stdout);
    let attempts: Vec<&str> = log.lines().filter(|l| l.contains("link     cannot connect to")).collect();
    assert!(attempts.len() >= 2, "{log}");
    assert!(attempts.iter().all(|l| l.contains("retrying in") && l.contains("(attempt ")), "{log}");
    assert!(!log.contains("action "), "{log}");
    let err = stderr(&out);
    assert!(err.contains("no vehicle answered within 1.5 s"), "{err}");
    // The trace has the attempts and nothing else happened.
    let tr = trace(&tp);
    assert!(tr.iter().filter(|r| matches!(r.kind, RecordKind::Link { .. })).count() >= 2);
    assert!(acts(&tr).is_empty());
    // -q: no live log and no link lines; the error says the link's last notice.
    let out = mcl(&["run", "--aac", &addr, "-q", "--connect-timeout", "1", "examples/extract-5-4.mcl"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(!err.lines().any(|l| l.starts_with("link")), "{err}");
    assert_eq!(err.lines().filter(|l| l.contains("retrying in")).count(), 1, "only the last notice: {err}");
    assert!(err.contains("no vehicle answered within 1 s"), "{err}");
    assert!(err.contains("the link's last notice: cannot connect to"), "{err}");
    assert!(String::from_utf8_lossy(&out.stdout).is_empty());
}

/// The mission clock starts when the vehicle is connected: an AAC that
/// starts listening 1.5 s after the player does not eat into the mission's
/// time-outs, and the first action is sent at mission time 0.
#[test]
fn the_mission_starts_when_the_vehicle_is_connected() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let tp = tmp("late-aac.jsonl");
    let player = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--aac", &addr, "-q", "--speed", "20", "examples/extract-5-4.mcl", "--trace"])
        .arg(&tp)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let mut aac = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["mock-aac", "--net", "examples/extract-5-4.mcl", "--listen", &addr, "--speed", "20", "--quiet"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let out = player.wait_with_output().unwrap();
    let _ = aac.kill();
    let _ = aac.wait();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let tr = trace(&tp);
    let first = &acts(&tr)[0];
    // Mission time at speed 20: the 1.5 s without a vehicle would be 30 s.
    assert!(first.t < 1.0, "{first:?}");
    assert!(!first.queued, "{first:?}");
    assert!(tr.iter().any(|r| matches!(&r.kind, RecordKind::Link { message } if message == "link to the AAC up")));
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
    // Every action and every event is a mark with its name on the page
    // (not only in a tooltip), and its tooltip gives the call's source line.
    let tr = trace(&tp);
    assert!(text.contains(r#"class="mark-name""#), "no mark names");
    for r in &tr {
        let (RecordKind::Action { action: name, .. } | RecordKind::Event { event: name, .. }) = &r.kind else {
            continue;
        };
        assert!(text.contains(&format!(">{name}<title>")), "{name} has no name on the page");
    }
    assert!(text.contains("event eventWallInspectionFail (task WallInspect) at examples/dam-inspection.mcl:27"));
    assert!(text.contains("enableSurface = SurfacePrimitive enable() (task Surface) at examples/dam-inspection.mcl:41"));
    // `mcl chronogram` renders the same picture from the trace.
    let svg2 = tmp("dam2.svg");
    let out = mcl(&["chronogram", tp.to_str().unwrap(), "-o", svg2.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&svg2).unwrap(), text);

    // CI sets MCL_REQUIRE_CHROMIUM=1 (.ci/run): there, no browser is a failure.
    if !browser::have_chromium() {
        return;
    }
    let png = tmp("dam.png");
    assert!(browser::screenshot(&svg, &png, &tmp("chromium-dam"), (1600, 900)), "chromium failed");
    let (w, h, size) = browser::png_size(&png).expect("a PNG");
    assert_eq!((w, h), (1600, 900));
    let blank_size = browser::blank_png_size(&tmp("blank"), (1600, 900)).expect("a blank page renders");
    assert!(size > 4 * blank_size, "the screenshot looks blank: {size} bytes vs {blank_size} for a blank page");
}
