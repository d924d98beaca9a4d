//! The pieces of the firing rule: enabledness, the P/T firing, the choice of
//! the ready transitions, the incremental enabled set and the seeded uniform
//! draw. The rule itself, with time, is stated once, in [`crate::engine`];
//! [`crate::engine::Engine`] plays a net by it, the player of `mcl-runtime`
//! plays missions on that engine, and [`mod@crate::explore`] (and with it the
//! block verifier) explores the same rule.
//!
//! * [`covers`] is the enabling condition (seed, Appendix A): every input
//!   place holds at least the arc's weight; [`is_enabled`] applies it to a
//!   [`Marking`], [`is_enabled_with`] to any marking representation;
//! * [`fire`] removes `w(p, t)` from each input place and adds `w(t, p)` to
//!   each output place;
//! * [`select_ready`] keeps, of an enabled set, the transitions the rule lets
//!   fire (immediate ones of highest priority in a vanishing marking, else
//!   deferred ones of highest priority, else all) and classifies the marking;
//! * [`EnabledTracker`] keeps the enabled set up to date after each firing by
//!   re-checking only the transitions that consume from places whose marking
//!   changed ([`Net::affected_by`]);
//! * [`uniform_index`] is the uniform draw among ready transitions, from a
//!   seedable ChaCha8 generator so that runs are reproducible.

use std::fmt;

use rand_chacha::rand_core::RngCore;

use crate::model::{Marking, Net, PlaceId, TransitionId};

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

/// The enabling condition itself, over any marking representation: every
/// `(place, weight)` of `pre` has `tokens(place) >= weight`.
///
/// This is the one enabledness test of the workspace: [`is_enabled`] applies
/// it to a [`Marking`], the explorer to its packed states (with its own place
/// keys: a bit field, or a word and a mask of 1-bit fields), the block
/// verifier to the states of a state space.
#[inline]
pub fn covers<K, W: PartialOrd>(pre: impl IntoIterator<Item = (K, W)>, mut tokens: impl FnMut(K) -> W) -> bool {
    pre.into_iter().all(|(k, w)| tokens(k) >= w)
}

/// True when `t` is enabled in the marking that `tokens` reads: `tokens(p)`
/// is the number of tokens in place `p` (a verifier's compact `u8` marking,
/// say). False for an unknown `t`.
#[inline]
pub fn is_enabled_with(net: &Net, t: TransitionId, tokens: impl FnMut(PlaceId) -> u32) -> bool {
    t.index() < net.transition_count() && covers(net.pre(t).iter().copied(), tokens)
}

/// True when `t` is enabled in `m` (false for an unknown `t`).
#[inline]
pub fn is_enabled(net: &Net, m: &Marking, t: TransitionId) -> bool {
    is_enabled_with(net, t, |p| m.get(p))
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
    pub(crate) fn scan(net: &Net, m: &Marking) -> Self {
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

    /// Transitions whose enabledness flipped since the last call (unordered).
    pub fn take_changed(&mut self) -> Vec<TransitionId> {
        let mut v = Vec::new();
        self.take_changed_into(&mut v);
        v
    }

    /// Appends to `buf` the transitions whose enabledness flipped since the
    /// last call, in the order [`EnabledTracker::take_changed`] gives them,
    /// without allocating; [`crate::engine::Engine`] arms and cancels timers
    /// with it.
    pub fn take_changed_into(&mut self, buf: &mut Vec<TransitionId>) {
        buf.extend_from_slice(&self.changed.items);
        self.changed.clear();
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{Delay, NetBuilder, Place, Transition, TransitionKind};

    /// Figure A.1 of the seed: T0, T2 immediate; T1 event `e1`; T3 timed 1 s
    /// (also the engine's tests' net).
    pub(crate) fn figure_a1() -> Net {
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
    fn figure_a1_classes_and_ready_sets() {
        let net = figure_a1();
        let m = net.initial_marking();
        assert_eq!(ready(&net, &m), (MarkingClass::Vanishing, vec![TransitionId(0)]));
        // {P1, P2}: T1 is enabled but waits for the immediate T2.
        let m = Marking(vec![0, 1, 1, 0]);
        assert!(is_enabled(&net, &m, TransitionId(1)));
        assert_eq!(ready(&net, &m), (MarkingClass::Vanishing, vec![TransitionId(2)]));
        let m = Marking(vec![0, 1, 0, 1]);
        assert_eq!(ready(&net, &m), (MarkingClass::Tangible, vec![TransitionId(1), TransitionId(3)]));
        assert!(!is_enabled(&net, &m, TransitionId(9)), "an unknown transition is never enabled");
    }

    #[test]
    fn enabledness_is_one_test_over_any_representation() {
        let net = figure_a1();
        let packed: u64 = 0b1010; // P1 and P3 marked, one bit per place
        for t in net.transition_ids() {
            let m = Marking(vec![0, 1, 0, 1]);
            let bits = is_enabled_with(&net, t, |p| ((packed >> p.index()) & 1) as u32);
            assert_eq!(bits, is_enabled(&net, &m, t));
        }
        assert!(covers([(0usize, 2u32), (1, 1)], |i| [2, 5][i]));
        assert!(!covers([(0usize, 3u32)], |i| [2][i]));
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
        let mut changed = Vec::new();
        tr.take_changed_into(&mut changed);
        assert!(!changed.is_empty());
        assert!(tr.take_changed().is_empty());
        assert!(matches!(EnabledTracker::new(&net, &Marking(vec![])), Err(FireError::MarkingSize { .. })));
    }

    #[test]
    fn overflow_leaves_the_marking_unchanged() {
        let mut m = Marking(vec![u32::MAX]);
        let mut b = NetBuilder::new("ovf");
        let p = b.add_place(Place::new("p"));
        let t = b.add_transition(Transition::new("t"));
        b.add_output(t, p, 1);
        let net = b.build().unwrap();
        assert_eq!(fire(&net, &mut m, t), Err(FireError::Overflow(p)));
        assert_eq!(m.0, vec![u32::MAX]);
        assert_eq!(fire(&net, &mut m, TransitionId(4)), Err(FireError::UnknownTransition(TransitionId(4))));
    }
}
