//! The Petri net player (seed 5.8): a *sans-IO* state machine that executes a
//! compiled mission net.
//!
//! The caller owns time and I/O: it calls [`Player::start`], then
//! [`Player::on_event`], [`Player::on_perception`] and [`Player::on_timer`] with
//! the current time in seconds, sends the [`Output::Send`] actions it gets
//! back, records the rest, and wakes the player at [`Player::next_deadline`].
//! The same player runs in virtual time and in real time.
//!
//! # Firing rule
//!
//! The one semantics of `mcl-net` (seed Appendix A):
//!
//! 1. **Immediate** transitions fire first, one chosen at random (seeded
//!    ChaCha8, [`mcl_net::semantics::uniform_index`]) among the enabled ones,
//!    until none is enabled: the marking is then *tangible*. A cascade longer
//!    than [`PlayerOptions::step_limit`] is a livelock and ends the mission as
//!    stuck; so are more than `step_limit` zero-delay timers fired at one
//!    instant without any input (`while ( True() ) { Void() }` with tasks
//!    that end at once: each call's `release` is a zero-delay timer).
//! 2. **Timed** transitions: a timer starts when the transition becomes
//!    enabled in a tangible marking and is cancelled when it is disabled (it
//!    starts from zero the next time). A transition disabled and re-enabled
//!    within one cascade of immediate firings restarts its timer. A delay
//!    `Param(p)` is read, when the timer starts, from the current binding of
//!    the transition's task (the arguments of the last call that started it):
//!    a number of seconds, else a symbol looked up in the run's symbol table
//!    (`--set timeout=60`, a scenario's `[symbols]`), else
//!    [`PlayerOptions::default_delay`] with a warning. Zero-delay timed
//!    transitions (*deferred*, used by the compiler for aborts) therefore fire
//!    as soon as the marking is tangible, before any event is delivered. When
//!    several timers are due at the same instant one is chosen at random, and
//!    the net settles again after each firing.
//! 3. **Events**: an event fires one enabled transition bound to it (random
//!    among several). An event that enables nothing is reported as an
//!    [`Output::Unexpected`] and changes nothing; it is never fatal.
//! 4. **Activations**: an event may name its *activation*, the `seq` of the
//!    action that started the primitive run that raised it
//!    ([`Player::on_event_from`], `docs/aac-protocol.md` §6). The player
//!    keeps, per primitive, the actions sent to it since it was last
//!    disabled (an action whose command is `disable`), or that `disable`
//!    while it stays disabled; an event whose activation is not one of them
//!    comes from a run that was disabled since (a late answer that crossed
//!    the `disable` on the wire): it is reported as [`Output::Stale`] and
//!    changes nothing, so that it is never credited to a later call of the
//!    same task.
//!
//! Before an event or a perception is handled, every timer due at or before
//! its time fires (at its own deadline), so a time-out and an answer that
//! arrive at the same instant resolve as "time-out first".
//!
//! The mission ends when `mission.ok` or `mission.fail` is marked and the net
//! has settled (no immediate transition enabled, no timer due now). It is
//! *stuck* when the marking is tangible and no event-driven or timed
//! transition is enabled: nothing can ever fire again.
//!
//! Enabledness is maintained incrementally by [`EnabledTracker`]; the player
//! never rescans the whole net after a firing (compare the seed's Extract 5.8,
//! benchmarked in `benches/player.rs`).

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::sync::Arc;

use mcl_net::semantics::{select_ready, uniform_index};
use mcl_net::{Delay, EnabledTracker, Marking, Net, PlaceId, TransitionId, TransitionKind};
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value};

use crate::link::Action;

/// Default bound on consecutive immediate firings.
pub const DEFAULT_STEP_LIMIT: usize = 100_000;
/// Delay used when a `Param` delay cannot be resolved to a number.
pub const DEFAULT_PARAM_DELAY: f64 = 60.0;
/// The place whose marking means the mission ended in ok.
pub const MISSION_OK: &str = "mission.ok";
/// The place whose marking means the mission ended in fail.
pub const MISSION_FAIL: &str = "mission.fail";

/// How a player is set up.
#[derive(Clone, Debug)]
pub struct PlayerOptions {
    /// Seed of the random choice among ready transitions.
    pub seed: u64,
    /// Values of symbolic call arguments (`timeout`, `altitude`...): used for
    /// `Param` delays and substituted in action parameters.
    pub symbols: BTreeMap<String, Value>,
    /// Bound on consecutive immediate firings, and on zero-delay timers fired
    /// at one instant without any input, before reporting a livelock.
    pub step_limit: usize,
    /// Delay of a timed transition whose `Param` delay has no numeric value.
    pub default_delay: f64,
}

impl Default for PlayerOptions {
    fn default() -> Self {
        PlayerOptions {
            seed: 0,
            symbols: BTreeMap::new(),
            step_limit: DEFAULT_STEP_LIMIT,
            default_delay: DEFAULT_PARAM_DELAY,
        }
    }
}

impl PlayerOptions {
    /// Options with this seed and defaults otherwise.
    pub fn seeded(seed: u64) -> Self {
        PlayerOptions { seed, ..Default::default() }
    }
}

/// How a mission ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Outcome {
    /// `mission.ok` was marked.
    Ok,
    /// `mission.fail` was marked.
    Fail,
    /// Nothing can fire any more (or immediate transitions loop forever).
    Stuck,
}

impl Outcome {
    /// `ok`, `fail` or `stuck`, as written in traces.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Ok => "ok",
            Outcome::Fail => "fail",
            Outcome::Stuck => "stuck",
        }
    }
}

