//! Coordination messages over Zenoh: a [`CoordTransport`] whose messages
//! travel under `mcl/<fleet>/<to>/coord/in/<from>/<kind>` and whose
//! acknowledgements come back under `mcl/<fleet>/<from>/coord/ack/<to>`
//! (docs/zenoh.md *Coordination*).
//!
//! The guarantees are those of the TCP link, from the same sans-IO code
//! ([`mcl_runtime::coord_seq`]): per sender and receiver, messages are
//! numbered from 1, delivered in order and once, acknowledged
//! cumulatively once durable, and re-sent every second until then; so a
//! peer or a router that restarts loses nothing, and a resumed vehicle
//! (journal) applies nothing twice. Every message and acknowledgement
//! carries an HMAC-SHA256 with the fleet secret ([`Auth`]) over the fleet,
//! both names, the sender's run, the number and the body.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use mcl_runtime::coord::{Auth, CoordMessage, CoordTransport, Incoming, RecvFuture};
use mcl_runtime::coord_link::MAX_REPORTED_REFUSALS;
use mcl_runtime::coord_seq::{Offer, RecvWindow, SendWindow, RESEND_AFTER};
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

use crate::keys;
use crate::node::{Node, Received};

/// A message on `mcl/<fleet>/<to>/coord/in/<from>/<kind>`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ZMsg {
    /// The sender's run (kept across its crashes when it resumes).
    pub run: String,
    /// Its number on the link `from` → `to`, from 1.
    pub seq: u64,
    /// The [`CoordMessage`] as JSON text.
    pub body: String,
    /// `mac("zmsg", fleet, from, to, run, seq, body)`.
    pub mac: String,
}

/// An acknowledgement on `mcl/<fleet>/<from>/coord/ack/<to>`: every
/// message of `run` up to `seq` is durable at `to`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ZAck {
    /// The sender's run it acknowledges.
    pub run: String,
    /// The last durable number.
    pub seq: u64,
    /// `mac("zack", fleet, from, to, run, seq)`.
    pub mac: String,
}

fn msg_mac(auth: &Auth, fleet: &str, from: &str, to: &str, run: &str, seq: u64, body: &str) -> String {
    auth.mac("zmsg", &[fleet, from, to, run, &seq.to_string(), body])
}

fn ack_mac(auth: &Auth, fleet: &str, from: &str, to: &str, run: &str, seq: u64) -> String {
    auth.mac("zack", &[fleet, from, to, run, &seq.to_string()])
}

/// What a receiving end knows of one sender.
#[derive(Default)]
struct FromPeer {
    window: RecvWindow,
    run: Option<String>,
    /// Runs refused (a sender started again without its journal), reported once.
    refused: Vec<String>,
}

struct Receiver {
    fleet: String,
    me: String,
    auth: Auth,
    allowed: Vec<String>,
    peers: HashMap<String, FromPeer>,
    tx: mpsc::UnboundedSender<Incoming>,
    node: Arc<Node>,
    refusals: usize,
}

impl Receiver {
    fn reject(&mut self, why: String) {
        self.refusals += 1;
        let why = match self.refusals {
            n if n < MAX_REPORTED_REFUSALS => why,
            MAX_REPORTED_REFUSALS => format!("{why} (further refusals are not reported)"),
            _ => return,
        };
        let _ = self.tx.send(Incoming::Rejected(why));
    }

    fn ack(&self, from: &str) {
        let Some(p) = self.peers.get(from) else { return };
        if let (Some(seq), Some(run)) = (p.window.ack(), &p.run) {
            let mac = ack_mac(&self.auth, &self.fleet, from, &self.me, run, seq);
            let a = ZAck { run: run.clone(), seq, mac };
            self.node.put(keys::coord_ack(&self.fleet, from, &self.me), serde_json::to_vec(&a).unwrap_or_default());
        }
    }

