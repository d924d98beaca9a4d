//! State-space exploration on hand-made nets, and against a naive reference.

use std::collections::{HashMap, VecDeque};

use mcl_net::explore::{explore, StopReason};
use mcl_net::semantics::{self, MarkingClass};
use mcl_net::{
    analyze, Delay, Marking, Net, NetBuilder, Options, Place, PlaceId, Semantics, Transition, TransitionId,
    TransitionKind,
};
use proptest::prelude::*;

fn event(name: &str) -> TransitionKind {
    TransitionKind::Event(name.to_string())
}

/// Seed Figure A.1: P1 is unbounded.
fn figure_a1() -> Net {
    let mut b = NetBuilder::new("a1");
    let p: Vec<_> = (0..4).map(|i| b.add_place(Place::new(format!("P{i}")).with_tokens(u32::from(i == 0)))).collect();
    let t0 = b.add_transition(Transition::new("T0"));
    let t1 = b.add_transition(Transition::new("T1").with_kind(event("e")));
    let t2 = b.add_transition(Transition::new("T2"));
    let t3 = b.add_transition(Transition::new("T3").with_kind(TransitionKind::Timed(Delay::Fixed(1.0))));
    b.add_input(p[0], t0, 1).add_output(t0, p[1], 1).add_output(t0, p[2], 1);
    b.add_input(p[1], t1, 1);
    b.add_input(p[2], t2, 1).add_output(t2, p[3], 1);
    b.add_input(p[3], t3, 1).add_output(t3, p[0], 1);
    b.build().unwrap()
}

fn opts(semantics: Semantics) -> Options {
    Options { semantics, ..Options::default() }
}

#[test]
fn unbounded_net_stops_at_the_state_limit() {
    let net = figure_a1();
    let o = Options { max_states: 1000, ..Options::default() };
    let r = analyze(&net, &o);
    assert!(!r.complete);
    assert_eq!(r.stop_reason, Some(StopReason::StateLimit));
    assert_eq!(r.states, 1000);
    // P0, P2, P3 form an invariant (seed, A.1): they stay 1-bounded.
    assert_eq!(r.bounds[0].bound, 1);
    assert_eq!(r.bounds[2].bound, 1);
    assert_eq!(r.bounds[3].bound, 1);
    assert!(r.bounds[1].bound > 1);
    let ss = explore(&net, &o);
    // Initial marking {P0} and {P1, P2} are vanishing, {P1, P3} tangible.
    assert!(ss.is_vanishing(mcl_net::StateId(0)));
    assert_eq!(ss.marking(mcl_net::StateId(1)).0, vec![0, 1, 1, 0]);
    assert!(ss.is_vanishing(mcl_net::StateId(1)));
    assert_eq!(ss.marking(mcl_net::StateId(2)).0, vec![0, 1, 0, 1]);
    assert!(!ss.is_vanishing(mcl_net::StateId(2)));
}

#[test]
fn immediate_transitions_preempt_events_only_under_mcl_semantics() {
    let mut b = NetBuilder::new("race");
    let p0 = b.add_place(Place::new("p0").with_tokens(1));
    let p1 = b.add_place(Place::new("p1"));
    let p2 = b.add_place(Place::new("p2"));
    let imm = b.add_transition(Transition::new("imm"));
    let ev = b.add_transition(Transition::new("ev").with_kind(event("go")));
    b.add_input(p0, imm, 1).add_output(imm, p1, 1);
    b.add_input(p0, ev, 1).add_output(ev, p2, 1);
    let net = b.build().unwrap();

    let plain = analyze(&net, &opts(Semantics::Plain));
    assert_eq!((plain.states, plain.edges, plain.dead_markings), (3, 2, 2));
    assert_eq!(plain.vanishing_states, 0);

    let mcl = analyze(&net, &opts(Semantics::Mcl));
    assert_eq!((mcl.states, mcl.edges, mcl.dead_markings), (2, 1, 1));
    assert_eq!(mcl.vanishing_states, 1);
    assert_eq!(mcl.dead_examples[0].marking, vec![("p1".to_string(), 1)]);
    assert_eq!(mcl.dead_examples[0].path_names, vec!["imm".to_string()]);
}

