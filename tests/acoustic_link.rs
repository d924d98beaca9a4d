//! Coordination over a lossy, slow acoustic link (`--link`,
//! `mcl_runtime::acoustic`, docs/acoustic.md): random coordinated pairs
//! (the generator of `tests/differential.rs`: two random missions with
//! labelled calls and a random mutex, order or sync) run in virtual time
//! over a link that loses up to half of its frames and delays each by
//! seconds. Every run ends (each mission reaches its outcome) and no
//! constraint is ever violated: replaying the firings of both vehicles in
//! the order of the trace on the centralized supervisors of the
//! constraints (seed 6.1: `μ_c = μ_c0 + D_c·v ≥ 0`), no supervisor place
//! ever goes negative; and no run sends more messages of a kind, or more
//! messages from a mission, than `mcl compile --link-report` bounds. The
//! cases come from a fixed proptest seed (CI runs the same ones).
//!
//! Through the binary: `mcl compile --link-report` on the seed's AUV/ASC
//! mission (every message fits a 32-byte frame; E0410 at one byte), `mcl
//! run --link` (every message handed over once, in order, over a lossy
//! link; the same seed gives the same trace), frames lost beyond `range` in
//! a simulated world, and the usage errors of `--link`.

use mcl_compiler::{check_file, Database};
use mcl_coord::link_report::LinkReport;
use mcl_runtime::acoustic::{AcousticLink, LinkSpec};
use mcl_runtime::driver::{Collect, End, Limits};
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::multi::{run_virtual_with_link, SharedSink, Vehicle};
use mcl_runtime::player::{Outcome, PlayerOptions};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::trace::{Record, RecordKind, SourceMap, Tracer};
use mcl_syntax::gen::Rng;
use proptest::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A random call of the test vehicle.
fn call(r: &mut Rng) -> String {
    match r.below(4) {
        0 => format!("A( {} )", r.below(3)),
        1 => "B()".into(),
        2 => format!("Timed( {} )", 1 + r.below(4)),
        _ => "Void()".into(),
    }
}

/// A random statement whose nominal runs reach the end (no `not`, no
/// `while`: the structures `TAME` of tests/differential.rs).
fn stmt(r: &mut Rng, depth: usize) -> String {
    if depth == 0 || r.chance(35) {
        return call(r);
    }
    let b = |r: &mut Rng| (0..1 + r.below(2)).map(|_| stmt(r, depth - 1)).collect::<Vec<_>>().join(" ; ");
    match r.below(6) {
        0 => format!("if ( {} ) {{ {} }}", b(r), b(r)),
        1 => format!("if ( {} ) {{ {} }} else {{ {} }}", b(r), b(r), b(r)),
        2 => format!("try {{ {} }} catch {{ {} }}", b(r), b(r)),
        3 => format!("parallel {{ {} }} and {{ {} }}", b(r), b(r)),
        4 => format!("parallel {{ {} }} or {{ {} }}", b(r), b(r)),
        _ => format!("monitor {{ {} }} condition ( {} ) do {{ {} }}", b(r), b(r), b(r)),
    }
}

/// A mission that starts with `s`, then has `x` and `y` among random statements.
fn labelled_mission(r: &mut Rng) -> String {
    let mut parts = vec!["A( 1 ) : x".to_string(), "B() : y".to_string()];
    if r.chance(50) {
        parts.swap(0, 1);
    }
    for _ in 0..1 + r.below(2) {
        let at = r.below(parts.len() + 1);
        parts.insert(at, stmt(r, 2));
    }
    format!("Void() : s ; {}", parts.join(" ; "))
}

/// One or two random constraints (orders and syncs from `s`, which every run reaches).
fn constraints(r: &mut Rng) -> String {
    let one = |r: &mut Rng| {
        let (l, m) = (*r.pick(&["x", "y"]), *r.pick(&["x", "y"]));
        match r.below(3) {
            0 => format!("mutex {{ a:{l}, b:{m} }} = 1"),
            1 => format!("order {{ a:s, b:{} }}", r.pick(&["s", "x", "y"])),
            _ => "sync { a:s, b:s }".to_string(),
        }
    };
    let mut cs = vec![one(r)];
    if r.chance(40) {
        cs.push(one(r));
    }
    cs.dedup();
    cs.join("\n    ")
}

/// A scenario in which every task ends (ok or fail, random delays).
fn scenario(r: &mut Rng) -> String {
    let mut s = format!("seed = {}\ndefault_duration = {}\n", r.below(1000), r.below(4));
    for task in ["A", "B", "Timed", "W"] {
        s.push_str(&format!("[tasks.{task}]\n"));
        match r.below(3) {
            0 => s.push_str("outcome = \"ok\"\n"),
            1 => s.push_str("outcome = \"fail\"\n"),
            _ => s.push_str(&format!("probabilities = {{ ok = {}, fail = {} }}\n", 1 + r.below(3), 1 + r.below(3))),
        }
        let lo = r.below(4);
        s.push_str(&format!("delay = [{lo}, {}]\n", lo + r.below(6)));
    }
    s
}

