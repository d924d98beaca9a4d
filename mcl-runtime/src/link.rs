//! The contract between the player and a vehicle's AAC, whatever carries it
//! (in-process channels, TCP): actions go out, events and perceptions come in.

use std::sync::{Arc, Mutex};

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
    /// Parameter values by name (resolved from the call's arguments), in
    /// the order the action declares them.
    pub params: crate::params::Params,
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
        /// Its number `n` in the AAC's session, when the AAC numbers them.
        #[serde(default)]
        n: Option<u64>,
    },
    /// A named perception value (for the world modeler of the planner).
    Perception {
        name: String,
        value: serde_json::Value,
        /// Its number `n` in the AAC's session (shared with events).
        #[serde(default)]
        n: Option<u64>,
    },
    /// The AAC acknowledged action `seq`.
    Ack { seq: u64 },
    /// The link went down (the player keeps its marking; the link reconnects).
    Disconnected,
    /// The AAC welcomed the player in session `id` (sent just before
    /// [`Inbound::Connected`]); the event numbers `n` that follow are in it.
    Session {
        /// The AAC's session id.
        id: String,
        /// The run knew another session: the AAC lost its memory of the run
        /// (it restarted without its state). The actions not acknowledged
        /// were dropped, not sent again: the player re-establishes what it
        /// has running ([`Player::reestablish`](crate::player::Player::reestablish)).
        restarted: bool,
    },
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

/// What the player has handled of the events and perceptions of an AAC
/// session: the session id and the highest number `n` in it. The player
/// sets it once an event is journaled; a TCP link reads it to tell the AAC
/// (`ping` and `hello` `last_event`), so that the AAC forgets only what
/// the player would still have after a crash. Shared by clones.
#[derive(Clone, Debug, Default)]
pub struct Delivered(Arc<Mutex<(Option<String>, u64)>>);

impl Delivered {
    /// Handled up to event `n` of `session` (`None`: no session known yet).
    pub fn new(session: Option<String>, n: u64) -> Delivered {
        Delivered(Arc::new(Mutex::new((session, n))))
    }

    /// Handled up to event `n` of `session`.
    pub fn set(&self, session: &str, n: u64) {
        let mut g = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if g.0.as_deref() != Some(session) {
            g.0 = Some(session.to_string());
        }
        g.1 = n;
    }

    /// The session and the highest event number handled in it.
    pub fn get(&self) -> (Option<String>, u64) {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// The highest event number handled in `session` (0 for another session).
    pub fn in_session(&self, session: Option<&str>) -> u64 {
        let g = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if g.0.as_deref() == session {
            g.1
        } else {
            0
        }
    }
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
