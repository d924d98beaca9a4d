//! The bridge file checked against a vehicle and the message types: a
//! correct file loads; each mistake is an error at its line.

use mcl_ros2::bridge::{load, Vehicle, VehiclePrimitive};
use std::path::PathBuf;

fn vehicle() -> Vehicle {
    let prim = |name: &str, enable: &[&str], events: &[&str]| VehiclePrimitive {
        name: name.into(),
        commands: vec![
            ("enable".into(), enable.iter().map(|s| s.to_string()).collect()),
            ("disable".into(), Vec::new()),
        ],
        events: events.iter().map(|s| s.to_string()).collect(),
    };
    Vehicle {
        primitives: vec![
            prim("GotoPrimitive", &["way-point", "speed"], &["eventGotoOk", "eventGotoFail"]),
            prim("AlarmPrimitive", &[], &["eventAlarm"]),
            prim("DepthPrimitive", &["depth"], &["eventDepthOk", "eventDepthFail"]),
        ],
    }
}

/// A folder of its own with `BRIDGE.toml` and the `nav` package.
fn write(name: &str, bridge: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-ros2-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("interfaces/nav/action")).unwrap();
    std::fs::write(
        dir.join("interfaces/nav/action/GoTo.action"),
        "geometry_msgs/Point target\nfloat64 speed 0.5\n---\nbool reached\n---\nfloat64 distance\n",
    )
    .unwrap();
    let path = dir.join("BRIDGE.toml");
    std::fs::write(&path, bridge).unwrap();
    path
}

const GOOD: &str = r#"node = "mcl_player"
namespace = "/auv"
domain_id = 7
interfaces = ["interfaces"]

[primitives.GotoPrimitive.action]
name = "/goto"
type = "nav/action/GoTo"
goal = { "target.x" = "$way-point.x", "target.y" = "$way-point.y", speed = "$speed * 0.5" }
succeeded = "eventGotoOk"
aborted = "eventGotoFail"
feedback = [{ field = "distance", name = "distance" }]

[primitives.AlarmPrimitive]
enable = { publish = "/alarm/enable", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/alarm/enable", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/alarm", type = "std_msgs/msg/Bool", when = "data == true", event = "eventAlarm" }]

[primitives.DepthPrimitive]
enable = { call = "/captain/depth", type = "std_srvs/srv/SetBool", fields = { data = true }, on_response = [{ when = "success == false", event = "eventDepthFail" }] }
disable = { call = "/captain/stop", type = "std_srvs/srv/Trigger" }
events = [{ topic = "/depth_reached", type = "std_msgs/msg/Empty", event = "eventDepthOk" }]
perceptions = [{ topic = "/navigator/depth", type = "std_msgs/msg/Float64", field = "data", name = "depth" }]
"#;

#[test]
fn a_correct_bridge_loads_with_its_interfaces() {
    let loaded = load(&write("good", GOOD), &vehicle()).unwrap_or_else(|e| panic!("{e:?}"));
    assert!(loaded.registry.has_action("nav/action/GoTo"));
    assert_eq!(loaded.bridge.domain_id.map(|d| *d.get_ref()), Some(7));
    assert_eq!(loaded.bridge.primitives.len(), 3);
}

/// The errors of `GOOD` with `from` replaced by `to`, as (line, message).
fn errors(name: &str, from: &str, to: &str) -> Vec<(usize, String)> {
    assert!(GOOD.contains(from), "{from}");
    let path = write(name, &GOOD.replacen(from, to, 1));
    match load(&path, &vehicle()) {
        Ok(_) => Vec::new(),
        Err(es) => es.into_iter().map(|e| (e.line, e.message)).collect(),
    }
}

#[track_caller]
fn one_error(name: &str, from: &str, to: &str, line: usize, needle: &str) {
    let es = errors(name, from, to);
    assert_eq!(es.len(), 1, "{es:?}");
    assert_eq!(es[0].0, line, "{es:?}");
    assert!(es[0].1.contains(needle), "{es:?}");
}

#[test]
fn each_mistake_is_an_error_at_its_line() {
    one_error("prim", "[primitives.AlarmPrimitive]", "[primitives.AlarmPrimitve]", 14, "no primitive `AlarmPrimitve`");
    one_error("field", "when = \"data == true\"", "when = \"value == true\"", 17, "no field `value`");
    one_error("kind", "when = \"data == true\"", "when = \"data > 2\"", 17, "a bool");
    one_error("param", "$speed * 0.5", "$velocity * 0.5", 9, "no parameter `velocity`");
    one_error("goalfield", "\"target.y\"", "\"target.w\"", 9, "no field `w`");
    one_error("event", "event = \"eventAlarm\"", "event = \"eventAlarmOk\"", 17, "no event `eventAlarmOk`");
    one_error("other", "event = \"eventAlarm\"", "event = \"eventGotoOk\"", 17, "belongs to primitive `GotoPrimitive`");
    one_error("type", "std_srvs/srv/Trigger", "std_srvs/srv/Trig", 21, "no service type");
    one_error("acttype", "nav/action/GoTo", "nav/action/Go", 8, "no action type");
    one_error("resp", "success == false", "succes == false", 20, "no field `succes`");
    one_error("feedback", "field = \"distance\"", "field = \"dist\"", 12, "no field `dist`");
    one_error("percep", "field = \"data\", name = \"depth\"", "field = \"datum\", name = \"depth\"", 23, "no field");
    one_error("const", "fields = { data = true } }", "fields = { data = 1 } }", 15, "a bool");
    one_error("topic", "\"/alarm\"", "\"/1alarm\"", 17, "topic name");
    one_error("domain", "domain_id = 7", "domain_id = 400", 3, "232");
    one_error("unknown key", "aborted =", "abort =", 11, "unknown field");
    one_error("both", "publish = \"/alarm/enable\"", "publish = \"/alarm/enable\", call = \"/x\"", 15, "one of");
    one_error("mapping", "domain_id = 7", "domain_id = 7\nservice_mapping = \"fast\"", 4, "not a service mapping");
    one_error(
        "timeout",
        "type = \"std_srvs/srv/Trigger\"",
        "type = \"std_srvs/srv/Trigger\", timeout = -1",
        21,
        "timeout -1",
    );
    one_error("acttimeout", "aborted = \"eventGotoFail\"", "aborted = \"eventGotoFail\"\ntimeout = 0", 12, "timeout 0");
    one_error(
        "failure topic",
        "fields = { data = false } }",
        "fields = { data = false }, on_failure = \"eventAlarm\" }",
        16,
        "`on_failure` goes with `call`",
    );
    one_error(
        "failure event",
        "type = \"std_srvs/srv/Trigger\"",
        "type = \"std_srvs/srv/Trigger\", on_failure = \"eventGotoFail\"",
        21,
        "no event `eventGotoFail`",
    );
    assert!(errors(
        "fine",
        "type = \"std_srvs/srv/Trigger\"",
        "type = \"std_srvs/srv/Trigger\", timeout = 2.5, on_failure = \"eventDepthFail\""
    )
    .is_empty());
}

#[test]
fn a_broken_interface_file_is_reported_at_its_own_line() {
    let path = write("idl", GOOD);
    let bad = path.parent().unwrap().join("interfaces/nav/action/GoTo.action");
    std::fs::write(&bad, "geometry_msgs/Point target\nfloat64 speed 0.5\n---\nbool reached\n---\nfloat65 distance\n")
        .unwrap();
    let es = load(&path, &vehicle()).unwrap_err();
    assert_eq!(es.len(), 1, "{es:?}");
    assert_eq!((es[0].file.clone(), es[0].line), (bad, 6));
}
