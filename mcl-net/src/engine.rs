//! The firing engine: a net played by the MCL firing rule, in mission time.
//!
//! # The firing rule
//!
//! This is the one statement of the rule; [`crate::semantics`] holds its
//! pieces, [`Engine`] plays it, the player of `mcl-runtime` runs missions on
//! an [`Engine`], and [`mod@crate::explore`] explores the same choices.
//!
//! 1. **Enabledness** (seed, Appendix A): `t` is enabled when every input
//!    place `p` holds at least `w(p, t)` tokens ([`semantics::covers`](crate::semantics::covers));
//!    firing removes `w(p, t)` from each input place and adds `w(t, p)` to
//!    each output place.
//! 2. **Immediate first** (GSPN): a marking in which some immediate
//!    transition is enabled is *vanishing*; there only the enabled immediate
//!    transitions of highest priority may fire, one chosen uniformly at
//!    random, until the marking is *tangible* ([`Engine::settle`]). A cascade
//!    longer than the step limit is a [`Livelock`].
//! 3. **Timers**: a timed transition's timer starts when the transition is
//!    enabled in a tangible marking (its delay comes from
//!    [`Hooks::delay`]) and is cancelled when it is disabled; a transition
//!    disabled and enabled again within one cascade restarts its timer, and a
//!    timed transition that fired and is still enabled starts a new one.
//!    *Deferred* transitions (delay 0) thus fire as soon as the marking is
//!    tangible, before any event ([`Engine::stabilize`]); more than the step
//!    limit of them at one instant is a [`Livelock`] too. Among the timers due
//!    at the same deadline, the rule's priorities choose
//!    ([`semantics::select_ready`](crate::semantics::select_ready): deferred ones of highest priority, when
//!    the net has priorities), then a uniform draw.
//! 4. **Events**: in a stable marking (tangible, no timer due) an event fires
//!    one enabled transition bound to it, chosen uniformly at random
//!    ([`Engine::deliver`]); an event that enables nothing changes nothing.
//!    Events that arrive together may be taken as one batch, in passes, with
//!    no other firing in between ([`Engine::deliver_batch`]).
//! 5. **Time**: before time moves to `t`, every timer due at or before `t`
//!    fires at its own deadline, and the net stabilizes after each
//!    ([`Engine::advance_to`]).
//!
//! Every random choice is a [`semantics::uniform_index`](crate::semantics::uniform_index) draw from one
//! ChaCha8 generator seeded by the caller, made only where there is a choice
//! (never for a single candidate), so a seed gives the same run.
//!
//! # Hooks
//!
//! What a caller adds to a firing (actions, bindings, outputs, parameter
//! delays, the end of a mission) goes through [`Hooks`], a generic parameter
//! of each method: the firing loop is monomorphised for the caller, with no
//! dynamic dispatch, and reuses its buffers (no allocation per firing).
//!
//! ```
//! use mcl_net::engine::Engine;
//! use mcl_net::{Delay, NetBuilder, Place, Transition, TransitionKind};
//!
//! let mut b = NetBuilder::new("ping");
//! let idle = b.add_place(Place::new("idle").with_tokens(1));
//! let busy = b.add_place(Place::new("busy"));
//! let go = b.add_transition(Transition::new("go").with_kind(TransitionKind::Event("go".into())));
//! let back = b.add_transition(Transition::new("back").with_kind(TransitionKind::Timed(Delay::Fixed(2.0))));
//! b.add_input(idle, go, 1).add_output(go, busy, 1);
//! b.add_input(busy, back, 1).add_output(back, idle, 1);
//! let mut e = Engine::new(b.build().unwrap(), 7);
//! e.start(0.0, &mut ()).unwrap();
//! assert_eq!(e.deliver("go", &mut ()), Ok(Some(go)));
//! assert_eq!(e.next_deadline(), Some(2.0));
//! e.advance_to(5.0, &mut ()).unwrap();
//! assert_eq!((e.marking().get(idle), e.now()), (1, 5.0));
//! ```

use std::collections::BTreeSet;
use std::fmt;
use std::ops::ControlFlow;

use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::model::{Delay, Marking, Net, TransitionId, TransitionKind};
use crate::semantics::{select_ready, uniform_index, EnabledTracker, FireError, MarkingClass};

/// Default bound on consecutive immediate firings, and on zero-delay timers
/// fired at one instant.
pub const DEFAULT_STEP_LIMIT: usize = 100_000;

