//! The player's side of the AAC protocol over Zenoh (docs/zenoh.md *The
//! AAC over Zenoh*): the messages of docs/aac-protocol.md, the same JSON,
//! published under `mcl/<vehicle>/aac/player/<type>` and received from
//! `mcl/<vehicle>/aac/vehicle/<type>`, behind the transport-neutral
//! [`Link`] that the player's real-time driver runs on.
//!
//! Zenoh has no connection to open or lose, so the rules of the TCP
//! protocol that hang on a connection are carried by time instead:
//!
//! * the player says `hello` every second until a `welcome` for its run
//!   comes; it takes the vehicle for gone after 5 s without a message from
//!   it, and says `hello` again;
//! * the player publishes every action once, and again every second until
//!   it is acknowledged; the vehicle executes action `seq` only when it is
//!   the next one (`last_seq + 1`): an action after a gap waits for its
//!   re-send;
//! * the vehicle re-sends the events and perceptions the player has not
//!   confirmed (`ping.last_event`); the player takes event `n` only when it
//!   is the next one, so a lost event is never overtaken.
//!
//! Every player message carries the run (`run`); every vehicle message
//! carries the run it answers (`run`) and the session (`session`).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use mcl_runtime::link::{Action, Delivered, Inbound, Link};
use mcl_runtime::protocol::{self, ActionMsg, EventEnd, Hello, Message, Ping, VERSION};
use serde_json::Value;
use tokio::sync::mpsc;

use crate::keys;
use crate::node::Node;

/// How often the player says `hello` (until welcomed), pings, and
/// publishes again the actions not acknowledged.
pub const PERIOD: Duration = Duration::from_secs(1);
/// Silence after which the vehicle is taken for gone.
pub const TIMEOUT: Duration = Duration::from_secs(5);

/// What the player tells the vehicle about its run.
#[derive(Clone, Debug, Default)]
pub struct AacOptions {
    /// The mission's name.
    pub mission: String,
    /// The run (the journal's when resuming).
    pub run: String,
    /// The AAC's shared secret, if it has one.
    pub token: Option<String>,
    /// The session and the event numbers handled (journaled) so far.
    pub delivered: Delivered,
    /// The events that end a task (`hello.events`).
    pub events: Vec<EventEnd>,
    /// After the player's last action: how long to wait for its
    /// acknowledgement.
    pub linger: Duration,
}

/// Opens the player's link to the AAC of `vehicle` over `node`. The link
/// task runs on the node's runtime; it ends once the player has dropped
/// its end and its last actions are acknowledged (or after `linger`).
pub async fn connect(
    node: Arc<Node>,
    vehicle: &str,
    opts: AacOptions,
) -> Result<(Link, tokio::task::JoinHandle<()>), String> {
    keys::check_chunk("vehicle", vehicle)?;
    let samples = node.subscribe(&format!("mcl/{vehicle}/aac/vehicle/*")).await?;
    let (atx, arx) = mpsc::unbounded_channel();
    let (itx, irx) = mpsc::unbounded_channel();
    let task = PlayerLink {
        node: node.clone(),
        vehicle: vehicle.to_string(),
        opts,
        inbound: itx,
        session: None,
        welcomed: false,
        last_n: 0,
        outbox: VecDeque::new(),
    };
    let handle = node.spawn(task.run(arx, samples));
    Ok((Link { actions: atx, inbound: irx }, handle))
}

struct PlayerLink {
    node: Arc<Node>,
    vehicle: String,
    opts: AacOptions,
    inbound: mpsc::UnboundedSender<Inbound>,
    /// The session of the last `welcome`.
    session: Option<String>,
    welcomed: bool,
    /// The highest event number received in the session.
    last_n: u64,
    /// Actions not acknowledged, in order.
    outbox: VecDeque<Action>,
}

impl PlayerLink {
    fn publish(&self, msg: &Message) {
        let mut v = serde_json::to_value(msg).unwrap_or(Value::Null);
        if let Value::Object(o) = &mut v {
            o.insert("run".into(), Value::String(self.opts.run.clone()));
        }
        let ty = msg.type_name();
        self.node.put(keys::aac_player(&self.vehicle, ty), serde_json::to_vec(&v).unwrap_or_default());
    }

    fn hello(&self) {
        let (session, last) = self.opts.delivered.get();
        self.publish(&Message::Hello(Hello {
            version: VERSION,
            token: self.opts.token.clone(),
            player: Some(format!("mcl/{}", env!("CARGO_PKG_VERSION"))),
            mission: Some(self.opts.mission.clone()),
            run: Some(self.opts.run.clone()),
            last_event: Some(if session.is_some() { last } else { 0 }),
            session,
            events: self.opts.events.clone(),
        }));
    }

    fn send_action(&self, a: &Action) {
        self.publish(&Message::Action(ActionMsg::from(a.clone())));
    }

    fn notice(&self, message: String) {
        let _ = self.inbound.send(Inbound::Notice { message });
    }

