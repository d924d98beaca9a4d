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
//! The player holds an [`Engine`] of `mcl-net`, which plays the one firing
//! rule, stated in [`mcl_net::engine`]: immediate transitions first (by
//! priority, then a seeded uniform draw), timers started when a timed
//! transition is enabled in a tangible marking, zero-delay (*deferred*)
//! timers before any event, ties among due timers by priority then draw,
//! an event firing one enabled transition bound to it, every timer due
//! before an input firing first at its own deadline (a time-out and an
//! answer at the same instant resolve as "time-out first"). A cascade of
//! immediate transitions longer than [`PlayerOptions::step_limit`], or more
//! than `step_limit` zero-delay timers at one instant (`while ( True() ) {
//! Void() }` with tasks that end at once), is a livelock: the mission is
//! stuck.
//!
//! The player adds, through the engine's [`Hooks`], what is its own:
//!
//! 1. **Actions and bindings**: a firing sends the transition's actions,
//!    their parameters resolved from the current binding of its task (the
//!    arguments of the last call that started it) and the run's symbols.
//! 2. **Parameter delays**: a delay `Param(p)` is read, when the timer
//!    starts, from the current binding: a number of seconds, else a symbol
//!    looked up in the run's symbol table (`--set timeout=60`, a scenario's
//!    `[symbols]`), else [`PlayerOptions::default_delay`] with a warning
//!    (given once).
//! 3. **Events**: an event that enables nothing is reported as an
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
//! The mission ends when `mission.ok` or `mission.fail` is marked and the net
//! has settled (no immediate transition enabled, no timer due now). It is
//! *stuck* when the marking is tangible and no event-driven or timed
//! transition is enabled: nothing can ever fire again.
//!
//! Enabledness is maintained incrementally by the engine's
//! [`mcl_net::EnabledTracker`]; the player never rescans the whole net after
//! a firing (compare the seed's Extract 5.8, benchmarked in
//! `benches/player.rs`).

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::sync::Arc;

use std::ops::ControlFlow;

use mcl_net::engine::{Engine, Hooks, Livelock, View};
use mcl_net::{Delay, FireError, Marking, Net, PlaceId, TransitionId, TransitionKind};
use serde_json::Value;

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

