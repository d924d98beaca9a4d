//! Real time against the in-process mock (on a paused tokio clock, so that
//! answers due at the same instant are really simultaneous) plays every
//! bundled single-mission example exactly as virtual time does: the same
//! actions and events, credited to the same calls, the same outcome, and no
//! event credited to a call it was not meant for.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use mcl_compiler::compile::compile_file;
use mcl_compiler::{Database, Db};
use mcl_net::Net;
use mcl_runtime::clock::Clock;
use mcl_runtime::driver::{self, Collect, End, Limits, Session};
use mcl_runtime::link;
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::player::{Outcome, Player, PlayerOptions};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::trace::{Record, RecordKind, SourceMap, Tracer};

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

/// The missions of an example file.
fn missions(file: &Path) -> Vec<(String, Arc<Net>)> {
    let db = Database::new();
    let f = db.file(file);
    compile_file(&db, f)
        .unwrap_or_else(|e| panic!("{}: {e:?}", file.display()))
        .into_iter()
        .map(|m| (m.name, Arc::new(m.net)))
        .collect()
}

/// What must be equal between two runs: every action and event with the
/// call it is credited to, and the outcome.
fn attribution(records: &[Record]) -> Vec<String> {
    records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Action { action, params, call, .. } => Some(format!(
                "action {action} {} {params:?} call {:?} {:?}",
                call.task.as_deref().unwrap_or("?"),
                call.call_site,
                call.label
            )),
            RecordKind::Event { event, call, .. } => {
                Some(format!("event {event} {} call {:?}", call.task.as_deref().unwrap_or("?"), call.call_site))
            }
            RecordKind::Outcome { result, .. } => Some(format!("outcome {result}")),
            _ => None,
        })
        .collect()
}

fn virtual_run(net: &Arc<Net>, scenario: &Scenario, seed: u64) -> (End, Vec<Record>) {
    let mut sink = Collect::default();
    let tracer = Tracer::new(net, None, &mut SourceMap::default());
    let mut s = Session::new(Player::new(net.clone(), PlayerOptions::seeded(seed)), tracer, &mut sink);
    let mut mock = MockVehicle::from_net(net, scenario.clone(), seed);
    mock.initial();
    let end = driver::run_virtual(&mut s, &mut mock, Limits::virtual_time(None)).unwrap();
    drop(s);
    (end, sink.0)
}

fn real_run(net: &Arc<Net>, scenario: &Scenario, seed: u64) -> (End, Vec<Record>) {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().start_paused(true).build().unwrap();
    rt.block_on(async {
        let clock = Clock::new(1.0, 0.0);
        let (mut link, end) = link::pair();
        let mock = MockVehicle::from_net(net, scenario.clone(), seed);
        let server = tokio::spawn(driver::serve_mock(mock, end, clock, |_| {}));
        let mut sink = Collect::default();
        let tracer = Tracer::new(net, None, &mut SourceMap::default());
        let mut s = Session::new(Player::new(net.clone(), PlayerOptions::seeded(seed)), tracer, &mut sink);
        let e = driver::run_real_time(&mut s, &mut link, clock, Limits::real_time(Some(100_000.0)), Vec::new())
            .await
            .unwrap();
        drop(s);
        drop(link);
        server.await.unwrap();
        (e, sink.0)
    })
}

fn compare(file: &str, scenario: Option<&str>, seed: u64) {
    let path = examples().join(file);
    let scenario = match scenario {
        Some(s) => Scenario::load(&examples().join(s)).unwrap(),
        None => Scenario::default(),
    };
    for (name, net) in missions(&path) {
        let (ev, v) = virtual_run(&net, &scenario, seed);
        let (er, r) = real_run(&net, &scenario, seed);
        let ctx = format!("{file} mission `{name}` seed {seed}");
        assert_eq!(ev, End::Outcome(Outcome::Ok), "{ctx}");
        assert_eq!(er, ev, "{ctx}");
        assert_eq!(attribution(&r), attribution(&v), "{ctx}");
        let unexpected: Vec<&Record> = r
            .iter()
            .filter(|r| matches!(r.kind, RecordKind::UnexpectedEvent { .. } | RecordKind::StaleEvent { .. }))
            .collect();
        assert!(unexpected.is_empty(), "{ctx}: {unexpected:?}");
    }
}

/// The audit's case: in `parallel { Depth( 15, "keep" ) } or { Goto( [24, 12] ) }`
/// both answers are due at t = 10; Goto's wins, the keep Depth is disabled,
/// and its answer must never be credited to the next call of Depth (which
/// would end the mission at t = 10 instead of 15).
#[test]
fn extract_5_4_simultaneous_answers() {
    for seed in 0..8 {
        compare("extract-5-4.mcl", None, seed);
    }
    let net = &missions(&examples().join("extract-5-4.mcl"))[0].1;
    let (_, r) = real_run(net, &Scenario::default(), 3);
    let last = r.iter().rfind(|r| matches!(r.kind, RecordKind::Event { .. })).unwrap();
    let RecordKind::Event { event, call, .. } = &last.kind else { unreachable!() };
    assert_eq!((event.as_str(), call.call_site, last.t), ("eventDepthOk", Some(4), 15.0));
}

#[test]
fn every_single_mission_example() {
    for (file, scenario) in [
        ("survey.mcl", None),
        ("survey.mcl", Some("scenarios/survey-nominal.toml")),
        ("survey.mcl", Some("scenarios/survey-alarm.toml")),
        ("dam-inspection.mcl", None),
        ("dam-inspection.mcl", Some("scenarios/dam-wall-failure.toml")),
        ("cable-tracking.mcl", None),
        ("pnml-pattern.mcl", None),
    ] {
        for seed in 0..3 {
            compare(file, scenario, seed);
        }
    }
}

/// Each mission of the multi-mission files alone (its own net, without the
/// other vehicles: the coordination is tested through the binary).
#[test]
fn every_mission_of_the_operators_file() {
    compare("mission-operators.mcl", None, 1);
}
