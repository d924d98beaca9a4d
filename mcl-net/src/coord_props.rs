//! The coordination properties of a vehicle net (`docs/coordination.md`,
//! "Vehicle nets"): which of its firings it tells which mission, which of
//! its transitions receive the firings of others, and which mutex tokens
//! between vehicles it borrows from a holder. `mcl-coord` writes them when
//! it splits a supervised net into vehicle nets; the runtime reads them.
//!
//! Each is a net property holding a JSON array; the fields of each record
//! are declared in the order of their keys, so the text is the one written
//! before these records existed (keys sorted).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::model::{Net, NetBuilder};

/// Net property: the firings to send, [`CoordSend`]s.
pub const SEND_PROPERTY: &str = "coord.send";
/// Net property: the receive transitions, [`CoordReceive`]s.
pub const RECEIVE_PROPERTY: &str = "coord.receive";
/// Net property: the mutex tokens borrowed from a holder,
/// [`BorrowedMutex`]es (absent when there are none).
pub const TOKENS_PROPERTY: &str = "coord.tokens";

/// After firing `transition`, tell mission `to`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoordSend {
    /// The mission told.
    pub to: String,
    /// Id of one of this net's transitions.
    pub transition: String,
}

/// `transition` is fired by a firing of mission `from` (its event is
/// `from/<their transition>`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoordReceive {
    /// The mission whose firing it receives.
    pub from: String,
    /// Id of the receive transition.
    pub transition: String,
}

/// A start that takes `weight` tokens of a borrowed mutex.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BorrowedStart {
    /// Id of the start transition.
    pub transition: String,
    /// Tokens it takes.
    pub weight: u32,
}

/// What a supervisor with a single holder enforces: the tokens it lends
/// are a mutex's, or those of a supervisor that deadlock avoidance added
/// (`coord.siphonN`, docs/coordination.md §3). A borrower asks for the
/// tokens of the siphon supervisors of a start before those of its
/// mutexes (the order of [`BorrowedMutex::rank`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TokenKind {
    /// A siphon supervisor of deadlock avoidance: it admits a vehicle into
    /// the part of its mission where the deadlock it prevents could start,
    /// so it is asked for first.
    Siphon,
    /// A mutex constraint's supervisor (absent from the property: the text
    /// written before siphon supervisors had a holder).
    #[default]
    Mutex,
}

impl TokenKind {
    fn is_mutex(&self) -> bool {
        *self == TokenKind::Mutex
    }
}

/// A supervisor between vehicles (a mutex, or a siphon supervisor of
/// deadlock avoidance: [`TokenKind`]) whose tokens another vehicle (the
/// holder) lends: this vehicle asks for them (`request`), receives them
/// (`grant`) and gives them back (its calls' `ends`, or `return` for a
/// token it cannot use).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BorrowedMutex {
    /// This vehicle's ends of the calls (their firings give tokens back).
    #[serde(default)]
    pub ends: Vec<String>,
    /// The receive transition of a grant.
    pub grant: String,
    /// The mission holding the mutex.
    pub holder: String,
    /// What the supervisor enforces (absent for a mutex).
    #[serde(default, skip_serializing_if = "TokenKind::is_mutex")]
    pub kind: TokenKind,
    /// The place of the tokens granted to this vehicle.
    pub place: String,
    /// Event (and transition) that sends a request to the holder.
    pub request: String,
    /// Event (and transition) that gives an unused token back.
    #[serde(rename = "return")]
    pub ret: String,
    /// This vehicle's starts that take tokens from it.
    pub starts: Vec<BorrowedStart>,
    /// Supervisor place id (`coord.mutexK`).
    pub supervisor: String,
}

impl BorrowedMutex {
    /// The order in which a borrower asks for the tokens of its
    /// supervisors (smallest first): siphon supervisors before mutexes,
    /// then by supervisor id. A start that needs several asks for the next
    /// only once it holds the previous ones, so no two vehicles each keep a
    /// token the other waits for, and a vehicle is admitted by a siphon
    /// supervisor before it keeps any mutex token.
    pub fn rank(&self) -> (TokenKind, &str) {
        (self.kind, &self.supervisor)
    }
}

