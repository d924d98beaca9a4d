//! The TCP coordination link: authenticated JSON lines, acknowledged end to
//! end (`docs/coordination.md`, *The TCP link*).
//!
//! Every connection carries the messages of one sender to one receiver.
//! It opens with a handshake in which each side proves that it knows the
//! fleet secret (HMAC-SHA256 over both sides' fresh nonces); then every
//! message and every acknowledgement carries an HMAC over the connection's
//! nonces, the sender, the receiver, the sequence number and the payload.
//! A line that fails any check is refused, reported
//! ([`Incoming::Rejected`]) and never delivered: a forged line, a line
//! captured on another connection, a handshake replayed.
//!
//! Sequence numbers count the messages of one sender to one receiver,
//! from one. The receiver delivers them in order, exactly once: `seq` equal to the
//! next expected one is delivered, a smaller one (a re-send) is dropped and
//! acknowledged again once durable, a larger one (a gap) is dropped and
//! comes back with the re-sends. The receiver acknowledges (cumulatively)
//! only what its vehicle has made durable ([`CoordTransport::delivered`]);
//! the sender keeps every message until it is acknowledged and re-sends
//! the unacknowledged ones on every new connection and every second.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use hmac::{Hmac, Mac};
use serde::{Deserialize, Serialize};
use sha2::Sha256;
use tokio::io::{AsyncWriteExt, BufReader};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::mpsc;

use crate::coord::{CoordMessage, CoordTransport, Incoming, RecvFuture};
pub use crate::coord_seq::RESEND_AFTER;
use crate::coord_seq::{Offer, RecvWindow, SendWindow};
use crate::protocol::{Line, LineReader, MAX_LINE};

/// Version of the link protocol (`hello`'s `version`).
pub const LINK_VERSION: u32 = 1;
/// Refusals reported by one end; the next ones are refused silently (a
/// peer that keeps knocking does not fill the trace).
pub const MAX_REPORTED_REFUSALS: usize = 100;
/// How long each side waits for the other's handshake line.
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);

type HmacSha256 = Hmac<Sha256>;

/// The fleet secret of the coordination links (`--coord-token`), or none:
/// without a secret the same protocol runs with an empty key, which keeps
/// garbage out but proves nothing.
#[derive(Clone, Default)]
pub struct Auth {
    key: Arc<Vec<u8>>,
}

impl std::fmt::Debug for Auth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Auth({})", if self.is_secret() { "secret" } else { "none" })
    }
}

impl Auth {
    /// No secret.
    pub fn none() -> Auth {
        Auth::default()
    }

    /// The fleet secret `secret` (its bytes are the HMAC key).
    pub fn secret(secret: &[u8]) -> Auth {
        Auth { key: Arc::new(secret.to_vec()) }
    }

    /// A fresh random secret of 32 bytes (links inside one process).
    pub fn random() -> Result<Auth, String> {
        let mut key = vec![0u8; 32];
        getrandom::fill(&mut key).map_err(|e| format!("no random numbers for the coordination secret: {e}"))?;
        Ok(Auth { key: Arc::new(key) })
    }

    /// A secret was given.
    pub fn is_secret(&self) -> bool {
        !self.key.is_empty()
    }

    fn hmac(&self, kind: &str, fields: &[&str]) -> HmacSha256 {
        let mut m = HmacSha256::new_from_slice(&self.key).expect("HMAC takes keys of any length");
        m.update(b"mcl-coord/1\n");
        m.update(kind.as_bytes());
        for f in fields {
            m.update(b"\n");
            m.update(f.as_bytes());
        }
        m
    }

    /// HMAC-SHA256 of `mcl-coord/1\n<kind>\n<field>\n…\n<field>`, in
    /// lowercase hex (docs/coordination.md).
    pub fn mac(&self, kind: &str, fields: &[&str]) -> String {
        hex(&self.hmac(kind, fields).finalize().into_bytes())
    }