/// The supervisors of the constraints (not those of deadlock avoidance):
/// per centralized transition id (`mission/id`), its effect on each.
struct Supervisors {
    ids: Vec<String>,
    initial: Vec<i64>,
    effect: HashMap<String, Vec<(usize, i64)>>,
}

/// The vehicle nets of a pair, its constraints' supervisors and its link
/// report, or why there are none (the analysis finds a deadlock or is
/// inconclusive).
fn coordinate(text: &str) -> Result<(Vec<mcl_coord::VehicleNet>, Supervisors, LinkReport), String> {
    let mut db = Database::new();
    let dir = Path::new("/virtual/acoustic");
    db.set_text(&dir.join("vehicle.mcl"), mcl_syntax::gen::TEST_VEHICLE);
    let file = db.set_text(&dir.join("pair.mcl"), text);
    let diags = check_file(&db, file);
    assert!(!mcl_compiler::has_errors(diags), "generated program has errors: {diags:?}\n{text}");
    let (missions, cs) = mcl_coord::source::load(&db, file).map_err(|e| e.to_string())?;
    let report = mcl_coord::analyze(&missions, &cs).map_err(|e| e.to_string())?;
    if !report.deadlock_free {
        return Err(format!("{:?}", report.verdict));
    }
    let mut sups = Supervisors { ids: Vec::new(), initial: Vec::new(), effect: HashMap::new() };
    for s in &report.supervisors {
        if !["coord.mutex", "coord.order", "coord.sync"].iter().any(|p| s.id.starts_with(p)) {
            continue;
        }
        let k = sups.ids.len();
        sups.ids.push(s.id.clone());
        sups.initial.push(s.initial);
        let arcs = s.produced_by.iter().map(|&(t, w)| (t, i64::from(w)));
        for (t, w) in arcs.chain(s.consumed_by.iter().map(|&(t, w)| (t, -i64::from(w)))) {
            let id = report.net.transitions()[t.index()].id.to_string();
            sups.effect.entry(id).or_default().push((k, w));
        }
    }
    let nets = mcl_coord::decentralize(&missions, &report.supervisors).map_err(|e| e.to_string())?;
    let links = mcl_coord::link_report::link_report(&missions, &cs, &nets);
    Ok((nets, sups, links))
}

/// The first message kind (or mission) of which a run sent more than the
/// link report's bound (`coord_send` records; an unbounded count has none).
fn over_bound(report: &LinkReport, records: &[Record]) -> Option<String> {
    let mut sent: HashMap<(&str, &str, &str), u64> = HashMap::new();
    let mut by_mission: HashMap<&str, u64> = HashMap::new();
    for r in records {
        if let (RecordKind::CoordSend { transition, to, .. }, Some(m)) = (&r.kind, &r.mission) {
            *sent.entry((m, transition, to)).or_default() += 1;
            *by_mission.entry(m).or_default() += 1;
        }
    }
    for ((from, t, to), n) in &sent {
        let Some(m) =
            report.messages.iter().find(|m| (m.from.as_str(), m.transition.as_str(), m.to.as_str()) == (from, t, to))
        else {
            return Some(format!("{from} -> {to}: {t} is no message of the report"));
        };
        if m.count.max().is_some_and(|max| *n > max) {
            return Some(format!("{from} -> {to}: {t} sent {n} times, at most {}", m.count.describe()));
        }
    }
    for m in &report.missions {
        let n = by_mission.get(m.mission.as_str()).copied().unwrap_or(0);
        if m.messages.max().is_some_and(|max| n > max) {
            return Some(format!("{} sent {n} messages, at most {}", m.mission, m.messages.describe()));
        }
    }
    None
}

/// Runs the pair over `link`; returns how each mission ended and the records.
fn run(nets: &[mcl_coord::VehicleNet], scenario: &str, seed: u64, link: AcousticLink) -> (Vec<End>, Vec<Record>) {
    let names: Vec<String> = nets.iter().map(|v| v.mission.clone()).collect();
    let sink = Arc::new(std::sync::Mutex::new(Collect::default()));
    let mut vehicles = Vec::new();
    for (v, transport) in nets.iter().zip(mcl_runtime::coord::in_process(&names)) {
        let net = Arc::new(v.net.clone());
        let tracer = Tracer::new(&net, Some(v.mission.clone()), &mut SourceMap::default());
        let scenario = Scenario::from_toml(scenario, "acoustic.toml").expect("a valid scenario");
        let mock = MockVehicle::from_net(&net, scenario, seed);
        let opts = PlayerOptions::seeded(seed);
        vehicles.push(Vehicle::new(&v.mission, net, opts, tracer, mock, Box::new(transport)).expect("a vehicle"));
    }
    let shared: SharedSink = sink.clone();
    let rt = tokio::runtime::Builder::new_current_thread().enable_time().build().expect("a runtime");
    let end = rt
        .block_on(run_virtual_with_link(vehicles, shared, Limits::virtual_time(Some(1e7)), Some(link), None))
        .expect("the run goes through");
    let records = std::mem::take(&mut sink.lock().expect("the sink").0);
    (end.ends.into_iter().map(|(_, e, _)| e).collect(), records)
}

