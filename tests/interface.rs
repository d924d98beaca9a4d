//! `mcl interface` through the binary: the contract a vehicle's AAC is
//! written against, taken from the program (never from names).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(root()).output().expect("run mcl")
}

fn primitive<'a>(i: &'a Value, name: &str) -> &'a Value {
    i["primitives"].as_array().unwrap().iter().find(|p| p["primitive"] == name).unwrap_or_else(|| panic!("{name}"))
}

/// A vehicle whose names follow no convention, and `mission`.
fn boat(dir: &std::path::Path, mission: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("boat.mcl");
    std::fs::write(&file, format!("{BOAT}\n{mission}\n")).unwrap();
    file
}

const BOAT: &str = r#"
actions {
    goThere = NavPrimitive( c: start, v: target, v: speed );
    halt = NavPrimitive( c: stop );
    armSonar = SonarPrimitive( c: on );
    disarmSonar = SonarPrimitive( c: off );
}
events { navReady; navLost; navProgress; obstacleSeen; sonarBroken; }
pattern {
    P_NAV {
        places { begin.1; abort.1; ok.1; fail.1; w; }
        transitions { Go; Arrived; Lost; Tick; Stop; }
        arcs {
            begin.1 -> Go; Go -> w; w -> Arrived; Arrived -> ok.1; w -> Lost; Lost -> fail.1;
            w -> Tick; Tick -> w; w -> Stop; abort.1 -> Stop;
        }
    }
}
tasks {
    Nav( target, speed ): P_NAV {
        a: goThere -> Go; a: halt -> Arrived, Lost, Stop;
        e: navReady -> Arrived; e: navLost -> Lost; e: navProgress -> Tick;
    }
    Sonar(): AchieveOneGoal {
        a: armSonar -> T0; a: disarmSonar -> T1, T6, T7;
        e: obstacleSeen -> T2; e: sonarBroken -> T3;
    }
}
"#;

/// The role `hello.events` gives to an event of `mcl interface`'s role.
fn hello_role(interface_role: &str) -> &str {
    match interface_role {
        "ends_ok" => "ok",
        "ends_fail" => "fail",
        "condition" => "condition",
        r => panic!("no hello role for {r}"),
    }
}

