//! Step 3: the reduced vehicle graphs run together with the supervisor
//! places, explored breadth-first, with a partial-order reduction
//! (stubborn sets of vehicles, `stubborn.rs`) or without.
//!
//! A supervisor place holds 0..=K tokens exactly, or `>K` (consuming from
//! `>K` may leave `K` or `>K`): every reachable marking of the real system
//! has an image. A step is *pessimistic* when every real marking with that
//! image can follow it (`>K` minus one is `K`).
//!
//! **Settling** (docs/coordination.md, "Settling"; only in the product
//! that picks counterexamples, never in the one that gives the verdict,
//! which interleaves every vehicle's moves): a player fires every
//! ready immediate transition of its vehicle before it takes its next
//! input, and sends its messages only then. A vehicle whose own step leads
//! to an *unstable* class (every marking in it vanishing:
//! [`Quotient::unstable`]), or to one in which an *urgent* gated start
//! waits, allowed (its supervisors are its own, or it holds the mutex
//! between vehicles among them: [`Product::urgent`]), *owes* a move: the next step of the product is
//! one of its own (the last slot of a state names it). A start allowed by another vehicle's step owes nothing (the message
//! that allows it may be late), and a start on a mutex between vehicles
//! that another vehicle holds waits for its grant: it makes the vehicle
//! owe nothing, nor its events wait (its *blocked* edges stay enabled).
//! That last rule holds in the interleaving product too: a player takes
//! events while its request for a remote token is on its way, and the
//! interleaving product must hold every run of the players.

use rustc_hash::FxHashMap;

use super::lts::{lab_action, lab_blocked, TAU};
use super::quotient::Quotient;
use super::stubborn::Deps;

/// A successor: the next state, the vehicle that moved, the label, and
/// whether the step is pessimistic.
pub(super) type Succ = (Vec<u32>, usize, u32, bool);

/// The supervisor arcs of one transition: (supervisor, weight) consumed and
/// produced, and the supervisors it takes one token back from when they
/// have one (a withdrawn sync arrival, [`crate::Supervisor::withdrawn_by`]).
#[derive(Default, Clone, PartialEq, Eq, Hash)]
pub(super) struct Effect {
    pub(super) consume: Vec<(usize, u32)>,
    pub(super) produce: Vec<(usize, u32)>,
    pub(super) take_back: Vec<usize>,
}

/// The reduced vehicle graphs running together with the supervisor places
/// (counted exactly up to `cap`, then `cap + 1` for `>K`).
pub(super) struct Product<'a> {
    pub(super) quots: &'a [&'a Quotient],
    pub(super) effects: &'a [Effect],
    pub(super) cap: u32,
    pub(super) nv: usize,
    /// Per vehicle and effect: a gated start of that effect fires as soon
    /// as it is allowed (`settle.rs`).
    pub(super) urgent: &'a [&'a [bool]],
    /// Per effect: the vehicles holding the mutexes between vehicles that
    /// it consumes from (`settle.rs`).
    pub(super) holders: &'a [Vec<usize>],
    /// Settling applies (a vehicle owes the next move after its own step
    /// into a vanishing class or to an allowed urgent start); off, every
    /// interleaving of the vehicles' moves is explored.
    pub(super) settling: bool,
}

/// The last slot of a product state when no vehicle owes a move.
pub(super) const NOBODY: u32 = u32::MAX;

