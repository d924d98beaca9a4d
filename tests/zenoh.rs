//! MCL over a real Zenoh (issue 16, items 1-3; docs/zenoh.md): the AUV and
//! ASC of examples/auv-asc.mcl as two `mcl run --vehicle` processes over
//! `--transport zenoh`, also with one of them killed and resumed, and
//! through a Zenoh router (`mcl zenoh-router`) restarted mid-run; the
//! survey against the Python reference vehicle over Zenoh
//! (clients/python/mcl_aac_zenoh.py), and a player killed (SIGKILL) and
//! resumed from its journal against it. Explicit loopback endpoints, no
//! multicast scouting. Every process is bounded in time.

mod aac_common;
#[allow(dead_code)]
#[path = "../mcl-zenoh/examples/aac_vehicle.rs"]
mod aac_vehicle;
mod auv_asc_common;
use auv_asc_common::{check, AUV_ASC, SCENARIO};
use mcl_runtime::trace::{Record, RecordKind};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-zenoh-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn trace(path: &Path) -> Vec<Record> {
    mcl_runtime::trace::read_trace(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn lines(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad line {l}: {e}")))
        .collect()
}

/// A free loopback port (bound then released).
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn endpoint(port: u16) -> String {
    format!("tcp/127.0.0.1:{port}")
}

/// Waits for `child`, killing it after `limit` (then panics).
fn wait(mut child: Child, limit: Duration, what: &str) -> (ExitStatus, String) {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = e.read_to_string(&mut err);
            }
            return (status, err);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = e.read_to_string(&mut err);
            }
            panic!("{what} still runs after {limit:?}: {err}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

const LIMIT: Duration = Duration::from_secs(90);

/// One test of this file at a time: each runs vehicles in real time at
/// `--speed 50`, where a scheduler stall of a loaded machine is seconds of
/// mission time (and the mock's answers then come at other moments than
/// in the dry run they are compared with).
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// How one vehicle process meets the others.
#[derive(Clone)]
struct Net {
    listen: Vec<String>,
    connect: Vec<String>,
    config: Option<PathBuf>,
    /// `--region NAME`.
    region: Option<String>,
}

impl Net {
    fn args(&self) -> Vec<String> {
        let mut a = Vec::new();
        for l in &self.listen {
            a.extend(["--zenoh-listen".to_string(), l.clone()]);
        }
        for c in &self.connect {
            a.extend(["--zenoh-connect".to_string(), c.clone()]);
        }
        if let Some(c) = &self.config {
            a.extend(["--zenoh-config".to_string(), c.display().to_string()]);
        }
        if let Some(r) = &self.region {
            a.extend(["--region".to_string(), r.clone()]);
        }
        a
    }
}

/// One vehicle of examples/auv-asc.mcl in its own process over Zenoh,
/// journaled, aborted after `crash_after` journal syncs (as `kill -9`
/// would) and then resumed until it ends. Returns its exit status, the
/// trace of its last run (the replay rebuilds the whole run) and its
/// journal.
fn vehicle(me: &str, net: &Net, crash_after: Option<u64>, tag: &str) -> (i32, Vec<Record>, Vec<Value>) {
    let journal = tmp(&format!("{tag}-{me}.journal"));
    let mut crash = crash_after;
    for life in 0.. {
        let trace_path = tmp(&format!("{tag}-{me}-{life}.jsonl"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mcl"));
        cmd.args(["run", "--mock", AUV_ASC, "--scenario", SCENARIO, "--vehicle", me, "--transport", "zenoh"])
            .args(net.args())
            .args(["--zenoh-fleet", tag, "--coord-token", "fleet secret"])
            .args(["--speed", "50", "--time-limit", "3000", "-q", "--trace", trace_path.to_str().unwrap()])
            .args([if life == 0 { "--journal" } else { "--resume" }, journal.to_str().unwrap()]);
        if let Some(n) = crash.take() {
            cmd.args(["--crash-after", &n.to_string()]);
        }
        let child = cmd.current_dir(root()).stderr(Stdio::piped()).stdout(Stdio::null()).spawn().expect("run mcl");
        let (status, err) = wait(child, LIMIT, me);
        match status.code() {
            Some(code) => {
                assert!(life <= 1, "{me}: more lives than crashes");
                assert!(err.contains("Zenoh transport"), "{me}: {err}");
                return (code, trace(&trace_path), lines(&journal));
            }
            None => assert!(crash_after.is_some() && life == 0, "{me} died unexpectedly: {err}"),
        }
    }
    unreachable!()
}

/// Both vehicles at once, each listening on its own port and connecting
/// to the other's (whichever restarts finds the other).
fn auv_asc(auv_crash: Option<u64>, asc_crash: Option<u64>, tag: &str) -> [(i32, Vec<Record>, Vec<Value>); 2] {
    let (pa, pc) = (free_port(), free_port());
    let auv = Net { listen: vec![endpoint(pa)], connect: vec![endpoint(pc)], config: None, region: None };
    let asc = Net { listen: vec![endpoint(pc)], connect: vec![endpoint(pa)], config: None, region: None };
    let tag2 = tag.to_string();
    let c = std::thread::spawn(move || vehicle("asc", &asc, asc_crash, &tag2));
    let a = vehicle("auv", &auv, auv_crash, tag);
    [a, c.join().unwrap()]
}

#[test]
fn auv_and_asc_over_zenoh_keep_every_constraint() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    let runs = auv_asc(None, None, "zplain");
    check(&runs, &reference, "zplain");
}

#[test]
fn a_vehicle_killed_and_resumed_over_zenoh_keeps_every_constraint() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    // The ASC right after the AUV arrived at the send_data sync, then the
    // AUV while it waits for the ASC at the sync.
    for (auv_crash, asc_crash, tag) in [(None, Some(6), "zasc"), (Some(7), None, "zauv")] {
        let runs = auv_asc(auv_crash, asc_crash, tag);
        check(&runs, &reference, tag);
        for (k, crash) in [auv_crash, asc_crash].iter().enumerate() {
            if crash.is_some() {
                assert!(
                    runs[k].1.iter().any(|r| matches!(&r.kind,
                        RecordKind::Link { message } if message.starts_with("resumed from the journal"))),
                    "{tag}"
                );
            }
        }
    }
}

/// `mcl zenoh-router --listen ENDPOINT`, once it says it listens.
fn router(port: u16) -> Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["zenoh-router", "--listen", &endpoint(port)])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run mcl zenoh-router");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert!(first.starts_with("zenoh router listening on"), "{first}");
    child
}

