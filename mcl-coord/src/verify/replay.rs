//! Counterexamples: a dead or blocked product state turned back into a
//! firing sequence of the supervised net (through the vehicles' graphs) and
//! replayed with exact token counts and the exact per-vehicle firing rule.
//! A replay that fails means that the state came from an abstraction (the
//! `>K` counts, or the over-approximated gating of `lts.rs`).

use std::ops::Range;

use mcl_net::semantics::{is_enabled_with, select_ready, EnabledTracker};
use mcl_net::{Marking, Net, PlaceId, TransitionId};
use rustc_hash::FxHashMap;

use super::lts::{Edge, Lts, TAU};
use super::product::ProductGraph;
use super::quotient::Quotient;
use super::{Witness, WitnessKind};

/// What a replay of a counterexample needs: the supervised net, its number
/// of supervisor places, and the transitions of the group (`None`: all).
pub(super) struct Replay<'a> {
    pub(super) snet: &'a Net,
    pub(super) nsups: usize,
    pub(super) group_ts: Option<&'a [TransitionId]>,
    pub(super) rules: &'a ReplayRules<'a>,
}

/// What a replay applies besides the net's arcs.
pub(super) struct ReplayRules<'a> {
    /// The transitions of each vehicle (plant ids): the firing rule picks
    /// among the enabled transitions of one vehicle.
    pub(super) vehicles: &'a [Range<u32>],
    /// Per transition of the plant: the supervisors it takes a token back
    /// from, if they have one ([`crate::Supervisor::withdrawn_by`]).
    pub(super) take_back: &'a [Vec<usize>],
    /// Per transition of the plant: it never fires while one of these
    /// places is marked (the off-nominal answers of
    /// [`super::verify_quiet`]; empty: no such rule).
    pub(super) quiet: &'a [Vec<PlaceId>],
    /// The final places of each vehicle (`mission.ok`, `mission.fail`, plant
    /// ids): once one is marked in a marking stable for its vehicle, the
    /// vehicle has ended and fires nothing more, as the player.
    pub(super) finals: &'a [Vec<PlaceId>],
    /// Per transition of the plant: a start on a mutex between vehicles of
    /// a vehicle that is not its holder, which may wait for its token while
    /// its vehicle takes other steps, and fires only once its vehicle has
    /// no other immediate step ready (empty: none).
    pub(super) remote: &'a [bool],
    /// Per transition of the plant: a start on a mutex between vehicles of
    /// a vehicle that is not its holder, which may wait for its token while
    /// its vehicle takes other steps (empty: none).
    pub(super) held: &'a [bool],
}

/// The end of a replay: the marking reached and, per vehicle, whether its
/// mission has ended.
pub(super) struct Replayed {
    pub(super) marking: Marking,
    pub(super) ended: Vec<bool>,
}

impl ReplayRules<'_> {
    /// Fires `path` from the initial marking of `snet` with exact counts
    /// and returns the marking reached; `None` when some step is not one
    /// that the firing rule could choose: each transition must be ready
    /// (`mcl_net::semantics::select_ready`) among the enabled transitions
    /// of its vehicle, so an event or a timer fires only in a marking
    /// tangible for its vehicle, and a deferred transition only before the
    /// events and after those of higher priority. A vehicle whose mission
    /// has ended (a final place marked in a marking stable for it) fires
    /// nothing more.
    fn replay(&self, snet: &Net, nsups: usize, path: &[TransitionId]) -> Option<Replayed> {
        let mut m = snet.initial_marking();
        let mut tracker = EnabledTracker::new(snet, &m).ok()?;
        let np = snet.place_count().checked_sub(nsups)?;
        let mut ready = Vec::new();
        let mut ended = vec![false; self.vehicles.len()];
        self.mark_ended(snet, &tracker, &m, &mut ended);
        for &t in path {
            let v = self.vehicles.iter().position(|r| r.contains(&t.0));
            if v.is_none_or(|v| ended[v]) || !self.ready(snet, &tracker, &m, t, &mut ready) {
                return None;
            }
            tracker.fire(snet, &mut m, t).ok()?;
            let mut took = false;
            for &k in self.take_back.get(t.index()).map_or(&[][..], |v| v.as_slice()) {
                let x = m.0.get_mut(np + k)?;
                took |= *x > 0;
                *x = x.saturating_sub(1);
            }
            if took {
                // A token taken outside the net's arcs: enabledness anew.
                tracker = EnabledTracker::new(snet, &m).ok()?;
            }
            self.mark_ended(snet, &tracker, &m, &mut ended);
        }
        Some(Replayed { marking: m, ended })
    }

    /// Marks the vehicles whose mission ends in `m`: a final place marked
    /// and no immediate nor zero-delay transition of theirs enabled (the
    /// player's end, `mcl_runtime::player`).
    fn mark_ended(&self, snet: &Net, tracker: &EnabledTracker, m: &Marking, ended: &mut [bool]) {
        for (v, range) in self.vehicles.iter().enumerate() {
            if ended[v] || !self.finals.get(v).is_some_and(|ps| ps.iter().any(|&p| m.get(p) > 0)) {
                continue;
            }
            let mine = |u: &&TransitionId| range.contains(&u.0) && !self.silent(m, **u);
            let settling = tracker.enabled_immediate().iter().any(|u| mine(&u))
                || tracker
                    .enabled_non_immediate()
                    .iter()
                    .filter(mine)
                    .any(|&u| snet.transitions()[u.index()].kind.is_deferred());
            ended[v] = !settling;
        }
    }

    /// True when `t` belongs to a vehicle that has ended.
    fn of_ended(&self, ended: &[bool], t: TransitionId) -> bool {
        self.vehicles.iter().position(|r| r.contains(&t.0)).is_some_and(|v| ended[v])
    }

    /// True when `t` is ready in `m` for its vehicle (`buf`: scratch).
    fn ready(
        &self,
        snet: &Net,
        tracker: &EnabledTracker,
        m: &Marking,
        t: TransitionId,
        buf: &mut Vec<TransitionId>,
    ) -> bool {
        let Some(range) = self.vehicles.iter().find(|r| r.contains(&t.0)) else { return false };
        // Another vehicle's mutex start may be waiting for its token.
        let flag = |f: &[bool], u: TransitionId| f.get(u.index()).copied().unwrap_or(false);
        let held = |u: TransitionId| u != t && (flag(self.remote, u) || flag(self.held, u));
        let mine = |u: &&TransitionId| range.contains(&u.0) && !self.silent(m, **u) && !held(**u);
        buf.clear();
        buf.extend(tracker.enabled_immediate().iter().filter(mine));
        // Its grant comes once the vehicle has settled.
        if flag(self.remote, t) && buf.iter().any(|&u| u != t) {
            return false;
        }
        if buf.is_empty() {
            buf.extend(tracker.enabled_non_immediate().iter().filter(mine));
        }
        select_ready(snet, buf);
        buf.contains(&t)
    }

    /// True when `t` never fires in `m` (an off-nominal answer).
    pub(super) fn silent(&self, m: &Marking, t: TransitionId) -> bool {
        self.quiet.get(t.index()).is_some_and(|ps| ps.iter().any(|&p| m.get(p) > 0))
    }
}

