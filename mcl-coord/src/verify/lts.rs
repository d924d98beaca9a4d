//! Step 1: the transition system of one vehicle's net alone under the
//! per-vehicle firing rule (`mcl_net::semantics::select_ready`: immediate
//! transitions first, by priority; then deferred ones, by priority; then
//! events and timers), with the supervisor effect of each transition as its
//! label. A mission stops where the player stops it: once a final place
//! is marked in a stable marking, nothing of it fires any more (`Lts::fin`).
//!
//! A transition that a supervisor controls (*gated*) may be held, so the
//! ready set is computed without the gated transitions (all held), and each
//! enabled gated transition is added when the rule would choose it beside
//! those (its supervisors allow it). An allowed gated immediate transition
//! makes the marking vanishing: the non-immediate transitions of a marking
//! in which one waits carry the *blocked* guard (ready only while every
//! waiting gated transition is held; exact). Two cases are
//! over-approximated, never under: a non-gated transition that an allowed
//! gated one of higher rank would preempt stays ready (compiled missions
//! gate only `start`, immediate, of priority 0), and so does the choice of
//! gated transitions among themselves. The replay of a counterexample
//! (`replay.rs`) applies the exact rule and rejects such a step.

use mcl_net::semantics::{is_enabled_with, select_ready};
use mcl_net::{PlaceId, TransitionId};
use rustc_hash::FxHashMap;

use crate::model::Mission;

/// The label of a silent, unguarded step.
pub(super) const TAU: u32 = 0;

/// An edge label: the supervisor effect of the transition (0: none, a
/// silent step; else an index in the effect table) and the blocked guard.
/// Transitions with the same effect on the supervisor places share a label.
pub(super) fn lab(effect: u32, blocked: bool) -> u32 {
    (effect << 1) | u32::from(blocked)
}

/// The effect of a label (`None`: no effect on the supervisor places).
pub(super) fn lab_action(l: u32) -> Option<u32> {
    match l >> 1 {
        0 => None,
        a => Some(a),
    }
}

/// True when the label carries the blocked guard.
pub(super) fn lab_blocked(l: u32) -> bool {
    l & 1 == 1
}

/// An edge of a vehicle's graph.
#[derive(Clone, Copy, Debug)]
pub(super) struct Edge {
    pub(super) label: u32,
    pub(super) to: u32,
    /// Global transition (in the plant).
    pub(super) t: u32,
}

/// The graph of one vehicle's net under the per-vehicle firing rule.
pub(super) struct Lts {
    /// The markings, `place_count` bytes each.
    marks: Vec<u8>,
    off: Vec<u32>,
    edges: Vec<Edge>,
    goff: Vec<u32>,
    gated: Vec<u32>,
    /// Markings in which the mission has ended as the player ends it: a
    /// final place marked and the marking stable (nothing immediate nor
    /// zero-delay ready). Such a marking has no edge but those of the
    /// gated immediate transitions waiting in it (allowed, they fire before
    /// the player looks; held, the mission has ended).
    pub(super) fin: Vec<bool>,
    /// Markings in which an immediate transition that no supervisor
    /// controls is ready: the player fires it before its next input.
    pub(super) vanishing: Vec<bool>,
}

impl Lts {
    /// Number of markings.
    pub(super) fn len(&self) -> usize {
        self.fin.len()
    }

    /// The edges out of marking `s`.
    pub(super) fn out(&self, s: u32) -> &[Edge] {
        &self.edges[self.off[s as usize] as usize..self.off[s as usize + 1] as usize]
    }

    /// The effects of the gated immediate transitions waiting in `s`.
    pub(super) fn gates(&self, s: u32) -> &[u32] {
        &self.gated[self.goff[s as usize] as usize..self.goff[s as usize + 1] as usize]
    }
}

/// Why a vehicle's graph could not be built.
pub(super) enum LtsError {
    /// More markings than the cap.
    TooMany,
    /// A place exceeds 200 tokens.
    Unbounded,
}

