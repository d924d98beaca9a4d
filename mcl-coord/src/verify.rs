//! Exhaustive verification of a supervised centralized net, one vehicle at a
//! time and then together.
//!
//! The plain product of two compiled missions is too large to explore (the
//! AUV of `examples/auv-asc.mcl` alone has 7,000 markings, its product with
//! the ASC tens of millions), and the counters of order and sync supervisors
//! are unbounded when calls sit in loops. The verification therefore works
//! in three steps, each exact or a sound over-approximation:
//!
//! 1. **Vehicle graphs.** The reachable markings of each vehicle's net alone,
//!    with the *per-vehicle* firing rule (seed Appendix A applied by each
//!    vehicle's player to its own transitions): immediate transitions first,
//!    then events and timers. A transition that a supervisor controls
//!    (*gated*) may be held: events of a marking in which a gated transition
//!    waits are recorded with a *blocked* guard (they are ready only while
//!    every waiting gated transition is held). Transitions connected to a
//!    supervisor place are *visible*; the others are silent (τ).
//! 2. **Reduction.** Each vehicle graph is reduced modulo divergence-
//!    preserving branching bisimulation (signature refinement, Blom and
//!    Orzan), with the gated transitions waiting and the end of the mission
//!    as state labels. Deadlocks, the reachability of the missions' ends and
//!    every visible behaviour are preserved.
//! 3. **Product.** The reduced graphs run together with the supervisor
//!    places. A supervisor place holds 0..=K tokens exactly, or `>K`
//!    (consuming from `>K` may leave `K` or `>K`): every reachable marking of
//!    the real system has an image, so *no dead image* proves *no dead
//!    marking*. The end of the missions must stay reachable from every image
//!    through *pessimistic* steps (`>K` minus one is `K`), which every real
//!    marking with that image can follow, so this proves that no vehicle can
//!    be blocked forever.
//!
//! The product is explored breadth-first with a partial-order reduction:
//! when a vehicle that has not ended (and can end alone) has only silent,
//! unguarded moves, those moves form a persistent set (no other vehicle nor
//! supervisor place can disable them or be affected by them), so only they
//! are expanded — provided they all lead to new states, which keeps a fully
//! expanded state on every cycle. Dead states are preserved, and so is the
//! reachability of the end: any path to the end must move that vehicle, and
//! its first move commutes to the front.
//!
//! A dead or blocked image is turned back into a firing sequence of the real
//! net (through the vehicles' graphs) and replayed with exact token counts;
//! if the replay fails, the image came from the `>K` abstraction and the
//! product is rebuilt with a larger K.
//!
//! The per-vehicle rule allows every interleaving that the centralized player
//! (one rule for all vehicles) allows, and more: a deadlock-free verdict
//! holds for both.
//!
//! Scaling (docs/coordination.md, "Scaling"): vehicles that no supervisor
//! links are verified as separate groups (exact: they share no place), and
//! when a group's product of class counts is large, seeded random walks look
//! for a dead state first; only a walk whose end replays on the real net is
//! reported.

use mcl_net::{Marking, Net, PlaceId, TransitionId};
use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::central::Plant;
use crate::model::Mission;
use crate::supervisor::Supervisor;

/// Caps of the verification.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyOptions {
    /// Largest number of markings of one vehicle's net.
    pub max_vehicle_states: usize,
    /// Largest number of states of the product.
    pub max_product_states: usize,
    /// First value of K (tokens counted exactly in a supervisor place).
    pub counter_cap: u32,
    /// Largest K tried before giving up on a spurious counterexample.
    pub max_counter_cap: u32,
    /// Above this many combinations of the vehicles' reduced states (the
    /// product of their class counts), random walks look for a deadlock
    /// before the exhaustive product.
    pub hunt_threshold: u64,
    /// Largest total number of random-walk steps.
    pub hunt_steps: usize,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            max_vehicle_states: 2_000_000,
            max_product_states: 4_000_000,
            counter_cap: 1,
            max_counter_cap: 32,
            hunt_threshold: 1_000_000,
            hunt_steps: 200_000,
        }
    }
}

/// Sizes met by a verification.
#[derive(Clone, Debug, Default, Serialize, PartialEq, Eq)]
pub struct VerifyStats {
    /// Markings of each vehicle's graph.
    pub vehicle_states: Vec<usize>,
    /// Classes of each reduced graph.
    pub vehicle_classes: Vec<usize>,
    /// States of the product.
    pub product_states: usize,
    /// K used.
    pub counter_cap: u32,
    /// True when no supervisor place ever exceeded K (the product is then
    /// exact, not an over-approximation).
    pub exact: bool,
}

/// What is wrong in a witness marking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WitnessKind {
    /// No transition can fire and some mission has not ended.
    Dead,
    /// Transitions can fire but some mission can no longer end.
    Blocked,
    /// A nominal run ([`Mission::off_nominal`]: no call fails outside a
    /// condition, no alarm) reaches a marking from which, in nominal runs,
    /// some mission can never end ([`verify_quiet`]).
    Stuck,
}

/// A firing sequence of the supervised centralized net that ends in a
/// deadlock or in a marking from which some mission can no longer end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Witness {
    /// Dead or blocked.
    pub kind: WitnessKind,
    /// The firing sequence, from the initial marking (transition indices of
    /// the supervised net).
    pub path: Vec<TransitionId>,
    /// The marking it ends in.
    pub marking: Marking,
    /// Transitions that wait in that marking only because supervisor places
    /// lack tokens, with the indices of those supervisors.
    pub held: Vec<(TransitionId, Vec<usize>)>,
}

/// Result of a verification.
#[derive(Clone, Debug)]
pub enum Outcome {
    /// No dead marking except the end of every mission, and from every
    /// reachable marking the end of every mission that can end alone is
    /// still reachable.
    Verified(VerifyStats),
    /// Counterexamples, replayed on the real net.
    Problems(Vec<Witness>, VerifyStats),
    /// A cap was reached, or a counterexample stayed spurious.
    Unknown(String, VerifyStats),
}

