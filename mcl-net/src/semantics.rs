//! The firing rule, written once for the verifier and the player.
//!
//! Seed, Appendix A: a transition `t` is *enabled* in marking `m` when every
//! input place `p` holds at least `w(p, t)` tokens; firing removes `w(p, t)`
//! from each input place and adds `w(t, p)` to each output place.
//!
//! MCL adds the GSPN-style rule between immediate and non-immediate transitions:
//!
//! * a marking in which some immediate transition is enabled is **vanishing**;
//!   there, only the enabled immediate transitions of highest
//!   [priority](crate::Transition::priority) are *ready*;
//! * any other marking is **tangible**; there, if some *deferred* transition
//!   (timed with delay 0, [`TransitionKind::is_deferred`]) is enabled, the
//!   enabled deferred transitions of highest priority are ready: the player
//!   fires a zero-delay timer as soon as the marking is tangible, before it
//!   handles any event or later timer; otherwise the enabled event-driven and
//!   timed transitions are ready (an event or a timer decides which fires);
//! * among ready transitions one is chosen uniformly at random, with a seedable
//!   ChaCha8 generator so that runs are reproducible.
//!
//! [`select_ready`] is that rule; [`mod@crate::explore`] and [`Executor`] both call it.
//! [`EnabledTracker`] keeps the enabled set up to date after each firing by
//! re-checking only the transitions that consume from places whose marking
//! changed ([`Net::affected_by`]).

use std::fmt;

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::model::{Marking, Net, PlaceId, TransitionId, TransitionKind};

/// Whether immediate transitions are pending in a marking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MarkingClass {
    /// Some immediate transition is enabled; only immediate transitions may fire.
    Vanishing,
    /// No immediate transition is enabled; events and timers may fire.
    Tangible,
}

/// Why a transition could not fire.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FireError {
    /// The transition index is out of range.
    UnknownTransition(TransitionId),
    /// The transition is not enabled in the current marking.
    NotEnabled(TransitionId),
    /// The transition is enabled but the firing rule does not allow it now
    /// (a non-immediate or lower-priority transition in a vanishing marking).
    NotReady(TransitionId),
    /// An event or timer was delivered while immediate transitions were pending.
    NotTangible,
    /// Firing would push a place beyond `u32::MAX` tokens.
    Overflow(PlaceId),
    /// The marking does not have one entry per place of the net.
    MarkingSize {
        /// Places in the net.
        expected: usize,
        /// Entries in the marking.
        found: usize,
    },
    /// Immediate transitions kept firing for this many steps without reaching a
    /// tangible marking (a loop of immediate transitions).
    Livelock(usize),
}

impl fmt::Display for FireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FireError::UnknownTransition(t) => write!(f, "no transition #{}", t.0),
            FireError::NotEnabled(t) => write!(f, "transition #{} is not enabled", t.0),
            FireError::NotReady(t) => write!(
                f,
                "transition #{} is enabled but must wait: immediate transitions of higher priority are pending",
                t.0
            ),
            FireError::NotTangible => {
                write!(f, "immediate transitions are pending; events and timers must wait")
            }
            FireError::Overflow(p) => write!(f, "place #{} would exceed {} tokens", p.0, u32::MAX),
            FireError::MarkingSize { expected, found } => {
                write!(f, "marking has {found} entries but the net has {expected} places")
            }
            FireError::Livelock(n) => {
                write!(f, "immediate transitions fired {n} times without reaching a tangible marking")
            }
        }
    }
}

impl std::error::Error for FireError {}

/// True when `t` is enabled in `m` (false for an unknown `t`).
#[inline]
pub fn is_enabled(net: &Net, m: &Marking, t: TransitionId) -> bool {
    t.index() < net.transition_count() && net.pre(t).iter().all(|&(p, w)| m.get(p) >= w)
}

/// [`is_enabled`] on any marking: `tokens(p)` is the number of tokens in
/// place `p` (a verifier's compact `u8` marking, say). False for an unknown
/// `t`.
#[inline]
pub fn is_enabled_with(net: &Net, t: TransitionId, tokens: impl Fn(PlaceId) -> u32) -> bool {
    t.index() < net.transition_count() && net.pre(t).iter().all(|&(p, w)| tokens(p) >= w)
}

