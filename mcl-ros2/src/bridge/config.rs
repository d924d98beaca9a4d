//! The bridge file's records, read with their positions
//! (`toml::Spanned`), and its errors with file and line.
//!
//! ```toml
//! node = "mcl_player"          # the ROS 2 node's name
//! namespace = "/girona500"     # optional, "/" by default
//! domain_id = 7                # optional, 0 by default
//! interfaces = ["interfaces"]  # optional: folders of .msg/.srv/.action, relative to this file
//! status_topic = "/mcl/status" # optional: the mission's state (std_msgs/String, JSON)
//! service_mapping = "cyclone"  # optional: "cyclone" (default), "enhanced" or "basic"
//!
//! [primitives.AlarmPrimitive]
//! enable = { publish = "/alarm/enable", type = "std_msgs/msg/Bool", fields = { data = true } }
//! disable = { call = "/alarm/set", type = "std_srvs/srv/SetBool", fields = { data = false } }
//! events = [{ topic = "/alarm", type = "std_msgs/msg/Bool", when = "data == true", event = "eventAlarm" }]
//! perceptions = [{ topic = "/altitude", type = "std_msgs/msg/Float64", field = "data", name = "altitude" }]
//!
//! [primitives.GotoPrimitive.action]
//! name = "/goto"
//! type = "nav/action/GoTo"
//! goal = { "target.x" = "$way-point[0]", "target.y" = "$way-point[1]", speed = 0.5 }
//! succeeded = "eventGotoOk"
//! aborted = "eventGotoFail"
//! timeout = 5                  # optional: seconds to accept a goal (10 by default)
//! ```

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The whole bridge file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bridge {
    pub node: Spanned<String>,
    #[serde(default)]
    pub namespace: Option<Spanned<String>>,
    #[serde(default)]
    pub domain_id: Option<Spanned<u16>>,
    #[serde(default)]
    pub interfaces: Vec<Spanned<String>>,
    #[serde(default)]
    pub status_topic: Option<Spanned<String>>,
    /// How requests and replies of services carry their request id on DDS:
    /// `"cyclone"` (rmw_cyclonedds, the default), `"enhanced"` (rmw_fastrtps,
    /// rmw_connextdds) or `"basic"` (RPC over DDS).
    #[serde(default)]
    pub service_mapping: Option<Spanned<String>>,
    #[serde(default)]
    pub primitives: BTreeMap<Spanned<String>, Primitive>,
}

/// How a service's request id travels on DDS (`service_mapping`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// rmw_cyclonedds: a 16-octet header before the request and the reply.
    Cyclone,
    /// rmw_fastrtps, rmw_connextdds: the related sample identity inline.
    Enhanced,
    /// RPC over DDS "basic": a request and a reply header.
    Basic,
}

impl Mapping {
    /// The mapping written `s` in the bridge file.
    pub fn parse(s: &str) -> Option<Mapping> {
        match s {
            "cyclone" => Some(Mapping::Cyclone),
            "enhanced" => Some(Mapping::Enhanced),
            "basic" => Some(Mapping::Basic),
            _ => None,
        }
    }
}

impl Bridge {
    /// The service mapping of the bridge (`cyclone` when not given).
    pub fn mapping(&self) -> Mapping {
        self.service_mapping.as_ref().and_then(|m| Mapping::parse(m.get_ref())).unwrap_or(Mapping::Cyclone)
    }
}

/// What stands for one primitive of the vehicle file.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Primitive {
    /// What the `enable` command does.
    #[serde(default)]
    pub enable: Option<Spanned<Command>>,
    /// What the `disable` command does.
    #[serde(default)]
    pub disable: Option<Spanned<Command>>,
    /// Events raised by messages on topics.
    #[serde(default)]
    pub events: Vec<Spanned<TopicEvent>>,
    /// Perceptions taken from fields of messages on topics.
    #[serde(default)]
    pub perceptions: Vec<Spanned<TopicPerception>>,
    /// The primitive is an action server: enable sends a goal, disable cancels it.
    #[serde(default)]
    pub action: Option<Spanned<ActionMap>>,
}

