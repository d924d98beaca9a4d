//! Drivers: what feeds time and messages to a [`Player`].
//!
//! * [`run_virtual`]: the player's timers and an in-process vehicle's
//!   agenda ([`VirtualVehicle`]: the mock, a simulator) stepped by the one
//!   discrete-event loop of [`crate::virtual_loop`], in virtual time:
//!   deterministic for a seed, and instantaneous. At equal times the
//!   player's timers go first, then the vehicle's messages in the order they
//!   were scheduled; the actions an input produces reach the vehicle before
//!   the next message is taken.
//! * [`run_real_time`]: a tokio loop over a [`Link`] to any AAC (the
//!   in-process mock served by [`serve_mock`], or a TCP link), selecting
//!   between the link's inbound channel and a sleep until the player's next
//!   deadline (scaled by the clock's speed). No busy waiting.
//!
//! Both go through a [`Session`], which journals each input and its firings
//! (synced before the input's actions are sent) and turns outputs into trace
//! records for a [`Sink`]. In real time, a session may also take an
//! operator's commands ([`Session::operator`], [`crate::operator`]).

use crate::clock::Clock;
use crate::journal::{Entry, Input, JournalWriter};
use crate::link::{AacEnd, Action, Delivered, Inbound, Link};
use crate::mock::MockVehicle;
use crate::operator::{self, Command};
use crate::player::{Outcome, Output, Player};
use crate::trace::{Record, RecordKind, Tracer};
use crate::vehicle::{Pose, VirtualVehicle};
use crate::virtual_loop::{self, Discrete, Stop};

/// Receives trace records as they are produced.
pub trait Sink {
    /// One record.
    fn record(&mut self, r: &Record);
    /// False when records are not wanted at all (they are then not built).
    fn wants_records(&self) -> bool {
        true
    }
    /// The records that follow, until `replaying(false)`, rebuild a run
    /// from its journal (a live log may leave them out).
    fn replaying(&mut self, _on: bool) {}
}

/// A sink that drops everything (benchmarks).
#[derive(Debug, Default)]
pub struct Discard;

impl Sink for Discard {
    fn record(&mut self, _: &Record) {}
    fn wants_records(&self) -> bool {
        false
    }
}

/// A sink that keeps every record.
#[derive(Debug, Default)]
pub struct Collect(pub Vec<Record>);

impl Sink for Collect {
    fn record(&mut self, r: &Record) {
        self.0.push(r.clone());
    }
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum End {
    /// The player reached an outcome.
    Outcome(Outcome),
    /// Virtual time: the player waits for events and nothing is scheduled.
    Quiescent {
        /// Events the enabled transitions wait for.
        awaited: Vec<String>,
    },
    /// The time limit passed.
    TimeLimit(f64),
    /// Virtual time: [`ZERO_TIME_INPUTS`] inputs in a row at one instant
    /// (a loop whose tasks all answer at once): stopped as stuck.
    ZeroTimeLoop(f64),
}

impl End {
    /// The exit status of `mcl run`: 0 ok, 1 fail, 3 stuck or time limit.
    pub fn exit_code(&self) -> u8 {
        match self {
            End::Outcome(Outcome::Ok) => 0,
            End::Outcome(Outcome::Fail) => 1,
            _ => 3,
        }
    }

    /// `ok`, `fail`, `stuck` or `time_limit`.
    pub fn result(&self) -> &'static str {
        match self {
            End::Outcome(o) => o.as_str(),
            End::Quiescent { .. } | End::ZeroTimeLoop(_) => "stuck",
            End::TimeLimit(_) => "time_limit",
        }
    }

    /// The mission time of the end when the driver decided it (the time
    /// limit, the instant of a zero-time loop), else None (the player's time).
    pub fn driver_time(&self) -> Option<f64> {
        match self {
            End::TimeLimit(t) | End::ZeroTimeLoop(t) => Some(*t),
            _ => None,
        }
    }
}