    fn handle(&mut self, r: Received) {
        let prefix = format!("mcl/{}/{}/coord/in", self.fleet, self.me);
        let Some([from, kind]) = keys::tail(&r.key, &prefix).and_then(|t| <[&str; 2]>::try_from(t).ok()) else {
            return self.reject(format!("a sample on `{}`, which is no coordination key", r.key));
        };
        let (from, kind) = (from.to_string(), kind.to_string());
        if !self.allowed.is_empty() && !self.allowed.contains(&from) {
            let from = mcl_runtime::protocol::truncate(&from, 60);
            return self.reject(format!("a message from `{from}`, which is no mission of this fleet"));
        }
        let z: ZMsg = match serde_json::from_slice(&r.payload) {
            Ok(z) => z,
            Err(e) => return self.reject(format!("a message from `{from}` that is not of the link: {e}")),
        };
        if !self.auth.verify("zmsg", &[&self.fleet, &from, &self.me, &z.run, &z.seq.to_string(), &z.body], &z.mac) {
            return self.reject(format!(
                "a message from `{from}` (#{}) with a wrong MAC (forged, or a wrong fleet secret)",
                z.seq
            ));
        }
        let m: CoordMessage = match serde_json::from_str(&z.body) {
            Ok(m) => m,
            Err(e) => {
                return self.reject(format!("a message from `{from}` whose body is not a coordination message: {e}"))
            }
        };
        if m.from != from || m.to != self.me || m.seq != z.seq || keys::coord_kind(&m.transition) != kind {
            return self
                .reject(format!("a message whose body does not match its key (`{from}` → `{}`, #{})", self.me, z.seq));
        }
        // A sender that started again without its journal would number its
        // messages from 1 again: refused (reported once per run).
        let refused = {
            let p = self.peers.entry(from.clone()).or_default();
            match &p.run {
                Some(known) if *known != z.run => {
                    let first = !p.refused.contains(&z.run);
                    if first {
                        p.refused.push(z.run.clone());
                    }
                    Some(first.then(|| known.clone()))
                }
                Some(_) => None,
                None => {
                    p.run = Some(z.run.clone());
                    None
                }
            }
        };
        match refused {
            Some(Some(known)) => {
                return self.reject(format!(
                    "`{from}` started a new run ({}) while this vehicle holds the messages of its run {known}: restart it with --resume JOURNAL (or restart every vehicle)",
                    z.run
                ))
            }
            Some(None) => return,
            None => {}
        }
        match self.peers.get_mut(&from).map(|p| p.window.offer(z.seq)) {
            Some(Offer::Deliver) => {
                let _ = self.tx.send(Incoming::Message(m));
            }
            Some(Offer::Durable) => self.ack(&from),
            _ => {}
        }
    }
}

fn locked<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// One vehicle's end of the Zenoh coordination transport (see the [module
/// documentation](self)).
pub struct ZenohEnd {
    mission: String,
    fleet: String,
    auth: Auth,
    run: String,
    node: Arc<Node>,
    recv: Arc<Mutex<Receiver>>,
    inbox: mpsc::UnboundedReceiver<Incoming>,
    inbox_tx: mpsc::UnboundedSender<Incoming>,
    acks: Arc<Mutex<HashMap<String, mpsc::UnboundedSender<ZAck>>>>,
    peers: HashMap<String, Peer>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
}

struct Peer {
    queue: mpsc::UnboundedSender<(u64, String)>,
    unacked: Arc<AtomicUsize>,
}