impl Product<'_> {
    /// True when the supervisor places of `st` allow `effect`.
    pub(super) fn allowed(&self, st: &[u32], effect: u32) -> bool {
        self.effects[effect as usize].consume.iter().all(|&(s, w)| st[self.nv + s] >= w)
    }

    /// The vehicle that owes the next move in `st` (settling), if any.
    pub(super) fn owing(&self, st: &[u32]) -> Option<usize> {
        st.last().filter(|&&v| v != NOBODY).map(|&v| v as usize)
    }

    /// True when an urgent gated start waits in class `c` of vehicle `v`,
    /// allowed by the supervisor places of `st`.
    pub(super) fn urgent_allowed(&self, st: &[u32], v: usize, c: u32) -> bool {
        self.quots[v].gates[c as usize].iter().any(|&g| self.urgent[v][g as usize] && self.allowed(st, g))
    }

    /// The holders that must settle before vehicle `v` may take a start of
    /// effect `a` (another vehicle holds its mutex, and has not begun: its
    /// class is vanishing, which, when it owes nothing, only its first one
    /// can be).
    pub(super) fn unsettled_holders(&self, st: &[u32], v: usize, a: u32) -> impl Iterator<Item = usize> + '_ {
        let hs: &[usize] = if self.urgent[v][a as usize] { &[] } else { &self.holders[a as usize] };
        let st: Vec<u32> = hs.iter().map(|&h| st[h]).collect();
        hs.iter().zip(st).filter(|&(&h, c)| self.quots[h].unstable[c as usize]).map(|(&h, _)| h)
    }

    /// True when vehicle `v`, having moved into class `c` of state `st`,
    /// owes the next move: the class is unstable, or an urgent start is
    /// allowed in it.
    fn owes(&self, st: &[u32], v: usize, c: u32) -> bool {
        self.settling && (self.quots[v].unstable[c as usize] || self.urgent_allowed(st, v, c))
    }

    /// Successors of `st` by the moves of the vehicles in `vehicles`; when
    /// a vehicle owes a move, by its moves alone (none if it is not among
    /// `vehicles`).
    pub(super) fn successors(
        &self,
        st: &[u32],
        vehicles: impl IntoIterator<Item = usize>,
        out: &mut Vec<Succ>,
        over: &mut bool,
    ) {
        let owing = self.owing(st);
        let first = out.len();
        for v in vehicles.into_iter().filter(|&v| owing.is_none_or(|o| o == v)) {
            let q = st[v];
            let qt = &self.quots[v];
            // Events wait while an urgent start is allowed (it fires
            // first); a remote start waits for its grant, and its
            // vehicle's events may come meanwhile, settling or not (the
            // interleaving product holds these runs of the players too).
            let any_gate_allowed = || self.urgent_allowed(st, v, q);
            for &(label, q2) in qt.out(q) {
                if lab_blocked(label) && any_gate_allowed() {
                    continue;
                }
                let mut base = st.to_vec();
                base[v] = q2;
                match lab_action(label) {
                    None => out.push((base, v, label, true)),
                    Some(t) => {
                        let waits = self.settling && self.unsettled_holders(st, v, t).next().is_some();
                        if !self.allowed(st, t) || waits {
                            continue;
                        }
                        let e = &self.effects[t as usize];
                        // Consumption, with the `>K` choices.
                        let mut states: Vec<(Vec<u32>, bool)> = vec![(base, true)];
                        for &(s, w) in &e.consume {
                            let mut nexts = Vec::new();
                            for (x, pess) in states {
                                let c = x[self.nv + s];
                                if c == self.cap + 1 {
                                    *over = true;
                                    // Concretely ≥ K+1: after − w, anything from K+1−w to >K.
                                    for r in (self.cap + 1 - w.min(self.cap + 1))..=self.cap + 1 {
                                        let mut y = x.clone();
                                        y[self.nv + s] = r;
                                        nexts.push((y, pess && r == self.cap + 1 - w.min(self.cap + 1)));
                                    }
                                } else {
                                    let mut y = x;
                                    y[self.nv + s] = c - w;
                                    nexts.push((y, pess));
                                }
                            }
                            states = nexts;
                        }
                        for (x, _) in states.iter_mut() {
                            for &(s, w) in &e.produce {
                                let c = &mut x[self.nv + s];
                                *c = (*c + w).min(self.cap + 1);
                                if *c == self.cap + 1 {
                                    *over = true;
                                }
                            }
                        }
                        // Take-backs: one token if there is one; from `>K`,
                        // `K` (the pessimistic choice) or `>K`.
                        for &s in &e.take_back {
                            let mut nexts = Vec::with_capacity(states.len());
                            for (mut x, pess) in states {
                                let c = x[self.nv + s];
                                if c == self.cap + 1 {
                                    *over = true;
                                    let mut y = x.clone();
                                    y[self.nv + s] = self.cap;
                                    nexts.push((y, pess));
                                    nexts.push((x, false));
                                } else {
                                    x[self.nv + s] = c.saturating_sub(1);
                                    nexts.push((x, pess));
                                }
                            }
                            states = nexts;
                        }
                        for (x, pess) in states {
                            out.push((x, v, label, pess));
                        }
                    }
                }
            }
        }
        // Who owes the next move: the vehicle that moved, if its own step
        // left an urgent start allowed.
        for (x, v, ..) in &mut out[first..] {
            let owes = self.owes(x, *v, x[*v]);
            if let Some(o) = x.last_mut() {
                *o = if owes { *v as u32 } else { NOBODY };
            }
        }
    }
}

/// The explored product: states, how each was first reached, the dead
/// ones and the pessimistic successors.
pub(super) struct ProductGraph {
    pub(super) width: usize,
    pub(super) states: Vec<u32>,
    pub(super) parent: Vec<(u32, u32, u32)>, // (parent, vehicle, label)
    pub(super) dead: Vec<u32>,
    /// Pessimistic successors of state `s`: `pess[pess_off[s]..pess_off[s + 1]]`
    /// (one flat array: millions of states made millions of small vectors).
    pub(super) pess_off: Vec<u32>,
    pub(super) pess: Vec<u32>,
    pub(super) over: bool,
    pub(super) complete: bool,
}