/// A player with its tracer, sink and optional journal.
pub struct Session<'a> {
    /// The player.
    pub player: Player,
    /// Turns outputs into records.
    pub tracer: Tracer,
    /// Where records go.
    pub sink: &'a mut (dyn Sink + Send),
    /// The journal, if any.
    pub journal: Option<JournalWriter>,
    /// Test hook: abort the process (as `kill -9` would) right after the
    /// n-th journal sync of this process, before that input's actions are sent.
    pub crash_after: Option<u64>,
    /// The link to the AAC is down (or not yet up): actions are queued, and
    /// their records say so (`queued`).
    pub link_down: bool,
    /// The AAC session the run is in (from the journal when resuming) and
    /// the events handled in it, told to the link once journaled.
    pub delivered: Delivered,
    /// [`Session::step`] leaves the journal's sync to the caller
    /// ([`Session::sync`]), who adds entries of its own to the same sync
    /// (a coordinated vehicle's messages).
    pub defer_sync: bool,
    /// Operator commands for [`run_real_time`] (none: no operator).
    pub operator: Option<operator::Receiver>,
    /// The operator aborted the mission: its end is `aborted`.
    operator_aborted: bool,
    syncs: u64,
}

impl<'a> Session<'a> {
    /// A session without journal.
    pub fn new(player: Player, tracer: Tracer, sink: &'a mut (dyn Sink + Send)) -> Self {
        Session {
            player,
            tracer,
            sink,
            journal: None,
            crash_after: None,
            link_down: false,
            delivered: Delivered::default(),
            defer_sync: false,
            operator: None,
            operator_aborted: false,
            syncs: 0,
        }
    }

    /// Records one output (used for replayed outputs too).
    pub fn emit(&mut self, o: &Output) {
        if !self.sink.wants_records() {
            return;
        }
        let mut r = self.tracer.record(o);
        if let (true, RecordKind::Action { queued, .. }) = (self.link_down, &mut r.kind) {
            *queued = true;
        }
        if self.operator_aborted {
            operator::mark_aborted(&mut r);
        }
        self.sink.record(&r);
    }

    /// Records a record made by the driver.
    pub fn emit_record(&mut self, mut r: Record) {
        r.mission = self.tracer.mission().map(str::to_string);
        if self.operator_aborted {
            operator::mark_aborted(&mut r);
        }
        self.sink.record(&r);
    }

    /// Feeds one input: journals it and its firings (synced), records the
    /// outputs and returns them; the caller sends their actions
    /// ([`actions`]).
    pub fn step(&mut self, input: Input) -> Result<Vec<Output>, String> {
        self.step_numbered(input, None)
    }

    /// [`Session::step`] for an event or perception that the AAC numbered
    /// `n` in its session: the number is journaled with it, then told to the
    /// link ([`Session::delivered`]).
    pub fn step_numbered(&mut self, input: Input, n: Option<u64>) -> Result<Vec<Output>, String> {
        let out = input.apply(&mut self.player);
        if let Some(j) = &mut self.journal {
            j.append(&input.entry_numbered(n));
            let ids = self.player.net().transitions();
            for o in &out {
                if let Output::Fired { t, transition, .. } = o {
                    j.append(&Entry::Fire { t: *t, transition: ids[transition.index()].id.to_string() });
                }
            }
        }
        if !self.defer_sync {
            self.sync()?;
        }
        if let (Some(n), (Some(session), _)) = (n, self.delivered.get()) {
            self.delivered.set(&session, n);
        }
        for o in &out {
            self.emit(o);
        }
        Ok(out)
    }

    /// The AAC welcomed the run in session `id`: journals it when it is
    /// another session than the run's (synced: the AAC may send events of
    /// it at once), and, when the AAC lost its memory (`restarted`),
    /// re-establishes the running primitives ([`Input::Restart`]). Returns
    /// the outputs, whose actions the caller sends.
    pub fn on_session(&mut self, now: f64, id: &str, restarted: bool) -> Result<Vec<Output>, String> {
        self.link_down = false;
        if self.delivered.get().0.as_deref() == Some(id) {
            return Ok(Vec::new());
        }
        self.delivered.set(id, 0);
        if let Some(j) = &mut self.journal {
            j.append(&Entry::Session { id: id.to_string() });
            if !restarted {
                j.sync()?;
            }
        }
        if !restarted || self.player.outcome().is_some() {
            return Ok(Vec::new());
        }
        self.step(Input::Restart(now.max(self.player.now())))
    }

    /// Buffers a journal entry (written with the next sync).
    pub fn journal_entry(&mut self, e: &Entry) {
        if let Some(j) = &mut self.journal {
            j.append(e);
        }
    }