    /// `given` is the MAC of `kind` and `fields` (compared in constant time).
    pub fn verify(&self, kind: &str, fields: &[&str], given: &str) -> bool {
        match unhex(given) {
            Some(bytes) => self.hmac(kind, fields).verify_slice(&bytes).is_ok(),
            None => false,
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    if (s.len() & 1) == 1 || !s.is_ascii() {
        return None;
    }
    (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).ok()).collect()
}

fn nonce() -> Result<String, String> {
    let mut n = [0u8; 16];
    getrandom::fill(&mut n).map_err(|e| format!("no random numbers for a nonce: {e}"))?;
    Ok(hex(&n))
}

/// One line of the link protocol.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Wire {
    /// Connector → listener, first line.
    Hello {
        /// [`LINK_VERSION`].
        version: u32,
        /// The sending mission.
        from: String,
        /// The receiving mission.
        to: String,
        /// The sender's run: the same across its crashes when it resumes
        /// from its journal, new when it starts again.
        run: String,
        /// The connector's nonce (32 hex digits).
        nonce: String,
    },
    /// Listener → connector: its nonce and its proof.
    Challenge {
        /// The listener's nonce.
        nonce: String,
        /// `mac("listener", from, to, run, connector nonce, listener nonce)`.
        proof: String,
    },
    /// Connector → listener: its proof.
    Auth {
        /// `mac("connector", from, to, run, connector nonce, listener nonce)`.
        proof: String,
    },
    /// Connector → listener: a message.
    Msg {
        /// Its sequence number on this link (from 1).
        seq: u64,
        /// The [`CoordMessage`] as JSON text.
        body: String,
        /// `mac("msg", connector nonce, listener nonce, from, to, seq, body)`.
        mac: String,
    },
    /// Listener → connector: every message up to `seq` is durable.
    Ack {
        /// The last durable sequence number.
        seq: u64,
        /// `mac("ack", connector nonce, listener nonce, from, to, seq)`.
        mac: String,
    },
    /// Either way: why the connection is closed.
    Error {
        /// Why.
        message: String,
    },
}

impl Wire {
    fn line(&self) -> Vec<u8> {
        let mut l = serde_json::to_vec(self).unwrap_or_default();
        l.push(b'\n');
        l
    }
}

/// The nonces of one connection (they bind every MAC to it).
#[derive(Clone, Debug)]
struct Session {
    from: String,
    to: String,
    cn: String,
    ln: String,
}

impl Session {
    fn msg_mac(&self, auth: &Auth, seq: u64, body: &str) -> String {
        auth.mac("msg", &[&self.cn, &self.ln, &self.from, &self.to, &seq.to_string(), body])
    }

    fn ack_mac(&self, auth: &Auth, seq: u64) -> String {
        auth.mac("ack", &[&self.cn, &self.ln, &self.from, &self.to, &seq.to_string()])
    }

    fn ack_ok(&self, auth: &Auth, seq: u64, mac: &str) -> bool {
        auth.verify("ack", &[&self.cn, &self.ln, &self.from, &self.to, &seq.to_string()], mac)
    }
}

/// The receiving side's state for one sender.
#[derive(Default)]
struct FromPeer {
    /// The next sequence number to deliver, and the last durable one
    /// (acknowledged).
    window: RecvWindow,
    /// The sender's run whose messages these are.
    run: Option<String>,
    /// The current connection from this sender: its id, session and acks.
    conn: Option<(u64, Session, mpsc::UnboundedSender<Vec<u8>>)>,
}

struct Receiver {
    mission: String,
    auth: Auth,
    peers: HashMap<String, FromPeer>,
    tx: mpsc::UnboundedSender<Incoming>,
    conns: u64,
    /// The missions allowed to send here (any when empty).
    allowed: Vec<String>,
    refusals: usize,
}

impl Receiver {
    fn peer(&mut self, from: &str) -> &mut FromPeer {
        self.peers.entry(from.to_string()).or_default()
    }

    fn reject(&mut self, why: String) {
        self.refusals += 1;
        let why = match self.refusals {
            n if n < MAX_REPORTED_REFUSALS => why,
            MAX_REPORTED_REFUSALS => format!("{why} (further refusals are not reported)"),
            _ => return,
        };
        let _ = self.tx.send(Incoming::Rejected(why));
    }

    /// Sends the acknowledgement of what is durable from `from` on its
    /// current connection.
    fn ack(&mut self, from: &str) {
        let auth = self.auth.clone();
        let p = self.peer(from);
        if let (Some((_, s, out)), Some(seq)) = (&p.conn, p.window.ack()) {
            let _ = out.send(Wire::Ack { seq, mac: s.ack_mac(&auth, seq) }.line());
        }
    }
}

type Shared<T> = Arc<Mutex<T>>;

fn locked<T>(m: &Shared<T>) -> std::sync::MutexGuard<'_, T> {
    // A task that panicked while holding the lock left consistent data
    // (every update is one assignment); go on with it.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A TCP end: listens for messages for its mission, and sends to its peers'
/// addresses over the authenticated link of the [module
/// documentation](self). Every task runs in the current tokio runtime and
/// ends when the end is dropped.
pub struct TcpEnd {
    mission: String,
    addr: SocketAddr,
    auth: Auth,
    run: String,
    peers: HashMap<String, Peer>,
    inbox: mpsc::UnboundedReceiver<Incoming>,
    inbox_tx: mpsc::UnboundedSender<Incoming>,
    recv: Shared<Receiver>,
    rejected: Shared<Vec<String>>,
    accept: tokio::task::JoinHandle<()>,
}

/// The sending side of one link: the messages not yet acknowledged.
struct Peer {
    queue: mpsc::UnboundedSender<(u64, String)>,
    unacked: Shared<usize>,
    task: tokio::task::JoinHandle<()>,
}

