//! Coordination messages between vehicles (seed 6.3; `docs/coordination.md`).
//!
//! When several vehicles run coordinated missions, each vehicle's net holds
//! its part of the supervisors; the decentralization of `mcl-coord` says
//! which of its transition firings it must tell which other vehicle
//! (net property `coord.send`). A [`CoordMessage`] is one such firing: "mission
//! `from` fired transition `transition`". The receiver turns it into the event
//! [`CoordMessage::event`] (`from/transition`), which fires its receive
//! transition `coord.recv.<from>.<transition>`.
//!
//! A [`CoordTransport`] is one vehicle's end of whatever carries the
//! messages. The contract is small so that an existing messaging system can
//! implement it (a Zenoh publisher on `mcl/coord/<to>` and a subscriber on
//! `mcl/coord/<mission>`, or a ROS 2 topic per vehicle, with reliable QoS):
//!
//! * [`CoordTransport::send`] never blocks and queues the message for `to`;
//! * delivery is reliable and in order between two missions;
//! * [`CoordTransport::recv`] waits for the next message for this mission.
//!
//! Two implementations: [`in_process`] (tokio channels) and [`TcpEnd`]
//! (authenticated JSON lines over TCP, acknowledged end to end:
//! [`crate::coord_link`]).

use std::collections::HashMap;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;

use mcl_net::coord_props::CoordProps;
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

pub use crate::coord_link::{tcp_mesh, Auth, TcpEnd};

/// Net property of a vehicle net: the firings it must send
/// ([`mcl_net::coord_props::CoordSend`]).
pub const SEND_PROPERTY: &str = mcl_net::coord_props::SEND_PROPERTY;
/// Net property of a vehicle net: its receive transitions
/// ([`mcl_net::coord_props::CoordReceive`]).
pub const RECEIVE_PROPERTY: &str = mcl_net::coord_props::RECEIVE_PROPERTY;

/// "Mission `from` fired `transition`", for mission `to`. On the wire (TCP):
/// `{"from":"asc","to":"auv","transition":"call3.ok","seq":1,"t":15.0}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoordMessage {
    /// The sending mission.
    pub from: String,
    /// The receiving mission.
    pub to: String,
    /// Id of the transition that fired in `from`'s net.
    pub transition: String,
    /// Numbered from 1 by the sender, per receiver (the link `from` →
    /// `to`); receivers take each number once, in order.
    pub seq: u64,
    /// Mission time of the firing at the sender (seconds).
    pub t: f64,
}

impl CoordMessage {
    /// The event the receiver's net waits for: `from/transition` (the same
    /// name as `mcl_coord::decentral::message_event`).
    pub fn event(&self) -> String {
        format!("{}/{}", self.from, self.transition)
    }
}

/// What [`CoordTransport::recv`] gives.
#[derive(Clone, Debug, PartialEq)]
pub enum Incoming {
    /// A message for this mission, in order, once.
    Message(CoordMessage),
    /// A line or a connection refused (forged, replayed, malformed, a
    /// failed handshake), with why: never delivered, to be logged.
    Rejected(String),
}

impl Incoming {
    /// The message, if it is one.
    pub fn message(self) -> Option<CoordMessage> {
        match self {
            Incoming::Message(m) => Some(m),
            Incoming::Rejected(_) => None,
        }
    }
}

/// A future returned by [`CoordTransport::recv`].
pub type RecvFuture<'a> = Pin<Box<dyn Future<Output = Option<Incoming>> + Send + 'a>>;

/// One vehicle's end of a coordination transport. See the [module
/// documentation](self).
pub trait CoordTransport: Send {
    /// The mission this end receives for.
    fn mission(&self) -> &str;
    /// Queues `msg` for `msg.to`. Never blocks. Errors when `msg.to` is
    /// unknown or the transport is closed.
    fn send(&mut self, msg: CoordMessage) -> Result<(), String>;
    /// The next message for this mission (or refusal), waiting for it;
    /// `None` once the transport is closed. Cancel-safe (usable in
    /// `tokio::select!`).
    fn recv(&mut self) -> RecvFuture<'_>;
    /// The receiver has made `msg` durable (journaled): the transport may
    /// acknowledge it to its sender, which stops re-sending it.
    fn delivered(&mut self, _msg: &CoordMessage) {}
    /// Messages sent but not yet acknowledged by their receivers.
    fn unacknowledged(&self) -> usize {
        0
    }
}