    /// Writes the buffered journal entries and waits until they are on
    /// disk; then the test hook `crash_after` may abort the process. Does
    /// nothing (and counts nothing) when nothing is buffered.
    pub fn sync(&mut self) -> Result<(), String> {
        let Some(j) = &mut self.journal else { return Ok(()) };
        if j.is_empty() {
            return Ok(());
        }
        j.sync()?;
        self.syncs += 1;
        if self.crash_after.is_some_and(|n| self.syncs >= n) {
            std::process::abort();
        }
        Ok(())
    }

    /// Journals an acknowledgement (written with the next sync).
    pub fn ack(&mut self, seq: u64) {
        if let Some(j) = &mut self.journal {
            j.append(&Entry::Ack { seq });
        }
    }

    /// Records the end of a run that the player did not decide itself.
    pub fn end_by_driver(&mut self, t: f64, result: &str, reason: String) {
        self.emit_record(Record::outcome(t, result, Some(reason)));
    }

    /// Records a warning.
    pub fn warn(&mut self, t: f64, message: String) {
        self.emit_record(Record::warning(t, message));
    }

    /// Records a notice of the link to the AAC.
    pub fn link_notice(&mut self, t: f64, message: String) {
        self.emit_record(Record::link(t, message));
    }
}

/// The actions among outputs.
pub fn actions(out: &[Output]) -> impl Iterator<Item = &Action> {
    out.iter().filter_map(|o| match o {
        Output::Send { action, .. } => Some(action),
        _ => None,
    })
}

/// The mission-time limit of a virtual-time run when none is given: one
/// day. A mission that loops forever then ends (exit status 3) instead of
/// filling the disk with its trace; `--time-limit` changes it.
pub const DEFAULT_VIRTUAL_TIME_LIMIT: f64 = 86_400.0;

pub use crate::virtual_loop::ZERO_TIME_INPUTS;

/// Limits of a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Limits {
    /// Stop when mission time passes this.
    pub time_limit: Option<f64>,
    /// The time limit is [`DEFAULT_VIRTUAL_TIME_LIMIT`], not one the user gave
    /// (the message says how to change it).
    pub default_limit: bool,
    /// Wall-clock seconds to wait for the vehicle (an AAC link that is down
    /// when the run starts) before the mission starts; `None`: for ever.
    pub connect_timeout: Option<f64>,
}

impl Limits {
    /// The limits of a virtual-time run: `given`, else the default limit.
    /// An infinite `given` means no limit.
    pub fn virtual_time(given: Option<f64>) -> Limits {
        match given {
            Some(t) if t.is_infinite() => Limits { time_limit: None, default_limit: false, connect_timeout: None },
            Some(t) => Limits { time_limit: Some(t), default_limit: false, connect_timeout: None },
            None => Limits { time_limit: Some(DEFAULT_VIRTUAL_TIME_LIMIT), default_limit: true, connect_timeout: None },
        }
    }

    /// The limits of a real-time run (no limit unless given).
    pub fn real_time(given: Option<f64>) -> Limits {
        Limits { time_limit: given.filter(|t| t.is_finite()), default_limit: false, connect_timeout: None }
    }

    /// Why a run stopped at the time limit `limit`.
    pub fn passed(&self, limit: f64) -> String {
        if self.default_limit {
            format!(
                "the default time limit of virtual-time runs ({limit} s of mission time) passed: the mission may loop forever (--time-limit SECONDS to change it, --time-limit inf for none)"
            )
        } else {
            format!("the time limit of {limit} s passed")
        }
    }
}

pub(crate) fn perception_or_event(t: f64, m: Inbound) -> Option<Input> {
    match m {
        Inbound::Event { event, activation, .. } => Some(Input::Event(t, event, activation)),
        Inbound::Perception { name, value, .. } => Some(Input::Perception(t, name, value)),
        _ => None,
    }
}

/// The number the AAC gave an event or a perception.
fn number(m: &Inbound) -> Option<u64> {
    match m {
        Inbound::Event { n, .. } | Inbound::Perception { n, .. } => *n,
        _ => None,
    }
}

