//! A proof of deadlock freedom for a group of vehicles without exploring
//! their product (issue 17): the state equation of the product of the
//! reduced vehicle graphs, solved as a finite constraint problem.
//!
//! A state of the product is one class per vehicle and a count per
//! supervisor place. When every vehicle's reduced graph is acyclic (no
//! loop in the mission: the generated fleets and most missions), the
//! effect of a path on the supervisor places is a sum over its edges, and
//! every reachable state `(c_1, …, c_n, s)` satisfies the *state equation*
//!
//! ```text
//! s = s0 + Σ_v Δ_v,   Δ_v the effect of some path of vehicle v from its
//!                      initial class to c_v (in its graph alone),   s ≥ 0.
//! ```
//!
//! A *dead* state (no move of any vehicle: every edge out of `c_v` is
//! blocked by its guard while some waiting start is allowed, or consumes
//! from a place short of tokens; `product.rs`) that is not the end of every
//! mission must then be a solution of: one `(c_v, Δ_v)` per vehicle, `s ≥
//! 0`, every vehicle dead at `s`, some vehicle not ended. The pairs `(c,
//! Δ)` of each vehicle are enumerated over its graph; the problem is
//! solved by a search with bounds propagation (each supervisor count lies
//! between the sums of the smallest and the largest effects still
//! possible; a pair whose vehicle cannot be dead within those bounds, or
//! that makes a count negative, is removed), branching on the vehicle with
//! the fewest pairs left. No solution proves that no reachable state of
//! the exact product (every count exact: no `>K`) is dead but the end.
//!
//! And since the graphs are acyclic, every run of the product is finite:
//! from every reachable state, any maximal run ends in a dead state, which
//! is the end of every mission. So the end is reachable from every state
//! (the second half of "free", `group.rs`), through exact steps, which are
//! pessimistic. A solution is only a candidate (the state equation ignores
//! the order of the moves): the explicit search decides then, as before,
//! first by random walks directed to the candidates' classes (`hunt.rs`).
//!
//! Not applicable (the explicit search decides): a graph with a cycle, an
//! edge that takes a withdrawn sync arrival back (`Effect::take_back`: its
//! effect depends on the count), more than [`MAX_PAIRS`] pairs for a
//! vehicle, or more than [`MAX_NODES`] nodes of search.

use rustc_hash::FxHashSet;

use super::lts::{lab_action, lab_blocked};
use super::product::Effect;
use super::quotient::Quotient;

/// Largest number of (class, effect) pairs of one vehicle.
pub(super) const MAX_PAIRS: usize = 50_000;
/// Largest number of nodes of the search.
pub(super) const MAX_NODES: usize = 200_000;
/// Solutions collected as candidates for a directed search.
const MAX_SOLUTIONS: usize = 16;

/// What the state equation says about a group.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Proof {
    /// No dead state but the end, and the end reachable from every state.
    Free,
    /// The state equation has solutions (perhaps not reachable): the
    /// classes of the vehicles in each of the first few.
    Candidates(Vec<Vec<u32>>),
    /// The method does not apply or ran out of budget.
    Unknown,
}

/// A possible dead position of a vehicle: a class and the effect on the
/// supervisor places of some path to it (dense over the vehicle's places).
struct Pair {
    class: u32,
    delta: Vec<i32>,
}

/// One vehicle of the problem.
struct Vehicle<'a> {
    quot: &'a Quotient,
    /// The supervisor places its edges touch (indices of the group).
    touched: Vec<usize>,
    pairs: Vec<Pair>,
}

/// Decides whether the product of `quots` with supervisor places initially
/// marked `init` (the group's effects `effects`) is free of deadlock by
/// the state equation (module doc).
pub(super) fn prove(quots: &[&Quotient], effects: &[Effect], init: &[u32]) -> Proof {
    let ns = init.len();
    let mut vehicles = Vec::with_capacity(quots.len());
    for q in quots {
        match vehicle(q, effects, ns) {
            Some(v) => vehicles.push(v),
            None => return Proof::Unknown,
        }
    }
    let mut search = Search {
        vs: &vehicles,
        effects,
        init: init.iter().map(|&x| i64::from(x)).collect(),
        nodes: 0,
        lo: vec![0; ns],
        hi: vec![0; ns],
        vmin: vehicles.iter().map(|v| vec![0; v.touched.len()]).collect(),
        vmax: vehicles.iter().map(|v| vec![0; v.touched.len()]).collect(),
        solutions: Vec::new(),
    };
    let dom: Vec<Vec<u32>> = vehicles.iter().map(|v| (0..v.pairs.len() as u32).collect()).collect();
    let done = search.solve(dom);
    if !search.solutions.is_empty() {
        return Proof::Candidates(search.solutions);
    }
    match done {
        Some(_) => Proof::Free,
        None => Proof::Unknown,
    }
}