#[test]
fn priorities_prune_immediate_choices() {
    let mut b = NetBuilder::new("prio");
    let p0 = b.add_place(Place::new("p0").with_tokens(1));
    let a = b.add_place(Place::new("a"));
    let c = b.add_place(Place::new("c"));
    let lo = b.add_transition(Transition::new("lo"));
    let hi = b.add_transition(Transition::new("hi").with_priority(1));
    b.add_input(p0, lo, 1).add_output(lo, a, 1);
    b.add_input(p0, hi, 1).add_output(hi, c, 1);
    let net = b.build().unwrap();
    assert_eq!(analyze(&net, &opts(Semantics::Plain)).states, 3);
    let r = analyze(&net, &opts(Semantics::Mcl));
    assert_eq!(r.states, 2);
    assert_eq!(r.dead_examples[0].marking, vec![("c".to_string(), 1)]);
}

#[test]
fn dead_markings_come_with_shortest_paths() {
    // Long way p0 -> x -> y -> end, short way p0 -> end.
    let mut b = NetBuilder::new("paths");
    let p0 = b.add_place(Place::new("p0").with_tokens(1));
    let x = b.add_place(Place::new("x"));
    let y = b.add_place(Place::new("y"));
    let end = b.add_place(Place::new("end"));
    let names = ["a", "b", "c", "short"];
    let t: Vec<_> = names.iter().map(|n| b.add_transition(Transition::new(*n))).collect();
    b.add_input(p0, t[0], 1).add_output(t[0], x, 1);
    b.add_input(x, t[1], 1).add_output(t[1], y, 1);
    b.add_input(y, t[2], 1).add_output(t[2], end, 1);
    b.add_input(p0, t[3], 1).add_output(t[3], end, 1);
    let net = b.build().unwrap();
    let r = analyze(&net, &opts(Semantics::Plain));
    assert_eq!(r.dead_markings, 1);
    assert_eq!(r.dead_examples[0].path_names, vec!["short".to_string()]);
    assert_eq!(r.dead_examples[0].path, vec![t[3]]);
    assert!(r.deadlock);
    assert!(r.one_safe);
}

#[test]
fn counters_widen_beyond_a_byte_and_two_bytes() {
    let mut b = NetBuilder::new("counter");
    let src = b.add_place(Place::new("src").with_tokens(300));
    let dst = b.add_place(Place::new("dst"));
    let t = b.add_transition(Transition::new("move"));
    b.add_input(src, t, 1).add_output(t, dst, 1);
    let net = b.build().unwrap();
    let r = analyze(&net, &opts(Semantics::Plain));
    assert_eq!((r.states, r.edges), (301, 300));
    assert_eq!(r.bounds[1].bound, 300);
    assert_eq!((r.max_tokens, r.max_tokens_per_marking), (300, 300));
    assert!(!r.one_safe);

    let mut b = NetBuilder::new("burst");
    let p = b.add_place(Place::new("p").with_tokens(1));
    let q = b.add_place(Place::new("q"));
    let t = b.add_transition(Transition::new("burst"));
    b.add_input(p, t, 1).add_output(t, q, 70_000);
    let net = b.build().unwrap();
    let r = analyze(&net, &opts(Semantics::Plain));
    assert_eq!(r.states, 2);
    assert_eq!((r.max_tokens, r.max_tokens_per_marking), (70_000, 70_000));
}