pub(crate) fn feed_mock(s: &mut Session<'_>, mock: &mut (impl VirtualVehicle + ?Sized), t: f64, out: &[Output]) {
    for a in actions(out) {
        mock.on_action(t, a);
    }
    for w in mock.take_warnings() {
        s.warn(t, w);
    }
    drain_poses(s, mock);
}

/// Traces the poses `vehicle` reached since the last call.
pub(crate) fn drain_poses(s: &mut Session<'_>, vehicle: &mut (impl VirtualVehicle + ?Sized)) {
    for p in vehicle.take_poses() {
        let r = pose_record(s.tracer.mission(), &p);
        s.emit_record(r);
    }
}

/// The `pose` trace record of `p`.
pub fn pose_record(mission: Option<&str>, p: &Pose) -> Record {
    let r = Record::new(p.t, RecordKind::Pose { x: p.x, y: p.y, z: p.z, yaw: p.yaw });
    Record { mission: mission.map(str::to_string), ..r }
}

/// Runs `s` against `mock` in virtual time until the mission ends, nothing
/// more can happen, or the time limit passes. Starts the player if it has
/// not started (a resumed player has). `mock.initial()` must have been called.
/// The loop is [`virtual_loop::run`]: at equal times the player's timers go
/// before the vehicle's messages.
pub fn run_virtual(
    s: &mut Session<'_>,
    mock: &mut (impl VirtualVehicle + ?Sized),
    limits: Limits,
) -> Result<End, String> {
    if !started(s) {
        let actions = s.step(Input::Start(0.0))?;
        feed_mock(s, mock, 0.0, &actions);
    }
    let mut one = Single { s, vehicle: mock };
    let stop = virtual_loop::run_now(&mut one, &limits)?;
    Ok(single_end(one.s, stop, &limits))
}

/// [`run_virtual`] paced by `clock` (`mcl run --sim --speed X`): the same
/// inputs at the same mission times, each taken once the clock reaches its
/// time ([`virtual_loop::run_paced`]). A resumed player's clock goes on from
/// its last journaled input.
pub async fn run_paced(
    s: &mut Session<'_>,
    vehicle: &mut (impl VirtualVehicle + ?Sized),
    limits: Limits,
    clock: Clock,
) -> Result<End, String> {
    if !started(s) {
        let actions = s.step(Input::Start(0.0))?;
        feed_mock(s, vehicle, 0.0, &actions);
    }
    // The operator's commands (`mcl run --sim --operator-token`).
    let commands: Vec<operator::Receiver> = s.operator.take().into_iter().collect();
    let mut one = Single { s, vehicle };
    let stop = virtual_loop::run_operated(&mut one, &limits, Some(clock), commands).await?;
    Ok(single_end(one.s, stop, &limits))
}

/// How a single run that the loop stopped with `stop` ended (recorded).
fn single_end(s: &mut Session<'_>, stop: Stop, limits: &Limits) -> End {
    match stop {
        Stop::Over => End::Outcome(s.player.outcome().unwrap_or(Outcome::Stuck)),
        Stop::Quiescent => {
            let awaited = s.player.awaited_events();
            let t = s.player.now();
            s.end_by_driver(
                t,
                "stuck",
                format!(
                    "nothing more can happen: no timer is pending and the mock vehicle has nothing left to send; the mission waits for {}",
                    if awaited.is_empty() { "nothing".to_string() } else { awaited.join(", ") }
                ),
            );
            End::Quiescent { awaited }
        }
        Stop::TimeLimit(limit) => {
            s.end_by_driver(limit, "time_limit", limits.passed(limit));
            End::TimeLimit(limit)
        }
        Stop::ZeroTimeLoop(t) => {
            s.end_by_driver(t, "stuck", virtual_loop::zero_time_message(t));
            End::ZeroTimeLoop(t)
        }
    }
}

/// Where the next input of a single run comes from.
#[derive(Clone, Copy, Debug)]
enum Source {
    Timer,
    Vehicle,
}

/// A player and its vehicle, for the virtual-time loop.
struct Single<'s, 'a, V: VirtualVehicle + ?Sized> {
    s: &'s mut Session<'a>,
    vehicle: &'s mut V,
}

impl<V: VirtualVehicle + ?Sized> Discrete for Single<'_, '_, V> {
    type Source = Source;

    fn is_over(&mut self) -> bool {
        self.s.player.outcome().is_some()
    }