/// What the player produces: actions to send and facts to record.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// Send this action to the vehicle.
    Send {
        /// Time of the firing that sent it.
        t: f64,
        /// The action, with its sequence number and resolved parameters.
        action: Action,
    },
    /// A transition fired.
    Fired {
        /// Time of the firing.
        t: f64,
        /// The transition.
        transition: TransitionId,
        /// The call site it served (its own, or its task's current call).
        call_site: Option<u32>,
    },
    /// An event was received and fired `transition` (a [`Output::Fired`] follows).
    Event {
        /// Time of reception.
        t: f64,
        /// Event name.
        event: String,
        /// The transition it fired.
        transition: TransitionId,
        /// The current call of the transition's task.
        call_site: Option<u32>,
        /// The activation the event named, if any.
        activation: Option<u64>,
    },
    /// An event named an activation that is no longer current (its
    /// primitive was disabled since): ignored.
    Stale {
        /// Time of reception.
        t: f64,
        /// Event name.
        event: String,
        /// The activation it named (the `seq` of an action).
        activation: u64,
        /// Why it is stale.
        reason: String,
    },
    /// An event was received while no transition bound to it was enabled.
    Unexpected {
        /// Time of reception.
        t: f64,
        /// Event name.
        event: String,
        /// Why it changed nothing.
        reason: &'static str,
    },
    /// A timed transition with a positive delay was armed.
    Timer {
        /// When the timer started.
        t: f64,
        /// The timed transition.
        transition: TransitionId,
        /// When it fires if it stays enabled.
        deadline: f64,
    },
    /// A perception was received.
    Perception {
        /// Time of reception.
        t: f64,
        /// Perception name.
        name: String,
        /// Its value.
        value: Value,
    },
    /// Something worth telling the operator.
    Warning {
        /// When.
        t: f64,
        /// What.
        message: String,
    },
    /// The mission ended.
    Outcome {
        /// When.
        t: f64,
        /// How.
        outcome: Outcome,
        /// Why, for a stuck mission.
        reason: Option<String>,
    },
}

impl Output {
    /// The time of the output.
    pub fn time(&self) -> f64 {
        match self {
            Output::Send { t, .. }
            | Output::Fired { t, .. }
            | Output::Event { t, .. }
            | Output::Stale { t, .. }
            | Output::Unexpected { t, .. }
            | Output::Timer { t, .. }
            | Output::Perception { t, .. }
            | Output::Warning { t, .. }
            | Output::Outcome { t, .. } => *t,
        }
    }
}

/// Where an action parameter's value comes from.
#[derive(Clone, Debug)]
enum ParamSrc {
    Const(Value),
    /// The task parameter of that name in the current binding.
    Param(String),
}

#[derive(Clone, Debug)]
struct ActionTemplate {
    action: String,
    primitive: String,
    /// Index of the primitive in [`Player::live`].
    prim: u32,
    /// The command is `disable`: the primitive's runs end.
    stops: bool,
    command: String,
    params: Vec<(String, ParamSrc)>,
}

#[derive(Clone, Debug)]
enum Kind {
    Immediate,
    Event,
    Timed(Delay),
}

/// Per-transition data, precomputed once.
#[derive(Clone, Debug)]
struct TInfo {
    kind: Kind,
    task: Option<u32>,
    call_site: Option<u32>,
    /// For a call's start transition: the call's arguments, parsed.
    args: Option<Arc<Vec<(String, Value)>>>,
    actions: Vec<ActionTemplate>,
}

#[derive(Clone, Debug)]
struct TaskState {
    name: String,
    /// The start transition of the task's current call.
    binding: Option<TransitionId>,
}

/// A total order key for non-negative finite deadlines.
fn time_key(t: f64) -> u64 {
    t.max(0.0).to_bits()
}

/// The player. See the [module documentation](self).
#[derive(Clone, Debug)]
pub struct Player {
    net: Arc<Net>,
    opts: PlayerOptions,
    marking: Marking,
    tracker: EnabledTracker,
    rng: ChaCha8Rng,
    info: Vec<TInfo>,
    tasks: Vec<TaskState>,
    has_priorities: bool,
    ok_place: Option<PlaceId>,
    fail_place: Option<PlaceId>,
    now: f64,
    seq: u64,
    /// Armed timer per transition: (deadline, arm id).
    armed: Vec<Option<(f64, u64)>>,
    /// (deadline key, arm id, transition) of every armed timer.
    timers: BTreeSet<(u64, u64, u32)>,
    arm_counter: u64,
    /// A timed transition that just fired and must be re-armed if still enabled.
    rearm: Option<TransitionId>,
    started: bool,
    outcome: Option<Outcome>,
    fired: u64,
    /// Delay warnings already given (each is given once).
    warned: BTreeSet<String>,
    /// Per primitive: its current activations, the actions sent to it since
    /// it was last disabled, or that `disable` while it stays disabled
    /// (`stopped`).
    live: Vec<Vec<Action>>,
    stopped: Vec<bool>,
    /// Every seq of `live`.
    live_seqs: HashSet<u64>,
}

