//! `mcl_net::explore::explore_por` (stubborn sets, plain rule) against the
//! full plain exploration on random nets: the same dead markings, no more
//! states, and every returned path fires to its dead marking.

use mcl_net::explore::{explore, explore_por, explore_por_examples, Options};
use mcl_net::{semantics, Marking, Net, NetBuilder, Place, PlaceId, Transition, TransitionId};
use proptest::prelude::*;

/// Random nets: state-machine transitions, extra weighted input arcs, and
/// test arcs (an input arc with the same arc back), so that transitions
/// share places they only read as well as places they take from.
fn random_net() -> impl Strategy<Value = Net> {
    (
        2usize..9,
        prop::collection::vec((0usize..9, 0usize..9), 1..14),
        prop::collection::vec((0usize..9, 0u32..3), 1..10),
        prop::collection::vec((0u8..3, 0usize..9, 0usize..14, 1u32..3), 0..6),
    )
        .prop_map(|(np, trans, marks, extra)| {
            let mut b = NetBuilder::new("random");
            let places: Vec<PlaceId> = (0..np).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
            for (p, m) in marks {
                let pl = b.place_mut(places[p % np]).unwrap();
                pl.initial = (pl.initial + m).min(3);
            }
            let ts: Vec<TransitionId> = trans
                .iter()
                .enumerate()
                .map(|(i, &(from, to))| {
                    let t = b.add_transition(Transition::new(format!("t{i}")));
                    b.add_input(places[from % np], t, 1).add_output(t, places[to % np], 1);
                    t
                })
                .collect();
            for (kind, p, t, w) in extra {
                let (p, t) = (places[p % np], ts[t % ts.len()]);
                match kind {
                    0 => {
                        b.add_input(p, t, w);
                    }
                    1 => {
                        b.add_input(p, t, w).add_output(t, p, w);
                    }
                    _ => {
                        b.add_output(t, p, 1).add_input(p, t, w);
                    }
                }
            }
            b.build().unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn stubborn_sets_keep_every_dead_marking(net in random_net()) {
        let full = explore(&net, &Options { max_states: 20_000, ..Options::plain() });
        prop_assume!(full.complete());
        let mut want: Vec<Marking> = full.dead_states().map(|s| full.marking(s)).collect();
        let r = explore_por(&net, 20_000);
        prop_assert!(r.complete);
        prop_assert!(r.states <= full.len() as u64);
        prop_assert_eq!(r.dead_markings, want.len() as u64);
        prop_assert_eq!(r.deadlock, !want.is_empty());
        let (r2, ex) = explore_por_examples(&net, 20_000, usize::MAX, |_| true);
        prop_assert_eq!(&r2, &r);
        let mut got: Vec<Marking> = Vec::new();
        for e in ex {
            let mut m = net.initial_marking();
            for &t in &e.path {
                semantics::fire(&net, &mut m, t).unwrap();
            }
            prop_assert_eq!(&m, &e.marking);
            got.push(m);
        }
        want.sort();
        got.sort();
        prop_assert_eq!(got, want);
    }
}
