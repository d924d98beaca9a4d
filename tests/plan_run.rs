//! `mcl plan FILE.mcl --run --mock`, end to end through the binary: the
//! seed's cable tracking mission with on-board planning (8.5.1.2) executed
//! against the mock vehicle, with the scenario that scripts the seed's
//! divergences (a failed search, the cable lost, the position degrading, an
//! alarm).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

const CABLE: &str = "examples/planning/cable/cable.mcl";
const SCENARIO: &str = "examples/scenarios/cable-planning.toml";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-plan-run-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).arg("plan").args(args).current_dir(root()).output().expect("run mcl")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Runs the cable mission with the scenario; returns the output and the trace records.
fn run_cable(trace: &str, extra: &[&str]) -> (Output, Vec<Value>) {
    let t = tmp(trace);
    let ts = t.display().to_string();
    let mut args = vec![CABLE, "--run", "--mock", "--scenario", SCENARIO, "--virtual-time", "--trace", &ts];
    args.extend_from_slice(extra);
    let o = mcl(&args);
    let records = std::fs::read_to_string(&t)
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    (o, records)
}

fn kind<'a>(rs: &'a [Value], k: &str) -> Vec<&'a Value> {
    rs.iter().filter(|r| r["kind"] == k).collect()
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array().unwrap().iter().map(|s| s.as_str().unwrap_or("null").to_string()).collect()
}

const SEED_PLAN: [&str; 7] = [
    "(takefixop auv)",
    "(gotoop auv deploy inspection)",
    "(achievealtitudeop auv)",
    "(searchcableop auv cable)",
    "(cabletrackingop auv cable)",
    "(surfaceop auv)",
    "(gotoop auv inspection recovery)",
];