impl Player {
    /// A player for `net` in its initial marking. Nothing fires before [`Player::start`].
    pub fn new(net: Arc<Net>, opts: PlayerOptions) -> Self {
        let marking = net.initial_marking();
        let tracker = EnabledTracker::new(&net, &marking).expect("the initial marking fits the net");
        let mut tasks: Vec<TaskState> = Vec::new();
        let mut task_index: BTreeMap<String, u32> = BTreeMap::new();
        let mut info = Vec::with_capacity(net.transition_count());
        let mut prims: HashMap<String, u32> = HashMap::new();
        for tr in net.transitions() {
            let task = tr.provenance.task.as_ref().or(tr.binding.as_ref().map(|b| &b.task)).map(|name| {
                *task_index.entry(name.clone()).or_insert_with(|| {
                    tasks.push(TaskState { name: name.clone(), binding: None });
                    tasks.len() as u32 - 1
                })
            });
            let kind = match &tr.kind {
                TransitionKind::Immediate => Kind::Immediate,
                TransitionKind::Event(_) => Kind::Event,
                TransitionKind::Timed(d) => Kind::Timed(d.clone()),
            };
            let args = tr.binding.as_ref().map(|b| {
                Arc::new(
                    b.args
                        .iter()
                        .map(|(k, v)| (k.clone(), serde_json::from_str(v).unwrap_or_else(|_| Value::String(v.clone()))))
                        .collect::<Vec<_>>(),
                )
            });
            let actions = tr
                .actions
                .iter()
                .map(|a| ActionTemplate {
                    action: a.action.clone(),
                    primitive: a.primitive.clone(),
                    prim: {
                        let n = prims.len() as u32;
                        *prims.entry(a.primitive.clone()).or_insert(n)
                    },
                    stops: a.command == "disable",
                    command: a.command.clone(),
                    params: a
                        .params
                        .iter()
                        .map(|(name, json)| {
                            let v: Value = serde_json::from_str(json).unwrap_or_else(|_| Value::String(json.clone()));
                            let src = match v.as_object().and_then(|o| o.get("param")).and_then(Value::as_str) {
                                Some(p) if v.as_object().is_some_and(|o| o.len() == 1) => {
                                    ParamSrc::Param(p.to_string())
                                }
                                _ => ParamSrc::Const(v),
                            };
                            (name.clone(), src)
                        })
                        .collect(),
                })
                .collect();
            info.push(TInfo {
                kind,
                task,
                call_site: tr.provenance.call_site.or(tr.binding.as_ref().map(|b| b.call_site)),
                args,
                actions,
            });
        }
        let has_priorities = net.transitions().iter().any(|t| t.priority.is_some());
        let n = net.transition_count();
        Player {
            ok_place: net.place_by_id(MISSION_OK),
            fail_place: net.place_by_id(MISSION_FAIL),
            rng: ChaCha8Rng::seed_from_u64(opts.seed),
            net,
            opts,
            marking,
            tracker,
            info,
            tasks,
            has_priorities,
            now: 0.0,
            seq: 0,
            armed: vec![None; n],
            timers: BTreeSet::new(),
            arm_counter: 0,
            rearm: None,
            started: false,
            outcome: None,
            fired: 0,
            warned: BTreeSet::new(),
            live: vec![Vec::new(); prims.len()],
            stopped: vec![false; prims.len()],
            live_seqs: HashSet::new(),
        }
    }

    /// The net.
    pub fn net(&self) -> &Arc<Net> {
        &self.net
    }

    /// The current marking.
    pub fn marking(&self) -> &Marking {
        &self.marking
    }

    /// The player's current time (the latest time it was given).
    pub fn now(&self) -> f64 {
        self.now
    }

    /// How the mission ended, once it has.
    pub fn outcome(&self) -> Option<Outcome> {
        self.outcome
    }

    /// Number of transitions fired so far.
    pub fn fired_count(&self) -> u64 {
        self.fired
    }

    /// Sequence number of the last action sent (0: none yet).
    pub fn last_seq(&self) -> u64 {
        self.seq
    }

    /// True once [`Player::start`] was called.
    pub fn is_started(&self) -> bool {
        self.started
    }

    /// The events that some enabled transition waits for, sorted.
    pub fn awaited_events(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .tracker
            .enabled_non_immediate()
            .iter()
            .filter_map(|&t| match &self.net.transitions()[t.index()].kind {
                TransitionKind::Event(e) => Some(e.clone()),
                _ => None,
            })
            .collect();
        v.sort();
        v.dedup();
        v
    }

    /// The earliest pending timer, if any.
    pub fn next_deadline(&self) -> Option<f64> {
        if self.outcome.is_some() {
            return None;
        }
        self.timers.first().map(|&(k, _, _)| f64::from_bits(k))
    }

    /// The arguments of the current call of `task` (name, JSON value).
    pub fn binding(&self, task: &str) -> Option<&[(String, Value)]> {
        let ts = self.tasks.iter().find(|t| t.name == task)?;
        let b = ts.binding?;
        self.info[b.index()].args.as_deref().map(Vec::as_slice)
    }

    /// Pending timers: (transition, deadline), earliest first.
    pub fn timers(&self) -> Vec<(TransitionId, f64)> {
        self.timers.iter().map(|&(k, _, t)| (TransitionId(t), f64::from_bits(k))).collect()
    }

    /// Starts the mission at time `now`: fires the initial cascade.
    pub fn start(&mut self, now: f64) -> Vec<Output> {
        let mut out = Vec::new();
        if self.started {
            return out;
        }
        self.started = true;
        self.now = now;
        if self.settle(&mut out) {
            // Timed transitions enabled from the initial marking on never
            // flipped, so `settle` did not arm them.
            let mut initially: Vec<TransitionId> = self.tracker.enabled_non_immediate().to_vec();
            initially.sort_unstable();
            for t in initially {
                if matches!(self.info[t.index()].kind, Kind::Timed(_)) && self.armed[t.index()].is_none() {
                    self.arm(t, &mut out);
                }
            }
            self.stabilize(&mut out);
        }
        out
    }

