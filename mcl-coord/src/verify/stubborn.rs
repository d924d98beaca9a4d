//! Stubborn sets over the vehicles of the product (partial-order
//! reduction; docs/coordination.md, "Stubborn sets").
//!
//! The vehicles share nothing but the supervisor places. For each class of
//! each reduced vehicle graph, [`Deps`] holds the supervisor places that
//! the edges out of that class read (consumptions, and the gates that a
//! blocked edge waits on) and write (consumptions, productions,
//! take-backs), and the same over every class reachable from it (the
//! vehicle's *future*). A set `S` of vehicles is *closed* in a state when no
//! vehicle outside `S` may, in its future, write a place that the current
//! edges of a vehicle of `S` read or write, nor read a place that they
//! write. Then, for every sequence `w` of moves of vehicles outside `S`
//! and every move `t` of a vehicle of `S` (Valmari's conditions):
//!
//! * D1: `w t` fires from the state iff `t w` does, to the same state (`w`
//!   leaves what `t` reads and writes unchanged, and `t` what `w` reads);
//! * D2: every enabled move of `S` stays enabled after `w` (a key move).
//!
//! Expanding only the moves of `S` (with one enabled) preserves every
//! reachable dead state; with the cycle proviso of `product.rs`, every
//! reachable state can reach a state of the reduced graph, which is what
//! the check that the end stays reachable needs.

use super::lts::{lab_action, lab_blocked};
use super::product::{Effect, Product};
use super::quotient::Quotient;

/// What the edges of a vehicle class do to the supervisor places, as bit
/// sets of `words` words: the places whose tokens they need (a
/// consumption), whose lack of tokens they need (a blocked edge, its
/// gates), that they decrease and that they increase; a take-back (one
/// token if there is one) counts as need, decrease and increase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Set {
    Need,
    Short,
    Dec,
    Inc,
}

/// The sets of each class of each vehicle, for its current edges and for
/// every edge reachable from it (its future).
pub(super) struct Deps {
    words: usize,
    /// Per vehicle, the offset of its class 0 (in classes).
    base: Vec<usize>,
    /// `[Need, Short, Dec, Inc]` of the edges reachable from each class.
    fut: [Vec<u64>; 4],
    /// Production and consumption of one place commute only with exact
    /// counts; `false`, every access of a place conflicts with a write.
    exact: bool,
    /// Per class (offset by `base`): it lies on a cycle of its graph. A
    /// move out of any other class lies on no cycle of the product.
    cyclic: Vec<bool>,
}

impl Deps {
    /// The sets of the vehicles `quots` with the (group-local) `effects`
    /// over `nsups` supervisor places.
    pub(super) fn new(quots: &[&Quotient], effects: &[Effect], nsups: usize, exact: bool) -> Deps {
        let words = nsups.div_ceil(64).max(1);
        let mut base = Vec::with_capacity(quots.len());
        let total: usize = quots.iter().map(|q| q.n).sum();
        let mut cur: [Vec<u64>; 4] = std::array::from_fn(|_| vec![0; total * words]);
        let mut put = |set: Set, k: usize, s: usize| cur[set as usize][k + s / 64] |= 1 << (s % 64);
        let mut at = 0usize;
        for q in quots {
            base.push(at);
            for c in 0..q.n {
                let k = (at + c) * words;
                for &(label, _) in q.out(c as u32) {
                    if let Some(a) = lab_action(label) {
                        let e = &effects[a as usize];
                        for &(s, _) in &e.consume {
                            put(Set::Need, k, s);
                            put(Set::Dec, k, s);
                        }
                        for &(s, _) in &e.produce {
                            put(Set::Inc, k, s);
                        }
                        for &s in &e.take_back {
                            put(Set::Need, k, s);
                            put(Set::Dec, k, s);
                            put(Set::Inc, k, s);
                        }
                    }
                    if lab_blocked(label) {
                        for &g in &q.gates[c] {
                            for &(s, _) in &effects[g as usize].consume {
                                put(Set::Short, k, s);
                            }
                        }
                    }
                }
            }
            at += q.n;
        }
        // The future: a fixpoint over each graph's edges (small graphs).
        let mut fut = cur.clone();
        for (v, q) in quots.iter().enumerate() {
            let b = base[v];
            loop {
                let mut changed = false;
                for c in 0..q.n {
                    for &(_, to) in q.out(c as u32) {
                        let (kc, kt) = ((b + c) * words, (b + to as usize) * words);
                        for f in fut.iter_mut() {
                            for i in 0..words {
                                let x = f[kc + i] | f[kt + i];
                                if x != f[kc + i] {
                                    f[kc + i] = x;
                                    changed = true;
                                }
                            }
                        }
                    }
                }
                if !changed {
                    break;
                }
            }
        }
        // Classes on a cycle: reachable from one of their successors.
        let mut cyclic = vec![false; total];
        for (v, q) in quots.iter().enumerate() {
            for c in 0..q.n as u32 {
                let mut seen = vec![false; q.n];
                let mut stack: Vec<u32> = q.out(c).iter().map(|&(_, to)| to).collect();
                while let Some(x) = stack.pop() {
                    if x == c {
                        cyclic[base[v] + c as usize] = true;
                        break;
                    }
                    if !std::mem::replace(&mut seen[x as usize], true) {
                        stack.extend(q.out(x).iter().map(|&(_, to)| to));
                    }
                }
            }
        }
        Deps { words, base, fut, exact, cyclic }
    }

