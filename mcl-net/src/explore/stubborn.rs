//! Deadlock detection with stubborn sets (partial-order reduction) under
//! the plain P/T rule: `mcl analyze --method por`.
//!
//! In each marking only the enabled transitions of a *stubborn set* are
//! fired (Valmari), a set closed under two rules:
//!
//! * an enabled transition `t` brings every transition `u` that can disable
//!   it or that it can disable: `u` shares an input place `p` with `t` and
//!   one of the two takes tokens from `p` (two transitions that only test
//!   `p`, with an arc back, neither disable nor need each other);
//! * a disabled one brings every transition that adds tokens to one of its
//!   insufficiently marked input places (only those can enable it), the
//!   *scapegoat*: the place whose producers bring the fewest new enabled
//!   transitions, then the fewest new transitions.
//!
//! Then any sequence of transitions outside the set commutes with a
//! transition of the set (D1: an outside transition needs no place that
//! the set's transition takes from, and takes from no place it needs) and
//! leaves the enabled ones of the set enabled (D2), so every reachable dead
//! marking is reached: the number of dead markings and the deadlock verdict
//! are those of the full state space; the number of states is not (it is
//! the reduced graph's). The closure is computed from every enabled
//! transition, and the one with the fewest enabled transitions is fired.
//!
//! Markings are stored packed (`pack`: the marked places only, as
//! variable-length gaps and counts), with one parent link per state, so
//! that a dead marking comes with a path from the initial marking
//! ([`explore_por_examples`]).

use rustc_hash::FxHasher;
use serde::Serialize;
use std::hash::Hasher;

use crate::model::{Marking, Net, PlaceId, TransitionId};
use crate::semantics::{covers, fire};

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

/// A reachable dead marking and a firing sequence from the initial marking
/// that reaches it (in the reduced graph, so not always a shortest one).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeadExample {
    /// The dead marking.
    pub marking: Marking,
    /// The transitions fired from the initial marking.
    pub path: Vec<TransitionId>,
}

/// Explores `net` under the plain rule with stubborn sets, up to
/// `max_states` states.
pub fn explore_por(net: &Net, max_states: usize) -> PorReport {
    explore_por_examples(net, max_states, 0, |_| false).0
}

/// [`explore_por`], also returning up to `max_examples` dead markings for
/// which `wanted` holds, each with its path.
pub fn explore_por_examples(
    net: &Net,
    max_states: usize,
    max_examples: usize,
    mut wanted: impl FnMut(&Marking) -> bool,
) -> (PorReport, Vec<DeadExample>) {
    let arcs = Arcs::new(net);
    let np = net.place_count();
    let mut store = Store::default();
    let m0 = net.initial_marking().0;
    let mut buf = Vec::new();
    pack(&m0, &mut buf);
    store.insert(&buf, u32::MAX, u32::MAX);
    let mut report = PorReport { states: 0, edges: 0, complete: true, deadlock: false, dead_markings: 0 };
    let mut examples = Vec::new();
    let mut m = vec![0u32; np];
    let mut marked: Vec<u32> = Vec::new();
    let mut closure = Closure::new(net.transition_count());
    let mut i = 0usize;
    while i < store.len() {
        unpack(store.get(i), &mut m, &mut marked);
        closure.enabled(&arcs, &m, &marked);
        if closure.en.is_empty() {
            report.deadlock = true;
            report.dead_markings += 1;
            if examples.len() < max_examples {
                let marking = Marking(m.clone());
                if wanted(&marking) {
                    examples.push(DeadExample { marking, path: store.path(i) });
                }
            }
        } else {
            closure.best(&arcs, &m);
            for k in 0..closure.best.len() {
                let t = closure.best[k];
                let mut m2 = Marking(m.clone());
                if fire(net, &mut m2, TransitionId(t)).is_err() {
                    // `t` is enabled: a place would pass `u32::MAX`.
                    report.complete = false;
                    continue;
                }
                report.edges += 1;
                pack(&m2.0, &mut buf);
                if store.find(&buf).is_none() {
                    if store.len() >= max_states {
                        report.complete = false;
                        continue;
                    }
                    store.insert(&buf, i as u32, t);
                }
            }
        }
        for &p in &marked {
            m[p as usize] = 0;
        }
        i += 1;
    }
    report.states = store.len() as u64;
    (report, examples)
}