#[test]
fn auv_and_asc_through_a_router() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    // Peers that only know the router: it tells each where the other
    // listens (loopback, a port of the system's choice).
    let pr = free_port();
    let mut r = router(pr);
    let net = Net { listen: vec!["tcp/127.0.0.1:0".into()], connect: vec![endpoint(pr)], config: None, region: None };
    let n2 = net.clone();
    let c = std::thread::spawn(move || vehicle("asc", &n2, None, "zrpeer"));
    let a = vehicle("auv", &net, None, "zrpeer");
    let runs = [a, c.join().unwrap()];
    let _ = r.kill();
    let _ = r.wait();
    check(&runs, &reference, "zrpeer");
}

/// `mcl zenoh-router --listen ENDPOINT --zenoh-config FILE`, once it says it listens.
fn router_with(port: u16, config: &Path) -> Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["zenoh-router", "--listen", &endpoint(port), "--config"])
        .arg(config)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run mcl zenoh-router");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert!(first.starts_with("zenoh router listening on"), "{first}");
    child
}

/// Peers that listen nowhere and only connect to the router: the others
/// cannot reach them, so Zenoh's peer-to-peer routing gives them nothing
/// of each other (docs/zenoh.md *Through a router*). Each vehicle names
/// its region (`region_name`), and the router is the gateway of one south
/// region per vehicle: it routes between them.
#[test]
fn peers_that_listen_nowhere_through_a_router_with_a_region_each() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    let pr = free_port();
    let rc = tmp("region-router.json5");
    std::fs::write(
        &rc,
        r#"{ scouting: { multicast: { enabled: false } }, gateway: { south: [
             { filters: [ { region_names: ["auv"] } ] },
             { filters: [ { region_names: ["asc"] } ] },
             { filters: [ { modes: ["peer", "client"] } ] } ] } }"#,
    )
    .unwrap();
    let mut r = router_with(pr, &rc);
    let nets = ["auv", "asc"].map(|me| {
        let config = tmp(&format!("region-{me}.json5"));
        std::fs::write(
            &config,
            format!(
                r#"{{ mode: "peer", region_name: "{me}", listen: {{ endpoints: [] }},
                     scouting: {{ multicast: {{ enabled: false }} }} }}"#
            ),
        )
        .unwrap();
        Net { listen: vec![], connect: vec![endpoint(pr)], config: Some(config), region: None }
    });
    let [na, nc] = nets;
    let c = std::thread::spawn(move || vehicle("asc", &nc, None, "zrregion"));
    let a = vehicle("auv", &na, None, "zrregion");
    let runs = [a, c.join().unwrap()];
    let _ = r.kill();
    let _ = r.wait();
    check(&runs, &reference, "zrregion");
}