    /// True when class `c` of vehicle `v` lies on a cycle of its graph.
    pub(super) fn cyclic(&self, v: usize, c: u32) -> bool {
        self.cyclic[self.base[v] + c as usize]
    }

    fn at(&self, v: usize, c: u32) -> usize {
        (self.base[v] + c as usize) * self.words
    }

    /// True when the future of vehicle `w` from class `cw` holds `place`
    /// in `set`.
    fn fut(&self, w: usize, cw: u32, set: Set, place: usize) -> bool {
        self.fut[set as usize][self.at(w, cw) + place / 64] & (1 << (place % 64)) != 0
    }

    /// True when some future move of vehicle `w` (from class `cw`) may
    /// disable, enable or not commute with the enabled move of effect `e`
    /// and gates `short` (the effects of the gates that it needs held), or
    /// be disabled by it. With exact counts, increases and decreases
    /// commute, a decrease cannot falsify a lack of tokens nor an increase
    /// a need of them.
    fn conflicts(&self, e: &Effect, short: &[usize], w: usize, cw: u32) -> bool {
        let writes = |s: usize| self.fut(w, cw, Set::Dec, s) || self.fut(w, cw, Set::Inc, s);
        let tests = |s: usize| self.fut(w, cw, Set::Need, s) || self.fut(w, cw, Set::Short, s);
        let needs = e.consume.iter().map(|&(s, _)| s).chain(e.take_back.iter().copied());
        let incs = e.produce.iter().map(|&(s, _)| s).chain(e.take_back.iter().copied());
        if self.exact {
            needs.clone().chain(short.iter().copied()).any(writes)
                || needs.clone().any(|s| self.fut(w, cw, Set::Need, s))
                || incs.clone().any(|s| self.fut(w, cw, Set::Short, s))
        } else {
            needs.clone().chain(incs.clone()).chain(short.iter().copied()).any(writes) || needs.chain(incs).any(tests)
        }
    }

    /// A stubborn set of vehicles that contains `seed` (which has an
    /// enabled move), in state `st` of product `p`, as a sorted list.
    /// Each vehicle of the set brings, for each enabled move out of its
    /// class, every vehicle whose future conflicts with it; for each
    /// disabled move, the vehicles that may enable it through one reason
    /// of its being disabled (a place short of tokens: the vehicles that
    /// may increase it; an allowed gate of a blocked move: those that may
    /// decrease one of its places), the reason that brings the fewest.
    pub(super) fn closure(&self, p: &Product<'_>, st: &[u32], seed: usize, out: &mut Vec<usize>) {
        out.clear();
        let n = p.nv;
        let mut inside = vec![false; n];
        inside[seed] = true;
        out.push(seed);
        let none = Effect::default();
        let mut short: Vec<usize> = Vec::new();
        let mut cand: Vec<usize> = Vec::new();
        let mut best: Vec<usize> = Vec::new();
        let mut k = 0;
        while k < out.len() {
            let u = out[k];
            k += 1;
            let q = &p.quots[u];
            let c = st[u];
            let allowed_gate = q.gates[c as usize].iter().copied().find(|&g| p.allowed(st, g));
            for &(label, _) in q.out(c) {
                let e = lab_action(label).map_or(&none, |a| &p.effects[a as usize]);
                let blocked = lab_blocked(label);
                let need_ok = lab_action(label).is_none_or(|a| p.allowed(st, a));
                if need_ok && !(blocked && allowed_gate.is_some()) {
                    short.clear();
                    if blocked {
                        for &g in &q.gates[c as usize] {
                            short.extend(p.effects[g as usize].consume.iter().map(|&(s, _)| s));
                        }
                    }
                    for w in 0..n {
                        if !inside[w] && self.conflicts(e, &short, w, st[w]) {
                            inside[w] = true;
                            out.push(w);
                        }
                    }
                    continue;
                }
                // Disabled: the cheapest reason.
                best.clear();
                let mut found = false;
                let reasons =
                    e.consume.iter().filter(|&&(s, wt)| st[p.nv + s] < wt).map(|&(s, _)| (Set::Inc, vec![s])).chain(
                        allowed_gate
                            .filter(|_| blocked)
                            .map(|g| (Set::Dec, p.effects[g as usize].consume.iter().map(|&(s, _)| s).collect())),
                    );
                for (set, places) in reasons {
                    cand.clear();
                    cand.extend(
                        (0..n).filter(|&w| !inside[w] && places.iter().any(|&s: &usize| self.fut(w, st[w], set, s))),
                    );
                    if !found || cand.len() < best.len() {
                        found = true;
                        std::mem::swap(&mut best, &mut cand);
                    }
                }
                for &w in &best {
                    if !inside[w] {
                        inside[w] = true;
                        out.push(w);
                    }
                }
            }
        }
        out.sort_unstable();
    }
}
