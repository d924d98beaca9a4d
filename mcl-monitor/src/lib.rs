//! # mcl-monitor
//!
//! The mission monitor (docs/monitor.md): a web page, served by the `mcl`
//! binary itself (no build step, nothing fetched from elsewhere: the page
//! is in `assets/`, embedded with `include_str!`), that shows a run as it
//! happens (`mcl run --monitor`) or replays trace files (`mcl monitor`):
//! the mission's source with its running and finished calls, a
//! chronogram, the log of actions, events and coordination messages, a map
//! of poses, the outcome.
//!
//! * [`state`]: what the records say, derived the way the page derives it
//!   (running calls with their lines, outcomes, pause); sans-IO.
//! * [`hub`]: the records of a run and its state, shared between the run
//!   (which [`Hub::push`]es records) and the server.
//! * [`tree`]: the control-structure tree of each mission, as plain data.
//! * [`http`]: the HTTP API (`/api/state`, `/api/events` with server-sent
//!   events, `/api/operator`, ...) and the page.
//! * [`Monitor`]: the server on its own thread.
//!
//! mcl-runtime knows nothing of this crate: the binary feeds the hub from
//! its trace sink and hands the operator channel
//! ([`mcl_runtime::operator`]) to the real-time driver.

pub mod http;
pub mod hub;
pub mod state;
pub mod tree;

mod server;

pub use hub::{Hub, Mode};
pub use server::Monitor;
