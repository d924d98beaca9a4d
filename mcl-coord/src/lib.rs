//! # mcl-coord
//!
//! Multi-vehicle coordination for MCL (seed chapter 6).

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod analysis;
pub mod central;
pub mod compact;
pub mod decentral;
pub mod error;
pub mod model;
pub mod source;
pub mod structure;
pub mod supervisor;
pub mod verify;

pub use analysis::{analyze, analyze_with, AnalyzeOptions, Problem, Report, Verdict};
pub use central::{centralize, Part, Plant};
pub use decentral::{decentralize, VehicleNet};
pub use error::CoordError;
pub use model::{Activity, CallRef, Constraint, ConstraintKind, Mission};
pub use supervisor::{Origin, Supervisor};
