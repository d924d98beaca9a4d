//! The AAC side: [`serve`] / [`Server`] accept players and hand one
//! [`AacEnd`] per *session* (one run of one mission) to a handler; a session
//! outlives its connections: actions are executed once per `seq`, events are
//! numbered and kept in an outbox re-sent to a player that reconnects.

use std::collections::{HashMap, VecDeque};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tokio::io::{AsyncWriteExt, BufReader};
use tokio::net::tcp::OwnedWriteHalf;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, Notify};
use tokio::time::{sleep, timeout, timeout_at, Instant};

use crate::link::{pair, AacEnd, Action, Inbound};
use crate::protocol::{
    encode, parse, token_matches, truncate, ActionMsg, ErrorCode, EventMsg, Line, LineReader, Message, PerceptionMsg,
    Welcome, DEFAULT_TIMEOUT, MAX_LINE, VERSION,
};

use super::*;

/// When the AAC acknowledges an action.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AckMode {
    /// As soon as it is handed to the session's handler.
    #[default]
    OnReceipt,
    /// When the handler sends [`Inbound::Ack`] through its [`AacEnd`] (it must
    /// do so in `seq` order): after it executed, or persisted, the action.
    ByHandler,
}

/// Options of [`serve`].
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// Shared secret: when set, a `hello` without it is refused.
    pub token: Option<String>,
    /// Silence after which a player is considered gone (it pings every
    /// second or so); also the time allowed for `hello` and for a write.
    pub timeout: Duration,
    /// When actions are acknowledged.
    pub ack: AckMode,
    /// Longest accepted line.
    pub max_line: usize,
    /// Sessions remembered (the least recently used idle ones are forgotten).
    pub max_sessions: usize,
    /// Events kept per session for a player that reconnects (the oldest are
    /// forgotten beyond that; a ping confirms and frees them).
    pub max_outbox: usize,
    /// Name sent in `welcome`.
    pub name: String,
    /// Logging on standard error.
    pub log: LogLevel,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            token: None,
            timeout: DEFAULT_TIMEOUT,
            ack: AckMode::OnReceipt,
            max_line: MAX_LINE,
            max_sessions: 64,
            max_outbox: 100_000,
            name: concat!("mcl-runtime/", env!("CARGO_PKG_VERSION")).into(),
            log: LogLevel::Off,
        }
    }
}

/// A session: one run of one mission, whatever connections carry it.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SessionKey {
    /// Mission name from `hello` (empty when absent).
    pub mission: String,
    /// Run id from `hello` (empty when absent).
    pub run: String,
}

/// A new session handed to the handler of [`serve`].
pub struct Session {
    pub key: SessionKey,
    /// The session id sent in `welcome`.
    pub id: String,
    /// Player software from the `hello` that opened it.
    pub player: Option<String>,
    /// Actions (each `seq` once, in order) and the way back for events,
    /// perceptions and, with [`AckMode::ByHandler`], acknowledgements.
    pub end: AacEnd,
}

type Handler = Box<dyn FnMut(Session) + Send>;

/// An AAC server: sessions and their connections.
pub struct Server {
    inner: Arc<ServerInner>,
}

struct ServerInner {
    opts: ServeOptions,
    sessions: Mutex<HashMap<SessionKey, Arc<SessionState>>>,
    handler: Mutex<Option<Handler>>,
    next_conn: AtomicU64,
}

struct SessionState {
    id: String,
    actions: mpsc::UnboundedSender<Action>,
    inner: Mutex<SessionInner>,
}

struct SessionInner {
    /// Highest seq handed to the handler.
    last_forwarded: u64,
    /// Highest seq acknowledged (executed).
    last_acked: u64,
    /// Highest event number given.
    last_event: u64,
    /// Events not yet confirmed by the player: (number, encoded line).
    outbox: VecDeque<(u64, String)>,
    /// Duplicates of actions still being executed: each is acknowledged
    /// once its action is (protocol §5).
    owed: Vec<u64>,
    conn: Option<ConnHandle>,
    handler_gone: bool,
    touched: Instant,
}