/// The arcs the closure reads, flattened.
struct Arcs {
    /// Per transition: its input places, weights, and whether it takes
    /// tokens from the place (`post < pre`).
    pre: Vec<Vec<(u32, u32, bool)>>,
    /// Per place: its consumers and whether each takes tokens from it.
    consumers: Vec<Vec<(u32, bool)>>,
    /// Per place: the transitions that add tokens to it.
    producers: Vec<Vec<u32>>,
    /// Transitions without input places (always enabled).
    free: Vec<u32>,
}

impl Arcs {
    fn new(net: &Net) -> Self {
        let np = net.place_count();
        let mut pre = Vec::with_capacity(net.transition_count());
        let mut consumers: Vec<Vec<(u32, bool)>> = vec![Vec::new(); np];
        let mut producers: Vec<Vec<u32>> = vec![Vec::new(); np];
        let mut free = Vec::new();
        for t in net.transition_ids() {
            let delta = net.delta(t);
            let takes = |p: PlaceId| delta.iter().any(|&(q, d)| q == p && d < 0);
            let row: Vec<(u32, u32, bool)> = net.pre(t).iter().map(|&(p, w)| (p.0, w, takes(p))).collect();
            for &(p, _, k) in &row {
                consumers[p as usize].push((t.0, k));
            }
            if row.is_empty() {
                free.push(t.0);
            }
            pre.push(row);
            for &(p, d) in delta {
                if d > 0 {
                    producers[p.index()].push(t.0);
                }
            }
        }
        Arcs { pre, consumers, producers, free }
    }

    fn is_enabled(&self, t: u32, m: &[u32]) -> bool {
        covers(self.pre[t as usize].iter().map(|&(p, w, _)| (p, w)), |p| m[p as usize])
    }
}

/// Buffers of the stubborn-set computation.
struct Closure {
    /// Enabled transitions of the current marking.
    en: Vec<u32>,
    /// Per transition: enabled in the current marking.
    en_mask: Vec<bool>,
    /// Per transition: in the set being closed.
    in_set: Vec<bool>,
    work: Vec<u32>,
    cand: Vec<u32>,
    /// The enabled transitions of the smallest set found.
    best: Vec<u32>,
}

impl Closure {
    fn new(nt: usize) -> Self {
        Closure {
            en: Vec::new(),
            en_mask: vec![false; nt],
            in_set: vec![false; nt],
            work: Vec::new(),
            cand: Vec::new(),
            best: Vec::new(),
        }
    }

    /// Fills `en` and `en_mask` from the consumers of the marked places.
    fn enabled(&mut self, arcs: &Arcs, m: &[u32], marked: &[u32]) {
        for &t in &self.en {
            self.en_mask[t as usize] = false;
        }
        self.en.clear();
        for &p in marked {
            for &(t, _) in &arcs.consumers[p as usize] {
                if !self.en_mask[t as usize] && arcs.is_enabled(t, m) {
                    self.en_mask[t as usize] = true;
                    self.en.push(t);
                }
            }
        }
        for &t in &arcs.free {
            self.en_mask[t as usize] = true;
            self.en.push(t);
        }
        self.en.sort_unstable();
    }

    /// The enabled transitions of the stubborn set with the fewest of them,
    /// over the closures of every enabled transition, into `best`.
    fn best(&mut self, arcs: &Arcs, m: &[u32]) {
        self.best.clear();
        let mut best_en = usize::MAX;
        for k in 0..self.en.len() {
            let seed = self.en[k];
            if let Some(n) = self.close(arcs, m, seed, best_en) {
                best_en = n;
                self.best.clear();
                self.best.extend(self.cand.iter().copied().filter(|&t| self.en_mask[t as usize]));
            }
            for &t in &self.cand {
                self.in_set[t as usize] = false;
            }
            if best_en == 1 {
                break;
            }
        }
    }

