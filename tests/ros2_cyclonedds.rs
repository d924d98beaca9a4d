//! `mcl run --ros2`: a mission of topics runs to its end against a vehicle
//! written in Python with Eclipse Cyclone DDS (`pip install cyclonedds`), a
//! DDS independent of MCL's (rustdds): ROS 2 topic names `rt/...`, ROS 2
//! type names, CDR both ways. Each run uses a domain id of its own.

use mcl_testutil::{have_tool, runs};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

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

#[test]
fn a_mission_of_topics_runs_against_a_cyclonedds_vehicle() {
    let found = runs("python3", &["-c", "import cyclonedds"]);
    if !have_tool("cyclonedds", found, "python3 -m pip install cyclonedds") {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // A domain of its own (1..=200) against cross-talk between runs.
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().subsec_nanos();
    let domain = 1 + (nanos ^ std::process::id()) % 200;
    let dir = std::env::temp_dir().join(format!("mcl-ros2-cyclone-{}-{domain}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = root.join("examples/vehicle.mcl");
    std::fs::write(dir.join("mission.mcl"), MISSION.replace("VEHICLE", vehicle.to_str().unwrap())).unwrap();
    std::fs::write(dir.join("BRIDGE.toml"), BRIDGE.replace("DOMAIN", &domain.to_string())).unwrap();

    let mut py = Command::new("python3")
        .arg(root.join("tests/ros2/vehicle.py"))
        .args([&domain.to_string(), "60"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(py.stdout.take().unwrap()).lines();
    assert_eq!(lines.next().unwrap().unwrap(), "ready");

    let trace = dir.join("trace.jsonl");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--ros2"])
        .arg(dir.join("BRIDGE.toml"))
        .arg(dir.join("mission.mcl"))
        .args(["--time-limit", "30", "--trace"])
        .arg(&trace)
        .output()
        .unwrap();
    let _ = py.kill();
    let heard: Vec<String> = lines.map_while(Result::ok).collect();
    let _ = py.wait();
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
}