impl ZenohEnd {
    /// Subscribes for `mission`'s messages of `fleet` on `node`; `received`
    /// gives, per sender, the last number already received (from a journal).
    pub async fn open(
        node: Arc<Node>,
        fleet: &str,
        mission: &str,
        auth: Auth,
        received: &HashMap<String, u64>,
    ) -> Result<ZenohEnd, String> {
        keys::check_chunk("fleet", fleet)?;
        keys::check_chunk("mission", mission)?;
        let (tx, inbox) = mpsc::unbounded_channel();
        let peers = received
            .iter()
            .map(|(f, &s)| (f.clone(), FromPeer { window: RecvWindow::resumed(s), ..Default::default() }));
        let recv = Arc::new(Mutex::new(Receiver {
            fleet: fleet.to_string(),
            me: mission.to_string(),
            auth: auth.clone(),
            allowed: Vec::new(),
            peers: peers.collect(),
            tx: tx.clone(),
            node: node.clone(),
            refusals: 0,
        }));
        let mut samples = node.subscribe(&keys::coord_inbox(fleet, mission)).await?;
        let r = recv.clone();
        let mut tasks = vec![node.spawn(async move {
            while let Some(s) = samples.recv().await {
                locked(&r).handle(s);
            }
        })];
        // Acknowledgements, dispatched to the link of their receiver.
        let acks: Arc<Mutex<HashMap<String, mpsc::UnboundedSender<ZAck>>>> = Arc::default();
        let mut ack_samples = node.subscribe(&keys::coord_acks(fleet, mission)).await?;
        let (a, prefix, report) = (acks.clone(), format!("mcl/{fleet}/{mission}/coord/ack"), tx.clone());
        tasks.push(node.spawn(async move {
            while let Some(s) = ack_samples.recv().await {
                let Some(to) = keys::tail(&s.key, &prefix).filter(|t| t.len() == 1).map(|t| t[0].to_string()) else {
                    continue;
                };
                match serde_json::from_slice::<ZAck>(&s.payload) {
                    Ok(ack) => {
                        if let Some(link) = locked(&a).get(&to) {
                            let _ = link.send(ack);
                        }
                    }
                    Err(e) => {
                        let _ = report.send(Incoming::Rejected(format!(
                            "an acknowledgement from `{to}` that is not of the link: {e}"
                        )));
                    }
                }
            }
        }));
        Ok(ZenohEnd {
            mission: mission.to_string(),
            fleet: fleet.to_string(),
            auth,
            run: mcl_runtime::tcp::new_id(),
            node,
            recv,
            inbox,
            inbox_tx: tx,
            acks,
            peers: HashMap::new(),
            tasks,
        })
    }

    /// The run this end's messages belong to: a vehicle that resumes from
    /// its journal gives the journal's. Call it before [`ZenohEnd::add_peer`].
    pub fn set_run(&mut self, run: &str) {
        self.run = run.to_string();
    }

    /// Only `missions` may send to this end.
    pub fn accept_from(&mut self, missions: &[String]) {
        locked(&self.recv).allowed = missions.to_vec();
    }

    /// This end sends to `mission` (one link, its own numbering).
    pub fn add_peer(&mut self, mission: &str) -> Result<(), String> {
        keys::check_chunk("mission", mission)?;
        let (queue, rx) = mpsc::unbounded_channel();
        let (ack_tx, ack_rx) = mpsc::unbounded_channel();
        locked(&self.acks).insert(mission.to_string(), ack_tx);
        let unacked = Arc::new(AtomicUsize::new(0));
        let link = SendLink {
            fleet: self.fleet.clone(),
            from: self.mission.clone(),
            to: mission.to_string(),
            run: self.run.clone(),
            auth: self.auth.clone(),
            node: self.node.clone(),
            report: self.inbox_tx.clone(),
            unacked: unacked.clone(),
        };
        self.tasks.push(self.node.spawn(link.run(rx, ack_rx)));
        self.peers.insert(mission.to_string(), Peer { queue, unacked });
        Ok(())
    }
}

impl Drop for ZenohEnd {
    fn drop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
    }
}

impl CoordTransport for ZenohEnd {
    fn mission(&self) -> &str {
        &self.mission
    }

    fn send(&mut self, msg: CoordMessage) -> Result<(), String> {
        let to = self.peers.get(&msg.to).ok_or_else(|| {
            format!("`{}` has no Zenoh link to mission `{}` (message {})", self.mission, msg.to, msg.transition)
        })?;
        let body = serde_json::to_string(&msg).map_err(|e| e.to_string())?;
        to.unacked.fetch_add(1, Ordering::SeqCst);
        to.queue.send((msg.seq, body)).map_err(|_| format!("the Zenoh link to `{}` is closed", msg.to))
    }

