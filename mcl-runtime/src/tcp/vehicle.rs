//! A sans-IO [`Vehicle`] (the mock vehicle) served in real time behind the
//! protocol: [`serve_vehicle`].

use std::io;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::time::sleep;

use crate::link::{AacEnd, Action, Inbound};

use super::*;

/// A vehicle as a sans-IO state machine with an agenda (the shape of
/// [`MockVehicle`](crate::mock::MockVehicle)): times are mission seconds
/// given by the caller; the vehicle schedules (and may cancel) the messages
/// it will send, and the caller takes them when they are due.
pub trait Vehicle: Send {
    /// Schedules what the vehicle sends by itself (called once, first).
    fn initial(&mut self);
    /// Executes an action at time `now`.
    fn on_action(&mut self, now: f64, action: &Action);
    /// Time of the next scheduled message.
    fn next_deadline(&self) -> Option<f64>;
    /// Removes and returns the first message due at or before `now`.
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)>;
    /// Warnings to log since the last call.
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }
}

impl Vehicle for crate::mock::MockVehicle {
    fn initial(&mut self) {
        crate::mock::MockVehicle::initial(self);
    }
    fn on_action(&mut self, now: f64, action: &Action) {
        crate::mock::MockVehicle::on_action(self, now, action);
    }
    fn next_deadline(&self) -> Option<f64> {
        crate::mock::MockVehicle::next_deadline(self)
    }
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        crate::mock::MockVehicle::pop_due(self, now)
    }
    fn take_warnings(&mut self) -> Vec<String> {
        crate::mock::MockVehicle::take_warnings(self)
    }
}

/// Options of [`serve_vehicle`].
#[derive(Clone, Debug)]
pub struct VehicleOptions {
    /// Mission seconds per real second (> 0).
    pub speed: f64,
    /// A JSON file where each session's executed actions are written before
    /// they are acknowledged, and read back at start.
    pub state: Option<PathBuf>,
    /// Sessions kept in the state file.
    pub max_saved: usize,
    /// Logging on standard error (`Info` logs every executed action).
    pub log: LogLevel,
}

impl Default for VehicleOptions {
    fn default() -> Self {
        VehicleOptions { speed: 1.0, state: None, max_saved: 16, log: LogLevel::Off }
    }
}

/// Serves a vehicle made by `make` for each new session (`None`: the session
/// gets `unavailable` errors), in real time at `vehicle.speed`. Actions are
/// acknowledged once the vehicle has executed them (and, with
/// `vehicle.state`, once they are saved); sessions saved in the state file
/// are restored first, their vehicle rebuilt by replaying the saved actions,
/// so a restarted process neither forgets nor repeats.
///
/// Returns only on a bad state file; otherwise serves forever.
pub async fn serve_vehicle<F>(
    listener: TcpListener,
    mut options: ServeOptions,
    vehicle: VehicleOptions,
    mut make: F,
) -> io::Result<()>
where
    F: FnMut(&SessionKey) -> Option<Box<dyn Vehicle>> + Send + 'static,
{
    options.ack = AckMode::ByHandler;
    let speed = if vehicle.speed.is_finite() && vehicle.speed > 0.0 { vehicle.speed } else { 1.0 };
    let store = match &vehicle.state {
        Some(path) => {
            let state = StateFile::load(path)?;
            Some(Store { path: path.clone(), max: vehicle.max_saved.max(1), state: Arc::new(Mutex::new(state)) })
        }
        None => None,
    };
    let server = Server::new(options);
    if let Some(store) = &store {
        let saved = lock(&store.state).sessions.clone();
        for s in saved {
            let key = s.key();
            let end = server.restore(key.clone(), s.session.clone(), s.last_seq());
            log(
                vehicle.log,
                LogLevel::Info,
                "vehicle",
                format_args!(
                    "restored session {} (mission `{}`, run `{}`, {} actions executed, last seq {})",
                    s.session,
                    s.mission,
                    s.run,
                    s.executed.len(),
                    s.last_seq()
                ),
            );
            match make(&key) {
                Some(v) => {
                    tokio::spawn(run_vehicle(v, end, s, store.clone().into(), vehicle.log));
                }
                None => log(vehicle.log, LogLevel::Info, "vehicle", format_args!("no vehicle for `{}`", key.mission)),
            }
        }
    }
    let level = vehicle.log;
    server
        .run(listener, move |session: Session| {
            let saved = SavedSession {
                mission: session.key.mission.clone(),
                run: session.key.run.clone(),
                session: session.id.clone(),
                epoch_unix: unix_now(),
                speed,
                executed: Vec::new(),
            };
            match make(&session.key) {
                Some(v) => {
                    tokio::spawn(run_vehicle(v, session.end, saved, store.clone(), level));
                }
                None => log(
                    level,
                    LogLevel::Info,
                    "vehicle",
                    format_args!("no vehicle for mission `{}`: its actions will be refused", session.key.mission),
                ),
            }
        })
        .await;
    Ok(())
}