#[test]
fn one_bit_fields_widen_on_overflow() {
    let mut b = NetBuilder::new("fill");
    let budget = b.add_place(Place::new("budget").with_tokens(1));
    let acc = b.add_place(Place::new("acc"));
    let fill = b.add_transition(Transition::new("fill"));
    let drain = b.add_transition(Transition::new("drain"));
    b.add_input(budget, fill, 1).add_output(fill, acc, 40);
    b.add_input(acc, drain, 1);
    let net = b.build().unwrap();
    let ss = explore(&net, &opts(Semantics::Plain));
    assert_eq!(ss.bits_per_place(), 8);
    assert_eq!(ss.len(), 42);
    assert_eq!(ss.bounds(), &[1, 40]);

    // A 1-safe net keeps one bit per place.
    let ss = explore(&figure_a1(), &Options { max_states: 5, ..Options::default() });
    assert_eq!(ss.len(), 5);
    // Four independent 1-token rings of 17 places: 17^4 states, 1-safe,
    // 68 places packed one bit each into two words.
    let rings = rings(17);
    let ss = explore(&rings, &opts(Semantics::Plain));
    assert_eq!(ss.bits_per_place(), 1);
    let r = mcl_net::explore::report(&rings, &ss, 1);
    assert!(r.one_safe && r.complete && !r.deadlock);
    assert_eq!((r.states, r.edges, r.max_tokens_per_marking), (17u64.pow(4), 4 * 17u64.pow(4), 4));
    assert_eq!(r.max_tokens, 1, "the largest bound of a place");
}

/// Four independent rings of `n` places with one token each.
fn rings(n: usize) -> Net {
    let mut b = NetBuilder::new("rings");
    for r in 0..4 {
        let p: Vec<_> =
            (0..n).map(|i| b.add_place(Place::new(format!("r{r}p{i}")).with_tokens(u32::from(i == 0)))).collect();
        for i in 0..n {
            let t = b.add_transition(Transition::new(format!("r{r}t{i}")));
            b.add_input(p[i], t, 1).add_output(t, p[(i + 1) % n], 1);
        }
    }
    b.build().unwrap()
}

#[test]
fn threads_give_the_same_numbered_state_space() {
    let net = rings(13); // 28561 states, levels wide enough to use threads
    let seq = explore(&net, &opts(Semantics::Plain));
    for threads in [2, 4] {
        let par = explore(&net, &Options { threads, ..opts(Semantics::Plain) });
        assert_eq!((par.len(), par.edges()), (seq.len(), seq.edges()));
        for s in seq.states() {
            assert_eq!(par.marking(s), seq.marking(s));
            assert_eq!(par.path_to(s), seq.path_to(s));
        }
    }
}

#[test]
fn parallel_engine_stops_at_the_state_limit() {
    let o = Options { max_states: 5000, threads: 2, ..opts(Semantics::Plain) };
    let r = analyze(&rings(13), &o);
    assert_eq!(r.states, 5000);
    assert!(!r.complete);
    assert_eq!(r.stop_reason, Some(StopReason::StateLimit));
    let r = analyze(&figure_a1(), &Options { max_states: 300, threads: 3, ..Options::default() });
    assert_eq!((r.states, r.complete), (300, false));
}

/// The markings of `ss`, sorted.
fn markings(ss: &mcl_net::explore::StateSpace) -> Vec<Marking> {
    let mut v: Vec<Marking> = ss.states().map(|s| ss.marking(s)).collect();
    v.sort();
    v
}

/// The unordered engine against the sequential one: the same states, edges,
/// dead and vanishing markings and bounds; every path leads to its marking.
fn assert_unordered_agrees(net: &Net, o: &Options, seq: &mcl_net::explore::StateSpace, threads: usize) {
    let par = explore(net, &Options { threads, exact_order: false, ..o.clone() });
    assert_eq!((par.len(), par.edges(), par.complete()), (seq.len(), seq.edges(), seq.complete()), "{threads} threads");
    assert_eq!(par.bounds(), seq.bounds());
    assert_eq!(par.max_tokens(), seq.max_tokens());
    assert_eq!(par.vanishing_count(), seq.vanishing_count());
    assert_eq!(markings(&par), markings(seq));
    let dead = |ss: &mcl_net::explore::StateSpace| {
        let mut v: Vec<Marking> = ss.dead_states().map(|s| ss.marking(s)).collect();
        v.sort();
        v
    };
    assert_eq!(dead(&par), dead(seq));
    assert!(par.path_to(mcl_net::explore::StateId(0)).is_empty(), "state 0 is the initial marking");
    for st in par.states() {
        let mut x = net.initial_marking();
        for t in par.path_to(st) {
            semantics::fire(net, &mut x, t).unwrap();
        }
        assert_eq!(x, par.marking(st));
    }
}

