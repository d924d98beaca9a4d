//! The player against the explorer: one firing rule, two implementations.
//!
//! The player (`mcl_runtime::player`, incremental enabledness, timers,
//! events from the mock vehicle) and the state-space explorer
//! (`mcl_net::explore` under [`Semantics::Mcl`]) must agree on which
//! transition may fire in which marking: immediate transitions first, by
//! priority, then events and timers in tangible markings. For random
//! missions compiled with the library, random nets, and random coordinated
//! pairs, each run through the virtual-time driver and the mock (random
//! seeds, random scenario delays and outcomes, so that events arrive in
//! varying orders) gives a firing sequence that must be a path of the
//! explored state space: every firing an edge from the current state.
//!
//! Coordinated vehicles take the messages waiting for them together
//! (`Player::on_events`): a message's receive transition may then fire in
//! a vanishing marking, which no edge of the state space does. There, each
//! vehicle's sequence is checked on its own net: receive transitions fire
//! whenever they are enabled; every other firing must be an edge of the
//! explored state space from the current marking.
//!
//! Their joint behaviour is checked too: the firings of both vehicles, in
//! the order the run took them, are a path of the coordination verifier's
//! product, replayed on the supervised centralized net (supervisor places
//! included, exact counts) under the per-vehicle firing rule that the
//! verifier applies (`check_joint`): a start on a mutex that another
//! vehicle holds may be held while its vehicle takes other steps (its token
//! comes from the holder, a round trip), as in the settled and the
//! interleaving products (whose events no longer wait while such a start
//! is allowed); no other start may. And they are a path of the exact
//! product (`check_exact`, `mcl_coord::verify::flight::follows`: the
//! vehicle nets as the runtime plays them, messages in flight), with no
//! exception at all.
//!
//! `MCL_DIFFERENTIAL_CASES` (default 40 per kind) and
//! `MCL_DIFFERENTIAL_SEED` change the run.

use mcl_compiler::compile::compile_file;
use mcl_compiler::{check_file, Database};
use mcl_net::explore::{explore, Options, Semantics, StateId, StateSpace};
use mcl_net::{Delay, Marking, Net, NetBuilder, Place, PlaceId, Transition, TransitionId, TransitionKind};
use mcl_runtime::driver::{run_virtual, Collect, Limits, Session};
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::player::{Player, PlayerOptions};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::trace::{Record, RecordKind, SourceMap, Tracer};
use mcl_syntax::gen::Rng;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// States explored per net at most; a larger space is skipped (counted).
const MAX_STATES: usize = 60_000;