impl TcpEnd {
    /// Listens on `listen` (`127.0.0.1:0` picks a free loopback port),
    /// without a secret and with nothing received yet.
    pub async fn bind(mission: &str, listen: &str) -> std::io::Result<TcpEnd> {
        TcpEnd::bind_with(mission, listen, Auth::none(), &HashMap::new()).await
    }

    /// Listens on `listen` with the fleet secret `auth`; `received` gives,
    /// per sender, the last sequence number already received (from a
    /// journal: a resumed vehicle neither takes those again nor waits for
    /// them).
    pub async fn bind_with(
        mission: &str,
        listen: &str,
        auth: Auth,
        received: &HashMap<String, u64>,
    ) -> std::io::Result<TcpEnd> {
        let listener = TcpListener::bind(listen).await?;
        let addr = listener.local_addr()?;
        let (tx, inbox) = mpsc::unbounded_channel();
        let mut peers = HashMap::new();
        for (from, &seq) in received {
            peers.insert(from.clone(), FromPeer { window: RecvWindow::resumed(seq), run: None, conn: None });
        }
        let recv = Arc::new(Mutex::new(Receiver {
            mission: mission.to_string(),
            auth: auth.clone(),
            peers,
            tx: tx.clone(),
            conns: 0,
            allowed: Vec::new(),
            refusals: 0,
        }));
        let rejected = Arc::new(Mutex::new(Vec::new()));
        let r = recv.clone();
        let accept = tokio::spawn(async move {
            while let Ok((stream, from_addr)) = listener.accept().await {
                let _ = stream.set_nodelay(true);
                tokio::spawn(serve_connection(stream, from_addr, r.clone()));
            }
        });
        Ok(TcpEnd {
            mission: mission.to_string(),
            addr,
            auth,
            run: crate::tcp::new_id(),
            peers: HashMap::new(),
            inbox,
            inbox_tx: tx,
            recv,
            rejected,
            accept,
        })
    }

    /// The mission this end receives for.
    pub fn mission_name(&self) -> &str {
        &self.mission
    }

    /// The address this end listens on (give it to the peers).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The run this end's messages belong to (sent in every hello; by
    /// default a new one): a vehicle that resumes from its journal gives
    /// the journal's, so that its peers know it is the same run. Call it
    /// before [`TcpEnd::add_peer`].
    pub fn set_run(&mut self, run: &str) {
        self.run = run.to_string();
    }

    /// Messages for `mission` go to `addr`.
    pub fn add_peer(&mut self, mission: &str, addr: SocketAddr) {
        let (queue, rx) = mpsc::unbounded_channel();
        let unacked = Arc::new(Mutex::new(0));
        let link = SendLink {
            from: self.mission.clone(),
            to: mission.to_string(),
            run: self.run.clone(),
            addr,
            auth: self.auth.clone(),
            report: self.inbox_tx.clone(),
            unacked: unacked.clone(),
        };
        let task = tokio::spawn(link.run(rx));
        self.peers.insert(mission.to_string(), Peer { queue, unacked, task });
    }

    /// Only `missions` may send to this end (a hello from another name is
    /// refused).
    pub fn accept_from(&mut self, missions: &[String]) {
        locked(&self.recv).allowed = missions.to_vec();
    }

    /// Lines refused so far, with why (also delivered by `recv` as
    /// [`Incoming::Rejected`]).
    pub fn rejected(&self) -> Vec<String> {
        locked(&self.rejected).clone()
    }
}

impl Drop for TcpEnd {
    fn drop(&mut self) {
        self.accept.abort();
        for p in self.peers.values() {
            p.task.abort();
        }
    }
}

impl CoordTransport for TcpEnd {
    fn mission(&self) -> &str {
        &self.mission
    }

    fn send(&mut self, msg: CoordMessage) -> Result<(), String> {
        let to = self.peers.get(&msg.to).ok_or_else(|| format!("no address for mission `{}`", msg.to))?;
        let body = serde_json::to_string(&msg).map_err(|e| e.to_string())?;
        *locked(&to.unacked) += 1;
        to.queue.send((msg.seq, body)).map_err(|_| format!("the link to `{}` is closed", msg.to))
    }

    fn recv(&mut self) -> RecvFuture<'_> {
        Box::pin(async move {
            let m = self.inbox.recv().await;
            if let Some(Incoming::Rejected(why)) = &m {
                locked(&self.rejected).push(why.clone());
            }
            m
        })
    }

    fn delivered(&mut self, msg: &CoordMessage) {
        let mut r = locked(&self.recv);
        r.peer(&msg.from).window.made_durable(msg.seq);
        r.ack(&msg.from);
    }

    fn unacknowledged(&self) -> usize {
        self.peers.values().map(|p| *locked(&p.unacked)).sum()
    }
}

