//! `mcl run --sim` and `mcl plan --run --sim`, end to end through the
//! binary: the seed's missions against the simulated vehicle (crate
//! `mcl-sim`), alone, several in one world, or executing a plan, checked on
//! the poses, events, facts and re-plans of the trace.

use mcl_testutil::browser;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-sim-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(root()).output().expect("run mcl")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn trace(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad trace line {l}: {e}")))
        .collect()
}

/// Runs `mcl run --sim --virtual-time FILE extra...` and returns (exit
/// status, trace, output).
fn sim(file: &str, extra: &[&str], name: &str) -> (i32, Vec<Value>, Output) {
    let tp = tmp(&format!("{name}.jsonl"));
    let mut args = vec!["run", "--sim", "--virtual-time", "-q", file, "--trace", tp.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = mcl(&args);
    let code = o.status.code().unwrap_or(-1);
    let tr = if tp.exists() { trace(&tp) } else { Vec::new() };
    (code, tr, o)
}

#[derive(Clone, Copy, Debug)]
struct P {
    t: f64,
    x: f64,
    y: f64,
    z: f64,
}

fn poses(tr: &[Value]) -> Vec<P> {
    tr.iter()
        .filter(|r| r["kind"] == "pose")
        .map(|r| P {
            t: r["t"].as_f64().unwrap(),
            x: r["x"].as_f64().unwrap(),
            y: r["y"].as_f64().unwrap(),
            z: r["z"].as_f64().unwrap(),
        })
        .collect()
}

/// Times of the records of `kind` whose `field` is `value`.
fn times(tr: &[Value], kind: &str, field: &str, value: &str) -> Vec<f64> {
    tr.iter().filter(|r| r["kind"] == kind && r[field] == value).map(|r| r["t"].as_f64().unwrap()).collect()
}

fn outcome(tr: &[Value]) -> &Value {
    let o: Vec<&Value> = tr.iter().filter(|r| r["kind"] == "outcome").collect();
    assert_eq!(o.len(), 1, "one outcome record");
    o[0]
}

/// The pose at (or last before) `t`.
fn pose_at(ps: &[P], t: f64) -> P {
    *ps.iter().rev().find(|p| p.t <= t + 1e-9).expect("a pose before t")
}

const SURVEY_PATH: [(f64, f64); 10] = [
    (0.0, 0.0),
    (20.0, 0.0),
    (20.0, 5.0),
    (0.0, 5.0),
    (0.0, 10.0),
    (20.0, 10.0),
    (20.0, 15.0),
    (0.0, 15.0),
    (0.0, 20.0),
    (20.0, 20.0),
];

#[test]
fn survey_passes_every_way_point_in_order_in_the_time_its_length_takes() {
    let svg = tmp("survey.svg");
    let (code, tr, o) = sim("examples/survey.mcl", &["--trajectory", svg.to_str().unwrap()], "survey");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    assert_eq!(outcome(&tr)["result"], "ok");
    let ps = poses(&tr);
    let t0 = times(&tr, "action", "action", "enableTrajectory")[0];
    let t1 = times(&tr, "event", "event", "eventTrajectoryOk")[0];
    // Every way-point, in order, within 2 m.
    let mut from = ps.iter().position(|p| p.t >= t0).unwrap();
    for (k, &(wx, wy)) in SURVEY_PATH.iter().enumerate() {
        let i = ps[from..]
            .iter()
            .position(|p| p.t <= t1 + 1e-9 && (p.x - wx).hypot(p.y - wy) <= 2.0)
            .unwrap_or_else(|| panic!("way-point {} ({wx}, {wy}) not passed within 2 m after t={}", k + 1, ps[from].t));
        from += i;
    }
    // Path length over speed: 120 m at 0.5 m/s.
    let length: f64 = SURVEY_PATH.windows(2).map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)).sum();
    let expected = length / 0.5;
    assert!(((t1 - t0) - expected).abs() <= 0.1 * expected, "trajectory took {} s, expected {expected} s", t1 - t0);
    // Kept at 2.5 m over the 20 m seabed while surveying; at the surface at the end.
    let mid = pose_at(&ps, (t0 + t1) / 2.0);
    assert!((mid.z - 17.5).abs() < 0.3, "{mid:?}");
    assert!(ps.last().unwrap().z <= 0.2);
    // At least a pose per second while moving, and one at every action and event.
    assert!(ps.windows(2).all(|w| w[1].t > w[0].t), "poses in time order");
    for w in ps.windows(2).filter(|w| w[0].t >= t0 && w[1].t <= t1) {
        assert!(w[1].t - w[0].t <= 1.0 + 1e-6, "gap {} -> {}", w[0].t, w[1].t);
    }
    for r in tr.iter().filter(|r| r["kind"] == "action" || r["kind"] == "event") {
        let t = r["t"].as_f64().unwrap();
        assert!(ps.iter().any(|p| (p.t - t).abs() < 1e-6), "no pose at t={t} ({r})");
    }
    // The picture is well-formed XML with the task names in its legend.
    let doc = std::fs::read_to_string(&svg).unwrap();
    well_formed(&doc);
    assert!(doc.contains(">Trajectory<") && doc.contains(">Altitude<"), "legend");
}