#[test]
fn a_vehicle_with_names_that_follow_no_convention() {
    let dir = std::env::temp_dir().join(format!("mcl-interface-{}", std::process::id()));
    let file = boat(&dir, "mission { monitor { Nav( [1, 2], 0.5 ) } condition ( Sonar() ) do { Nav( [0, 0], 1 ) } }");
    let out = mcl(&["interface", file.to_str().unwrap(), "--format", "json"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let i: Value = serde_json::from_slice(&out.stdout).unwrap();
    let nav = primitive(&i, "NavPrimitive");
    assert_eq!(nav["commands"][0]["command"], "start");
    assert_eq!(nav["commands"][0]["params"], serde_json::json!(["target", "speed"]));
    assert_eq!(nav["commands"][1]["command"], "stop");
    let role = |p: &Value, e: &str| {
        p["events"].as_array().unwrap().iter().find(|x| x["event"] == e).map(|x| x["role"].clone()).unwrap()
    };
    assert_eq!(role(nav, "navReady"), "ends_ok");
    assert_eq!(role(nav, "navLost"), "ends_fail");
    assert_eq!(role(nav, "navProgress"), "other");
    assert_eq!(nav["monitor_condition"], false);
    let sonar = primitive(&i, "SonarPrimitive");
    // A monitor's condition: its ok event raises the `do` block, and the
    // vehicle must not send it as a plain answer.
    assert_eq!(role(sonar, "obstacleSeen"), "condition");
    assert_eq!(role(sonar, "sonarBroken"), "ends_fail");
    assert_eq!(sonar["monitor_condition"], true);

    let md = mcl(&["interface", file.to_str().unwrap()]);
    assert_eq!(md.status.code(), Some(0));
    let md = String::from_utf8(md.stdout).unwrap();
    assert!(md.contains("## `NavPrimitive`"), "{md}");
    assert!(md.contains("| `start` | `goThere` | `target`, `speed` |"), "{md}");
    assert!(md.contains("| `navReady` | ends the task ok | `Nav` |"), "{md}");
    assert!(md.contains("Watched as a monitor's condition"), "{md}");

    // The player announces the same roles in its `hello` (docs/aac-protocol.md §3).
    let hello = first_hello(&file);
    assert_same_roles(&i, &hello);
    let ends = hello["events"].as_array().unwrap();
    let nav = ends.iter().find(|x| x["event"] == "navReady").unwrap();
    assert_eq!(nav["task"], "Nav");
    let seen = ends.iter().find(|x| x["event"] == "obstacleSeen").unwrap();
    assert_eq!((seen["role"].as_str(), seen["call_sites"].as_array().map(Vec::len)), (Some("condition"), Some(1)));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `mcl interface` and the player's `hello.events` give every event the
/// same roles, and `hello` lists exactly the events that end a task.
fn assert_same_roles(i: &Value, hello: &Value) {
    assert_eq!(hello["type"], "hello");
    let ends = hello["events"].as_array().expect("hello.events");
    let mut expected = 0;
    for p in i["primitives"].as_array().unwrap() {
        for e in p["events"].as_array().unwrap() {
            let role = e["role"].as_str().unwrap();
            let said: Vec<&Value> =
                ends.iter().filter(|x| x["event"] == e["event"] && x["task"] == e["task"]).collect();
            if role == "other" {
                assert!(said.is_empty(), "{} ends nothing but hello lists it: {hello}", e["event"]);
                continue;
            }
            expected += 1;
            let said = said
                .iter()
                .find(|x| x["role"] == hello_role(role))
                .unwrap_or_else(|| panic!("{} ({role}) not in hello: {hello}", e["event"]));
            assert_eq!(said["primitive"], p["primitive"], "{hello}");
        }
    }
    assert_eq!(ends.len(), expected, "hello lists more than the interface: {hello}");
}

/// A task called both as a monitor's condition and as a step: its ok event
/// has both roles, and `hello` names the condition's call.
#[test]
fn a_task_called_as_a_condition_and_as_a_step() {
    let dir = std::env::temp_dir().join(format!("mcl-interface-both-{}", std::process::id()));
    let file = boat(
        &dir,
        "mission { Sonar() ; monitor { Nav( [1, 2], 0.5 ) } condition ( Sonar() ) do { Nav( [0, 0], 1 ) } }",
    );
    let out = mcl(&["interface", file.to_str().unwrap(), "--format", "json"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let i: Value = serde_json::from_slice(&out.stdout).unwrap();
    let sonar = primitive(&i, "SonarPrimitive");
    let roles: Vec<&str> = sonar["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["event"] == "obstacleSeen")
        .map(|e| e["role"].as_str().unwrap())
        .collect();
    assert_eq!(roles, ["ends_ok", "condition"]);
    let hello = first_hello(&file);
    assert_same_roles(&i, &hello);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The first message `mcl run --aac` sends for `file`, read by a listener
/// that answers nothing (the player is then stopped).
fn first_hello(file: &std::path::Path) -> Value {
    use std::io::BufRead;
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--aac", &addr, "-q", file.to_str().unwrap()])
        .current_dir(root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("run mcl");
    let (stream, _) = listener.accept().expect("the player connects");
    stream.set_read_timeout(Some(std::time::Duration::from_secs(30))).unwrap();
    let mut line = String::new();
    std::io::BufReader::new(stream).read_line(&mut line).expect("a hello line");
    let _ = child.kill();
    let _ = child.wait();
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
}

#[test]
fn errors_and_unreadable_files() {
    let out = mcl(&["interface", "tests/ui/e0101_did_you_mean.mcl"]);
    assert_eq!(out.status.code(), Some(1));
    let out = mcl(&["interface", "no/such/file.mcl"]);
    assert_eq!(out.status.code(), Some(2));
}

/// A symbolic argument without a value is sent as its own name
/// (docs/aac-protocol.md §11): a run against a vehicle says so at start,
/// naming each one and the `--set` that gives it a value.
#[test]
fn a_run_against_a_vehicle_names_its_symbols_without_a_value() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let run = |extra: &[&str]| {
        let mut args = vec!["run", "--aac", &addr, "-q", "--connect-timeout", "0.2", "examples/survey.mcl"];
        args.extend_from_slice(extra);
        let out = mcl(&args);
        assert_eq!(out.status.code(), Some(2), "nobody listens");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = run(&[]);
    assert!(
        err.contains("warning: symbolic arguments without a value, sent to the vehicle as their own names: altitude, timeout, velocity (give each a value with --set altitude=VALUE)"),
        "{err}"
    );
    let err = run(&["--set", "altitude=2.5", "--set", "timeout=60"]);
    assert!(err.contains("as its own name: velocity (give it a value with --set velocity=VALUE)"), "{err}");
    let err = run(&["--set", "altitude=2.5", "--set", "timeout=60", "--set", "velocity=0.5"]);
    assert!(!err.contains("symbolic"), "{err}");
}