/// The first firing after which a constraint's supervisor is negative.
fn violation(sups: &Supervisors, records: &[Record]) -> Option<String> {
    let mut tokens = sups.initial.clone();
    for r in records {
        let RecordKind::Fire { transition, .. } = &r.kind else { continue };
        let Some(m) = &r.mission else { continue };
        let Some(effect) = sups.effect.get(&format!("{m}/{transition}")) else { continue };
        for &(k, w) in effect {
            tokens[k] += w;
            if tokens[k] < 0 {
                return Some(format!("{m}/{transition} at t={} leaves `{}` at {}", r.t, sups.ids[k], tokens[k]));
            }
        }
    }
    None
}

struct Case {
    text: String,
    scenario: String,
    seed: u64,
    link: LinkSpec,
}

fn case(seed: u64) -> Case {
    let mut r = Rng(seed);
    let (a, b, c) = (labelled_mission(&mut r), labelled_mission(&mut r), constraints(&mut r));
    let text =
        format!("import \"vehicle.mcl\";\nmission : a {{ {a} }}\nmission : b {{ {b} }}\nconstraints {{\n    {c}\n}}\n");
    let scenario = scenario(&mut r);
    let link = LinkSpec {
        bitrate: *r.pick(&[20.0, 80.0, 500.0]),
        loss: r.below(51) as f64 / 100.0,
        delay: r.below(60) as f64 / 10.0,
        range: None,
    };
    Case { text, scenario, seed: r.next_u64(), link }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6163_6f75_7374_6963),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn lossy_slow_links_keep_every_constraint_and_every_run_ends(seed in any::<u64>()) {
        let c = case(seed);
        let (nets, sups, links) = match coordinate(&c.text) {
            Ok(x) => x,
            // The analysis refuses it: nothing to run (counted below).
            Err(_) => return Ok(()),
        };
        let what = || format!("{}\nscenario:\n{}\nlink {:?}, seed {}", c.text, c.scenario, c.link, c.seed);
        let link = AcousticLink { spec: c.link.clone(), seed: c.seed, positions: None };
        let (ends, records) = run(&nets, &c.scenario, c.seed, link);
        for e in &ends {
            prop_assert!(matches!(e, End::Outcome(Outcome::Ok | Outcome::Fail)), "a mission did not end: {e:?}\n{}", what());
        }
        prop_assert_eq!(violation(&sups, &records), None, "{}", what());
        // The link report's counts are upper bounds of every run.
        prop_assert_eq!(over_bound(&links, &records), None, "{}\n{}", what(), links.to_text());
        if c.link.loss > 0.2 {
            let sent = records.iter().filter(|r| matches!(r.kind, RecordKind::CoordSend { .. })).count();
            let lost = records.iter().filter(|r| matches!(r.kind, RecordKind::LinkLost { .. })).count();
            prop_assert!(sent == 0 || lost > 0 || sent < 4, "a lossy link lost nothing: {}", what());
        }
    }
}

#[test]
fn the_generated_pairs_are_mostly_runnable_and_coordinate() {
    // Guards the property above: most of its cases pass the analysis and
    // send messages, some over links that lose frames.
    let mut runnable = 0;
    let mut lossy_runs = 0;
    let mut caught = 0;
    let mut token_requests = 0;
    let mut excess = 0;
    for seed in 0..12u64 {
        let c = case(seed * 7919);
        let Ok((nets, sups, links)) = coordinate(&c.text) else { continue };
        runnable += 1;
        let link = AcousticLink { spec: LinkSpec { loss: 0.5, ..c.link }, seed: c.seed, positions: None };
        let (_, records) = run(&nets, &c.scenario, c.seed, link);
        // The bound check sees a run that sends every message twice (the
        // bounds are tight enough to notice).
        let twice: Vec<Record> = records
            .iter()
            .flat_map(|r| vec![r.clone(); if matches!(r.kind, RecordKind::CoordSend { .. }) { 2 } else { 1 }])
            .collect();
        if over_bound(&links, &twice).is_some() {
            excess += 1;
        }
        if records.iter().any(|r| matches!(r.kind, RecordKind::LinkLost { .. })) {
            lossy_runs += 1;
        }
        let asks =
            |r: &Record| matches!(&r.kind, RecordKind::LinkSend { what, .. } if what.starts_with("coord.request."));
        if records.iter().any(asks) {
            token_requests += 1;
        }
        // The checker sees violations: without `a`'s firings, the credits
        // of an order (or a sync) that `b` used were never given.
        if c.text.contains("order") || c.text.contains("sync") {
            let without_a: Vec<Record> = records
                .iter()
                .filter(|r| !(r.mission.as_deref() == Some("a") && matches!(r.kind, RecordKind::Fire { .. })))
                .cloned()
                .collect();
            if violation(&sups, &without_a).is_some() {
                caught += 1;
            }
        }
    }
    assert!(runnable >= 8, "only {runnable} of 12 generated pairs pass the analysis");
    assert!(lossy_runs >= 4, "only {lossy_runs} runs lost frames");
    assert!(caught >= 2, "the checker caught only {caught} forged violations");
    assert!(token_requests >= 1, "no run asked a mutex holder for a token over the link");
    assert!(excess >= 4, "the bound check caught only {excess} runs that sent every message twice");
}

