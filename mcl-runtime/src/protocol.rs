//! The AAC wire protocol, version 1 (`docs/aac-protocol.md`): JSON lines
//! over TCP between the player (client) and a vehicle's Architecture
//! Abstraction Component (server).
//!
//! This module holds what both ends share and has no I/O of its own beyond a
//! cancel-safe, size-limited line reader: the message types ([`Message`]),
//! parsing with the protocol's error codes ([`parse`]), encoding
//! ([`encode`]) and the defaults (port, line limit, heartbeat).

use std::time::Duration;

use serde::{Deserialize, Serialize};
use serde_json::Value;
use tokio::io::{AsyncBufRead, AsyncBufReadExt};

use crate::link::{Action, Inbound};

/// The protocol version this crate speaks.
pub const VERSION: u32 = 1;
/// Longest accepted line, in bytes before its terminating `\n` (a `\r`
/// before the `\n` counts and is ignored).
pub const MAX_LINE: usize = 64 * 1024;
/// Default address of an AAC (loopback only: listening on another interface
/// is an explicit choice).
pub const DEFAULT_ADDR: &str = "127.0.0.1:7010";
/// Default interval between two pings of the player.
pub const DEFAULT_PING_INTERVAL: Duration = Duration::from_secs(1);
/// Default silence after which a peer is considered gone.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(5);

/// `hello`: the first message of the player.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    /// Protocol version the player speaks.
    pub version: u32,
    /// Shared secret, when the AAC is configured with one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub token: Option<String>,
    /// Player software, e.g. `mcl/0.1` (informative).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub player: Option<String>,
    /// Mission name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// Identifier of this run of the mission: a new run starts a new session
    /// (sequence numbers from scratch); the same run resumes it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<String>,
    /// The AAC session id of the last `welcome` this player received for
    /// this run, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub session: Option<String>,
    /// Highest event number the player has received in that session: the
    /// AAC re-sends the events it still holds after it (all of them if
    /// `session` names another session). Absent: re-send nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_event: Option<u64>,
    /// The events that end a task of the mission, with their role, from
    /// the compiled net (never from their names): an AAC learns from them
    /// which answer of a primitive ends its run ok or fail, and which ok
    /// event is a monitor's condition (sent only when what it watches
    /// happens); an event not listed ends nothing. Absent or empty: the
    /// player does not say.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<EventEnd>,
}

/// What an event ends, as the compiled mission uses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventRole {
    /// It ends its task's run ok.
    Ok,
    /// It ends its task's run in failure.
    Fail,
    /// It ends its task's run ok, and that run is a monitor's condition:
    /// the event raises the monitor's `do` block, so the vehicle sends it
    /// only when what the primitive watches happens, never as a plain
    /// answer (for the calls listed in [`EventEnd::call_sites`]).
    Condition,
}

/// One event that ends a task (an entry of `hello.events`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EventEnd {
    /// The event's name.
    pub event: String,
    /// `ok`, `fail` or `condition`.
    pub role: EventRole,
    /// The task whose run it ends.
    pub task: String,
    /// The primitive that task drives (the one that raises the event).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primitive: Option<String>,
    /// For role `condition`: the calls of the task (the actions'
    /// `call_site`) that are a monitor's condition. A task also called
    /// elsewhere is listed with role `ok` too, for its other calls.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub call_sites: Vec<u32>,
}

impl EventEnd {
    /// Every event that ends a task of `net` (its `task_events` properties),
    /// with the primitive each task's actions drive; the ok events of a
    /// task called as a monitor's condition ([`mcl_net::Net::task_calls`])
    /// have role `condition` for those calls (and `ok` as well when the task
    /// has other calls). Sorted by task, then ok, fail, condition.
    pub fn of_net(net: &mcl_net::Net) -> Vec<EventEnd> {
        let primitive = |task: &str| {
            net.transitions()
                .iter()
                .filter(|t| t.provenance.task.as_deref() == Some(task))
                .find_map(|t| t.actions.first().map(|a| a.primitive.clone()))
        };
        let calls = net.task_calls();
        let mut tasks: Vec<(&str, mcl_net::TaskEvents)> = net.task_events().collect();
        tasks.sort_by(|a, b| a.0.cmp(b.0));
        let mut out = Vec::new();
        for (task, ev) in tasks {
            let prim = primitive(task);
            let (condition, other) = match calls.get(task) {
                Some(c) => (c.condition.clone(), !c.other.is_empty()),
                None => (Vec::new(), true),
            };
            let ok = ev.ok.iter().filter(|_| other).map(|e| (e, EventRole::Ok, Vec::new()));
            let fail = ev.fail.iter().map(|e| (e, EventRole::Fail, Vec::new()));
            let cond =
                ev.ok.iter().filter(|_| !condition.is_empty()).map(|e| (e, EventRole::Condition, condition.clone()));
            for (event, role, call_sites) in ok.chain(fail).chain(cond) {
                out.push(EventEnd {
                    event: event.clone(),
                    role,
                    task: task.to_string(),
                    primitive: prim.clone(),
                    call_sites,
                });
            }
        }
        out
    }
}

