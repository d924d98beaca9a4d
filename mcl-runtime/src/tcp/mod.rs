//! The AAC protocol over TCP (`docs/aac-protocol.md`, module [`protocol`]).
//!
//! * Player side: [`connect`] returns a [`Link`] backed by a background task
//!   that connects, shakes hands, forwards actions, keeps every action until
//!   the AAC acknowledges it and re-sends it after a reconnection, reconnects
//!   with capped exponential backoff (reporting [`Inbound::Disconnected`] and
//!   [`Inbound::Connected`]), drops re-sent events and sends heartbeats.
//! * AAC side: [`serve`] / [`Server`] accept players and hand one
//!   [`AacEnd`] per *session* (one run of one mission) to a handler; a
//!   session outlives its connections: actions are executed once per `seq`,
//!   events are numbered and re-sent to a player that reconnects.
//! * [`serve_vehicle`] runs a sans-IO [`Vehicle`] (the mock vehicle) in real
//!   time behind the protocol, optionally persisting what it executed in a
//!   state file so that a restarted process neither forgets nor repeats.
//!
//! Every task must run inside a tokio runtime. One file per side:
//! `client.rs` (the player's link), `server.rs` (the AAC side),
//! `vehicle.rs` (a vehicle served behind it) and `state.rs` (its state file).
//!
//! [`protocol`]: crate::protocol
//! [`Link`]: crate::link::Link
//! [`AacEnd`]: crate::link::AacEnd
//! [`Inbound::Disconnected`]: crate::link::Inbound::Disconnected
//! [`Inbound::Connected`]: crate::link::Inbound::Connected

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

mod client;
mod server;
mod state;
mod vehicle;

pub use client::{connect, connect_with_handle, ConnectOptions, LinkError, LinkStats};
pub use server::{serve, AckMode, ServeOptions, Server, Session, SessionKey};
use state::Store;
pub use state::{Executed, SavedSession, StateFile};
pub use vehicle::{serve_vehicle, Vehicle, VehicleOptions};

/// How much a side writes on standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// Nothing.
    #[default]
    Off,
    /// Connections, refusals, errors, duplicates, executed actions.
    Info,
    /// Also every message sent and received.
    Messages,
}

fn log(level: LogLevel, need: LogLevel, who: &str, msg: std::fmt::Arguments<'_>) {
    if level >= need && level != LogLevel::Off {
        eprintln!("[{:>10.3}] {who}: {msg}", unix_now() % 100_000.0);
    }
}

fn unix_now() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}

/// A fresh identifier (run ids, session ids): time, process and a counter.
pub fn new_id() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    format!("{:x}-{:x}-{:x}", nanos, std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed))
}

/// Locks a mutex, ignoring poisoning (a panicking task must not take the
/// whole AAC down).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