/// The pairs of one vehicle whose class may be dead, or `None` when the
/// method does not apply (a cycle, a take-back, too many pairs).
fn vehicle<'a>(q: &'a Quotient, effects: &[Effect], ns: usize) -> Option<Vehicle<'a>> {
    let n = q.n;
    // Reachable classes in topological order (depth-first postorder,
    // reversed); a grey successor is a cycle.
    let start = *q.block.first()?;
    let mut colour = vec![0u8; n]; // 0 white, 1 grey, 2 black
    let mut post = Vec::with_capacity(n);
    let mut stack: Vec<(u32, usize)> = vec![(start, 0)];
    colour[start as usize] = 1;
    while let Some(&mut (c, ref mut i)) = stack.last_mut() {
        let out = q.out(c);
        if *i < out.len() {
            let (label, to) = out[*i];
            *i += 1;
            if let Some(a) = lab_action(label) {
                if !effects[a as usize].take_back.is_empty() {
                    return None;
                }
            }
            match colour[to as usize] {
                0 => {
                    colour[to as usize] = 1;
                    stack.push((to, 0));
                }
                1 => return None,
                _ => {}
            }
        } else {
            colour[c as usize] = 2;
            post.push(c);
            stack.pop();
        }
    }
    let mut touched: Vec<usize> = Vec::new();
    for &c in &post {
        for &(label, _) in q.out(c) {
            if let Some(a) = lab_action(label) {
                let e = &effects[a as usize];
                touched.extend(e.consume.iter().chain(&e.produce).map(|&(k, _)| k));
            }
        }
        for &g in &q.gates[c as usize] {
            touched.extend(effects[g as usize].consume.iter().map(|&(k, _)| k));
        }
    }
    touched.sort_unstable();
    touched.dedup();
    debug_assert!(touched.iter().all(|&k| k < ns));
    let local = |k: usize| touched.binary_search(&k).ok();
    // The effects of the paths to each class, in topological order.
    let mut deltas: Vec<FxHashSet<Vec<i32>>> = vec![FxHashSet::default(); n];
    deltas[start as usize].insert(vec![0; touched.len()]);
    let mut total = 1usize;
    for &c in post.iter().rev() {
        let here: Vec<Vec<i32>> = deltas[c as usize].iter().cloned().collect();
        for &(label, to) in q.out(c) {
            for d in &here {
                let mut d2 = d.clone();
                if let Some(a) = lab_action(label) {
                    let e = &effects[a as usize];
                    for &(k, w) in &e.consume {
                        d2[local(k)?] -= w as i32;
                    }
                    for &(k, w) in &e.produce {
                        d2[local(k)?] += w as i32;
                    }
                }
                if deltas[to as usize].insert(d2) {
                    total += 1;
                    if total > MAX_PAIRS {
                        return None;
                    }
                }
            }
        }
    }
    // A class may be dead only if every edge out of it can be disabled: a
    // blocked guard (with some waiting start to allow) or a consumption.
    let may_die = |c: u32| {
        q.out(c).iter().all(|&(label, _)| {
            (lab_blocked(label) && !q.gates[c as usize].is_empty())
                || lab_action(label).is_some_and(|a| !effects[a as usize].consume.is_empty())
        })
    };
    let mut pairs = Vec::new();
    for &c in &post {
        if may_die(c) {
            pairs.extend(deltas[c as usize].drain().map(|delta| Pair { class: c, delta }));
        }
    }
    pairs.sort_by(|a, b| (a.class, &a.delta).cmp(&(b.class, &b.delta)));
    Some(Vehicle { quot: q, touched, pairs })
}

/// The search over one pair per vehicle.
struct Search<'a> {
    vs: &'a [Vehicle<'a>],
    effects: &'a [Effect],
    init: Vec<i64>,
    nodes: usize,
    /// Bounds of each supervisor count over the pairs still possible.
    lo: Vec<i64>,
    hi: Vec<i64>,
    /// Per vehicle, per touched place: the smallest and largest effect of
    /// its pairs still possible.
    vmin: Vec<Vec<i32>>,
    vmax: Vec<Vec<i32>>,
    /// The classes of the solutions found.
    solutions: Vec<Vec<u32>>,
}

