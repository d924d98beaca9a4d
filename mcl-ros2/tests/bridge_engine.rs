//! The bridge's state machine: commands become messages, service calls and
//! goals built from the command's parameters; messages, responses and goal
//! ends become the mapped events and perceptions, topic events only while
//! their primitive is enabled.

use mcl_ros2::bridge::engine::{Engine, GoalEnd, Out};
use mcl_ros2::bridge::{load, Vehicle, VehiclePrimitive};
use serde_json::{json, Map, Value};

const BRIDGE: &str = r#"node = "mcl"
interfaces = ["interfaces"]

[primitives.GotoPrimitive.action]
name = "/goto"
type = "nav/action/GoTo"
goal = { "target.x" = "$way-point[0]", "target.y" = "$way-point[1]", speed = "$speed * 0.5" }
succeeded = "eventGotoOk"
aborted = "eventGotoFail"
feedback = [{ field = "distance", name = "distance" }]

[primitives.AlarmPrimitive]
enable = { publish = "/alarm/enable", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/alarm/enable", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/alarm", type = "std_msgs/msg/Bool", when = "data == true", event = "eventAlarm" }]
perceptions = [{ topic = "/alarm", type = "std_msgs/msg/Bool", field = "data", name = "alarm" }]

[primitives.DepthPrimitive]
enable = { call = "/captain/depth", type = "std_srvs/srv/SetBool", fields = { data = true }, on_response = [{ when = "success == false", event = "eventDepthFail" }] }
disable = { call = "/captain/stop", type = "std_srvs/srv/Trigger", timeout = 2.5, on_failure = "eventDepthFail" }
"#;