impl ProductGraph {
    /// A graph holding only the initial state `init`.
    pub(super) fn rooted(init: &[u32]) -> Self {
        ProductGraph {
            width: init.len(),
            states: init.to_vec(),
            parent: vec![(u32::MAX, 0, 0)],
            dead: Vec::new(),
            pess_off: vec![0],
            pess: Vec::new(),
            over: false,
            complete: true,
        }
    }

    /// State `i` (vehicle classes, then supervisor counts, then the vehicle
    /// that owes a move or [`NOBODY`]).
    pub(super) fn state(&self, i: u32) -> &[u32] {
        &self.states[i as usize * self.width..(i as usize + 1) * self.width]
    }
}

/// Explores the product breadth-first from `init`, up to `max` states;
/// with `deps`, expanding in each state only the moves of a stubborn set of
/// vehicles (`stubborn.rs`) when one satisfies the cycle proviso.
pub(super) fn explore_product(p: &Product<'_>, init: Vec<u32>, max: usize, deps: Option<&Deps>) -> ProductGraph {
    let mut index: FxHashMap<Vec<u32>, u32> = FxHashMap::default();
    let mut g = ProductGraph::rooted(&init);
    index.insert(init, 0);
    let mut i = 0usize;
    let mut succ = Vec::new();
    let mut seeds: Vec<Vec<usize>> = Vec::new();
    let mut set: Vec<usize> = Vec::new();
    while i < index.len() {
        if i % 4096 == 0 {
            crate::interrupt::poll();
        }
        let st = g.state(i as u32).to_vec();
        succ.clear();
        // Partial-order reduction: the moves of a stubborn set of vehicles
        // only (`stubborn.rs`), when one of them is enabled and every
        // successor by a move on a cycle of its vehicle's graph is a state
        // not yet expanded (index above `i`): a reduced edge then lies on
        // no cycle or goes up in the order of expansion, so every cycle
        // keeps a fully expanded state (docs/coordination.md).
        let mut reduced = false;
        // The reduction is used without settling (`Product::settling`).
        if let Some(d) = deps.filter(|_| !p.settling) {
            // A vehicle with a single silent, unguarded move is a stubborn
            // set alone with one successor: nothing does better.
            for v in 0..p.nv {
                if let [(TAU, _)] = p.quots[v].out(st[v]) {
                    succ.clear();
                    p.successors(&st, v..v + 1, &mut succ, &mut g.over);
                    let (x, ..) = &succ[0];
                    if !d.cyclic(v, st[v]) || index.get(x).is_none_or(|&j| j as usize > i) {
                        reduced = true;
                        break;
                    }
                }
            }
            // Each vehicle with an enabled move seeds a set; the set with
            // the fewest successors that meets the proviso is expanded.
            seeds.clear();
            for v in (0..p.nv).filter(|_| !reduced) {
                succ.clear();
                p.successors(&st, v..v + 1, &mut succ, &mut g.over);
                if succ.is_empty() {
                    continue;
                }
                d.closure(p, &st, v, &mut set);
                if set.len() < p.nv && !seeds.iter().any(|s: &Vec<usize>| s == &set) {
                    seeds.push(set.clone());
                }
            }
            let mut best: Option<Vec<Succ>> = None;
            for s in &seeds {
                succ.clear();
                p.successors(&st, s.iter().copied(), &mut succ, &mut g.over);
                let proviso = |(x, v, ..): &Succ| !d.cyclic(*v, st[*v]) || index.get(x).is_none_or(|&j| j as usize > i);
                if !succ.is_empty() && succ.iter().all(proviso) && best.as_ref().is_none_or(|b| succ.len() < b.len()) {
                    best = Some(std::mem::take(&mut succ));
                }
            }
            if !reduced {
                succ.clear();
                if let Some(b) = best {
                    succ = b;
                    reduced = true;
                }
            }
        }
        if !reduced {
            p.successors(&st, 0..p.nv, &mut succ, &mut g.over);
        }
        if succ.is_empty() {
            g.dead.push(i as u32);
        }
        let first = g.pess.len();
        for (x, v, label, pess) in succ.drain(..) {
            let n = index.len() as u32;
            let to = match index.get(&x) {
                Some(&to) => to,
                None => {
                    if index.len() >= max {
                        g.complete = false;
                        continue;
                    }
                    g.states.extend_from_slice(&x);
                    g.parent.push((i as u32, v as u32, label));
                    index.insert(x, n);
                    n
                }
            };
            if pess {
                g.pess.push(to);
            }
        }
        g.pess[first..].sort_unstable();
        let mut kept = first;
        for k in first..g.pess.len() {
            if kept == first || g.pess[kept - 1] != g.pess[k] {
                g.pess[kept] = g.pess[k];
                kept += 1;
            }
        }
        g.pess.truncate(kept);
        g.pess_off.push(g.pess.len() as u32);
        i += 1;
    }
    g
}