struct ConnHandle {
    id: u64,
    tx: mpsc::UnboundedSender<String>,
    kill: Arc<Notify>,
}

impl SessionInner {
    fn send(&self, line: String) {
        if let Some(c) = &self.conn {
            let _ = c.tx.send(line);
        }
    }

    fn trim(&mut self, upto: u64) {
        while self.outbox.front().is_some_and(|(n, _)| *n <= upto) {
            self.outbox.pop_front();
        }
    }
}

/// Accepts players on `listener` forever; `handler` receives each new session.
pub async fn serve<H>(listener: TcpListener, options: ServeOptions, handler: H)
where
    H: FnMut(Session) + Send + 'static,
{
    Server::new(options).run(listener, handler).await
}

impl Server {
    /// A server with no session yet.
    pub fn new(options: ServeOptions) -> Server {
        Server {
            inner: Arc::new(ServerInner {
                opts: options,
                sessions: Mutex::new(HashMap::new()),
                handler: Mutex::new(None),
                next_conn: AtomicU64::new(1),
            }),
        }
    }

    /// Declares a session known before this server started (restored from a
    /// state file): `id` is its session id, `last_seq` the highest seq it has
    /// executed. Returns its AAC end.
    pub fn restore(&self, key: SessionKey, id: String, last_seq: u64) -> AacEnd {
        let (state, end) = new_session(&self.inner, id, last_seq);
        lock(&self.inner.sessions).insert(key, state);
        end
    }

    /// Accepts players on `listener` forever; `handler` receives each new
    /// session (not the restored ones).
    pub async fn run<H>(self, listener: TcpListener, handler: H)
    where
        H: FnMut(Session) + Send + 'static,
    {
        *lock(&self.inner.handler) = Some(Box::new(handler));
        let who = "aac";
        if let Ok(a) = listener.local_addr() {
            log(self.inner.opts.log, LogLevel::Info, who, format_args!("listening on {a}"));
        }
        loop {
            match listener.accept().await {
                Ok((stream, peer)) => {
                    tokio::spawn(connection(self.inner.clone(), stream, peer));
                }
                Err(e) => {
                    // E.g. too many open files: wait and go on.
                    log(self.inner.opts.log, LogLevel::Info, who, format_args!("accept failed: {e}"));
                    sleep(Duration::from_millis(100)).await;
                }
            }
        }
    }
}

fn new_session(inner: &Arc<ServerInner>, id: String, last_seq: u64) -> (Arc<SessionState>, AacEnd) {
    let (link, end) = pair();
    let state = Arc::new(SessionState {
        id,
        actions: link.actions,
        inner: Mutex::new(SessionInner {
            last_forwarded: last_seq,
            last_acked: last_seq,
            last_event: 0,
            outbox: VecDeque::new(),
            owed: Vec::new(),
            conn: None,
            handler_gone: false,
            touched: Instant::now(),
        }),
    });
    tokio::spawn(pump(Arc::downgrade(&state), link.inbound, inner.opts.clone()));
    (state, end)
}

