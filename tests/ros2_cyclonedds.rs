//! `mcl run --ros2`: a mission of topics runs to its end against a vehicle
//! written in Python with Eclipse Cyclone DDS (`pip install cyclonedds`), a
//! DDS independent of MCL's (rustdds): ROS 2 topic names `rt/...`, ROS 2
//! type names, CDR both ways. Each run uses a domain id of its own.

use mcl_testutil::{have_tool, runs};
use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

const MISSION: &str = "import \"VEHICLE\";\n\nmission {\n    Depth( 15, \"achieve\" ) ;\n    Surface()\n}\n";

const BRIDGE: &str = r#"node = "mcl_test"
domain_id = DOMAIN

[primitives.DepthPrimitive]
enable = { publish = "/depth/setpoint", type = "std_msgs/msg/Float64", fields = { data = "$depth" } }
disable = { publish = "/depth/stop", type = "std_msgs/msg/Empty" }
events = [
    { topic = "/depth/reached", type = "std_msgs/msg/Float64", when = "data >= 0", event = "eventDepthOk" },
    { topic = "/depth/reached", type = "std_msgs/msg/Float64", when = "data < 0", event = "eventDepthFail" },
]
perceptions = [{ topic = "/depth/reached", type = "std_msgs/msg/Float64", field = "data", name = "depth" }]

[primitives.SurfacePrimitive]
enable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/surface/done", type = "std_msgs/msg/String", when = "data == \"ok\"", event = "eventSurfaceOk" }]
"#;

/// A Python vehicle on Cyclone DDS in a domain of its own, with a folder
/// for the run's files (`BRIDGE.toml` written there).
struct Peer {
    dir: PathBuf,
    py: Child,
    lines: std::io::Lines<BufReader<std::process::ChildStdout>>,
}

