//! The decision-diagram exploration (`explore_symbolic`) against the
//! explicit one on random nets, and its limits on unbounded nets.

use mcl_net::explore::symbolic::{SymbolicStop, VariableOrder};
use mcl_net::explore::{explore_symbolic, SymbolicOptions};
use mcl_net::{analyze, semantics, Net, NetBuilder, Options, Place, PlaceId, Transition, TransitionId};
use proptest::prelude::*;

#[test]
fn unbounded_place_stops_at_the_token_limit() {
    let mut b = NetBuilder::new("counter");
    let run = b.add_place(Place::new("run").with_tokens(1));
    let count = b.add_place(Place::new("count"));
    let t = b.add_transition(Transition::new("tick"));
    b.add_input(run, t, 1).add_output(t, run, 1).add_output(t, count, 1);
    let net = b.build().unwrap();
    let r = explore_symbolic(&net, &SymbolicOptions { max_tokens: 1000, ..SymbolicOptions::default() });
    assert!(!r.complete);
    assert_eq!(r.stop, Some(SymbolicStop::TokenLimit { place: "count".into(), max_tokens: 1000 }));
    assert_eq!(r.states, Some(0), "no counts when incomplete");
}

#[test]
fn empty_net_has_one_dead_marking() {
    let net = NetBuilder::new("empty").build().unwrap();
    let r = explore_symbolic(&net, &SymbolicOptions::default());
    assert!(r.complete && r.deadlock && r.one_safe);
    assert_eq!((r.states, r.edges, r.dead_markings), (Some(1), Some(0), Some(1)));
    assert_eq!(r.dead_example.map(|d| d.path.len()), Some(0));
}

/// A dead marking that marks a place of every terminal group is an end,
/// not a deadlock.
#[test]
fn terminal_markings_are_not_deadlocks() {
    let mut b = NetBuilder::new("choice");
    let start = b.add_place(Place::new("start").with_tokens(1));
    let done = b.add_place(Place::new("done"));
    let stuck = b.add_place(Place::new("stuck"));
    let finish = b.add_transition(Transition::new("finish"));
    let fail = b.add_transition(Transition::new("fail"));
    b.add_input(start, finish, 1).add_output(finish, done, 1);
    b.add_input(start, fail, 1).add_output(fail, stuck, 1);
    let net = b.build().unwrap();
    let plain = explore_symbolic(&net, &SymbolicOptions::default());
    assert_eq!((plain.dead_markings, plain.terminal_markings), (Some(2), Some(0)));
    let o = SymbolicOptions { terminal: vec![vec![done, PlaceId(99)]], ..SymbolicOptions::default() };
    let r = explore_symbolic(&net, &o);
    assert!(r.deadlock);
    assert_eq!((r.dead_markings, r.terminal_markings), (Some(2), Some(1)));
    assert_eq!(r.dead_example.unwrap().path_names, vec!["fail".to_string()]);
    let o = SymbolicOptions { terminal: vec![vec![done, stuck]], ..SymbolicOptions::default() };
    let r = explore_symbolic(&net, &o);
    assert!(!r.deadlock && r.dead_example.is_none());
    assert_eq!(r.terminal_markings, Some(2));
}