/// All transitions enabled in `m`, in index order.
pub fn enabled(net: &Net, m: &Marking) -> Vec<TransitionId> {
    net.transition_ids().filter(|&t| is_enabled(net, m, t)).collect()
}

/// Fires `t` in `m` (plain P/T rule, no immediate/tangible check).
///
/// On error `m` is left unchanged.
pub fn fire(net: &Net, m: &mut Marking, t: TransitionId) -> Result<(), FireError> {
    check_size(net, m)?;
    if t.index() >= net.transition_count() {
        return Err(FireError::UnknownTransition(t));
    }
    if !is_enabled(net, m, t) {
        return Err(FireError::NotEnabled(t));
    }
    for &(p, d) in net.delta(t) {
        if d > 0 && i64::from(m.0[p.index()]) + d > i64::from(u32::MAX) {
            return Err(FireError::Overflow(p));
        }
    }
    for &(p, d) in net.delta(t) {
        let slot = &mut m.0[p.index()];
        // In range: checked above (d > 0) or guaranteed by enabledness (d < 0).
        *slot = (i64::from(*slot) + d) as u32;
    }
    Ok(())
}

/// Applies the MCL firing rule to an enabled set, in place: keeps the ready
/// transitions and says whether the marking is vanishing or tangible.
///
/// If some immediate transition is enabled, keeps the enabled immediate
/// transitions of highest priority (vanishing). Otherwise (tangible), if
/// some deferred transition is enabled, keeps the enabled deferred
/// transitions of highest priority; else keeps everything. The relative
/// order of kept transitions is preserved.
pub fn select_ready(net: &Net, enabled: &mut Vec<TransitionId>) -> MarkingClass {
    let ts = net.transitions();
    let (mut best_imm, mut best_def): (Option<u32>, Option<u32>) = (None, None);
    for &t in enabled.iter() {
        if let Some(tr) = ts.get(t.index()) {
            let slot = if tr.kind.is_immediate() {
                &mut best_imm
            } else if tr.kind.is_deferred() {
                &mut best_def
            } else {
                continue;
            };
            let p = tr.effective_priority();
            *slot = Some(slot.map_or(p, |b| b.max(p)));
        }
    }
    let keep = |deferred: bool, b: u32, enabled: &mut Vec<TransitionId>| {
        enabled.retain(|&t| {
            ts.get(t.index()).is_some_and(|tr| {
                (if deferred { tr.kind.is_deferred() } else { tr.kind.is_immediate() }) && tr.effective_priority() == b
            })
        });
    };
    match (best_imm, best_def) {
        (Some(b), _) => {
            keep(false, b, enabled);
            MarkingClass::Vanishing
        }
        (None, Some(b)) => {
            keep(true, b, enabled);
            MarkingClass::Tangible
        }
        (None, None) => MarkingClass::Tangible,
    }
}

/// The ready transitions of `m` and its class (see [`select_ready`]).
pub fn ready(net: &Net, m: &Marking) -> (MarkingClass, Vec<TransitionId>) {
    let mut e = enabled(net, m);
    let class = select_ready(net, &mut e);
    (class, e)
}

/// Uniform index in `0..n` from `rng` (0 when `n` is 0), by Lemire's
/// multiply-and-reject method. Depends only on the generator's `u64` stream,
/// so a seed gives the same choices across library versions.
pub fn uniform_index(rng: &mut impl RngCore, n: usize) -> usize {
    if n == 0 {
        return 0;
    }
    let n = n as u64;
    let mut m = u128::from(rng.next_u64()) * u128::from(n);
    if (m as u64) < n {
        let threshold = n.wrapping_neg() % n;
        while (m as u64) < threshold {
            m = u128::from(rng.next_u64()) * u128::from(n);
        }
    }
    (m >> 64) as usize
}

fn check_size(net: &Net, m: &Marking) -> Result<(), FireError> {
    if m.len() == net.place_count() {
        Ok(())
    } else {
        Err(FireError::MarkingSize { expected: net.place_count(), found: m.len() })
    }
}

/// A set of transition ids with O(1) insert, remove and membership.
#[derive(Clone, Debug)]
struct IdSet {
    items: Vec<TransitionId>,
    pos: Vec<u32>,
}

