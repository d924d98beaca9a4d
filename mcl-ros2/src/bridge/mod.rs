//! The bridge file `BRIDGE.toml`: per primitive of a vehicle file, which
//! ROS 2 topics, services and actions stand for it ([`config`]), the small
//! mapping language of its values and conditions ([`expr`]), the bridge as
//! a sans-IO state machine ([`engine`]), and the checks against the
//! vehicle file and the message types, each error with file and line
//! ([`check`]), whose vehicle comes from the compiler ([`vehicle`]).

pub mod check;
pub mod config;
pub mod engine;
pub mod expr;
pub mod vehicle;

pub use check::{check, load, load_text, Loaded, Vehicle, VehiclePrimitive};
pub use config::{Bridge, BridgeError};
pub use vehicle::vehicle_of;