// ---------------------------------------------------------------------------
// In-process
// ---------------------------------------------------------------------------

/// An in-process end (see [`in_process`]).
pub struct InProcessEnd {
    mission: String,
    peers: Arc<HashMap<String, mpsc::UnboundedSender<CoordMessage>>>,
    inbox: mpsc::UnboundedReceiver<CoordMessage>,
}

/// One connected end per mission, over unbounded tokio channels. Works
/// without a runtime for `send`.
pub fn in_process(missions: &[String]) -> Vec<InProcessEnd> {
    let mut senders = HashMap::new();
    let mut receivers = Vec::new();
    for m in missions {
        let (tx, rx) = mpsc::unbounded_channel();
        senders.insert(m.clone(), tx);
        receivers.push((m.clone(), rx));
    }
    let peers = Arc::new(senders);
    receivers.into_iter().map(|(mission, inbox)| InProcessEnd { mission, peers: peers.clone(), inbox }).collect()
}

impl CoordTransport for InProcessEnd {
    fn mission(&self) -> &str {
        &self.mission
    }

    fn send(&mut self, msg: CoordMessage) -> Result<(), String> {
        let to = self.peers.get(&msg.to).ok_or_else(|| format!("no mission `{}` on this transport", msg.to))?;
        to.send(msg).map_err(|m| format!("mission `{}` no longer receives", m.0.to))
    }

    fn recv(&mut self) -> RecvFuture<'_> {
        Box::pin(async move { self.inbox.recv().await.map(Incoming::Message) })
    }
}

// ---------------------------------------------------------------------------
// In-process with a delay (slow links: acoustic modems)
// ---------------------------------------------------------------------------

/// An in-process end whose messages take `delay` (wall-clock time) to
/// arrive (see [`delayed_in_process`]).
pub struct DelayedEnd {
    mission: String,
    delay: Duration,
    peers: Arc<HashMap<String, mpsc::UnboundedSender<(tokio::time::Instant, CoordMessage)>>>,
    inbox: mpsc::UnboundedReceiver<CoordMessage>,
}

/// One connected end per mission, like [`in_process`], but every message
/// is delivered `delay` after it was sent (in order): a slow link such as
/// an acoustic modem, to test what the coordination keeps when messages
/// cross. Must be called inside a tokio runtime (one forwarding task per
/// mission).
pub fn delayed_in_process(missions: &[String], delay: Duration) -> Vec<DelayedEnd> {
    let mut senders = HashMap::new();
    let mut receivers = Vec::new();
    for m in missions {
        let (tx, mut rx) = mpsc::unbounded_channel::<(tokio::time::Instant, CoordMessage)>();
        let (out_tx, out_rx) = mpsc::unbounded_channel();
        tokio::spawn(async move {
            while let Some((due, m)) = rx.recv().await {
                tokio::time::sleep_until(due).await;
                if out_tx.send(m).is_err() {
                    return;
                }
            }
        });
        senders.insert(m.clone(), tx);
        receivers.push((m.clone(), out_rx));
    }
    let peers = Arc::new(senders);
    receivers.into_iter().map(|(mission, inbox)| DelayedEnd { mission, delay, peers: peers.clone(), inbox }).collect()
}

impl CoordTransport for DelayedEnd {
    fn mission(&self) -> &str {
        &self.mission
    }

    fn send(&mut self, msg: CoordMessage) -> Result<(), String> {
        let to = self.peers.get(&msg.to).ok_or_else(|| format!("no mission `{}` on this transport", msg.to))?;
        let due = tokio::time::Instant::now() + self.delay;
        to.send((due, msg)).map_err(|m| format!("mission `{}` no longer receives", m.0 .1.to))
    }

    fn recv(&mut self) -> RecvFuture<'_> {
        Box::pin(async move { self.inbox.recv().await.map(Incoming::Message) })
    }
}