/// Per-transition data, precomputed once.
#[derive(Clone, Debug)]
struct TInfo {
    /// The delay of a timed transition.
    delay: Option<Delay>,
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

/// The player. See the [module documentation](self).
#[derive(Clone, Debug)]
pub struct Player {
    /// The net, its marking, timers, clock and random choices.
    engine: Engine<Arc<Net>>,
    /// The player's own state, and the engine's hooks.
    layer: Layer,
}

/// What the player adds to the engine's firings: action templates,
/// bindings, activations, the outcome, the outputs.
#[derive(Clone, Debug)]
struct Layer {
    opts: PlayerOptions,
    info: Vec<TInfo>,
    tasks: Vec<TaskState>,
    ok_place: Option<PlaceId>,
    fail_place: Option<PlaceId>,
    seq: u64,
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
    /// The activation of the event being delivered.
    activation: Option<u64>,
    /// Outputs of the call in progress.
    out: Vec<Output>,
}

impl Player {
    /// A player for `net` in its initial marking. Nothing fires before [`Player::start`].
    pub fn new(net: Arc<Net>, opts: PlayerOptions) -> Self {
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
            let delay = match &tr.kind {
                TransitionKind::Timed(d) => Some(d.clone()),
                _ => None,
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
                delay,
                task,
                call_site: tr.provenance.call_site.or(tr.binding.as_ref().map(|b| b.call_site)),
                args,
                actions,
            });
        }
        let layer = Layer {
            ok_place: net.place_by_id(MISSION_OK),
            fail_place: net.place_by_id(MISSION_FAIL),
            info,
            tasks,
            seq: 0,
            started: false,
            outcome: None,
            fired: 0,
            warned: BTreeSet::new(),
            live: vec![Vec::new(); prims.len()],
            stopped: vec![false; prims.len()],
            live_seqs: HashSet::new(),
            activation: None,
            out: Vec::new(),
            opts,
        };
        let engine = Engine::new(net, layer.opts.seed).with_step_limit(layer.opts.step_limit);
        Player { engine, layer }
    }

    /// The net.
    pub fn net(&self) -> &Arc<Net> {
        self.engine.net_handle()
    }

    /// The current marking.
    pub fn marking(&self) -> &Marking {
        self.engine.marking()
    }

    /// The player's current time (the latest time it was given).
    pub fn now(&self) -> f64 {
        self.engine.now()
    }

    /// How the mission ended, once it has.
    pub fn outcome(&self) -> Option<Outcome> {
        self.layer.outcome
    }

    /// Number of transitions fired so far.
    pub fn fired_count(&self) -> u64 {
        self.layer.fired
    }

    /// Sequence number of the last action sent (0: none yet).
    pub fn last_seq(&self) -> u64 {
        self.layer.seq
    }

    /// True once [`Player::start`] was called.
    pub fn is_started(&self) -> bool {
        self.layer.started
    }

    /// The events that some enabled transition waits for, sorted.
    pub fn awaited_events(&self) -> Vec<String> {
        self.engine.awaited_events()
    }

    /// The earliest pending timer, if any.
    pub fn next_deadline(&self) -> Option<f64> {
        if self.layer.outcome.is_some() {
            return None;
        }
        self.engine.next_deadline()
    }

    /// The arguments of the current call of `task` (name, JSON value).
    pub fn binding(&self, task: &str) -> Option<&[(String, Value)]> {
        let l = &self.layer;
        let ts = l.tasks.iter().find(|t| t.name == task)?;
        let b = ts.binding?;
        l.info[b.index()].args.as_deref().map(Vec::as_slice)
    }

    /// Pending timers: (transition, deadline), earliest first.
    pub fn timers(&self) -> Vec<(TransitionId, f64)> {
        self.engine.timers()
    }

    /// Starts the mission at time `now`: fires the initial cascade.
    pub fn start(&mut self, now: f64) -> Vec<Output> {
        if self.layer.started {
            return Vec::new();
        }
        self.layer.started = true;
        let r = self.engine.start(now, &mut self.layer);
        self.layer.livelocked(r);
        std::mem::take(&mut self.layer.out)
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
        self.advance_to(now);
        let l = &mut self.layer;
        if !l.started || l.outcome.is_some() {
            return std::mem::take(&mut l.out);
        }
        let t = self.engine.now();
        let mut running: Vec<(usize, Action)> = Vec::new();
        for (prim, live) in l.live.iter_mut().enumerate() {
            if l.stopped[prim] || live.is_empty() {
                continue;
            }
            for a in live.drain(..) {
                l.live_seqs.remove(&a.seq);
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
        l.out.push(Output::Warning { t, message });
        for (prim, mut a) in running {
            l.seq += 1;
            a.seq = l.seq;
            l.live[prim].push(a.clone());
            l.live_seqs.insert(a.seq);
            l.out.push(Output::Send { t, action: a });
        }
        std::mem::take(&mut l.out)
    }

    /// An event arrived at time `now` (without an activation).
    pub fn on_event(&mut self, now: f64, event: &str) -> Vec<Output> {
        self.on_event_from(now, event, None)
    }

    /// True when `seq` is a current activation: an action sent to a
    /// primitive that has not been disabled since, or the `disable` of a
    /// primitive not enabled again since.
    pub fn is_live_activation(&self, seq: u64) -> bool {
        self.layer.live_seqs.contains(&seq)
    }

    /// An event arrived at time `now`, raised by the primitive run that the
    /// action `activation` started (when the AAC says so). An event whose
    /// activation is not current is reported as [`Output::Stale`] and
    /// changes nothing.
    pub fn on_event_from(&mut self, now: f64, event: &str, activation: Option<u64>) -> Vec<Output> {
        self.advance_to(now);
        let t = self.engine.now();
        let l = &mut self.layer;
        if !l.started {
            l.out.push(Output::Unexpected { t, event: event.to_string(), reason: "the mission has not started" });
            return std::mem::take(&mut l.out);
        }
        if let Some(a) = activation.filter(|a| !l.live_seqs.contains(a)) {
            let reason = if a == 0 || a > l.seq {
                format!("its activation, action #{a}, was never sent")
            } else {
                format!("its activation, action #{a}, is over: its primitive was disabled since")
            };
            l.out.push(Output::Stale { t, event: event.to_string(), activation: a, reason });
            return std::mem::take(&mut l.out);
        }
        if l.outcome.is_some() {
            l.out.push(Output::Unexpected { t, event: event.to_string(), reason: "the mission has ended" });
            return std::mem::take(&mut l.out);
        }
        l.activation = activation;
        match self.engine.deliver(event, l) {
            Ok(None) => {
                l.out.push(Output::Unexpected { t, event: event.to_string(), reason: "no transition waits for it" })
            }
            r => l.livelocked(r.map(|_| ())),
        }
        l.activation = None;
        std::mem::take(&mut l.out)
    }

    /// Events that arrived together at time `now` and must all be taken
    /// before the net reacts (coordination messages from other vehicles,
    /// `mcl_runtime::multi`: the firings of other vehicles that a supervisor
    /// copy must learn at once). Each fires one enabled transition bound to
    /// it, in order, in passes while some still can, with no other firing in
    /// between; the net then settles once ([`Engine::deliver_batch`]).
    /// Returns the outputs and the events that enabled nothing (nothing is
    /// reported for them: the caller keeps them for later).
    pub fn on_events(&mut self, now: f64, events: Vec<String>) -> (Vec<Output>, Vec<String>) {
        self.advance_to(now);
        let l = &mut self.layer;
        if l.outcome.is_some() || !l.started {
            return (std::mem::take(&mut l.out), events);
        }
        let mut left = events;
        let r = self.engine.deliver_batch(&mut left, l);
        l.livelocked(r.map(|_| ()));
        (std::mem::take(&mut l.out), left)
    }

    /// A perception arrived at time `now` (recorded; it fires nothing).
    pub fn on_perception(&mut self, now: f64, name: &str, value: Value) -> Vec<Output> {
        self.advance_to(now);
        let t = self.engine.now();
        self.layer.out.push(Output::Perception { t, name: name.to_string(), value });
        std::mem::take(&mut self.layer.out)
    }

    /// Time passed: fires every timer due at or before `now`, each at its deadline.
    pub fn on_timer(&mut self, now: f64) -> Vec<Output> {
        self.advance_to(now);
        std::mem::take(&mut self.layer.out)
    }

    /// Fires the timers due by `now` (once started, until the mission ends)
    /// and moves the clock to `now`.
    fn advance_to(&mut self, now: f64) {
        if self.layer.started && self.layer.outcome.is_none() {
            let r = self.engine.advance_to(now, &mut self.layer);
            self.layer.livelocked(r);
        } else {
            self.engine.set_clock(now);
        }
    }
}

impl Hooks for Layer {
    #[inline]
    fn fired(&mut self, v: View<'_>, t: TransitionId) {
        self.fired += 1;
        let info = &self.info[t.index()];
        if info.args.is_some() {
            if let Some(task) = info.task {
                self.tasks[task as usize].binding = Some(t);
            }
        }
        let call_site = self.call_site_of(t);
        self.out.push(Output::Fired { t: v.now, transition: t, call_site });
        let n = self.info[t.index()].actions.len();
        for k in 0..n {
            let action = self.make_action(t, k, call_site, v.now);
            self.out.push(Output::Send { t: v.now, action });
        }
    }

    fn refused(&mut self, v: View<'_>, t: TransitionId, e: FireError) {
        self.out.push(Output::Warning {
            t: v.now,
            message: format!("cannot fire {}: {e}", v.net.transitions()[t.index()].id),
        });
    }

    #[inline]
    fn delay(&mut self, v: View<'_>, t: TransitionId) -> f64 {
        self.delay_of(v, t)
    }

    #[inline]
    fn armed(&mut self, v: View<'_>, t: TransitionId, delay: f64, deadline: f64) {
        if delay > 0.0 {
            self.out.push(Output::Timer { t: v.now, transition: t, deadline });
        }
    }

    fn event(&mut self, v: View<'_>, event: &str, t: TransitionId) {
        let call_site = self.call_site_of(t);
        self.out.push(Output::Event {
            t: v.now,
            event: event.to_string(),
            transition: t,
            call_site,
            activation: self.activation,
        });
    }

    fn stable(&mut self, v: View<'_>) -> ControlFlow<()> {
        self.check_end(v);
        if self.outcome.is_some() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

impl Layer {
    /// A livelock ends the mission as stuck.
    fn livelocked(&mut self, r: Result<(), Livelock>) {
        if let Err(l) = r {
            self.end(Outcome::Stuck, Some(l.to_string()), l.at());
        }
    }

    fn check_end(&mut self, v: View<'_>) {
        if self.outcome.is_some() {
            return;
        }
        let marked = |p: Option<PlaceId>| p.is_some_and(|p| v.marking.get(p) > 0);
        if marked(self.ok_place) {
            self.end(Outcome::Ok, None, v.now);
        } else if marked(self.fail_place) {
            self.end(Outcome::Fail, None, v.now);
        } else if v.tracker.enabled_non_immediate().is_empty() {
            self.end(
                Outcome::Stuck,
                Some("no event-driven or timed transition is enabled: nothing can fire any more".into()),
                v.now,
            );
        }
    }

    fn end(&mut self, outcome: Outcome, reason: Option<String>, t: f64) {
        self.outcome = Some(outcome);
        self.out.push(Output::Outcome { t, outcome, reason });
    }

    fn call_site_of(&self, t: TransitionId) -> Option<u32> {
        let i = &self.info[t.index()];
        i.call_site.or_else(|| {
            let task = i.task?;
            let b = self.tasks[task as usize].binding?;
            self.info[b.index()].call_site
        })
    }

    fn make_action(&mut self, t: TransitionId, k: usize, call_site: Option<u32>, now: f64) -> Action {
        self.seq += 1;
        let info = &self.info[t.index()];
        let tmpl = &info.actions[k];
        let args =
            info.task.and_then(|i| self.tasks[i as usize].binding).and_then(|b| self.info[b.index()].args.clone());
        let mut params = crate::params::Params::new();
        for (name, src) in &tmpl.params {
            let v = match src {
                ParamSrc::Const(v) => v.clone(),
                ParamSrc::Param(p) => match args.as_ref().and_then(|a| a.iter().find(|(n, _)| n == p)) {
                    Some((_, v)) => v.clone(),
                    None => {
                        self.out.push(Output::Warning {
                            t: now,
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
    fn delay_of(&mut self, v: View<'_>, t: TransitionId) -> f64 {
        let info = &self.info[t.index()];
        let Some(d) = &info.delay else { return 0.0 };
        let p = match d {
            Delay::Fixed(x) => return *x,
            Delay::Param(p) => p,
        };
        let args =
            info.task.and_then(|i| self.tasks[i as usize].binding).and_then(|b| self.info[b.index()].args.clone());
        let id = &v.net.transitions()[t.index()].id;
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
                    self.out.push(Output::Warning { t: v.now, message });
                }
                self.opts.default_delay
            }
        }
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