    /// One message from the vehicle. Returns false when the player is gone.
    fn on_message(&mut self, key: &str, payload: &[u8], heard: &mut tokio::time::Instant) -> bool {
        let value: Value = match serde_json::from_slice(payload) {
            Ok(v) => v,
            Err(e) => {
                self.notice(format!("a malformed message from the AAC on `{key}`: {e}"));
                return true;
            }
        };
        let field = |f: &str| value.get(f).and_then(Value::as_str).map(str::to_string);
        // Messages for another run (another player of this vehicle) are not ours.
        if field("run").is_some_and(|r| r != self.opts.run) {
            return true;
        }
        let msg = match protocol::parse(payload) {
            Ok(m) => m,
            Err(e) => {
                self.notice(format!("a malformed message from the AAC: {}", e.message));
                return true;
            }
        };
        *heard = tokio::time::Instant::now();
        let session = field("session");
        // A message of a session that is not the welcomed one (before the
        // welcome, or from a vehicle that restarted) is not taken.
        let current = self.welcomed && session.is_some() && self.session == session;
        let mut ok = true;
        match msg {
            Message::Welcome(w) => {
                if self.welcomed && self.session.as_deref() == Some(w.session.as_str()) {
                    return true;
                }
                let restarted = self.session.as_ref().is_some_and(|s| *s != w.session)
                    || self.opts.delivered.get().0.is_some_and(|s| s != w.session);
                self.last_n = self.opts.delivered.in_session(Some(&w.session));
                self.session = Some(w.session.clone());
                self.welcomed = true;
                if restarted {
                    // The AAC lost the run: what was not acknowledged is
                    // dropped; the player re-establishes what runs.
                    self.outbox.clear();
                } else {
                    self.outbox.retain(|a| a.seq > w.last_seq);
                }
                ok &= self.inbound.send(Inbound::Session { id: w.session.clone(), restarted }).is_ok();
                ok &= self.inbound.send(Inbound::Connected).is_ok();
                for a in &self.outbox {
                    self.send_action(a);
                }
            }
            Message::Ack { seq } if current => {
                while self.outbox.front().is_some_and(|a| a.seq <= seq) {
                    if let Some(a) = self.outbox.pop_front() {
                        ok &= self.inbound.send(Inbound::Ack { seq: a.seq }).is_ok();
                    }
                }
            }
            Message::Event(e) if current && self.take(e.n) => {
                ok &= self.inbound.send(Inbound::Event { event: e.event, activation: e.activation, n: e.n }).is_ok();
            }
            Message::Perception(p) if current && self.take(p.n) => {
                ok &= self.inbound.send(Inbound::Perception { name: p.name, value: p.value, n: p.n }).is_ok();
            }
            Message::Error(e) => {
                if e.code == "unexpected" && self.welcomed {
                    // The vehicle no longer knows the run: say hello again.
                    self.welcomed = false;
                    self.hello();
                }
                self.notice(format!("the AAC reports {}: {}", e.code, e.message));
            }
            _ => {}
        }
        ok
    }

    /// Whether to take the event or perception numbered `n`: the next one
    /// (or one without a number); a duplicate or one after a gap waits.
    fn take(&mut self, n: Option<u64>) -> bool {
        match n {
            None => true,
            Some(n) if n == self.last_n + 1 => {
                self.last_n = n;
                true
            }
            Some(_) => false,
        }
    }

    async fn run(
        mut self,
        mut actions: mpsc::UnboundedReceiver<Action>,
        mut samples: mpsc::UnboundedReceiver<crate::node::Received>,
    ) {
        let mut heard = tokio::time::Instant::now();
        let mut open = true;
        let mut closed_at: Option<tokio::time::Instant> = None;
        let mut tick = tokio::time::interval(PERIOD);
        self.hello();
        loop {
            if !open {
                let done = self.outbox.is_empty() || !self.welcomed;
                if done || closed_at.is_some_and(|t| t.elapsed() >= self.opts.linger) {
                    return;
                }
            }
            tokio::select! {
                a = actions.recv(), if open => match a {
                    Some(a) => {
                        if self.welcomed {
                            self.send_action(&a);
                        }
                        self.outbox.push_back(a);
                    }
                    None => {
                        open = false;
                        closed_at = Some(tokio::time::Instant::now());
                    }
                },
                s = samples.recv() => match s {
                    Some(s) => {
                        if !self.on_message(&s.key, &s.payload, &mut heard) {
                            open = false;
                            closed_at.get_or_insert_with(tokio::time::Instant::now);
                        }
                    }
                    None => return,
                },
                _ = tick.tick() => {
                    if self.welcomed && heard.elapsed() >= TIMEOUT {
                        self.welcomed = false;
                        let _ = self.inbound.send(Inbound::Disconnected);
                    }
                    if self.welcomed {
                        let last = self.opts.delivered.in_session(self.session.as_deref());
                        let mut v = serde_json::to_value(Message::Ping(Ping { last_event: Some(last) })).unwrap_or(Value::Null);
                        if let Value::Object(o) = &mut v {
                            o.insert("run".into(), Value::String(self.opts.run.clone()));
                        }
                        self.node.put(keys::aac_player(&self.vehicle, "ping"), serde_json::to_vec(&v).unwrap_or_default());
                        for a in &self.outbox {
                            self.send_action(a);
                        }
                    } else {
                        self.hello();
                    }
                }
            }
        }
    }
}