impl AsRef<Net> for Net {
    fn as_ref(&self) -> &Net {
        self
    }
}

/// The net never reaches a stable marking: the engine stopped firing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Livelock {
    /// Immediate transitions fired `steps` times in a row without reaching a
    /// tangible marking.
    Immediate {
        /// Immediate firings.
        steps: usize,
        /// Mission time.
        at: f64,
    },
    /// `timers` zero-delay timers fired at one instant without time advancing.
    ZeroDelay {
        /// Zero-delay timers fired.
        timers: usize,
        /// Mission time.
        at: f64,
    },
}

impl Livelock {
    /// The mission time at which the engine stopped.
    pub fn at(&self) -> f64 {
        match *self {
            Livelock::Immediate { at, .. } | Livelock::ZeroDelay { at, .. } => at,
        }
    }
}

impl fmt::Display for Livelock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Livelock::Immediate { steps, .. } => write!(
                f,
                "livelock: immediate transitions fired {steps} times in a row without reaching a tangible marking"
            ),
            Livelock::ZeroDelay { timers, at } => write!(
                f,
                "livelock: {timers} zero-delay timers fired at t={at} s without time advancing (a loop whose tasks \
                 end at once?)"
            ),
        }
    }
}

impl std::error::Error for Livelock {}

/// What hooks may read of the engine while it fires.
#[derive(Clone, Copy, Debug)]
pub struct View<'a> {
    /// The net.
    pub net: &'a Net,
    /// The current marking.
    pub marking: &'a Marking,
    /// The enabled set of the current marking.
    pub tracker: &'a EnabledTracker,
    /// Mission time.
    pub now: f64,
}

/// What a caller adds to the engine's firings. Every method has a default
/// that does nothing (or reads the net), so `()` is the hook of a bare run.
pub trait Hooks {
    /// `t` fired (the marking in `v` is the new one).
    #[inline]
    fn fired(&mut self, v: View<'_>, t: TransitionId) {
        let _ = (v, t);
    }

    /// `t` could not fire (a place would overflow); nothing changed.
    #[inline]
    fn refused(&mut self, v: View<'_>, t: TransitionId, error: FireError) {
        let _ = (v, t, error);
    }

    /// The delay of timed transition `t`, whose timer starts now. By default
    /// a fixed delay as written, and a parameter delay never expires
    /// (`f64::INFINITY`): a caller with bindings resolves it.
    #[inline]
    fn delay(&mut self, v: View<'_>, t: TransitionId) -> f64 {
        match v.net.transition(t).map(|tr| &tr.kind) {
            Some(TransitionKind::Timed(Delay::Fixed(d))) => *d,
            _ => f64::INFINITY,
        }
    }

    /// The timer of `t` started: it fires at `deadline` (`v.now + delay`).
    #[inline]
    fn armed(&mut self, v: View<'_>, t: TransitionId, delay: f64, deadline: f64) {
        let _ = (v, t, delay, deadline);
    }

    /// `event` is about to fire `t` (called before [`Hooks::fired`]).
    #[inline]
    fn event(&mut self, v: View<'_>, event: &str, t: TransitionId) {
        let _ = (v, event, t);
    }

    /// The net is stable (tangible, no timer due now). `Break` stops
    /// [`Engine::advance_to`] from firing later timers (the mission ended).
    #[inline]
    fn stable(&mut self, v: View<'_>) -> ControlFlow<()> {
        let _ = v;
        ControlFlow::Continue(())
    }
}

impl Hooks for () {}

/// A total order key for non-negative finite deadlines.
#[inline]
fn time_key(t: f64) -> u64 {
    t.max(0.0).to_bits()
}

/// A net in a marking, played by the rule of the [module documentation](self)
/// with its timers and mission time.
///
/// `N` is anything that can lend a [`Net`]: `Net`, `&Net`, `Arc<Net>`…
#[derive(Clone, Debug)]
pub struct Engine<N: AsRef<Net>> {
    net: N,
    marking: Marking,
    tracker: EnabledTracker,
    rng: ChaCha8Rng,
    now: f64,
    step_limit: usize,
    /// Some transition has an explicit priority.
    has_priorities: bool,
    /// Per transition: it is timed.
    timed: Vec<bool>,
    /// Armed timer per transition: (deadline, arm id).
    armed: Vec<Option<(f64, u64)>>,
    /// (deadline key, arm id, transition) of every armed timer.
    timers: BTreeSet<(u64, u64, u32)>,
    arm_counter: u64,
    /// A timed transition that just fired and must be re-armed if still enabled.
    rearm: Option<TransitionId>,
    /// Scratch buffers, reused by every firing.
    buf: Vec<TransitionId>,
    changed: Vec<TransitionId>,
    ties: Vec<(u64, u64, u32)>,
}