/// `welcome`: the AAC accepted the `hello`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Welcome {
    /// Protocol version of the session.
    pub version: u32,
    /// Highest action `seq` the AAC has executed in this session (0: none).
    pub last_seq: u64,
    /// Highest event number the AAC has sent in this session (0: none).
    #[serde(default)]
    pub last_event: u64,
    /// Session id: the same for every connection of one run, as long as the
    /// AAC remembers it; a new id means event numbers start again at 1.
    #[serde(default)]
    pub session: String,
    /// AAC software (informative).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aac: Option<String>,
}

/// `action`: one action of the player (the fields of [`Action`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ActionMsg {
    pub seq: u64,
    pub action: String,
    pub primitive: String,
    pub command: String,
    #[serde(default)]
    pub params: crate::params::Params,
    #[serde(default)]
    pub task: Option<String>,
    #[serde(default)]
    pub call_site: Option<u32>,
}

impl From<Action> for ActionMsg {
    fn from(a: Action) -> Self {
        ActionMsg {
            seq: a.seq,
            action: a.action,
            primitive: a.primitive,
            command: a.command,
            params: a.params,
            task: a.task,
            call_site: a.call_site,
        }
    }
}

impl From<ActionMsg> for Action {
    fn from(a: ActionMsg) -> Self {
        Action {
            seq: a.seq,
            action: a.action,
            primitive: a.primitive,
            command: a.command,
            params: a.params,
            task: a.task,
            call_site: a.call_site,
        }
    }
}

/// `ping`: heartbeat of the player, answered by `pong`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ping {
    /// Highest event number received so far (the AAC may forget older ones).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_event: Option<u64>,
}

/// `event`: a primitive raised an event.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EventMsg {
    pub event: String,
    /// Event number in the session (1, 2, 3…; shared with perceptions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<u64>,
    /// The `seq` of the action that started the primitive run that raised
    /// the event (optional: the player then cannot tell a late answer of
    /// a disabled run from an answer of the current one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub activation: Option<u64>,
}

/// `perception`: a named value for the mission layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PerceptionMsg {
    pub name: String,
    pub value: Value,
    /// Event number in the session (shared with events).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<u64>,
}

/// `error`: something went wrong; `seq` names the action concerned, if any.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorMsg {
    pub code: String,
    pub message: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seq: Option<u64>,
}

/// Every message of the protocol, in both directions (the `type` field
/// selects the variant; unknown fields are ignored).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Message {
    Hello(Hello),
    Welcome(Welcome),
    Action(ActionMsg),
    Ping(Ping),
    Ack { seq: u64 },
    Event(EventMsg),
    Perception(PerceptionMsg),
    Pong {},
    Error(ErrorMsg),
}

/// The `type` names of [`Message`].
pub const MESSAGE_TYPES: [&str; 9] =
    ["hello", "welcome", "action", "ping", "ack", "event", "perception", "pong", "error"];

impl Message {
    /// The `type` field of this message.
    pub fn type_name(&self) -> &'static str {
        match self {
            Message::Hello(_) => "hello",
            Message::Welcome(_) => "welcome",
            Message::Action(_) => "action",
            Message::Ping(_) => "ping",
            Message::Ack { .. } => "ack",
            Message::Event(_) => "event",
            Message::Perception(_) => "perception",
            Message::Pong {} => "pong",
            Message::Error(_) => "error",
        }
    }

    /// An `error` message.
    pub fn error(code: ErrorCode, message: impl Into<String>, seq: Option<u64>) -> Message {
        Message::Error(ErrorMsg { code: code.as_str().to_string(), message: message.into(), seq })
    }

    /// The inbound item this message carries to the player, if any.
    pub fn to_inbound(&self) -> Option<Inbound> {
        match self {
            Message::Ack { seq } => Some(Inbound::Ack { seq: *seq }),
            Message::Event(e) => Some(Inbound::Event { event: e.event.clone(), activation: e.activation, n: e.n }),
            Message::Perception(p) => {
                Some(Inbound::Perception { name: p.name.clone(), value: p.value.clone(), n: p.n })
            }
            _ => None,
        }
    }
}