/// Reads one line within the handshake timeout.
async fn read_wire(lines: &mut LineReader<BufReader<OwnedReadHalf>>) -> Result<Wire, String> {
    match tokio::time::timeout(HANDSHAKE_TIMEOUT, lines.next_line()).await {
        Err(_) => Err(format!("no answer within {HANDSHAKE_TIMEOUT:?}")),
        Ok(Ok(Line::Text(bytes))) => {
            serde_json::from_slice(&bytes).map_err(|e| format!("not a line of the coordination link: {e}"))
        }
        Ok(Ok(Line::TooLong(n))) => Err(format!("a line of {n} bytes (more than {MAX_LINE})")),
        Ok(Ok(Line::Eof)) => Err("the connection closed".into()),
        Ok(Err(e)) => Err(e.to_string()),
    }
}

/// The listener's side of one connection.
async fn serve_connection(stream: TcpStream, peer: SocketAddr, recv: Shared<Receiver>) {
    let (rd, mut wr) = stream.into_split();
    let mut lines = LineReader::new(BufReader::new(rd), MAX_LINE);
    let (me, auth, inbox) = {
        let r = locked(&recv);
        (r.mission.clone(), r.auth.clone(), r.tx.clone())
    };
    let refuse = |why: String| {
        locked(&recv).reject(format!("connection from {peer}: {why}"));
    };
    // Handshake.
    let (from, run, cn) = match read_wire(&mut lines).await {
        Ok(Wire::Hello { version, from, to, run, nonce }) => {
            if version != LINK_VERSION {
                let why = format!("link version {version}, this vehicle speaks version {LINK_VERSION}");
                let _ = wr.write_all(&Wire::Error { message: why.clone() }.line()).await;
                return refuse(why);
            }
            let allowed = {
                let r = locked(&recv);
                r.allowed.is_empty() || r.allowed.contains(&from)
            };
            if to != me || !allowed {
                let why = if to != me {
                    format!("a hello for `{to}` reached `{me}`")
                } else {
                    format!(
                        "a hello from `{}`, which is no mission of this fleet",
                        crate::protocol::truncate(&from, 60)
                    )
                };
                let _ = wr.write_all(&Wire::Error { message: why.clone() }.line()).await;
                return refuse(why);
            }
            if nonce.len() != 32 || unhex(&nonce).is_none() {
                return refuse("a hello whose nonce is not 32 hex digits".into());
            }
            (from, run, nonce)
        }
        Ok(other) => {
            return refuse(format!("expected a hello, got {}", crate::protocol::truncate(&format!("{other:?}"), 120)))
        }
        Err(e) => return refuse(format!("no hello: {e}")),
    };
    let Ok(ln) = nonce() else { return refuse("no random numbers for a nonce".into()) };
    let proof = auth.mac("listener", &[&from, &me, &run, &cn, &ln]);
    if wr.write_all(&Wire::Challenge { nonce: ln.clone(), proof }.line()).await.is_err() {
        return;
    }
    match read_wire(&mut lines).await {
        Ok(Wire::Auth { proof }) if auth.verify("connector", &[&from, &me, &run, &cn, &ln], &proof) => {}
        Ok(Wire::Auth { .. }) => {
            let why = format!("`{from}` did not prove the fleet secret (wrong --coord-token, or a replayed handshake)");
            let _ = wr.write_all(&Wire::Error { message: "authentication failed".into() }.line()).await;
            return refuse(why);
        }
        Ok(other) => {
            return refuse(format!("expected auth, got {}", crate::protocol::truncate(&format!("{other:?}"), 120)))
        }
        Err(e) => return refuse(format!("no auth: {e}")),
    }
    // A sender that started again without its journal would number its
    // messages from 1 again: they would be taken for re-sends and dropped.
    let other_run = {
        let mut r = locked(&recv);
        let p = r.peer(&from);
        match &p.run {
            Some(known) if *known != run => Some(known.clone()),
            _ => {
                p.run = Some(run.clone());
                None
            }
        }
    };
    if let Some(known) = other_run {
        let why = format!(
            "`{from}` started a new run ({run}) while this vehicle holds the messages of its run {known}: restart it with --resume JOURNAL (or restart every vehicle)"
        );
        let _ = wr.write_all(&Wire::Error { message: why.clone() }.line()).await;
        return refuse(why);
    }
    let session = Session { from: from.clone(), to: me.clone(), cn, ln };
    // Acks go out through this connection's writer.
    let (out, mut out_rx) = mpsc::unbounded_channel::<Vec<u8>>();
    tokio::spawn(async move {
        while let Some(l) = out_rx.recv().await {
            if wr.write_all(&l).await.is_err() {
                return;
            }
        }
    });
    let id = {
        let mut r = locked(&recv);
        r.conns += 1;
        let id = r.conns;
        r.peer(&from).conn = Some((id, session.clone(), out));
        r.ack(&from);
        id
    };
    loop {
        // The end was dropped: close the connection (as a crash would).
        let line = tokio::select! {
            l = lines.next_line() => l,
            _ = inbox.closed() => break,
        };
        let why = match line {
            Ok(Line::Text(bytes)) => match serde_json::from_slice::<Wire>(&bytes) {
                Ok(Wire::Msg { seq, body, mac }) => {
                    if !auth.verify("msg", &[&session.cn, &session.ln, &from, &me, &seq.to_string(), &body], &mac) {
                        format!("a message from `{from}` (#{seq}) with a wrong MAC (forged, or captured on another connection)")
                    } else {
                        match serde_json::from_str::<CoordMessage>(&body) {
                            Ok(m) if m.from == from && m.to == me && m.seq == seq => {
                                let mut r = locked(&recv);
                                match r.peer(&from).window.offer(seq) {
                                    Offer::Deliver => {
                                        let _ = r.tx.send(Incoming::Message(m));
                                    }
                                    // A re-send of a durable message: acknowledge it again.
                                    Offer::Durable => r.ack(&from),
                                    Offer::Delivered | Offer::Gap => {}
                                }
                                continue;
                            }
                            Ok(_) => {
                                format!("a message whose body does not match its link (`{from}` → `{me}`, #{seq})")
                            }
                            Err(e) => format!("a message from `{from}` whose body is not a coordination message: {e}"),
                        }
                    }
                }
                Ok(other) => format!("unexpected {}", crate::protocol::truncate(&format!("{other:?}"), 120)),
                Err(e) => format!("not a line of the coordination link: {e}"),
            },
            Ok(Line::TooLong(n)) => format!("a line of {n} bytes (more than {MAX_LINE})"),
            Ok(Line::Eof) | Err(_) => break,
        };
        // A refused line closes the connection: the sender re-sends on a new one.
        refuse(why);
        break;
    }
    let mut r = locked(&recv);
    let p = r.peer(&from);
    if p.conn.as_ref().is_some_and(|(c, _, _)| *c == id) {
        p.conn = None;
    }
}