fn well_formed(doc: &str) {
    let mut r = quick_xml::Reader::from_str(doc);
    let mut depth = 0i32;
    loop {
        match r.read_event() {
            Ok(quick_xml::events::Event::Start(_)) => depth += 1,
            Ok(quick_xml::events::Event::End(_)) => depth -= 1,
            Ok(quick_xml::events::Event::Eof) => break,
            Ok(_) => {}
            Err(e) => panic!("SVG is not well-formed at {}: {e}", r.buffer_position()),
        }
    }
    assert_eq!(depth, 0);
}

#[test]
fn survey_is_deterministic() {
    let (_, a, _) = sim("examples/survey.mcl", &["--seed", "3"], "det-a");
    let (_, b, _) = sim("examples/survey.mcl", &["--seed", "3"], "det-b");
    assert!(a.len() > 300);
    assert_eq!(a, b);
}

#[test]
fn low_battery_ends_the_survey_through_the_emergency_surface_when_the_model_says() {
    let (code, tr, o) = sim("examples/survey.mcl", &["--world", "examples/sim/survey-low-battery.toml"], "battery");
    let out = outcome(&tr);
    assert!(out["via"].as_str().is_some_and(|v| v.contains("condition")), "{out} {}", text(&o.stderr));
    assert_eq!(code, if out["result"] == "ok" { 0 } else { 1 });
    let alarm = times(&tr, "event", "event", "eventAlarmOk");
    assert_eq!(alarm.len(), 1);
    let t = alarm[0];
    // The battery model: 50 W of hotel load plus 100 J per metre, from
    // 10 Wh down to the alarm at 5 Wh (25 % of 20 Wh): 18 kJ.
    let ps = poses(&tr);
    let travelled: f64 = ps
        .windows(2)
        .filter(|w| w[1].t <= t + 1e-9)
        .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y).hypot(w[1].z - w[0].z))
        .sum();
    let used = 50.0 * t + 100.0 * travelled;
    assert!((used - 18_000.0).abs() < 0.01 * 18_000.0, "alarm at t={t} s after {travelled} m: {used} J used");
    // During the trajectory, then straight up.
    let traj = times(&tr, "action", "action", "enableTrajectory")[0];
    assert!(t > traj && times(&tr, "event", "event", "eventTrajectoryOk").is_empty());
    let es = times(&tr, "action", "action", "enableEmergencySurface");
    assert_eq!(es, vec![t]);
    let up = times(&tr, "event", "event", "eventEmergencySurfaceOk");
    assert_eq!(up.len(), 1);
    let before = pose_at(&ps, t);
    assert!((up[0] - t - before.z / 1.0).abs() < 0.4, "17.5 m at 1 m/s: {} s", up[0] - t);
    let last = ps.last().unwrap();
    assert!(last.z <= 0.2 && (last.x - before.x).hypot(last.y - before.y) < 0.5, "{last:?} {before:?}");
}

