//! Operator control of a real-time run: the commands an operator sends
//! (`mcl run --operator-token`, through the monitor's web page or its HTTP
//! API, docs/monitor.md) and the channel that carries them into the
//! real-time driver ([`crate::driver::run_real_time`] reads
//! [`crate::driver::Session::operator`]).
//!
//! * `pause`: no input is taken and no action is sent, and mission time
//!   stands still (timers stop), until `resume`. What the vehicle sends
//!   meanwhile waits in the link, and is taken after `resume`.
//! * `abort`: fires the mission's abort through the abort hook that
//!   [`with_abort_hook`] adds to the net (an event transition [`ABORT_EVENT`]
//!   that marks `mission.abort` once), so the abort cascades as the
//!   compiled net defines; the run then ends with the outcome `aborted`.
//! * `answer`: delivers an event as if the vehicle had sent it (the seed's
//!   manual mode: the operator answers for a primitive).
//!
//! Every command is traced (a `operator` record) and journaled
//! ([`crate::journal::Entry::Operator`]); `abort` and `answer` are also
//! journaled as the event inputs they are, so that `--resume` replays them.

use mcl_net::{Net, Place, Transition, TransitionKind};
use serde::{Deserialize, Serialize};

/// The event of the abort hook ([`with_abort_hook`]).
pub const ABORT_EVENT: &str = "mclOperatorAbort";

/// The place that arms the abort hook (marked once).
pub const ABORT_ARMED: &str = "operator.abortable";

/// An operator command, as sent to the monitor (`{"command": "answer",
/// "event": "..."}`) and written in traces and journals.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum Command {
    /// Stop sending actions and stop mission time.
    Pause,
    /// Go on after a pause.
    Resume,
    /// Abort the mission (its `mission.abort`).
    Abort,
    /// Deliver `event` as if the vehicle had sent it.
    Answer {
        /// The event's name.
        event: String,
    },
}

impl Command {
    /// `pause`, `resume`, `abort` or `answer` (the `command` of its JSON).
    pub fn name(&self) -> &'static str {
        match self {
            Command::Pause => "pause",
            Command::Resume => "resume",
            Command::Abort => "abort",
            Command::Answer { .. } => "answer",
        }
    }
}

/// The sending end of the operator channel (held by the monitor).
pub type Sender = tokio::sync::mpsc::UnboundedSender<Command>;

/// The receiving end of the operator channel (held by the driver).
pub type Receiver = tokio::sync::mpsc::UnboundedReceiver<Command>;

/// A new operator channel.
pub fn channel() -> (Sender, Receiver) {
    tokio::sync::mpsc::unbounded_channel()
}

/// `net` with the operator's abort hook: an event transition
/// [`ABORT_EVENT`] that marks `mission.abort` once. Its journal
/// fingerprint differs from the net's: a run started with the hook is
/// resumed with it.
pub fn with_abort_hook(net: &Net) -> Result<Net, String> {
    let Some(abort) = net.place_by_id("mission.abort") else {
        return Err(format!("mission `{}` has no `mission.abort` place", net.name()));
    };
    let mut b = net.to_builder();
    let armed = b.add_place(Place::new(ABORT_ARMED).with_tokens(1));
    let t = b.add_transition(Transition::new("operator.abort").with_kind(TransitionKind::Event(ABORT_EVENT.into())));
    b.add_input(armed, t, 1).add_output(t, abort, 1);
    b.build().map_err(|e| format!("mission `{}`: {e}", net.name()))
}

/// Rewrites the `stuck` outcome of a mission the operator aborted (it is
/// left with nothing to fire: the operator's doing, not a stuck mission)
/// as `aborted`.
pub fn mark_aborted(r: &mut crate::trace::Record) {
    if let crate::trace::RecordKind::Outcome { result, reason, .. } = &mut r.kind {
        if result == "stuck" {
            *result = "aborted".into();
            *reason = Some("aborted by the operator".into());
        }
    }
}

/// Whether a journal records an operator's abort (a resumed run's outcome
/// is then `aborted`, [`mark_aborted`]).
pub fn journal_aborted(entries: &[crate::journal::Entry]) -> bool {
    entries.iter().any(|e| matches!(e, crate::journal::Entry::Operator { command: Command::Abort, .. }))
}

/// Whether `net` has the abort hook.
pub fn has_abort_hook(net: &Net) -> bool {
    net.place_by_id(ABORT_ARMED).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_read_and_write_as_tagged_objects() {
        let c: Command = serde_json::from_str(r#"{"command":"answer","event":"evXOk"}"#).unwrap();
        assert_eq!(c, Command::Answer { event: "evXOk".into() });
        assert_eq!(serde_json::to_string(&Command::Pause).unwrap(), r#"{"command":"pause"}"#);
        assert!(serde_json::from_str::<Command>(r#"{"command":"explode"}"#).is_err());
    }
}