/// The sending side of one link.
struct SendLink {
    from: String,
    to: String,
    run: String,
    addr: SocketAddr,
    auth: Auth,
    report: mpsc::UnboundedSender<Incoming>,
    unacked: Shared<usize>,
}

/// An open, authenticated connection of a [`SendLink`].
struct Conn {
    session: Session,
    lines: LineReader<BufReader<OwnedReadHalf>>,
    wr: OwnedWriteHalf,
}

impl SendLink {
    async fn connect(&self) -> Result<Conn, String> {
        let stream = tokio::time::timeout(HANDSHAKE_TIMEOUT, TcpStream::connect(self.addr))
            .await
            .map_err(|_| "connection timed out".to_string())?
            .map_err(|e| e.to_string())?;
        let _ = stream.set_nodelay(true);
        let (rd, mut wr) = stream.into_split();
        let mut lines = LineReader::new(BufReader::new(rd), MAX_LINE);
        let cn = nonce()?;
        let hello = Wire::Hello {
            version: LINK_VERSION,
            from: self.from.clone(),
            to: self.to.clone(),
            run: self.run.clone(),
            nonce: cn.clone(),
        };
        wr.write_all(&hello.line()).await.map_err(|e| e.to_string())?;
        let ln = match read_wire(&mut lines).await? {
            Wire::Challenge { nonce, proof } => {
                if !self.auth.verify("listener", &[&self.from, &self.to, &self.run, &cn, &nonce], &proof) {
                    return Err(format!(
                        "the listener at {} did not prove the fleet secret (wrong --coord-token?)",
                        self.addr
                    ));
                }
                nonce
            }
            Wire::Error { message } => return Err(format!("refused: {message}")),
            other => return Err(format!("unexpected {other:?}")),
        };
        let proof = self.auth.mac("connector", &[&self.from, &self.to, &self.run, &cn, &ln]);
        wr.write_all(&Wire::Auth { proof }.line()).await.map_err(|e| e.to_string())?;
        Ok(Conn { session: Session { from: self.from.clone(), to: self.to.clone(), cn, ln }, lines, wr })
    }