#[test]
fn cable_tracking_loses_the_cable_where_it_is_buried_and_finds_it_again() {
    let svg = tmp("cable.svg");
    let (code, tr, o) = sim(
        "examples/cable-tracking.mcl",
        &["--world", "examples/sim/cable.toml", "--trajectory", svg.to_str().unwrap()],
        "cable",
    );
    assert_eq!(code, 0, "{}", text(&o.stderr));
    assert_eq!(outcome(&tr)["result"], "ok");
    // Ended through the search loop's condition (the last handler it went
    // through), neither the catch nor the alarm.
    let via = outcome(&tr)["via"].as_str().unwrap_or("").to_string();
    assert!(!via.contains("catch") && times(&tr, "action", "action", "enableEmergencySurface").is_empty(), "{via}");
    let found = times(&tr, "event", "event", "eventSearchOk");
    let ended = times(&tr, "event", "event", "eventCableTrackingOk");
    assert_eq!(found.len(), 2, "found twice: {found:?}");
    assert_eq!(ended.len(), 2, "lost, then at its end: {ended:?}");
    assert!(found[0] < ended[0] && ended[0] < found[1] && found[1] < ended[1]);
    // Lost where the buried section starts (50 m along the cable, near (74.5, 3.2)).
    let ps = poses(&tr);
    let lost = pose_at(&ps, ended[0]);
    assert!((lost.x - 74.5).hypot(lost.y - 3.2) < 3.0, "{lost:?}");
    // Found again past its end (65 m along, near (89.4, 1.3)), ended at the cable's end (140, 10).
    let again = pose_at(&ps, found[1]);
    assert!(again.x > 86.0, "{again:?}");
    let end = pose_at(&ps, ended[1]);
    assert!((end.x - 140.0).hypot(end.y - 10.0) < 3.0, "{end:?}");
    // The simulation told the mission when the cable came into and out of sight.
    let seen: Vec<(f64, bool)> = tr
        .iter()
        .filter(|r| r["kind"] == "perception" && r["name"] == "cable.seen")
        .map(|r| (r["t"].as_f64().unwrap(), r["value"].as_bool().unwrap()))
        .collect();
    assert!(seen.iter().any(|&(t, v)| !v && t >= ended[0] - 1.0 && t <= found[1]), "{seen:?}");
    well_formed(&std::fs::read_to_string(&svg).unwrap());
}

#[test]
fn dam_inspection_flies_the_wall_path_facing_the_wall() {
    let (code, tr, o) = sim("examples/dam-inspection.mcl", &["--world", "examples/sim/dam.toml"], "dam");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    assert_eq!(outcome(&tr)["result"], "ok");
    let t = times(&tr, "event", "event", "eventWallInspectionOk");
    assert_eq!(t.len(), 1);
    // Its last way-point: 4 m along the wall, 5 m deep, 1.5 m in front of it (y = -8.5).
    let p = pose_at(&poses(&tr), t[0]);
    assert!((p.x - 4.0).abs() < 0.4 && (p.y + 8.5).abs() < 0.4 && (p.z - 5.0).abs() < 0.4, "{p:?}");
    let yaw = tr.iter().rev().find(|r| r["kind"] == "pose" && r["t"].as_f64().unwrap() <= t[0]).unwrap()["yaw"]
        .as_f64()
        .unwrap();
    assert!((yaw + std::f64::consts::FRAC_PI_2).abs() < 0.05, "facing the wall: {yaw}");
}

#[test]
fn another_vehicle_file_runs_on_its_own_model() {
    let (code, tr, o) = sim(
        "examples/sim/rov-inspection.mcl",
        &["--vehicle-model", "examples/sim/rov-model.toml", "--world", "examples/sim/rov-world.toml"],
        "rov",
    );
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let spotted = times(&tr, "event", "event", "spotted");
    assert_eq!(spotted.len(), 1);
    let p = pose_at(&poses(&tr), spotted[0]);
    assert!((p.x - 31.0).hypot(p.y - 25.0) <= 4.0 + 0.1, "{p:?}");
    assert_eq!(times(&tr, "event", "event", "surfaced").len(), 1);
    assert!(tr.iter().any(|r| r["kind"] == "perception" && r["name"] == "power"));
}