/// Error codes of the `error` message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorCode {
    /// The `hello` lacks the configured token or has a wrong one (fatal).
    Unauthorized,
    /// Unsupported protocol version (fatal).
    Version,
    /// Not JSON, not an object, or missing / mistyped fields.
    Malformed,
    /// Line longer than [`MAX_LINE`]; it was discarded.
    TooLong,
    /// A `type` this end does not know.
    UnknownType,
    /// A known message at the wrong moment (e.g. `action` before `hello`).
    Unexpected,
    /// Another connection took over this session (fatal for this connection).
    Replaced,
    /// The AAC cannot execute actions now (its vehicle side is gone).
    Unavailable,
    /// No message for too long (fatal for this connection).
    Timeout,
}

impl ErrorCode {
    /// The wire spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorCode::Unauthorized => "unauthorized",
            ErrorCode::Version => "version",
            ErrorCode::Malformed => "malformed",
            ErrorCode::TooLong => "too_long",
            ErrorCode::UnknownType => "unknown_type",
            ErrorCode::Unexpected => "unexpected",
            ErrorCode::Replaced => "replaced",
            ErrorCode::Unavailable => "unavailable",
            ErrorCode::Timeout => "timeout",
        }
    }

    /// Codes after which the sender closes the connection.
    pub fn is_fatal(self) -> bool {
        matches!(self, ErrorCode::Unauthorized | ErrorCode::Version | ErrorCode::Replaced | ErrorCode::Timeout)
    }

    /// All codes.
    pub const ALL: [ErrorCode; 9] = [
        ErrorCode::Unauthorized,
        ErrorCode::Version,
        ErrorCode::Malformed,
        ErrorCode::TooLong,
        ErrorCode::UnknownType,
        ErrorCode::Unexpected,
        ErrorCode::Replaced,
        ErrorCode::Unavailable,
        ErrorCode::Timeout,
    ];

    /// The code with this wire spelling.
    pub fn parse(s: &str) -> Option<ErrorCode> {
        ErrorCode::ALL.into_iter().find(|c| c.as_str() == s)
    }
}

/// Why a line is not a valid message: what to put in the `error` reply.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProtocolError {
    pub code: ErrorCode,
    pub message: String,
    /// The `seq` of the offending action, when it could be read.
    pub seq: Option<u64>,
}

impl ProtocolError {
    /// The `error` message answering this error.
    pub fn to_message(&self) -> Message {
        Message::error(self.code, self.message.clone(), self.seq)
    }
}

impl std::fmt::Display for ProtocolError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.code.as_str(), self.message)
    }
}

impl std::error::Error for ProtocolError {}

/// Parses one line (without its `\n`).
pub fn parse(line: &[u8]) -> Result<Message, ProtocolError> {
    let malformed = |message: String, seq| ProtocolError { code: ErrorCode::Malformed, message, seq };
    let value: Value = serde_json::from_slice(line).map_err(|e| malformed(format!("invalid JSON: {e}"), None))?;
    let Value::Object(obj) = &value else {
        return Err(malformed("a message must be a JSON object".into(), None));
    };
    let seq = obj.get("seq").and_then(Value::as_u64);
    let ty = match obj.get("type") {
        Some(Value::String(t)) => t.as_str(),
        Some(_) => return Err(malformed("field `type` must be a string".into(), seq)),
        None => return Err(malformed("missing field `type`".into(), seq)),
    };
    if !MESSAGE_TYPES.contains(&ty) {
        return Err(ProtocolError {
            code: ErrorCode::UnknownType,
            message: format!("unknown message type `{}`", truncate(ty, 64)),
            seq,
        });
    }
    // From the text, not from `value`, whose object keys are sorted: an
    // action's `params` keep the order they were sent in.
    serde_json::from_slice(line).map_err(|e| malformed(format!("bad `{ty}` message: {e}"), seq))
}

