//! Structural analysis on textbook nets and against brute force.

use mcl_net::structural::{
    incidence, is_siphon, is_trap, max_siphon_within, max_trap_within, minimal_siphons, minimal_siphons_within,
    minimal_traps, p_invariants, t_invariants, Limits,
};
use mcl_net::{Net, NetBuilder, Place, PlaceId, Transition, TransitionId};
use proptest::prelude::*;

fn ids(net: &Net, names: &[&str]) -> Vec<PlaceId> {
    let mut v: Vec<PlaceId> = names.iter().map(|n| net.place_by_id(n).unwrap()).collect();
    v.sort();
    v
}

/// Two processes sharing a mutex.
fn mutex() -> Net {
    let mut b = NetBuilder::new("mutex");
    let m = b.add_place(Place::new("mutex").with_tokens(1));
    for i in 1..=2 {
        let idle = b.add_place(Place::new(format!("idle{i}")).with_tokens(1));
        let cs = b.add_place(Place::new(format!("cs{i}")));
        let enter = b.add_transition(Transition::new(format!("enter{i}")));
        let leave = b.add_transition(Transition::new(format!("leave{i}")));
        b.add_input(idle, enter, 1).add_input(m, enter, 1).add_output(enter, cs, 1);
        b.add_input(cs, leave, 1).add_output(leave, idle, 1).add_output(leave, m, 1);
    }
    b.build().unwrap()
}

/// Dining philosophers taking the left fork, then the right one.
fn philosophers(n: usize) -> Net {
    let mut b = NetBuilder::new(format!("philo{n}"));
    let think: Vec<_> = (0..n).map(|i| b.add_place(Place::new(format!("think{i}")).with_tokens(1))).collect();
    let left: Vec<_> = (0..n).map(|i| b.add_place(Place::new(format!("left{i}")))).collect();
    let eat: Vec<_> = (0..n).map(|i| b.add_place(Place::new(format!("eat{i}")))).collect();
    let fork: Vec<_> = (0..n).map(|i| b.add_place(Place::new(format!("fork{i}")).with_tokens(1))).collect();
    for i in 0..n {
        let j = (i + 1) % n;
        let tl = b.add_transition(Transition::new(format!("takeLeft{i}")));
        let tr = b.add_transition(Transition::new(format!("takeRight{i}")));
        let rel = b.add_transition(Transition::new(format!("release{i}")));
        b.add_input(think[i], tl, 1).add_input(fork[i], tl, 1).add_output(tl, left[i], 1);
        b.add_input(left[i], tr, 1).add_input(fork[j], tr, 1).add_output(tr, eat[i], 1);
        b.add_input(eat[i], rel, 1)
            .add_output(rel, think[i], 1)
            .add_output(rel, fork[i], 1)
            .add_output(rel, fork[j], 1);
    }
    b.build().unwrap()
}

fn unit_invariants(net: &Net, sets: &[&[&str]]) -> Vec<Vec<(PlaceId, u64)>> {
    let mut v: Vec<Vec<(PlaceId, u64)>> =
        sets.iter().map(|s| ids(net, s).into_iter().map(|p| (p, 1)).collect()).collect();
    v.sort();
    v
}

#[test]
fn mutex_invariants_siphons_traps() {
    let net = mutex();
    let l = Limits::default();
    let expected: &[&[&str]] = &[&["idle1", "cs1"], &["idle2", "cs2"], &["mutex", "cs1", "cs2"]];
    let inv = p_invariants(&net, &l);
    assert!(inv.complete);
    assert_eq!(inv.invariants, unit_invariants(&net, expected));
    let mut sets: Vec<Vec<PlaceId>> = expected.iter().map(|s| ids(&net, s)).collect();
    sets.sort();
    let s = minimal_siphons(&net, &l);
    assert!(s.complete);
    assert_eq!(s.sets, sets);
    assert_eq!(minimal_traps(&net, &l).sets, sets);
    // enter_i followed by leave_i reproduces the marking.
    let t = t_invariants(&net, &l);
    assert_eq!(
        t.invariants,
        vec![vec![(TransitionId(0), 1), (TransitionId(1), 1)], vec![(TransitionId(2), 1), (TransitionId(3), 1)],]
    );
}

