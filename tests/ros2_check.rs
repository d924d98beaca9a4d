//! `mcl check --ros2 BRIDGE.toml`: the example bridge of docs/ros2.md is
//! correct against examples/vehicle.mcl, and a broken copy gives each
//! error at its file and line, in the human and the JSON output.

use std::path::Path;
use std::process::Command;

fn mcl(args: &[&str]) -> (i32, String) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
fn the_example_bridge_is_correct() {
    let (code, out) = mcl(&["check", "--ros2", "examples/ros2/BRIDGE.toml", "examples/vehicle.mcl"]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("0 errors"), "{out}");
}

#[test]
fn a_broken_bridge_gives_errors_with_file_and_line() {
    let dir = std::env::temp_dir().join(format!("mcl-ros2-check-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("interfaces/auv_msgs/action")).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/ros2");
    std::fs::copy(
        root.join("interfaces/auv_msgs/action/GoTo.action"),
        dir.join("interfaces/auv_msgs/action/GoTo.action"),
    )
    .unwrap();
    let text = std::fs::read_to_string(root.join("BRIDGE.toml")).unwrap();
    let line_of = |needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    let broken = text
        .replacen("\"$way-point[1]\"", "\"$waypoint[1]\"", 1)
        .replacen("when = \"data < 0.2\"", "when = \"dat < 0.2\"", 1)
        .replacen("[primitives.AlarmPrimitive]", "[primitives.AlarmPrimitiv]", 1);
    let bridge = dir.join("BRIDGE.toml");
    std::fs::write(&bridge, broken).unwrap();
    let b = bridge.to_str().unwrap();
    let (code, out) = mcl(&["check", "--ros2", b, "examples/vehicle.mcl"]);
    assert_eq!(code, 1, "{out}");
    for (needle, what) in [
        ("$way-point[1]", "no parameter `waypoint`"),
        ("data < 0.2", "no field `dat`"),
        ("[primitives.AlarmPrimitive]", "no primitive `AlarmPrimitiv`"),
    ] {
        let at = format!("{b}:{}:", line_of(needle));
        assert!(out.lines().any(|l| l.starts_with(&at) && l.contains(what)), "{at} {what}\n{out}");
    }
    assert!(out.contains("3 errors"), "{out}");
    let (code, out) = mcl(&["check", "--format", "json", "--ros2", b, "examples/vehicle.mcl"]);
    assert_eq!(code, 1);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let lines: Vec<u64> = v.as_array().unwrap().iter().map(|d| d["line"].as_u64().unwrap()).collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(lines.contains(&(line_of("data < 0.2") as u64)));
}

/// `mcl plan --run --ros2`: the bridge is checked against the operators'
/// vehicle before anything runs (no DDS needed to see it refused), and
/// what needs the in-process mock is refused.
#[test]
fn a_planned_run_checks_the_bridge_first() {
    let dir = std::env::temp_dir().join(format!("mcl-ros2-plan-check-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let bridge = dir.join("BRIDGE.toml");
    std::fs::write(&bridge, "node = \"n\"\n\n[primitives.NoSuchPrimitive]\nevents = []\n").unwrap();
    let (b, plan) = (bridge.to_str().unwrap(), "examples/planning/move/move.mcl");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["plan", plan, "--run", "--ros2", b])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(&format!("{b}:3:")) && stderr.contains("no primitive `NoSuchPrimitive`"), "{stderr}");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["plan", plan, "--run", "--ros2", b, "--virtual-time"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--ros2 runs in real time"), "{stderr}");
}