    fn add(&mut self, u: u32) {
        if !self.in_set[u as usize] {
            self.in_set[u as usize] = true;
            self.work.push(u);
            self.cand.push(u);
        }
    }

    /// Closes `{seed}` into `cand`; `None` as soon as it holds `bound`
    /// enabled transitions, else their number.
    fn close(&mut self, arcs: &Arcs, m: &[u32], seed: u32, bound: usize) -> Option<usize> {
        self.cand.clear();
        self.work.clear();
        self.add(seed);
        let mut n_en = 0usize;
        while let Some(t) = self.work.pop() {
            if self.en_mask[t as usize] {
                n_en += 1;
                if n_en >= bound {
                    return None;
                }
                for &(p, _, takes) in &arcs.pre[t as usize] {
                    for &(u, u_takes) in &arcs.consumers[p as usize] {
                        if takes || u_takes {
                            self.add(u);
                        }
                    }
                }
            } else {
                let place = self.scapegoat(arcs, m, t);
                for &u in &arcs.producers[place as usize] {
                    self.add(u);
                }
            }
        }
        Some(n_en)
    }

    /// The insufficiently marked input place of the disabled `t` whose
    /// producers add the fewest enabled, then the fewest, new transitions.
    fn scapegoat(&self, arcs: &Arcs, m: &[u32], t: u32) -> u32 {
        let mut best = (usize::MAX, usize::MAX, u32::MAX);
        for &(p, w, _) in &arcs.pre[t as usize] {
            if m[p as usize] >= w {
                continue;
            }
            let (mut new_en, mut new) = (0, 0);
            for &u in &arcs.producers[p as usize] {
                if !self.in_set[u as usize] {
                    new += 1;
                    new_en += usize::from(self.en_mask[u as usize]);
                }
            }
            if (new_en, new) < (best.0, best.1) {
                best = (new_en, new, p);
                if new == 0 {
                    break;
                }
            }
        }
        best.2
    }
}

/// Markings packed one after another, with a parent link each and an
/// open-addressing table of their indices.
#[derive(Default)]
struct Store {
    bytes: Vec<u8>,
    /// Start of each marking in `bytes` (one more entry: the end).
    starts: Vec<usize>,
    /// Per state: the state it was first reached from and the transition.
    parent: Vec<(u32, u32)>,
    /// State index + 1, 0 when empty.
    table: Vec<u32>,
}

impl Store {
    fn len(&self) -> usize {
        self.parent.len()
    }

    fn get(&self, i: usize) -> &[u8] {
        &self.bytes[self.starts[i]..self.starts[i + 1]]
    }

    fn hash(key: &[u8]) -> usize {
        let mut h = FxHasher::default();
        h.write(key);
        h.finish() as usize
    }

    fn find(&self, key: &[u8]) -> Option<usize> {
        if self.table.is_empty() {
            return None;
        }
        let mask = self.table.len() - 1;
        let mut s = Self::hash(key) & mask;
        loop {
            match self.table[s] {
                0 => return None,
                x if self.get(x as usize - 1) == key => return Some(x as usize - 1),
                _ => s = (s + 1) & mask,
            }
        }
    }

    /// Adds a marking known to be new.
    fn insert(&mut self, key: &[u8], parent: u32, via: u32) {
        if self.starts.is_empty() {
            self.starts.push(0);
        }
        if 2 * (self.len() + 1) > self.table.len() {
            self.grow();
        }
        self.bytes.extend_from_slice(key);
        self.starts.push(self.bytes.len());
        self.parent.push((parent, via));
        let n = self.len();
        self.place(n - 1);
    }

    fn place(&mut self, i: usize) {
        let mask = self.table.len() - 1;
        let mut s = Self::hash(self.get(i)) & mask;
        while self.table[s] != 0 {
            s = (s + 1) & mask;
        }
        self.table[s] = i as u32 + 1;
    }

    fn grow(&mut self) {
        self.table = vec![0; (2 * self.table.len()).max(1024)];
        for i in 0..self.len() {
            self.place(i);
        }
    }