/// The engine of `BRIDGE`, from a folder of its own per test (`name`):
/// the tests run in parallel.
fn engine(name: &str) -> Engine {
    let dir = std::env::temp_dir().join(format!("mcl-ros2-engine-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("interfaces/nav/action")).unwrap();
    std::fs::write(
        dir.join("interfaces/nav/action/GoTo.action"),
        "geometry_msgs/Point target\nfloat64 speed\n---\nbool reached\n---\nfloat64 distance\n",
    )
    .unwrap();
    std::fs::write(dir.join("BRIDGE.toml"), BRIDGE).unwrap();
    let prim = |name: &str, params: &[&str], events: &[&str]| VehiclePrimitive {
        name: name.into(),
        commands: vec![
            ("enable".into(), params.iter().map(|s| s.to_string()).collect()),
            ("disable".into(), Vec::new()),
        ],
        events: events.iter().map(|s| s.to_string()).collect(),
    };
    let vehicle = Vehicle {
        primitives: vec![
            prim("GotoPrimitive", &["way-point", "speed"], &["eventGotoOk", "eventGotoFail"]),
            prim("AlarmPrimitive", &[], &["eventAlarm"]),
            prim("DepthPrimitive", &["depth"], &["eventDepthOk", "eventDepthFail"]),
        ],
    };
    Engine::new(load(&dir.join("BRIDGE.toml"), &vehicle).unwrap_or_else(|e| panic!("{e:?}")))
}

fn params(v: Value) -> Map<String, Value> {
    v.as_object().unwrap().clone()
}

#[test]
fn an_action_primitive_sends_goals_cancels_and_maps_ends() {
    let mut e = engine("action");
    let out = e.on_command("GotoPrimitive", "enable", &params(json!({"way-point": [24, 12], "speed": 2})));
    assert_eq!(
        out,
        [Out::SendGoal {
            primitive: "GotoPrimitive".into(),
            action: "/goto".into(),
            ty: "nav/action/GoTo".into(),
            goal: json!({"target": {"x": 24, "y": 12}, "speed": 1.0}),
        }]
    );
    // The goal encodes against its type (a missing z takes its default).
    let goal = match &out[0] {
        Out::SendGoal { goal, .. } => goal.clone(),
        _ => unreachable!(),
    };
    mcl_ros2::cdr::encode(&e.loaded().registry, "nav/action/GoTo_Goal", &goal).unwrap();
    assert_eq!(
        e.on_feedback("GotoPrimitive", &json!({"distance": 3.5})),
        [Out::Perception { name: "distance".into(), value: json!(3.5) }]
    );
    assert_eq!(e.on_goal_end("GotoPrimitive", GoalEnd::Succeeded), [Out::Event("eventGotoOk".into())]);
    e.on_command("GotoPrimitive", "enable", &params(json!({"way-point": [1, 2], "speed": 1})));
    assert_eq!(e.on_goal_end("GotoPrimitive", GoalEnd::Rejected), [Out::Event("eventGotoFail".into())]);
    // Disabled (the losing branch of a parallel-or): cancel, and its end raises nothing.
    assert_eq!(
        e.on_command("GotoPrimitive", "disable", &Map::new()),
        [Out::CancelGoal { primitive: "GotoPrimitive".into(), action: "/goto".into() }]
    );
    assert!(e.on_goal_end("GotoPrimitive", GoalEnd::Canceled).is_empty());
    // A goal whose parameter is missing fails at once, with a warning.
    let out = e.on_command("GotoPrimitive", "enable", &params(json!({"speed": 1})));
    assert!(matches!(&out[0], Out::Warning(w) if w.contains("way-point")), "{out:?}");
    assert_eq!(out[1], Out::Event("eventGotoFail".into()));
}

#[test]
fn topic_events_only_while_enabled_and_perceptions_always() {
    let mut e = engine("topic");
    assert_eq!(e.subscriptions().get("/alarm").map(String::as_str), Some("std_msgs/msg/Bool"));
    let alarm = json!({"data": true});
    assert_eq!(e.on_message("/alarm", &alarm), [Out::Perception { name: "alarm".into(), value: json!(true) }]);
    assert_eq!(
        e.on_command("AlarmPrimitive", "enable", &Map::new()),
        [Out::Publish { topic: "/alarm/enable".into(), ty: "std_msgs/msg/Bool".into(), value: json!({"data": true}) }]
    );
    assert!(e.on_message("/alarm", &alarm).contains(&Out::Event("eventAlarm".into())));
    assert!(!e.on_message("/alarm", &json!({"data": false})).iter().any(|o| matches!(o, Out::Event(_))));
    e.on_command("AlarmPrimitive", "disable", &Map::new());
    assert!(!e.on_message("/alarm", &alarm).iter().any(|o| matches!(o, Out::Event(_))));
    assert!(e.on_message("/elsewhere", &alarm).is_empty());
}

#[test]
fn service_responses_raise_their_events_and_failures_warn() {
    let mut e = engine("service");
    let out = e.on_command("DepthPrimitive", "enable", &params(json!({"depth": 10})));
    let Out::Call { call, service, request, .. } = &out[0] else { panic!("{out:?}") };
    assert_eq!((service.as_str(), request), ("/captain/depth", &json!({"data": true})));
    assert_eq!(
        e.on_response(*call, Ok(json!({"success": false, "message": "no"}))),
        [Out::Event("eventDepthFail".into())]
    );
    // Answered once only.
    assert!(e.on_response(*call, Ok(json!({"success": false}))).is_empty());
    let out = e.on_command("DepthPrimitive", "enable", &params(json!({"depth": 10})));
    let Out::Call { call, .. } = &out[0] else { panic!("{out:?}") };
    assert!(e.on_response(*call, Ok(json!({"success": true}))).is_empty());
    let out = e.on_command("DepthPrimitive", "enable", &params(json!({"depth": 10})));
    let Out::Call { call, .. } = &out[0] else { panic!("{out:?}") };
    let failed = e.on_response(*call, Err("no answer".into()));
    assert!(matches!(&failed[..], [Out::Warning(w)] if w.contains("no answer")), "{failed:?}");
    assert!(matches!(&e.on_command("Nope", "enable", &Map::new())[0], Out::Warning(_)));
    // The answer to an enable that comes after the disable raises nothing.
    let out = e.on_command("DepthPrimitive", "enable", &params(json!({"depth": 10})));
    let Out::Call { call: late, .. } = &out[0] else { panic!("{out:?}") };
    // A call with `on_failure` raises it when there is no response, and has its own timeout.
    let out = e.on_command("DepthPrimitive", "disable", &Map::new());
    let Out::Call { call, timeout, .. } = &out[0] else { panic!("{out:?}") };
    assert_eq!(*timeout, std::time::Duration::from_millis(2500));
    let failed = e.on_response(*call, Err("no answer".into()));
    assert!(matches!(&failed[..], [Out::Warning(_), Out::Event(ev)] if ev == "eventDepthFail"), "{failed:?}");
    assert!(e.on_response(*late, Ok(json!({"success": false}))).is_empty());
    assert_eq!(e.goal_timeout("GotoPrimitive"), std::time::Duration::from_secs(10));
}