#[test]
fn unordered_threads_find_the_same_state_space() {
    let net = rings(13);
    let seq = explore(&net, &opts(Semantics::Plain));
    for threads in [2, 3, 4] {
        assert_unordered_agrees(&net, &opts(Semantics::Plain), &seq, threads);
    }
    // Widening from 1-bit to 8-bit fields restarts the workers.
    let mut b = NetBuilder::new("fill");
    let budget = b.add_place(Place::new("budget").with_tokens(1));
    let acc = b.add_place(Place::new("acc"));
    let fill = b.add_transition(Transition::new("fill"));
    let drain = b.add_transition(Transition::new("drain"));
    b.add_input(budget, fill, 1).add_output(fill, acc, 40);
    b.add_input(acc, drain, 1);
    let net = b.build().unwrap();
    let seq = explore(&net, &opts(Semantics::Plain));
    assert_unordered_agrees(&net, &opts(Semantics::Plain), &seq, 3);
}

/// More threads than cores on a two-word net whose 104976 states outgrow
/// the shared table several times (rehashed on all threads): threads are
/// descheduled in the middle of inserts and stealing.
#[test]
fn unordered_threads_share_a_growing_table() {
    let net = rings(18);
    let seq = explore(&net, &opts(Semantics::Plain));
    assert_eq!(seq.len(), 18usize.pow(4));
    assert_unordered_agrees(&net, &opts(Semantics::Plain), &seq, 8);
}

#[test]
fn unordered_engine_stops_at_the_state_limit() {
    for threads in [2, 4] {
        let o = Options { max_states: 5000, threads, exact_order: false, ..opts(Semantics::Plain) };
        let ss = explore(&rings(13), &o);
        assert!(ss.len() <= 5000 && !ss.is_empty(), "{} states", ss.len());
        assert_eq!(ss.stop_reason(), Some(StopReason::StateLimit));
        // Stored states are reachable: their paths replay.
        for st in ss.states() {
            let mut x = rings(13).initial_marking();
            for t in ss.path_to(st) {
                semantics::fire(&rings(13), &mut x, t).unwrap();
            }
            assert_eq!(x, ss.marking(st));
        }
    }
}

#[test]
fn wide_markings_use_the_generic_engine() {
    // 70 places of 16 bits: 18 words per marking, beyond the specialised sizes.
    let mut b = NetBuilder::new("wide");
    let p: Vec<_> = (0..70).map(|i| b.add_place(Place::new(format!("p{i}")).with_tokens(200))).collect();
    let t = b.add_transition(Transition::new("move"));
    let u = b.add_transition(Transition::new("back"));
    b.add_input(p[0], t, 1).add_output(t, p[69], 1);
    b.add_input(p[69], u, 2).add_output(u, p[0], 2);
    let net = b.build().unwrap();
    let seq = explore(&net, &opts(Semantics::Plain));
    assert_eq!(seq.bits_per_place(), 16);
    assert_eq!(seq.len(), 401); // p0 + p69 = 400
    let r = reference(&net, Semantics::Plain);
    assert_eq!((seq.len() as u64, seq.edges()), (r.states, r.edges));
    assert_eq!(seq.bounds(), &r.bounds[..]);
    let par = explore(&net, &Options { threads: 2, ..opts(Semantics::Plain) });
    for s in seq.states() {
        assert_eq!(par.marking(s), seq.marking(s));
        assert_eq!(par.path_to(s), seq.path_to(s));
    }
    assert_unordered_agrees(&net, &opts(Semantics::Plain), &seq, 2);
}