/// Encodes a message as one line, `\n` included.
pub fn encode(msg: &Message) -> String {
    // Serializing these types cannot fail (string keys, no non-finite floats
    // reach serde_json::Value).
    let mut s = serde_json::to_string(msg).unwrap_or_else(|e| {
        format!(r#"{{"type":"error","code":"malformed","message":"cannot encode message: {}"}}"#, e)
    });
    s.push('\n');
    s
}

/// Compares two tokens in time independent of where they differ.
pub fn token_matches(expected: &str, given: Option<&str>) -> bool {
    let Some(given) = given else { return false };
    let (a, b) = (expected.as_bytes(), given.as_bytes());
    let mut diff = (a.len() != b.len()) as u8;
    for i in 0..a.len().max(b.len()) {
        diff |= a.get(i).copied().unwrap_or(0) ^ b.get(i).copied().unwrap_or(0);
    }
    diff == 0
}

/// Shortens `s` to at most `max` characters for logs and error messages.
pub fn truncate(s: &str, max: usize) -> String {
    if s.chars().count() <= max {
        s.to_string()
    } else {
        let mut t: String = s.chars().take(max).collect();
        t.push('…');
        t
    }
}

/// What [`LineReader::next_line`] read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Line {
    /// A complete line, without `\n` (nor a trailing `\r`).
    Text(Vec<u8>),
    /// A line longer than the limit was read and discarded; its length.
    TooLong(usize),
    /// The peer closed its side.
    Eof,
}

/// Reads `\n`-terminated lines of at most `max` bytes from a buffered reader.
///
/// [`LineReader::next_line`] is cancel-safe (it may be used in
/// `tokio::select!`): a partly read line is kept in the reader. A longer line
/// is discarded as it arrives (memory stays bounded) and reported once, when
/// its `\n` arrives.
pub struct LineReader<R> {
    inner: R,
    buf: Vec<u8>,
    max: usize,
    discarding: Option<usize>,
}

impl<R: AsyncBufRead + Unpin> LineReader<R> {
    /// A reader of lines of at most `max` bytes.
    pub fn new(inner: R, max: usize) -> Self {
        LineReader { inner, buf: Vec::new(), max, discarding: None }
    }

    /// The next line.
    pub async fn next_line(&mut self) -> std::io::Result<Line> {
        loop {
            let avail = self.inner.fill_buf().await?;
            if avail.is_empty() {
                if let Some(n) = self.discarding.take() {
                    return Ok(Line::TooLong(n));
                }
                if !self.buf.is_empty() {
                    // The last line had no `\n`: deliver it anyway.
                    return Ok(Line::Text(self.take()));
                }
                return Ok(Line::Eof);
            }
            match avail.iter().position(|&b| b == b'\n') {
                Some(i) => {
                    let line_len = self.buf.len() + i;
                    if let Some(n) = self.discarding.take() {
                        self.inner.consume(i + 1);
                        return Ok(Line::TooLong(n + i));
                    }
                    if line_len > self.max {
                        self.buf.clear();
                        self.inner.consume(i + 1);
                        return Ok(Line::TooLong(line_len));
                    }
                    self.buf.extend_from_slice(&avail[..i]);
                    self.inner.consume(i + 1);
                    return Ok(Line::Text(self.take()));
                }
                None => {
                    let n = avail.len();
                    if let Some(d) = self.discarding.as_mut() {
                        *d += n;
                    } else if self.buf.len() + n > self.max {
                        self.discarding = Some(self.buf.len() + n);
                        self.buf.clear();
                        self.buf.shrink_to(4096);
                    } else {
                        self.buf.extend_from_slice(avail);
                    }
                    self.inner.consume(n);
                }
            }
        }
    }