/// The graph of `m`'s net, whose transitions are those of the plant from
/// `t_off` on (`effect_of`, `gated` and `remote` are indexed by plant
/// transitions); with `quiet`, the off-nominal answers never come. A
/// `remote` start (on a mutex between vehicles that another vehicle holds)
/// fires only in a marking where nothing else immediate is ready: its
/// token is granted in answer to a request sent once the vehicle settled.
pub(super) fn build_lts(
    m: &Mission,
    t_off: u32,
    effect_of: &[u32],
    gated: &[bool],
    remote: &[bool],
    quiet: bool,
    max: usize,
) -> Result<Lts, LtsError> {
    let net = &m.net;
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
    let mut lts = Lts {
        marks: Vec::new(),
        off: vec![0],
        edges: Vec::new(),
        goff: vec![0],
        gated: Vec::new(),
        fin: Vec::new(),
        vanishing: Vec::new(),
    };
    index.insert(m0.clone(), 0);
    lts.marks.extend_from_slice(&m0);
    let mut next = 0usize;
    // Buffers reused from state to state: this loop runs for every marking
    // of every vehicle, and allocation dominated it.
    let mut cur: Vec<u8> = Vec::with_capacity(np);
    let mut m2: Vec<u8> = Vec::with_capacity(np);
    let mut ready: Vec<TransitionId> = Vec::new();
    let mut gated_en: Vec<TransitionId> = Vec::new();
    let mut pair: Vec<TransitionId> = Vec::with_capacity(2);
    let mut waiting: Vec<u32> = Vec::new();
    let mut out: Vec<(u32, u32)> = Vec::new(); // (label, local t)
    let g = |t: TransitionId| gated[(t.0 + t_off) as usize];
    let v = |t: TransitionId| effect_of[(t.0 + t_off) as usize];
    while next < index.len() {
        if next % 4096 == 0 {
            crate::interrupt::poll();
        }
        cur.clear();
        cur.extend_from_slice(&lts.marks[next * np..(next + 1) * np]);
        let final_marked = m.final_places.iter().any(|p| cur[p.index()] > 0);
        ready.clear();
        gated_en.clear();
        for t in net.transition_ids() {
            if is_enabled_with(net, t, |p| u32::from(cur[p.index()]))
                && !quiet_places[t.index()].is_some_and(|ps| ps.iter().any(|p| cur[p.index()] > 0))
            {
                if g(t) {
                    gated_en.push(t);
                } else {
                    ready.push(t);
                }
            }
        }
        // The rule with every gated transition held.
        select_ready(net, &mut ready);
        waiting.clear();
        out.clear();
        // The player's end: a final place marked in a stable marking (no
        // immediate nor zero-delay transition ready, gated ones held); from
        // there it fires nothing more. Only a gated immediate transition
        // that its supervisors allow would still fire first.
        let settles = |t: TransitionId| net.transitions()[t.index()].kind.is_deferred() || imm[t.index()];
        let ended = final_marked && !ready.iter().any(|&t| settles(t));
        lts.fin.push(ended);
        lts.vanishing.push(ready.iter().any(|&u| imm[u.index()]));
        // A gated transition is ready when allowed if the rule picks it
        // beside the best of the others (the ready ones all rank alike).
        for &t in &gated_en {
            if imm[t.index()] {
                waiting.push(v(t));
            }
            if ended && !settles(t) {
                continue;
            }
            let r = remote.get((t.0 + t_off) as usize).copied().unwrap_or(false);
            if r && ready.iter().any(|&u| imm[u.index()]) {
                continue;
            }
            pair.clear();
            pair.extend(ready.first().copied());
            pair.push(t);
            select_ready(net, &mut pair);
            if pair.contains(&t) {
                out.push((lab(v(t), false), t.0));
            }
        }
        // Non-immediate transitions wait for every waiting gated immediate
        // one to be held.
        let blocked = |t: TransitionId| !imm[t.index()] && !waiting.is_empty();
        for &t in ready.iter().filter(|_| !ended) {
            out.push((lab(v(t), blocked(t)), t.0));
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
        lts.gated.extend_from_slice(&waiting);
        lts.goff.push(lts.gated.len() as u32);
        next += 1;
    }
    Ok(lts)
}

/// True when the mission can end from every marking it reaches while no
/// supervisor holds it (every gated transition allowed).
pub(super) fn can_end_alone(l: &Lts) -> bool {
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

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_net::{Delay, NetBuilder, Place, Transition, TransitionKind};

    fn mission(net: mcl_net::Net) -> Mission {
        let n = net.transition_count();
        Mission {
            name: "m".into(),
            net,
            initial_places: Vec::new(),
            final_places: Vec::new(),
            controllable: vec![true; n],
            activities: Vec::new(),
            off_nominal: Vec::new(),
        }
    }

    fn deferred(id: &str, priority: u32) -> Transition {
        Transition::new(id).with_kind(TransitionKind::Timed(Delay::Fixed(0.0))).with_priority(priority)
    }

    #[test]
    fn deferred_transitions_fire_by_priority_before_events() {
        // A call's release (deferred, priority 0) waits for a kill
        // (deferred, higher priority); the event waits for both.
        let mut b = NetBuilder::new("v");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let kill = b.add_transition(deferred("kill", 3));
        let release = b.add_transition(deferred("release", 0));
        let ev = b.add_transition(Transition::new("ev").with_kind(TransitionKind::Event("e".into())));
        for t in [kill, release, ev] {
            b.add_input(p, t, 1);
        }
        let m = mission(b.build().unwrap());
        let Ok(lts) = build_lts(&m, 0, &[0; 3], &[false; 3], &[], false, 100) else { panic!("built") };
        let fired: Vec<u32> = lts.out(0).iter().map(|e| e.t).collect();
        assert_eq!(fired, vec![kill.0]);
    }

    #[test]
    fn events_wait_for_every_waiting_gated_start() {
        // A gated start may be held: then the event may fire, else not.
        let mut b = NetBuilder::new("v");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q").with_tokens(1));
        let start = b.add_transition(Transition::new("start"));
        let ev = b.add_transition(Transition::new("ev").with_kind(TransitionKind::Event("e".into())));
        b.add_input(p, start, 1).add_input(q, ev, 1);
        let m = mission(b.build().unwrap());
        let Ok(lts) = build_lts(&m, 0, &[1, 0], &[true, false], &[], false, 100) else { panic!("built") };
        let out: Vec<(u32, u32)> = lts.out(0).iter().map(|e| (e.t, e.label)).collect();
        assert_eq!(out, vec![(start.0, lab(1, false)), (ev.0, lab(0, true))]);
        assert_eq!(lts.gates(0), &[1]);
    }
}