#[test]
fn cut_and_coreachability_check_unbounded_blocks() {
    // Figure A.1: P1 grows without bound; cutting at 1 token keeps it finite.
    let net = figure_a1();
    let o = Options { cut_above: Some(1), record_edges: true, ..Options::default() };
    let ss = explore(&net, &o);
    assert!(ss.complete());
    let cut: Vec<_> = ss.cut_states().collect();
    assert!(!cut.is_empty());
    for &s in &cut {
        assert!(ss.marking(s).0.iter().any(|&k| k > 1));
        assert!(ss.successors(s).is_empty());
    }
    let r = mcl_net::explore::report(&net, &ss, 1);
    assert_eq!(r.cut_states, cut.len() as u64);
    assert!(!r.one_safe);
    assert!(!r.deadlock);
    // Every state can reach a cut state (P1 keeps filling up) ...
    assert!(ss.coreachable(|s| cut.contains(&s)).into_iter().all(|b| b));
    // Back to the initial marking: T1 (event) can empty P1 before T3 refills
    // P0, so {P1, P3} leads home; cut states are never expanded.
    let back = ss.coreachable(|s| s == mcl_net::StateId(0));
    assert!(back[0]);
    let p1p3 = ss.states().find(|&s| ss.marking(s).0 == vec![0, 1, 0, 1]).unwrap();
    assert!(back[p1p3.0 as usize]);
    for &s in &cut {
        assert!(!back[s.0 as usize]);
    }
}

#[test]
fn token_overflow_stops_cleanly() {
    let mut b = NetBuilder::new("flood");
    let p = b.add_place(Place::new("p"));
    let t = b.add_transition(Transition::new("gen"));
    b.add_output(t, p, 1 << 31);
    let net = b.build().unwrap();
    for (threads, exact_order) in [(1, true), (2, true), (2, false), (3, false)] {
        let r = analyze(&net, &Options { threads, exact_order, ..opts(Semantics::Plain) });
        assert!(!r.complete);
        assert_eq!(r.stop_reason, Some(StopReason::TokenOverflow));
        assert_eq!(r.states, 2);
    }
}

#[test]
fn empty_net_has_one_dead_state() {
    let net = NetBuilder::new("empty").build().unwrap();
    let r = analyze(&net, &Options::default());
    assert_eq!((r.states, r.edges, r.dead_markings), (1, 0, 1));
    assert!(r.one_safe && r.complete);
}

#[test]
fn report_serializes_to_json() {
    let r = analyze(&figure_a1(), &Options { max_states: 10, ..Options::default() });
    let v = serde_json::to_value(&r).unwrap();
    for key in
        ["states", "edges", "dead_markings", "one_safe", "max_tokens", "max_tokens_per_marking", "bounds", "complete"]
    {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["stop_reason"], "state_limit");
    assert_eq!(v["semantics"], "mcl");
}

// ---------------------------------------------------------------------------
// Reference: a naive BFS over `Marking`s with the `semantics` module.

struct Reference {
    states: u64,
    edges: u64,
    dead: u64,
    vanishing: u64,
    bounds: Vec<u32>,
    max_total: u64,
    depth: HashMap<Marking, usize>,
}

fn reference(net: &Net, s: Semantics) -> Reference {
    let m0 = net.initial_marking();
    let mut depth = HashMap::new();
    depth.insert(m0.clone(), 0usize);
    let mut queue = VecDeque::from([m0]);
    let (mut edges, mut dead, mut vanishing) = (0, 0, 0);
    let mut bounds = vec![0u32; net.place_count()];
    let mut max_total = 0;
    while let Some(m) = queue.pop_front() {
        max_total = max_total.max(m.total());
        for (b, &x) in bounds.iter_mut().zip(&m.0) {
            *b = (*b).max(x);
        }
        let mut ready = semantics::enabled(net, &m);
        if s == Semantics::Mcl && semantics::select_ready(net, &mut ready) == MarkingClass::Vanishing {
            vanishing += 1;
        }
        if ready.is_empty() {
            dead += 1;
        }
        edges += ready.len() as u64;
        let d = depth[&m];
        for t in ready {
            let mut m2 = m.clone();
            semantics::fire(net, &mut m2, t).unwrap();
            if !depth.contains_key(&m2) {
                depth.insert(m2.clone(), d + 1);
                queue.push_back(m2);
            }
        }
    }
    Reference { states: depth.len() as u64, edges, dead, vanishing, bounds, max_total, depth }
}