const TAU: u32 = 0;

/// An edge label: the supervisor effect of the transition (0: none, a
/// silent step; else an index in the effect table) and the blocked guard.
/// Transitions with the same effect on the supervisor places share a label.
fn lab(effect: u32, blocked: bool) -> u32 {
    (effect << 1) | u32::from(blocked)
}

fn lab_action(l: u32) -> Option<u32> {
    match l >> 1 {
        0 => None,
        a => Some(a),
    }
}

fn lab_blocked(l: u32) -> bool {
    l & 1 == 1
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    label: u32,
    to: u32,
    /// Global transition (in the plant).
    t: u32,
}

/// The graph of one vehicle's net under the per-vehicle firing rule.
struct Lts {
    marks: Vec<u8>,
    off: Vec<u32>,
    edges: Vec<Edge>,
    goff: Vec<u32>,
    gated: Vec<u32>,
    fin: Vec<bool>,
}

impl Lts {
    fn len(&self) -> usize {
        self.fin.len()
    }
    fn out(&self, s: u32) -> &[Edge] {
        &self.edges[self.off[s as usize] as usize..self.off[s as usize + 1] as usize]
    }
    fn gates(&self, s: u32) -> &[u32] {
        &self.gated[self.goff[s as usize] as usize..self.goff[s as usize + 1] as usize]
    }
}

enum LtsError {
    TooMany,
    Unbounded,
}

fn build_lts(
    m: &Mission,
    t_off: u32,
    effect_of: &[u32],
    gated: &[bool],
    quiet: bool,
    max: usize,
) -> Result<Lts, LtsError> {
    let net = &m.net;
    // With `quiet`, off-nominal answers never come.
    let mut quiet_places: Vec<Option<&[PlaceId]>> = vec![None; net.transition_count()];
    if quiet {
        for (t, ps) in &m.off_nominal {
            if let Some(x) = quiet_places.get_mut(t.index()) {
                *x = Some(ps.as_slice());
            }
        }
    }
    let np = net.place_count();
    let m0: Vec<u8> = net.places().iter().map(|p| u8::try_from(p.initial).unwrap_or(u8::MAX)).collect();
    if net.places().iter().any(|p| p.initial > 200) {
        return Err(LtsError::Unbounded);
    }
    let imm: Vec<bool> = net.transitions().iter().map(|t| t.kind.is_immediate()).collect();
    let mut index: FxHashMap<Vec<u8>, u32> = FxHashMap::default();
    let mut lts =
        Lts { marks: Vec::new(), off: vec![0], edges: Vec::new(), goff: vec![0], gated: Vec::new(), fin: Vec::new() };
    index.insert(m0.clone(), 0);
    lts.marks.extend_from_slice(&m0);
    let mut next = 0usize;
    // Buffers reused from state to state: this loop runs for every marking
    // of every vehicle, and allocation dominated it.
    let mut cur: Vec<u8> = Vec::with_capacity(np);
    let mut m2: Vec<u8> = Vec::with_capacity(np);
    let mut en: Vec<u32> = Vec::new();
    let mut imm_ng: Vec<u32> = Vec::new();
    let mut gimm: Vec<u32> = Vec::new();
    let mut waiting: Vec<u32> = Vec::new();
    let mut out: Vec<(u32, u32)> = Vec::new(); // (label, local t)
    let g = |t: u32| gated[(t + t_off) as usize];
    let v = |t: u32| effect_of[(t + t_off) as usize];
    let prio = |t: u32| net.transitions()[t as usize].effective_priority();
    while next < index.len() {
        if next % 4096 == 0 {
            crate::interrupt::poll();
        }
        cur.clear();
        cur.extend_from_slice(&lts.marks[next * np..(next + 1) * np]);
        lts.fin.push(m.final_places.iter().any(|p| cur[p.index()] > 0));
        en.clear();
        for t in net.transition_ids() {
            if net.pre(t).iter().all(|&(p, w)| u32::from(cur[p.index()]) >= w)
                && !quiet_places[t.index()].is_some_and(|ps| ps.iter().any(|p| cur[p.index()] > 0))
            {
                en.push(t.0);
            }
        }
        imm_ng.clear();
        imm_ng.extend(en.iter().copied().filter(|&t| imm[t as usize] && !g(t)));
        gimm.clear();
        gimm.extend(en.iter().copied().filter(|&t| imm[t as usize] && g(t)));
        // Priorities: among the non-gated immediate transitions only the
        // highest are ready, and a gated one below them never is. (A gated
        // transition above them would make them depend on the supervisor:
        // both are kept, an over-approximation; compiled missions gate only
        // `start`, of priority 0.)
        if let Some(pmax) = imm_ng.iter().map(|&t| prio(t)).max() {
            imm_ng.retain(|&t| prio(t) == pmax);
            gimm.retain(|&t| prio(t) >= pmax);
        }
        waiting.clear();
        waiting.extend(en.iter().copied().filter(|&t| imm[t as usize] && g(t)));
        out.clear();
        for &t in &gimm {
            out.push((lab(v(t), false), t));
        }
        if !imm_ng.is_empty() {
            for &t in &imm_ng {
                out.push((lab(v(t), false), t));
            }
        } else {
            // Deferred transitions (delay 0) fire before any event or timer,
            // as in the player (`mcl_net::semantics::select_ready`).
            let deferred = |t: u32| net.transitions()[t as usize].kind.is_deferred();
            let any_deferred = en.iter().any(|&t| deferred(t));
            for &t in en.iter().filter(|&&t| !imm[t as usize] && (!any_deferred || deferred(t))) {
                out.push((lab(v(t), !gimm.is_empty()), t));
            }
        }
        for &(label, t) in &out {
            m2.clear();
            m2.extend_from_slice(&cur);
            for &(p, d) in net.delta(TransitionId(t)) {
                let x = i64::from(m2[p.index()]) + d;
                if x > 200 {
                    return Err(LtsError::Unbounded);
                }
                m2[p.index()] = x as u8;
            }
            let to = match index.get(m2.as_slice()) {
                Some(&to) => to,
                None => {
                    let n = index.len() as u32;
                    lts.marks.extend_from_slice(&m2);
                    index.insert(m2.clone(), n);
                    if index.len() > max {
                        return Err(LtsError::TooMany);
                    }
                    n
                }
            };
            lts.edges.push(Edge { label, to, t: t + t_off });
        }
        lts.off.push(lts.edges.len() as u32);
        lts.gated.extend(if imm_ng.is_empty() { &gimm } else { &waiting }.iter().map(|&t| v(t)));
        lts.goff.push(lts.gated.len() as u32);
        next += 1;
    }
    Ok(lts)
}