    fn take(&mut self) -> Vec<u8> {
        let mut line = std::mem::take(&mut self.buf);
        if line.last() == Some(&b'\r') {
            line.pop();
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_every_message() {
        let msgs = vec![
            Message::Hello(Hello {
                version: 1,
                token: Some("s3cret".into()),
                player: Some("mcl/0.1".into()),
                mission: Some("survey".into()),
                run: Some("r1".into()),
                session: None,
                last_event: None,
                events: vec![EventEnd {
                    event: "eventGotoOk".into(),
                    role: EventRole::Ok,
                    task: "Goto".into(),
                    primitive: Some("GotoPrimitive".into()),
                    call_sites: vec![],
                }],
            }),
            Message::Welcome(Welcome { version: 1, last_seq: 4, last_event: 2, session: "s1".into(), aac: None }),
            Message::Action(ActionMsg {
                seq: 1,
                action: "enableGoto".into(),
                primitive: "GotoPrimitive".into(),
                command: "enable".into(),
                params: serde_json::from_str(r#"{"way-point":[24,12],"speed":1}"#).unwrap(),
                task: Some("Goto".into()),
                call_site: Some(3),
            }),
            Message::Ping(Ping { last_event: Some(3) }),
            Message::Ack { seq: 1 },
            Message::Event(EventMsg { event: "eventGotoOk".into(), n: Some(1), activation: Some(3) }),
            Message::Perception(PerceptionMsg { name: "depth".into(), value: 14.5.into(), n: Some(2) }),
            Message::Pong {},
            Message::error(ErrorCode::Malformed, "bad", Some(3)),
        ];
        for m in msgs {
            let line = encode(&m);
            assert!(line.ends_with('\n') && !line[..line.len() - 1].contains('\n'));
            assert_eq!(parse(line.trim_end().as_bytes()).unwrap(), m, "{line}");
            assert!(line.contains(&format!(r#""type":"{}""#, m.type_name())));
        }
    }

    #[test]
    fn parse_spec_examples() {
        let m = parse(
            br#"{"type":"action","seq":7,"action":"disableGoto","primitive":"GotoPrimitive","command":"disable"}"#,
        )
        .unwrap();
        let Message::Action(a) = m else { panic!() };
        assert_eq!((a.seq, a.params.len(), a.task), (7, 0, None));
        assert_eq!(parse(br#"{"type":"pong"}"#).unwrap(), Message::Pong {});
        assert_eq!(parse(br#"{"type":"ping"}"#).unwrap(), Message::Ping(Ping { last_event: None }));
        assert_eq!(
            parse(br#"{"type":"event","event":"e","extra":1}"#).unwrap(),
            Message::Event(EventMsg { event: "e".into(), n: None, activation: None })
        );
        // The activation is optional, and must be a number when present.
        assert_eq!(
            parse(br#"{"type":"event","event":"e","n":4,"activation":7}"#).unwrap(),
            Message::Event(EventMsg { event: "e".into(), n: Some(4), activation: Some(7) })
        );
        assert_eq!(
            parse(br#"{"type":"event","event":"e","activation":null}"#).unwrap(),
            Message::Event(EventMsg { event: "e".into(), n: None, activation: None })
        );
        assert_eq!(parse(br#"{"type":"event","event":"e","activation":"x"}"#).unwrap_err().code, ErrorCode::Malformed);
    }

    #[test]
    fn parse_errors_have_codes() {
        let e = parse(b"{not json").unwrap_err();
        assert_eq!(e.code, ErrorCode::Malformed);
        assert_eq!(parse(b"[1,2]").unwrap_err().code, ErrorCode::Malformed);
        assert_eq!(parse(br#"{"seq":1}"#).unwrap_err().code, ErrorCode::Malformed);
        let e = parse(br#"{"type":"teleport","seq":9}"#).unwrap_err();
        assert_eq!((e.code, e.seq), (ErrorCode::UnknownType, Some(9)));
        let e = parse(br#"{"type":"action","seq":5,"action":"a"}"#).unwrap_err();
        assert_eq!((e.code, e.seq), (ErrorCode::Malformed, Some(5)));
        assert!(e.message.contains("primitive"), "{}", e.message);
        assert_eq!(parse(&[0xff, 0xfe]).unwrap_err().code, ErrorCode::Malformed);
    }

    #[test]
    fn tokens() {
        assert!(token_matches("abc", Some("abc")));
        assert!(!token_matches("abc", Some("abd")));
        assert!(!token_matches("abc", Some("abcd")));
        assert!(!token_matches("abc", None));
    }

    #[tokio::test]
    async fn line_reader_limits_and_recovers() {
        let mut input = Vec::new();
        input.extend_from_slice(b"short\r\n");
        input.extend(std::iter::repeat_n(b'x', 100));
        input.extend_from_slice(b"\n");
        input.extend(std::iter::repeat_n(b'y', 10));
        input.extend_from_slice(b"\nok\nlast");
        // A tiny buffer so that lines span many reads.
        let reader = tokio::io::BufReader::with_capacity(7, &input[..]);
        let mut r = LineReader::new(reader, 10);
        assert_eq!(r.next_line().await.unwrap(), Line::Text(b"short".to_vec()));
        assert_eq!(r.next_line().await.unwrap(), Line::TooLong(100));
        assert_eq!(r.next_line().await.unwrap(), Line::Text(b"yyyyyyyyyy".to_vec()));
        assert_eq!(r.next_line().await.unwrap(), Line::Text(b"ok".to_vec()));
        assert_eq!(r.next_line().await.unwrap(), Line::Text(b"last".to_vec()));
        assert_eq!(r.next_line().await.unwrap(), Line::Eof);
    }
}