    fn recv(&mut self) -> RecvFuture<'_> {
        Box::pin(async move { self.inbox.recv().await })
    }

    fn delivered(&mut self, msg: &CoordMessage) {
        let mut r = locked(&self.recv);
        if let Some(p) = r.peers.get_mut(&msg.from) {
            p.window.made_durable(msg.seq);
        }
        r.ack(&msg.from);
    }

    fn unacknowledged(&self) -> usize {
        self.peers.values().map(|p| p.unacked.load(Ordering::SeqCst)).sum()
    }
}

/// The sending side of one link.
struct SendLink {
    fleet: String,
    from: String,
    to: String,
    run: String,
    auth: Auth,
    node: Arc<Node>,
    report: mpsc::UnboundedSender<Incoming>,
    unacked: Arc<AtomicUsize>,
}

impl SendLink {
    fn publish(&self, seq: u64, body: &str) {
        let mac = msg_mac(&self.auth, &self.fleet, &self.from, &self.to, &self.run, seq, body);
        let z = ZMsg { run: self.run.clone(), seq, body: body.to_string(), mac };
        let kind =
            serde_json::from_str::<CoordMessage>(body).map(|m| keys::coord_kind(&m.transition)).unwrap_or("firing");
        self.node
            .put(keys::coord_msg(&self.fleet, &self.to, &self.from, kind), serde_json::to_vec(&z).unwrap_or_default());
    }

    async fn run(self, mut rx: mpsc::UnboundedReceiver<(u64, String)>, mut acks: mpsc::UnboundedReceiver<ZAck>) {
        let mut outbox: SendWindow<String> = SendWindow::new();
        let mut last_write = tokio::time::Instant::now();
        let mut wrong_acks = 0usize;
        loop {
            tokio::select! {
                m = rx.recv() => match m {
                    Some((seq, body)) => {
                        self.publish(seq, &body);
                        outbox.push(seq, body);
                        last_write = tokio::time::Instant::now();
                    }
                    None => return,
                },
                a = acks.recv() => match a {
                    Some(ack) => {
                        let ok = ack.run == self.run
                            && self.auth.verify("zack", &[&self.fleet, &self.from, &self.to, &ack.run, &ack.seq.to_string()], &ack.mac);
                        if ok {
                            let n = outbox.acked(ack.seq);
                            let _ = self.unacked.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |u| Some(u.saturating_sub(n)));
                        } else if ack.run == self.run && wrong_acks < MAX_REPORTED_REFUSALS {
                            wrong_acks += 1;
                            let _ = self.report.send(Incoming::Rejected(format!("an acknowledgement from `{}` with a wrong MAC", self.to)));
                        }
                    }
                    None => return,
                },
                _ = tokio::time::sleep(Duration::from_millis(250)) => {
                    if !outbox.is_empty() && last_write.elapsed() >= RESEND_AFTER {
                        for (seq, body) in outbox.pending() {
                            self.publish(*seq, body);
                        }
                        last_write = tokio::time::Instant::now();
                    }
                }
            }
        }
    }
}

/// One end per mission on `node`, all of `fleet` and knowing each other,
/// with a fresh random secret: the one-process set-up of `mcl run
/// --transport zenoh`.
pub async fn zenoh_mesh(node: Arc<Node>, fleet: &str, missions: &[String]) -> Result<Vec<ZenohEnd>, String> {
    let auth = Auth::random()?;
    let mut ends = Vec::new();
    for m in missions {
        let mut e = ZenohEnd::open(node.clone(), fleet, m, auth.clone(), &HashMap::new()).await?;
        e.accept_from(missions);
        ends.push(e);
    }
    for e in &mut ends {
        for m in missions {
            if *m != e.mission {
                e.add_peer(m)?;
            }
        }
    }
    Ok(ends)
}