#[test]
fn seed_figure_a1_incidence_invariant_siphon_trap() {
    let mut b = NetBuilder::new("a1");
    let p: Vec<_> = (0..4).map(|i| b.add_place(Place::new(format!("P{i}")))).collect();
    let t: Vec<_> = (0..4).map(|i| b.add_transition(Transition::new(format!("T{i}")))).collect();
    b.add_input(p[0], t[0], 1).add_output(t[0], p[1], 1).add_output(t[0], p[2], 1);
    b.add_input(p[1], t[1], 1);
    b.add_input(p[2], t[2], 1).add_output(t[2], p[3], 1);
    b.add_input(p[3], t[3], 1).add_output(t[3], p[0], 1);
    let net = b.build().unwrap();
    // D of the seed, equation after (A.2).
    let d = [[-1, 0, 0, 1], [1, -1, 0, 0], [1, 0, -1, 0], [0, 0, 1, -1]];
    let c = incidence(&net);
    for (i, row) in d.iter().enumerate() {
        assert_eq!(c.row(PlaceId(i as u32)), row);
    }
    let l = Limits::default();
    let s = vec![p[0], p[2], p[3]];
    assert_eq!(p_invariants(&net, &l).invariants, vec![s.iter().map(|&x| (x, 1)).collect::<Vec<_>>()]);
    assert!(is_siphon(&net, &s) && is_trap(&net, &s));
    assert_eq!(minimal_siphons(&net, &l).sets, vec![s.clone()]);
    assert_eq!(minimal_traps(&net, &l).sets, vec![s]);
    assert!(!is_siphon(&net, &[p[1]]));
}

#[test]
fn philosophers_deadlock_is_explained_by_an_empty_siphon() {
    for n in [2usize, 3] {
        let net = philosophers(n);
        let l = Limits::default();
        // P-invariants: each philosopher is in one state; each fork is free or held.
        let mut expected: Vec<Vec<String>> = Vec::new();
        for i in 0..n {
            expected.push(vec![format!("think{i}"), format!("left{i}"), format!("eat{i}")]);
            let prev = (i + n - 1) % n;
            expected.push(vec![format!("fork{i}"), format!("left{i}"), format!("eat{i}"), format!("eat{prev}")]);
        }
        let expected: Vec<Vec<&str>> = expected.iter().map(|v| v.iter().map(String::as_str).collect()).collect();
        let refs: Vec<&[&str]> = expected.iter().map(Vec::as_slice).collect();
        let inv = p_invariants(&net, &l);
        assert!(inv.complete);
        assert_eq!(inv.invariants, unit_invariants(&net, &refs), "n = {n}");

        // Every philosopher holding its left fork is the deadlock; the siphon
        // {eat_i, fork_i} is empty there and contains no marked trap.
        let r = mcl_net::analyze(&net, &mcl_net::Options::plain());
        assert_eq!(r.dead_markings, 1);
        let names: Vec<String> = (0..n).flat_map(|i| [format!("eat{i}"), format!("fork{i}")]).collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let s = ids(&net, &names);
        assert!(is_siphon(&net, &s));
        let siphons = minimal_siphons(&net, &l);
        assert!(siphons.complete);
        assert!(siphons.sets.contains(&s), "n = {n}: {:?}", siphons.sets);
        for &(ref place, tokens) in &r.dead_examples[0].marking {
            assert!(place.starts_with("left") && tokens == 1);
        }
        assert!(max_trap_within(&net, &s).is_empty());
        assert_eq!(max_siphon_within(&net, &s), s);
        // Every minimal siphon is a siphon and minimal.
        for set in &siphons.sets {
            assert!(is_siphon(&net, set));
            for k in 0..set.len() {
                let mut smaller = set.clone();
                smaller.remove(k);
                assert!(max_siphon_within(&net, &smaller).is_empty());
            }
        }
    }
}

#[test]
fn siphons_within_an_allowed_set_containing_a_required_place() {
    let net = mutex();
    let l = Limits::default();
    let all: Vec<PlaceId> = net.place_ids().collect();
    // The siphons through the mutex place, then those of the first process.
    let s = minimal_siphons_within(&net, &all, &ids(&net, &["mutex"]), &l);
    assert!(s.complete);
    assert_eq!(s.sets, vec![ids(&net, &["mutex", "cs1", "cs2"])]);
    let s = minimal_siphons_within(&net, &ids(&net, &["idle1", "cs1", "cs2"]), &[], &l);
    assert_eq!(s.sets, vec![ids(&net, &["idle1", "cs1"])]);
    // Not allowed to hold `cs2`: no siphon through the mutex; unknown places are ignored.
    let s = minimal_siphons_within(&net, &ids(&net, &["mutex", "cs1"]), &[ids(&net, &["mutex"])[0], PlaceId(99)], &l);
    assert_eq!((s.sets.len(), s.complete), (0, true));
}

