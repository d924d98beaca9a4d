//! # mcl-runtime
//!
//! Runs compiled missions. The player and the mock vehicle are *sans-IO*
//! state machines (time is a number of seconds given by the caller), driven
//! either in virtual time (deterministic, instantaneous) or in real time
//! over a [`link::Link`] to an Architecture Abstraction Component (AAC), in
//! process or over TCP.

pub mod acoustic;
pub mod chronogram;
pub mod clock;
pub mod coord;
pub mod coord_link;
pub mod coord_seq;
pub mod counterexample;
pub mod driver;
pub mod journal;
pub mod link;
pub mod mock;
pub mod multi;
pub mod operator;
pub mod params;
pub mod player;
pub mod protocol;
pub mod scenario;
pub mod status;
pub mod tcp;
pub mod trace;
pub mod vehicle;
pub mod virtual_loop;