/// Net property of a vehicle net: the mutexes between vehicles whose tokens
/// it must ask a holder for ([`mcl_net::coord_props::BorrowedMutex`]).
pub const TOKENS_PROPERTY: &str = mcl_net::coord_props::TOKENS_PROPERTY;

/// A supervisor between vehicles (a mutex, or a siphon supervisor of
/// deadlock avoidance) held by another vehicle (the *holder*): this
/// vehicle asks for its tokens (request), receives them (grant) and gives
/// them back (its calls' ends, or `return` for a token it cannot use).
#[derive(Clone, Debug, PartialEq)]
pub struct TokenMutex {
    /// Supervisor place id (`coord.mutexK`).
    pub supervisor: String,
    /// The mission holding the mutex.
    pub holder: String,
    /// The place of the tokens granted to this vehicle.
    pub place: mcl_net::PlaceId,
    /// This vehicle's starts that take tokens from it, with their weights.
    pub starts: Vec<(mcl_net::TransitionId, u32)>,
    /// Event (and transition) that sends a request to the holder.
    pub request: String,
    /// Event (and transition) that gives an unused token back.
    pub ret: String,
    /// The receive transition of a grant.
    pub grant: mcl_net::TransitionId,
    /// This vehicle's ends of the calls (their firings give tokens back).
    pub ends: Vec<String>,
}

/// The supervisors a vehicle net borrows tokens of (mutexes and siphon
/// supervisors between vehicles), in the order it asks for them
/// ([`mcl_net::coord_props::BorrowedMutex::rank`]: siphon supervisors
/// first, then by supervisor id), from its `coord.tokens` property (empty
/// without it). Errors on a malformed property.
pub fn token_table(net: &mcl_net::Net) -> Result<Vec<TokenMutex>, String> {
    let props = read_props(net)?;
    // `CoordProps::read` checked that every node named exists.
    let missing =
        |id: &str| format!("net `{}`: `{TOKENS_PROPERTY}` names `{id}`, which the net does not have", net.name());
    let transition = |id: &str| net.transition_by_id(id).ok_or_else(|| missing(id));
    let mut out = Vec::new();
    let mut tokens = props.tokens;
    tokens.sort_by(|a, b| a.rank().cmp(&b.rank()));
    for e in tokens {
        let place = net.place_by_id(&e.place).ok_or_else(|| missing(&e.place))?;
        let starts =
            e.starts.iter().map(|s| Ok((transition(&s.transition)?, s.weight))).collect::<Result<_, String>>()?;
        let grant = transition(&e.grant)?;
        out.push(TokenMutex {
            supervisor: e.supervisor,
            holder: e.holder,
            place,
            starts,
            request: e.request,
            ret: e.ret,
            grant,
            ends: e.ends,
        });
    }
    Ok(out)
}

/// The coordination properties of `net`, checked against its nodes.
fn read_props(net: &mcl_net::Net) -> Result<CoordProps, String> {
    CoordProps::read(net).map_err(|e| format!("net `{}`: {e}", net.name()))
}

/// Messages of the single-holder mutex protocol, by kind (counted by their
/// senders).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MutexMessages {
    /// Requests for a token, sent to a holder.
    pub requests: u64,
    /// Tokens granted by a holder.
    pub grants: u64,
    /// Tokens given back to a holder (a call's end, or unused).
    pub returns: u64,
}

impl MutexMessages {
    /// Adds `o`'s counts.
    pub fn add(&mut self, o: MutexMessages) {
        self.requests += o.requests;
        self.grants += o.grants;
        self.returns += o.returns;
    }

    /// Their sum.
    pub fn total(&self) -> u64 {
        self.requests + self.grants + self.returns
    }
}

