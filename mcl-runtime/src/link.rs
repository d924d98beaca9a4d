//! The contract between the player and a vehicle's AAC, whatever carries it
//! (in-process channels, TCP): actions go out, events and perceptions come in.

use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

/// An action sent by the player (seed 5.2: `action = primitive( c: command, v: ... )`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Action {
    /// Sequence number, unique and increasing within a run (the AAC drops
    /// an action whose `seq` it has already executed).
    pub seq: u64,
    /// MCL action name, e.g. `enableGoto`.
    pub action: String,
    /// Vehicle primitive, e.g. `GotoPrimitive`.
    pub primitive: String,
    /// Command, e.g. `enable`.
    pub command: String,
    /// Parameter values by name (resolved from the call's arguments).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// The task that sent it, and its call site.
    pub task: Option<String>,
    pub call_site: Option<u32>,
}

/// What an AAC sends to the player.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Inbound {
    /// A primitive raised an event (seed 5.2: `events { ... }`).
    Event {
        /// Event name.
        event: String,
        /// The `seq` of the action that started the primitive run that
        /// raised it, when the AAC says (`docs/aac-protocol.md` §6).
        activation: Option<u64>,
    },
    /// A named perception value (for the world modeler of the planner).
    Perception { name: String, value: serde_json::Value },
    /// The AAC acknowledged action `seq`.
    Ack { seq: u64 },
    /// The link went down (the player keeps its marking; the link reconnects).
    Disconnected,
    /// The link is up again.
    Connected,
    /// Something about the link worth telling the operator (a reconnection
    /// attempt, an error reported by the AAC, a malformed message, a gap in
    /// the event numbers...). Changes nothing.
    Notice {
        /// One line.
        message: String,
    },
}

/// The player's end of a link to an AAC.
pub struct Link {
    pub actions: mpsc::UnboundedSender<Action>,
    pub inbound: mpsc::UnboundedReceiver<Inbound>,
}

/// The AAC's end of a link (what a mock vehicle or a TCP bridge holds).
pub struct AacEnd {
    pub actions: mpsc::UnboundedReceiver<Action>,
    pub inbound: mpsc::UnboundedSender<Inbound>,
}

/// A connected pair of in-process ends.
pub fn pair() -> (Link, AacEnd) {
    let (atx, arx) = mpsc::unbounded_channel();
    let (itx, irx) = mpsc::unbounded_channel();
    (Link { actions: atx, inbound: irx }, AacEnd { actions: arx, inbound: itx })
}
