//! MCL over Zenoh (docs/zenoh.md): coordination messages between vehicles
//! ([`coord`]), the AAC protocol between the player and its vehicle
//! ([`aac`]), and each vehicle's mission state ([`status`]), under the key
//! expressions of [`keys`], on one Zenoh session per process ([`node`]).
//!
//! Only the `mcl` binary and its tests link this crate: mcl-runtime knows
//! nothing of Zenoh; it gives the transport-neutral pieces
//! ([`mcl_runtime::coord::CoordTransport`], [`mcl_runtime::link::Link`],
//! the sans-IO sequence windows of [`mcl_runtime::coord_seq`]).

pub mod aac;
pub mod coord;
pub mod keys;
pub mod node;
pub mod status;

pub use aac::{connect, AacOptions};
pub use coord::{zenoh_mesh, ZenohEnd};
pub use node::{Mode, Node, ZenohOptions};
pub use status::{Status, StatusPublisher, StatusTracker};