/// Carries what a session's handler sends to the session's connection.
async fn pump(session: Weak<SessionState>, mut rx: mpsc::UnboundedReceiver<Inbound>, opts: ServeOptions) {
    while let Some(item) = rx.recv().await {
        let Some(s) = session.upgrade() else { return };
        let mut g = lock(&s.inner);
        match item {
            Inbound::Event { event, activation, .. } => {
                g.last_event += 1;
                let n = g.last_event;
                let line = encode(&Message::Event(EventMsg { event, n: Some(n), activation }));
                g.send(line.clone());
                g.outbox.push_back((n, line));
            }
            Inbound::Perception { name, value, .. } => {
                g.last_event += 1;
                let n = g.last_event;
                let line = encode(&Message::Perception(PerceptionMsg { name, value, n: Some(n) }));
                g.send(line.clone());
                g.outbox.push_back((n, line));
            }
            Inbound::Ack { seq } => {
                if opts.ack == AckMode::ByHandler {
                    g.last_acked = g.last_acked.max(seq);
                    g.send(encode(&Message::Ack { seq }));
                    // Duplicates received while it was being executed.
                    let last = g.last_acked;
                    let owed: Vec<u64> = g.owed.iter().copied().filter(|&s| s <= last).collect();
                    g.owed.retain(|&s| s > last);
                    for s in owed {
                        g.send(encode(&Message::Ack { seq: s }));
                    }
                }
            }
            Inbound::Connected | Inbound::Disconnected | Inbound::Session { .. } | Inbound::Notice { .. } => {}
        }
        if g.outbox.len() > opts.max_outbox {
            let excess = g.outbox.len() - opts.max_outbox;
            g.outbox.drain(..excess);
        }
    }
    if let Some(s) = session.upgrade() {
        lock(&s.inner).handler_gone = true;
    }
}

/// Finds or creates the session of a `hello`; `true` if created.
fn session_for(inner: &Arc<ServerInner>, key: &SessionKey, player: Option<String>) -> (Arc<SessionState>, bool) {
    let mut sessions = lock(&inner.sessions);
    if let Some(s) = sessions.get(key) {
        return (s.clone(), false);
    }
    // Forget the least recently used idle sessions beyond the limit.
    while sessions.len() >= inner.opts.max_sessions.max(1) {
        let oldest = sessions
            .iter()
            .filter(|(_, s)| lock(&s.inner).conn.is_none())
            .min_by_key(|(_, s)| lock(&s.inner).touched)
            .map(|(k, _)| k.clone());
        match oldest {
            Some(k) => {
                sessions.remove(&k);
            }
            None => break,
        }
    }
    let (state, end) = new_session(inner, new_id(), 0);
    sessions.insert(key.clone(), state.clone());
    drop(sessions);
    let session = Session { key: key.clone(), id: state.id.clone(), player, end };
    match lock(&inner.handler).as_mut() {
        Some(h) => h(session),
        None => drop(session),
    }
    (state, true)
}