    fn deadlines(&self, out: &mut Vec<(f64, Source)>) {
        out.extend(self.s.player.next_deadline().map(|t| (t, Source::Timer)));
        out.extend(self.vehicle.next_deadline().map(|t| (t, Source::Vehicle)));
    }

    async fn step(&mut self, t: f64, source: Source) -> Result<(), String> {
        let (s, vehicle) = (&mut *self.s, &mut *self.vehicle);
        let actions = match source {
            Source::Timer => s.step(Input::Timer(t))?,
            Source::Vehicle => {
                // A simulated vehicle may only advance to `t` (a step with
                // nothing to send but poses).
                let Some((tm, m)) = vehicle.pop_due(t) else {
                    drain_poses(s, vehicle);
                    return Ok(());
                };
                match perception_or_event(tm, m) {
                    Some(input) => s.step(input)?,
                    None => return Ok(()),
                }
            }
        };
        let now = s.player.now();
        feed_mock(s, vehicle, now, &actions);
        Ok(())
    }

    async fn operator(&mut self, t: f64, _who: usize, c: Command) -> Result<(), String> {
        let actions = self.s.operator_input(t, c)?;
        feed_mock(self.s, self.vehicle, t, &actions);
        Ok(())
    }
}

fn started(s: &Session<'_>) -> bool {
    s.player.is_started()
}

/// What the player does with one message from the link, at mission time
/// `now`; returns its outputs (actions to send). Link states are `link`
/// records (a lost link is also a warning: actions are queued meanwhile).
fn on_inbound(s: &mut Session<'_>, now: f64, m: Inbound) -> Result<Vec<Output>, String> {
    Ok(match m {
        Inbound::Ack { seq } => {
            s.ack(seq);
            Vec::new()
        }
        Inbound::Disconnected => {
            s.link_down = true;
            s.warn(now, "link to the AAC lost; reconnecting (actions are queued meanwhile)".into());
            Vec::new()
        }
        Inbound::Connected => {
            s.link_down = false;
            s.link_notice(now, "link to the AAC up".into());
            Vec::new()
        }
        Inbound::Session { id, restarted } => s.on_session(now, &id, restarted)?,
        Inbound::Notice { message } => {
            s.link_notice(now, message);
            Vec::new()
        }
        m => {
            let n = number(&m);
            match perception_or_event(now, m) {
                Some(input) => s.step_numbered(input, n)?,
                None => Vec::new(),
            }
        }
    })
}