/// Runs one session's vehicle in real time.
///
/// Inputs first, one message at a time: every action already received is
/// executed before the next due message is sent (a primitive disabled
/// before its answer is sent never answers), and the task yields after each
/// message.
///
/// Determinism across restarts: each executed action is saved with the
/// number of messages sent before it; replaying the saved actions after as
/// many messages (always the first of the agenda) rebuilds the same agenda
/// and sends the same messages in the same order (the transport numbers
/// them identically and the player drops the ones it has).
async fn run_vehicle(
    mut v: Box<dyn Vehicle>,
    mut end: AacEnd,
    mut saved: SavedSession,
    store: Option<Store>,
    level: LogLevel,
) {
    use tokio::sync::mpsc::error::TryRecvError;
    let who = format!("vehicle {}", saved.session);
    let clock = |s: &SavedSession| ((unix_now() - s.epoch_unix) * s.speed).max(0.0);
    // Messages sent in this session (by this process and, replayed, by the previous ones).
    let mut sent: u64 = 0;
    let send = |v: &mut Box<dyn Vehicle>, end: &AacEnd, sent: &mut u64, (t, item): (f64, Inbound)| -> bool {
        log(level, LogLevel::Messages, &who, format_args!("t={t:.3} sends {item:?}"));
        *sent += 1;
        for w in v.take_warnings() {
            log(level, LogLevel::Info, &who, format_args!("{w}"));
        }
        end.inbound.send(item).is_ok()
    };
    v.initial();
    // Replay what a previous process executed: same messages, same order.
    for ex in &saved.executed {
        match ex.sent_before {
            Some(k) => {
                while sent < k {
                    let Some(m) = v.pop_due(f64::INFINITY) else { break };
                    if !send(&mut v, &end, &mut sent, m) {
                        return;
                    }
                }
            }
            None => {
                while let Some(m) = v.pop_due(ex.t) {
                    if !send(&mut v, &end, &mut sent, m) {
                        return;
                    }
                }
            }
        }
        log(
            level,
            LogLevel::Info,
            &who,
            format_args!("restored seq={} t={:.3} {} (executed before restart)", ex.action.seq, ex.t, ex.action.action),
        );
        v.on_action(ex.t, &ex.action);
    }
    let _ = v.take_warnings();
    let execute = |v: &mut Box<dyn Vehicle>, saved: &mut SavedSession, sent: u64, a: Action| -> bool {
        let now = clock(saved).max(saved.executed.last().map_or(0.0, |e| e.t));
        v.on_action(now, &a);
        saved.executed.push(Executed { t: now, sent_before: Some(sent), action: a.clone() });
        if let Some(store) = &store {
            if let Err(e) = store.put(saved) {
                // Acknowledged anyway: the player must go on; only a
                // restart of this process could now repeat it.
                log(LogLevel::Info, LogLevel::Info, &who, format_args!("cannot save state: {e}"));
            }
        }
        log(
            level,
            LogLevel::Info,
            &who,
            format_args!("executed seq={} t={now:.3} {} ({} {})", a.seq, a.action, a.primitive, a.command),
        );
        for w in v.take_warnings() {
            log(level, LogLevel::Info, &who, format_args!("{w}"));
        }
        end.inbound.send(Inbound::Ack { seq: a.seq }).is_ok()
    };
    loop {
        loop {
            match end.actions.try_recv() {
                Ok(a) => {
                    if !execute(&mut v, &mut saved, sent, a) {
                        return;
                    }
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        let now = clock(&saved);
        if let Some(m) = v.pop_due(now) {
            if !send(&mut v, &end, &mut sent, m) {
                return;
            }
            tokio::task::yield_now().await;
            continue;
        }
        let wait = v.next_deadline().map(|d| Duration::from_secs_f64(((d - now) / saved.speed).clamp(0.0, 1e9)));
        tokio::select! {
            a = end.actions.recv() => {
                let Some(a) = a else { return };
                if !execute(&mut v, &mut saved, sent, a) {
                    return;
                }
            }
            _ = sleep(wait.unwrap_or(Duration::ZERO)), if wait.is_some() => {}
        }
    }
}