impl Peer {
    /// `None` (the test skips) when cyclonedds is missing and not required.
    fn start(name: &str) -> Option<Peer> {
        let found = runs("python3", &["-c", "import cyclonedds"]);
        if !have_tool("cyclonedds", found, "python3 -m pip install cyclonedds") {
            return None;
        }
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        // A domain of its own (1..=200) against cross-talk between runs.
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().subsec_nanos();
        let domain = 1 + (nanos ^ std::process::id()) % 200;
        let dir = std::env::temp_dir().join(format!("mcl-ros2-{name}-{}-{domain}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("BRIDGE.toml"), BRIDGE.replace("DOMAIN", &domain.to_string())).unwrap();
        let mut py = Command::new("python3")
            .arg(root.join("tests/ros2/vehicle.py"))
            .args([&domain.to_string(), "60"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(py.stdout.take().unwrap()).lines();
        assert_eq!(lines.next().unwrap().unwrap(), "ready");
        Some(Peer { dir, py, lines })
    }

    /// Runs `mcl ARGS`, then stops the vehicle: the output and what the
    /// vehicle heard.
    fn run(mut self, args: &[&OsStr]) -> (Output, Vec<String>) {
        let out = Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).output().unwrap();
        let _ = self.py.kill();
        let heard: Vec<String> = self.lines.map_while(Result::ok).collect();
        let _ = self.py.wait();
        (out, heard)
    }
}

/// `examples/vehicle.mcl`'s path.
fn vehicle() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/vehicle.mcl").to_str().unwrap().to_string()
}

#[test]
fn a_mission_of_topics_runs_against_a_cyclonedds_vehicle() {
    let Some(peer) = Peer::start("run") else { return };
    let dir = peer.dir.clone();
    std::fs::write(dir.join("mission.mcl"), MISSION.replace("VEHICLE", &vehicle())).unwrap();
    let trace = dir.join("trace.jsonl");
    let (bridge, mission) = (dir.join("BRIDGE.toml"), dir.join("mission.mcl"));
    let (out, heard) = peer.run(&[
        "run".as_ref(),
        "--ros2".as_ref(),
        bridge.as_os_str(),
        mission.as_os_str(),
        "--time-limit".as_ref(),
        "30".as_ref(),
        "--trace".as_ref(),
        trace.as_os_str(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}\nvehicle heard: {heard:?}");
    // The vehicle heard the mission's commands, in order.
    let pos = |l: &str| heard.iter().position(|h| h == l).unwrap_or_else(|| panic!("`{l}` not in {heard:?}"));
    assert!(pos("setpoint 15.0") < pos("stop") && pos("stop") < pos("surface True"), "{heard:?}");
    assert!(pos("surface True") < pos("surface False"), "{heard:?}");
    // The events and the perception came back through the bridge.
    let t = std::fs::read_to_string(&trace).unwrap();
    for needle in ["eventDepthOk", "eventSurfaceOk", "\"depth\""] {
        assert!(t.contains(needle), "{needle} not in the trace:\n{t}");
    }
    // The status topic told the vehicle which calls ran, where, and how
    // the mission ended.
    let statuses = statuses(&heard);
    let running = |task: &str| {
        statuses.iter().flat_map(|s| s["running"].as_array().cloned().unwrap_or_default()).find(|c| c["task"] == task)
    };
    let depth = running("Depth").unwrap_or_else(|| panic!("no running Depth in {statuses:?}"));
    assert!(depth["file"].as_str().unwrap().ends_with("mission.mcl"), "{depth}");
    assert_eq!(depth["line"], 4, "{depth}");
    assert_eq!(running("Surface").unwrap_or_else(|| panic!("{statuses:?}"))["line"], 5);
    let last = statuses.last().unwrap();
    assert_eq!((last["mission"].as_str(), last["outcome"].as_str()), (Some("mission"), Some("ok")), "{last}");
    assert_eq!(last["running"], serde_json::json!([]), "{last}");
}

const PLAN: &str = r#"import "operators.mcl";

planning {
    type vehicle { max_depth; }
    type location { z; }

    entity vehicle auv { max_depth = 30; }
    entity location top { z = 0; }
    entity location site { z = 15; }

    operator dive( vehicle v, location l1, location l2 ) {
        precond { v in l1; }
        add { v in l2; }
        del { v in l1; }
        expression { l1 != l2; l2.z <= v.max_depth; }
        mcl DiveOp( l2.z );
    }

    initial { auv in top; }
    goal { auv in site; }
}
"#;

const OPERATORS: &str =
    "import \"VEHICLE\";\n\nmission DiveOp( z ) {\n    Depth( z, \"achieve\" ) ;\n    Surface()\n}\n";

/// The vehicle is at the site once the depth it reports is 10 m or more.
const WORLD: &str = r#"<?xml version="1.0"?>
<world>
  <script id="at_site">
    <condition value1="depth" type1="perception" operator=">=" value2="10" type2="literal"/>
    <del value1="auv" type1="vehicle" prop="in" value2="top" type2="location"/>
    <add value1="auv" type1="vehicle" prop="in" value2="site" type2="location"/>
  </script>
</world>
"#;

#[test]
fn a_planned_mission_runs_against_a_cyclonedds_vehicle() {
    let Some(peer) = Peer::start("plan") else { return };
    let dir = peer.dir.clone();
    std::fs::write(dir.join("plan.mcl"), PLAN).unwrap();
    std::fs::write(dir.join("operators.mcl"), OPERATORS.replace("VEHICLE", &vehicle())).unwrap();
    std::fs::write(dir.join("world.xml"), WORLD).unwrap();
    let trace = dir.join("trace.jsonl");
    let (bridge, plan) = (dir.join("BRIDGE.toml"), dir.join("plan.mcl"));
    let (out, heard) = peer.run(&[
        "plan".as_ref(),
        plan.as_os_str(),
        "--run".as_ref(),
        "--ros2".as_ref(),
        bridge.as_os_str(),
        "--time-limit".as_ref(),
        "30".as_ref(),
        "--trace".as_ref(),
        trace.as_os_str(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}\nvehicle heard: {heard:?}");
    assert!(stderr.contains("planned mission: OK") && stderr.contains("(1 plan(s), 1 step(s))"), "{stderr}");
    // The step's mission ran on the vehicle: the depth of the plan's
    // location, then the surfacing.
    let pos = |l: &str| heard.iter().position(|h| h == l).unwrap_or_else(|| panic!("`{l}` not in {heard:?}"));
    assert!(pos("setpoint 15.0") < pos("surface True"), "{heard:?}");
    let t = std::fs::read_to_string(&trace).unwrap();
    assert!(t.contains("eventDepthOk") && t.contains("eventSurfaceOk"), "{t}");
    // The status topic followed the step's mission, in operators.mcl.
    let statuses = statuses(&heard);
    let depth = statuses
        .iter()
        .flat_map(|s| s["running"].as_array().cloned().unwrap_or_default())
        .find(|c| c["task"] == "Depth")
        .unwrap_or_else(|| panic!("no running Depth in {statuses:?}"));
    assert!(depth["file"].as_str().unwrap().ends_with("operators.mcl"), "{depth}");
    assert_eq!(depth["line"], 4, "{depth}");
    let last = statuses.last().unwrap();
    assert_eq!((last["mission"].as_str(), last["outcome"].as_str()), (Some("plan:plan"), Some("ok")), "{last}");
}

/// The JSON of each `status` line the vehicle printed.
fn statuses(heard: &[String]) -> Vec<serde_json::Value> {
    heard.iter().filter_map(|l| l.strip_prefix("status ")).map(|j| serde_json::from_str(j).unwrap()).collect()
}