    /// The vehicle lost its memory at time `now` (its AAC welcomed the run
    /// in another session: it restarted without its state), so the
    /// primitives the player has running run no more. Each of them (a
    /// primitive sent actions since its last `disable`) is started again:
    /// those actions are sent again, in their order, with new sequence
    /// numbers, and only the new ones are its current activations (an
    /// answer naming an old one is stale). The marking, the bindings and the
    /// timers are unchanged: a call's time-out still counts from its start.
    /// Timers due by `now` fire first, as before any input.
    pub fn reestablish(&mut self, now: f64) -> Vec<Output> {
        let mut out = Vec::new();
        self.advance_to(now, &mut out);
        if !self.started || self.outcome.is_some() {
            return out;
        }
        let t = self.now;
        let mut running: Vec<(usize, Action)> = Vec::new();
        for (prim, live) in self.live.iter_mut().enumerate() {
            if self.stopped[prim] || live.is_empty() {
                continue;
            }
            for a in live.drain(..) {
                self.live_seqs.remove(&a.seq);
                running.push((prim, a));
            }
        }
        running.sort_by_key(|(_, a)| a.seq);
        let mut names: Vec<&str> = Vec::new();
        for (_, a) in &running {
            if !names.contains(&a.primitive.as_str()) {
                names.push(&a.primitive);
            }
        }
        let message = if names.is_empty() {
            "the vehicle lost its state (its AAC started a new session): no primitive was running".to_string()
        } else {
            format!(
                "the vehicle lost its state (its AAC started a new session): {} restarted, its actions sent again with new sequence numbers",
                names.join(", ")
            )
        };
        out.push(Output::Warning { t, message });
        for (prim, mut a) in running {
            self.seq += 1;
            a.seq = self.seq;
            self.live[prim].push(a.clone());
            self.live_seqs.insert(a.seq);
            out.push(Output::Send { t, action: a });
        }
        out
    }

    /// An event arrived at time `now` (without an activation).
    pub fn on_event(&mut self, now: f64, event: &str) -> Vec<Output> {
        self.on_event_from(now, event, None)
    }

    /// True when `seq` is a current activation: an action sent to a
    /// primitive that has not been disabled since, or the `disable` of a
    /// primitive not enabled again since.
    pub fn is_live_activation(&self, seq: u64) -> bool {
        self.live_seqs.contains(&seq)
    }

    /// An event arrived at time `now`, raised by the primitive run that the
    /// action `activation` started (when the AAC says so). An event whose
    /// activation is not current is reported as [`Output::Stale`] and
    /// changes nothing.
    pub fn on_event_from(&mut self, now: f64, event: &str, activation: Option<u64>) -> Vec<Output> {
        let mut out = Vec::new();
        self.advance_to(now, &mut out);
        let t = self.now;
        if !self.started {
            out.push(Output::Unexpected { t, event: event.to_string(), reason: "the mission has not started" });
            return out;
        }
        if let Some(a) = activation.filter(|a| !self.live_seqs.contains(a)) {
            let reason = if a == 0 || a > self.seq {
                format!("its activation, action #{a}, was never sent")
            } else {
                format!("its activation, action #{a}, is over: its primitive was disabled since")
            };
            out.push(Output::Stale { t, event: event.to_string(), activation: a, reason });
            return out;
        }
        if self.outcome.is_some() {
            out.push(Output::Unexpected { t, event: event.to_string(), reason: "the mission has ended" });
            return out;
        }
        let net = self.net.clone();
        let waiting = net.event_transitions(event);
        let n = waiting.iter().filter(|&&c| self.tracker.is_enabled(c)).count();
        if n == 0 {
            out.push(Output::Unexpected { t, event: event.to_string(), reason: "no transition waits for it" });
            return out;
        }
        let k = uniform_index(&mut self.rng, n);
        let tr = waiting.iter().copied().filter(|&c| self.tracker.is_enabled(c)).nth(k).expect("k < n");
        let call_site = self.call_site_of(tr);
        out.push(Output::Event { t, event: event.to_string(), transition: tr, call_site, activation });
        self.fire(tr, &mut out);
        self.stabilize(&mut out);
        out
    }

    /// Events that arrived together at time `now` and must all be taken
    /// before the net reacts (coordination messages from other vehicles,
    /// `mcl_runtime::multi`: the firings of other vehicles that a supervisor
    /// copy must learn at once). Each fires one enabled transition bound to
    /// it, in order, in passes while some still can, with no other firing in
    /// between; the net then settles once. Returns the outputs and the events
    /// that enabled nothing (nothing is reported for them: the caller keeps
    /// them for later).
    pub fn on_events(&mut self, now: f64, events: Vec<String>) -> (Vec<Output>, Vec<String>) {
        let mut out = Vec::new();
        self.advance_to(now, &mut out);
        if self.outcome.is_some() || !self.started {
            return (out, events);
        }
        let t = self.now;
        let net = self.net.clone();
        let mut left = events;
        let mut fired = false;
        loop {
            let mut next = Vec::new();
            let before = left.len();
            for event in left {
                let waiting = net.event_transitions(&event);
                let n = waiting.iter().filter(|&&c| self.tracker.is_enabled(c)).count();
                if n == 0 {
                    next.push(event);
                    continue;
                }
                let k = uniform_index(&mut self.rng, n);
                let tr = waiting.iter().copied().filter(|&c| self.tracker.is_enabled(c)).nth(k).expect("k < n");
                let call_site = self.call_site_of(tr);
                out.push(Output::Event { t, event, transition: tr, call_site, activation: None });
                self.fire(tr, &mut out);
                fired = true;
            }
            left = next;
            if left.is_empty() || left.len() == before {
                break;
            }
        }
        if fired {
            self.stabilize(&mut out);
        }
        (out, left)
    }

