//! `mcl run --ros2`: services and actions on the wire, against servers
//! written in Python with Eclipse Cyclone DDS (`pip install cyclonedds`),
//! a DDS independent of MCL's (rustdds), as rmw_cyclonedds lays services
//! and actions out: `tests/ros2/vehicle.py` (topics and the services
//! `std_srvs/Trigger` and `SetBool`) and `tests/ros2/goto_server.py` (the
//! action `/goto`, whose goals behave by their target's x). Each run uses
//! a domain id of its own; the servers print what they saw, in order.

use mcl_testutil::{have_tool, runs};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};

/// The mappings every test uses: the go-to (`/goto`) and a second primitive
/// on the same action server, the alarm as a `std_msgs/Bool` topic, the
/// depth on topics, and the services of the vehicle.
const BRIDGE: &str = r#"node = "mcl_wire"
domain_id = DOMAIN
interfaces = ["INTERFACES"]

[primitives.GotoPrimitive.action]
name = "/goto"
type = "auv_msgs/action/GoTo"
goal = { "target.x" = "$way-point[0]", "target.y" = "$way-point[1]" }
succeeded = "eventGotoOk"
aborted = "eventGotoFail"
feedback = [{ field = "distance_to_target", name = "distance" }]
timeout = 3

[primitives.GotoTargetPrimitive.action]
name = "/goto"
type = "auv_msgs/action/GoTo"
goal = { "target.x" = 99.0 }
succeeded = "eventGotoTargetOk"
aborted = "eventGotoTargetFail"

[primitives.AlarmPrimitive]
enable = { publish = "/safety/alarm_watch", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/safety/alarm_watch", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/safety/alarm", type = "std_msgs/msg/Bool", when = "data == true", event = "eventAlarmOk" }]

[primitives.DepthPrimitive]
enable = { publish = "/depth/setpoint", type = "std_msgs/msg/Float64", fields = { data = "$depth" } }
disable = { publish = "/depth/stop", type = "std_msgs/msg/Empty" }
events = [{ topic = "/depth/reached", type = "std_msgs/msg/Float64", when = "data >= 0", event = "eventDepthOk" }]
perceptions = [{ topic = "/depth/reached", type = "std_msgs/msg/Float64", field = "data", name = "depth" }]

[primitives.SurfacePrimitive]
enable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = true } }
disable = { publish = "/surface/cmd", type = "std_msgs/msg/Bool", fields = { data = false } }
events = [{ topic = "/surface/done", type = "std_msgs/msg/String", when = "data == \"ok\"", event = "eventSurfaceOk" }]

[primitives.InitializeVehiclePrimitive]
enable = { call = "/vehicle/initialize", type = "std_srvs/srv/Trigger", on_response = [
    { when = "success == true", event = "eventInitializeVehicleOk" },
    { when = "success == false", event = "eventInitializeVehicleFail" },
] }

[primitives.TakeImagesPrimitive]
enable = { call = "CAMERA", type = "std_srvs/srv/SetBool", fields = { data = true }, timeout = 2, on_response = [
    { when = "success == true", event = "eventTakeImagesOk" },
], on_failure = "eventTakeImagesFail" }
disable = { call = "/camera/enable", type = "std_srvs/srv/SetBool", fields = { data = false } }

# A service called with a type other than its server's (a Trigger).
[primitives.GetPositionFixPrimitive]
enable = { call = "/vehicle/fix", type = "std_srvs/srv/SetBool", timeout = 2, on_failure = "eventGetPositionFixFail" }
"#;

/// What one run gave.
struct Run {
    /// The exit status of `mcl run`.
    code: Option<i32>,
    stderr: String,
    /// The trace (JSON lines).
    trace: String,
    /// What each server printed, by script.
    heard: Vec<Vec<String>>,
}

impl Run {
    /// Where `line` is in what server `i` printed (it must be there).
    fn at(&self, i: usize, line: &str) -> usize {
        let h = &self.heard[i];
        h.iter().position(|l| l == line).unwrap_or_else(|| panic!("`{line}` not in {h:?}\nstderr: {}", self.stderr))
    }