// ---------------------------------------------------------------------------
// Pairs that need a siphon supervisor (seed Figure 6.9b)
// ---------------------------------------------------------------------------

/// A pair of the shape of the seed's Figure 6.9b (`mcl-coord/tests/
/// deadlock.rs`): two compact missions `P1 → … → P5`, `P6 → … → P10`
/// with the mutexes `M([P2 → T2 → P3 → T3 → P4], P8)` and
/// `M(P3, [P7 → T6 → P8 → T7 → P9])`, which deadlock until deadlock
/// avoidance adds a siphon supervisor that links both vehicles. Random
/// mission and place names, order of the missions (the first holds the
/// supervisors), outcomes (a mission's last place is `mission.ok` or
/// `mission.fail`), step durations (timed transitions: the player's own
/// timers, no vehicle needed) and start times.
struct SiphonCase {
    missions: Vec<mcl_coord::Mission>,
    constraints: Vec<mcl_coord::Constraint>,
    starts: Vec<f64>,
    link: LinkSpec,
    seed: u64,
}

fn siphon_case(seed: u64) -> SiphonCase {
    use mcl_coord::compact::{place, pw_transform, sequence};
    use mcl_coord::{Activity, CallRef, Constraint, Mission};
    let mut r = Rng(seed);
    let pool = ["auv", "asc", "glider", "rov", "sparus", "girona"];
    let a = *r.pick(&pool);
    let b = loop {
        let b = *r.pick(&pool);
        if b != a {
            break b;
        }
    };
    // One mission: five places (the last is its outcome), steps of random
    // durations, the second and third places PW-transformed.
    let mission = |r: &mut Rng, name: &str| {
        let stem = *r.pick(&["survey", "dock", "scan", "dive", "track"]);
        let last = if r.chance(80) { "mission.ok" } else { "mission.fail" };
        let ps: Vec<String> = (1..5).map(|k| format!("{stem}{k}")).chain([last.to_string()]).collect();
        let ts: Vec<String> = (1..5).map(|k| format!("{stem}_step{k}")).collect();
        let net = sequence(
            name,
            &ps.iter().map(String::as_str).collect::<Vec<_>>(),
            &ts.iter().map(String::as_str).collect::<Vec<_>>(),
        );
        let mut b = net.to_builder();
        for t in net.transition_ids() {
            let d = 0.5 + r.below(40) as f64 / 10.0;
            if let Some(tr) = b.transition_mut(t) {
                tr.kind = mcl_net::TransitionKind::Timed(mcl_net::Delay::Fixed(d));
            }
        }
        let mut net = b.build().expect("a sequence");
        for k in [1, 2] {
            let p = place(&net, &ps[k]);
            net = pw_transform(&net, p, &format!("{}_wait", ps[k]), &format!("{}_enter", ps[k])).expect("a transform");
        }
        let region = |net: &mcl_net::Net, label: &str, ids: &[String]| {
            let places: Vec<_> = ids.iter().map(|p| place(net, p)).collect();
            Activity::region(net, label, &places)
        };
        let init = vec![place(&net, &ps[0])];
        let fin = vec![place(&net, &ps[4])];
        let long = [ps[1].clone(), format!("{}_wait", ps[2]), ps[2].clone(), ps[3].clone()];
        let short = [ps[2].clone()];
        (Mission::new(name, net.clone(), init, fin), region(&net, "long", &long), region(&net, "short", &short))
    };
    // Both missions have Figure 6.9b's shape: a long region (P2 to P4, wait
    // place of P3 included) around a short call (P3); the long region of
    // each excludes the short call of the other.
    let (m1, long1, short1) = mission(&mut r, a);
    let (m2, long2, short2) = mission(&mut r, b);
    let m1 = m1.with_activity(long1).with_activity(short1);
    let m2 = m2.with_activity(long2).with_activity(short2);
    let mut constraints = vec![
        Constraint::mutex([CallRef::new(a, "long"), CallRef::new(b, "short")], 1),
        Constraint::mutex([CallRef::new(a, "short"), CallRef::new(b, "long")], 1),
    ];
    let mut missions = vec![m1, m2];
    if r.chance(50) {
        missions.reverse();
        constraints.reverse();
    }
    let starts = vec![r.below(30) as f64 / 10.0, r.below(30) as f64 / 10.0];
    let link = LinkSpec {
        bitrate: *r.pick(&[20.0, 80.0, 500.0]),
        loss: r.below(51) as f64 / 100.0,
        delay: 0.5 + r.below(55) as f64 / 10.0,
        range: None,
    };
    SiphonCase { missions, constraints, starts, link, seed: r.next_u64() }
}