fn cases() -> usize {
    std::env::var("MCL_DIFFERENTIAL_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(40)
}

fn seed() -> u64 {
    std::env::var("MCL_DIFFERENTIAL_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(0x5eed_d1ff)
}

/// The complete state space of `net` under the MCL rule, with its edges;
/// `None` when it has more than [`MAX_STATES`] states.
fn state_space(net: &Net) -> Option<StateSpace> {
    state_space_cut(net, None)
}

/// [`state_space`], markings with more than `cut` tokens in a place left
/// unexpanded (a vehicle net alone receives messages without bound).
fn state_space_cut(net: &Net, cut: Option<u32>) -> Option<StateSpace> {
    let opts = Options {
        cut_above: cut,
        semantics: Semantics::Mcl,
        max_states: MAX_STATES,
        record_edges: true,
        threads: 1,
        ..Options::default()
    };
    let space = explore(net, &opts);
    assert!(space.path_to(StateId(0)).is_empty(), "state 0 is the initial marking");
    space.complete().then_some(space)
}

/// The transitions fired in `records` (kind `fire`), for `mission` when given.
fn fired(net: &Net, records: &[Record], mission: Option<&str>) -> Vec<TransitionId> {
    records
        .iter()
        .filter(|r| mission.is_none_or(|m| r.mission.as_deref() == Some(m)))
        .filter_map(|r| match &r.kind {
            RecordKind::Fire { transition, .. } => Some(transition.as_str()),
            _ => None,
        })
        .map(|id| net.transition_by_id(id).unwrap_or_else(|| panic!("`{id}` is not a transition of `{}`", net.id())))
        .collect()
}

fn names(net: &Net, ts: &[TransitionId]) -> Vec<String> {
    ts.iter().map(|&t| net.transitions()[t.index()].id.to_string()).collect()
}

/// Fails loudly unless `seq` is a path of `space` from the initial state.
fn assert_path(space: &StateSpace, net: &Net, seq: &[TransitionId], what: &dyn Fn() -> String) {
    let mut s = StateId(0);
    for (k, &t) in seq.iter().enumerate() {
        match space.successors(s).iter().find(|&&(u, _)| u == t) {
            Some(&(_, next)) => s = next,
            None => {
                let allowed: Vec<TransitionId> = space.successors(s).iter().map(|&(u, _)| u).collect();
                panic!(
                    "the player fired `{}` (firing {} of {}) where the explorer allows only {:?}\nmarking: {:?}\nfired so far: {:?}\n{}",
                    net.transitions()[t.index()].id,
                    k + 1,
                    seq.len(),
                    names(net, &allowed),
                    marked(net, &space.marking(s)),
                    names(net, &seq[..k]),
                    what()
                );
            }
        }
    }
}

fn marked(net: &Net, m: &Marking) -> Vec<String> {
    net.places()
        .iter()
        .zip(&m.0)
        .filter(|(_, &n)| n > 0)
        .map(|(p, n)| if *n == 1 { p.id.to_string() } else { format!("{}={n}", p.id) })
        .collect()
}

/// Plays `net` in virtual time against a mock answering by `scenario`,
/// until `limit` seconds of mission time at most; returns the transitions
/// fired.
fn play(net: &Arc<Net>, scenario: &str, opts: PlayerOptions, limit: f64) -> Vec<TransitionId> {
    let seed = opts.seed;
    let scenario = Scenario::from_toml(scenario, "differential.toml").expect("a valid scenario");
    let mut sink = Collect::default();
    let tracer = Tracer::new(net, None, &mut SourceMap::default());
    let mut s = Session::new(Player::new(net.clone(), opts), tracer, &mut sink);
    let mut mock = MockVehicle::from_net(net, scenario, seed);
    mock.initial();
    run_virtual(&mut s, &mut mock, Limits::virtual_time(Some(limit))).expect("the run goes through");
    drop(s);
    fired(net, &sink.0, None)
}

/// Counts what a kind of case checked, and fails when it checked too little.
#[derive(Default)]
struct Tally {
    runs: usize,
    firings: usize,
    skipped: usize,
}

impl Tally {
    fn done(&self, what: &str, cases: usize) {
        eprintln!(
            "{what}: {} runs, {} firings checked, {} too large to explore",
            self.runs, self.firings, self.skipped
        );
        assert!(
            self.skipped * 2 <= cases,
            "{what}: most cases were too large to explore ({} of {cases})",
            self.skipped
        );
        assert!(self.firings > self.runs, "{what}: the runs fired nothing worth checking");
    }
}

// ---------------------------------------------------------------------------
// (a) Random missions
// ---------------------------------------------------------------------------

fn call(r: &mut Rng) -> String {
    match r.below(4) {
        0 => format!("A( {} )", r.below(3)),
        1 => "B()".into(),
        2 => format!("Timed( {} )", 1 + r.below(4)),
        _ => "Void()".into(),
    }
}

/// Every control structure ([`stmt`]).
const ALL: &[usize] = &[0, 1, 2, 3, 4, 5, 6, 7, 8];

/// The structures whose nominal runs (no failure, no alarm) reach the end:
/// no `not`, no `while` (coordinated pairs, whose constraints would
/// otherwise wait for ever).
const TAME: &[usize] = &[0, 1, 2, 5, 6, 7];

fn block(r: &mut Rng, depth: usize, kinds: &[usize]) -> String {
    let n = 1 + r.below(2);
    (0..n).map(|_| stmt(r, depth, kinds)).collect::<Vec<_>>().join(" ; ")
}

/// A random statement with the control structures `kinds` (the shapes of
/// mcl-compiler's property test).
fn stmt(r: &mut Rng, depth: usize, kinds: &[usize]) -> String {
    if depth == 0 || r.chance(35) {
        return call(r);
    }
    let d = depth - 1;
    let b = |r: &mut Rng| block(r, d, kinds);
    match *r.pick(kinds) {
        0 => format!("if ( {} ) {{ {} }}", b(r), b(r)),
        1 => format!("if ( {} ) {{ {} }} else {{ {} }}", b(r), b(r), b(r)),
        2 => format!("try {{ {} }} catch {{ {} }}", b(r), b(r)),
        3 => format!("not ( {} )", b(r)),
        // B ends fail now and then: the loop ends.
        4 => format!("while ( B() ) {{ {} }}", b(r)),
        5 => format!("parallel {{ {} }} and {{ {} }}", b(r), b(r)),
        6 => format!("parallel {{ {} }} or {{ {} }}", b(r), b(r)),
        7 => format!("monitor {{ {} }} condition ( {} ) do {{ {} }}", b(r), b(r), b(r)),
        _ => format!("monitor {{ {} }} while_condition ( W() ) do {{ {} }}", b(r), b(r)),
    }
}

/// A scenario with random delays and outcomes for every task.
fn mission_scenario(r: &mut Rng) -> String {
    let mut s = format!("seed = {}\ndefault_duration = {}\n", r.below(1000), r.below(4));
    for task in ["A", "B", "Timed", "W"] {
        s.push_str(&format!("[tasks.{task}]\n"));
        match r.below(5) {
            0 => s.push_str("outcome = \"ok\"\n"),
            1 => s.push_str("outcome = \"fail\"\n"),
            // Timed's time-out, or a stuck mission: paths all the same.
            2 if task != "B" => s.push_str("outcome = \"never\"\n"),
            _ => s.push_str(&format!("probabilities = {{ ok = {}, fail = {} }}\n", 1 + r.below(3), 1 + r.below(3))),
        }
        let lo = r.below(4);
        s.push_str(&format!("delay = [{lo}, {}]\n", lo + r.below(6)));
    }
    s
}

fn compile_mission(body: &str) -> Net {
    let mut db = Database::new();
    let dir = Path::new("/virtual/differential");
    db.set_text(&dir.join("vehicle.mcl"), mcl_syntax::gen::TEST_VEHICLE);
    let file = db.set_text(&dir.join("m.mcl"), format!("import \"vehicle.mcl\";\nmission {{ {body} }}\n"));
    let diags = check_file(&db, file);
    assert!(!mcl_compiler::has_errors(diags), "generated program has errors: {diags:?}\n{body}");
    let mut missions = compile_file(&db, file).unwrap_or_else(|e| panic!("{e}\n{body}"));
    assert_eq!(missions.len(), 1);
    missions.remove(0).net
}

#[test]
fn random_missions_fire_along_the_explored_state_space() {
    let cases = cases();
    let mut r = Rng(seed());
    let mut tally = Tally::default();
    for case in 0..cases {
        let body = block(&mut r, 3, ALL);
        let net = Arc::new(compile_mission(&body));
        let Some(space) = state_space(&net) else {
            tally.skipped += 1;
            continue;
        };
        for _ in 0..3 {
            let scenario = mission_scenario(&mut r);
            let seed = r.next_u64();
            let seq = play(&net, &scenario, PlayerOptions::seeded(seed), 5_000.0);
            assert_path(&space, &net, &seq, &|| {
                format!("case {case}, player seed {seed}\nmission {{ {body} }}\nscenario:\n{scenario}")
            });
            tally.runs += 1;
            tally.firings += seq.len();
        }
    }
    tally.done("random missions", cases);
}

// ---------------------------------------------------------------------------
// (b) Random nets
// ---------------------------------------------------------------------------

/// Events of the random nets.
const EVENTS: [&str; 3] = ["e0", "e1", "e2"];

/// A random net (after mcl-net's explorer test): immediate and deferred
/// transitions with random priorities, events, timed transitions, extra
/// arcs and weights.
fn random_net(r: &mut Rng) -> Net {
    let mut b = NetBuilder::new("random");
    let np = 2 + r.below(7);
    let places: Vec<PlaceId> = (0..np).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
    for _ in 0..1 + r.below(4) {
        let p = places[r.below(np)];
        let pl = b.place_mut(p).expect("a place of the net");
        pl.initial = (pl.initial + 1 + r.below(2) as u32).min(3);
    }
    let mut ts = Vec::new();
    for i in 0..1 + r.below(12) {
        let kind = match r.below(5) {
            0..=2 => TransitionKind::Immediate,
            3 => TransitionKind::Event((*r.pick(&EVENTS)).into()),
            // Delay 0: a deferred transition (fires in tangible markings,
            // by priority among those due).
            _ => TransitionKind::Timed(Delay::Fixed(r.below(3) as f64)),
        };
        let mut t = Transition::new(format!("t{i}")).with_kind(kind);
        if r.chance(50) {
            t.priority = Some(r.below(3) as u32);
        }
        let t = b.add_transition(t);
        b.add_input(places[r.below(np)], t, 1).add_output(t, places[r.below(np)], 1);
        ts.push(t);
    }
    for _ in 0..r.below(4) {
        let (p, t, w) = (places[r.below(np)], ts[r.below(ts.len())], 1 + r.below(2) as u32);
        if r.chance(50) {
            b.add_input(p, t, w);
        } else {
            b.add_output(t, p, w);
        }
    }
    b.build().expect("a well-formed random net")
}

/// Scripted events at random times (some at the same instant).
fn events_scenario(r: &mut Rng) -> String {
    let mut s = String::new();
    for _ in 0..r.below(12) {
        s.push_str(&format!("[[events]]\nat = {}\nevent = \"{}\"\n", r.below(8), r.pick(&EVENTS)));
    }
    s
}

#[test]
fn random_nets_fire_along_the_explored_state_space() {
    let cases = cases() * 2;
    let mut r = Rng(seed() ^ 0x6e65_7473);
    let mut tally = Tally::default();
    for case in 0..cases {
        let net = Arc::new(random_net(&mut r));
        let Some(space) = state_space(&net) else {
            tally.skipped += 1;
            continue;
        };
        for _ in 0..3 {
            let scenario = events_scenario(&mut r);
            let seed = r.next_u64();
            let seq = play(&net, &scenario, PlayerOptions { step_limit: 2_000, ..PlayerOptions::seeded(seed) }, 100.0);
            assert_path(&space, &net, &seq, &|| {
                format!(
                    "case {case}, player seed {seed}\nnet:\n{}\nscenario:\n{scenario}",
                    mcl_net::write_pnml(&net).unwrap_or_default()
                )
            });
            tally.runs += 1;
            tally.firings += seq.len();
        }
    }
    tally.done("random nets", cases);
}

// ---------------------------------------------------------------------------
// (c) Random coordinated pairs
// ---------------------------------------------------------------------------

/// A random mission that starts with the instantaneous call `s`, then has
/// the calls `x` and `y` among random statements.
fn labelled_mission(r: &mut Rng) -> String {
    let mut parts = vec!["A( 1 ) : x".to_string(), "B() : y".to_string()];
    if r.chance(50) {
        parts.swap(0, 1);
    }
    for _ in 0..1 + r.below(2) {
        let at = r.below(parts.len() + 1);
        parts.insert(at, stmt(r, 2, TAME));
    }
    format!("Void() : s ; {}", parts.join(" ; "))
}

/// A mutex on any calls; an order or a sync whose first call is `s`,
/// which every run reaches (a mission that fails before a call would
/// otherwise leave the other waiting: a deadlock that the analysis refuses).
fn constraint(r: &mut Rng) -> String {
    let (l, m) = (*r.pick(&["x", "y"]), *r.pick(&["x", "y"]));
    match r.below(3) {
        0 => format!("mutex {{ a:{l}, b:{m} }} = 1"),
        1 => format!("order {{ a:s, b:{} }}", r.pick(&["s", "x", "y"])),
        _ => "sync { a:s, b:s }".to_string(),
    }
}

/// The vehicle nets of a coordinated pair and its supervised centralized
/// net (the take-back of withdrawn sync arrivals written as nodes), or why
/// there are none (the constraints deadlock, or the analysis was
/// inconclusive).
fn vehicle_nets(text: &str) -> Result<(Vec<mcl_coord::VehicleNet>, Net, Vec<mcl_coord::Mission>), String> {
    let mut db = Database::new();
    let dir = Path::new("/virtual/differential");
    db.set_text(&dir.join("vehicle.mcl"), mcl_syntax::gen::TEST_VEHICLE);
    let file = db.set_text(&dir.join("pair.mcl"), text);
    let diags = check_file(&db, file);
    assert!(!mcl_compiler::has_errors(diags), "generated program has errors: {diags:?}\n{text}");
    let (missions, constraints) = mcl_coord::source::load(&db, file).map_err(|e| e.to_string())?;
    let report = mcl_coord::analyze(&missions, &constraints).map_err(|e| e.to_string())?;
    if !report.deadlock_free {
        return Err(format!("{:?}: {:?}", report.verdict, report.problems.first().map(|p| &p.message)));
    }
    let central =
        mcl_coord::supervisor::with_take_backs(&report.net, &report.supervisors).map_err(|e| e.to_string())?;
    let nets = mcl_coord::decentralize(&missions, &report.supervisors).map_err(|e| e.to_string())?;
    Ok((nets, central, missions))
}

/// Fires the take-back nodes that `central` enables (`S.withdraw`, else
/// `S.forget`, immediate of priorities 2 and 1: under the firing rule they
/// fire before anything else).
fn take_backs(central: &Net, m: &mut Marking) {
    loop {
        let en = mcl_net::semantics::enabled(central, m);
        let id = |t: &&TransitionId| central.transitions()[t.index()].id.to_string();
        let next =
            en.iter().find(|t| id(t).ends_with(".withdraw")).or_else(|| en.iter().find(|t| id(t).ends_with(".forget")));
        match next {
            Some(&t) => mcl_net::semantics::fire(central, m, t).expect("an enabled take-back fires"),
            None => return,
        }
    }
}

/// What [`check_joint`] checked.
#[derive(Default)]
struct Joint {
    /// Firings replayed on the supervised centralized net.
    firings: usize,
}

/// Checks the joint behaviour of a coordinated run: the firings of both
/// vehicles, in the order of the records, are a path of the coordination
/// verifier's product, replayed on the supervised centralized net with
/// exact token counts. Each firing of a mission's transition (`mission/id`
/// there) must be enabled there, supervisor places included, and ready for
/// its vehicle under the per-vehicle firing rule (`select_ready` among its
/// enabled transitions, as the verifier's transition systems and replay
/// apply it), where a start on a mutex that another vehicle holds may be
/// held (its token may be on its way; the interleaving and the settled
/// products hold it too) and no other start may. The vehicle nets' own coordination transitions
/// (receptions, `coord.*`) have no counterpart there; a mission fires
/// nothing of its own after its outcome (its supervisor copies still
/// receive).
fn check_joint(
    central: &Net,
    nets: &[mcl_coord::VehicleNet],
    records: &[Record],
    joint: &mut Joint,
    what: &dyn Fn() -> String,
) {
    let mut m = central.initial_marking();
    let remote_starts = remote_mutex_starts(central);
    // Each vehicle's own marking, on its vehicle net.
    let mut local: Vec<Marking> = nets.iter().map(|v| v.net.initial_marking()).collect();
    let mut started = vec![false; nets.len()];
    let mut ended: Vec<&str> = Vec::new();
    let mut so_far: Vec<String> = Vec::new();
    for r in records {
        let Some(mission) = r.mission.as_deref() else { continue };
        let Some(k) = nets.iter().position(|v| v.mission == mission) else { continue };
        let v = &nets[k];
        let id = match &r.kind {
            RecordKind::Outcome { .. } => {
                ended.push(mission);
                continue;
            }
            // Messages received before the start fire on the initial marking.
            RecordKind::Event { transition, .. } if !started[k] => {
                if let Some(t) = v.net.transition_by_id(transition) {
                    mcl_net::semantics::fire(&v.net, &mut local[k], t).expect("a delivery fires");
                }
                continue;
            }
            RecordKind::Fire { transition, .. } => transition.as_str(),
            _ => continue,
        };
        started[k] = true;
        let fail = |why: String, m: &Marking| -> ! {
            panic!("joint run: {why}\nmarking: {:?}\nfired so far: {so_far:?}\n{}", marked(central, m), what())
        };
        let lt = v.net.transition_by_id(id).unwrap_or_else(|| panic!("`{id}` is not a transition of `{mission}`"));
        let gid = format!("{mission}/{id}");
        let Some(t) = central.transition_by_id(&gid) else {
            if !v.receive.iter().any(|(r, _)| r == id) && !id.starts_with("coord.") {
                fail(format!("`{gid}` is not a transition of the centralized net"), &m);
            }
            mcl_net::semantics::fire(&v.net, &mut local[k], lt).expect("a reception fires");
            continue;
        };
        if ended.contains(&mission) {
            fail(format!("`{mission}` fired `{id}` after its outcome"), &m);
        }
        if !mcl_net::semantics::is_enabled(central, &m, t) {
            fail(format!("`{gid}` fired while the supervised centralized net does not enable it"), &m);
        }
        let prefix = format!("{mission}/");
        let mut ready: Vec<TransitionId> = mcl_net::semantics::enabled(central, &m)
            .into_iter()
            .filter(|u| central.transitions()[u.index()].id.starts_with(&prefix))
            .collect();
        // A start on a mutex that another vehicle holds may wait for its
        // token (the verifier's products hold it too); no other start may.
        ready.retain(|&u| u == t || !remote_starts.contains(&u));
        mcl_net::semantics::select_ready(central, &mut ready);
        if !ready.contains(&t) {
            let ready: Vec<String> = ready.iter().map(|u| central.transitions()[u.index()].id.to_string()).collect();
            fail(format!("`{gid}` fired where its vehicle's firing rule allows only {ready:?}"), &m);
        }
        mcl_net::semantics::fire(central, &mut m, t).expect("an enabled transition fires");
        take_backs(central, &mut m);
        mcl_net::semantics::fire(&v.net, &mut local[k], lt).expect("the vehicle's firing fires");
        so_far.push(gid);
        joint.firings += 1;
    }
}

/// The starts of the centralized net on a mutex between vehicles (a
/// `coord.mutex*` place that transitions of several missions consume) of
/// the missions that do not hold it (the holder is the first mission with
/// one of its calls, `mcl_coord::decentral`; the plant lays the missions
/// out in order).
fn remote_mutex_starts(central: &Net) -> Vec<TransitionId> {
    let mission = |t: TransitionId| central.transitions()[t.index()].id.split_once('/').map(|(m, _)| m.to_string());
    let mut out = Vec::new();
    for p in central.place_ids().filter(|&p| central.places()[p.index()].id.starts_with("coord.mutex")) {
        let users: Vec<TransitionId> =
            central.transition_ids().filter(|&t| central.pre(t).iter().any(|&(q, _)| q == p)).collect();
        let holder = users.iter().min().and_then(|&t| mission(t));
        if users.iter().any(|&t| mission(t) != holder) {
            out.extend(users.into_iter().filter(|&t| mission(t) != holder));
        }
    }
    out
}

/// Runs the vehicles of `nets` together in virtual time, each against its
/// mock; returns the records.
fn play_pair(nets: &[mcl_coord::VehicleNet], scenario: &str, seed: u64) -> Vec<Record> {
    use mcl_runtime::multi::{run_virtual, SharedSink, Vehicle};
    let names: Vec<String> = nets.iter().map(|v| v.mission.clone()).collect();
    let sink = Arc::new(std::sync::Mutex::new(Collect::default()));
    let mut vehicles = Vec::new();
    for (v, transport) in nets.iter().zip(mcl_runtime::coord::in_process(&names)) {
        let net = Arc::new(v.net.clone());
        let tracer = Tracer::new(&net, Some(v.mission.clone()), &mut SourceMap::default());
        let scenario = Scenario::from_toml(scenario, "differential.toml").expect("a valid scenario");
        let mock = MockVehicle::from_net(&net, scenario, seed);
        let opts = PlayerOptions::seeded(seed);
        vehicles.push(Vehicle::new(&v.mission, net, opts, tracer, mock, Box::new(transport)).expect("a vehicle"));
    }
    let shared: SharedSink = sink.clone();
    let rt = tokio::runtime::Builder::new_current_thread().enable_time().build().expect("a runtime");
    rt.block_on(run_virtual(vehicles, shared, Limits::virtual_time(Some(5_000.0)))).expect("the run goes through");
    let records = std::mem::take(&mut sink.lock().expect("the sink").0);
    records
}

/// How a vehicle's firings were checked.
#[derive(Default)]
struct PairTally {
    /// Firings that were an edge of the state space from the current state.
    edges: usize,
    /// Receive transitions fired while enabled (delivered together).
    received: usize,
    /// Firings in a marking the explorer never reaches (after messages
    /// delivered together): checked against the firing rule's ready set.
    off_space: usize,
    /// Firings of both vehicles checked together on the supervised
    /// centralized net ([`check_joint`]).
    joint: Joint,
    /// Firings of both vehicles followed along the exact product
    /// ([`check_exact`]).
    exact: usize,
}

/// Checks that the firings of both vehicles, in the order of the records,
/// are a path of the coordination verifier's exact product (the vehicle
/// nets as the runtime plays them, messages in flight:
/// `mcl_coord::verify::flight::follows`), with no exception: a start held
/// for a remote mutex grant is a run of it like any other. Returns the
/// firings followed.
fn check_exact(
    missions: &[mcl_coord::Mission],
    nets: &[mcl_coord::VehicleNet],
    records: &[Record],
    what: &dyn Fn() -> String,
) -> usize {
    let fires: Vec<(usize, TransitionId)> = records
        .iter()
        .filter_map(|r| {
            let RecordKind::Fire { transition, .. } = &r.kind else { return None };
            let k = nets.iter().position(|v| Some(v.mission.as_str()) == r.mission.as_deref())?;
            Some((k, nets[k].net.transition_by_id(transition)?))
        })
        .collect();
    if let Err(why) = mcl_coord::verify::flight::follows(missions, nets, &fires, 2_000_000) {
        panic!(
            "exact product: {why}
{}",
            what()
        );
    }
    fires.len()
}

/// Checks one vehicle's firings in `records` on its net (see the module
/// documentation), up to its outcome.
fn check_vehicle(
    v: &mcl_coord::VehicleNet,
    space: &StateSpace,
    records: &[Record],
    tally: &mut PairTally,
    what: &dyn Fn() -> String,
) {
    let net = &v.net;
    let receive: Vec<TransitionId> = v.receive.iter().filter_map(|(id, _)| net.transition_by_id(id)).collect();
    let cut: std::collections::HashSet<u32> = space.cut_states().map(|s| s.0).collect();
    let states: HashMap<Vec<u32>, StateId> =
        space.states().filter(|s| !cut.contains(&s.0)).map(|s| (space.marking(s).0, s)).collect();
    let mut m = net.initial_marking();
    let mut started = false;
    let mut so_far = Vec::new();
    for r in records.iter().filter(|r| r.mission.as_deref() == Some(v.mission.as_str())) {
        let fail = |why: String, m: &Marking, so_far: &[TransitionId]| -> ! {
            panic!(
                "`{}`: {why}\nmarking: {:?}\nfired so far: {:?}\n{}",
                v.mission,
                marked(net, m),
                names(net, so_far),
                what()
            )
        };
        match &r.kind {
            RecordKind::Outcome { .. } => return,
            // Messages received before the start fire on the initial marking.
            RecordKind::Event { transition, .. } if !started => {
                if let Some(t) = net.transition_by_id(transition) {
                    if !mcl_net::semantics::is_enabled(net, &m, t) {
                        fail(
                            format!("`{}` delivered before the start but not enabled", net.transitions()[t.index()].id),
                            &m,
                            &so_far,
                        );
                    }
                    mcl_net::semantics::fire(net, &mut m, t).expect("an enabled transition fires");
                    tally.received += 1;
                }
            }
            RecordKind::Fire { transition, .. } => {
                started = true;
                let id = transition.as_str();
                let t =
                    net.transition_by_id(id).unwrap_or_else(|| panic!("`{id}` is not a transition of `{}`", v.mission));
                if receive.contains(&t) {
                    if !mcl_net::semantics::is_enabled(net, &m, t) {
                        fail(format!("the player received `{id}` while it is not enabled"), &m, &so_far);
                    }
                    tally.received += 1;
                } else if let Some(&s) = states.get(&m.0) {
                    if !space.successors(s).iter().any(|&(u, _)| u == t) {
                        let allowed: Vec<TransitionId> = space.successors(s).iter().map(|&(u, _)| u).collect();
                        fail(
                            format!(
                                "the player fired `{id}` where the explorer allows only {:?}",
                                names(net, &allowed)
                            ),
                            &m,
                            &so_far,
                        );
                    }
                    tally.edges += 1;
                } else {
                    let (_, ready) = mcl_net::semantics::ready(net, &m);
                    if !ready.contains(&t) {
                        fail(format!("the player fired `{id}`, not ready by the firing rule"), &m, &so_far);
                    }
                    tally.off_space += 1;
                }
                mcl_net::semantics::fire(net, &mut m, t).expect("an enabled transition fires");
                so_far.push(t);
            }
            _ => {}
        }
    }
}

/// Tokens in a place above which a vehicle net's marking is not expanded.
const CUT: u32 = 3;

/// Random delays and outcomes for the tasks of both vehicles.
fn pair_scenario(r: &mut Rng) -> String {
    mission_scenario(r)
}

#[test]
fn coordinated_vehicles_fire_along_their_explored_state_spaces() {
    let cases = cases();
    let mut r = Rng(seed() ^ 0x7061_6972);
    let mut tally = PairTally::default();
    let (mut runs, mut skipped) = (0, 0);
    let mut pairs = 0;
    for case in 0..cases * 4 {
        if pairs == cases {
            break;
        }
        let (a, b, c) = (labelled_mission(&mut r), labelled_mission(&mut r), constraint(&mut r));
        let text = format!(
            "import \"vehicle.mcl\";\nmission : a {{ {a} }}\nmission : b {{ {b} }}\nconstraints {{\n    {c}\n}}\n"
        );
        let (nets, central, missions) = match vehicle_nets(&text) {
            Ok(x) => x,
            Err(why) => {
                eprintln!("pair {case} skipped: {why}");
                skipped += 1;
                continue;
            }
        };
        let Some(spaces) = nets.iter().map(|v| state_space_cut(&v.net, Some(CUT))).collect::<Option<Vec<_>>>() else {
            eprintln!("pair {case} skipped: more than {MAX_STATES} states");
            skipped += 1;
            continue;
        };
        pairs += 1;
        for _ in 0..3 {
            let scenario = pair_scenario(&mut r);
            let seed = r.next_u64();
            let records = play_pair(&nets, &scenario, seed);
            let what = || format!("case {case}, seed {seed}\n{text}\nscenario:\n{scenario}");
            for (v, space) in nets.iter().zip(&spaces) {
                check_vehicle(v, space, &records, &mut tally, &what);
            }
            check_joint(&central, &nets, &records, &mut tally.joint, &what);
            tally.exact += check_exact(&missions, &nets, &records, &what);
            runs += 1;
        }
    }
    eprintln!(
        "coordinated pairs: {runs} runs; {} firings along edges, {} receptions, {} off the explored space, {} joint \
         firings along the product, {} along the exact product; {skipped} pairs skipped",
        tally.edges, tally.received, tally.off_space, tally.joint.firings, tally.exact
    );
    assert_eq!(pairs, cases, "too many pairs were skipped ({skipped})");
    assert!(tally.received > 0, "no coordination message was received: the pairs do not coordinate");
    assert!(tally.edges > 10 * tally.off_space, "too few firings checked against the explorer");
    assert!(tally.joint.firings > 0, "no joint firing was checked against the product");
    assert!(tally.exact > 0, "no firing was followed along the exact product");
}