/// A command of the primitive as a message published or a service called.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Command {
    /// Publish on this topic...
    #[serde(default)]
    pub publish: Option<Spanned<String>>,
    /// ... or call this service.
    #[serde(default)]
    pub call: Option<Spanned<String>>,
    /// The message or service type (`std_msgs/msg/Bool`, `std_srvs/srv/SetBool`).
    #[serde(rename = "type")]
    pub ty: Spanned<String>,
    /// Field path → value (see [`super::expr::Source`]).
    #[serde(default)]
    pub fields: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    /// A service's response: events raised when it meets a condition.
    #[serde(default)]
    pub on_response: Vec<Spanned<Raise>>,
    /// A service's event when it gives no response: no answer within
    /// `timeout`, or a response that does not decode.
    #[serde(default)]
    pub on_failure: Option<Spanned<String>>,
    /// Seconds a service has to answer ([`DEFAULT_TIMEOUT_S`] when absent).
    #[serde(default)]
    pub timeout: Option<Spanned<f64>>,
}

/// Seconds a service has to answer, or an action server to accept or
/// cancel a goal, when the bridge file does not say.
pub const DEFAULT_TIMEOUT_S: f64 = 10.0;

/// `when` the condition holds, raise `event`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Raise {
    #[serde(default)]
    pub when: Option<Spanned<String>>,
    pub event: Spanned<String>,
}

/// An event raised when a message on a topic meets a condition.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicEvent {
    pub topic: Spanned<String>,
    #[serde(rename = "type")]
    pub ty: Spanned<String>,
    /// Absent: every message raises the event.
    #[serde(default)]
    pub when: Option<Spanned<String>>,
    pub event: Spanned<String>,
}

/// A perception named `name` with the value of `field` of each message.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicPerception {
    pub topic: Spanned<String>,
    #[serde(rename = "type")]
    pub ty: Spanned<String>,
    pub field: Spanned<String>,
    pub name: Spanned<String>,
}

/// A primitive that is an action server.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActionMap {
    /// The action's name (`/goto`).
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub ty: Spanned<String>,
    /// Goal field path → value, from the `enable` command's parameters.
    #[serde(default)]
    pub goal: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    /// Event of a succeeded goal.
    pub succeeded: Spanned<String>,
    /// Event of an aborted goal, or of one the server rejected.
    pub aborted: Spanned<String>,
    /// Event of a goal the server cancelled itself; absent: `aborted`'s.
    #[serde(default)]
    pub canceled: Option<Spanned<String>>,
    /// Perceptions from feedback fields.
    #[serde(default)]
    pub feedback: Vec<Spanned<FeedbackPerception>>,
    /// Seconds the server has to accept a goal or answer a cancel
    /// ([`DEFAULT_TIMEOUT_S`] when absent); the goal itself may run longer.
    #[serde(default)]
    pub timeout: Option<Spanned<f64>>,
}

/// A perception from a field of an action's feedback.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedbackPerception {
    pub field: Spanned<String>,
    pub name: Spanned<String>,
}

/// An error of a bridge file, at a line and column (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BridgeError {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl std::fmt::Display for BridgeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}: error: {}", self.file.display(), self.line, self.column, self.message)
    }
}

impl std::error::Error for BridgeError {}

/// Turns byte offsets of one text into positioned errors.
pub struct Locator<'a> {
    pub file: &'a Path,
    pub text: &'a str,
}

impl Locator<'_> {
    /// The error `message` at byte `offset`.
    pub fn at(&self, offset: usize, message: impl Into<String>) -> BridgeError {
        let before = self.text.get(..offset.min(self.text.len())).unwrap_or("");
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        BridgeError { file: self.file.to_path_buf(), line, column, message: message.into() }
    }

    /// The error `message` at the start of `s`.
    pub fn on<T>(&self, s: &Spanned<T>, message: impl Into<String>) -> BridgeError {
        self.at(s.span().start, message)
    }
}

/// Reads a bridge file's text (no checks beyond its shape).
pub fn parse(file: &Path, text: &str) -> Result<Bridge, BridgeError> {
    toml::from_str(text).map_err(|e| {
        let loc = Locator { file, text };
        let msg = e.message().trim().to_string();
        loc.at(e.span().map_or(0, |s| s.start), msg)
    })
}
