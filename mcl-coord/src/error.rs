//! Errors in the input of the coordination (bad references, bad arities).
//! Deadlocks are not errors of this kind: they are [`crate::Problem`]s of the
//! analysis report.

use mcl_net::NetError;

use crate::model::CallRef;

/// Why missions and constraints could not be coordinated at all.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CoordError {
    /// Two missions have the same name.
    DuplicateMission(String),
    /// A constraint names a mission that is not given.
    UnknownMission {
        /// Index of the constraint.
        constraint: usize,
        /// The missing mission.
        mission: String,
    },
    /// A constraint names a label that the mission does not have.
    UnknownLabel {
        /// Index of the constraint.
        constraint: usize,
        /// The reference.
        call: CallRef,
    },
    /// Wrong number of calls (order: 2; mutex, sync: at least 2).
    Arity {
        /// Index of the constraint.
        constraint: usize,
        /// Number of calls found.
        found: usize,
    },
    /// A mutex with bound 0.
    ZeroBound {
        /// Index of the constraint.
        constraint: usize,
    },
    /// The initial marking already violates the constraint (its supervisor
    /// place would need a negative initial marking, seed A.11).
    InitiallyViolated {
        /// Index of the constraint.
        constraint: usize,
        /// Initial marking the supervisor would need.
        initial: i64,
    },
    /// A net could not be built (an internal error).
    Net(NetError),
}

impl std::fmt::Display for CoordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CoordError::DuplicateMission(m) => write!(f, "two missions are named `{m}`"),
            CoordError::UnknownMission { constraint, mission } => {
                write!(f, "constraint #{}: there is no mission named `{mission}`", constraint + 1)
            }
            CoordError::UnknownLabel { constraint, call } => {
                write!(
                    f,
                    "constraint #{}: mission `{}` has no call labelled `{}`",
                    constraint + 1,
                    call.mission,
                    call.label
                )
            }
            CoordError::Arity { constraint, found } => {
                write!(f, "constraint #{}: wrong number of calls ({found})", constraint + 1)
            }
            CoordError::ZeroBound { constraint } => {
                write!(f, "constraint #{}: a mutex bound must be >= 1", constraint + 1)
            }
            CoordError::InitiallyViolated { constraint, initial } => write!(
                f,
                "constraint #{}: the initial marking violates it (its supervisor would start with {initial} tokens)",
                constraint + 1
            ),
            CoordError::Net(e) => write!(f, "internal error while building a net: {e}"),
        }
    }
}

impl std::error::Error for CoordError {}

impl From<NetError> for CoordError {
    fn from(e: NetError) -> Self {
        CoordError::Net(e)
    }
}