impl<N: AsRef<Net>> Engine<N> {
    /// The net in its initial marking at time 0, choices drawn from `seed`.
    pub fn new(net: N, seed: u64) -> Self {
        let marking = net.as_ref().initial_marking();
        let tracker = EnabledTracker::scan(net.as_ref(), &marking);
        Self::build(net, marking, tracker, seed)
    }

    /// The net in `marking` at time 0.
    pub fn with_marking(net: N, marking: Marking, seed: u64) -> Result<Self, FireError> {
        let tracker = EnabledTracker::new(net.as_ref(), &marking)?;
        Ok(Self::build(net, marking, tracker, seed))
    }

    fn build(net: N, marking: Marking, tracker: EnabledTracker, seed: u64) -> Self {
        let n = net.as_ref();
        let timed = n.transitions().iter().map(|t| matches!(t.kind, TransitionKind::Timed(_))).collect();
        Engine {
            has_priorities: n.transitions().iter().any(|t| t.priority.is_some()),
            timed,
            armed: vec![None; n.transition_count()],
            net,
            marking,
            tracker,
            rng: ChaCha8Rng::seed_from_u64(seed),
            now: 0.0,
            step_limit: DEFAULT_STEP_LIMIT,
            timers: BTreeSet::new(),
            arm_counter: 0,
            rearm: None,
            buf: Vec::new(),
            changed: Vec::new(),
            ties: Vec::new(),
        }
    }

    /// Bounds consecutive immediate firings, and zero-delay timers fired at
    /// one instant, before a [`Livelock`] (default [`DEFAULT_STEP_LIMIT`]).
    pub fn with_step_limit(mut self, limit: usize) -> Self {
        self.step_limit = limit;
        self
    }

    /// The net.
    pub fn net(&self) -> &Net {
        self.net.as_ref()
    }

    /// The net as given to [`Engine::new`].
    pub fn net_handle(&self) -> &N {
        &self.net
    }

    /// The current marking.
    pub fn marking(&self) -> &Marking {
        &self.marking
    }

    /// The enabled set of the current marking.
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

    /// The ready transitions ([`semantics::select_ready`](crate::semantics::select_ready)), sorted by index.
    pub fn ready(&self) -> Vec<TransitionId> {
        self.tracker.ready(self.net.as_ref())
    }

    /// Mission time.
    pub fn now(&self) -> f64 {
        self.now
    }

    /// Moves the clock to `to` without firing anything (never backwards).
    pub fn set_clock(&mut self, to: f64) {
        self.now = self.now.max(to);
    }

    /// The earliest pending timer's deadline.
    pub fn next_deadline(&self) -> Option<f64> {
        self.timers.first().map(|&(k, _, _)| f64::from_bits(k))
    }

    /// Pending timers: (transition, deadline), earliest first.
    pub fn timers(&self) -> Vec<(TransitionId, f64)> {
        self.timers.iter().map(|&(k, _, t)| (TransitionId(t), f64::from_bits(k))).collect()
    }

    /// The deadline of `t`'s timer, if it is armed.
    pub fn deadline(&self, t: TransitionId) -> Option<f64> {
        self.armed.get(t.index()).copied().flatten().map(|(d, _)| d)
    }

    /// The events that some enabled transition waits for, sorted.
    pub fn awaited_events(&self) -> Vec<String> {
        let ts = self.net.as_ref().transitions();
        let mut v: Vec<String> = self
            .tracker
            .enabled_non_immediate()
            .iter()
            .filter_map(|&t| match &ts[t.index()].kind {
                TransitionKind::Event(e) => Some(e.clone()),
                _ => None,
            })
            .collect();
        v.sort();
        v.dedup();
        v
    }