/// Every supervisor of `report` (the constraints' and deadlock
/// avoidance's): per centralized transition id, its effect on each.
fn all_supervisors(report: &mcl_coord::Report) -> Supervisors {
    let mut sups = Supervisors { ids: Vec::new(), initial: Vec::new(), effect: HashMap::new() };
    for (k, s) in report.supervisors.iter().enumerate() {
        sups.ids.push(s.id.clone());
        sups.initial.push(s.initial);
        let arcs = s.produced_by.iter().map(|&(t, w)| (t, i64::from(w)));
        for (t, w) in arcs.chain(s.consumed_by.iter().map(|&(t, w)| (t, -i64::from(w)))) {
            let id = report.net.transitions()[t.index()].id.to_string();
            sups.effect.entry(id).or_default().push((k, w));
        }
    }
    sups
}

/// The analysis of a Figure 6.9b pair: one siphon supervisor added, which
/// links both vehicles.
fn siphon_report(c: &SiphonCase) -> mcl_coord::Report {
    let report = mcl_coord::analyze(&c.missions, &c.constraints).expect("the analysis runs");
    assert!(report.deadlock_free, "{:#?}", report.problems);
    assert_eq!(report.added, 1, "deadlock avoidance adds one supervisor");
    let s = report.supervisors.last().expect("a siphon supervisor");
    assert!(s.id.starts_with("coord.siphon"), "{}", s.id);
    let plant = mcl_coord::centralize(&c.missions).expect("a plant");
    assert!(mcl_coord::decentral::is_token_supervisor(&plant, s), "the siphon supervisor has a single holder");
    report
}

/// The vehicle nets of the pair as they were before siphon supervisors
/// had a holder: the siphon supervisor kept as copies (the mutexes still
/// with a holder). For the guard below.
fn copies_of_siphon(c: &SiphonCase, report: &mcl_coord::Report) -> Vec<mcl_coord::VehicleNet> {
    use mcl_coord::decentral::{minimize_communication, vehicle_nets_with_tokens, Costs};
    let plant = mcl_coord::centralize(&c.missions).expect("a plant");
    let (tokens, copies): (Vec<_>, Vec<_>) =
        report.supervisors.iter().cloned().partition(|s| matches!(s.origin, mcl_coord::Origin::Mutex { .. }));
    let comm = minimize_communication(&plant, &copies, &Costs::default()).expect("a policy");
    vehicle_nets_with_tokens(&c.missions, &plant, &copies, &comm, &tokens).expect("vehicle nets")
}

/// Runs the pair's vehicle nets `nets` over the case's link.
fn run_siphon(c: &SiphonCase, nets: &[mcl_coord::VehicleNet], link: LinkSpec) -> (Vec<End>, Vec<Record>) {
    let names: Vec<String> = nets.iter().map(|v| v.mission.clone()).collect();
    let sink = Arc::new(std::sync::Mutex::new(Collect::default()));
    let mut vehicles = Vec::new();
    for ((v, transport), start) in nets.iter().zip(mcl_runtime::coord::in_process(&names)).zip(&c.starts) {
        let net = Arc::new(v.net.clone());
        let tracer = Tracer::new(&net, Some(v.mission.clone()), &mut SourceMap::default());
        let mock = MockVehicle::from_net(&net, Scenario::from_toml("", "none.toml").expect("a scenario"), c.seed);
        let opts = PlayerOptions::seeded(c.seed);
        let vehicle = Vehicle::new(&v.mission, net, opts, tracer, mock, Box::new(transport)).expect("a vehicle");
        vehicles.push(vehicle.starting_at(*start));
    }
    let shared: SharedSink = sink.clone();
    let link = AcousticLink { spec: link, seed: c.seed, positions: None };
    let rt = tokio::runtime::Builder::new_current_thread().enable_time().build().expect("a runtime");
    let end = rt
        .block_on(run_virtual_with_link(vehicles, shared, Limits::virtual_time(Some(1e5)), Some(link), None))
        .expect("the run goes through");
    let records = std::mem::take(&mut sink.lock().expect("the sink").0);
    (end.ends.into_iter().map(|(_, e, _)| e).collect(), records)
}

