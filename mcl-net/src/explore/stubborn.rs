//! Deadlock detection with stubborn sets (partial-order reduction) under
//! the plain P/T rule: `mcl analyze --method por`.
//!
//! In each marking only the enabled transitions of a *stubborn set* are
//! fired (Valmari): starting from one enabled transition, the set is closed
//! under two rules. An enabled transition brings every transition that
//! shares an input place with it (only those can disable it, or be
//! disabled by it); a disabled one brings every transition that adds
//! tokens to one of its insufficiently marked input places (only those can
//! enable it). Then any sequence of transitions outside the set commutes
//! with a transition of the set (D1) and leaves the enabled ones of the set
//! enabled (D2), so every reachable dead marking is reached: the number of
//! dead markings and the deadlock verdict are those of the full state
//! space; the number of states is not (it is the reduced graph's).

use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::model::{Net, PlaceId, TransitionId};
use crate::semantics::is_enabled_with;

/// What a reduced exploration found.
#[derive(Clone, Debug, Serialize, PartialEq, Eq)]
pub struct PorReport {
    /// States of the reduced graph.
    pub states: u64,
    /// Edges of the reduced graph.
    pub edges: u64,
    /// The whole reduced graph was built (under `max_states`).
    pub complete: bool,
    /// Some reachable marking is dead (exact when `complete`).
    pub deadlock: bool,
    /// Reachable dead markings (all of them when `complete`).
    pub dead_markings: u64,
}

/// Explores `net` under the plain rule with stubborn sets, up to
/// `max_states` states.
pub fn explore_por(net: &Net, max_states: usize) -> PorReport {
    let nt = net.transition_count();
    let np = net.place_count();
    // Consumers of each place, and the transitions that add tokens to it.
    let mut consumers: Vec<Vec<u32>> = vec![Vec::new(); np];
    let mut producers: Vec<Vec<u32>> = vec![Vec::new(); np];
    for t in net.transition_ids() {
        for &(p, _) in net.pre(t) {
            consumers[p.index()].push(t.0);
        }
        for &(p, d) in net.delta(t) {
            if d > 0 {
                producers[p.index()].push(t.0);
            }
        }
    }
    let m0: Vec<u32> = net.initial_marking().0.clone();
    let mut index: FxHashMap<Vec<u32>, u32> = FxHashMap::default();
    let mut states: Vec<Vec<u32>> = vec![m0.clone()];
    index.insert(m0, 0);
    let mut report = PorReport { states: 0, edges: 0, complete: true, deadlock: false, dead_markings: 0 };
    let mut in_set = vec![false; nt];
    let mut en_mask = vec![false; nt];
    let mut work: Vec<u32> = Vec::new();
    let mut best: Vec<u32> = Vec::new();
    let mut cand: Vec<u32> = Vec::new();
    let mut i = 0usize;
    while i < states.len() {
        let m = states[i].clone();
        for (t, e) in en_mask.iter_mut().enumerate() {
            *e = is_enabled_with(net, TransitionId(t as u32), |p: PlaceId| m[p.index()]);
        }
        let enabled = |t: u32| en_mask[t as usize];
        let en: Vec<u32> = (0..nt as u32).filter(|&t| enabled(t)).collect();
        if en.is_empty() {
            report.deadlock = true;
            report.dead_markings += 1;
            i += 1;
            continue;
        }
        // The closure from a few seeds; the one with the fewest enabled
        // transitions is fired.
        best.clear();
        let mut best_en = usize::MAX;
        for &seed in en.iter().take(8) {
            cand.clear();
            work.clear();
            work.push(seed);
            in_set[seed as usize] = true;
            while let Some(t) = work.pop() {
                cand.push(t);
                let tid = TransitionId(t);
                let add: &[u32] = if enabled(t) {
                    // Everything that shares an input place.
                    for &(p, _) in net.pre(tid) {
                        for &u in &consumers[p.index()] {
                            if !in_set[u as usize] {
                                in_set[u as usize] = true;
                                work.push(u);
                            }
                        }
                    }
                    &[]
                } else {
                    // The producers of the input place short of tokens
                    // with the fewest producers.
                    net.pre(tid)
                        .iter()
                        .filter(|&&(p, w)| m[p.index()] < w)
                        .map(|&(p, _)| producers[p.index()].as_slice())
                        .min_by_key(|v| v.len())
                        .unwrap_or(&[])
                };
                for &u in add {
                    if !in_set[u as usize] {
                        in_set[u as usize] = true;
                        work.push(u);
                    }
                }
            }
            for &t in &cand {
                in_set[t as usize] = false;
            }
            let n_en = cand.iter().filter(|&&t| enabled(t)).count();
            if n_en < best_en {
                best_en = n_en;
                best.clear();
                best.extend(cand.iter().copied().filter(|&t| enabled(t)));
                if n_en == 1 {
                    break;
                }
            }
        }
        for &t in &best {
            let mut m2 = m.clone();
            let mut overflow = false;
            for &(p, d) in net.delta(TransitionId(t)) {
                let x = i64::from(m2[p.index()]) + d;
                match u32::try_from(x) {
                    Ok(x) => m2[p.index()] = x,
                    Err(_) => overflow = true,
                }
            }
            if overflow {
                report.complete = false;
                continue;
            }
            report.edges += 1;
            if !index.contains_key(&m2) {
                if states.len() >= max_states {
                    report.complete = false;
                    continue;
                }
                index.insert(m2.clone(), states.len() as u32);
                states.push(m2);
            }
        }
        i += 1;
    }
    report.states = states.len() as u64;
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{NetBuilder, Place, Transition};

    #[test]
    fn independent_processes_explore_one_interleaving_and_keep_the_deadlock() {
        // Four independent two-step processes; one ends in a dead place.
        let mut b = NetBuilder::new("n");
        for k in 0..4 {
            let p = b.add_place(Place::new(format!("p{k}")).with_tokens(1));
            let q = b.add_place(Place::new(format!("q{k}")));
            let r = b.add_place(Place::new(format!("r{k}")));
            let t = b.add_transition(Transition::new(format!("t{k}")));
            let u = b.add_transition(Transition::new(format!("u{k}")));
            b.add_input(p, t, 1).add_output(t, q, 1).add_input(q, u, 1).add_output(u, r, 1);
        }
        let net = b.build().unwrap();
        let r = explore_por(&net, 1000);
        assert!(r.complete && r.deadlock);
        assert_eq!(r.dead_markings, 1);
        // 3^4 = 81 markings in full; one path of 8 steps here.
        assert_eq!(r.states, 9);
    }
}