/// A vehicle graph reduced modulo divergence-preserving branching bisimulation.
struct Quotient {
    block: Vec<u32>,
    n: usize,
    off: Vec<u32>,
    edges: Vec<(u32, u32)>,
    gates: Vec<Vec<u32>>,
    fin: Vec<bool>,
}

impl Quotient {
    fn out(&self, c: u32) -> &[(u32, u32)] {
        &self.edges[self.off[c as usize] as usize..self.off[c as usize + 1] as usize]
    }
}

/// Iterative Tarjan over `n` nodes; calls `emit` with each SCC in reverse
/// topological order (an SCC after every SCC it reaches).
fn tarjan(n: usize, succ: impl Fn(u32, &mut Vec<u32>), mut emit: impl FnMut(&[u32])) {
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0u32; n];
    let mut on = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    let mut counter = 0u32;
    let mut buf = Vec::new();
    // Call frames: (node, successors, next successor position).
    let mut frames: Vec<(u32, Vec<u32>, usize)> = Vec::new();
    for root in 0..n as u32 {
        if index[root as usize] != UNSEEN {
            continue;
        }
        buf.clear();
        succ(root, &mut buf);
        index[root as usize] = counter;
        low[root as usize] = counter;
        counter += 1;
        stack.push(root);
        on[root as usize] = true;
        frames.push((root, buf.clone(), 0));
        while let Some(frame) = frames.last_mut() {
            let v = frame.0;
            if frame.2 < frame.1.len() {
                let w = frame.1[frame.2];
                frame.2 += 1;
                if index[w as usize] == UNSEEN {
                    buf.clear();
                    succ(w, &mut buf);
                    index[w as usize] = counter;
                    low[w as usize] = counter;
                    counter += 1;
                    stack.push(w);
                    on[w as usize] = true;
                    frames.push((w, buf.clone(), 0));
                } else if on[w as usize] {
                    low[v as usize] = low[v as usize].min(index[w as usize]);
                }
            } else {
                frames.pop();
                if let Some(parent) = frames.last() {
                    let p = parent.0;
                    low[p as usize] = low[p as usize].min(low[v as usize]);
                }
                if low[v as usize] == index[v as usize] {
                    let mut scc = Vec::new();
                    while let Some(w) = stack.pop() {
                        on[w as usize] = false;
                        scc.push(w);
                        if w == v {
                            break;
                        }
                    }
                    emit(&scc);
                }
            }
        }
    }
}

/// A signature: the current block, divergence, and the (label, block) pairs.
type SigKey<'a> = (u32, bool, &'a [(u32, u32)]);

fn reduce(lts: &Lts) -> Quotient {
    let n = lts.len();
    // Initial partition: end of mission and waiting gated transitions.
    let mut keys: FxHashMap<(bool, Vec<u32>), u32> = FxHashMap::default();
    let mut block: Vec<u32> = (0..n as u32)
        .map(|s| {
            let k = (lts.fin[s as usize], lts.gates(s).to_vec());
            let next = keys.len() as u32;
            *keys.entry(k).or_insert(next)
        })
        .collect();
    let mut count = keys.len();
    let mut div = vec![false; n];
    loop {
        let inert = |s: u32, e: &Edge, block: &[u32]| e.label == TAU && block[e.to as usize] == block[s as usize];
        let mut scc_of = vec![u32::MAX; n];
        let mut sigs: Vec<(Vec<(u32, u32)>, bool)> = Vec::new();
        {
            let block_ref = &block;
            let mut emit = |scc: &[u32]| {
                let id = sigs.len() as u32;
                for &s in scc {
                    scc_of[s as usize] = id;
                }
                let mut sig: Vec<(u32, u32)> = Vec::new();
                let mut d = scc.len() > 1;
                for &s in scc {
                    for e in lts.out(s) {
                        if inert(s, e, block_ref) {
                            let o = scc_of[e.to as usize];
                            if o == id {
                                d = true; // inert self-loop
                            } else {
                                let (os, od) = &sigs[o as usize];
                                sig.extend_from_slice(os);
                                d |= *od;
                            }
                        } else {
                            sig.push((e.label, block_ref[e.to as usize]));
                        }
                    }
                }
                sig.sort_unstable();
                sig.dedup();
                sigs.push((sig, d));
            };
            tarjan(
                n,
                |s, out: &mut Vec<u32>| {
                    out.extend(lts.out(s).iter().filter(|e| inert(s, e, block_ref)).map(|e| e.to));
                },
                &mut emit,
            );
        }
        let mut ids: FxHashMap<SigKey<'_>, u32> = FxHashMap::default();
        let mut nb = vec![0u32; n];
        for s in 0..n {
            let (sig, d) = &sigs[scc_of[s] as usize];
            let next = ids.len() as u32;
            nb[s] = *ids.entry((block[s], *d, sig.as_slice())).or_insert(next);
            div[s] = *d;
        }
        let new_count = ids.len();
        drop(ids);
        block = nb;
        if new_count == count {
            break;
        }
        count = new_count;
    }
    let mut edges: Vec<Vec<(u32, u32)>> = vec![Vec::new(); count];
    let mut gates = vec![Vec::new(); count];
    let mut fin = vec![false; count];
    for s in 0..n as u32 {
        let b = block[s as usize];
        for e in lts.out(s) {
            let tb = block[e.to as usize];
            if !(e.label == TAU && tb == b) {
                edges[b as usize].push((e.label, tb));
            }
        }
        if div[s as usize] {
            edges[b as usize].push((TAU, b));
        }
        gates[b as usize] = lts.gates(s).to_vec();
        fin[b as usize] = lts.fin[s as usize];
    }
    let mut off = vec![0u32];
    let mut flat = Vec::new();
    for mut e in edges {
        e.sort_unstable();
        e.dedup();
        flat.extend(e);
        off.push(flat.len() as u32);
    }
    Quotient { block, n: count, off, edges: flat, gates, fin }
}