/// The same through the options alone: `mcl zenoh-router --region auv
/// --region asc` is the gateway of both regions, and each vehicle, run with
/// `--region NAME` and no `--zenoh-listen`, listens nowhere and names its
/// region: no configuration file written (the router's `gateway.south`
/// and each vehicle's `region_name` come from the options).
#[test]
fn vehicles_in_their_own_regions_through_a_router_given_regions() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    let pr = free_port();
    let mut r = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["zenoh-router", "--listen", &endpoint(pr), "--region", "auv", "--region", "asc"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run mcl zenoh-router");
    let mut first = String::new();
    BufReader::new(r.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert!(first.starts_with("zenoh router listening on"), "{first}");
    let [na, nc] = ["auv", "asc"].map(|me| Net {
        listen: vec![],
        connect: vec![endpoint(pr)],
        config: None,
        region: Some(me.to_string()),
    });
    let c = std::thread::spawn(move || vehicle("asc", &nc, None, "zrregionopt"));
    let a = vehicle("auv", &na, None, "zrregionopt");
    let runs = [a, c.join().unwrap()];
    let _ = r.kill();
    let _ = r.wait();
    check(&runs, &reference, "zrregionopt");
}

#[test]
fn bad_regions_are_usage_errors() {
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["zenoh-router", "--listen", "tcp/127.0.0.1:0", "--region", "auv", "--region", "auv"])
        .output()
        .expect("run mcl zenoh-router");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("region `auv` given twice"));
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["zenoh-router", "--listen", "tcp/127.0.0.1:0", "--region", "a/b"])
        .output()
        .expect("run mcl zenoh-router");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("region `a/b`"));
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_mcl"))
            .args(["run", "--mock", AUV_ASC, "--vehicle", "auv"])
            .args(args)
            .current_dir(root())
            .output()
            .expect("run mcl")
    };
    let out = run(&["--transport", "zenoh", "--zenoh-connect", "tcp/127.0.0.1:9", "--region", "no space"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("region `no space`"));
    let out = run(&["--region", "auv"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--region go with --zenoh or --transport zenoh"));
}

#[test]
fn auv_and_asc_through_a_router_restarted_mid_run() {
    let _one = serial();
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    let pr = free_port();
    // Clients: everything goes through the router.
    let config = tmp("client.json5");
    std::fs::write(&config, r#"{ mode: "client", scouting: { multicast: { enabled: false } } }"#).unwrap();
    let net = Net { listen: vec![], connect: vec![endpoint(pr)], config: Some(config), region: None };
    let mut first = router(pr);
    let n2 = net.clone();
    let c = std::thread::spawn(move || vehicle("asc", &n2, None, "zrclient"));
    let a = std::thread::spawn(move || vehicle("auv", &net, None, "zrclient"));
    // The router goes down for a while mid-run (the mission lasts ~8 s of
    // wall-clock time at --speed 50), then comes back on the same port.
    std::thread::sleep(Duration::from_millis(3000));
    let _ = first.kill();
    let _ = first.wait();
    std::thread::sleep(Duration::from_millis(700));
    let mut second = router(pr);
    let runs = [a.join().unwrap(), c.join().unwrap()];
    let _ = second.kill();
    let _ = second.wait();
    check(&runs, &reference, "zrclient");
}

/// `python3` with the Zenoh binding, or None: the test is then skipped,
/// unless `MCL_REQUIRE_ZENOH_PY=1` (CI) makes its absence a failure.
fn python_zenoh() -> bool {
    let found = mcl_testutil::runs("python3", &["-c", "import zenoh"]);
    mcl_testutil::have_tool("zenoh_py", found, "pip install eclipse-zenoh")
}

#[test]
fn the_survey_against_the_python_reference_vehicle_over_zenoh() {
    let _one = serial();
    if !python_zenoh() {
        return;
    }
    let port = free_port();
    let map = tmp("survey-map.json");
    std::fs::write(&map, r#"{"AlarmPrimitive": "", "TakeImagesPrimitive": ""}"#).unwrap();
    let mut aac = Command::new("python3")
        .arg(root().join("clients/python/mcl_aac_zenoh.py"))
        .args(["--vehicle", "sparus", "--listen", &endpoint(port), "--delay", "0.05"])
        .args(["--map-file", map.to_str().unwrap(), "--map", "AltitudePrimitive=eventAltitudeOk"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run python3");
    let mut first = String::new();
    BufReader::new(aac.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert!(first.starts_with("listening on"), "{first}");
    // A shore station: subscribes to the vehicle's status.
    let shore = mcl_zenoh::Node::open(&mcl_zenoh::ZenohOptions {
        connect: vec![endpoint(port)],
        listen: vec!["tcp/127.0.0.1:0".into()],
        ..Default::default()
    })
    .unwrap();
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let mut statuses = rt.block_on(shore.subscribe("mcl/sparus/status")).unwrap();
    let tp = tmp("survey.jsonl");
    let child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--zenoh", "examples/survey.mcl", "--vehicle-name", "sparus"])
        .args(["--zenoh-connect", &endpoint(port), "--zenoh-listen", "tcp/127.0.0.1:0", "--connect-timeout", "30"])
        .args(["--set", "timeout=60", "--set", "altitude=2.5", "--set", "velocity=0.5", "-q", "--trace"])
        .arg(&tp)
        .current_dir(root())
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let (status, err) = wait(child, LIMIT, "mcl run --zenoh");
    let _ = aac.kill();
    let mut aac_log = String::new();
    let _ = aac.wait();
    if let Some(mut e) = aac.stderr.take() {
        let _ = e.read_to_string(&mut aac_log);
    }
    let ctx = format!("stderr:\n{err}\nAAC:\n{aac_log}");
    assert_eq!(status.code(), Some(0), "{ctx}");
    assert!(err.contains("mission `mission`: OK"), "{ctx}");
    let tr = trace(&tp);
    let sent: Vec<u64> = tr
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Action { seq, .. } => Some(*seq),
            _ => None,
        })
        .collect();
    assert!(!sent.is_empty(), "{ctx}");
    assert!(
        !tr.iter().any(
            |r| matches!(&r.kind, RecordKind::Action { primitive, .. } if primitive == "EmergencySurfacePrimitive")
        ),
        "the alarm never fires\n{ctx}"
    );
    // The shore station saw the calls run, then the outcome.
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut seen: Vec<mcl_zenoh::Status> = Vec::new();
    while seen.last().is_none_or(|s| s.outcome.is_none()) && Instant::now() < deadline {
        match statuses.try_recv() {
            Ok(r) => seen.push(serde_json::from_slice(&r.payload).unwrap()),
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    }
    let last = seen.last().unwrap_or_else(|| panic!("no status on mcl/sparus/status\n{ctx}"));
    assert_eq!((last.mission.as_str(), last.outcome.as_deref()), ("mission", Some("ok")), "{ctx}");
    assert!(last.running.is_empty(), "{ctx}");
    assert!(seen.iter().any(|s| s.running.iter().any(|c| c.task == "Trajectory")), "{seen:?}");
    assert_eq!(last.actions as usize, sent.len(), "{ctx}");
    // Every action executed exactly once, in order.
    let executed: Vec<u64> = aac_log
        .lines()
        .filter_map(|l| l.split("executed seq=").nth(1)?.split_whitespace().next()?.parse().ok())
        .collect();
    assert_eq!(executed, sent, "{ctx}");
}

/// The player over Zenoh killed at several moments (an abort right after
/// journaling an input; SIGKILL wherever it is once the dive ended, and
/// once the altitude is reached while Goto still runs) against the running
/// Python reference vehicle (which answers meanwhile), then resumed with
/// `--resume`: the mission ends ok with the actions and events of the dry
/// run, every action executed exactly once.
#[test]
fn the_player_killed_and_resumed_over_zenoh_against_the_python_vehicle() {
    use aac_common::{crashed_run_over, odd_events, resumed_run_over, sent, unique, Kill, Proc};
    let _one = serial();
    if !python_zenoh() {
        return;
    }
    let dir = aac_common::scratch("zenoh-resume");
    let file = aac_common::resume_mission(&dir);
    let mut reference = aac_common::reference_calls(&dir, &file, "default_duration = 1\n");
    reference.sort();
    let kills = [Kill::After(1), Kill::After(3), Kill::When("eventDepthOk"), Kill::When("eventAltitudeOk")];
    for (i, kill) in kills.into_iter().enumerate() {
        let vehicle = format!("resume{i}");
        let mut py = Command::new("python3");
        py.arg(root().join("clients/python/mcl_aac_zenoh.py")).args([
            "--vehicle",
            &vehicle,
            "--listen",
            &endpoint(free_port()),
            "--delay",
            "0.3",
        ]);
        let aac = Proc::spawn(py);
        let player = ["--zenoh", "--vehicle-name", &vehicle, "--zenoh-connect", &aac.addr];
        let player = [&player[..], &["--zenoh-listen", "tcp/127.0.0.1:0", "--connect-timeout", "20"]].concat();
        let journal = dir.join(format!("j{i}.jsonl"));
        let trace = dir.join(format!("t{i}.jsonl"));
        crashed_run_over(&player, &file, &journal, &[], kill);
        // The vehicle goes on while the player is down.
        std::thread::sleep(Duration::from_millis(800));
        let (code, ctx) = resumed_run_over(&player, &file, &journal, &trace, &["-q"]);
        let ctx = format!("{kill:?}\n{ctx}\nAAC:\n{}", aac.log().join("\n"));
        assert_eq!(code, Some(0), "{ctx}");
        let mut calls = aac_common::calls(&trace);
        calls.sort();
        assert_eq!(calls, reference, "{ctx}");
        assert_eq!(odd_events(&trace), Vec::new(), "{ctx}");
        let mut executed = aac.executed();
        assert!(unique(&executed), "an action was executed twice\n{ctx}");
        executed.sort_unstable();
        let mut sent = sent(&trace);
        sent.sort_unstable();
        assert_eq!(executed, sent, "{ctx}");
        // The resumed player went on with the run of its journal: the
        // vehicle saw one run, in one session.
        assert_eq!(aac.log().iter().filter(|l| l.contains("new session")).count(), 1, "{ctx}");
    }
}

/// The survey played by `mcl run --zenoh` against the Rust example vehicle
/// (mcl-zenoh/examples/aac_vehicle.rs, on the `zenoh` crate alone), run in
/// this process: the mission ends ok, the alarm never fires, every action
/// executed exactly once and in order.
#[test]
fn the_survey_against_the_rust_example_vehicle_over_zenoh() {
    let _one = serial();
    let port = free_port();
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let map = [("AlarmPrimitive", ""), ("TakeImagesPrimitive", ""), ("AltitudePrimitive", "eventAltitudeOk")];
    let opts = aac_vehicle::VehicleOptions {
        vehicle: "rustv".into(),
        listen: vec![endpoint(port)],
        delay: Duration::from_millis(50),
        map: map.iter().map(|(p, e)| (p.to_string(), e.to_string())).collect(),
        ..Default::default()
    };
    let vehicle = rt.block_on(aac_vehicle::start(opts)).unwrap();
    let tp = tmp("survey-rust.jsonl");
    let child = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--zenoh", "examples/survey.mcl", "--vehicle-name", "rustv"])
        .args(["--zenoh-connect", &endpoint(port), "--zenoh-listen", "tcp/127.0.0.1:0", "--connect-timeout", "30"])
        .args(["--set", "timeout=60", "--set", "altitude=2.5", "--set", "velocity=0.5", "-q", "--trace"])
        .arg(&tp)
        .current_dir(root())
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let (status, err) = wait(child, LIMIT, "mcl run --zenoh");
    assert_eq!(status.code(), Some(0), "{err}");
    assert!(err.contains("mission `mission`: OK"), "{err}");
    let tr = trace(&tp);
    let sent: Vec<u64> = tr
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Action { seq, .. } => Some(*seq),
            _ => None,
        })
        .collect();
    assert!(sent.len() > 4, "{err}");
    assert!(
        !tr.iter().any(
            |r| matches!(&r.kind, RecordKind::Action { primitive, .. } if primitive == "EmergencySurfacePrimitive")
        ),
        "the alarm never fires\n{err}"
    );
    assert_eq!(*vehicle.executed.lock().unwrap(), sent, "{err}");
    drop(vehicle);
    rt.shutdown_timeout(Duration::from_secs(2));
}