const ABSENT: u32 = u32::MAX;

impl IdSet {
    fn new(n: usize) -> Self {
        IdSet { items: Vec::new(), pos: vec![ABSENT; n] }
    }

    fn insert(&mut self, t: TransitionId) {
        if self.pos[t.index()] == ABSENT {
            self.pos[t.index()] = self.items.len() as u32;
            self.items.push(t);
        }
    }

    fn remove(&mut self, t: TransitionId) {
        let i = self.pos[t.index()];
        if i != ABSENT {
            self.items.swap_remove(i as usize);
            if let Some(&moved) = self.items.get(i as usize) {
                self.pos[moved.index()] = i;
            }
            self.pos[t.index()] = ABSENT;
        }
    }

    fn clear(&mut self) {
        for t in self.items.drain(..) {
            self.pos[t.index()] = ABSENT;
        }
    }
}

/// Incrementally maintained enabled set of a marking.
///
/// After a firing, only [`Net::affected_by`] of the fired transition is
/// re-checked, never the whole net.
#[derive(Clone, Debug)]
pub struct EnabledTracker {
    enabled: Vec<bool>,
    immediate: IdSet,
    other: IdSet,
    changed: IdSet,
}

impl EnabledTracker {
    /// Scans every transition once.
    pub fn new(net: &Net, m: &Marking) -> Result<Self, FireError> {
        check_size(net, m)?;
        Ok(Self::scan(net, m))
    }

    /// Full scan; `m` must have one entry per place.
    fn scan(net: &Net, m: &Marking) -> Self {
        let n = net.transition_count();
        let mut tr = EnabledTracker {
            enabled: vec![false; n],
            immediate: IdSet::new(n),
            other: IdSet::new(n),
            changed: IdSet::new(n),
        };
        for t in net.transition_ids() {
            if is_enabled(net, m, t) {
                tr.set(net, t, true);
            }
        }
        tr.changed.clear();
        tr
    }

    fn set(&mut self, net: &Net, t: TransitionId, on: bool) {
        if self.enabled[t.index()] == on {
            return;
        }
        self.enabled[t.index()] = on;
        self.changed.insert(t);
        let imm = net.transition(t).is_some_and(|tr| tr.kind.is_immediate());
        let set = if imm { &mut self.immediate } else { &mut self.other };
        if on {
            set.insert(t);
        } else {
            set.remove(t);
        }
    }

    /// True when `t` is enabled.
    pub fn is_enabled(&self, t: TransitionId) -> bool {
        self.enabled.get(t.index()).copied().unwrap_or(false)
    }

    /// Enabled immediate transitions (unordered).
    pub fn enabled_immediate(&self) -> &[TransitionId] {
        &self.immediate.items
    }

    /// Enabled event-driven and timed transitions (unordered).
    pub fn enabled_non_immediate(&self) -> &[TransitionId] {
        &self.other.items
    }

    /// Vanishing when some immediate transition is enabled.
    pub fn class(&self) -> MarkingClass {
        if self.immediate.items.is_empty() {
            MarkingClass::Tangible
        } else {
            MarkingClass::Vanishing
        }
    }

    /// Ready transitions by [`select_ready`], sorted by index.
    pub fn ready(&self, net: &Net) -> Vec<TransitionId> {
        let mut v: Vec<TransitionId> =
            if self.immediate.items.is_empty() { self.other.items.clone() } else { self.immediate.items.clone() };
        v.sort_unstable();
        select_ready(net, &mut v);
        v
    }

    /// Fires `t` in `m` (plain rule) and updates the enabled set.
    pub fn fire(&mut self, net: &Net, m: &mut Marking, t: TransitionId) -> Result<(), FireError> {
        if self.enabled.len() != net.transition_count() {
            return Err(FireError::UnknownTransition(t));
        }
        fire(net, m, t)?;
        for u in net.affected_by(t) {
            let on = is_enabled(net, m, u);
            self.set(net, u, on);
        }
        Ok(())
    }

    /// Transitions whose enabledness flipped since the last call (unordered);
    /// the player uses it to arm and cancel timers.
    pub fn take_changed(&mut self) -> Vec<TransitionId> {
        let v = self.changed.items.clone();
        self.changed.clear();
        v
    }
}