#[test]
fn caps_are_reported() {
    let net = philosophers(3);
    let tiny = Limits { max_rows: 1, max_nodes: 2, max_results: 1 };
    assert!(!p_invariants(&net, &tiny).complete);
    assert!(!minimal_siphons(&net, &tiny).complete);
    assert!(!minimal_traps(&net, &tiny).complete);
}

// ---------------------------------------------------------------------------
// Brute force on small random nets.

fn random_net() -> impl Strategy<Value = Net> {
    (1usize..8, 1usize..7, prop::collection::vec((any::<bool>(), 0usize..8, 0usize..7, 1u32..3), 0..18)).prop_map(
        |(np, nt, arcs)| {
            let mut b = NetBuilder::new("r");
            let ps: Vec<_> = (0..np).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
            let ts: Vec<_> = (0..nt).map(|i| b.add_transition(Transition::new(format!("t{i}")))).collect();
            for (input, p, t, w) in arcs {
                let (p, t) = (ps[p % np], ts[t % nt]);
                if input {
                    b.add_input(p, t, w);
                } else {
                    b.add_output(t, p, w);
                }
            }
            b.build().unwrap()
        },
    )
}

fn subsets(n: usize) -> impl Iterator<Item = Vec<PlaceId>> {
    (1u32..(1 << n)).map(move |mask| (0..n as u32).filter(|i| mask & (1 << i) != 0).map(PlaceId).collect())
}

fn brute_minimal(net: &Net, pred: impl Fn(&Net, &[PlaceId]) -> bool) -> Vec<Vec<PlaceId>> {
    let all: Vec<Vec<PlaceId>> = subsets(net.place_count()).filter(|s| pred(net, s)).collect();
    let mut min: Vec<Vec<PlaceId>> = all
        .iter()
        .filter(|s| !all.iter().any(|o| o.len() < s.len() && o.iter().all(|p| s.contains(p))))
        .cloned()
        .collect();
    min.sort();
    min
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn siphons_and_traps_match_brute_force(net in random_net()) {
        let l = Limits::default();
        let s = minimal_siphons(&net, &l);
        prop_assert!(s.complete);
        prop_assert_eq!(s.sets, brute_minimal(&net, is_siphon));
        let t = minimal_traps(&net, &l);
        prop_assert!(t.complete);
        prop_assert_eq!(t.sets, brute_minimal(&net, is_trap));
    }

    #[test]
    fn siphons_within_match_brute_force(net in random_net(), allowed in any::<u8>(), required in any::<u8>()) {
        let pick = |mask: u8| -> Vec<PlaceId> {
            net.place_ids().filter(|p| mask & (1 << p.index()) != 0).collect()
        };
        let (allowed, required) = (pick(allowed), pick(required));
        let s = minimal_siphons_within(&net, &allowed, &required, &Limits::default());
        prop_assert!(s.complete);
        let expected: Vec<Vec<PlaceId>> = brute_minimal(&net, is_siphon)
            .into_iter()
            .filter(|s| s.iter().all(|p| allowed.contains(p)))
            .filter(|s| required.is_empty() || s.iter().any(|p| required.contains(p)))
            .collect();
        prop_assert_eq!(s.sets, expected);
    }

    #[test]
    fn invariants_are_valid_minimal_and_complete(net in random_net()) {
        let c = incidence(&net);
        let inv = p_invariants(&net, &Limits::default());
        prop_assert!(inv.complete);
        let np = net.place_count();
        for y in &inv.invariants {
            for t in net.transition_ids() {
                let s: i64 = y.iter().map(|&(p, w)| w as i64 * c.get(p, t)).sum();
                prop_assert_eq!(s, 0);
            }
            let g = y.iter().fold(0u64, |g, &(_, w)| gcd(g, w));
            prop_assert_eq!(g, 1);
            for z in &inv.invariants {
                if z != y {
                    prop_assert!(!z.iter().all(|(p, _)| y.iter().any(|(q, _)| q == p)));
                }
            }
        }
        // Every invariant with weights in 0..=2 has a returned one under its support.
        let mut y = vec![0i64; np];
        loop {
            let mut k = 0;
            while k < np && y[k] == 2 { y[k] = 0; k += 1; }
            if k == np { break; }
            y[k] += 1;
            let is_inv = net.transition_ids().all(|t| (0..np).map(|p| y[p] * c.get(PlaceId(p as u32), t)).sum::<i64>() == 0);
            if is_inv {
                let covered = inv.invariants.iter().any(|z| z.iter().all(|&(p, _)| y[p.index()] > 0));
                prop_assert!(covered, "{:?} not covered by {:?}", y, inv.invariants);
            }
        }
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}
