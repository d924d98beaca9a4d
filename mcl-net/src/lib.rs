//! Petri nets for MCL: the net model shared by the compiler, the verifier and
//! the on-board player.
//!
//! * [`model`]: [`Net`], its builder, MCL annotations and provenance;
//! * [`pnml`]: PNML 2009 reading and writing, with MCL data in
//!   `<toolspecific tool="mcl">`;
//! * [`engine`]: the one firing rule, stated in its docs, and [`Engine`], a
//!   net played by it in mission time (immediate first, timers, events,
//!   seeded random choice), with caller hooks;
//! * [`semantics`]: the rule's pieces (enabledness, firing, the choice of the
//!   ready transitions, an incremental enabled-set tracker);
//! * [`mod@explore`]: explicit-state reachability analysis;
//! * [`structural`]: incidence matrix, invariants, siphons and traps;
//! * [`graph`]: strongly connected components of implicit graphs;
//! * [`coord_props`]: the coordination properties of a vehicle net;
//! * [`wire`]: the compact binary encoding of coordination messages;
//! * [`input`]: the bounded reader of every input file (regular files only).
//!
//! ```
//! use mcl_net::{analyze, NetBuilder, Options, Place, Transition};
//!
//! let mut b = NetBuilder::new("ping");
//! let idle = b.add_place(Place::new("idle").with_tokens(1));
//! let busy = b.add_place(Place::new("busy"));
//! let start = b.add_transition(Transition::new("start"));
//! let stop = b.add_transition(Transition::new("stop"));
//! b.add_input(idle, start, 1).add_output(start, busy, 1);
//! b.add_input(busy, stop, 1).add_output(stop, idle, 1);
//! let net = b.build().unwrap();
//!
//! let report = analyze(&net, &Options::plain());
//! assert_eq!((report.states, report.edges, report.deadlock), (2, 2, false));
//! let xml = mcl_net::write_pnml(&net).unwrap();
//! assert_eq!(mcl_net::read_pnml(&xml).unwrap(), net);
//! ```

// Unsafe code only in `explore/hw.rs` (a prefetch hint and `madvise`).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod coord_props;
pub mod engine;
pub mod explore;
pub mod graph;
pub mod input;
pub mod model;
mod name;
pub mod pnml;
pub mod semantics;
pub mod structural;
pub mod suggest;
pub mod wire;
mod xml;
pub mod xml_id;

pub use engine::{Engine, Hooks, Livelock};
pub use explore::{analyze, explore, AnalysisReport, Options, Semantics, StateId, StateSpace};
pub use model::{
    ActionRef, Arc, CallBinding, Delay, Handler, HandlerKind, Marking, Name, Net, NetBuilder, NetError, NodeId, Place,
    PlaceId, Provenance, SharedText, SourceSpan, TaskCalls, TaskEvents, Transition, TransitionId, TransitionKind,
    HANDLERS_PROPERTY,
};
pub use pnml::{read_pnml, read_pnml_nets, write_pnml, write_pnml_to, PnmlError};
pub use semantics::{EnabledTracker, FireError, MarkingClass};