/// Default bound on consecutive immediate firings in [`Executor::settle`].
pub const DEFAULT_SETTLE_LIMIT: usize = 100_000;

/// A net in a marking, firing by the MCL rule with reproducible random choice.
///
/// `N` is anything that can lend a [`Net`]: `Net`, `&Net`, `Arc<Net>`…
#[derive(Clone, Debug)]
pub struct Executor<N: AsRef<Net>> {
    net: N,
    marking: Marking,
    tracker: EnabledTracker,
    rng: ChaCha8Rng,
}

impl AsRef<Net> for Net {
    fn as_ref(&self) -> &Net {
        self
    }
}

impl<N: AsRef<Net>> Executor<N> {
    /// Starts in the initial marking with the given seed.
    pub fn new(net: N, seed: u64) -> Self {
        let marking = net.as_ref().initial_marking();
        let tracker = EnabledTracker::scan(net.as_ref(), &marking);
        Executor { net, marking, tracker, rng: ChaCha8Rng::seed_from_u64(seed) }
    }

    /// Starts in `marking`.
    pub fn with_marking(net: N, marking: Marking, seed: u64) -> Result<Self, FireError> {
        let tracker = EnabledTracker::new(net.as_ref(), &marking)?;
        Ok(Executor { net, marking, tracker, rng: ChaCha8Rng::seed_from_u64(seed) })
    }

    /// The net.
    pub fn net(&self) -> &Net {
        self.net.as_ref()
    }

    /// The current marking.
    pub fn marking(&self) -> &Marking {
        &self.marking
    }

    /// The enabled-set tracker.
    pub fn tracker(&self) -> &EnabledTracker {
        &self.tracker
    }

    /// Vanishing or tangible.
    pub fn class(&self) -> MarkingClass {
        self.tracker.class()
    }

    /// True when `t` is enabled.
    pub fn is_enabled(&self, t: TransitionId) -> bool {
        self.tracker.is_enabled(t)
    }

    /// Ready transitions, sorted by index.
    pub fn ready(&self) -> Vec<TransitionId> {
        self.tracker.ready(self.net.as_ref())
    }

    /// Fires `t` if the rule allows it now: `t` must be ready.
    pub fn fire(&mut self, t: TransitionId) -> Result<(), FireError> {
        let net = self.net.as_ref();
        if t.index() >= net.transition_count() {
            return Err(FireError::UnknownTransition(t));
        }
        if !self.tracker.is_enabled(t) {
            return Err(FireError::NotEnabled(t));
        }
        if self.tracker.class() == MarkingClass::Vanishing && !self.ready().contains(&t) {
            return Err(FireError::NotReady(t));
        }
        self.tracker.fire(net, &mut self.marking, t)
    }

    /// In a vanishing marking, fires one ready immediate transition chosen at
    /// random and returns it; in a tangible marking does nothing.
    pub fn step(&mut self) -> Result<Option<TransitionId>, FireError> {
        if self.tracker.class() == MarkingClass::Tangible {
            return Ok(None);
        }
        let ready = self.ready();
        if ready.is_empty() {
            return Ok(None);
        }
        let t = ready[uniform_index(&mut self.rng, ready.len())];
        self.tracker.fire(self.net.as_ref(), &mut self.marking, t)?;
        Ok(Some(t))
    }

    /// Fires immediate transitions until the marking is tangible; returns them
    /// in firing order. Fails with [`FireError::Livelock`] after `max_steps`.
    pub fn settle(&mut self, max_steps: usize) -> Result<Vec<TransitionId>, FireError> {
        let mut fired = Vec::new();
        while self.tracker.class() == MarkingClass::Vanishing {
            if fired.len() >= max_steps {
                return Err(FireError::Livelock(fired.len()));
            }
            match self.step()? {
                Some(t) => fired.push(t),
                None => break,
            }
        }
        Ok(fired)
    }