fn ended(ends: &[End]) -> bool {
    ends.iter().all(|e| matches!(e, End::Outcome(Outcome::Ok | Outcome::Fail)))
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x7369_7068_6f6e_3962),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Figure 6.9b pairs over lossy, slow links: the siphon supervisor's
    /// single holder keeps the deadlock it prevents away (every mission
    /// ends), no supervisor of the centralized net (the mutexes' and the
    /// siphon's) ever goes negative, and no message is sent more often
    /// than the link report bounds.
    #[test]
    fn siphon_supervisors_hold_over_lossy_slow_links(seed in any::<u64>()) {
        let c = siphon_case(seed);
        let report = siphon_report(&c);
        let nets = mcl_coord::decentralize(&c.missions, &report.supervisors).expect("vehicle nets");
        let links = mcl_coord::link_report::link_report(&c.missions, &c.constraints, &nets);
        let what = || format!("{:?}\nstarts {:?}, link {:?}, seed {}", c.missions.iter().map(|m| &m.name).collect::<Vec<_>>(), c.starts, c.link, c.seed);
        let (ends, records) = run_siphon(&c, &nets, c.link.clone());
        prop_assert!(ended(&ends), "a mission did not end: {ends:?}\n{}", what());
        prop_assert_eq!(violation(&all_supervisors(&report), &records), None, "{}", what());
        prop_assert_eq!(over_bound(&links, &records), None, "{}\n{}", what(), links.to_text());
    }
}

#[test]
fn figure_6_9b_repaired_ends_over_the_documented_acoustic_link() {
    // The link of docs/acoustic.md, on a few pairs; the siphon
    // supervisor's messages are token requests and returns of the compact
    // encoding, counted by the link report, in a 32-byte frame.
    let spec = LinkSpec::parse("acoustic:bitrate=80,loss=0.3,delay=2").expect("a link");
    let mut asked = 0;
    for seed in 0..8u64 {
        let c = siphon_case(seed * 104_729);
        let report = siphon_report(&c);
        let nets = mcl_coord::decentralize(&c.missions, &report.supervisors).expect("vehicle nets");
        let siphon = &report.supervisors.last().expect("a siphon supervisor").id;
        let links = mcl_coord::link_report::link_report(&c.missions, &c.constraints, &nets);
        let key = siphon.strip_prefix("coord.").expect("a supervisor id");
        for kind in ["request", "return"] {
            let m = links
                .messages
                .iter()
                .find(|m| m.kind == kind && m.transition == format!("coord.{kind}.{key}"))
                .unwrap_or_else(|| panic!("no {kind} of {siphon} in the link report:\n{}", links.to_text()));
            assert!(m.count.max().is_some(), "{kind}: {:?}", m.count);
            assert!(m.compact_bytes <= 32, "{kind} takes {} bytes", m.compact_bytes);
        }
        assert!(links.messages.iter().any(|m| m.transition.starts_with(&format!("coord.lend.{key}."))));
        let (ends, records) = run_siphon(&c, &nets, spec.clone());
        assert!(ended(&ends), "seed {seed}: {ends:?}");
        assert_eq!(violation(&all_supervisors(&report), &records), None, "seed {seed}");
        assert_eq!(over_bound(&links, &records), None, "seed {seed}");
        let requests = |r: &Record| matches!(&r.kind, RecordKind::CoordSend { transition, .. } if transition == &format!("coord.request.{key}"));
        asked += usize::from(records.iter().any(requests));
    }
    assert!(asked >= 4, "only {asked} of 8 runs asked the holder for the siphon supervisor's token");
}

#[test]
fn the_siphon_property_would_catch_copies_that_cross() {
    // Guards the property above: with the siphon supervisor kept as copies
    // (before it had a holder), both vehicles take its last token while
    // their messages cross, and the checks of the property see it (a run
    // stuck, or the centralized supervisor below zero) on some pairs.
    let mut caught = 0;
    let mut runs = 0;
    for seed in 0..96u64 {
        let c = siphon_case(seed * 7_919 + 1);
        let report = siphon_report(&c);
        let nets = copies_of_siphon(&c, &report);
        let has_copies =
            nets.iter().filter(|v| v.net.place_by_id(&report.supervisors.last().unwrap().id).is_some()).count();
        assert_eq!(has_copies, 2, "both vehicles keep a copy");
        runs += 1;
        // A slow link without losses: the grant of a mutex and the firing
        // that took the siphon supervisor's last token travel in separate
        // frames, seconds apart.
        let slow = LinkSpec { bitrate: 500.0, loss: 0.0, delay: 3.0, range: None };
        let (ends, records) = run_siphon(&c, &nets, slow);
        if !ended(&ends) || violation(&all_supervisors(&report), &records).is_some() {
            caught += 1;
        }
    }
    assert!(caught >= 2, "the checks caught only {caught} of {runs} runs with copies");
}