    /// The transitions from the initial marking to state `i`.
    fn path(&self, mut i: usize) -> Vec<TransitionId> {
        let mut path = Vec::new();
        while self.parent[i].0 != u32::MAX {
            path.push(TransitionId(self.parent[i].1));
            i = self.parent[i].0 as usize;
        }
        path.reverse();
        path
    }
}

fn put_varint(out: &mut Vec<u8>, mut x: u64) {
    while x >= 0x80 {
        out.push((x as u8) | 0x80);
        x >>= 7;
    }
    out.push(x as u8);
}

fn get_varint(bytes: &[u8], at: &mut usize) -> u64 {
    let (mut x, mut shift) = (0u64, 0);
    loop {
        let b = bytes[*at];
        *at += 1;
        x |= u64::from(b & 0x7f) << shift;
        if b < 0x80 {
            return x;
        }
        shift += 7;
    }
}

/// The marked places of `m` as (gap from the previous one, tokens − 1).
fn pack(m: &[u32], out: &mut Vec<u8>) {
    out.clear();
    let mut next = 0usize;
    for (p, &x) in m.iter().enumerate() {
        if x > 0 {
            put_varint(out, (p - next) as u64);
            put_varint(out, u64::from(x - 1));
            next = p + 1;
        }
    }
}

/// Writes the packed marking into `m` (all zeros) and lists its marked
/// places in `marked`.
fn unpack(bytes: &[u8], m: &mut [u32], marked: &mut Vec<u32>) {
    marked.clear();
    let (mut at, mut next) = (0usize, 0usize);
    while at < bytes.len() {
        let p = next + get_varint(bytes, &mut at) as usize;
        m[p] = get_varint(bytes, &mut at) as u32 + 1;
        marked.push(p as u32);
        next = p + 1;
    }
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
        let (_, ex) = explore_por_examples(&net, 1000, 5, |_| true);
        assert_eq!(ex.len(), 1);
        let mut m = net.initial_marking();
        for &t in &ex[0].path {
            crate::semantics::fire(&net, &mut m, t).unwrap();
        }
        assert_eq!(m, ex[0].marking);
        assert!(crate::semantics::enabled(&net, &m).is_empty());
    }

    #[test]
    fn readers_of_a_place_do_not_conflict() {
        // Three transitions test `flag` (arc back) and each move their own
        // token; `clear` would take `flag` but waits for `go`, never marked.
        let mut b = NetBuilder::new("n");
        let flag = b.add_place(Place::new("flag").with_tokens(1));
        for k in 0..3 {
            let p = b.add_place(Place::new(format!("p{k}")).with_tokens(1));
            let q = b.add_place(Place::new(format!("q{k}")));
            let t = b.add_transition(Transition::new(format!("t{k}")));
            b.add_input(p, t, 1).add_input(flag, t, 1).add_output(t, flag, 1).add_output(t, q, 1);
        }
        let go = b.add_place(Place::new("go"));
        let clear = b.add_transition(Transition::new("clear"));
        b.add_input(flag, clear, 1).add_input(go, clear, 1);
        let net = b.build().unwrap();
        let r = explore_por(&net, 1000);
        let full = crate::explore::analyze(&net, &crate::explore::Options::plain());
        assert!(r.complete);
        assert_eq!(r.dead_markings, full.dead_markings);
        assert_eq!(r.dead_markings, 1);
        // One interleaving of the readers instead of all 2^3 markings.
        assert_eq!(full.states, 8);
        assert_eq!(r.states, 4);
    }

    #[test]
    fn packed_markings_round_trip() {
        let m = vec![0, 3, 0, 0, 1, 200, 0, 70_000, 1];
        let mut buf = Vec::new();
        pack(&m, &mut buf);
        let (mut back, mut marked) = (vec![0; m.len()], Vec::new());
        unpack(&buf, &mut back, &mut marked);
        assert_eq!(back, m);
        assert_eq!(marked, vec![1, 4, 5, 7, 8]);
    }
}