    /// A perception arrived at time `now` (recorded; it fires nothing).
    pub fn on_perception(&mut self, now: f64, name: &str, value: Value) -> Vec<Output> {
        let mut out = Vec::new();
        self.advance_to(now, &mut out);
        out.push(Output::Perception { t: self.now, name: name.to_string(), value });
        out
    }

    /// Time passed: fires every timer due at or before `now`, each at its deadline.
    pub fn on_timer(&mut self, now: f64) -> Vec<Output> {
        let mut out = Vec::new();
        self.advance_to(now, &mut out);
        out
    }

    fn advance_to(&mut self, now: f64, out: &mut Vec<Output>) {
        if self.started {
            while self.outcome.is_none() {
                let Some(d) = self.next_deadline() else { break };
                if d > now {
                    break;
                }
                self.now = self.now.max(d);
                if let Some(t) = self.pop_due_timer() {
                    self.fire(t, out);
                }
                self.stabilize(out);
            }
        }
        self.now = self.now.max(now);
    }

    /// Settles immediate transitions and fires due timers (zero-delay ones
    /// first of all) until the marking is tangible with no timer due now;
    /// then checks for the end of the mission.
    fn stabilize(&mut self, out: &mut Vec<Output>) {
        let mut timers = 0usize;
        loop {
            if !self.settle(out) {
                return;
            }
            match self.next_deadline() {
                Some(d) if d <= self.now => {
                    timers += 1;
                    if timers > self.opts.step_limit {
                        let reason = format!(
                            "livelock: {} zero-delay timers fired at t={} s without time advancing (a loop whose \
                             tasks end at once?)",
                            timers - 1,
                            self.now
                        );
                        self.end(Outcome::Stuck, Some(reason), out);
                        return;
                    }
                    if let Some(t) = self.pop_due_timer() {
                        self.fire(t, out);
                    }
                }
                _ => break,
            }
        }
        self.check_end(out);
    }

    /// Fires immediate transitions until none is enabled, then updates the
    /// timers. False after a livelock (the mission is then stuck).
    fn settle(&mut self, out: &mut Vec<Output>) -> bool {
        let mut steps = 0usize;
        loop {
            let imm = self.tracker.enabled_immediate();
            if imm.is_empty() {
                break;
            }
            if steps >= self.opts.step_limit {
                let reason = format!(
                    "livelock: immediate transitions fired {steps} times in a row without reaching a tangible marking"
                );
                self.end(Outcome::Stuck, Some(reason), out);
                return false;
            }
            let t = if self.has_priorities {
                let mut v = imm.to_vec();
                v.sort_unstable();
                select_ready(&self.net, &mut v);
                v[uniform_index(&mut self.rng, v.len())]
            } else {
                imm[uniform_index(&mut self.rng, imm.len())]
            };
            self.fire(t, out);
            steps += 1;
        }
        // The marking is tangible: start and cancel timers.
        let changed = self.tracker.take_changed();
        for t in changed {
            if let Kind::Timed(_) = self.info[t.index()].kind {
                if self.tracker.is_enabled(t) {
                    self.arm(t, out);
                } else {
                    self.cancel(t);
                }
            }
        }
        if let Some(t) = self.rearm.take() {
            if self.tracker.is_enabled(t) && self.armed[t.index()].is_none() {
                self.arm(t, out);
            }
        }
        true
    }

    fn check_end(&mut self, out: &mut Vec<Output>) {
        if self.outcome.is_some() {
            return;
        }
        let marked = |p: Option<PlaceId>, m: &Marking| p.is_some_and(|p| m.get(p) > 0);
        if marked(self.ok_place, &self.marking) {
            self.end(Outcome::Ok, None, out);
        } else if marked(self.fail_place, &self.marking) {
            self.end(Outcome::Fail, None, out);
        } else if self.tracker.enabled_non_immediate().is_empty() {
            self.end(
                Outcome::Stuck,
                Some("no event-driven or timed transition is enabled: nothing can fire any more".into()),
                out,
            );
        }
    }

    fn end(&mut self, outcome: Outcome, reason: Option<String>, out: &mut Vec<Output>) {
        self.outcome = Some(outcome);
        out.push(Output::Outcome { t: self.now, outcome, reason });
    }

    fn call_site_of(&self, t: TransitionId) -> Option<u32> {
        let i = &self.info[t.index()];
        i.call_site.or_else(|| {
            let task = i.task?;
            let b = self.tasks[task as usize].binding?;
            self.info[b.index()].call_site
        })
    }

    fn fire(&mut self, t: TransitionId, out: &mut Vec<Output>) {
        if let Err(e) = self.tracker.fire(&self.net, &mut self.marking, t) {
            out.push(Output::Warning {
                t: self.now,
                message: format!("cannot fire {}: {e}", self.net.transitions()[t.index()].id),
            });
            return;
        }
        self.fired += 1;
        let info = &self.info[t.index()];
        if info.args.is_some() {
            if let Some(task) = info.task {
                self.tasks[task as usize].binding = Some(t);
            }
        }
        if let Kind::Timed(_) = info.kind {
            self.cancel(t);
            self.rearm = Some(t);
        }
        let call_site = self.call_site_of(t);
        out.push(Output::Fired { t: self.now, transition: t, call_site });
        let n = self.info[t.index()].actions.len();
        for k in 0..n {
            let action = self.make_action(t, k, call_site, out);
            out.push(Output::Send { t: self.now, action });
        }
    }