#[test]
fn figure_6_9b_repaired_over_tcp_in_real_time() {
    // A real transport (the authenticated TCP link on loopback), vehicles
    // in real time (20 times faster than mission time): the siphon
    // supervisor's holder lends its token over it, every mission ends and
    // no supervisor of the centralized net goes negative.
    for seed in 0..3u64 {
        let c = siphon_case(seed * 31 + 5);
        let report = siphon_report(&c);
        let nets = mcl_coord::decentralize(&c.missions, &report.supervisors).expect("vehicle nets");
        let names: Vec<String> = nets.iter().map(|v| v.mission.clone()).collect();
        let sink = Arc::new(std::sync::Mutex::new(Collect::default()));
        let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().expect("a runtime");
        let end = rt.block_on(async {
            let ends = mcl_runtime::coord::tcp_mesh(&names, "127.0.0.1").await.expect("a TCP mesh");
            let mut vehicles = Vec::new();
            for (v, transport) in nets.iter().zip(ends) {
                let net = Arc::new(v.net.clone());
                let tracer = Tracer::new(&net, Some(v.mission.clone()), &mut SourceMap::default());
                let mock =
                    MockVehicle::from_net(&net, Scenario::from_toml("", "none.toml").expect("a scenario"), c.seed);
                let opts = PlayerOptions::seeded(c.seed);
                vehicles
                    .push(Vehicle::new(&v.mission, net, opts, tracer, mock, Box::new(transport)).expect("a vehicle"));
            }
            let shared: SharedSink = sink.clone();
            let clock = mcl_runtime::clock::Clock::new(20.0, 0.0);
            mcl_runtime::multi::run_real_time(vehicles, shared, clock, Limits::real_time(Some(600.0))).await
        });
        let end = end.expect("the run goes through");
        let records = std::mem::take(&mut sink.lock().expect("the sink").0);
        let ends: Vec<End> = end.ends.into_iter().map(|(_, e, _)| e).collect();
        assert!(ended(&ends), "seed {seed}: {ends:?}");
        assert_eq!(violation(&all_supervisors(&report), &records), None, "seed {seed}");
        assert!(end.mutex.requests > 0, "seed {seed}: no token was asked for");
    }
}

// ---------------------------------------------------------------------------
// Through the binary
// ---------------------------------------------------------------------------

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mcl(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_mcl")).current_dir(root()).args(args).output().expect("mcl runs")
}