/// One player connection.
async fn connection(inner: Arc<ServerInner>, stream: TcpStream, peer: SocketAddr) {
    let opts = &inner.opts;
    let _ = stream.set_nodelay(true);
    let who = format!("aac {peer}");
    let lg = |need: LogLevel, msg: std::fmt::Arguments<'_>| log(opts.log, need, &who, msg);
    lg(LogLevel::Info, format_args!("connected"));
    let (rd, wr) = stream.into_split();
    let mut reader = LineReader::new(BufReader::new(rd), opts.max_line);
    let (tx, rx) = mpsc::unbounded_channel::<String>();
    let kill = Arc::new(Notify::new());
    let writer = tokio::spawn(write_loop(wr, rx, opts.timeout, opts.log, who.clone(), kill.clone()));
    let send = |m: &Message| {
        let _ = tx.send(encode(m));
    };
    let too_long = |n: usize| {
        let m = format!("line of {n} bytes exceeds the limit of {} bytes; discarded", opts.max_line);
        lg(LogLevel::Info, format_args!("{m}"));
        Message::error(ErrorCode::TooLong, m, None)
    };

    // Handshake.
    let deadline = Instant::now() + opts.timeout;
    let hello = loop {
        let line = match timeout_at(deadline, reader.next_line()).await {
            Err(_) => {
                send(&Message::error(ErrorCode::Timeout, "no hello", None));
                lg(LogLevel::Info, format_args!("no hello within {:?}; closing", opts.timeout));
                break None;
            }
            Ok(Err(_)) | Ok(Ok(Line::Eof)) => break None,
            Ok(Ok(Line::TooLong(n))) => {
                send(&too_long(n));
                continue;
            }
            Ok(Ok(Line::Text(t))) => t,
        };
        lg(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(&line), 300)));
        match parse(&line) {
            Ok(Message::Hello(h)) => break Some(h),
            Ok(Message::Error(e)) => lg(LogLevel::Info, format_args!("player reports ({}): {}", e.code, e.message)),
            Ok(other) => {
                let seq = if let Message::Action(a) = &other { Some(a.seq) } else { None };
                let m = format!("expected `hello` first, got `{}`", other.type_name());
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, seq));
            }
            Err(pe) => {
                lg(LogLevel::Info, format_args!("{pe}"));
                send(&pe.to_message());
            }
        }
    };
    let Some(hello) = hello else {
        drop(tx);
        let _ = writer.await;
        return;
    };
    if hello.version != VERSION {
        let m = format!("this AAC speaks protocol version {VERSION}, not {}", hello.version);
        lg(LogLevel::Info, format_args!("refused: {m}"));
        send(&Message::error(ErrorCode::Version, m, None));
        drop(tx);
        let _ = writer.await;
        return;
    }
    if let Some(expected) = &opts.token {
        if !token_matches(expected, hello.token.as_deref()) {
            let m = if hello.token.is_some() { "wrong token" } else { "this AAC requires a token" };
            lg(LogLevel::Info, format_args!("refused: {m}"));
            send(&Message::error(ErrorCode::Unauthorized, m, None));
            drop(tx);
            let _ = writer.await;
            return;
        }
    }
    // A `hello` without `run` names no run to resume: it opens a session of
    // its own, never one that an earlier run-less player left (whose seqs
    // would make this player's actions duplicates).
    let run = hello.run.clone().unwrap_or_else(|| format!("unnamed-{}", super::new_id()));
    let key = SessionKey { mission: hello.mission.clone().unwrap_or_default(), run };
    let (session, created) = session_for(&inner, &key, hello.player.clone());
    let conn_id = inner.next_conn.fetch_add(1, Ordering::Relaxed);
    {
        let mut g = lock(&session.inner);
        g.touched = Instant::now();
        if let Some(old) = g.conn.replace(ConnHandle { id: conn_id, tx: tx.clone(), kill: kill.clone() }) {
            let _ = old.tx.send(encode(&Message::error(
                ErrorCode::Replaced,
                "another connection took over this session",
                None,
            )));
            old.kill.notify_one();
        }
        let welcome = Welcome {
            version: VERSION,
            last_seq: g.last_acked,
            last_event: g.last_event,
            session: session.id.clone(),
            aac: Some(opts.name.clone()),
        };
        send(&Message::Welcome(welcome));
        // Re-send the events the player has not seen, if it tells which: all
        // of them if it names another session (it knew an older incarnation).
        if let Some(last) = hello.last_event {
            let from = match hello.session.as_deref() {
                Some(id) if id != session.id => 0,
                _ => last,
            };
            if from > 0 {
                g.trim(from);
            }
            for (_, line) in g.outbox.iter().filter(|(n, _)| *n > from) {
                let _ = tx.send(line.clone());
            }
        }
        lg(
            LogLevel::Info,
            format_args!(
                "{} session {} (mission `{}`, run `{}`, last seq {}, player {})",
                if created { "new" } else { "resumed" },
                session.id,
                key.mission,
                key.run,
                g.last_acked,
                hello.player.as_deref().unwrap_or("?")
            ),
        );
    }

    // Session.
    let mut last_heard = Instant::now();
    loop {
        let silence = last_heard + opts.timeout;
        let line = tokio::select! {
            _ = kill.notified() => {
                lg(LogLevel::Info, format_args!("closing (replaced by another connection, or the player stopped reading)"));
                break;
            }
            r = timeout_at(silence, reader.next_line()) => r,
        };
        last_heard = Instant::now();
        let line = match line {
            Err(_) => {
                let m = format!("no message for {:?}", opts.timeout);
                lg(LogLevel::Info, format_args!("{m}; closing"));
                send(&Message::error(ErrorCode::Timeout, m, None));
                break;
            }
            Ok(Err(_)) | Ok(Ok(Line::Eof)) => break,
            Ok(Ok(Line::TooLong(n))) => {
                send(&too_long(n));
                continue;
            }
            Ok(Ok(Line::Text(t))) => t,
        };
        lg(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(&line), 300)));
        match parse(&line) {
            Ok(Message::Action(a)) => {
                if let Some(reply) = on_action(&session, opts, a, &lg) {
                    send(&reply);
                }
            }
            Ok(Message::Ping(p)) => {
                let mut g = lock(&session.inner);
                if let Some(n) = p.last_event {
                    g.trim(n);
                }
                g.touched = Instant::now();
                drop(g);
                send(&Message::Pong {});
            }
            Ok(Message::Pong {}) => {}
            Ok(Message::Error(e)) => {
                lg(LogLevel::Info, format_args!("player reports an error ({}): {}", e.code, truncate(&e.message, 200)))
            }
            Ok(Message::Hello(_)) => {
                let m = "already in a session: `hello` is only the first message";
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, None));
            }
            Ok(other) => {
                let m = format!("an AAC does not accept `{}`", other.type_name());
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, None));
            }
            Err(pe) => {
                lg(LogLevel::Info, format_args!("{pe}"));
                send(&pe.to_message());
            }
        }
    }
    {
        let mut g = lock(&session.inner);
        if g.conn.as_ref().is_some_and(|c| c.id == conn_id) {
            g.conn = None;
        }
        g.touched = Instant::now();
    }
    lg(LogLevel::Info, format_args!("disconnected"));
    drop(tx);
    let _ = writer.await;
}