    fn make_action(&mut self, t: TransitionId, k: usize, call_site: Option<u32>, out: &mut Vec<Output>) -> Action {
        self.seq += 1;
        let info = &self.info[t.index()];
        let tmpl = &info.actions[k];
        let args =
            info.task.and_then(|i| self.tasks[i as usize].binding).and_then(|b| self.info[b.index()].args.clone());
        let mut params = Map::new();
        for (name, src) in &tmpl.params {
            let v = match src {
                ParamSrc::Const(v) => v.clone(),
                ParamSrc::Param(p) => match args.as_ref().and_then(|a| a.iter().find(|(n, _)| n == p)) {
                    Some((_, v)) => v.clone(),
                    None => {
                        out.push(Output::Warning {
                            t: self.now,
                            message: format!("action `{}`: no value for parameter `{p}` (sent as null)", tmpl.action),
                        });
                        Value::Null
                    }
                },
            };
            let v = match &v {
                Value::String(s) => self.opts.symbols.get(s).cloned().unwrap_or(v),
                _ => v,
            };
            params.insert(name.clone(), v);
        }
        let prim = tmpl.prim as usize;
        // A disable ends the primitive's runs: their answers are stale from
        // now on (but an event about the disable itself is not); the next
        // action starts a new run.
        if tmpl.stops || self.stopped[prim] {
            for a in self.live[prim].drain(..) {
                self.live_seqs.remove(&a.seq);
            }
        }
        self.stopped[prim] = tmpl.stops;
        let action = Action {
            seq: self.seq,
            action: tmpl.action.clone(),
            primitive: tmpl.primitive.clone(),
            command: tmpl.command.clone(),
            params,
            task: info.task.map(|i| self.tasks[i as usize].name.clone()),
            call_site,
        };
        self.live[prim].push(action.clone());
        self.live_seqs.insert(self.seq);
        action
    }

    /// The delay of timed transition `t` under the current binding.
    fn delay_of(&mut self, t: TransitionId, out: &mut Vec<Output>) -> f64 {
        let info = &self.info[t.index()];
        let Kind::Timed(d) = &info.kind else { return 0.0 };
        let p = match d {
            Delay::Fixed(x) => return *x,
            Delay::Param(p) => p,
        };
        let args =
            info.task.and_then(|i| self.tasks[i as usize].binding).and_then(|b| self.info[b.index()].args.clone());
        let id = &self.net.transitions()[t.index()].id;
        let value = args.as_ref().and_then(|a| a.iter().find(|(n, _)| n == p)).map(|(_, v)| v.clone());
        let resolved = match &value {
            Some(Value::Number(n)) => n.as_f64(),
            Some(Value::String(s)) => self.opts.symbols.get(s).and_then(|v| match v {
                Value::Number(n) => n.as_f64(),
                Value::String(s) => s.parse::<f64>().ok(),
                _ => None,
            }),
            _ => None,
        };
        match resolved {
            Some(x) if x.is_finite() && x >= 0.0 => x,
            _ => {
                let why = match &value {
                    None => format!("the current call gives no parameter `{p}`"),
                    Some(Value::String(s)) => {
                        format!("`{p}` is the symbol `{s}`, which has no numeric value (use --set {s}=SECONDS or the scenario's [symbols])")
                    }
                    Some(v) => format!("`{p}` is {v}, not a number of seconds"),
                };
                let message = format!("delay of `{id}`: {why}; using {} s", self.opts.default_delay);
                if self.warned.insert(message.clone()) {
                    out.push(Output::Warning { t: self.now, message });
                }
                self.opts.default_delay
            }
        }
    }

    fn arm(&mut self, t: TransitionId, out: &mut Vec<Output>) {
        self.cancel(t);
        let d = self.delay_of(t, out);
        let deadline = self.now + d;
        self.arm_counter += 1;
        self.armed[t.index()] = Some((deadline, self.arm_counter));
        self.timers.insert((time_key(deadline), self.arm_counter, t.0));
        if d > 0.0 {
            out.push(Output::Timer { t: self.now, transition: t, deadline });
        }
    }

    fn cancel(&mut self, t: TransitionId) {
        if let Some((deadline, id)) = self.armed[t.index()].take() {
            self.timers.remove(&(time_key(deadline), id, t.0));
        }
    }