fn read_trace(path: &Path) -> Vec<Record> {
    std::fs::read_to_string(path)
        .expect("a trace")
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

#[test]
fn link_report_of_the_auv_asc_mission_fits_32_bytes_and_refuses_one() {
    let out = mcl(&["compile", "--link-report", "examples/auv-asc.mcl", "--frame-bytes", "32", "--format", "json"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert!(v["frame_bytes"].as_u64().is_some_and(|b| b <= 32), "{v}");
    assert_eq!(v["diagnostics"].as_array().map(Vec::len), Some(0));
    assert_eq!(v["constraints"][0]["messages"], serde_json::json!({"bound": "bounded", "max": 1}));
    // A loop: unbounded, with a bound per iteration.
    assert_eq!(v["constraints"][1]["messages"]["bound"], "unbounded");
    assert!(v["constraints"][1]["messages"]["per_iteration"].as_u64().is_some_and(|n| n >= 1), "{v}");
    // A dry run (and a lossy one) sends no message more often than its bound.
    for link in [None, Some("acoustic:bitrate=80,loss=0.4,delay=2")] {
        let tp =
            std::env::temp_dir().join(format!("mcl-acoustic-bound-{}-{}.jsonl", std::process::id(), link.is_some()));
        let mut args = vec!["run", "--mock", "--virtual-time", "examples/auv-asc.mcl", "-q", "--trace"];
        args.extend([tp.to_str().unwrap(), "--scenario", "examples/scenarios/auv-asc.toml"]);
        args.extend(link.iter().flat_map(|l| ["--link", l]));
        let run = mcl(&args);
        assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
        let records = read_trace(&tp);
        let mut checked = 0;
        for m in v["messages"].as_array().expect("messages") {
            let n = records
                .iter()
                .filter(|r| {
                    r.mission.as_deref() == m["from"].as_str()
                        && matches!(&r.kind, RecordKind::CoordSend { transition, to, .. }
                            if Some(transition.as_str()) == m["transition"].as_str() && Some(to.as_str()) == m["to"].as_str())
                })
                .count() as u64;
            if let Some(max) = m["count"]["max"].as_u64() {
                assert!(n <= max, "{m}: sent {n} times\n{v}");
                checked += u64::from(n > 0);
            }
        }
        assert!(checked >= 3, "the run sent few bounded messages: {checked}");
    }
    let out = mcl(&["compile", "--link-report", "examples/auv-asc.mcl", "--frame-bytes", "1"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("[E0410]").count(), 7, "{err}");
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("compact encoding: 10 bits per frame, 2 bytes"));
}

#[test]
fn a_lossy_link_run_delivers_every_message_once_in_order_and_is_deterministic() {
    let dir = std::env::temp_dir().join(format!("mcl-acoustic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |name: &str| {
        let trace = dir.join(name);
        let out = mcl(&[
            "run",
            "--mock",
            "--virtual-time",
            "-q",
            "examples/auv-asc.mcl",
            "--scenario",
            "examples/scenarios/auv-asc.toml",
            "--link",
            "acoustic:bitrate=80,loss=0.4,delay=2",
            "--seed",
            "3",
            "--trace",
            trace.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        trace
    };
    let (a, b) = (run("a.jsonl"), run("b.jsonl"));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "the same seed gives the same run");
    let records = read_trace(&a);
    let lost = records.iter().filter(|r| matches!(r.kind, RecordKind::LinkLost { .. })).count();
    let resent =
        records.iter().filter(|r| matches!(r.kind, RecordKind::LinkSend { attempt, .. } if attempt > 1)).count();
    assert!(lost > 0 && resent > 0, "{lost} lost, {resent} resent");
    // Per link, the messages handed over (`new`) are 1, 2, 3... and each is
    // received once, as a `coord_receive` with the same number.
    let mut next: HashMap<(String, String), u64> = HashMap::new();
    for r in &records {
        match &r.kind {
            RecordKind::LinkDeliver { from, seq, status, .. } if status == "new" => {
                let n = next.entry((from.clone(), r.mission.clone().unwrap())).or_insert(1);
                assert_eq!(*seq, *n, "in order");
                *n += 1;
            }
            RecordKind::CoordReceive { from, seq, .. } => {
                let n = next.get(&(from.clone(), r.mission.clone().unwrap())).copied().unwrap_or(1);
                assert_eq!(*seq + 1, n, "received right after it was handed over");
            }
            _ => {}
        }
    }
    let sent = records.iter().filter(|r| matches!(r.kind, RecordKind::CoordSend { .. })).count() as u64;
    let handed: u64 = next.values().map(|n| n - 1).sum();
    assert!(
        handed + 1 >= sent && handed > 0,
        "{handed} handed over of {sent} sent (the last may be in flight at the end)"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn in_a_simulated_world_frames_beyond_range_are_lost() {
    // The simulated AUV and ASC are more than 10 m apart: nothing gets
    // through, the order on the AUV's dive waits until the time limit.
    let dir = std::env::temp_dir().join(format!("mcl-acoustic-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let trace = dir.join("t.jsonl");
    let args = [
        "run",
        "--sim",
        "--virtual-time",
        "-q",
        "examples/auv-asc.mcl",
        "--time-limit",
        "2000",
        "--trace",
        trace.to_str().unwrap(),
    ];
    let mut near = args.to_vec();
    near.extend(["--link", "acoustic:bitrate=80,loss=0,delay=0,range=10"]);
    let out = mcl(&near);
    assert_eq!(out.status.code(), Some(3), "{}", String::from_utf8_lossy(&out.stderr));
    let records = read_trace(&trace);
    let reasons: Vec<&str> = records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::LinkLost { reason, .. } => Some(reason.as_str()),
            _ => None,
        })
        .collect();
    assert!(!reasons.is_empty() && reasons.iter().all(|r| *r == "range"), "{reasons:?}");
    // In range, the delay comes from the distance (not the 0 s given).
    let mut far = args.to_vec();
    far.extend(["--link", "acoustic:bitrate=8000,loss=0,delay=0,range=100000"]);
    let out = mcl(&far);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let records = read_trace(&trace);
    let sent = records.iter().find(|r| matches!(r.kind, RecordKind::LinkSend { .. })).expect("a frame");
    let got = records.iter().find(|r| matches!(r.kind, RecordKind::LinkDeliver { .. })).expect("a delivery");
    assert!(got.t - sent.t > 0.01, "sent at {}, delivered at {}", sent.t, got.t);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_link_option_is_refused_where_it_cannot_apply() {
    let out = mcl(&["run", "--mock", "examples/auv-asc.mcl", "--link", "acoustic:bitrate=80,loss=0,delay=0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--virtual-time"));
    let out = mcl(&["run", "--mock", "--virtual-time", "examples/auv-asc.mcl", "--link", "acoustic:bitrate=80"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing `loss=`"));
    let out = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        "examples/survey.mcl",
        "--link",
        "acoustic:bitrate=80,loss=0,delay=0",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
}