/// Random bounded nets: state-machine transitions plus weighted arcs that
/// may create or destroy tokens, self-loops (read arcs), and transitions
/// without inputs or outputs.
fn random_net() -> impl Strategy<Value = Net> {
    (
        1usize..8,
        prop::collection::vec((0usize..8, 0usize..8), 1..14),
        prop::collection::vec((0usize..8, 0u32..4), 1..8),
        prop::collection::vec((0u8..3, 0usize..8, 0usize..14, 1u32..3), 0..5),
    )
        .prop_map(|(np, trans, marks, extra)| {
            let mut b = NetBuilder::new("random");
            let places: Vec<PlaceId> = (0..np).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
            for (p, m) in marks {
                let pl = b.place_mut(places[p % np]).unwrap();
                pl.initial = (pl.initial + m).min(4);
            }
            let mut ts: Vec<TransitionId> = Vec::new();
            for (i, &(from, to)) in trans.iter().enumerate() {
                let t = b.add_transition(Transition::new(format!("t{i}")));
                b.add_input(places[from % np], t, 1).add_output(t, places[to % np], 1);
                ts.push(t);
            }
            for (kind, p, t, w) in extra {
                let (p, t) = (places[p % np], ts[t % ts.len()]);
                match kind {
                    0 => {
                        b.add_input(p, t, w);
                    }
                    1 => {
                        b.add_output(t, p, 1).add_input(p, t, w);
                    }
                    _ => {
                        b.add_input(p, t, w).add_output(t, p, w);
                    }
                }
            }
            b.build().unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Counts, verdicts and bounds of the explicit search, in both orders,
    /// with and without grouping; the dead example replays to a dead
    /// marking by a shortest path.
    #[test]
    fn symbolic_agrees_with_explicit(net in random_net(), pnml in any::<bool>(), group in any::<bool>()) {
        let o = Options { max_states: 20_000, ..Options::plain() };
        let e = analyze(&net, &o);
        prop_assume!(e.complete);
        let order = if pnml { VariableOrder::Pnml } else { VariableOrder::Force };
        let r = explore_symbolic(&net, &SymbolicOptions { order, group, ..SymbolicOptions::default() });
        prop_assert!(r.complete);
        prop_assert_eq!(r.states, Some(u128::from(e.states)));
        prop_assert_eq!(r.edges, Some(u128::from(e.edges)));
        prop_assert_eq!(r.dead_markings, Some(u128::from(e.dead_markings)));
        prop_assert_eq!(r.deadlock, e.deadlock);
        prop_assert_eq!(r.one_safe, e.one_safe);
        let bounds: Vec<u32> = e.bounds.iter().map(|b| b.bound).collect();
        prop_assert_eq!(&r.bounds, &bounds);
        prop_assert_eq!(r.max_tokens_per_marking, e.max_tokens_per_marking);
        prop_assert_eq!(r.dead_example.is_some(), e.deadlock);
        if let Some(d) = &r.dead_example {
            let mut m = net.initial_marking();
            for &t in &d.path {
                semantics::fire(&net, &mut m, t).unwrap();
            }
            prop_assert!(semantics::enabled(&net, &m).is_empty());
            let shortest = e.dead_examples.iter().map(|x| x.path.len()).min().unwrap();
            prop_assert_eq!(d.path.len(), shortest);
        }
    }

    /// Grouping mutually exclusive places changes the levels, not the
    /// answer: the same counts, bounds, verdicts (terminal groups
    /// included) and dead example length as one level per place.
    #[test]
    fn grouping_keeps_the_answer(net in one_token_net(), pnml in any::<bool>(), terminal in prop::collection::vec(0usize..8, 0..3)) {
        let order = if pnml { VariableOrder::Pnml } else { VariableOrder::Force };
        let places: Vec<PlaceId> = net.place_ids().collect();
        let terminal = if terminal.is_empty() {
            Vec::new()
        } else {
            vec![terminal.iter().map(|&i| places[i % places.len()]).collect()]
        };
        let opts = SymbolicOptions { order, terminal, ..SymbolicOptions::default() };
        let grouped = explore_symbolic(&net, &opts);
        let flat = explore_symbolic(&net, &SymbolicOptions { group: false, ..opts });
        prop_assert!(grouped.complete && flat.complete);
        prop_assert!(grouped.levels <= flat.levels);
        prop_assert_eq!(flat.levels, net.place_count());
        prop_assert_eq!(grouped.states, flat.states);
        prop_assert_eq!(grouped.edges, flat.edges);
        prop_assert_eq!(grouped.dead_markings, flat.dead_markings);
        prop_assert_eq!(grouped.terminal_markings, flat.terminal_markings);
        prop_assert_eq!(grouped.deadlock, flat.deadlock);
        prop_assert_eq!(&grouped.bounds, &flat.bounds);
        prop_assert_eq!(grouped.max_tokens_per_marking, flat.max_tokens_per_marking);
        prop_assert_eq!(
            grouped.dead_example.as_ref().map(|d| d.path.len()),
            flat.dead_example.as_ref().map(|d| d.path.len())
        );
    }
}

/// Random nets made of one-token state machines (each a cycle of places
/// with one token, so a group) synchronised by shared transitions, plus a
/// few extra arcs (a pool of two tokens, read arcs of weight 1 or 2, arcs
/// that lose a machine's token): nets that grouping changes.
fn one_token_net() -> impl Strategy<Value = Net> {
    (
        prop::collection::vec(2usize..5, 1..4),
        prop::collection::vec((0usize..4, 0usize..5, 0usize..4, 0usize..5), 0..6),
        prop::collection::vec((0u8..3, 0usize..20, 0usize..12, 1u32..3), 0..4),
    )
        .prop_map(|(sizes, syncs, extra)| {
            let mut b = NetBuilder::new("machines");
            let mut places: Vec<Vec<PlaceId>> = Vec::new();
            let mut ts: Vec<TransitionId> = Vec::new();
            for (m, &n) in sizes.iter().enumerate() {
                let ps: Vec<PlaceId> = (0..n)
                    .map(|i| b.add_place(Place::new(format!("m{m}_{i}")).with_tokens(u32::from(i == 0))))
                    .collect();
                for i in 0..n {
                    let t = b.add_transition(Transition::new(format!("m{m}_t{i}")));
                    b.add_input(ps[i], t, 1).add_output(t, ps[(i + 1) % n], 1);
                    ts.push(t);
                }
                places.push(ps);
            }
            // A step of machine a synchronised with a step of machine b.
            for (k, &(a, i, c, j)) in syncs.iter().enumerate() {
                let (a, c) = (&places[a % places.len()], &places[c % places.len()]);
                let (i, j) = (i % a.len(), j % c.len());
                let t = b.add_transition(Transition::new(format!("sync{k}")));
                b.add_input(a[i], t, 1).add_output(t, a[(i + 1) % a.len()], 1);
                if c != a {
                    b.add_input(c[j], t, 1).add_output(t, c[(j + 1) % c.len()], 1);
                }
                ts.push(t);
            }
            let all: Vec<PlaceId> = places.iter().flatten().copied().collect();
            // A pool of two tokens (a semiflow of two tokens: no group).
            let free = b.add_place(Place::new("free").with_tokens(2));
            let used = b.add_place(Place::new("used"));
            let release = b.add_transition(Transition::new("release"));
            b.add_input(used, release, 1).add_output(release, free, 1);
            for (kind, p, t, w) in extra {
                let t = ts[t % ts.len()];
                match kind {
                    0 => {
                        b.add_input(free, t, w).add_output(t, used, w);
                    }
                    1 => {
                        b.add_input(all[p % all.len()], t, w).add_output(t, all[p % all.len()], w);
                    }
                    _ => {
                        b.add_input(all[p % all.len()], t, 1);
                    }
                }
            }
            b.build().unwrap()
        })
}