/// Runs `s` over `link` in real time with `clock` until the mission ends or
/// the time limit passes. `resend` are actions to send first (after a resume).
///
/// A link that reports [`Inbound::Session`] with `restarted` must have
/// dropped the actions it had not got acknowledged (the TCP link with
/// [`ConnectOptions::reestablish`](crate::tcp::ConnectOptions::reestablish)):
/// the player then sends what re-establishes its running primitives.
pub async fn run_real_time(
    s: &mut Session<'_>,
    link: &mut Link,
    clock: Clock,
    limits: Limits,
    resend: Vec<Action>,
) -> Result<End, String> {
    let send = |link: &mut Link, out: Vec<Output>| -> Result<(), String> {
        for o in out {
            if let Output::Send { action, .. } = o {
                link.actions.send(action).map_err(|_| "the link to the AAC is closed".to_string())?;
            }
        }
        Ok(())
    };
    let mut clock = clock;
    if !started(s) && s.link_down {
        // The mission starts when the vehicle is there: no time-out runs,
        // and no action waits in a queue, while nobody answers. Mission time
        // stands still meanwhile.
        let at = clock.now();
        let wait = async {
            loop {
                match link.inbound.recv().await {
                    None => return Err("the link to the AAC closed".to_string()),
                    Some(m) => {
                        let connected = !matches!(m, Inbound::Notice { .. } | Inbound::Session { .. });
                        let out = on_inbound(s, at, m)?;
                        send(link, out)?;
                        if connected {
                            return Ok(());
                        }
                    }
                }
            }
        };
        match limits.connect_timeout {
            Some(t) => {
                tokio::time::timeout(std::time::Duration::from_secs_f64(t.max(0.0)), wait).await.map_err(|_| {
                    format!("no vehicle answered within {t} s (--connect-timeout SECONDS waits longer, `inf` for ever)")
                })??
            }
            None => wait.await?,
        }
        clock = Clock::new(clock.speed(), at);
    }
    for a in resend {
        link.actions.send(a).map_err(|_| "the link to the AAC is closed".to_string())?;
    }
    if !started(s) {
        let out = s.step(Input::Start(clock.now()))?;
        send(link, out)?;
    }
    let mut commands = s.operator.take();
    // While paused: the mission time it was paused at, and the actions
    // held until `resume`.
    let mut paused: Option<f64> = None;
    let mut held: Vec<Output> = Vec::new();
    loop {
        if let Some(o) = s.player.outcome() {
            send(link, std::mem::take(&mut held))?;
            if let Some(j) = &mut s.journal {
                j.sync()?;
            }
            s.operator = commands;
            return Ok(End::Outcome(o));
        }
        let deadline = s.player.next_deadline();
        let wake = match (deadline, limits.time_limit) {
            (Some(d), Some(l)) => Some(d.min(l)),
            (d, l) => d.or(l),
        };
        let until = wake.map(|w| clock.instant_at(w));
        let sleep = async move {
            match until {
                Some(i) => tokio::time::sleep_until(i).await,
                None => std::future::pending::<()>().await,
            }
        };
        let actions = tokio::select! {
            c = async {
                match &mut commands {
                    Some(c) => c.recv().await,
                    None => std::future::pending().await,
                }
            } => match c {
                // The operator's side is gone: no more commands.
                None => {
                    commands = None;
                    Vec::new()
                }
                Some(c) => {
                    let now = paused.unwrap_or_else(|| clock.now()).max(s.player.now());
                    on_operator(s, now, c, &mut paused, &mut clock)?
                }
            },
            m = link.inbound.recv(), if paused.is_none() => {
                let now = clock.now().max(s.player.now());
                match m {
                    None => return Err("the link to the AAC closed".into()),
                    Some(m) => on_inbound(s, now, m)?,
                }
            }
            _ = sleep, if paused.is_none() => {
                let w = wake.unwrap_or_default();
                match deadline {
                    Some(d) if d <= w => s.step(Input::Timer(d.max(s.player.now())))?,
                    _ => {
                        let limit = limits.time_limit.unwrap_or(w);
                        s.end_by_driver(limit, "time_limit", limits.passed(limit));
                        if let Some(j) = &mut s.journal {
                            j.sync()?;
                        }
                        s.operator = commands;
                        return Ok(End::TimeLimit(limit));
                    }
                }
            }
        };
        if paused.is_some() {
            held.extend(actions);
        } else {
            send(link, std::mem::take(&mut held))?;
            send(link, actions)?;
        }
    }
}

/// Takes an operator's command at mission time `now`: traces and journals
/// it, pauses or resumes the clock, and returns the outputs of the input it
/// becomes (`abort`, `answer`), whose actions the caller sends (or holds,
/// while paused).
fn on_operator(
    s: &mut Session<'_>,
    now: f64,
    c: Command,
    paused: &mut Option<f64>,
    clock: &mut Clock,
) -> Result<Vec<Output>, String> {
    let ignored = match &c {
        Command::Pause => paused.is_some(),
        Command::Resume => paused.is_none(),
        Command::Abort | Command::Answer { .. } => false,
    };
    if ignored {
        s.warn(
            now,
            format!(
                "operator: {} ignored (the run is {})",
                c.name(),
                if paused.is_some() { "paused" } else { "running" }
            ),
        );
        return Ok(Vec::new());
    }
    match c {
        Command::Pause => *paused = Some(now),
        Command::Resume => {
            let at = paused.take().unwrap_or(now);
            *clock = Clock::new(clock.speed(), at);
        }
        _ => {}
    }
    s.operator_input(now, c)
}