#[test]
fn the_dry_run_follows_the_seed_plan_replans_on_each_divergence_and_reaches_the_goal() {
    let (o, rs) = run_cable("cable.jsonl", &["--holding", "Holding", "--seed", "7"]);
    assert_eq!(o.status.code(), Some(0), "{}\n{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stderr).contains("planned mission: OK"), "{}", text(&o.stderr));
    // Re-planning aborts steps and stops the holding mission: they say so,
    // and nothing is reported stuck in a run that ends ok.
    assert!(!text(&o.stdout).contains("STUCK"), "{}", text(&o.stdout));
    assert!(!rs.iter().any(|r| r["kind"] == "outcome" && r["result"] == "stuck"));
    assert!(rs
        .iter()
        .any(|r| r["kind"] == "outcome" && r["result"] == "aborted" && r["reason"] == "aborted to re-plan"));

    // The first plan is the seed's seven steps, with the MCL instances drawn from the attributes.
    let plans = kind(&rs, "plan");
    assert_eq!(plans[0]["reason"], "initial");
    assert_eq!(strings(&plans[0]["steps"]), SEED_PLAN);
    assert_eq!(strings(&plans[0]["calls"])[1], "GotoMCLop( 45, 30 )");
    assert_eq!(strings(&plans[0]["calls"])[3], "SearchCableMCLop( 300, \"cable\", 1.5 )");

    // Each scripted divergence triggers a re-plan, in the seed's order.
    let replans = kind(&rs, "replan");
    let reasons: Vec<&str> = replans.iter().map(|r| r["reason"].as_str().unwrap()).collect();
    assert_eq!(reasons.len(), 4, "{reasons:#?}");
    assert!(reasons[0].contains("(searchcableop auv cable) ended in fail"), "{}", reasons[0]);
    assert!(
        reasons[1].contains("missing [(found cable)]") && reasons[1].contains("(not_found cable)"),
        "{}",
        reasons[1]
    );
    assert!(reasons[2].contains("(position_ok auv)") && reasons[2].contains("(position_bad auv)"), "{}", reasons[2]);
    assert!(reasons[3].contains("(no_alarms auv)") && reasons[3].contains("(alarm auv)"), "{}", reasons[3]);
    for r in &reasons[1..] {
        assert!(r.contains("step aborted"), "{r}");
    }
    // ... and each re-plan gives a plan that deals with it.
    assert_eq!(plans.len(), 5);
    let first = |p: &Value| strings(&p["steps"])[0].clone();
    assert_eq!(first(plans[1]), "(searchcableop auv cable)");
    assert_eq!(first(plans[2]), "(searchcableop auv cable)");
    assert_eq!(strings(&plans[3]["steps"])[..2], ["(surfaceop auv)", "(takefixop auv)"]);
    assert_eq!(first(plans[4]), "(checkalarmop auv)");

    // The divergences happen where the scenario puts them: the step that was running.
    let ends: Vec<(String, String)> = kind(&rs, "step_end")
        .iter()
        .map(|r| (r["action"].as_str().unwrap().to_string(), r["result"].as_str().unwrap().to_string()))
        .collect();
    let not_ok: Vec<(&str, &str)> =
        ends.iter().filter(|(_, r)| r != "ok").map(|(a, r)| (a.as_str(), r.as_str())).collect();
    assert_eq!(
        not_ok,
        [
            ("(searchcableop auv cable)", "fail"),
            ("(cabletrackingop auv cable)", "aborted"),
            ("(cabletrackingop auv cable)", "aborted"),
            ("(cabletrackingop auv cable)", "aborted"),
        ]
    );
    assert_eq!(ends.last().unwrap(), &("(gotoop auv inspection recovery)".to_string(), "ok".to_string()));

    // The holding mission runs while each new plan is computed: between the
    // re-plan and the plan, it starts, keeps position, and is stopped.
    for (k, _) in rs.iter().enumerate().filter(|(_, r)| r["kind"] == "replan") {
        let until = k + rs[k..].iter().position(|x| x["kind"] == "plan").expect("a plan follows each re-plan");
        let between = &rs[k..until];
        let hold = |what: &str| between.iter().any(|x| x["kind"] == "holding" && x["state"] == what);
        assert!(hold("started") && hold("stopped"), "{between:#?}");
        let cmds: Vec<&str> = between
            .iter()
            .filter(|x| x["kind"] == "action" && x["mission"] == "holding:Holding")
            .map(|x| x["action"].as_str().unwrap())
            .collect();
        assert_eq!(cmds, ["enableStationKeeping", "disableStationKeeping"], "{between:#?}");
    }

    // Each step's MCL mission ran on the player: its actions carry the instance's arguments.
    let goto: Vec<&Value> =
        rs.iter().filter(|r| r["kind"] == "action" && r["action"] == "enableGoto").map(|r| &r["params"]).collect();
    assert_eq!(goto.len(), 2);
    assert_eq!(goto[0]["way-point"], serde_json::json!([45, 30]));
    assert_eq!(goto[1]["way-point"], serde_json::json!([0, 0]));
    // ... and point at the operator's call in the operators file.
    let src = std::fs::read_to_string(root().join(CABLE)).unwrap();
    let line = src.lines().position(|l| l.contains("Goto( [x, y] )")).unwrap() + 1;
    let goto_src: Vec<&Value> =
        rs.iter().filter(|r| r["kind"] == "action" && r["action"] == "enableGoto").map(|r| &r["src"]).collect();
    assert!(goto_src.iter().all(|s| **s == format!("{CABLE}:{line}")), "{goto_src:?}");

    // The run ends with the goal's facts and an ok outcome.
    let out = rs.last().unwrap();
    assert_eq!((out["kind"].as_str(), out["result"].as_str()), (Some("outcome"), Some("ok")), "{out}");
    assert_eq!(out["plans"], 5);

    // The live log shows the plans and re-plans.
    let log = text(&o.stdout);
    assert!(log.contains("PLAN 1 (initial): 7 step(s), cost 594"), "{log}");
    assert!(log.contains("REPLAN: facts differ from the plan while step 2 (cabletrackingop auv cable) runs"), "{log}");
    assert!(log.contains("PLANNED MISSION OK"), "{log}");
}

#[test]
fn virtual_time_runs_are_deterministic() {
    let (a, _) = run_cable("det-a.jsonl", &["--holding", "Holding", "--seed", "3"]);
    let (b, _) = run_cable("det-b.jsonl", &["--holding", "Holding", "--seed", "3"]);
    assert_eq!(a.status.code(), Some(0));
    let read = |n: &str| std::fs::read_to_string(tmp(n)).unwrap();
    assert_eq!(read("det-a.jsonl"), read("det-b.jsonl"));
    assert_eq!(a.stdout, b.stdout);
}

#[test]
fn without_perceptions_the_world_never_matches_and_replanning_gives_up() {
    // No scenario: the primitives end ok but no perception ever tells the
    // world modeler that the position is good, so after TakeFixOp the facts
    // are not the expected ones, every time.
    let t = tmp("none.jsonl");
    let o = mcl(&[CABLE, "--run", "--mock", "--virtual-time", "--max-plans", "3", "--trace", &t.display().to_string()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("gave up after 3 plans"), "{}", text(&o.stderr));
    let rs: Vec<Value> =
        std::fs::read_to_string(&t).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(kind(&rs, "plan").len(), 3, "--max-plans 3: the initial plan and two re-plans");
    let replans = kind(&rs, "replan");
    assert_eq!(replans.len(), 3, "the third re-plan is refused");
    assert!(replans[0]["reason"].as_str().unwrap().contains("missing [(position_ok auv)"), "{}", replans[0]);
    // No holding mission was asked for: none ran.
    assert!(kind(&rs, "holding").is_empty());
}

/// A `mcl mock-aac` process, killed when dropped.
struct MockAac {
    child: std::process::Child,
    addr: String,
}

impl Drop for MockAac {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `mcl mock-aac ARGS --listen 127.0.0.1:0` and reads the address it listens on.
fn mock_aac(args: &[&str]) -> MockAac {
    use std::io::BufRead;
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .arg("mock-aac")
        .args(args)
        .args(["--listen", "127.0.0.1:0", "--quiet"])
        .current_dir(root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start mcl mock-aac");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let addr = line.trim().strip_prefix("listening on ").unwrap_or_else(|| panic!("{line:?}")).to_string();
    MockAac { child, addr }
}

#[test]
fn the_plan_runs_against_a_vehicle_aac_over_tcp_in_real_time() {
    // The mock vehicle of the planned mission behind the AAC protocol, 200 times faster than real time.
    let aac = mock_aac(&["--plan", CABLE, "--scenario", SCENARIO, "--speed", "200", "--token", "s3cret"]);

    // The AAC refuses a player without the token: bad input, nothing runs.
    let o = mcl(&[CABLE, "--run", "--aac", &aac.addr, "--speed", "200", "--token", "wrong"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("refused the connection (unauthorized)"), "{}", text(&o.stderr));

    let t = tmp("aac.jsonl");
    let ts = t.display().to_string();
    let o = mcl(&[
        CABLE,
        "--run",
        "--aac",
        &aac.addr,
        "--token",
        "s3cret",
        "--speed",
        "200",
        "--holding",
        "Holding",
        "--trace",
        &ts,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}\n{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stderr).contains("planned mission: OK"), "{}", text(&o.stderr));
    let rs: Vec<Value> =
        std::fs::read_to_string(&t).unwrap().lines().map(|l| serde_json::from_str(l).expect("a JSON line")).collect();

    // The first plan is the seed's; the vehicle's events ended the steps and
    // its perceptions, through the world modeler, made the executor re-plan.
    let plans = kind(&rs, "plan");
    assert_eq!(strings(&plans[0]["steps"]), SEED_PLAN);
    let replans = kind(&rs, "replan");
    assert!(!replans.is_empty(), "no re-plan");
    assert_eq!(plans.len(), replans.len() + 1);
    assert!(kind(&rs, "event").iter().any(|e| e["event"] == "eventGotoOk"));
    assert!(kind(&rs, "facts").iter().any(|f| strings(&f["added"]).contains(&"(found cable)".to_string())));
    assert!(
        replans.iter().any(|r| r["reason"].as_str().unwrap().contains("missing [(found cable)]")),
        "the lost cable (a perception from the AAC) is a divergence: {replans:#?}"
    );
    // The holding mission ran on the vehicle while re-planning.
    let holding: Vec<&str> = rs
        .iter()
        .filter(|x| x["kind"] == "action" && x["mission"] == "holding:Holding")
        .map(|x| x["action"].as_str().unwrap())
        .collect();
    assert_eq!(holding.len(), 2 * replans.len(), "{holding:?}");
    // The goal is reached: the last step brought the vehicle to the recovery zone.
    let ends = kind(&rs, "step_end");
    assert_eq!(ends.last().unwrap()["action"], "(gotoop auv inspection recovery)");
    assert_eq!(ends.last().unwrap()["result"], "ok");
    let out = rs.last().unwrap();
    assert_eq!((out["kind"].as_str(), out["result"].as_str()), (Some("outcome"), Some("ok")), "{out}");
    assert!(text(&o.stdout).contains("PLANNED MISSION OK"), "{}", text(&o.stdout));
}

#[test]
fn bad_input_is_reported() {
    let o = mcl(&[CABLE, "--run", "--virtual-time"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--run needs --mock"), "{}", text(&o.stderr));

    let o = mcl(&[CABLE, "--run", "--mock", "--virtual-time", "--holding", "Hover"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("holding mission `Hover`"), "{}", text(&o.stderr));

    let o = mcl(&[CABLE, "--run", "--mock", "--virtual-time", "--holding", "GotoMCLop"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("has parameters"), "{}", text(&o.stderr));

    let s = tmp("bad.toml");
    std::fs::write(&s, "[[perceptions]]\nname = \"auv.x\"\nvalue = 1\n").unwrap();
    let o = mcl(&[CABLE, "--run", "--mock", "--virtual-time", "--scenario", &s.display().to_string()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("bad.toml:1:1: perception `auv.x` needs `at`"), "{}", text(&o.stderr));

    let w = tmp("world.xml");
    std::fs::write(
        &w,
        "<world><script id=\"x\"><add value1=\"ghost\" type1=\"robot\" prop=\"surface\"/></script></world>",
    )
    .unwrap();
    let o = mcl(&[CABLE, "--run", "--mock", "--virtual-time", "--world", &w.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("world.xml"), "{}", text(&o.stderr));

    // A vehicle's AAC runs in real time, with its own scenario.
    let o = mcl(&[CABLE, "--run", "--aac", "127.0.0.1:1", "--virtual-time"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--virtual-time needs --mock"), "{}", text(&o.stderr));
    let o = mcl(&[CABLE, "--run", "--aac", "127.0.0.1:1", "--scenario", SCENARIO]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("mcl mock-aac --plan"), "{}", text(&o.stderr));
    let o = mcl(&[CABLE, "--run", "--aac", "127.0.0.1:1", "--mock"]);
    assert_eq!(o.status.code(), Some(2));

    // --mock without --run is a usage error.
    let o = mcl(&[CABLE, "--mock"]);
    assert_eq!(o.status.code(), Some(2));
}

/// The cable mission written in MCL (`planning.mcl`) runs as its PDDL form
/// does: the same plans, steps and outcome with the same seed.
#[test]
fn the_mcl_planning_model_runs_like_the_pddl_files() {
    let run = |file: &str, trace: &str| {
        let t = tmp(trace);
        let ts = t.display().to_string();
        let o =
            mcl(&[file, "--run", "--mock", "--scenario", SCENARIO, "--virtual-time", "--trace", &ts, "--seed", "7"]);
        let rs: Vec<Value> = std::fs::read_to_string(&t)
            .unwrap_or_default()
            .lines()
            .map(|l| serde_json::from_str(l).expect("a JSON line"))
            .collect();
        (o, rs)
    };
    let (a, ra) = run("examples/planning/cable/planning.mcl", "mcl-form.jsonl");
    let (b, rb) = run(CABLE, "pddl-form.jsonl");
    assert_eq!(a.status.code(), Some(0), "{}\n{}", text(&a.stdout), text(&a.stderr));
    assert_eq!(b.status.code(), Some(0));
    assert_eq!(strings(&kind(&ra, "plan")[0]["steps"]), SEED_PLAN);
    let plans =
        |rs: &[Value]| kind(rs, "plan").iter().map(|p| (p["steps"].clone(), p["calls"].clone())).collect::<Vec<_>>();
    assert_eq!(plans(&ra), plans(&rb));
    assert_eq!(kind(&ra, "outcome"), kind(&rb, "outcome"));
}

/// A planned step whose mission loops without mission time advancing (its
/// tasks answer at once) is stopped by the virtual-time loop's zero-time
/// guard: the step fails as stuck and the run goes on (here: re-plans until
/// `--max-plans`), instead of hanging.
#[test]
fn a_step_that_loops_in_zero_time_ends_stuck() {
    let sc = tmp("zero-time.toml");
    std::fs::write(&sc, "default_duration = 0\n[tasks.GetPositionFix]\noutcome = \"ok\"\n").unwrap();
    let t = tmp("zero-time.jsonl");
    let o = mcl(&[
        "tests/run/plan-loop/plan.mcl",
        "--run",
        "--mock",
        "--virtual-time",
        "--scenario",
        sc.to_str().unwrap(),
        "--max-plans",
        "2",
        "--trace",
        &t.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}\n{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stderr).contains("gave up after 2 plans"), "{}", text(&o.stderr));
    let rs: Vec<Value> =
        std::fs::read_to_string(&t).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let warnings: Vec<&str> = kind(&rs, "warning").iter().filter_map(|w| w["message"].as_str()).collect();
    assert_eq!(
        warnings.iter().filter(|w| w.starts_with("zero-time loop: 10000 inputs at t=0 s")).count(),
        2,
        "{warnings:?}"
    );
    let ends = kind(&rs, "step_end");
    assert_eq!(ends.len(), 2, "{ends:?}");
    assert!(ends.iter().all(|e| e["result"] != "ok"), "{ends:?}");
}