    async fn write_all<'a>(conn: &mut Conn, auth: &Auth, outbox: impl IntoIterator<Item = &'a (u64, String)>) -> bool {
        let mut buf = Vec::new();
        for (seq, body) in outbox {
            let mac = conn.session.msg_mac(auth, *seq, body);
            buf.extend(Wire::Msg { seq: *seq, body: body.clone(), mac }.line());
        }
        conn.wr.write_all(&buf).await.is_ok()
    }

    async fn run(self, mut rx: mpsc::UnboundedReceiver<(u64, String)>) {
        let mut outbox: SendWindow<String> = SendWindow::new();
        let mut conn: Option<Conn> = None;
        let mut last_error: Option<String> = None;
        let mut last_write = tokio::time::Instant::now();
        let mut open = true;
        loop {
            if conn.is_none() && !outbox.is_empty() {
                match self.connect().await {
                    Ok(mut c) => {
                        last_error = None;
                        if SendLink::write_all(&mut c, &self.auth, outbox.pending()).await {
                            last_write = tokio::time::Instant::now();
                            conn = Some(c);
                        }
                    }
                    Err(e) => {
                        // Refusals are reported once, and retried slowly; a
                        // peer that is down is retried every 100 ms.
                        let down = e.contains("refused (os error") || e.contains("timed out");
                        if !down && last_error.as_deref() != Some(e.as_str()) {
                            let _ = self.report.send(Incoming::Rejected(format!("link to `{}`: {e}", self.to)));
                        }
                        last_error = Some(e);
                        tokio::time::sleep(Duration::from_millis(if down { 100 } else { 2000 })).await;
                    }
                }
                // Take the queued messages first.
                while let Ok((seq, body)) = rx.try_recv() {
                    outbox.push(seq, body.clone());
                    if let Some(c) = &mut conn {
                        if !SendLink::write_all(c, &self.auth, &[(seq, body)]).await {
                            conn = None;
                        }
                    }
                }
                continue;
            }
            if !open && outbox.is_empty() {
                return;
            }
            let tick = tokio::time::sleep(Duration::from_millis(250));
            tokio::select! {
                m = rx.recv(), if open => match m {
                    Some((seq, body)) => {
                        outbox.push(seq, body.clone());
                        if let Some(c) = &mut conn {
                            if SendLink::write_all(c, &self.auth, &[(seq, body)]).await {
                                last_write = tokio::time::Instant::now();
                            } else {
                                conn = None;
                            }
                        }
                    }
                    None => open = false,
                },
                line = async {
                    match &mut conn {
                        Some(c) => c.lines.next_line().await,
                        None => std::future::pending().await,
                    }
                } => {
                    let Some(c) = &conn else { continue };
                    match line {
                        Ok(Line::Text(bytes)) => match serde_json::from_slice::<Wire>(&bytes) {
                            Ok(Wire::Ack { seq, mac }) if c.session.ack_ok(&self.auth, seq, &mac) => {
                                let acked = outbox.acked(seq);
                                let mut u = locked(&self.unacked);
                                *u = u.saturating_sub(acked);
                            }
                            other => {
                                let why = match other {
                                    Ok(Wire::Error { message }) => format!("`{}` closed the link: {message}", self.to),
                                    Ok(_) => format!("an acknowledgement from `{}` with a wrong MAC", self.to),
                                    Err(e) => format!("a line from `{}` that is not of the link: {e}", self.to),
                                };
                                let _ = self.report.send(Incoming::Rejected(why));
                                conn = None;
                            }
                        },
                        _ => conn = None,
                    }
                },
                _ = tick => {
                    if let Some(c) = &mut conn {
                        if !outbox.is_empty() && last_write.elapsed() >= RESEND_AFTER {
                            if SendLink::write_all(c, &self.auth, outbox.pending()).await {
                                last_write = tokio::time::Instant::now();
                            } else {
                                conn = None;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// One TCP end per mission, all listening on `host` (port chosen by the
/// system) and knowing each other, with a fresh random secret: the
/// one-process set-up of `mcl run --transport tcp`.
pub async fn tcp_mesh(missions: &[String], host: &str) -> std::io::Result<Vec<TcpEnd>> {
    let auth = Auth::random().map_err(std::io::Error::other)?;
    let mut ends = Vec::new();
    for m in missions {
        ends.push(TcpEnd::bind_with(m, &format!("{host}:0"), auth.clone(), &HashMap::new()).await?);
    }
    let addrs: Vec<(String, SocketAddr)> = ends.iter().map(|e| (e.mission.clone(), e.addr)).collect();
    for e in &mut ends {
        for (m, a) in &addrs {
            if *m != e.mission {
                e.add_peer(m, *a);
            }
        }
    }
    Ok(ends)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::AsyncBufReadExt;

    fn msg(from: &str, to: &str, transition: &str, seq: u64) -> CoordMessage {
        CoordMessage { from: from.into(), to: to.into(), transition: transition.into(), seq, t: seq as f64 }
    }

    async fn next(end: &mut TcpEnd) -> Incoming {
        tokio::time::timeout(Duration::from_secs(10), end.recv()).await.expect("in time").expect("open")
    }

    /// The next message, skipping refusals.
    async fn message(end: &mut TcpEnd) -> CoordMessage {
        loop {
            if let Incoming::Message(m) = next(end).await {
                return m;
            }
        }
    }

    /// The next refusal that says `what` (no message may come first).
    async fn refusal(end: &mut TcpEnd, what: &str) -> String {
        loop {
            match next(end).await {
                Incoming::Rejected(why) if why.contains(what) => return why,
                Incoming::Rejected(_) => continue,
                Incoming::Message(m) => panic!("delivered {m:?}"),
            }
        }
    }

    /// A raw client: sends `lines`, returns the lines it got back until the
    /// listener closes or goes quiet.
    async fn raw(addr: SocketAddr, lines: &[String]) -> Vec<String> {
        let s = TcpStream::connect(addr).await.unwrap();
        let (rd, mut wr) = s.into_split();
        for l in lines {
            let _ = wr.write_all(format!("{l}\n").as_bytes()).await;
        }
        let mut back = Vec::new();
        let mut rd = BufReader::new(rd).lines();
        while let Ok(Ok(Some(l))) = tokio::time::timeout(Duration::from_millis(300), rd.next_line()).await {
            back.push(l);
        }
        back
    }

    #[tokio::test]
    async fn delivers_in_order_once_and_acknowledges() {
        let names: Vec<String> = vec!["auv".into(), "asc".into()];
        let mut ends = tcp_mesh(&names, "127.0.0.1").await.unwrap();
        let mut asc = ends.pop().unwrap();
        let mut auv = ends.pop().unwrap();
        assert!(auv.local_addr().ip().is_loopback());
        for i in 1..=20 {
            auv.send(msg("auv", "asc", &format!("call{i}.ok"), i)).unwrap();
        }
        asc.send(msg("asc", "auv", "call3.ok", 1)).unwrap();
        for i in 1..=20 {
            let m = message(&mut asc).await;
            assert_eq!((m.transition.as_str(), m.seq), (format!("call{i}.ok").as_str(), i));
            asc.delivered(&m);
        }
        let m = message(&mut auv).await;
        assert_eq!(m, msg("asc", "auv", "call3.ok", 1));
        auv.delivered(&m);
        assert!(auv.send(msg("auv", "nobody", "t", 22)).is_err());
        // Acknowledged end to end.
        for _ in 0..100 {
            if auv.unacknowledged() == 0 && asc.unacknowledged() == 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        assert_eq!((auv.unacknowledged(), asc.unacknowledged()), (0, 0));
    }

    #[tokio::test]
    async fn a_receiver_that_comes_back_gets_what_was_not_acknowledged() {
        let auth = Auth::secret(b"fleet");
        let mut a = TcpEnd::bind_with("a", "127.0.0.1:0", auth.clone(), &HashMap::new()).await.unwrap();
        let mut b = TcpEnd::bind_with("b", "127.0.0.1:0", auth.clone(), &HashMap::new()).await.unwrap();
        let addr = b.local_addr();
        a.add_peer("b", addr);
        for i in 1..=3 {
            a.send(msg("a", "b", &format!("t{i}"), i)).unwrap();
        }
        // b takes 1 and 2, makes only 1 durable, and crashes.
        let m1 = message(&mut b).await;
        b.delivered(&m1);
        let _m2 = message(&mut b).await;
        tokio::time::sleep(Duration::from_millis(100)).await;
        drop(b);
        tokio::time::sleep(Duration::from_millis(50)).await;
        // b comes back on the same address with its journal (1 received).
        let mut b =
            TcpEnd::bind_with("b", &addr.to_string(), auth, &HashMap::from([("a".to_string(), 1)])).await.unwrap();
        a.send(msg("a", "b", "t4", 4)).unwrap();
        for i in 2..=4 {
            let m = message(&mut b).await;
            assert_eq!(m.seq, i);
            b.delivered(&m);
        }
        for _ in 0..100 {
            if a.unacknowledged() == 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        assert_eq!(a.unacknowledged(), 0);

        // a starts again without its journal (a new run, numbering from 1):
        // refused, with why. Resuming (the same run) is accepted.
        let mut again = TcpEnd::bind_with("a", "127.0.0.1:0", Auth::secret(b"fleet"), &HashMap::new()).await.unwrap();
        again.add_peer("b", addr);
        again.send(msg("a", "b", "t1", 1)).unwrap();
        let why = refusal(&mut b, "started a new run").await;
        assert!(why.contains("--resume"), "{why}");
        refusal(&mut again, "started a new run").await;
        drop(again);
        let mut resumed = TcpEnd::bind_with("a", "127.0.0.1:0", Auth::secret(b"fleet"), &HashMap::new()).await.unwrap();
        resumed.set_run(&a.run);
        resumed.add_peer("b", addr);
        resumed.send(msg("a", "b", "t1", 1)).unwrap();
        for _ in 0..100 {
            if resumed.unacknowledged() == 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        assert_eq!(resumed.unacknowledged(), 0, "a duplicate is acknowledged again");
    }

    #[tokio::test]
    async fn forged_replayed_and_unauthenticated_lines_are_refused() {
        let auth = Auth::secret(b"fleet");
        let mut b = TcpEnd::bind_with("b", "127.0.0.1:0", auth.clone(), &HashMap::new()).await.unwrap();
        b.accept_from(&["a".to_string()]);
        let addr = b.local_addr();
        // A hello from a name that is no mission of the fleet.
        let stranger =
            r#"{"type":"hello","version":1,"from":"zz","to":"b","run":"r","nonce":"0123456789abcdef0123456789abcdef"}"#;
        let back = raw(addr, &[stranger.to_string()]).await;
        assert!(back.iter().any(|l| l.contains("no mission of this fleet")), "{back:?}");
        refusal(&mut b, "no mission of this fleet").await;
        // A plain message without a handshake.
        let forged = r#"{"from":"a","to":"b","transition":"call1.release","seq":1,"t":0}"#.to_string();
        let back = raw(addr, std::slice::from_ref(&forged)).await;
        assert!(back.is_empty(), "{back:?}");
        refusal(&mut b, "no hello").await;

        // A peer with the wrong secret: refused at the handshake, both ways.
        let mut wrong = TcpEnd::bind_with("a", "127.0.0.1:0", Auth::secret(b"guess"), &HashMap::new()).await.unwrap();
        wrong.add_peer("b", addr);
        wrong.send(msg("a", "b", "call1.release", 1)).unwrap();
        refusal(&mut wrong, "did not prove the fleet secret").await;
        refusal(&mut b, "no auth").await;
        drop(wrong);

        // A genuine connection, by hand (the documented protocol).
        let cn = "0123456789abcdef0123456789abcdef";
        let hello = format!(r#"{{"type":"hello","version":1,"from":"a","to":"b","run":"r1","nonce":"{cn}"}}"#);
        let s = TcpStream::connect(addr).await.unwrap();
        let (rd, mut wr) = s.into_split();
        let mut rd = BufReader::new(rd).lines();
        wr.write_all(format!("{hello}\n").as_bytes()).await.unwrap();
        let ch: Wire = serde_json::from_str(&rd.next_line().await.unwrap().unwrap()).unwrap();
        let Wire::Challenge { nonce: ln, proof } = ch else { panic!("{ch:?}") };
        assert!(auth.verify("listener", &["a", "b", "r1", cn, &ln], &proof));
        let auth_line = Wire::Auth { proof: auth.mac("connector", &["a", "b", "r1", cn, &ln]) };
        let body = serde_json::to_string(&msg("a", "b", "call1.release", 1)).unwrap();
        let m = Wire::Msg { seq: 1, mac: auth.mac("msg", &[cn, &ln, "a", "b", "1", &body]), body };
        let (auth_line, m) = (auth_line.line(), m.line());
        wr.write_all(&auth_line).await.unwrap();
        wr.write_all(&m).await.unwrap();
        let got = message(&mut b).await;
        assert_eq!(got.transition, "call1.release");
        b.delivered(&got);
        let ack: Wire = serde_json::from_str(&rd.next_line().await.unwrap().unwrap()).unwrap();
        assert_eq!(ack, Wire::Ack { seq: 1, mac: auth.mac("ack", &[cn, &ln, "a", "b", "1"]) });

        // The captured conversation replayed on a new connection: the
        // listener's new nonce makes the captured proof wrong.
        let text = |l: &[u8]| String::from_utf8_lossy(l).trim().to_string();
        let back = raw(addr, &[hello.clone(), text(&auth_line), text(&m)]).await;
        assert!(back.iter().any(|l| l.contains("authentication failed")), "{back:?}");
        refusal(&mut b, "did not prove the fleet secret").await;

        // The captured message after a fresh handshake of a forger who
        // knows no secret: refused at the handshake too; and with the
        // secret but on another connection, its MAC is wrong.
        let cn2 = "fedcba9876543210fedcba9876543210";
        let hello2 = hello.replace(cn, cn2);
        let s = TcpStream::connect(addr).await.unwrap();
        let (rd, mut wr) = s.into_split();
        let mut rd = BufReader::new(rd).lines();
        wr.write_all(format!("{hello2}\n").as_bytes()).await.unwrap();
        let Ok(Wire::Challenge { nonce: ln2, .. }) = serde_json::from_str(&rd.next_line().await.unwrap().unwrap())
        else {
            panic!("no challenge")
        };
        wr.write_all(&Wire::Auth { proof: auth.mac("connector", &["a", "b", "r1", cn2, &ln2]) }.line()).await.unwrap();
        wr.write_all(&m).await.unwrap();
        refusal(&mut b, "wrong MAC").await;
        assert!(b.rejected().len() >= 4, "{:?}", b.rejected());
    }

    #[test]
    fn macs_are_hmac_sha256_of_the_documented_text() {
        // RFC 4231 test case 2 ("Jefe"), through the documented framing:
        // HMAC(key, "mcl-coord/1\n" + kind + "\n" + fields joined by "\n").
        let a = Auth::secret(b"Jefe");
        let mut m = HmacSha256::new_from_slice(b"Jefe").unwrap();
        m.update(b"mcl-coord/1\nack\nc\nl\na\nb\n7");
        assert_eq!(a.mac("ack", &["c", "l", "a", "b", "7"]), hex(&m.finalize().into_bytes()));
        assert_eq!(a.mac("x", &[]).len(), 64);
        assert!(!a.verify("x", &[], "zz"));
        assert!(!Auth::none().is_secret());
    }
}