    /// The index of the first trace line holding `needle` (it must be there).
    fn traced(&self, needle: &str) -> usize {
        self.trace
            .lines()
            .position(|l| l.contains(needle))
            .unwrap_or_else(|| panic!("{needle} not in the trace:\n{}\nstderr: {}", self.trace, self.stderr))
    }
}

fn have_cyclonedds() -> bool {
    let found = runs("python3", &["-c", "import cyclonedds"]);
    have_tool("cyclonedds", found, "python3 -m pip install cyclonedds")
}

/// A Python server of a run: its script in tests/ros2, its arguments after
/// the domain and the seconds, its environment.
struct Server<'a>(&'a str, &'a [&'a str], &'a [(&'a str, &'a str)]);

/// A domain id (1..=200) of its own for each run of this process, against
/// cross-talk between the tests that run at the same time.
fn domain() -> u32 {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().subsec_nanos();
    static BASE: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    let base = *BASE.get_or_init(|| nanos ^ std::process::id());
    1 + (base.wrapping_add(NEXT.fetch_add(1, Ordering::Relaxed))) % 200
}

/// Runs `mission` (its body) through `mcl run --ros2` with [`BRIDGE`]
/// (`camera`: the service TakeImages calls) against the Python `servers`.
fn run(name: &str, mission: &str, camera: &str, servers: &[Server<'_>]) -> Run {
    run_for(name, mission, camera, servers, "40")
}

/// [`run`] with a time limit of `limit` seconds.
fn run_for(name: &str, mission: &str, camera: &str, servers: &[Server<'_>], limit: &str) -> Run {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let domain = domain();
    let dir: PathBuf = std::env::temp_dir().join(format!("mcl-ros2-wire-{name}-{}-{domain}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = root.join("examples/vehicle.mcl");
    let text = format!("import \"{}\";\n\nmission {{\n{mission}\n}}\n", vehicle.display());
    std::fs::write(dir.join("mission.mcl"), text).unwrap();
    let bridge = BRIDGE
        .replace("DOMAIN", &domain.to_string())
        .replace("INTERFACES", root.join("examples/ros2/interfaces").to_str().unwrap())
        .replace("CAMERA", camera);
    std::fs::write(dir.join("BRIDGE.toml"), bridge).unwrap();

    let mut children: Vec<(Child, Box<dyn Iterator<Item = String>>)> = Vec::new();
    for Server(script, args, env) in servers {
        let mut c = Command::new("python3")
            .arg(root.join("tests/ros2").join(script))
            .args([&domain.to_string(), "60"])
            .args(*args)
            .envs(env.iter().copied())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(c.stdout.take().unwrap()).lines().map_while(Result::ok);
        assert_eq!(lines.next().as_deref(), Some("ready"), "{script} did not start");
        children.push((c, Box::new(lines)));
    }
    let trace = dir.join("trace.jsonl");
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--ros2"])
        .arg(dir.join("BRIDGE.toml"))
        .arg(dir.join("mission.mcl"))
        .args(["--time-limit", limit, "--trace"])
        .arg(&trace)
        .output()
        .unwrap();
    let mut heard = Vec::new();
    for (mut c, lines) in children {
        let _ = c.kill();
        heard.push(lines.collect());
        let _ = c.wait();
    }
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "the player crashed: {stderr}");
    Run { code: out.status.code(), stderr, trace: std::fs::read_to_string(&trace).unwrap_or_default(), heard }
}

#[test]
fn a_mission_of_topics_and_services_runs_against_a_cyclonedds_vehicle() {
    if !have_cyclonedds() {
        return;
    }
    let mission = "    InitializeVehicle() ;\n    Depth( 15, \"achieve\" ) ;\n    TakeImages() ;\n    Surface()";
    let r = run("services", mission, "/camera/enable", &[Server("vehicle.py", &[], &[])]);
    assert_eq!(r.code, Some(0), "stderr: {}\nheard: {:?}", r.stderr, r.heard);
    // The vehicle answered the services in the mission's order, between its
    // topics (a disable and the next enable go out together, on different
    // topics: DDS does not order them).
    assert!(r.at(0, "initialize") < r.at(0, "setpoint 15.0"), "{:?}", r.heard);
    assert!(r.at(0, "setpoint 15.0") < r.at(0, "camera True"), "{:?}", r.heard);
    assert!(r.at(0, "camera True") < r.at(0, "camera False"), "{:?}", r.heard);
    assert!(r.at(0, "camera True") < r.at(0, "surface True"), "{:?}", r.heard);
    assert!(r.at(0, "surface True") < r.at(0, "surface False"), "{:?}", r.heard);
    // The responses raised the events, in order.
    assert!(r.traced("eventInitializeVehicleOk") < r.traced("eventDepthOk"));
    assert!(r.traced("eventDepthOk") < r.traced("eventTakeImagesOk"));
    assert!(r.traced("eventTakeImagesOk") < r.traced("eventSurfaceOk"));
}

#[test]
fn action_goals_give_feedback_results_and_cancels_before_the_next_goal() {
    if !have_cyclonedds() {
        return;
    }
    // A goal to its end; a parallel-or whose losing branch (x 99, endless)
    // is cancelled when the other wins; the next goal; a goal aborted by
    // the monitor's alarm (x 95 raises it), then the handler's goal.
    let mission = "    Goto( [1, 2] ) ;
    parallel { Goto( [3, 4] ) } or { GotoTarget() } ;
    Goto( [5, 6] ) ;
    monitor { Goto( [95, 0] ) } condition ( Alarm() ) do { Goto( [7, 8] ) }";
    let r = run("actions", mission, "/camera/enable", &[Server("goto_server.py", &[], &[])]);
    assert_eq!(r.code, Some(0), "stderr: {}\nheard: {:?}", r.stderr, r.heard);
    // Goal, feedback, result.
    assert!(r.at(0, "goal 1 2") < r.at(0, "succeeded 1"), "{:?}", r.heard);
    assert!(r.traced("\"distance\"") < r.traced("eventGotoOk"));
    // The losing branch was cancelled before the next goal reached the server.
    let (won, cancel, next) = (r.at(0, "succeeded 3"), r.at(0, "cancel 99"), r.at(0, "goal 5 6"));
    assert!(won < cancel && cancel < next, "{:?}", r.heard);
    assert!(!r.trace.contains("eventGotoTargetFail"), "a cancelled goal raised its fail event:\n{}", r.trace);
    // The alarm aborted the monitored goal: cancelled, then the handler's goal.
    let (alarmed, cancel, handler) = (r.at(0, "goal 95 0"), r.at(0, "cancel 95"), r.at(0, "goal 7 8"));
    assert!(alarmed < cancel && cancel < handler, "{:?}", r.heard);
    assert!(r.at(0, "goal 7 8") < r.at(0, "succeeded 7"), "{:?}", r.heard);
}

#[test]
fn a_rejected_an_aborted_an_unanswered_and_a_server_cancelled_goal_give_the_fail_event() {
    if !have_cyclonedds() {
        return;
    }
    // Each failure runs the catch, whose goal succeeds.
    let mission = "    try { Goto( [-1, 0] ) } catch { Goto( [1, 0] ) } ;
    try { Goto( [96, 0] ) } catch { Goto( [2, 0] ) } ;
    try { Goto( [98, 0] ) } catch { Goto( [3, 0] ) } ;
    try { Goto( [94, 0] ) } catch { Goto( [4, 0] ) }";
    let r = run("goals", mission, "/camera/enable", &[Server("goto_server.py", &[], &[])]);
    assert_eq!(r.code, Some(0), "stderr: {}\nheard: {:?}", r.stderr, r.heard);
    assert!(r.at(0, "rejected -1") < r.at(0, "goal 1 0"), "{:?}", r.heard);
    assert!(r.at(0, "aborted 96") < r.at(0, "goal 2 0"), "{:?}", r.heard);
    assert!(r.at(0, "goal 98 0") < r.at(0, "goal 3 0"), "{:?}", r.heard);
    assert!(r.at(0, "canceled 94") < r.at(0, "goal 4 0"), "{:?}", r.heard);
    assert!(r.stderr.contains("the action server `/goto` rejected the goal"), "{}", r.stderr);
    assert!(r.stderr.contains("the action server `/goto` did not answer the goal within 3.0 s"), "{}", r.stderr);
    assert_eq!(r.trace.matches("eventGotoFail").count(), 4, "{}", r.trace);
    assert!(r.traced("eventGotoFail") < r.traced("eventGotoOk"));
}

#[test]
fn a_service_that_never_answers_and_malformed_messages_do_not_stop_the_player() {
    if !have_cyclonedds() {
        return;
    }
    // /camera/stuck is served but never answered: after its 2 s, the fail
    // event runs the catch. /vehicle/fix is served, but as a Trigger:
    // the SetBool call finds no server of its type. The vehicle's hostile
    // mode sends a `Float64` without its field and a message of another
    // type on /depth/reached before the right answer.
    let mission = "    try { TakeImages() } catch { InitializeVehicle() } ;
    try { GetPositionFix() } catch { Depth( 15, \"achieve\" ) }";
    let r = run("hostile", mission, "/camera/stuck", &[Server("vehicle.py", &["hostile"], &[])]);
    assert_eq!(r.code, Some(0), "stderr: {}\nheard: {:?}", r.stderr, r.heard);
    assert!(r.at(0, "stuck") < r.at(0, "initialize"), "{:?}", r.heard);
    assert!(r.stderr.contains("service `/camera/stuck`: the server did not answer within 2.0 s"), "{}", r.stderr);
    assert!(r.traced("eventTakeImagesFail") < r.traced("eventInitializeVehicleOk"));
    assert!(
        r.stderr.contains("a message on `/depth/reached` is not a `std_msgs/msg/Float64`"),
        "no warning for the malformed message: {}",
        r.stderr
    );
    assert!(
        r.stderr.contains(
            "a publisher on `/depth/reached` writes `std_msgs::msg::dds_::String_`, not `std_msgs::msg::dds_::Float64_`"
        ),
        "no warning for the publisher of another type: {}",
        r.stderr
    );
    assert!(
        r.stderr.contains(
            "service `/vehicle/fix`: no server was found within 2.0 s: one reads requests of type \
             std_srvs::srv::dds_::Trigger_Request_, not std_srvs::srv::dds_::SetBool_Request_"
        ),
        "{}",
        r.stderr
    );
    assert!(r.traced("eventInitializeVehicleOk") < r.traced("eventGetPositionFixFail"));
    assert!(r.traced("eventGetPositionFixFail") < r.traced("eventDepthOk"));
}

#[test]
fn an_action_server_that_disappears_mid_goal_fails_the_goal() {
    if !have_cyclonedds() {
        return;
    }
    // The server crashes (no goodbye on DDS) while x 97 runs; its lease of
    // 1 s runs out, and the goal fails; the catch's Depth runs on the vehicle.
    let lease = "<CycloneDDS><Domain><Discovery><LeaseDuration>1s</LeaseDuration></Discovery></Domain></CycloneDDS>";
    let mission = "    try { Goto( [97, 0] ) } catch { Depth( 5, \"achieve\" ) }";
    let r = run(
        "crash",
        mission,
        "/camera/enable",
        &[Server("goto_server.py", &[], &[("CYCLONEDDS_URI", lease)]), Server("vehicle.py", &[], &[])],
    );
    assert_eq!(r.code, Some(0), "stderr: {}\nheard: {:?}", r.stderr, r.heard);
    assert!(r.at(0, "goal 97 0") < r.at(0, "crash"), "{:?}", r.heard);
    assert!(r.stderr.contains("the action server `/goto` left while the goal ran"), "{}", r.stderr);
    assert!(r.traced("eventGotoFail") < r.traced("eventDepthOk"));
    r.at(1, "setpoint 5.0");
}

#[test]
fn a_goal_still_running_when_the_player_stops_is_cancelled() {
    if !have_cyclonedds() {
        return;
    }
    // x 99 runs until cancelled; the time limit ends the mission under way.
    let r = run_for("left", "    Goto( [99, 0] )", "/camera/enable", &[Server("goto_server.py", &[], &[])], "4");
    assert_ne!(r.code, Some(0), "the mission cannot have ended: {}", r.stderr);
    assert!(r.at(0, "goal 99 0") < r.at(0, "cancel 99"), "{:?}", r.heard);
}