impl Search<'_> {
    /// Collects solutions in `self.solutions`. `Some(true)`: enough of
    /// them; `Some(false)`: the search is complete; `None`: out of budget.
    fn solve(&mut self, mut dom: Vec<Vec<u32>>) -> Option<bool> {
        self.nodes += 1;
        if self.nodes > MAX_NODES {
            return None;
        }
        if self.nodes % 1024 == 0 {
            crate::interrupt::poll();
        }
        if !self.propagate(&mut dom) {
            return Some(false);
        }
        let Some(v) = (0..dom.len()).filter(|&v| dom[v].len() > 1).min_by_key(|&v| dom[v].len()) else {
            if self.is_solution(&dom) {
                let classes = dom.iter().enumerate().map(|(v, d)| self.vs[v].pairs[d[0] as usize].class).collect();
                if !self.solutions.contains(&classes) {
                    self.solutions.push(classes);
                }
            }
            return Some(self.solutions.len() >= MAX_SOLUTIONS);
        };
        for &p in &dom[v].clone() {
            let mut d = dom.clone();
            d[v] = vec![p];
            if self.solve(d)? {
                return Some(true);
            }
        }
        Some(false)
    }

    /// Recomputes the bounds of the counts from the domains.
    fn bounds(&mut self, dom: &[Vec<u32>]) {
        self.lo.clone_from(&self.init);
        self.hi.clone_from(&self.init);
        for (v, veh) in self.vs.iter().enumerate() {
            for (j, &k) in veh.touched.iter().enumerate() {
                let it = dom[v].iter().map(|&p| veh.pairs[p as usize].delta[j]);
                let (mn, mx) = it.fold((i32::MAX, i32::MIN), |(a, b), x| (a.min(x), b.max(x)));
                self.vmin[v][j] = mn;
                self.vmax[v][j] = mx;
                self.lo[k] += i64::from(mn);
                self.hi[k] += i64::from(mx);
            }
        }
    }

    /// Removes the pairs that cannot be part of a solution within the
    /// bounds, to a fixpoint; false when a domain empties.
    fn propagate(&mut self, dom: &mut [Vec<u32>]) -> bool {
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        loop {
            if dom.iter().any(Vec::is_empty) {
                return false;
            }
            self.bounds(dom);
            let mut changed = false;
            for v in 0..dom.len() {
                let veh = &self.vs[v];
                let before = dom[v].len();
                let mut kept = Vec::with_capacity(before);
                for &p in &dom[v] {
                    let pair = &veh.pairs[p as usize];
                    lo.clone_from(&self.lo);
                    hi.clone_from(&self.hi);
                    let mut ok = true;
                    for (j, &k) in veh.touched.iter().enumerate() {
                        lo[k] += i64::from(pair.delta[j] - self.vmin[v][j]);
                        hi[k] += i64::from(pair.delta[j] - self.vmax[v][j]);
                        ok &= hi[k] >= 0;
                    }
                    ok = ok && self.may_be_dead(veh.quot, pair.class, &lo, &hi);
                    // The vehicles already fixed stay possibly dead.
                    ok = ok
                        && (0..dom.len()).all(|u| {
                            u == v || dom[u].len() != 1 || {
                                let c = self.vs[u].pairs[dom[u][0] as usize].class;
                                self.may_be_dead(self.vs[u].quot, c, &lo, &hi)
                            }
                        });
                    if ok {
                        kept.push(p);
                    }
                }
                if kept.len() != before {
                    changed = true;
                    dom[v] = kept;
                    if dom[v].is_empty() {
                        return false;
                    }
                    self.bounds(dom);
                }
            }
            if !changed {
                return true;
            }
        }
    }

    /// True when every edge out of class `c` may be disabled for some count
    /// within `lo..=hi` (each edge on its own: exact only when `lo == hi`).
    fn may_be_dead(&self, q: &Quotient, c: u32, lo: &[i64], hi: &[i64]) -> bool {
        let gates = &q.gates[c as usize];
        let gate_may_be_allowed =
            || gates.iter().any(|&g| self.effects[g as usize].consume.iter().all(|&(k, w)| hi[k] >= i64::from(w)));
        q.out(c).iter().all(|&(label, _)| {
            (lab_blocked(label) && gate_may_be_allowed())
                || lab_action(label)
                    .is_some_and(|a| self.effects[a as usize].consume.iter().any(|&(k, w)| lo[k] < i64::from(w)))
        })
    }

    /// Every domain a single pair: the exact check.
    fn is_solution(&self, dom: &[Vec<u32>]) -> bool {
        let mut s = self.init.clone();
        for (v, veh) in self.vs.iter().enumerate() {
            let pair = &veh.pairs[dom[v][0] as usize];
            for (j, &k) in veh.touched.iter().enumerate() {
                s[k] += i64::from(pair.delta[j]);
            }
        }
        s.iter().all(|&x| x >= 0)
            && self
                .vs
                .iter()
                .enumerate()
                .all(|(v, veh)| self.may_be_dead(veh.quot, veh.pairs[dom[v][0] as usize].class, &s, &s))
            && self.vs.iter().enumerate().any(|(v, veh)| !veh.quot.fin[veh.pairs[dom[v][0] as usize].class as usize])
    }
}

/// Per vehicle, the classes from which its class in `target` is reachable
/// in its graph (the guide of a directed walk, `hunt.rs`).
pub(super) fn on_the_way(quots: &[&Quotient], target: &[u32]) -> Vec<Vec<bool>> {
    quots
        .iter()
        .zip(target)
        .map(|(q, &t)| {
            let mut preds: Vec<Vec<u32>> = vec![Vec::new(); q.n];
            for c in 0..q.n as u32 {
                for &(_, to) in q.out(c) {
                    preds[to as usize].push(c);
                }
            }
            let mut on = vec![false; q.n];
            let mut stack = vec![t];
            on[t as usize] = true;
            while let Some(c) = stack.pop() {
                for &p in &preds[c as usize] {
                    if !on[p as usize] {
                        on[p as usize] = true;
                        stack.push(p);
                    }
                }
            }
            on
        })
        .collect()
}