/// The supervisor arcs of one transition: (supervisor, weight) consumed and
/// produced, and the supervisors it takes one token back from when they
/// have one (a withdrawn sync arrival, [`Supervisor::withdrawn_by`]).
#[derive(Default, Clone, PartialEq, Eq, Hash)]
struct Effect {
    consume: Vec<(usize, u32)>,
    produce: Vec<(usize, u32)>,
    take_back: Vec<usize>,
}

struct Product<'a> {
    quots: &'a [&'a Quotient],
    can_end: &'a [bool],
    effects: &'a [Effect],
    cap: u32,
    nv: usize,
}

impl Product<'_> {
    fn allowed(&self, st: &[u32], effect: u32) -> bool {
        self.effects[effect as usize].consume.iter().all(|&(s, w)| st[self.nv + s] >= w)
    }

    /// Successors of `st`: (next state, vehicle, label, pessimistic).
    /// A vehicle whose moves form a persistent set in `st`: not ended, able
    /// to end alone, and every move of its class a silent unguarded step
    /// (independent of every other vehicle and of the supervisor places,
    /// and never disabled by them).
    fn ample_vehicle(&self, st: &[u32]) -> Option<usize> {
        (0..self.nv).find(|&v| {
            let q = &self.quots[v];
            let c = st[v];
            self.can_end[v] && !q.fin[c as usize] && !q.out(c).is_empty() && q.out(c).iter().all(|&(l, _)| l == TAU)
        })
    }

    /// Successors of `st` by the moves of the vehicles in `vehicles`.
    fn successors(
        &self,
        st: &[u32],
        vehicles: std::ops::Range<usize>,
        out: &mut Vec<(Vec<u32>, usize, u32, bool)>,
        over: &mut bool,
    ) {
        for v in vehicles {
            let q = st[v];
            let qt = &self.quots[v];
            let any_gate_allowed = || qt.gates[q as usize].iter().any(|&g| self.allowed(st, g));
            for &(label, q2) in qt.out(q) {
                if lab_blocked(label) && any_gate_allowed() {
                    continue;
                }
                let mut base = st.to_vec();
                base[v] = q2;
                match lab_action(label) {
                    None => out.push((base, v, label, true)),
                    Some(t) => {
                        if !self.allowed(st, t) {
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
    }
}

struct ProductGraph {
    width: usize,
    states: Vec<u32>,
    parent: Vec<(u32, u32, u32)>, // (parent, vehicle, label)
    dead: Vec<u32>,
    /// Pessimistic successors of state `s`: `pess[pess_off[s]..pess_off[s + 1]]`
    /// (one flat array: millions of states made millions of small vectors).
    pess_off: Vec<u32>,
    pess: Vec<u32>,
    over: bool,
    complete: bool,
}

impl ProductGraph {
    fn state(&self, i: u32) -> &[u32] {
        &self.states[i as usize * self.width..(i as usize + 1) * self.width]
    }
}

fn explore_product(p: &Product<'_>, init: Vec<u32>, max: usize) -> ProductGraph {
    let width = init.len();
    let mut index: FxHashMap<Vec<u32>, u32> = FxHashMap::default();
    let mut g = ProductGraph {
        width,
        states: init.clone(),
        parent: vec![(u32::MAX, 0, 0)],
        dead: Vec::new(),
        pess_off: vec![0],
        pess: Vec::new(),
        over: false,
        complete: true,
    };
    index.insert(init, 0);
    let mut i = 0usize;
    let mut succ = Vec::new();
    while i < index.len() {
        if i % 4096 == 0 {
            crate::interrupt::poll();
        }
        let st = g.state(i as u32).to_vec();
        succ.clear();
        // Partial-order reduction: the moves of one vehicle only, when they
        // form a persistent set and all lead to new states (which keeps
        // every cycle through a fully expanded state). Dead states and the
        // reachability of the end are preserved (docs/coordination.md).
        let mut reduced = false;
        if let Some(v) = p.ample_vehicle(&st) {
            p.successors(&st, v..v + 1, &mut succ, &mut g.over);
            if succ.iter().all(|(x, ..)| !index.contains_key(x)) {
                reduced = true;
            } else {
                succ.clear();
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

/// Verifies the supervised net `snet` = plant + `sups` (supervisor places
/// appended in order).
pub fn verify(missions: &[Mission], plant: &Plant, sups: &[Supervisor], snet: &Net, opts: &VerifyOptions) -> Outcome {
    verify_mode(missions, plant, sups, snet, opts, false)
}

/// True when some mission has off-nominal answers ([`Mission::off_nominal`]):
/// only then can [`verify_quiet`] find more than [`verify`].
pub fn has_off_nominal(missions: &[Mission]) -> bool {
    missions.iter().any(|m| !m.off_nominal.is_empty())
}

/// [`verify`] restricted to nominal runs ([`Mission::off_nominal`]: no call
/// fails outside a condition, no monitor condition fires; what a mock
/// vehicle does unless told otherwise, whatever the timing). Its
/// counterexamples, of kind [`WitnessKind::Stuck`], are markings reached by
/// a nominal run from which a mission can end only through a failure or an
/// alarm: a call waiting for ever for a sync partner that a `parallel ...
/// or` withdrew, say. [`verify`] does not see them, since an alarm, always
/// possible, would let the mission end.
pub fn verify_quiet(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
) -> Outcome {
    match verify_mode(missions, plant, sups, snet, opts, true) {
        Outcome::Problems(mut ws, st) => {
            for w in &mut ws {
                w.kind = WitnessKind::Stuck;
            }
            Outcome::Problems(ws, st)
        }
        o => o,
    }
}

fn verify_mode(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
    quiet: bool,
) -> Outcome {
    let nt = plant.net.transition_count();
    let mut gated = vec![false; nt];
    let mut per_t: Vec<Effect> = vec![Effect::default(); nt];
    let mut take_back: Vec<Vec<usize>> = vec![Vec::new(); nt];
    for (k, s) in sups.iter().enumerate() {
        for &t in &s.withdrawn_by {
            per_t[t.index()].take_back.push(k);
            take_back[t.index()].push(k);
        }
        for &(t, w) in &s.consumed_by {
            gated[t.index()] = true;
            per_t[t.index()].consume.push((k, w));
        }
        for &(t, w) in &s.produced_by {
            per_t[t.index()].produce.push((k, w));
        }
    }
    // One label per distinct effect on the supervisor places.
    let mut effects: Vec<Effect> = vec![Effect::default()];
    let mut effect_ids: FxHashMap<Effect, u32> = FxHashMap::default();
    let effect_of: Vec<u32> = per_t
        .into_iter()
        .map(|e| {
            if e.consume.is_empty() && e.produce.is_empty() && e.take_back.is_empty() {
                return 0;
            }
            let next = effects.len() as u32;
            *effect_ids.entry(e.clone()).or_insert_with(|| {
                effects.push(e);
                next
            })
        })
        .collect();
    let mut stats = VerifyStats::default();
    let mut ltss = Vec::new();
    for (m, part) in missions.iter().zip(&plant.parts) {
        match build_lts(m, part.transitions.start, &effect_of, &gated, quiet, opts.max_vehicle_states) {
            Ok(l) => {
                stats.vehicle_states.push(l.len());
                ltss.push(l);
            }
            Err(LtsError::TooMany) => {
                return Outcome::Unknown(
                    format!("mission `{}` has more than {} markings", m.name, opts.max_vehicle_states),
                    stats,
                )
            }
            Err(LtsError::Unbounded) => {
                return Outcome::Unknown(
                    format!("mission `{}` is not bounded (a place exceeds 200 tokens)", m.name),
                    stats,
                )
            }
        }
    }
    let quots: Vec<Quotient> = ltss.iter().map(reduce).collect();
    stats.vehicle_classes = quots.iter().map(|q| q.n).collect();
    // Which vehicles can end when nothing holds them.
    let can_end: Vec<bool> = ltss.iter().map(can_end_alone).collect();
    // The off-nominal answers, in centralized ids.
    let quiet_ts: Vec<(TransitionId, Vec<PlaceId>)> = if quiet {
        missions
            .iter()
            .zip(&plant.parts)
            .flat_map(|(m, part)| {
                m.off_nominal.iter().map(move |(t, ps)| {
                    (
                        TransitionId(t.0 + part.transitions.start),
                        ps.iter().map(|p| PlaceId(p.0 + part.places.start)).collect(),
                    )
                })
            })
            .collect()
    } else {
        Vec::new()
    };
    let rules = ReplayRules { take_back: &take_back, quiet: &quiet_ts };

    // Vehicles that no supervisor links are independent: each group of
    // linked vehicles is verified alone (docs/coordination.md).
    let groups = groups(plant, sups);
    stats.exact = true;
    let mut witnesses = Vec::new();
    let mut unknown: Option<String> = None;
    for (vs, ss) in &groups {
        let g = Group {
            vehicles: vs,
            sups: ss,
            ltss: vs.iter().map(|&v| &ltss[v]).collect(),
            quots: vs.iter().map(|&v| &quots[v]).collect(),
            can_end: vs.iter().map(|&v| can_end[v]).collect(),
            whole: groups.len() == 1,
            rules: &rules,
        };
        match verify_group(&g, plant, &effects, sups, snet, opts, &mut stats) {
            GroupOutcome::Verified => {}
            GroupOutcome::Problems(ws) => witnesses.extend(ws),
            GroupOutcome::Unknown(r) => {
                unknown.get_or_insert(r);
            }
        }
    }
    if !witnesses.is_empty() {
        return Outcome::Problems(witnesses, stats);
    }
    match unknown {
        Some(r) => Outcome::Unknown(r, stats),
        None => Outcome::Verified(stats),
    }
}

/// The groups of vehicles that supervisors link (connected components of
/// the graph vehicle — supervisor), with their supervisors, in order.
fn groups(plant: &Plant, sups: &[Supervisor]) -> Vec<(Vec<usize>, Vec<usize>)> {
    let nv = plant.parts.len();
    let mut parent: Vec<usize> = (0..nv).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let owner = |t: TransitionId| plant.parts.iter().position(|p| p.owns_transition(t));
    let mut sup_vehicle = Vec::with_capacity(sups.len());
    for s in sups {
        let vs: Vec<usize> = s.consumed_by.iter().chain(&s.produced_by).filter_map(|&(t, _)| owner(t)).collect();
        for w in vs.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[a] = b;
        }
        sup_vehicle.push(vs.first().copied());
    }
    let mut out: Vec<(usize, Vec<usize>, Vec<usize>)> = Vec::new(); // (root, vehicles, sups)
    for v in 0..nv {
        let r = root(&mut parent, v);
        match out.iter_mut().find(|(x, ..)| *x == r) {
            Some(g) => g.1.push(v),
            None => out.push((r, vec![v], Vec::new())),
        }
    }
    for (k, v) in sup_vehicle.into_iter().enumerate() {
        // A supervisor no transition touches is constant: any group may keep it.
        let r = root(&mut parent, v.unwrap_or(0));
        if let Some(g) = out.iter_mut().find(|(x, ..)| *x == r) {
            g.2.push(k);
        }
    }
    out.into_iter().map(|(_, vs, ss)| (vs, ss)).collect()
}

/// One group of linked vehicles: indices into the missions and supervisors.
struct Group<'a> {
    vehicles: &'a [usize],
    sups: &'a [usize],
    ltss: Vec<&'a Lts>,
    quots: Vec<&'a Quotient>,
    can_end: Vec<bool>,
    /// The group holds every vehicle.
    whole: bool,
    /// What a replay of its counterexamples applies.
    rules: &'a ReplayRules<'a>,
}

enum GroupOutcome {
    Verified,
    Problems(Vec<Witness>),
    Unknown(String),
}

fn verify_group(
    grp: &Group<'_>,
    plant: &Plant,
    effects_all: &[Effect],
    sups_all: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
    stats: &mut VerifyStats,
) -> GroupOutcome {
    let rules = grp.rules;
    let sups: Vec<&Supervisor> = grp.sups.iter().map(|&k| &sups_all[k]).collect();
    // Supervisor indices local to the group.
    let mut local = vec![usize::MAX; sups_all.len()];
    for (i, &k) in grp.sups.iter().enumerate() {
        local[k] = i;
    }
    let effects: Vec<Effect> = effects_all
        .iter()
        .map(|e| Effect {
            consume: e.consume.iter().filter(|(k, _)| local[*k] != usize::MAX).map(|&(k, w)| (local[k], w)).collect(),
            produce: e.produce.iter().filter(|(k, _)| local[*k] != usize::MAX).map(|&(k, w)| (local[k], w)).collect(),
            take_back: e.take_back.iter().filter(|&&k| local[k] != usize::MAX).map(|&k| local[k]).collect(),
        })
        .collect();
    let quots = &grp.quots;
    let nv = grp.vehicles.len();
    let can_end = &grp.can_end;
    let group_ts: Vec<TransitionId> =
        grp.vehicles.iter().flat_map(|&v| plant.parts[v].transitions.clone().map(TransitionId)).collect();
    let replay =
        Replay { snet, nsups: sups_all.len(), group_ts: if grp.whole { None } else { Some(&group_ts) }, rules };
    let max_w = sups.iter().flat_map(|s| s.consumed_by.iter().map(|&(_, w)| w)).max().unwrap_or(1);
    let max_init = sups.iter().map(|s| u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX)).max().unwrap_or(0);
    let mut cap = opts.counter_cap.max(max_w).max(max_init).max(1);
    let init_of = |cap: u32| -> Vec<u32> {
        let mut init: Vec<u32> = quots.iter().map(|q| q.block[0]).collect();
        init.extend(sups.iter().map(|s| u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX).min(cap + 1)));
        init
    };
    // A large product: look for a deadlock by random walks first.
    let estimate: f64 = quots.iter().map(|q| q.n as f64).product();
    if nv > 1 && estimate > opts.hunt_threshold as f64 {
        let prod = Product { quots, can_end, effects: &effects, cap, nv };
        if let Some(w) = hunt(&prod, init_of(cap), &grp.ltss, &replay, opts.hunt_steps) {
            stats.counter_cap = stats.counter_cap.max(cap);
            return GroupOutcome::Problems(vec![w]);
        }
    }
    loop {
        let prod = Product { quots, can_end, effects: &effects, cap, nv };
        let g = explore_product(&prod, init_of(cap), opts.max_product_states);
        let states = g.states.len() / g.width.max(1);
        stats.counter_cap = stats.counter_cap.max(cap);
        if !g.complete {
            stats.product_states += states;
            stats.exact &= !g.over;
            return GroupOutcome::Unknown(format!(
                "the product of {} has more than {} states",
                names(plant, grp.vehicles),
                opts.max_product_states
            ));
        }
        let is_end = |st: &[u32]| (0..nv).all(|v| quots[v].fin[st[v] as usize]);
        let is_target = |st: &[u32]| (0..nv).all(|v| !can_end[v] || quots[v].fin[st[v] as usize]);
        let n = g.pess_off.len() - 1;
        // Backward reachability of the targets over pessimistic steps; the
        // predecessors in one flat array (counting sort).
        let mut pred_off = vec![0u32; n + 1];
        for &t in &g.pess {
            pred_off[t as usize + 1] += 1;
        }
        for k in 0..n {
            pred_off[k + 1] += pred_off[k];
        }
        let mut fill = pred_off.clone();
        let mut pred = vec![0u32; g.pess.len()];
        for s in 0..n {
            for &t in &g.pess[g.pess_off[s] as usize..g.pess_off[s + 1] as usize] {
                pred[fill[t as usize] as usize] = s as u32;
                fill[t as usize] += 1;
            }
        }
        let preds = |s: u32| &pred[pred_off[s as usize] as usize..pred_off[s as usize + 1] as usize];
        let mut co = vec![false; n];
        let mut stack: Vec<u32> = (0..n as u32).filter(|&s| is_target(g.state(s))).collect();
        for &s in &stack {
            co[s as usize] = true;
        }
        while let Some(s) = stack.pop() {
            for &p in preds(s) {
                if !co[p as usize] {
                    co[p as usize] = true;
                    stack.push(p);
                }
            }
        }
        let mut is_dead = vec![false; n];
        for &s in &g.dead {
            is_dead[s as usize] = true;
        }
        let dead: Vec<u32> = g.dead.iter().copied().filter(|&s| !is_end(g.state(s))).collect();
        let blocked: Vec<u32> = (0..n as u32).filter(|&s| !co[s as usize] && !is_dead[s as usize]).collect();
        let settle = |stats: &mut VerifyStats| {
            stats.product_states += states;
            stats.exact &= !g.over;
        };
        if dead.is_empty() && blocked.is_empty() {
            settle(stats);
            return GroupOutcome::Verified;
        }
        // Counterexamples: every dead state (up to a few), and the first
        // blocked state that holds some call (else the first blocked one).
        let mut witnesses = Vec::new();
        let mut spurious = false;
        let held_state = |s: u32| {
            let st = g.state(s);
            (0..nv).any(|v| quots[v].gates[st[v] as usize].iter().any(|&t| !prod.allowed(st, t)))
        };
        let mut picks: Vec<(u32, WitnessKind)> = dead.iter().take(8).map(|&s| (s, WitnessKind::Dead)).collect();
        // A dead marking explains itself; a blocked one is reported only
        // when there is none.
        if picks.is_empty() {
            if let Some(&b) = blocked.iter().find(|&&s| held_state(s)).or(blocked.first()) {
                picks.push((b, WitnessKind::Blocked));
            }
        }
        for (s, kind) in picks {
            match concretize(&g, s, &grp.ltss, quots, &replay, kind) {
                Some(w) => witnesses.push(w),
                None => spurious = true,
            }
        }
        if witnesses.is_empty() && spurious {
            if g.over && cap < opts.max_counter_cap {
                cap = (cap * 2).min(opts.max_counter_cap);
                continue;
            }
            settle(stats);
            return GroupOutcome::Unknown(format!(
                "counterexamples found with supervisor places counted up to {cap} tokens do not replay"
            ));
        }
        // A blocked image reached through `>K` counts may be an artefact of
        // the abstraction: only an exact product proves it.
        if witnesses.iter().all(|w| w.kind == WitnessKind::Blocked) && g.over {
            if cap < opts.max_counter_cap {
                cap = (cap * 2).min(opts.max_counter_cap);
                continue;
            }
            settle(stats);
            return GroupOutcome::Unknown(format!(
                "no deadlock, but whether every mission can always end is not decided: supervisor places \
                 exceed {cap} tokens"
            ));
        }
        settle(stats);
        return GroupOutcome::Problems(witnesses);
    }
}

fn names(plant: &Plant, vs: &[usize]) -> String {
    let n: Vec<String> = vs.iter().map(|&v| format!("`{}`", plant.parts[v].name)).collect();
    if n.len() == plant.parts.len() {
        format!("the {} vehicles", n.len())
    } else {
        format!("the vehicles {}", n.join(", "))
    }
}

/// Random walks through the product, looking for a dead state that replays
/// on the real net (a deadlock found this way is real; finding none proves
/// nothing). Seeded: the same input gives the same walks.
fn hunt(p: &Product<'_>, init: Vec<u32>, ltss: &[&Lts], replay: &Replay<'_>, budget: usize) -> Option<Witness> {
    let mut rng: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move |n: usize| {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng % n as u64) as usize
    };
    let depth: usize = 64 + 8 * p.quots.iter().map(|q| q.n).sum::<usize>();
    let mut used = 0usize;
    let mut succ = Vec::new();
    let mut over = false;
    let mut tried = 0;
    while used < budget {
        let mut g = ProductGraph {
            width: init.len(),
            states: init.clone(),
            parent: vec![(u32::MAX, 0, 0)],
            dead: Vec::new(),
            pess_off: vec![0],
            pess: Vec::new(),
            over: false,
            complete: true,
        };
        let mut cur = init.clone();
        crate::interrupt::poll();
        for step in 0..depth {
            used += 1;
            succ.clear();
            p.successors(&cur, 0..p.nv, &mut succ, &mut over);
            if succ.is_empty() {
                let is_end = (0..p.nv).all(|v| p.quots[v].fin[cur[v] as usize]);
                if !is_end {
                    tried += 1;
                    if let Some(w) = concretize(&g, step as u32, ltss, p.quots, replay, WitnessKind::Dead) {
                        return Some(w);
                    }
                    if tried > 64 {
                        return None;
                    }
                }
                break;
            }
            let (x, v, label, _) = succ.swap_remove(next(succ.len()));
            g.states.extend_from_slice(&x);
            g.parent.push((step as u32, v as u32, label));
            cur = x;
        }
    }
    None
}

/// What a replay of a counterexample needs: the supervised net, its number
/// of supervisor places, and the transitions of the group (`None`: all).
struct Replay<'a> {
    snet: &'a Net,
    nsups: usize,
    group_ts: Option<&'a [TransitionId]>,
    rules: &'a ReplayRules<'a>,
}

/// What a replay applies besides the net's arcs.
struct ReplayRules<'a> {
    /// Per transition of the plant: the supervisors it takes a token back
    /// from, if they have one ([`Supervisor::withdrawn_by`]).
    take_back: &'a [Vec<usize>],
    /// Transitions that never fire while one of the places is marked (the
    /// off-nominal answers of [`verify_quiet`]).
    quiet: &'a [(TransitionId, Vec<PlaceId>)],
}

impl ReplayRules<'_> {
    fn fire(&self, snet: &Net, nsups: usize, m: &mut Marking, t: TransitionId) -> bool {
        if mcl_net::semantics::fire(snet, m, t).is_err() {
            return false;
        }
        let np = snet.place_count() - nsups;
        for &k in self.take_back.get(t.index()).map_or(&[][..], |v| v.as_slice()) {
            let x = &mut m.0[np + k];
            *x = x.saturating_sub(1);
        }
        true
    }

    fn silent(&self, m: &Marking, t: TransitionId) -> bool {
        self.quiet.iter().any(|(q, ps)| *q == t && ps.iter().any(|&p| m.get(p) > 0))
    }
}