    /// Delivers `event`: in a tangible marking fires one enabled transition
    /// waiting for it, chosen at random. `Ok(None)` means no transition was
    /// waiting for it (the caller should report the dropped event).
    pub fn fire_event(&mut self, event: &str) -> Result<Option<TransitionId>, FireError> {
        if self.tracker.class() == MarkingClass::Vanishing {
            return Err(FireError::NotTangible);
        }
        let net = self.net.as_ref();
        let candidates: Vec<TransitionId> =
            net.event_transitions(event).iter().copied().filter(|&t| self.tracker.is_enabled(t)).collect();
        if candidates.is_empty() {
            return Ok(None);
        }
        let t = candidates[uniform_index(&mut self.rng, candidates.len())];
        self.tracker.fire(net, &mut self.marking, t)?;
        Ok(Some(t))
    }

    /// Fires timed transition `t` whose delay expired; it must be enabled and
    /// the marking tangible.
    pub fn fire_timed(&mut self, t: TransitionId) -> Result<(), FireError> {
        let net = self.net.as_ref();
        match net.transition(t).map(|tr| &tr.kind) {
            None => return Err(FireError::UnknownTransition(t)),
            Some(TransitionKind::Timed(_)) => {}
            Some(_) => return Err(FireError::NotReady(t)),
        }
        if self.tracker.class() == MarkingClass::Vanishing {
            return Err(FireError::NotTangible);
        }
        if !self.tracker.is_enabled(t) {
            return Err(FireError::NotEnabled(t));
        }
        self.tracker.fire(net, &mut self.marking, t)
    }

    /// Transitions whose enabledness flipped since the last call.
    pub fn take_changed(&mut self) -> Vec<TransitionId> {
        self.tracker.take_changed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Delay, NetBuilder, Place, Transition};

    /// Figure A.1 of the seed: T0, T2 immediate; T1, T3 non-immediate.
    fn figure_a1() -> Net {
        let mut b = NetBuilder::new("a1");
        let p: Vec<_> =
            (0..4).map(|i| b.add_place(Place::new(format!("P{i}")).with_tokens(u32::from(i == 0)))).collect();
        let t0 = b.add_transition(Transition::new("T0"));
        let t1 = b.add_transition(Transition::new("T1").with_kind(TransitionKind::Event("e1".into())));
        let t2 = b.add_transition(Transition::new("T2"));
        let t3 = b.add_transition(Transition::new("T3").with_kind(TransitionKind::Timed(Delay::Fixed(1.0))));
        b.add_input(p[0], t0, 1).add_output(t0, p[1], 1).add_output(t0, p[2], 1);
        b.add_input(p[1], t1, 1);
        b.add_input(p[2], t2, 1).add_output(t2, p[3], 1);
        b.add_input(p[3], t3, 1).add_output(t3, p[0], 1);
        b.build().unwrap()
    }

    #[test]
    fn figure_a1_immediate_first() {
        let net = figure_a1();
        let mut ex = Executor::new(&net, 7);
        assert_eq!(ex.class(), MarkingClass::Vanishing);
        assert_eq!(ex.fire(TransitionId(1)), Err(FireError::NotEnabled(TransitionId(1))));
        let fired = ex.settle(10).unwrap();
        assert_eq!(fired, vec![TransitionId(0), TransitionId(2)]);
        assert_eq!(ex.marking().0, vec![0, 1, 0, 1]);
        assert_eq!(ex.class(), MarkingClass::Tangible);
        assert_eq!(ex.ready(), vec![TransitionId(1), TransitionId(3)]);
        assert_eq!(ex.fire_event("nothing"), Ok(None));
        assert_eq!(ex.fire_event("e1"), Ok(Some(TransitionId(1))));
        assert_eq!(ex.marking().0, vec![0, 0, 0, 1]);
        ex.fire_timed(TransitionId(3)).unwrap();
        assert_eq!(ex.class(), MarkingClass::Vanishing);
        assert_eq!(ex.fire_event("e1"), Err(FireError::NotTangible));
    }

    #[test]
    fn non_immediate_waits_in_vanishing_marking() {
        let net = figure_a1();
        let mut ex = Executor::new(&net, 1);
        ex.fire(TransitionId(0)).unwrap(); // {P1, P2}: T1 enabled but T2 immediate
        assert!(ex.is_enabled(TransitionId(1)));
        assert_eq!(ex.fire(TransitionId(1)), Err(FireError::NotReady(TransitionId(1))));
        ex.fire(TransitionId(2)).unwrap();
        ex.fire(TransitionId(1)).unwrap();
    }