/// Turns a product state into a firing sequence of the real net, replays it
/// with exact counts, and describes the marking reached.
pub(super) fn concretize(
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
    let Replayed { marking: m, ended } = replay.rules.replay(snet, replay.nsups, &path)?;
    // What can still fire: the transitions of the vehicles that have not
    // ended (an ended vehicle is not deadlocked, whatever is enabled in it).
    let mut enabled = mcl_net::semantics::enabled(snet, &m);
    enabled.retain(|&t| !replay.rules.silent(&m, t) && !replay.rules.of_ended(&ended, t));
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
                let live = ts.iter().any(|&t| {
                    mcl_net::semantics::is_enabled(snet, &m, t)
                        && !replay.rules.silent(&m, t)
                        && !replay.rules.of_ended(&ended, t)
                });
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
    for t in snet.transition_ids().filter(|&t| !replay.rules.of_ended(&ended, t)) {
        // Enabled but for the supervisor places (the one enabledness test,
        // with those places counted as full).
        let plant_ok = is_enabled_with(snet, t, |p| if p.index() < np_plant { m.get(p) } else { u32::MAX });
        let missing: Vec<usize> = snet
            .pre(t)
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

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_net::{Delay, NetBuilder, Place, Transition, TransitionKind};

    /// Two vehicles: the first has an immediate `a`, an event `e` and two
    /// deferred `lo`, `hi` on one marked place; the second an event `f`.
    fn net() -> Net {
        let mut b = NetBuilder::new("s");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q").with_tokens(1));
        let a = b.add_transition(Transition::new("a"));
        let e = b.add_transition(Transition::new("e").with_kind(TransitionKind::Event("e".into())));
        let timed = |id: &str, prio| {
            Transition::new(id).with_kind(TransitionKind::Timed(Delay::Fixed(0.0))).with_priority(prio)
        };
        let lo = b.add_transition(timed("lo", 0));
        let hi = b.add_transition(timed("hi", 2));
        let f = b.add_transition(Transition::new("f").with_kind(TransitionKind::Event("f".into())));
        for t in [a, e, lo, hi] {
            b.add_input(p, t, 1);
        }
        b.add_input(q, f, 1);
        b.build().unwrap()
    }

    #[test]
    fn a_step_replays_only_if_its_vehicle_could_choose_it() {
        let snet = net();
        let vehicles = [0..4, 4..5];
        let rules =
            ReplayRules { vehicles: &vehicles, take_back: &[], quiet: &[], finals: &[], remote: &[], held: &[] };
        let replays = |path: &[u32]| {
            let path: Vec<TransitionId> = path.iter().map(|&t| TransitionId(t)).collect();
            rules.replay(&snet, 0, &path).is_some()
        };
        // The immediate `a` is ready; the event and the deferred ones wait.
        assert!(replays(&[0]));
        assert!(!replays(&[1]));
        assert!(!replays(&[2]));
        assert!(!replays(&[3]));
        // The other vehicle's event does not wait for `a`.
        assert!(replays(&[4, 0]));
        // Not enabled any more.
        assert!(!replays(&[0, 0]));
    }

    #[test]
    fn deferred_steps_replay_by_priority() {
        // `a` (immediate, transition 0) belongs to no vehicle here: the
        // vehicle 1..4 sees only `e`, `lo` and `hi`; `hi` goes first.
        let snet = net();
        let vehicles = [1..4, 4..5];
        let rules =
            ReplayRules { vehicles: &vehicles, take_back: &[], quiet: &[], finals: &[], remote: &[], held: &[] };
        let m = snet.initial_marking();
        let tracker = EnabledTracker::new(&snet, &m).unwrap();
        let mut buf = Vec::new();
        assert!(rules.ready(&snet, &tracker, &m, TransitionId(3), &mut buf));
        assert!(!rules.ready(&snet, &tracker, &m, TransitionId(2), &mut buf));
        assert!(!rules.ready(&snet, &tracker, &m, TransitionId(1), &mut buf));
    }
}