fn can_end_alone(l: &Lts) -> bool {
    // Nothing held: drop the events of markings with waiting gated
    // transitions (these fire first when allowed).
    let n = l.len();
    let mut preds: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut reach = vec![false; n];
    let mut stack = vec![0u32];
    reach[0] = true;
    while let Some(s) = stack.pop() {
        for e in l.out(s) {
            if lab_blocked(e.label) {
                continue;
            }
            preds[e.to as usize].push(s);
            if !reach[e.to as usize] {
                reach[e.to as usize] = true;
                stack.push(e.to);
            }
        }
    }
    let mut co = vec![false; n];
    let mut stack: Vec<u32> = (0..n as u32).filter(|&s| l.fin[s as usize] && reach[s as usize]).collect();
    for &s in &stack {
        co[s as usize] = true;
    }
    while let Some(s) = stack.pop() {
        for &p in &preds[s as usize] {
            if !co[p as usize] {
                co[p as usize] = true;
                stack.push(p);
            }
        }
    }
    (0..n).all(|s| !reach[s] || co[s])
}

/// Turns a product state into a firing sequence of the real net, replays it
/// with exact counts, and describes the marking reached.
fn concretize(
    g: &ProductGraph,
    target: u32,
    ltss: &[&Lts],
    quots: &[&Quotient],
    replay: &Replay<'_>,
    kind: WitnessKind,
) -> Option<Witness> {
    let snet = replay.snet;
    // Abstract steps, from the initial state.
    let mut steps: Vec<(usize, u32, u32)> = Vec::new(); // (vehicle, label, target class)
    let mut cur = target;
    while g.parent[cur as usize].0 != u32::MAX {
        let (p, v, label) = g.parent[cur as usize];
        steps.push((v as usize, label, g.state(cur)[v as usize]));
        cur = p;
    }
    steps.reverse();
    let mut conc: Vec<u32> = vec![0; ltss.len()];
    let mut path: Vec<TransitionId> = Vec::new();
    for (v, label, q2) in steps {
        let lts = &ltss[v];
        let q = &quots[v];
        let from_block = q.block[conc[v] as usize];
        // BFS through inert steps of the current class to an edge `label` into q2.
        let mut seen: FxHashMap<u32, (u32, u32)> = FxHashMap::default(); // state -> (pred, transition)
        seen.insert(conc[v], (u32::MAX, u32::MAX));
        let mut queue = std::collections::VecDeque::from([conc[v]]);
        let mut found: Option<(u32, Edge)> = None;
        'bfs: while let Some(s) = queue.pop_front() {
            for e in lts.out(s) {
                if e.label == label && q.block[e.to as usize] == q2 && !(label == TAU && q2 == from_block) {
                    found = Some((s, *e));
                    break 'bfs;
                }
            }
            for e in lts.out(s) {
                if e.label == TAU && q.block[e.to as usize] == from_block && !seen.contains_key(&e.to) {
                    seen.insert(e.to, (s, e.t));
                    queue.push_back(e.to);
                }
            }
        }
        let (s, e) = match found {
            Some(x) => x,
            // A divergence self-loop: any inert cycle step will do.
            None if label == TAU && q2 == from_block => {
                let e = lts.out(conc[v]).iter().find(|e| e.label == TAU && q.block[e.to as usize] == from_block)?;
                (conc[v], *e)
            }
            None => return None,
        };
        let mut local = Vec::new();
        let mut x = s;
        while let Some(&(p, t)) = seen.get(&x) {
            if p == u32::MAX {
                break;
            }
            local.push(TransitionId(t));
            x = p;
        }
        local.reverse();
        path.extend(local);
        path.push(TransitionId(e.t));
        conc[v] = e.to;
    }
    if kind == WitnessKind::Dead {
        // Settle each vehicle through its remaining inert steps.
        for (v, lts) in ltss.iter().enumerate() {
            for _ in 0..lts.len() {
                let s = conc[v];
                match lts.out(s).iter().find(|e| e.label == TAU) {
                    Some(e) => {
                        path.push(TransitionId(e.t));
                        conc[v] = e.to;
                    }
                    None => break,
                }
            }
        }
    }
    // Replay with exact counts.
    let mut m = snet.initial_marking();
    for &t in &path {
        if !replay.rules.fire(snet, replay.nsups, &mut m, t) {
            return None;
        }
    }
    let mut enabled = mcl_net::semantics::enabled(snet, &m);
    enabled.retain(|&t| !replay.rules.silent(&m, t));
    let mut kind = kind;
    match replay.group_ts {
        None => {
            if kind == WitnessKind::Dead && !enabled.is_empty() {
                return None;
            }
        }
        Some(ts) => {
            // The group is dead when none of its transitions has its
            // input places marked (no other vehicle touches them); the
            // whole net is dead only if the other vehicles are too.
            if kind == WitnessKind::Dead {
                let live =
                    ts.iter().any(|&t| snet.pre(t).iter().all(|&(p, w)| m.get(p) >= w) && !replay.rules.silent(&m, t));
                if live {
                    return None;
                }
                if !enabled.is_empty() {
                    kind = WitnessKind::Blocked;
                }
            }
        }
    }
    let np_plant = snet.place_count() - replay.nsups;
    let mut held = Vec::new();
    for t in snet.transition_ids() {
        let pre = snet.pre(t);
        let plant_ok = pre.iter().filter(|(p, _)| p.index() < np_plant).all(|&(p, w)| m.get(p) >= w);
        let missing: Vec<usize> = pre
            .iter()
            .filter(|(p, _)| p.index() >= np_plant)
            .filter(|&&(p, w)| m.get(p) < w)
            .map(|&(p, _)| p.index() - np_plant)
            .collect();
        if plant_ok && !missing.is_empty() {
            held.push((t, missing));
        }
    }
    Some(Witness { kind, path, marking: m, held })
}

/// The places of a marking that hold no token (for siphon analysis).
pub fn empty_places(m: &Marking) -> Vec<PlaceId> {
    m.0.iter().enumerate().filter(|(_, &n)| n == 0).map(|(i, _)| PlaceId(i as u32)).collect()
}