    #[test]
    fn priorities_filter_immediate_transitions() {
        let mut b = NetBuilder::new("prio");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let lo = b.add_transition(Transition::new("lo"));
        let hi = b.add_transition(Transition::new("hi").with_priority(3));
        b.add_input(p, lo, 1).add_input(p, hi, 1);
        let net = b.build().unwrap();
        let (class, r) = ready(&net, &net.initial_marking());
        assert_eq!(class, MarkingClass::Vanishing);
        assert_eq!(r, vec![hi]);
        for seed in 0..20 {
            let mut ex = Executor::new(&net, seed);
            assert_eq!(ex.step(), Ok(Some(hi)));
        }
    }

    #[test]
    fn deferred_transitions_fire_before_events_and_timers() {
        let mut b = NetBuilder::new("deferred");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let ev = b.add_transition(Transition::new("ev").with_kind(TransitionKind::Event("e".into())));
        let late = b.add_transition(Transition::new("late").with_kind(TransitionKind::Timed(Delay::Fixed(3.0))));
        let d0 = b.add_transition(Transition::new("d0").with_kind(TransitionKind::Timed(Delay::Fixed(0.0))));
        let d1 = b
            .add_transition(Transition::new("d1").with_kind(TransitionKind::Timed(Delay::Fixed(0.0))).with_priority(2));
        for t in [ev, late, d0, d1] {
            b.add_input(p, t, 1);
        }
        let net = b.build().unwrap();
        let (class, r) = ready(&net, &net.initial_marking());
        assert_eq!(class, MarkingClass::Tangible);
        assert_eq!(r, vec![d1], "deferred first, highest priority first");
    }

    #[test]
    fn tracker_matches_full_scan_and_reports_changes() {
        let net = figure_a1();
        let mut m = net.initial_marking();
        let mut tr = EnabledTracker::new(&net, &m).unwrap();
        let seq = [0u32, 2, 1, 3, 0];
        for &t in &seq {
            tr.fire(&net, &mut m, TransitionId(t)).unwrap();
            for u in net.transition_ids() {
                assert_eq!(tr.is_enabled(u), is_enabled(&net, &m, u));
            }
        }
        let mut changed = tr.take_changed();
        changed.sort();
        assert!(!changed.is_empty());
        assert!(tr.take_changed().is_empty());
    }

    #[test]
    fn seeded_choice_is_reproducible_and_uniform_enough() {
        let mut b = NetBuilder::new("choice");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let ts: Vec<_> = (0..4).map(|i| b.add_transition(Transition::new(format!("t{i}")))).collect();
        for &t in &ts {
            b.add_input(p, t, 1).add_output(t, p, 1);
        }
        let net = b.build().unwrap();
        let run = |seed| {
            let mut ex = Executor::new(&net, seed);
            (0..400).map(|_| ex.step().unwrap().unwrap().0).collect::<Vec<_>>()
        };
        assert_eq!(run(42), run(42));
        assert_ne!(run(42), run(43));
        let r = run(5);
        for i in 0..4 {
            let c = r.iter().filter(|&&x| x == i).count();
            assert!((60..140).contains(&c), "count {c}");
        }
    }

    #[test]
    fn livelock_and_errors_are_reported() {
        let mut b = NetBuilder::new("loop");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let t = b.add_transition(Transition::new("t"));
        b.add_input(p, t, 1).add_output(t, p, 1);
        let net = b.build().unwrap();
        let mut ex = Executor::new(&net, 0);
        assert_eq!(ex.settle(50), Err(FireError::Livelock(50)));
        assert_eq!(ex.fire(TransitionId(9)), Err(FireError::UnknownTransition(TransitionId(9))));
        assert!(matches!(Executor::with_marking(&net, Marking(vec![]), 0), Err(FireError::MarkingSize { .. })));
        let mut m = Marking(vec![u32::MAX]);
        let mut b = NetBuilder::new("ovf");
        let p = b.add_place(Place::new("p"));
        let t = b.add_transition(Transition::new("t"));
        b.add_output(t, p, 1);
        let net = b.build().unwrap();
        assert_eq!(fire(&net, &mut m, t), Err(FireError::Overflow(p)));
        assert_eq!(m.0, vec![u32::MAX]);
    }
}