impl Session<'_> {
    /// Takes an operator's command at mission time `now` (the caller pauses
    /// or resumes its clock): traces and journals it; `abort` and `answer`
    /// become inputs, whose outputs are returned (the caller sends their
    /// actions). Used by every driver that takes commands.
    pub fn operator_input(&mut self, now: f64, c: Command) -> Result<Vec<Output>, String> {
        self.emit_record(Record::new(now, RecordKind::Operator { command: c.clone() }));
        self.journal_entry(&Entry::Operator { t: now, command: c.clone() });
        match c {
            Command::Pause | Command::Resume => {
                self.sync()?;
                Ok(Vec::new())
            }
            Command::Abort => {
                if !operator::has_abort_hook(self.player.net()) {
                    self.sync()?;
                    self.warn(
                        now,
                        "operator: abort refused: the net has no abort hook (mcl run adds it with --operator-token)"
                            .into(),
                    );
                    return Ok(Vec::new());
                }
                self.operator_aborted = true;
                self.step(Input::Event(now, operator::ABORT_EVENT.to_string(), None))
            }
            Command::Answer { event } => self.step(Input::Event(now, event, None)),
        }
    }

    /// The mission was aborted by an operator (a resumed run whose journal
    /// says so): its `stuck` end is recorded as `aborted`.
    pub fn set_operator_aborted(&mut self) {
        self.operator_aborted = true;
    }

    /// Whether an operator aborted the mission.
    pub fn operator_aborted(&self) -> bool {
        self.operator_aborted
    }
}