#[test]
fn scenario_faults_apply_on_top_of_the_simulation() {
    let sc = tmp("fault.toml");
    std::fs::write(&sc, "[tasks.Trajectory]\noutcome = \"fail\"\ndelay = 30\n").unwrap();
    let (code, tr, o) = sim("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "fault");
    let traj = times(&tr, "action", "action", "enableTrajectory")[0];
    let fail = times(&tr, "event", "event", "eventTrajectoryFail");
    assert_eq!(fail.len(), 1, "{}", text(&o.stderr));
    assert!((fail[0] - traj - 30.0).abs() < 1e-3, "{fail:?} {traj}");
    assert!(outcome(&tr)["via"].as_str().is_some_and(|v| v.contains("catch")));
    assert_eq!(code, 0);
}

#[test]
fn bad_world_and_model_files_are_located_errors() {
    let w = tmp("bad-world.toml");
    std::fs::write(&w, "[seabed]\ndepth = 20\n\n[cable]\npoints = [[0, 0], [10, 0]]\nburied = [[5, 40]]\n").unwrap();
    let o = mcl(&["run", "--sim", "--virtual-time", "examples/survey.mcl", "--world", w.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = text(&o.stderr);
    assert!(e.contains(&format!("{}:6:11:", w.display())) && e.contains("buried"), "{e}");

    let m = tmp("bad-model.toml");
    std::fs::write(&m, "[primitives.GotoPrimitive]\nbehaviour = \"goto\"\nparams = { traget = \"way-point\" }\n")
        .unwrap();
    let o = mcl(&["run", "--sim", "--virtual-time", "examples/survey.mcl", "--vehicle-model", m.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = text(&o.stderr);
    assert!(e.contains(&format!("{}:3:12:", m.display())) && e.contains("traget"), "{e}");

    let o = mcl(&["run", "--sim", "--speed", "0", "examples/survey.mcl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--speed"));
    let o = mcl(&["run", "--mock", "--virtual-time", "examples/survey.mcl", "--world", w.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
}

/// The poses of `mission` in a trace of several vehicles.
fn poses_of(tr: &[Value], mission: &str) -> Vec<P> {
    let mine: Vec<Value> = tr.iter().filter(|r| r["mission"] == mission).cloned().collect();
    poses(&mine)
}

#[test]
fn auv_and_asc_run_together_in_the_default_world() {
    let svg = tmp("auv-asc.svg");
    let (code, tr, o) = sim("examples/auv-asc.mcl", &["--trajectory", svg.to_str().unwrap()], "auv-asc");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let (auv, asc) = (poses_of(&tr, "auv"), poses_of(&tr, "asc"));
    assert!(auv.len() > 100 && asc.len() > 10, "{} {}", auv.len(), asc.len());
    assert!(auv.iter().any(|p| p.z > 5.0), "the AUV dives");
    assert!(asc.iter().all(|p| p.z == 0.0), "the ASC stays at the surface");
    // The ASC reaches the deployment area before the AUV dives (order { asc:deploy_auv, auv:deploy_auv }).
    let dive = auv.iter().find(|p| p.z > 0.1).unwrap().t;
    let deployed = asc.iter().find(|p| (p.x - 20.0).hypot(p.y + 5.0) <= 1.0).expect("the ASC reaches deploy_area");
    assert!(deployed.t < dive, "{} < {dive}", deployed.t);
    let doc = std::fs::read_to_string(&svg).unwrap();
    well_formed(&doc);
    assert!(doc.contains(">auv<") && doc.contains(">asc<") && doc.contains(">vehicle<"));
    assert_eq!(doc.matches("<title>start</title>").count(), 2, "one path per vehicle");
}

#[test]
fn the_asc_goes_over_the_object_the_auv_found() {
    let (code, tr, o) = sim("examples/auv-asc.mcl", &["--world", "examples/sim/auv-asc.toml"], "auv-asc-object");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let (auv, asc) = (poses_of(&tr, "auv"), poses_of(&tr, "asc"));
    // Each starts where the world says.
    assert_eq!((auv[0].x, auv[0].y), (0.0, 0.0));
    assert_eq!((asc[0].x, asc[0].y), (0.0, -5.0));
    let found =
        tr.iter().find(|r| r["mission"] == "auv" && r["event"] == "eventSearchOk").expect("the AUV finds the object");
    let over = asc.iter().find(|p| (p.x - 20.0).hypot(p.y - 10.0) <= 1.0).expect("the ASC goes over the object");
    assert!(over.t > found["t"].as_f64().unwrap());
    let sent: Vec<&Value> = tr.iter().filter(|r| r["kind"] == "action" && r["action"] == "enableSendData").collect();
    assert_eq!(sent.len(), 1, "the images are sent once: the object is found once");
}

#[test]
fn planned_cable_tracking_replans_when_the_simulated_vision_loses_the_cable() {
    let (tp, svg) = (tmp("plan-cable.jsonl"), tmp("plan-cable.svg"));
    let o = mcl(&[
        "plan",
        "examples/planning/cable/cable.mcl",
        "--run",
        "--sim",
        "--virtual-time",
        "--holding",
        "Holding",
        "--vehicle-model",
        "examples/planning/cable/sim-model.toml",
        "--sim-world",
        "examples/planning/cable/sim-world.toml",
        "-q",
        "--trace",
        tp.to_str().unwrap(),
        "--trajectory",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let tr = trace(&tp);
    let has = |r: &Value, field: &str, fact: &str| r[field].as_array().is_some_and(|a| a.iter().any(|f| f == fact));
    // The first re-plan: the cable is no longer found...
    let replan = tr.iter().find(|r| r["kind"] == "replan").expect("a re-plan");
    let t = replan["t"].as_f64().unwrap();
    assert!(replan["reason"].as_str().unwrap().contains("(not_found cable)"), "{replan}");
    // ... because the simulated vision lost it: the vehicle's perception,
    // turned into that fact by world.xml, at that instant.
    let lost = tr
        .iter()
        .find(|r| r["kind"] == "facts" && r["perception"] == "cable.detected" && has(r, "deleted", "(found cable)"))
        .expect("the cable lost");
    assert_eq!(lost["t"], replan["t"]);
    assert!(tr.iter().any(|r| r["kind"] == "perception"
        && r["name"] == "cable.detected"
        && r["value"] == 0.0
        && r["t"] == replan["t"]));
    // Where the cable is buried: 60 m along it from (42, 32).
    let at = pose_at(&poses(&tr), t);
    assert!((at.x - 102.0).abs() < 3.0 && (at.y - 32.0).abs() < 3.0, "{at:?}");
    // Then a search finds it again and the tracking maps it (cable.tracked), and the goal is reached.
    let after: Vec<&Value> = tr.iter().filter(|r| r["t"].as_f64().unwrap() >= t).collect();
    assert!(after.iter().any(|r| r["kind"] == "step" && r["action"] == "(searchcableop auv cable)"));
    assert!(after
        .iter()
        .any(|r| r["kind"] == "facts" && r["perception"] == "cable.tracked" && has(r, "added", "(mapped cable)")));
    let doc = std::fs::read_to_string(&svg).unwrap();
    well_formed(&doc);
    assert!(doc.contains(">CableTracking<") && doc.contains(">SearchPattern<"));
}

#[test]
fn eight_vehicles_survey_side_by_side() {
    let (code, tr, o) = sim("examples/sim/fleet8.mcl", &["--world", "examples/sim/fleet8.toml"], "fleet8");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    for k in 0..8 {
        let ps = poses_of(&tr, &format!("auv{}", k + 1));
        let y0 = 30.0 * k as f64;
        assert_eq!((ps[0].x, ps[0].y), (0.0, y0), "auv{} starts at its corner", k + 1);
        // Its lawn-mower's last way-point, (20, y0 + 20).
        assert!(ps.iter().any(|p| (p.x - 20.0).hypot(p.y - y0 - 20.0) <= 2.0), "auv{}", k + 1);
        assert!(ps.iter().all(|p| p.y > y0 - 3.0 && p.y < y0 + 23.0), "auv{} stays in its area", k + 1);
    }
}

/// The width and height an SVG says it has.
fn svg_size(doc: &str) -> (u32, u32) {
    let attr = |name: &str| -> u32 {
        let i = doc.find(&format!(" {name}=\"")).unwrap_or_else(|| panic!("no {name}")) + name.len() + 3;
        let j = doc[i..].find('"').unwrap() + i;
        doc[i..j].parse::<f64>().unwrap().ceil() as u32
    };
    (attr("width"), attr("height"))
}

/// The survey's and the cable tracking's trajectories render in a real
/// browser (headless Chromium), at the size they declare, and are not blank.
#[test]
fn trajectories_render_in_a_browser() {
    let survey = tmp("browser-survey.svg");
    let (code, _, o) = sim("examples/survey.mcl", &["--trajectory", survey.to_str().unwrap()], "browser-survey");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let cable = tmp("browser-cable.svg");
    let (code, _, o) = sim(
        "examples/cable-tracking.mcl",
        &["--world", "examples/sim/cable.toml", "--trajectory", cable.to_str().unwrap()],
        "browser-cable",
    );
    assert_eq!(code, 0, "{}", text(&o.stderr));
    // CI sets MCL_REQUIRE_CHROMIUM=1 (.ci/run): there, no browser is a failure.
    if !browser::have_chromium() {
        return;
    }
    for svg in [survey, cable] {
        let size = svg_size(&std::fs::read_to_string(&svg).unwrap());
        let png = svg.with_extension("png");
        let profile = svg.with_extension("chromium");
        assert!(browser::screenshot(&svg, &png, &profile, size), "chromium failed on {}", svg.display());
        let (w, h, bytes) = browser::png_size(&png).expect("a PNG");
        assert_eq!((w, h), size, "{}", svg.display());
        let blank = browser::blank_png_size(&svg.with_extension("blank"), size).expect("a blank page renders");
        assert!(bytes > 4 * blank, "{} looks blank: {bytes} bytes vs {blank} for a blank page", svg.display());
    }
}

/// Top horizontal speed between consecutive poses.
fn top_speed(ps: &[P]) -> f64 {
    ps.windows(2)
        .filter(|w| w[1].t > w[0].t)
        .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y) / (w[1].t - w[0].t))
        .fold(0.0, f64::max)
}

/// `--speed` instead of `--virtual-time`: the same run, paced by the wall
/// clock; one vehicle and several.
#[test]
fn real_time_gives_the_run_of_virtual_time() {
    for (file, extra, several) in [
        ("examples/survey.mcl", vec![], false),
        ("examples/auv-asc.mcl", vec!["--world", "examples/sim/auv-asc.toml"], true),
    ] {
        let (code, reference, _) = sim(file, &extra, "rt-reference");
        assert_eq!(code, 0);
        let tp = tmp("rt.jsonl");
        let mut args = vec!["run", "--sim", "--speed", "500", "-q", file, "--trace", tp.to_str().unwrap()];
        args.extend_from_slice(&extra);
        let o = mcl(&args);
        assert_eq!(o.status.code(), Some(0), "{file}: {}", text(&o.stderr));
        let tr = trace(&tp);
        let missions: Vec<&str> = if several { vec!["auv", "asc"] } else { vec![""] };
        for m in missions {
            let (ps, want) =
                if several { (poses_of(&tr, m), poses_of(&reference, m)) } else { (poses(&tr), poses(&reference)) };
            assert!(ps.len() > 50, "{file} {m}: {} poses", ps.len());
            assert_eq!(ps.len(), want.len(), "{file} {m}");
            for (p, q) in ps.iter().zip(&want) {
                assert!(
                    (p.t - q.t).abs() < 1e-6 && (p.x - q.x).hypot(p.y - q.y) < 0.01 && (p.z - q.z).abs() < 0.01,
                    "{p:?} {q:?}"
                );
            }
            // A pose at least every simulated second while moving.
            assert!(ps
                .windows(2)
                .all(|w| w[1].t - w[0].t <= 1.0 + 1e-6 || w[0].x == w[1].x && w[0].y == w[1].y && w[0].z == w[1].z));
        }
        let outcomes = |tr: &[Value]| -> Vec<String> {
            tr.iter().filter(|r| r["kind"] == "outcome").map(|r| format!("{} {}", r["mission"], r["result"])).collect()
        };
        assert_eq!(outcomes(&tr), outcomes(&reference), "{file}");
        assert!(outcomes(&tr).iter().all(|o| o.ends_with("\"ok\"")), "{:?}", outcomes(&tr));
    }
}

fn run_sim(args: &[&str]) -> Output {
    let mut all = vec!["run", "--sim", "-q"];
    all.extend_from_slice(args);
    mcl(&all)
}

/// A simulated run that crashes (abort right after a journal sync) resumes
/// with the vehicle re-derived from the journal: the trace is the
/// uninterrupted run's, byte for byte, wherever it crashed; a resume
/// against another world is refused where the simulation differs.
#[test]
fn a_crashed_simulated_run_resumes_where_it_was() {
    let base = ["examples/survey.mcl", "--world", "examples/sim/survey-low-battery.toml"];
    let whole = tmp("sim-whole.jsonl");
    let mut args = vec!["--virtual-time"];
    args.extend_from_slice(&base);
    args.extend_from_slice(&["--trace", whole.to_str().unwrap()]);
    assert_eq!(run_sim(&args).status.code(), Some(0));
    let whole = std::fs::read(&whole).unwrap();
    assert!(String::from_utf8_lossy(&whole).contains("eventEmergencySurfaceOk"), "the battery alarm path");
    for n in [1, 3, 6, 9, 12] {
        let j = tmp(&format!("sim-crash{n}.journal"));
        let _ = std::fs::remove_file(&j);
        let mut args = vec!["--virtual-time"];
        args.extend_from_slice(&base);
        let crash = n.to_string();
        args.extend_from_slice(&["--journal", j.to_str().unwrap(), "--crash-after", &crash]);
        let o = run_sim(&args);
        assert!(o.status.code().is_none(), "crash after {n}: the process was killed by a signal");
        let resumed = tmp(&format!("sim-resumed{n}.jsonl"));
        let mut args = vec!["--virtual-time"];
        args.extend_from_slice(&base);
        args.extend_from_slice(&["--resume", j.to_str().unwrap(), "--trace", resumed.to_str().unwrap()]);
        let o = run_sim(&args);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
        assert!(std::fs::read(&resumed).unwrap() == whole, "crash after {n} inputs: the resumed trace differs");
    }
    // Another world: the vehicle would not have sent what the journal says.
    let j = tmp("sim-crash9.journal");
    let o = run_sim(&["--virtual-time", "examples/survey.mcl", "--resume", j.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("the simulated vehicle differs from the journal"), "{}", text(&o.stderr));
}

/// kill -9 of a real-time simulated run, then resume (real time again):
/// the trace of the virtual-time run.
#[test]
fn kill_9_of_a_real_time_simulated_run_and_resume() {
    let (code, _, _) = sim("examples/survey.mcl", &[], "kill-reference");
    assert_eq!(code, 0);
    let reference = std::fs::read(tmp("kill-reference.jsonl")).unwrap();
    let j = tmp("sim-rt.journal");
    let _ = std::fs::remove_file(&j);
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--sim", "--speed", "100", "-q", "examples/survey.mcl", "--journal", j.to_str().unwrap()])
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Killed once the trajectory has started (t = 58 s of 359: 0.6 s of real time).
    let started = Instant::now();
    loop {
        if std::fs::read_to_string(&j).unwrap_or_default().contains("\"event\":\"eventAltitudeOk\"") {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(30), "the run did not progress");
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be killed");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let resumed = tmp("sim-rt-resumed.jsonl");
    let o = run_sim(&[
        "--speed",
        "100",
        "examples/survey.mcl",
        "--resume",
        j.to_str().unwrap(),
        "--trace",
        resumed.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(std::fs::read(&resumed).unwrap() == reference, "the resumed trace differs from the uninterrupted run's");
}

/// `--vehicle-model asc=FILE`: the ASC has the bundled surface model
/// (faster, depth fixed at 0), the AUV the default one.
#[test]
fn each_vehicle_of_a_world_has_its_own_model() {
    let extra = ["--world", "examples/sim/auv-asc.toml", "--vehicle-model", "asc=examples/sim/asc-model.toml"];
    let (code, tr, o) = sim("examples/auv-asc.mcl", &extra, "auv-asc-models");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let (auv, asc) = (poses_of(&tr, "auv"), poses_of(&tr, "asc"));
    assert!(asc.iter().all(|p| p.z == 0.0) && auv.iter().any(|p| p.z > 5.0));
    let (va, vs) = (top_speed(&auv), top_speed(&asc));
    assert!(va <= 1.0 + 1e-6, "the AUV's top speed is the bundled model's 1 m/s: {va}");
    assert!(vs > 1.2 && vs <= 1.5 + 1e-6, "the ASC's top speed is its model's 1.5 m/s: {vs}");
    // The ASC's over the object sooner than with the AUV's model.
    let (_, slow, _) = sim("examples/auv-asc.mcl", &extra[..2], "auv-asc-one-model");
    let over = |tr: &[Value]| poses_of(tr, "asc").iter().find(|p| (p.x - 20.0).hypot(p.y - 10.0) <= 1.0).map(|p| p.t);
    assert!(over(&tr).unwrap() < over(&slow).unwrap());
    // A surface vehicle does not dive: a depth fails at once.
    let (_, tr, o) = sim("examples/survey.mcl", &["--vehicle-model", "examples/sim/asc-model.toml"], "surface-survey");
    let init = times(&tr, "event", "event", "eventInitializeVehicleOk");
    assert_eq!(times(&tr, "event", "event", "eventAltitudeFail"), init, "{}", text(&o.stderr));
    assert!(poses(&tr).iter().all(|p| p.z == 0.0));
    // A model for a mission the file does not have.
    let o = mcl(&[
        "run",
        "--sim",
        "--virtual-time",
        "-q",
        "examples/auv-asc.mcl",
        "--vehicle-model",
        "rov=examples/sim/asc-model.toml",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("has no mission `rov`"), "{}", text(&o.stderr));
}

/// A scenario's perceptions `after` an event, its rules per call label and
/// its probabilities apply on top of the simulation.
#[test]
fn scenario_rules_after_labels_and_probabilities() {
    // A perception 2 s after the altitude is reached.
    let sc = tmp("after.toml");
    std::fs::write(&sc, "[[perceptions]]\nafter = \"eventAltitudeOk\"\ndelay = 2\nname = \"sonar\"\nvalue = 3\n")
        .unwrap();
    let (code, tr, o) = sim("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "after");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("not sent"), "{}", text(&o.stderr));
    let reached = times(&tr, "event", "event", "eventAltitudeOk");
    let sonar = times(&tr, "perception", "name", "sonar");
    assert_eq!(reached.len(), 1);
    assert_eq!(sonar.len(), 1, "once, after the one eventAltitudeOk");
    assert!((sonar[0] - reached[0] - 2.0).abs() < 1e-6, "{sonar:?} {reached:?}");
    // The labelled Deploy of the ASC (`Deploy() : deploy_auv`) takes 30 s instead of its model's 10 s.
    let sc = tmp("label.toml");
    std::fs::write(&sc, "[tasks.Deploy.label.deploy_auv]\noutcome = \"ok\"\ndelay = 30\n").unwrap();
    let (code, tr, o) = sim("examples/auv-asc.mcl", &["--scenario", sc.to_str().unwrap()], "label");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let start = times(&tr, "action", "action", "enableDeploy");
    let done = times(&tr, "event", "event", "eventDeployOk");
    assert_eq!((start.len(), done.len()), (1, 1));
    assert!((done[0] - start[0] - 30.0).abs() < 1e-6, "{start:?} {done:?}");
    // A rule's explicit event is raised instead of the model's, at the rule's time.
    let sc = tmp("event.toml");
    std::fs::write(&sc, "[tasks.Trajectory]\noutcome = \"fail\"\ndelay = 12\nevent = \"eventTrajectoryOk\"\n").unwrap();
    let (code, tr, o) = sim("examples/survey.mcl", &["--scenario", sc.to_str().unwrap()], "explicit-event");
    assert_eq!(code, 0, "{}", text(&o.stderr));
    let start = times(&tr, "action", "action", "enableTrajectory");
    assert_eq!(times(&tr, "event", "event", "eventTrajectoryOk"), [start[0] + 12.0]);
    assert!(times(&tr, "event", "event", "eventTrajectoryFail").is_empty());
    // Probabilities and delay ranges are drawn from the seed: both outcomes
    // over a few seeds, each at its drawn delay, the same for the same seed.
    let sc = tmp("probabilities.toml");
    std::fs::write(&sc, "[tasks.Trajectory]\nprobabilities = { ok = 0.5, fail = 0.5 }\ndelay = [20, 40]\n").unwrap();
    let mut outcomes = Vec::new();
    for seed in 0..8 {
        let seed = seed.to_string();
        let (code, tr, o) = sim("examples/survey.mcl", &["--scenario", sc.to_str().unwrap(), "--seed", &seed], "prob");
        assert_eq!(code, 0, "{}", text(&o.stderr));
        let start = times(&tr, "action", "action", "enableTrajectory")[0];
        let ok = times(&tr, "event", "event", "eventTrajectoryOk");
        let fail = times(&tr, "event", "event", "eventTrajectoryFail");
        let (t, good) = match (ok.as_slice(), fail.as_slice()) {
            ([t], []) => (*t, true),
            ([], [t]) => (*t, false),
            other => panic!("seed {seed}: {other:?}"),
        };
        assert!((20.0 - 1e-6..=40.0 + 1e-6).contains(&(t - start)), "seed {seed}: after {} s", t - start);
        let (_, again, _) = sim("examples/survey.mcl", &["--scenario", sc.to_str().unwrap(), "--seed", &seed], "prob");
        assert_eq!(
            times(&again, "event", "event", if good { "eventTrajectoryOk" } else { "eventTrajectoryFail" }),
            [t]
        );
        outcomes.push(good);
    }
    assert!(outcomes.contains(&true) && outcomes.contains(&false), "{outcomes:?}");
}