/// An action of an established session; returns the immediate reply.
fn on_action(
    session: &SessionState,
    opts: &ServeOptions,
    a: ActionMsg,
    lg: &dyn Fn(LogLevel, std::fmt::Arguments<'_>),
) -> Option<Message> {
    let seq = a.seq;
    let mut g = lock(&session.inner);
    g.touched = Instant::now();
    if seq <= g.last_acked {
        lg(LogLevel::Info, format_args!("duplicate action seq {seq} (already executed): acknowledged, not executed"));
        return Some(Message::Ack { seq });
    }
    if seq <= g.last_forwarded {
        lg(
            LogLevel::Info,
            format_args!("duplicate action seq {seq} (being executed): not executed again, acknowledged once executed"),
        );
        g.owed.push(seq);
        return None;
    }
    if g.handler_gone || session.actions.send(a.into()).is_err() {
        g.handler_gone = true;
        let m = "this AAC cannot execute actions of this session any more";
        lg(LogLevel::Info, format_args!("seq {seq}: {m}"));
        return Some(Message::error(ErrorCode::Unavailable, m, Some(seq)));
    }
    g.last_forwarded = seq;
    if opts.ack == AckMode::OnReceipt {
        g.last_acked = seq;
        return Some(Message::Ack { seq });
    }
    None
}

async fn write_loop(
    mut wr: OwnedWriteHalf,
    mut rx: mpsc::UnboundedReceiver<String>,
    limit: Duration,
    level: LogLevel,
    who: String,
    kill: Arc<Notify>,
) {
    let mut batch = String::new();
    while let Some(line) = rx.recv().await {
        batch.clear();
        batch.push_str(&line);
        while let Ok(more) = rx.try_recv() {
            batch.push_str(&more);
            if batch.len() > 256 * 1024 {
                break;
            }
        }
        if level >= LogLevel::Messages {
            for l in batch.lines() {
                log(level, LogLevel::Messages, &who, format_args!("-> {}", truncate(l, 300)));
            }
        }
        match timeout(limit, wr.write_all(batch.as_bytes())).await {
            Ok(Ok(())) => {}
            _ => {
                log(level, LogLevel::Info, &who, format_args!("write failed or timed out; dropping the connection"));
                kill.notify_one();
                return;
            }
        }
    }
    let _ = wr.shutdown().await;
}