/// Random bounded nets: a few state-machine components (token conserving)
/// plus extra weighted arcs that may create or destroy tokens.
fn random_net() -> impl Strategy<Value = Net> {
    (
        2usize..9,
        prop::collection::vec((0usize..9, 0usize..9, 0u8..4, 0u32..3), 1..16),
        prop::collection::vec((0usize..9, 0u32..4), 1..10),
        prop::collection::vec((any::<bool>(), 0usize..9, 0usize..16, 1u32..3), 0..4),
    )
        .prop_map(|(np, trans, marks, extra)| build_random(np, &trans, marks, extra, &[]))
}

/// Random nets as [`random_net`] after isolated places holding `pads`
/// tokens: markings of two or three words whose places with independent
/// incidence rows fit in fewer, so the sequential search folds its keys
/// (the kept places of the later words moved into the first one).
fn padded_net() -> impl Strategy<Value = Net> {
    (
        2usize..9,
        prop::collection::vec((0usize..9, 0usize..9, 0u8..4, 0u32..3), 1..16),
        prop::collection::vec((0usize..9, 0u32..4), 1..10),
        prop::collection::vec((any::<bool>(), 0usize..9, 0usize..16, 1u32..3), 0..4),
        prop::collection::vec(0u32..5, 12..40),
    )
        .prop_map(|(np, trans, marks, extra, mut pads)| {
            // 4-bit fields at least: 16 places per word.
            pads[0] = 4;
            build_random(np, &trans, marks, extra, &pads)
        })
}

/// The net of [`random_net`] from its drawn parts, after isolated places
/// holding `pads` tokens.
fn build_random(
    np: usize,
    trans: &[(usize, usize, u8, u32)],
    marks: Vec<(usize, u32)>,
    extra: Vec<(bool, usize, usize, u32)>,
    pads: &[u32],
) -> Net {
    let mut b = NetBuilder::new("random");
    for (i, &x) in pads.iter().enumerate() {
        b.add_place(Place::new(format!("pad{i}")).with_tokens(x));
    }
    let places: Vec<PlaceId> = (0..np).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
    for (p, m) in marks {
        let pl = b.place_mut(places[p % np]).unwrap();
        pl.initial = (pl.initial + m).min(4);
    }
    let mut ts: Vec<TransitionId> = Vec::new();
    for (i, &(from, to, kind, prio)) in trans.iter().enumerate() {
        let kind = match kind {
            0 | 1 => TransitionKind::Immediate,
            2 => TransitionKind::Event("e".into()),
            _ => TransitionKind::Timed(Delay::Fixed(1.0)),
        };
        let mut t = Transition::new(format!("t{i}")).with_kind(kind);
        if prio > 0 {
            t.priority = Some(prio);
        }
        let t = b.add_transition(t);
        b.add_input(places[from % np], t, 1).add_output(t, places[to % np], 1);
        ts.push(t);
    }
    for (input, p, t, w) in extra {
        let (p, t) = (places[p % np], ts[t % ts.len()]);
        if input {
            b.add_input(p, t, w);
        } else {
            // Producing arcs only on transitions that also consume
            // more, to keep most nets bounded.
            b.add_output(t, p, 1).add_input(p, t, w);
        }
    }
    b.build().unwrap()
}

