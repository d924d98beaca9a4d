//! Call adapters end to end through `mcl run --mock --virtual-time`: the
//! exact actions of shared tasks, with their parameters and call labels.
//!
//! * Two parallel calls of one task (SEED-NOTES item 3): the disable of the
//!   first call is sent with the first call's parameters and label, before
//!   the second call's enable.
//! * Stop before start: a call still waiting for its task when a
//!   parallel-or or a monitor decides to abort it is never enabled.

use mcl_runtime::trace::RecordKind;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn tmp() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-calls-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// Writes `mission` (importing the bundled vehicle, or with its own
/// definitions) and `scenario`, runs it with `seed`, and returns every
/// action as `command(params) task:label`, and the result.
fn run(name: &str, program: &str, scenario: &str, seed: u64) -> (Vec<String>, String) {
    let dir = tmp();
    let file = dir.join(format!("{name}.mcl"));
    let program = program.replace("VEHICLE", &examples().join("vehicle.mcl").display().to_string());
    std::fs::write(&file, program).unwrap();
    let scen = dir.join(format!("{name}.toml"));
    std::fs::write(&scen, scenario).unwrap();
    let trace = dir.join(format!("{name}-{seed}.jsonl"));
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "-q", "--mock", "--virtual-time", "--seed", &seed.to_string(), "--scenario"])
        .arg(&scen)
        .arg("--trace")
        .arg(&trace)
        .arg(&file)
        .output()
        .expect("run mcl");
    let records = mcl_runtime::trace::read_trace(&trace)
        .unwrap_or_else(|e| panic!("no trace ({e}): {}", String::from_utf8_lossy(&out.stderr)));
    let mut actions = Vec::new();
    let mut result = String::new();
    for r in records {
        match r.kind {
            RecordKind::Action { primitive, command, params, call, .. } => {
                let params: Vec<String> = params.iter().map(|(k, v)| format!("{k}={v}")).collect();
                let label = call.label.map(|l| format!(":{l}")).unwrap_or_default();
                actions.push(format!(
                    "{} {primitive} {command}({}) {}{label}",
                    Value::from(r.t),
                    params.join(","),
                    call.task.as_deref().unwrap_or("?"),
                ));
            }
            RecordKind::Outcome { result: res, .. } => result = res,
            _ => {}
        }
    }
    (actions, result)
}

const G: &str = r#"
actions {
    enableG = GPrimitive( c: enable, v: wp );
    disableG = GPrimitive( c: disable, v: wp );
}
events { gOk; gFail; }
tasks {
    G( wp ): AchieveOneGoal { a: enableG -> T0; a: disableG -> T1, T6, T7; e: gOk -> T2; e: gFail -> T3; }
}
mission { parallel { G( 1 ) : a } and { G( 2 ) : b } }
"#;

#[test]
fn parallel_calls_of_one_task_disable_with_their_own_parameters() {
    let scenario = "[tasks.G.label.a]\noutcome = \"fail\"\n[tasks.G.label.b]\noutcome = \"ok\"\n";
    for seed in [3, 7] {
        let (actions, result) = run("parallel-g", G, scenario, seed);
        assert_eq!(
            actions,
            vec![
                "0.0 GPrimitive enable(wp=1) G:a",
                "5.0 GPrimitive disable(wp=1) G:a",
                "5.0 GPrimitive enable(wp=2) G:b",
                "10.0 GPrimitive disable(wp=2) G:b",
            ],
            "seed {seed}"
        );
        assert_eq!(result, "fail");
    }
}