/// The send table of a vehicle net: transition id → the missions to tell,
/// from its `coord.send` property (empty without it). Errors on a malformed
/// property.
pub fn send_table(net: &mcl_net::Net) -> Result<HashMap<String, Vec<String>>, String> {
    let mut out: HashMap<String, Vec<String>> = HashMap::new();
    for s in read_props(net)?.send {
        out.entry(s.transition).or_default().push(s.to);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(from: &str, to: &str, transition: &str, seq: u64) -> CoordMessage {
        CoordMessage { from: from.into(), to: to.into(), transition: transition.into(), seq, t: seq as f64 }
    }

    #[tokio::test]
    async fn in_process_delivers_in_order_to_the_named_mission() {
        let mut ends = in_process(&["a".into(), "b".into()]);
        let mut b = ends.pop().unwrap();
        let mut a = ends.pop().unwrap();
        assert_eq!((a.mission(), b.mission()), ("a", "b"));
        for i in 1..=3 {
            a.send(msg("a", "b", &format!("t{i}"), i)).unwrap();
        }
        b.send(msg("b", "a", "x", 1)).unwrap();
        assert!(a.send(msg("a", "zz", "t", 4)).unwrap_err().contains("zz"));
        for i in 1..=3 {
            assert_eq!(b.recv().await.and_then(Incoming::message).unwrap().transition, format!("t{i}"));
        }
        assert_eq!(a.recv().await.and_then(Incoming::message).unwrap().event(), "b/x");
    }

    #[tokio::test]
    async fn delayed_in_process_delivers_in_order() {
        let mut ends = delayed_in_process(&["a".into(), "b".into()], Duration::from_millis(5));
        let mut b = ends.pop().unwrap();
        let mut a = ends.pop().unwrap();
        for i in 1..=3 {
            a.send(msg("a", "b", &format!("t{i}"), i)).unwrap();
        }
        assert!(a.send(msg("a", "zz", "t", 4)).unwrap_err().contains("zz"));
        for i in 1..=3 {
            assert_eq!(b.recv().await.and_then(Incoming::message).unwrap().transition, format!("t{i}"));
        }
        assert_eq!(b.mission(), "b");
    }

    #[test]
    fn token_table_reads_the_property() {
        let net = |tokens: &str| {
            let mut b = mcl_net::NetBuilder::new("v");
            let p = b.add_place(mcl_net::Place::new("coord.mutex1"));
            let t = b.add_transition(mcl_net::Transition::new("call1.start"));
            b.add_input(p, t, 1);
            for id in ["coord.request.mutex1", "coord.return.mutex1", "coord.recv.a.coord.lend.mutex1.v"] {
                b.add_transition(mcl_net::Transition::new(id));
            }
            b.property(TOKENS_PROPERTY, tokens);
            b.build().unwrap()
        };
        let entry = |start: &str| {
            format!(
                r#"[{{"supervisor":"coord.mutex1","holder":"a","place":"coord.mutex1","starts":[{{"transition":"{start}","weight":1}}],"request":"coord.request.mutex1","return":"coord.return.mutex1","grant":"coord.recv.a.coord.lend.mutex1.v","ends":["call1.release"]}}]"#
            )
        };
        let ok = token_table(&net(&entry("call1.start"))).unwrap();
        assert_eq!(ok.len(), 1);
        assert_eq!((ok[0].holder.as_str(), ok[0].starts.len(), ok[0].ends.len()), ("a", 1, 1));
        assert!(token_table(&net(&entry("nope"))).unwrap_err().contains("`nope`"));
        assert!(token_table(&net("[")).unwrap_err().contains("bad `coord.tokens`"));
    }

    #[test]
    fn send_table_reads_the_property() {
        let net = |send: &str| {
            let mut b = mcl_net::NetBuilder::new("v");
            let p = b.add_place(mcl_net::Place::new("p").with_tokens(1));
            let t = b.add_transition(mcl_net::Transition::new("call1.ok"));
            b.add_input(p, t, 1);
            b.property(SEND_PROPERTY, send);
            b.build().unwrap()
        };
        let ok = net(r#"[{"transition":"call1.ok","to":"b"},{"transition":"call1.ok","to":"c"}]"#);
        assert_eq!(send_table(&ok).unwrap()["call1.ok"], ["b", "c"]);
        assert!(send_table(&net(r#"[{"transition":"nope","to":"b"}]"#)).unwrap_err().contains("nope"));
        assert!(send_table(&net("{")).unwrap_err().contains("bad `coord.send`"));
    }
}