/// Random nets of one-token state machines (a cycle of 3 to 15 places
/// each, the token on the first, and random moves, some synchronised with a
/// second machine), free places holding 0 to 6 tokens that some moves pass
/// on, take or give, and isolated places holding 4 tokens. Markings span two
/// words or more and their independent places more than one, but the
/// machines are one-token groups: the sequential search keys them by one
/// word, linear in the marking. Tokens gathered on a free place may
/// overflow a 4-bit field (restart with wider ones).
fn machines_net() -> impl Strategy<Value = Net> {
    (
        prop::collection::vec(3usize..16, 2..4),
        prop::collection::vec(
            (0usize..4, 0usize..16, 0usize..16, prop::option::of((0usize..4, 0usize..16, 0usize..16))),
            0..12,
        ),
        prop::collection::vec((0usize..16, 0u8..8, 0usize..3, 0usize..3), 0..8),
        prop::collection::vec(0u32..7, 0..3),
        1usize..12,
    )
        .prop_map(|(sizes, moves, free_arcs, free, pads)| {
            let mut b = NetBuilder::new("machines");
            for i in 0..pads {
                b.add_place(Place::new(format!("pad{i}")).with_tokens(4));
            }
            let machines: Vec<Vec<PlaceId>> = sizes
                .iter()
                .enumerate()
                .map(|(m, &n)| {
                    (0..n)
                        .map(|i| b.add_place(Place::new(format!("m{m}_{i}")).with_tokens(u32::from(i == 0))))
                        .collect()
                })
                .collect();
            let free: Vec<PlaceId> = free
                .iter()
                .enumerate()
                .map(|(i, &x)| b.add_place(Place::new(format!("f{i}")).with_tokens(x)))
                .collect();
            let mut ts = Vec::new();
            for (m, places) in machines.iter().enumerate() {
                for i in 0..places.len() {
                    let t = b.add_transition(Transition::new(format!("c{m}_{i}")));
                    b.add_input(places[i], t, 1).add_output(t, places[(i + 1) % places.len()], 1);
                    ts.push(t);
                }
            }
            let nm = machines.len();
            for (i, (a, from, to, sync)) in moves.into_iter().enumerate() {
                let ma = &machines[a % nm];
                let t = b.add_transition(Transition::new(format!("t{i}")));
                b.add_input(ma[from % ma.len()], t, 1).add_output(t, ma[to % ma.len()], 1);
                if let Some((c, from, to)) = sync.filter(|s| s.0 % nm != a % nm) {
                    let mc = &machines[c % nm];
                    b.add_input(mc[from % mc.len()], t, 1).add_output(t, mc[to % mc.len()], 1);
                }
                ts.push(t);
            }
            for (t, mode, f, g) in free_arcs.into_iter().filter(|_| !free.is_empty()) {
                let (t, f, g) = (ts[t % ts.len()], free[f % free.len()], free[g % free.len()]);
                match mode {
                    // Pass a token on (bounded), mostly.
                    0..=4 => {
                        b.add_input(f, t, 1).add_output(t, g, 1);
                    }
                    5 | 6 => {
                        b.add_input(f, t, 1);
                    }
                    _ => {
                        b.add_output(t, g, 1);
                    }
                }
            }
            b.build().unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn linear_keys_find_the_reference_state_space(net in machines_net(), mcl in any::<bool>()) {
        let s = if mcl { Semantics::Mcl } else { Semantics::Plain };
        let o = Options { semantics: s, max_states: 20_000, max_dead_examples: usize::MAX, ..Options::default() };
        let ss = explore(&net, &o);
        prop_assume!(ss.complete());
        let r = reference(&net, s);
        let rep = mcl_net::explore::report(&net, &ss, usize::MAX);
        prop_assert_eq!((rep.states, rep.edges, rep.dead_markings), (r.states, r.edges, r.dead));
        prop_assert_eq!(rep.vanishing_states, r.vanishing);
        prop_assert_eq!(ss.bounds(), &r.bounds[..]);
        prop_assert_eq!(ss.max_tokens(), r.max_total);
        // Numbered as by the search of whole markings (with edges recorded).
        let g = explore(&net, &Options { record_edges: true, ..o.clone() });
        prop_assert_eq!(g.len(), ss.len());
        for st in ss.states() {
            let m = ss.marking(st);
            prop_assert_eq!(ss.path_to(st).len(), r.depth[&m]);
            prop_assert_eq!(g.marking(st), m);
        }
    }

    #[test]
    fn folded_keys_find_the_reference_state_space(net in padded_net(), mcl in any::<bool>()) {
        let s = if mcl { Semantics::Mcl } else { Semantics::Plain };
        let o = Options { semantics: s, max_states: 20_000, max_dead_examples: usize::MAX, ..Options::default() };
        let ss = explore(&net, &o);
        prop_assume!(ss.complete());
        let r = reference(&net, s);
        let rep = mcl_net::explore::report(&net, &ss, usize::MAX);
        prop_assert_eq!((rep.states, rep.edges, rep.dead_markings), (r.states, r.edges, r.dead));
        prop_assert_eq!(rep.vanishing_states, r.vanishing);
        prop_assert_eq!(ss.bounds(), &r.bounds[..]);
        prop_assert_eq!(ss.max_tokens(), r.max_total);
        for st in ss.states() {
            let m = ss.marking(st);
            let path = ss.path_to(st);
            prop_assert_eq!(path.len(), r.depth[&m]);
            let mut x = net.initial_marking();
            for t in path {
                semantics::fire(&net, &mut x, t).unwrap();
            }
            prop_assert_eq!(x, m);
        }
    }

    #[test]
    fn explorer_agrees_with_naive_reference(net in random_net(), mcl in any::<bool>()) {
        let s = if mcl { Semantics::Mcl } else { Semantics::Plain };
        let o = Options { semantics: s, max_states: 20_000, max_dead_examples: usize::MAX, ..Options::default() };
        let ss = explore(&net, &o);
        prop_assume!(ss.complete());
        let r = reference(&net, s);
        let rep = mcl_net::explore::report(&net, &ss, usize::MAX);
        prop_assert_eq!(rep.states, r.states);
        prop_assert_eq!(rep.edges, r.edges);
        prop_assert_eq!(rep.dead_markings, r.dead);
        prop_assert_eq!(rep.vanishing_states, r.vanishing);
        prop_assert_eq!(ss.bounds(), &r.bounds[..]);
        prop_assert_eq!(ss.max_tokens(), r.max_total);
        // Paths are shortest and lead to the stored marking.
        for st in ss.states() {
            let m = ss.marking(st);
            let path = ss.path_to(st);
            prop_assert_eq!(path.len(), r.depth[&m]);
            let mut x = net.initial_marking();
            for t in path {
                semantics::fire(&net, &mut x, t).unwrap();
            }
            prop_assert_eq!(x, m);
        }
        // Recorded edges are exactly the ready transitions and their firings.
        let g = explore(&net, &Options { record_edges: true, ..o.clone() });
        prop_assert_eq!(g.len(), ss.len());
        for st in g.states() {
            let m = g.marking(st);
            let mut ready = semantics::enabled(&net, &m);
            if s == Semantics::Mcl {
                semantics::select_ready(&net, &mut ready);
            }
            let mut want: Vec<(TransitionId, Marking)> = ready
                .into_iter()
                .map(|t| {
                    let mut m2 = m.clone();
                    semantics::fire(&net, &mut m2, t).unwrap();
                    (t, m2)
                })
                .collect();
            let mut got: Vec<(TransitionId, Marking)> =
                g.successors(st).iter().map(|&(t, d)| (t, g.marking(d))).collect();
            want.sort();
            got.sort();
            prop_assert_eq!(got, want);
        }
        // The partitioned engine gives the same state space, numbering included.
        for threads in [2, 3] {
            let par = explore(&net, &Options { threads, ..o.clone() });
            prop_assert_eq!(par.len(), ss.len());
            prop_assert_eq!(par.edges(), ss.edges());
            prop_assert_eq!(par.bounds(), ss.bounds());
            prop_assert_eq!(par.max_tokens(), ss.max_tokens());
            prop_assert!(par.complete());
            prop_assert_eq!(par.dead_states().collect::<Vec<_>>(), ss.dead_states().collect::<Vec<_>>());
            for st in ss.states() {
                prop_assert_eq!(par.marking(st), ss.marking(st));
                prop_assert_eq!(par.path_to(st), ss.path_to(st));
                prop_assert_eq!(par.is_vanishing(st), ss.is_vanishing(st));
            }
        }
        // The unordered engine finds the same states, in another order.
        for threads in [2, 3, 4] {
            assert_unordered_agrees(&net, &o, &ss, threads);
        }
    }
}