#[test]
fn a_time_out_disables_the_call_that_timed_out() {
    let program = r#"
actions {
    enableH = HPrimitive( c: enable, v: wp );
    disableH = HPrimitive( c: disable, v: wp );
}
events { hOk; hFail; }
tasks {
    H( wp, timeout ): AchieveOneGoalTimed { a: enableH -> T0; a: disableH -> T1, T6, T7; e: hOk -> T2; e: hFail -> T3; }
}
mission { parallel { H( 1, 3 ) : a } and { H( 2, 10 ) : b } }
"#;
    // a never answers and times out after 3 s; b succeeds after 5 s.
    let scenario = "[tasks.H.label.a]\noutcome = \"never\"\n[tasks.H.label.b]\noutcome = \"ok\"\n";
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..8 {
        let (actions, result) = run("timed-h", program, scenario, seed);
        let expected = if actions[0].contains(":a") {
            // a times out at 3 s and is disabled with its own parameter; then b runs.
            vec![
                "0.0 HPrimitive enable(wp=1) H:a",
                "3.0 HPrimitive disable(wp=1) H:a",
                "3.0 HPrimitive enable(wp=2) H:b",
                "8.0 HPrimitive disable(wp=2) H:b",
            ]
        } else {
            vec![
                "0.0 HPrimitive enable(wp=2) H:b",
                "5.0 HPrimitive disable(wp=2) H:b",
                "5.0 HPrimitive enable(wp=1) H:a",
                "8.0 HPrimitive disable(wp=1) H:a",
            ]
        };
        assert_eq!(actions, expected, "seed {seed}");
        assert_eq!(result, "fail");
        seen.insert(actions[0].clone());
    }
    assert_eq!(seen.len(), 2, "both calls run first over the seeds");
}

const LOSER_A: &str = "[tasks.Goto.label.a]\noutcome = \"fail\"\n[tasks.Goto.label.b]\noutcome = \"ok\"\n";

#[test]
fn parallel_or_never_starts_the_call_it_has_decided_to_abort() {
    let program =
        "import \"VEHICLE\";\nmission { parallel { Goto( [1, 2] ) : a } or { Goto( [3, 4] ) : b } ; Surface() }\n";
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..8 {
        let (actions, result) = run("por", program, LOSER_A, seed);
        let expected: Vec<&str> = if actions[0].contains(":b") {
            // b runs first and wins: a, waiting for Goto, is cancelled, never enabled.
            assert_eq!(result, "ok", "seed {seed}");
            vec![
                "0.0 GotoPrimitive enable(way-point=[3,4]) Goto:b",
                "5.0 GotoPrimitive disable() Goto:b",
                "5.0 SurfacePrimitive enable() Surface",
                "10.0 SurfacePrimitive disable() Surface",
            ]
        } else {
            // a runs first and fails: the parallel-or fails, b is never enabled.
            assert_eq!(result, "fail", "seed {seed}");
            vec!["0.0 GotoPrimitive enable(way-point=[1,2]) Goto:a", "5.0 GotoPrimitive disable() Goto:a"]
        };
        assert_eq!(actions, expected, "seed {seed}");
        seen.insert(actions[0].clone());
    }
    assert_eq!(seen.len(), 2, "both calls win the task over the seeds");
}

#[test]
fn monitor_never_starts_the_call_it_has_decided_to_abort() {
    let program = "import \"VEHICLE\";\nmission { monitor { Goto( [1, 2] ) : a } condition ( Goto( [3, 4] ) : b ) do { Surface() } }\n";
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..8 {
        let (actions, result) = run("mon", program, LOSER_A, seed);
        let expected: Vec<&str> = if actions[0].contains(":b") {
            assert_eq!(result, "ok", "seed {seed}");
            vec![
                "0.0 GotoPrimitive enable(way-point=[3,4]) Goto:b",
                "5.0 GotoPrimitive disable() Goto:b",
                "5.0 SurfacePrimitive enable() Surface",
                "10.0 SurfacePrimitive disable() Surface",
            ]
        } else {
            assert_eq!(result, "fail", "seed {seed}");
            vec!["0.0 GotoPrimitive enable(way-point=[1,2]) Goto:a", "5.0 GotoPrimitive disable() Goto:a"]
        };
        assert_eq!(actions, expected, "seed {seed}");
        seen.insert(actions[0].clone());
    }
    assert_eq!(seen.len(), 2, "both calls win the task over the seeds");
}