    /// Removes and returns one of the timers with the earliest deadline,
    /// chosen at random among ties.
    fn pop_due_timer(&mut self) -> Option<TransitionId> {
        let &(k, _, _) = self.timers.first()?;
        let ties: Vec<(u64, u64, u32)> = self.timers.range((k, 0, 0)..=(k, u64::MAX, u32::MAX)).copied().collect();
        // Among deferred transitions due now, the highest priority first
        // (`mcl_net::semantics::select_ready`, the rule the verifier explores).
        let ties: Vec<(u64, u64, u32)> = if ties.len() > 1 && self.has_priorities {
            let mut ts: Vec<TransitionId> = ties.iter().map(|&(_, _, t)| TransitionId(t)).collect();
            select_ready(&self.net, &mut ts);
            ties.into_iter().filter(|&(_, _, t)| ts.contains(&TransitionId(t))).collect()
        } else {
            ties
        };
        let pick = if ties.len() == 1 { ties[0] } else { ties[uniform_index(&mut self.rng, ties.len())] };
        self.timers.remove(&pick);
        let t = TransitionId(pick.2);
        self.armed[t.index()] = None;
        Some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_net::{NetBuilder, Place, Transition};

    fn kinds(out: &[Output]) -> Vec<String> {
        out.iter()
            .map(|o| match o {
                Output::Send { action, .. } => format!("send {}", action.action),
                Output::Fired { transition, .. } => format!("fire {}", transition.0),
                Output::Event { event, .. } => format!("event {event}"),
                Output::Stale { event, activation, .. } => format!("stale {event} #{activation}"),
                Output::Unexpected { event, .. } => format!("unexpected {event}"),
                Output::Timer { deadline, .. } => format!("timer {deadline}"),
                Output::Perception { name, .. } => format!("perception {name}"),
                Output::Warning { .. } => "warning".into(),
                Output::Outcome { outcome, .. } => format!("outcome {}", outcome.as_str()),
            })
            .collect()
    }

    /// begin -> t0 (imm) -> wait -> tE (event e) -> mid -> tT (timed 5) -> mission.ok
    fn small() -> Arc<Net> {
        let mut b = NetBuilder::new("m");
        let begin = b.add_place(Place::new("mission.begin").with_tokens(1));
        let wait = b.add_place(Place::new("wait"));
        let mid = b.add_place(Place::new("mid"));
        let ok = b.add_place(Place::new("mission.ok"));
        let t0 = b.add_transition(Transition::new("t0").with_action(mcl_net::ActionRef {
            action: "enableX".into(),
            primitive: "XPrimitive".into(),
            command: "enable".into(),
            params: vec![("v0".into(), "4".into())],
        }));
        let te = b.add_transition(Transition::new("te").with_kind(TransitionKind::Event("e".into())));
        let tt = b.add_transition(Transition::new("tt").with_kind(TransitionKind::Timed(Delay::Fixed(5.0))));
        b.add_input(begin, t0, 1).add_output(t0, wait, 1);
        b.add_input(wait, te, 1).add_output(te, mid, 1);
        b.add_input(mid, tt, 1).add_output(tt, ok, 1);
        Arc::new(b.build().unwrap())
    }

    #[test]
    fn immediate_event_timer_outcome() {
        let mut p = Player::new(small(), PlayerOptions::seeded(1));
        let out = p.start(0.0);
        assert_eq!(kinds(&out), ["fire 0", "send enableX"]);
        assert_eq!(p.next_deadline(), None);
        assert_eq!(kinds(&p.on_event(1.0, "nope")), ["unexpected nope"]);
        let out = p.on_event(2.0, "e");
        assert_eq!(kinds(&out), ["event e", "fire 1", "timer 7"]);
        assert_eq!(p.next_deadline(), Some(7.0));
        assert!(p.on_timer(6.9).is_empty());
        let out = p.on_timer(8.0);
        assert_eq!(kinds(&out), ["fire 2", "outcome ok"]);
        assert_eq!(out[0].time(), 7.0);
        assert_eq!(p.outcome(), Some(Outcome::Ok));
    }

    /// begin -> t0 (enable X) -> w1 -> te1 (event e: disable X, enable X) -> w2 -> te2 (event e) -> mission.ok
    fn twice() -> Arc<Net> {
        let x = |cmd: &str| mcl_net::ActionRef {
            action: format!("{cmd}X"),
            primitive: "XPrimitive".into(),
            command: cmd.into(),
            params: vec![],
        };
        let mut b = NetBuilder::new("m");
        let begin = b.add_place(Place::new("mission.begin").with_tokens(1));
        let w1 = b.add_place(Place::new("w1"));
        let w2 = b.add_place(Place::new("w2"));
        let ok = b.add_place(Place::new("mission.ok"));
        let t0 = b.add_transition(Transition::new("t0").with_action(x("enable")));
        let te1 = b.add_transition(
            Transition::new("te1")
                .with_kind(TransitionKind::Event("e".into()))
                .with_action(x("disable"))
                .with_action(x("enable")),
        );
        let te2 = b.add_transition(Transition::new("te2").with_kind(TransitionKind::Event("e".into())));
        b.add_input(begin, t0, 1).add_output(t0, w1, 1);
        b.add_input(w1, te1, 1).add_output(te1, w2, 1);
        b.add_input(w2, te2, 1).add_output(te2, ok, 1);
        Arc::new(b.build().unwrap())
    }

    #[test]
    fn answers_of_a_disabled_activation_are_stale() {
        let mut p = Player::new(twice(), PlayerOptions::seeded(1));
        assert_eq!(kinds(&p.start(0.0)), ["fire 0", "send enableX"]);
        assert!(p.is_live_activation(1));
        let out = p.on_event_from(1.0, "e", Some(1));
        assert_eq!(kinds(&out), ["event e", "fire 1", "send disableX", "send enableX"]);
        assert!(!p.is_live_activation(1) && p.is_live_activation(3));
        // A second answer of the first run (it crossed the disable): ignored.
        let out = p.on_event_from(1.0, "e", Some(1));
        assert_eq!(kinds(&out), ["stale e #1"]);
        let Output::Stale { reason, .. } = &out[0] else { panic!() };
        assert!(reason.contains("action #1") && reason.contains("disabled since"), "{reason}");
        // Nor does an activation never sent, nor the disable itself.
        assert_eq!(kinds(&p.on_event_from(1.0, "e", Some(9))), ["stale e #9"]);
        assert_eq!(kinds(&p.on_event_from(1.0, "e", Some(2))), ["stale e #2"]);
        assert_eq!(p.outcome(), None);
        assert!(!p.is_live_activation(2), "the primitive was enabled again since its disable");
        // The current run's answer ends the mission.
        let out = p.on_event_from(2.0, "e", Some(3));
        assert_eq!(kinds(&out), ["event e", "fire 2", "outcome ok"]);
        assert!(matches!(out[0], Output::Event { activation: Some(3), .. }));
    }

    /// A vehicle that lost its state gets the running primitive's actions
    /// again, with new seqs: only those are current; a disabled primitive
    /// is left alone.
    #[test]
    fn reestablish_sends_the_running_primitives_again() {
        let mut p = Player::new(twice(), PlayerOptions::seeded(1));
        assert_eq!(kinds(&p.reestablish(0.0)), Vec::<String>::new(), "not started: nothing runs");
        p.start(0.0);
        let out = p.on_event_from(1.0, "e", Some(1));
        assert_eq!(kinds(&out), ["event e", "fire 1", "send disableX", "send enableX"]);
        let out = p.reestablish(2.0);
        assert_eq!(kinds(&out), ["warning", "send enableX"]);
        let Output::Send { action, .. } = &out[1] else { panic!() };
        assert_eq!((action.seq, action.command.as_str()), (4, "enable"));
        let Output::Warning { message, .. } = &out[0] else { panic!() };
        assert!(message.contains("XPrimitive restarted"), "{message}");
        assert!(!p.is_live_activation(3) && p.is_live_activation(4));
        assert_eq!(kinds(&p.on_event_from(3.0, "e", Some(3))), ["stale e #3"]);
        assert_eq!(kinds(&p.on_event_from(3.0, "e", Some(4))), ["event e", "fire 2", "outcome ok"]);
        assert_eq!(kinds(&p.reestablish(4.0)), Vec::<String>::new(), "the mission is over");
    }

    /// An event about a disable (a primitive confirming it stopped) names
    /// the disable: current until the primitive is enabled again.
    #[test]
    fn an_event_may_answer_a_disable() {
        let x = |cmd: &str| mcl_net::ActionRef {
            action: format!("{cmd}X"),
            primitive: "XPrimitive".into(),
            command: cmd.into(),
            params: vec![],
        };
        let mut b = NetBuilder::new("m");
        let begin = b.add_place(Place::new("mission.begin").with_tokens(1));
        let w1 = b.add_place(Place::new("w1"));
        let w2 = b.add_place(Place::new("w2"));
        let ok = b.add_place(Place::new("mission.ok"));
        let t0 = b.add_transition(Transition::new("t0").with_action(x("enable")));
        let te1 = b.add_transition(
            Transition::new("te1").with_kind(TransitionKind::Event("e".into())).with_action(x("disable")),
        );
        let te2 = b.add_transition(Transition::new("te2").with_kind(TransitionKind::Event("stopped".into())));
        b.add_input(begin, t0, 1).add_output(t0, w1, 1);
        b.add_input(w1, te1, 1).add_output(te1, w2, 1);
        b.add_input(w2, te2, 1).add_output(te2, ok, 1);
        let mut p = Player::new(Arc::new(b.build().unwrap()), PlayerOptions::seeded(1));
        p.start(0.0);
        p.on_event_from(1.0, "e", Some(1));
        assert_eq!(kinds(&p.on_event_from(1.0, "stopped", Some(1))), ["stale stopped #1"]);
        assert_eq!(kinds(&p.on_event_from(1.0, "stopped", Some(2))), ["event stopped", "fire 2", "outcome ok"]);
    }

    #[test]
    fn events_without_activation_are_taken_as_before() {
        let mut p = Player::new(twice(), PlayerOptions::seeded(1));
        p.start(0.0);
        p.on_event(1.0, "e");
        assert_eq!(kinds(&p.on_event(1.0, "e")), ["event e", "fire 2", "outcome ok"]);
    }

    #[test]
    fn stuck_when_nothing_can_fire() {
        let mut b = NetBuilder::new("m");
        let begin = b.add_place(Place::new("mission.begin").with_tokens(1));
        let t0 = b.add_transition(Transition::new("t0"));
        let q = b.add_place(Place::new("q"));
        b.add_input(begin, t0, 1).add_output(t0, q, 1);
        let mut p = Player::new(Arc::new(b.build().unwrap()), PlayerOptions::seeded(1));
        let out = p.start(0.0);
        assert_eq!(kinds(&out), ["fire 0", "outcome stuck"]);
    }

    #[test]
    fn livelock_is_stuck() {
        let mut b = NetBuilder::new("m");
        let p0 = b.add_place(Place::new("p").with_tokens(1));
        let t0 = b.add_transition(Transition::new("t0"));
        b.add_input(p0, t0, 1).add_output(t0, p0, 1);
        let mut p = Player::new(Arc::new(b.build().unwrap()), PlayerOptions { step_limit: 10, ..Default::default() });
        let out = p.start(0.0);
        assert_eq!(out.len(), 11);
        assert_eq!(p.outcome(), Some(Outcome::Stuck));
    }

    /// A loop through a zero-delay timer (each call's `release`) never
    /// leaves the instant: it is a livelock too, not an endless run.
    #[test]
    fn zero_delay_loop_is_stuck() {
        let mut b = NetBuilder::new("m");
        let p0 = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q"));
        let t0 = b.add_transition(Transition::new("t0"));
        let t1 = b.add_transition(Transition::new("t1").with_kind(TransitionKind::Timed(Delay::Fixed(0.0))));
        b.add_input(p0, t0, 1).add_output(t0, q, 1).add_input(q, t1, 1).add_output(t1, p0, 1);
        let mut p = Player::new(Arc::new(b.build().unwrap()), PlayerOptions { step_limit: 10, ..Default::default() });
        let out = p.start(0.0);
        assert_eq!(p.outcome(), Some(Outcome::Stuck));
        let reason = out.iter().find_map(|o| match o {
            Output::Outcome { reason, .. } => reason.clone(),
            _ => None,
        });
        assert!(reason.is_some_and(|r| r.contains("zero-delay timers")), "{out:?}");
    }
}
