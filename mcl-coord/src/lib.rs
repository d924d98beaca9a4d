//! # mcl-coord
//!
//! Multi-vehicle coordination for MCL (seed chapter 6; design and formulas
//! in `docs/coordination.md`).
//!
//! Each vehicle has its own mission; a `constraints { ... }` block relates
//! labelled calls of several missions (`mutex`, `order`, `sync`). This crate
//!
//! 1. maps every labelled call of a compiled mission to the nodes of its call
//!    adapter that mean *waiting*, *started*, *running* and *ended*
//!    ([`model`], [`Mission::from_compiled`]);
//! 2. builds the centralized net of several missions ([`centralize`]) and
//!    the supervisor places of every constraint, by SBPI and its Parikh
//!    vector extension ([`supervisor`]);
//! 3. proves the supervised net free of deadlock, or finds the deadlocks with
//!    a counterexample, adding supervisors for uncontrolled siphons where
//!    possible (seed Extract 6.1: [`analyze`], [`structure`], [`verify`]);
//! 4. reports deadlocking constraints as compiler diagnostics (E0406, and
//!    W0407 when the analysis cannot conclude), as a salsa query
//!    ([`check::coordination_diagnostics`]);
//! 5. splits it into one net per vehicle with the least communication, from
//!    an integer program (seed Extracts 6.2-6.4: [`decentral`],
//!    [`decentralize`]);
//! 6. turns the counterexamples of E0406 (and E0601) into scenarios that a
//!    dry run replays ([`replay`]).
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use mcl_compiler::{Database, Db};
//! let db = Database::new();
//! let file = db.file(std::path::Path::new("examples/auv-asc.mcl"));
//! let (missions, constraints) = mcl_coord::source::load(&db, file).map_err(|e| e.to_string())?;
//! let report = mcl_coord::analyze(&missions, &constraints)?;
//! assert!(report.deadlock_free);
//! for v in mcl_coord::decentralize(&missions, &report.supervisors)? {
//!     std::fs::write(format!("{}.pnml", v.mission), mcl_net::write_pnml(&v.net)?)?;
//! }
//! # Ok(())
//! # }
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod analysis;
pub mod central;
pub mod check;
pub mod compact;
pub mod conflict;
pub mod decentral;
pub mod error;
pub mod gen;
pub mod interrupt;
pub mod link_report;
pub mod model;
pub mod replay;
pub mod source;
pub mod structure;
pub mod supervisor;
pub mod verify;

pub use analysis::{analyze, analyze_with, AnalyzeOptions, Problem, Report, Verdict};
pub use central::{centralize, Part, Plant};
pub use check::coordination_diagnostics;
pub use decentral::{decentralize, VehicleNet};
pub use error::CoordError;
pub use model::{Activity, CallRef, Constraint, ConstraintKind, Mission};
pub use supervisor::{Origin, Supervisor};