/// Serves `mock` on `end` in real time: answers actions (with an `Ack`) and
/// sends its scheduled messages when they are due. Ends when the player's
/// end of the link is dropped. Warnings go to `warn`.
///
/// Inputs first, one answer at a time: every action already received is
/// executed before the next due message is sent (so a primitive disabled
/// before its answer was due never answers), and after each message the
/// task yields, so that an in-process player reacts (and its `disable`
/// actions arrive) before the next message due at the same time is taken,
/// as in virtual time.
pub async fn serve_mock(mut mock: MockVehicle, mut end: AacEnd, clock: Clock, mut warn: impl FnMut(String)) {
    use tokio::sync::mpsc::error::TryRecvError;
    mock.initial();
    let mut execute = |mock: &mut MockVehicle, end: &AacEnd, a: Action| -> bool {
        mock.on_action(clock.now(), &a);
        for w in mock.take_warnings() {
            warn(w);
        }
        end.inbound.send(Inbound::Ack { seq: a.seq }).is_ok()
    };
    loop {
        loop {
            match end.actions.try_recv() {
                Ok(a) => {
                    if !execute(&mut mock, &end, a) {
                        return;
                    }
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        let wake = mock.next_deadline();
        if let Some(d) = wake.filter(|&d| clock.instant_at(d) <= tokio::time::Instant::now()) {
            if let Some((_, m)) = mock.pop_due(d.max(clock.now())) {
                if end.inbound.send(m).is_err() {
                    return;
                }
            }
            tokio::task::yield_now().await;
            continue;
        }
        let sleep = async {
            match wake {
                Some(w) => tokio::time::sleep_until(clock.instant_at(w)).await,
                None => std::future::pending::<()>().await,
            }
        };
        tokio::select! {
            a = end.actions.recv() => match a {
                None => return,
                Some(a) => {
                    if !execute(&mut mock, &end, a) {
                        return;
                    }
                }
            },
            _ = sleep => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::player::PlayerOptions;
    use crate::scenario::Scenario;
    use crate::trace::SourceMap;
    use mcl_net::{ActionRef, Delay, NetBuilder, Place, Transition, TransitionKind};
    use std::sync::Arc;

    /// begin → enable X (T0) → X's ok event (T2) or a 30 s time-out (TO) → ok / fail.
    fn net() -> Arc<mcl_net::Net> {
        let mut b = NetBuilder::new("m");
        b.property("task_events:X", r#"{"ok":["evXOk"],"fail":["evXFail"]}"#);
        let begin = b.add_place(Place::new("mission.begin").with_tokens(1));
        let run = b.add_place(Place::new("run"));
        let ok = b.add_place(Place::new("mission.ok"));
        let fail = b.add_place(Place::new("mission.fail"));
        let task =
            |t: Transition| t.with_provenance(mcl_net::Provenance { task: Some("X".into()), ..Default::default() });
        let enable = ActionRef {
            action: "enableX".into(),
            primitive: "XPrimitive".into(),
            command: "enable".into(),
            params: vec![],
        };
        let disable = ActionRef { command: "disable".into(), action: "disableX".into(), ..enable.clone() };
        let t0 = b.add_transition(task(Transition::new("T0").with_action(enable)));
        let t2 = b.add_transition(task(
            Transition::new("T2").with_kind(TransitionKind::Event("evXOk".into())).with_action(disable.clone()),
        ));
        let to = b.add_transition(task(
            Transition::new("TO").with_kind(TransitionKind::Timed(Delay::Fixed(30.0))).with_action(disable),
        ));
        b.add_input(begin, t0, 1).add_output(t0, run, 1);
        b.add_input(run, t2, 1).add_output(t2, ok, 1);
        b.add_input(run, to, 1).add_output(to, fail, 1);
        Arc::new(b.build().unwrap())
    }

    fn run_both(scenario: &str) -> (Vec<String>, Vec<String>, End, End) {
        let net = net();
        let names = |c: &Collect| -> Vec<String> {
            c.0.iter()
                .filter_map(|r| match &r.kind {
                    RecordKind::Action { action: what, .. }
                    | RecordKind::Event { event: what, .. }
                    | RecordKind::Outcome { result: what, .. } => Some(format!("{} {what}", r.t)),
                    _ => None,
                })
                .collect()
        };
        // Virtual time.
        let mut sink = Collect::default();
        let tracer = Tracer::new(&net, None, &mut SourceMap::default());
        let mut s = Session::new(Player::new(net.clone(), PlayerOptions::seeded(3)), tracer, &mut sink);
        let mut mock = MockVehicle::from_net(&net, Scenario::from_toml(scenario, "s").unwrap(), 3);
        mock.initial();
        let ev = run_virtual(&mut s, &mut mock, Limits::default()).unwrap();
        drop(s);
        let virtual_names = names(&sink);
        // Real time on a paused tokio clock, through the link and the mock task.
        let rt = tokio::runtime::Builder::new_current_thread().enable_all().start_paused(true).build().unwrap();
        let (er, real_names) = rt.block_on(async {
            let clock = Clock::new(1.0, 0.0);
            let (mut link, end) = crate::link::pair();
            let mock = MockVehicle::from_net(&net, Scenario::from_toml(scenario, "s").unwrap(), 3);
            let server = tokio::spawn(serve_mock(mock, end, clock, |_| {}));
            let mut sink = Collect::default();
            let tracer = Tracer::new(&net, None, &mut SourceMap::default());
            let mut s = Session::new(Player::new(net.clone(), PlayerOptions::seeded(3)), tracer, &mut sink);
            let e = run_real_time(&mut s, &mut link, clock, Limits::default(), Vec::new()).await.unwrap();
            drop(s);
            drop(link);
            server.await.unwrap();
            (e, names(&sink))
        });
        (virtual_names, real_names, ev, er)
    }

    #[test]
    fn real_time_on_a_paused_clock_equals_virtual_time() {
        let (v, r, ev, er) = run_both("[tasks.X]\ndelay = 12\n");
        assert_eq!(v, ["0 enableX", "12 evXOk", "12 disableX", "12 ok"]);
        assert_eq!(ev, End::Outcome(Outcome::Ok));
        assert_eq!(er, ev);
        // Real time reads the clock: times are equal up to the clock's resolution.
        let strip = |v: &[String]| v.iter().map(|s| s.split_once(' ').unwrap().1.to_string()).collect::<Vec<_>>();
        assert_eq!(strip(&r), strip(&v));

        let (v, r, ev, er) = run_both("[tasks.X]\noutcome = \"never\"\n");
        assert_eq!(v, ["0 enableX", "30 disableX", "30 fail"]);
        assert_eq!((ev.clone(), er), (End::Outcome(Outcome::Fail), ev));
        assert_eq!(strip(&r), strip(&v));
    }

    #[test]
    fn time_limit() {
        let net = net();
        let mut sink = Collect::default();
        let tracer = Tracer::new(&net, None, &mut SourceMap::default());
        let mut s = Session::new(Player::new(net.clone(), PlayerOptions::seeded(3)), tracer, &mut sink);
        let mut mock = MockVehicle::from_net(&net, Scenario::from_toml("[tasks.X]\ndelay = 50", "s").unwrap(), 3);
        mock.initial();
        assert_eq!(
            run_virtual(
                &mut s,
                &mut mock,
                Limits { time_limit: Some(10.0), default_limit: false, connect_timeout: None }
            )
            .unwrap(),
            End::TimeLimit(10.0)
        );
    }
}