/// The coordination properties of one vehicle net.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CoordProps {
    /// Property [`SEND_PROPERTY`].
    pub send: Vec<CoordSend>,
    /// Property [`RECEIVE_PROPERTY`].
    pub receive: Vec<CoordReceive>,
    /// Property [`TOKENS_PROPERTY`].
    pub tokens: Vec<BorrowedMutex>,
}

/// Why the coordination properties of a net cannot be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CoordPropsError {
    /// The property does not hold the JSON it should.
    Malformed {
        /// Property key.
        property: &'static str,
        /// What the JSON reader said.
        message: String,
    },
    /// The property names a node that the net does not have.
    UnknownNode {
        /// Property key.
        property: &'static str,
        /// `place` or `transition`.
        kind: &'static str,
        /// The id named.
        id: String,
    },
}

impl fmt::Display for CoordPropsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoordPropsError::Malformed { property, message } => write!(f, "bad `{property}` property: {message}"),
            CoordPropsError::UnknownNode { property, kind, id } => {
                write!(f, "`{property}` names {kind} `{id}`, which the net does not have")
            }
        }
    }
}

impl std::error::Error for CoordPropsError {}

fn to_json<T: Serialize>(v: &[T]) -> String {
    serde_json::to_string(v).expect("records of strings and numbers serialize")
}

impl CoordProps {
    /// Sets the properties on `b`: `coord.send` and `coord.receive` always,
    /// `coord.tokens` when some mutex is borrowed.
    pub fn write(&self, b: &mut NetBuilder) {
        if !self.tokens.is_empty() {
            b.property(TOKENS_PROPERTY, to_json(&self.tokens));
        }
        b.property(SEND_PROPERTY, to_json(&self.send));
        b.property(RECEIVE_PROPERTY, to_json(&self.receive));
    }

    /// The properties of `net` (an absent one is empty), checked against
    /// its nodes: every transition and place they name exists (the ends of
    /// a borrowed mutex are names only, not checked).
    pub fn read(net: &Net) -> Result<CoordProps, CoordPropsError> {
        let props = CoordProps {
            send: parse(net, SEND_PROPERTY)?,
            receive: parse(net, RECEIVE_PROPERTY)?,
            tokens: parse(net, TOKENS_PROPERTY)?,
        };
        let transition = |property: &'static str, id: &str| match net.transition_by_id(id) {
            Some(_) => Ok(()),
            None => Err(CoordPropsError::UnknownNode { property, kind: "transition", id: id.to_string() }),
        };
        for s in &props.send {
            transition(SEND_PROPERTY, &s.transition)?;
        }
        for r in &props.receive {
            transition(RECEIVE_PROPERTY, &r.transition)?;
        }
        for m in &props.tokens {
            if net.place_by_id(&m.place).is_none() {
                return Err(CoordPropsError::UnknownNode {
                    property: TOKENS_PROPERTY,
                    kind: "place",
                    id: m.place.clone(),
                });
            }
            for s in &m.starts {
                transition(TOKENS_PROPERTY, &s.transition)?;
            }
            for t in [&m.request, &m.ret, &m.grant] {
                transition(TOKENS_PROPERTY, t)?;
            }
        }
        Ok(props)
    }
}