    #[inline]
    fn view(&self) -> View<'_> {
        View { net: self.net.as_ref(), marking: &self.marking, tracker: &self.tracker, now: self.now }
    }

    /// Starts the run at time `now`: settles the initial cascade, starts the
    /// timers of the timed transitions enabled then (in index order) and
    /// stabilizes. Call it once.
    pub fn start<H: Hooks>(&mut self, now: f64, hooks: &mut H) -> Result<(), Livelock> {
        self.now = now;
        self.settle(hooks)?;
        // Timed transitions enabled from the initial marking on never
        // flipped, so `settle` did not arm them.
        self.buf.clear();
        self.buf.extend_from_slice(self.tracker.enabled_non_immediate());
        self.buf.sort_unstable();
        for i in 0..self.buf.len() {
            let t = self.buf[i];
            if self.timed[t.index()] && self.armed[t.index()].is_none() {
                self.arm(t, hooks);
            }
        }
        self.stabilize(hooks)
    }

    /// Fires immediate transitions until the marking is tangible (each chosen
    /// uniformly among the ready ones), then starts the timers of the timed
    /// transitions enabled since the last call and cancels those of the ones
    /// disabled.
    pub fn settle<H: Hooks>(&mut self, hooks: &mut H) -> Result<(), Livelock> {
        let mut steps = 0usize;
        loop {
            let imm = self.tracker.enabled_immediate();
            if imm.is_empty() {
                break;
            }
            if steps >= self.step_limit {
                return Err(Livelock::Immediate { steps, at: self.now });
            }
            let t = if self.has_priorities {
                self.buf.clear();
                self.buf.extend_from_slice(imm);
                self.buf.sort_unstable();
                select_ready(self.net.as_ref(), &mut self.buf);
                self.buf[uniform_index(&mut self.rng, self.buf.len())]
            } else {
                imm[uniform_index(&mut self.rng, imm.len())]
            };
            self.fire(t, hooks);
            steps += 1;
        }
        // The marking is tangible: start and cancel timers.
        self.changed.clear();
        self.tracker.take_changed_into(&mut self.changed);
        for i in 0..self.changed.len() {
            let t = self.changed[i];
            if self.timed[t.index()] {
                if self.tracker.is_enabled(t) {
                    self.arm(t, hooks);
                } else {
                    self.cancel(t);
                }
            }
        }
        if let Some(t) = self.rearm.take() {
            if self.tracker.is_enabled(t) && self.armed[t.index()].is_none() {
                self.arm(t, hooks);
            }
        }
        Ok(())
    }

    /// Settles, then fires the timers due now (zero-delay ones), settling
    /// after each, until the net is stable; then calls [`Hooks::stable`].
    pub fn stabilize<H: Hooks>(&mut self, hooks: &mut H) -> Result<(), Livelock> {
        self.stabilize_flow(hooks).map(|_| ())
    }

    fn stabilize_flow<H: Hooks>(&mut self, hooks: &mut H) -> Result<ControlFlow<()>, Livelock> {
        let mut timers = 0usize;
        loop {
            self.settle(hooks)?;
            match self.next_deadline() {
                Some(d) if d <= self.now => {
                    timers += 1;
                    if timers > self.step_limit {
                        return Err(Livelock::ZeroDelay { timers: timers - 1, at: self.now });
                    }
                    if let Some(t) = self.pop_due_timer() {
                        self.fire(t, hooks);
                    }
                }
                _ => break,
            }
        }
        Ok(hooks.stable(self.view()))
    }

    /// Delivers `event` in a stable marking: fires one enabled transition
    /// bound to it, chosen uniformly, then stabilizes. `Ok(None)` when no
    /// transition waits for it, or immediate transitions are pending (before
    /// [`Engine::start`], after a livelock): nothing changed.
    pub fn deliver<H: Hooks>(&mut self, event: &str, hooks: &mut H) -> Result<Option<TransitionId>, Livelock> {
        if self.tracker.class() == MarkingClass::Vanishing {
            return Ok(None);
        }
        let Some(t) = self.fire_event(event, hooks) else { return Ok(None) };
        self.stabilize(hooks)?;
        Ok(Some(t))
    }

    /// Delivers events that arrived together, before the net reacts: each
    /// fires one enabled transition bound to it (chosen uniformly), in order,
    /// in passes while some still can, with no other firing in between; the
    /// net then stabilizes once if anything fired. The events that enabled
    /// nothing stay in `events`, in their order. True when something fired.
    pub fn deliver_batch<H: Hooks>(&mut self, events: &mut Vec<String>, hooks: &mut H) -> Result<bool, Livelock> {
        let mut fired = false;
        loop {
            let before = events.len();
            events.retain(|e| {
                let hit = self.fire_event(e, hooks).is_some();
                fired |= hit;
                !hit
            });
            if events.is_empty() || events.len() == before {
                break;
            }
        }
        if fired {
            self.stabilize(hooks)?;
        }
        Ok(fired)
    }

    /// Fires one enabled transition bound to `event`, chosen uniformly.
    fn fire_event<H: Hooks>(&mut self, event: &str, hooks: &mut H) -> Option<TransitionId> {
        let waiting = self.net.as_ref().event_transitions(event);
        let n = waiting.iter().filter(|&&c| self.tracker.is_enabled(c)).count();
        if n == 0 {
            return None;
        }
        let k = uniform_index(&mut self.rng, n);
        let t = waiting.iter().copied().filter(|&c| self.tracker.is_enabled(c)).nth(k)?;
        hooks.event(self.view(), event, t);
        self.fire(t, hooks);
        Some(t)
    }

    /// Time passes to `to`: fires every timer due at or before `to`, each at
    /// its own deadline, stabilizing after each, until [`Hooks::stable`]
    /// says stop; the clock is then at `to` (never moved backwards), also
    /// after a livelock ([`Livelock::at`] says when it happened).
    pub fn advance_to<H: Hooks>(&mut self, to: f64, hooks: &mut H) -> Result<(), Livelock> {
        let r = self.fire_due(to, hooks);
        self.now = self.now.max(to);
        r
    }

    fn fire_due<H: Hooks>(&mut self, to: f64, hooks: &mut H) -> Result<(), Livelock> {
        while let Some(d) = self.next_deadline() {
            if d > to {
                break;
            }
            self.now = self.now.max(d);
            if let Some(t) = self.pop_due_timer() {
                self.fire(t, hooks);
            }
            if self.stabilize_flow(hooks)?.is_break() {
                break;
            }
        }
        Ok(())
    }

    /// Fires `t` (enabled), cancels its timer and tells the hooks.
    #[inline]
    fn fire<H: Hooks>(&mut self, t: TransitionId, hooks: &mut H) {
        if let Err(e) = self.tracker.fire(self.net.as_ref(), &mut self.marking, t) {
            hooks.refused(self.view(), t, e);
            return;
        }
        if self.timed[t.index()] {
            self.cancel(t);
            self.rearm = Some(t);
        }
        hooks.fired(self.view(), t);
    }

    fn arm<H: Hooks>(&mut self, t: TransitionId, hooks: &mut H) {
        self.cancel(t);
        let d = hooks.delay(self.view(), t);
        let deadline = self.now + d;
        self.arm_counter += 1;
        self.armed[t.index()] = Some((deadline, self.arm_counter));
        self.timers.insert((time_key(deadline), self.arm_counter, t.0));
        hooks.armed(self.view(), t, d, deadline);
    }

    fn cancel(&mut self, t: TransitionId) {
        if let Some((deadline, id)) = self.armed[t.index()].take() {
            self.timers.remove(&(time_key(deadline), id, t.0));
        }
    }

    /// Removes and returns one of the timers with the earliest deadline:
    /// among ties, the ready ones by [`select_ready`] (when the net has
    /// priorities), then a uniform draw.
    fn pop_due_timer(&mut self) -> Option<TransitionId> {
        let &(k, _, _) = self.timers.first()?;
        self.ties.clear();
        self.ties.extend(self.timers.range((k, 0, 0)..=(k, u64::MAX, u32::MAX)).copied());
        if self.ties.len() > 1 && self.has_priorities {
            self.buf.clear();
            self.buf.extend(self.ties.iter().map(|&(_, _, t)| TransitionId(t)));
            select_ready(self.net.as_ref(), &mut self.buf);
            let keep = &self.buf;
            self.ties.retain(|&(_, _, t)| keep.contains(&TransitionId(t)));
        }
        let i = if self.ties.len() == 1 { 0 } else { uniform_index(&mut self.rng, self.ties.len()) };
        let pick = *self.ties.get(i)?;
        self.timers.remove(&pick);
        let t = TransitionId(pick.2);
        self.armed[t.index()] = None;
        Some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{NetBuilder, Place, Transition};

    /// Records the firings and timers.
    #[derive(Default)]
    struct Log {
        fired: Vec<TransitionId>,
        armed: Vec<(TransitionId, f64)>,
        events: Vec<(String, TransitionId)>,
    }

    impl Hooks for Log {
        fn fired(&mut self, _: View<'_>, t: TransitionId) {
            self.fired.push(t);
        }
        fn armed(&mut self, _: View<'_>, t: TransitionId, _: f64, deadline: f64) {
            self.armed.push((t, deadline));
        }
        fn event(&mut self, _: View<'_>, event: &str, t: TransitionId) {
            self.events.push((event.to_string(), t));
        }
    }

    fn ids(v: &[u32]) -> Vec<TransitionId> {
        v.iter().map(|&i| TransitionId(i)).collect()
    }

    use crate::semantics::tests::figure_a1;

    #[test]
    fn figure_a1_immediate_first_then_events_and_timers() {
        let net = figure_a1();
        let mut e = Engine::new(&net, 7);
        let mut log = Log::default();
        assert_eq!(e.class(), MarkingClass::Vanishing);
        assert_eq!(e.deliver("e1", &mut log), Ok(None), "events wait while immediate transitions are pending");
        e.start(0.0, &mut log).unwrap();
        assert_eq!(log.fired, ids(&[0, 2]));
        assert_eq!(e.marking().0, vec![0, 1, 0, 1]);
        assert_eq!(e.class(), MarkingClass::Tangible);
        assert_eq!(e.ready(), ids(&[1, 3]));
        assert_eq!(e.timers(), vec![(TransitionId(3), 1.0)]);
        assert_eq!(e.awaited_events(), vec!["e1".to_string()]);
        assert_eq!(e.deliver("nothing", &mut log), Ok(None));
        assert_eq!(e.deliver("e1", &mut log), Ok(Some(TransitionId(1))));
        assert_eq!(log.events, vec![("e1".to_string(), TransitionId(1))]);
        assert_eq!(e.marking().0, vec![0, 0, 0, 1]);
        e.advance_to(0.5, &mut log).unwrap();
        assert_eq!((e.now(), log.fired.len()), (0.5, 3), "nothing due before 1 s");
        e.advance_to(1.5, &mut log).unwrap();
        // T3 fired at its deadline, then the cascade T0, T2 and a new timer.
        assert_eq!(log.fired, ids(&[0, 2, 1, 3, 0, 2]));
        assert_eq!(log.armed, vec![(TransitionId(3), 1.0), (TransitionId(3), 2.0)]);
        assert_eq!((e.now(), e.next_deadline()), (1.5, Some(2.0)));
    }

    #[test]
    fn priorities_choose_the_immediate_transition() {
        let mut b = NetBuilder::new("prio");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let lo = b.add_transition(Transition::new("lo"));
        let hi = b.add_transition(Transition::new("hi").with_priority(3));
        b.add_input(p, lo, 1).add_input(p, hi, 1);
        let net = b.build().unwrap();
        for seed in 0..20 {
            let mut log = Log::default();
            Engine::new(&net, seed).settle(&mut log).unwrap();
            assert_eq!(log.fired, vec![hi]);
        }
    }

    #[test]
    fn deferred_timers_fire_before_events_highest_priority_first() {
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
        for seed in 0..20 {
            let mut e = Engine::new(&net, seed);
            let mut log = Log::default();
            e.start(0.0, &mut log).unwrap();
            assert_eq!(log.fired, vec![d1]);
            assert_eq!(log.armed, vec![(late, 3.0), (d0, 0.0), (d1, 0.0)], "started in index order");
            assert!(e.timers().is_empty(), "the others were disabled: their timers are cancelled");
            assert_eq!(e.deliver("e", &mut log), Ok(None));
        }
    }

    #[test]
    fn ties_at_one_deadline_are_drawn_uniformly_and_reproducibly() {
        let mut b = NetBuilder::new("ties");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let ts: Vec<_> = (0..3)
            .map(|i| {
                let t = b.add_transition(
                    Transition::new(format!("t{i}")).with_kind(TransitionKind::Timed(Delay::Fixed(2.0))),
                );
                b.add_input(p, t, 1);
                t
            })
            .collect();
        let net = b.build().unwrap();
        let first = |seed| {
            let mut e = Engine::new(&net, seed);
            let mut log = Log::default();
            e.start(0.0, &mut log).unwrap();
            e.advance_to(10.0, &mut log).unwrap();
            assert_eq!(log.fired.len(), 1);
            assert!(e.timers().is_empty());
            log.fired[0]
        };
        let picks: Vec<_> = (0..60).map(first).collect();
        assert_eq!(picks, (0..60).map(first).collect::<Vec<_>>());
        for t in ts {
            assert!(picks.contains(&t), "{t:?} never chosen");
        }
    }

    #[test]
    fn a_timed_transition_still_enabled_after_firing_starts_again() {
        let mut b = NetBuilder::new("tick");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let n = b.add_place(Place::new("n"));
        let tick = b.add_transition(Transition::new("tick").with_kind(TransitionKind::Timed(Delay::Fixed(1.5))));
        b.add_input(p, tick, 1).add_output(tick, p, 1).add_output(tick, n, 1);
        let net = b.build().unwrap();
        let mut e = Engine::new(&net, 0);
        let mut log = Log::default();
        e.start(0.0, &mut log).unwrap();
        e.advance_to(4.0, &mut log).unwrap();
        assert_eq!(log.armed, vec![(tick, 1.5), (tick, 3.0), (tick, 4.5)]);
        assert_eq!((e.marking().get(n), e.deadline(tick)), (2, Some(4.5)));
    }

    #[test]
    fn a_batch_fires_in_passes_before_the_net_reacts() {
        // e2 waits for a token that e1's transition puts; the immediate `go`
        // consumes it as soon as the net may react.
        let mut b = NetBuilder::new("batch");
        let a = b.add_place(Place::new("a").with_tokens(1));
        let mid = b.add_place(Place::new("mid"));
        let end = b.add_place(Place::new("end"));
        let t1 = b.add_transition(Transition::new("t1").with_kind(TransitionKind::Event("e1".into())));
        let t2 = b.add_transition(Transition::new("t2").with_kind(TransitionKind::Event("e2".into())));
        let go = b.add_transition(Transition::new("go"));
        b.add_input(a, t1, 1).add_output(t1, mid, 1).add_output(t1, end, 1);
        b.add_input(mid, t2, 1);
        b.add_input(mid, go, 1);
        let net = b.build().unwrap();
        let mut e = Engine::new(&net, 3);
        let mut log = Log::default();
        e.start(0.0, &mut log).unwrap();
        let mut events = vec!["e2".to_string(), "zz".to_string(), "e1".to_string()];
        assert_eq!(e.deliver_batch(&mut events, &mut log), Ok(true));
        assert_eq!(events, vec!["zz".to_string()]);
        assert_eq!(log.fired, vec![t1, t2], "no immediate firing between the events");
        assert_eq!(e.marking().0, vec![0, 0, 1]);
        let mut none = vec!["zz".to_string()];
        assert_eq!(e.deliver_batch(&mut none, &mut log), Ok(false));
        assert_eq!(none, vec!["zz".to_string()]);
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
            let mut e = Engine::new(&net, seed).with_step_limit(400);
            let mut log = Log::default();
            assert_eq!(e.settle(&mut log), Err(Livelock::Immediate { steps: 400, at: 0.0 }));
            log.fired.iter().map(|t| t.0).collect::<Vec<_>>()
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
    fn livelocks_are_reported() {
        let mut b = NetBuilder::new("loop");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q"));
        let t0 = b.add_transition(Transition::new("t0"));
        let t1 = b.add_transition(Transition::new("t1").with_kind(TransitionKind::Timed(Delay::Fixed(0.0))));
        b.add_input(p, t0, 1).add_output(t0, q, 1).add_input(q, t1, 1).add_output(t1, p, 1);
        let net = b.build().unwrap();
        let mut e = Engine::new(&net, 0).with_step_limit(10);
        let err = e.start(2.0, &mut ()).unwrap_err();
        assert_eq!(err, Livelock::ZeroDelay { timers: 10, at: 2.0 });
        assert!(err.to_string().contains("zero-delay timers"), "{err}");
        assert!(matches!(Engine::with_marking(&net, Marking(vec![]), 0), Err(FireError::MarkingSize { .. })));
    }

    #[test]
    fn parameter_delays_never_expire_without_hooks() {
        let mut b = NetBuilder::new("param");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let t = b.add_transition(Transition::new("t").with_kind(TransitionKind::Timed(Delay::Param("timeout".into()))));
        b.add_input(p, t, 1);
        let net = b.build().unwrap();
        let mut e = Engine::new(net, 0);
        e.start(0.0, &mut ()).unwrap();
        e.advance_to(1e12, &mut ()).unwrap();
        assert_eq!((e.marking().0.clone(), e.next_deadline()), (vec![1], Some(f64::INFINITY)));
    }
}