fn parse<T: for<'de> Deserialize<'de>>(net: &Net, property: &'static str) -> Result<Vec<T>, CoordPropsError> {
    match net.properties().iter().find(|(k, _)| k == property) {
        None => Ok(Vec::new()),
        Some((_, v)) => {
            serde_json::from_str(v).map_err(|e| CoordPropsError::Malformed { property, message: e.to_string() })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Place, Transition};

    fn net(props: &CoordProps) -> Net {
        let mut b = NetBuilder::new("v");
        b.add_place(Place::new("coord.mutex1"));
        for id in ["call1.start", "call1.ok", "coord.request.mutex1", "coord.return.mutex1", "coord.recv.a.x"] {
            b.add_transition(Transition::new(id));
        }
        props.write(&mut b);
        b.build().unwrap()
    }

    fn sample() -> CoordProps {
        CoordProps {
            send: vec![CoordSend { to: "a".into(), transition: "call1.ok".into() }],
            receive: vec![CoordReceive { from: "a".into(), transition: "coord.recv.a.x".into() }],
            tokens: vec![BorrowedMutex {
                ends: vec!["call1.release".into()],
                grant: "coord.recv.a.x".into(),
                holder: "a".into(),
                kind: TokenKind::Mutex,
                place: "coord.mutex1".into(),
                request: "coord.request.mutex1".into(),
                ret: "coord.return.mutex1".into(),
                starts: vec![BorrowedStart { transition: "call1.start".into(), weight: 1 }],
                supervisor: "coord.mutex1".into(),
            }],
        }
    }

    #[test]
    fn written_text_has_sorted_keys_and_reads_back() {
        let p = sample();
        let n = net(&p);
        let text = |k: &str| n.properties().iter().find(|(key, _)| key == k).map(|(_, v)| v.to_string()).unwrap();
        assert_eq!(text(SEND_PROPERTY), r#"[{"to":"a","transition":"call1.ok"}]"#);
        assert_eq!(text(RECEIVE_PROPERTY), r#"[{"from":"a","transition":"coord.recv.a.x"}]"#);
        assert_eq!(
            text(TOKENS_PROPERTY),
            r#"[{"ends":["call1.release"],"grant":"coord.recv.a.x","holder":"a","place":"coord.mutex1","request":"coord.request.mutex1","return":"coord.return.mutex1","starts":[{"transition":"call1.start","weight":1}],"supervisor":"coord.mutex1"}]"#
        );
        assert_eq!(CoordProps::read(&n).unwrap(), p);
        assert_eq!(CoordProps::read(&net(&CoordProps::default())).unwrap(), CoordProps::default());
    }

    #[test]
    fn a_siphon_supervisor_is_marked_and_asked_for_first() {
        let mut p = sample();
        let mut siphon = p.tokens[0].clone();
        siphon.kind = TokenKind::Siphon;
        siphon.supervisor = "coord.siphon1".into();
        p.tokens.push(siphon);
        let n = net(&p);
        let text = n.properties().iter().find(|(k, _)| k == TOKENS_PROPERTY).map(|(_, v)| v.to_string()).unwrap();
        // Only the siphon supervisor's record says its kind.
        assert_eq!(text.matches(r#""kind":"siphon""#).count(), 1, "{text}");
        assert!(!text.contains(r#""kind":"mutex""#), "{text}");
        let read = CoordProps::read(&n).unwrap();
        assert_eq!(read, p);
        let mut order = read.tokens.clone();
        order.sort_by(|a, b| a.rank().cmp(&b.rank()));
        assert_eq!(order[0].supervisor, "coord.siphon1");
        assert_eq!(order[1].supervisor, "coord.mutex1");
    }

    #[test]
    fn malformed_or_dangling_properties_are_errors() {
        let mut p = sample();
        p.send[0].transition = "nope".into();
        let e = CoordProps::read(&net(&p)).unwrap_err();
        assert_eq!(e.to_string(), "`coord.send` names transition `nope`, which the net does not have");
        let mut p = sample();
        p.tokens[0].place = "gone".into();
        assert!(CoordProps::read(&net(&p)).unwrap_err().to_string().contains("place `gone`"));
        let mut b = NetBuilder::new("v");
        b.property(TOKENS_PROPERTY, "[");
        let e = CoordProps::read(&b.build().unwrap()).unwrap_err();
        assert!(e.to_string().starts_with("bad `coord.tokens` property: "), "{e}");
    }
}
