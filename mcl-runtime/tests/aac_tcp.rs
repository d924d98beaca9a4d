//! The AAC protocol over loopback TCP, in process: handshake, refusals,
//! malformed input, duplicates, heartbeats, and connections cut under a
//! player (through a proxy that can be cut) without losing or repeating.

use std::collections::BTreeSet;
use std::time::Duration;

use mcl_runtime::link::{Action, Delivered, Inbound};
use mcl_runtime::protocol::{Line, LineReader};
use mcl_runtime::tcp::{self, connect_with_handle, serve, AckMode, ConnectOptions, LinkError, ServeOptions, Session};
use serde_json::{json, Value};
use tokio::io::{AsyncWriteExt, BufReader};
use tokio::net::tcp::OwnedWriteHalf;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::mpsc;
use tokio::time::timeout;

const T: Duration = Duration::from_secs(10);

fn action(seq: u64, name: &str) -> Action {
    Action {
        seq,
        action: name.into(),
        primitive: "GotoPrimitive".into(),
        command: "enable".into(),
        params: Default::default(),
        task: Some("Goto".into()),
        call_site: Some(1),
    }
}

/// A raw client speaking JSON lines.
struct Raw {
    rd: LineReader<BufReader<tokio::net::tcp::OwnedReadHalf>>,
    wr: OwnedWriteHalf,
}

impl Raw {
    async fn connect(addr: std::net::SocketAddr) -> Raw {
        Raw::of(TcpStream::connect(addr).await.unwrap())
    }

    fn of(s: TcpStream) -> Raw {
        let (rd, wr) = s.into_split();
        Raw { rd: LineReader::new(BufReader::new(rd), 1 << 20), wr }
    }

    /// The next message that is not a `ping`.
    async fn recv_no_ping(&mut self) -> Option<Value> {
        loop {
            let m = self.recv().await?;
            if m["type"] != "ping" {
                return Some(m);
            }
        }
    }

    /// The `last_event` of the next `ping`.
    async fn next_ping(&mut self) -> Value {
        loop {
            let m = self.recv().await.expect("closed");
            if m["type"] == "ping" {
                return m["last_event"].clone();
            }
        }
    }

    async fn send_raw(&mut self, bytes: &[u8]) {
        self.wr.write_all(bytes).await.unwrap();
    }

    async fn send(&mut self, v: Value) {
        let mut s = v.to_string();
        s.push('\n');
        self.send_raw(s.as_bytes()).await;
    }

    /// The next message, or None at the end of the stream.
    async fn recv(&mut self) -> Option<Value> {
        match timeout(T, self.rd.next_line()).await.expect("no message within 10 s").unwrap() {
            Line::Text(t) => Some(serde_json::from_slice(&t).unwrap()),
            Line::TooLong(n) => panic!("too long: {n}"),
            Line::Eof => None,
        }
    }

    async fn hello(&mut self, extra: Value) -> Value {
        let mut h = json!({"type":"hello","version":1,"player":"test","mission":"m","run":"r"});
        for (k, v) in extra.as_object().unwrap() {
            h[k] = v.clone();
        }
        self.send(h).await;
        self.recv().await.expect("closed after hello")
    }
}

/// The next inbound item of a player link that is not a notice; the
/// notices skipped are pushed on `notices`.
async fn next_item(link: &mut mcl_runtime::link::Link, notices: &mut Vec<String>) -> Option<Inbound> {
    loop {
        match timeout(T, link.inbound.recv()).await.expect("nothing from the link within 10 s") {
            Some(Inbound::Notice { message }) => notices.push(message),
            // The session a welcome names: told before `Connected`.
            Some(Inbound::Session { id, restarted }) => notices.push(format!("session {id} restarted={restarted}")),
            other => return other,
        }
    }
}

/// A server whose handler forwards every session to the test.
async fn server(opts: ServeOptions) -> (std::net::SocketAddr, mpsc::UnboundedReceiver<Session>) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = mpsc::unbounded_channel();
    tokio::spawn(serve(listener, opts, move |s| {
        let _ = tx.send(s);
    }));
    (addr, rx)
}

#[tokio::test]
async fn handshake_and_version_mismatch() {
    let (addr, mut sessions) = server(ServeOptions::default()).await;
    let mut c = Raw::connect(addr).await;
    let w = c.hello(json!({})).await;
    assert_eq!(w["type"], "welcome", "{w}");
    assert_eq!((w["version"].as_u64(), w["last_seq"].as_u64(), w["last_event"].as_u64()), (Some(1), Some(0), Some(0)));
    assert!(!w["session"].as_str().unwrap().is_empty());
    let s = timeout(T, sessions.recv()).await.unwrap().unwrap();
    assert_eq!((s.key.mission.as_str(), s.key.run.as_str(), s.player.as_deref()), ("m", "r", Some("test")));
    c.send(json!({"type":"ping"})).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"pong"}));

    let mut c = Raw::connect(addr).await;
    let e = c.hello(json!({"version": 2})).await;
    assert_eq!((e["type"].as_str(), e["code"].as_str()), (Some("error"), Some("version")), "{e}");
    assert_eq!(c.recv().await, None, "the AAC closes after a version error");

    // A minimal hello (no mission, no run, unknown fields) is welcome.
    let mut c = Raw::connect(addr).await;
    c.send(json!({"type":"hello","version":1,"future_field":{"x":1}})).await;
    assert_eq!(c.recv().await.unwrap()["type"], "welcome");
}

#[tokio::test]
async fn token_refusal() {
    let opts = ServeOptions { token: Some("s3cret".into()), ..ServeOptions::default() };
    let (addr, mut sessions) = server(opts).await;
    for extra in [json!({}), json!({"token":"wrong"}), json!({"token":"s3cre"})] {
        let mut c = Raw::connect(addr).await;
        let e = c.hello(extra.clone()).await;
        assert_eq!((e["type"].as_str(), e["code"].as_str()), (Some("error"), Some("unauthorized")), "{extra}: {e}");
        assert_eq!(c.recv().await, None);
    }
    assert!(sessions.try_recv().is_err(), "a refused player opens no session");
    let mut c = Raw::connect(addr).await;
    assert_eq!(c.hello(json!({"token":"s3cret"})).await["type"], "welcome");

    // Through tcp::connect: the task ends with Refused and the link closes.
    let (mut link, handle) = connect_with_handle(
        addr.to_string(),
        ConnectOptions { token: Some("nope".into()), ..ConnectOptions::default() },
    );
    let mut notices = Vec::new();
    assert_eq!(next_item(&mut link, &mut notices).await, None);
    let r = timeout(T, handle).await.unwrap().unwrap();
    assert!(matches!(&r, Err(LinkError::Refused { code, .. }) if code == "unauthorized"), "{r:?}");
    // The player was told why.
    assert!(notices.iter().any(|n| n.contains("unauthorized") && n.contains("giving up")), "{notices:?}");
}

#[tokio::test]
async fn long_lines_and_malformed_messages_get_errors_and_the_session_survives() {
    let (addr, mut sessions) = server(ServeOptions::default()).await;
    let mut c = Raw::connect(addr).await;
    // Before hello: errors, and the connection stays open.
    c.send_raw(b"{oops\n").await;
    assert_eq!(c.recv().await.unwrap()["code"], "malformed");
    c.send(json!({"type":"action","seq":1,"action":"a","primitive":"p","command":"enable"})).await;
    let e = c.recv().await.unwrap();
    assert_eq!((e["code"].as_str(), e["seq"].as_u64()), (Some("unexpected"), Some(1)), "{e}");
    assert_eq!(c.hello(json!({})).await["type"], "welcome");
    let mut s = timeout(T, sessions.recv()).await.unwrap().unwrap();

    // A line over 64 KiB, sent in pieces.
    let big = format!("{{\"type\":\"ping\",\"pad\":\"{}\"}}\n", "x".repeat(70_000));
    for chunk in big.as_bytes().chunks(8192) {
        c.send_raw(chunk).await;
    }
    let e = c.recv().await.unwrap();
    assert_eq!((e["type"].as_str(), e["code"].as_str()), (Some("error"), Some("too_long")), "{e}");
    // Exactly at the limit is fine.
    let pad = 64 * 1024 - r#"{"type":"ping","pad":""}"#.len();
    c.send_raw(format!("{{\"type\":\"ping\",\"pad\":\"{}\"}}\n", "y".repeat(pad)).as_bytes()).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"pong"}));

    for (line, code) in [
        (&b"not json at all\n"[..], "malformed"),
        (b"[1,2,3]\n", "malformed"),
        (b"{\"no\":\"type\"}\n", "malformed"),
        (b"{\"type\":\"teleport\"}\n", "unknown_type"),
        (b"{\"type\":\"action\",\"seq\":\"one\"}\n", "malformed"),
        (b"{\"type\":\"event\",\"event\":\"x\"}\n", "unexpected"),
        (b"{\"type\":\"hello\",\"version\":1}\n", "unexpected"),
        (b"\xff\xfe\n", "malformed"),
    ] {
        c.send_raw(line).await;
        let e = c.recv().await.unwrap();
        assert_eq!((e["type"].as_str(), e["code"].as_str()), (Some("error"), Some(code)), "{line:?}: {e}");
        assert!(!e["message"].as_str().unwrap().is_empty());
    }
    let e = {
        c.send(json!({"type":"action","seq":4,"action":"a"})).await;
        c.recv().await.unwrap()
    };
    assert_eq!((e["code"].as_str(), e["seq"].as_u64()), (Some("malformed"), Some(4)), "{e}");
    // Empty lines and CRLF are tolerated; the session still works.
    c.send_raw(b"\r\n{\"type\":\"ping\"}\r\n").await;
    // (the empty line is a malformed message, answered as such)
    let first = c.recv().await.unwrap();
    assert_eq!(first["code"], "malformed", "{first}");
    assert_eq!(c.recv().await.unwrap(), json!({"type":"pong"}));
    c.send(json!({"type":"action","seq":1,"action":"go","primitive":"P","command":"enable","params":{"x":1}})).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":1}));
    let a = timeout(T, s.end.actions.recv()).await.unwrap().unwrap();
    assert_eq!((a.seq, a.action.as_str(), a.params["x"].as_i64()), (1, "go", Some(1)));
}

#[tokio::test]
async fn duplicates_are_acknowledged_not_executed() {
    let (addr, mut sessions) = server(ServeOptions::default()).await;
    let mut c = Raw::connect(addr).await;
    c.hello(json!({})).await;
    let mut s = timeout(T, sessions.recv()).await.unwrap().unwrap();
    let act = |seq: u64| json!({"type":"action","seq":seq,"action":"a","primitive":"p","command":"enable"});
    for seq in [1, 2, 2, 1, 3, 3, 5, 4] {
        c.send(act(seq)).await;
        assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":seq}));
    }
    let mut got = Vec::new();
    while let Ok(a) = s.end.actions.try_recv() {
        got.push(a.seq);
    }
    assert_eq!(got, [1, 2, 3, 5], "each seq once; a lower seq after a higher one is a duplicate");

    // A reconnection of the same run resumes the session: last_seq = 5.
    drop(c);
    let mut c = Raw::connect(addr).await;
    let w = c.hello(json!({})).await;
    assert_eq!(w["last_seq"], 5, "{w}");
    c.send(act(5)).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":5}));
    c.send(act(6)).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":6}));
    assert_eq!(timeout(T, s.end.actions.recv()).await.unwrap().unwrap().seq, 6);
    assert!(sessions.try_recv().is_err(), "same run, same session");

    // Another run is another session, numbered from scratch.
    let mut c = Raw::connect(addr).await;
    let w = c.hello(json!({"run":"r2"})).await;
    assert_eq!(w["last_seq"], 0);
    assert!(timeout(T, sessions.recv()).await.unwrap().is_some());

    // A hello without `run` resumes nothing: each opens a new session,
    // even after a run-less player's actions (docs/aac-protocol.md §2).
    let mut ids = Vec::new();
    for _ in 0..2 {
        let mut c = Raw::connect(addr).await;
        let w = c.hello(json!({"run": null})).await;
        assert_eq!(w["last_seq"], 0, "{w}");
        ids.push(w["session"].clone());
        c.send(act(1)).await;
        assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":1}));
        let mut s = timeout(T, sessions.recv()).await.unwrap().unwrap();
        assert_eq!(timeout(T, s.end.actions.recv()).await.unwrap().unwrap().seq, 1, "executed, not a duplicate");
    }
    assert_ne!(ids[0], ids[1]);
}

#[tokio::test]
async fn ack_by_handler_and_events_numbered_and_replayed() {
    let opts = ServeOptions { ack: AckMode::ByHandler, ..ServeOptions::default() };
    let (addr, mut sessions) = server(opts).await;
    let mut c = Raw::connect(addr).await;
    let w = c.hello(json!({})).await;
    let sid = w["session"].as_str().unwrap().to_string();
    let mut s = timeout(T, sessions.recv()).await.unwrap().unwrap();
    c.send(json!({"type":"action","seq":1,"action":"a","primitive":"p","command":"enable"})).await;
    let a = timeout(T, s.end.actions.recv()).await.unwrap().unwrap();
    // In progress: a duplicate is not executed again, and gets its ack once
    // the action is executed (protocol §5: dropped but acknowledged).
    c.send(json!({"type":"action","seq":1,"action":"a","primitive":"p","command":"enable"})).await;
    c.send(json!({"type":"ping"})).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"pong"}));
    s.end.inbound.send(Inbound::Event { event: "e1".into(), activation: Some(1), n: None }).unwrap();
    s.end.inbound.send(Inbound::Ack { seq: a.seq }).unwrap();
    s.end.inbound.send(Inbound::Perception { name: "depth".into(), value: json!(3.5), n: None }).unwrap();
    assert_eq!(c.recv().await.unwrap(), json!({"type":"event","event":"e1","n":1,"activation":1}));
    assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":1}));
    assert_eq!(c.recv().await.unwrap(), json!({"type":"ack","seq":1}), "the duplicate's ack");
    assert_eq!(c.recv().await.unwrap(), json!({"type":"perception","name":"depth","value":3.5,"n":2}));
    assert!(s.end.actions.try_recv().is_err(), "executed once");
    drop(c);
    // Events while nobody is connected are kept…
    tokio::time::sleep(Duration::from_millis(50)).await;
    s.end.inbound.send(Inbound::Event { event: "e3".into(), activation: None, n: None }).unwrap();
    // …and re-sent to a player naming the session, after its last event.
    let mut c = Raw::connect(addr).await;
    let w = c.hello(json!({"session": sid, "last_event": 1})).await;
    assert_eq!((w["last_seq"].as_u64(), w["last_event"].as_u64()), (Some(1), Some(3)), "{w}");
    assert_eq!(c.recv().await.unwrap()["n"], 2);
    assert_eq!(c.recv().await.unwrap(), json!({"type":"event","event":"e3","n":3}));
    // A ping confirms up to 3; a later reconnection re-sends nothing.
    c.send(json!({"type":"ping","last_event":3})).await;
    assert_eq!(c.recv().await.unwrap(), json!({"type":"pong"}));
    let mut c2 = Raw::connect(addr).await;
    let w = c2.hello(json!({"session": sid, "last_event": 0})).await;
    assert_eq!(w["type"], "welcome");
    // The first connection is told it was replaced, then closed.
    let e = c.recv().await.unwrap();
    assert_eq!(e["code"], "replaced", "{e}");
    assert_eq!(c.recv().await, None);
    c2.send(json!({"type":"ping"})).await;
    assert_eq!(c2.recv().await.unwrap(), json!({"type":"pong"}), "nothing re-sent");
    s.end.inbound.send(Inbound::Event { event: "e4".into(), activation: None, n: None }).unwrap();
    assert_eq!(c2.recv().await.unwrap()["n"], 4);
    drop(c2);
    tokio::time::sleep(Duration::from_millis(50)).await;
    s.end.inbound.send(Inbound::Event { event: "e5".into(), activation: None, n: None }).unwrap();
    // Without `last_event`, nothing is re-sent…
    let mut c3 = Raw::connect(addr).await;
    assert_eq!(c3.hello(json!({})).await["last_event"], 5);
    c3.send(json!({"type":"ping"})).await;
    assert_eq!(c3.recv().await.unwrap(), json!({"type":"pong"}));
    drop(c3);
    // …naming an older session, every event held (4 and 5: 1..3 were
    // confirmed by a ping)…
    let mut c4 = Raw::connect(addr).await;
    c4.hello(json!({"session": "older", "last_event": 4})).await;
    assert_eq!(c4.recv().await.unwrap()["n"], 4);
    assert_eq!(c4.recv().await.unwrap()["n"], 5);
    drop(c4);
    // …with `last_event` and no session (a player resumed from its journal),
    // the events after it.
    let mut c5 = Raw::connect(addr).await;
    c5.hello(json!({"last_event": 4})).await;
    assert_eq!(c5.recv().await.unwrap()["n"], 5);
    c5.send(json!({"type":"ping"})).await;
    assert_eq!(c5.recv().await.unwrap(), json!({"type":"pong"}));
}

#[tokio::test]
async fn silent_player_is_dropped_and_player_detects_silent_aac() {
    let opts = ServeOptions { timeout: Duration::from_millis(300), ..ServeOptions::default() };
    let (addr, _sessions) = server(opts).await;
    let mut c = Raw::connect(addr).await;
    assert_eq!(c.hello(json!({})).await["type"], "welcome");
    let e = c.recv().await.unwrap();
    assert_eq!(e["code"], "timeout", "{e}");
    assert_eq!(c.recv().await, None);

    // An "AAC" that welcomes and then says nothing: the link reports
    // Disconnected after the timeout, then reconnects.
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    tokio::spawn(async move {
        let mut keep = Vec::new();
        loop {
            let (s, _) = listener.accept().await.unwrap();
            let (rd, mut wr) = s.into_split();
            wr.write_all(b"{\"type\":\"welcome\",\"version\":1,\"last_seq\":0,\"session\":\"x\"}\n").await.unwrap();
            keep.push((rd, wr));
        }
    });
    let opts = ConnectOptions {
        timeout: Duration::from_millis(300),
        ping_interval: Duration::from_millis(100),
        backoff_min: Duration::from_millis(10),
        ..ConnectOptions::default()
    };
    let (mut link, _h) = connect_with_handle(addr.to_string(), opts);
    let mut seen = Vec::new();
    let mut notices = Vec::new();
    while seen.len() < 3 {
        seen.push(next_item(&mut link, &mut notices).await.unwrap());
    }
    assert_eq!(seen, [Inbound::Connected, Inbound::Disconnected, Inbound::Connected]);
    assert!(notices.iter().any(|n| n.starts_with("disconnected:") && n.contains("no message for")), "{notices:?}");
}

/// A TCP proxy that can cut every connection through it.
struct Proxy {
    addr: std::net::SocketAddr,
    cut: tokio::sync::watch::Sender<u64>,
}

impl Proxy {
    async fn start(target: std::net::SocketAddr) -> Proxy {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let (cut, cut_rx) = tokio::sync::watch::channel(0u64);
        tokio::spawn(async move {
            loop {
                let (a, _) = listener.accept().await.unwrap();
                let Ok(b) = TcpStream::connect(target).await else { continue };
                let mut cut_rx = cut_rx.clone();
                cut_rx.borrow_and_update();
                tokio::spawn(async move {
                    let (mut a, mut b) = (a, b);
                    tokio::select! {
                        _ = tokio::io::copy_bidirectional(&mut a, &mut b) => {}
                        _ = cut_rx.changed() => {}
                    }
                });
            }
        });
        Proxy { addr, cut }
    }

    fn cut(&self) {
        self.cut.send_modify(|n| *n += 1);
    }
}

/// A player and an AAC that answers each action with an event, through a
/// proxy cut again and again: every action executed once, every event
/// delivered once, in order.
#[tokio::test]
async fn cut_connections_lose_and_repeat_nothing() {
    let (addr, mut sessions) = server(ServeOptions::default()).await;
    let proxy = Proxy::start(addr).await;
    let executed = std::sync::Arc::new(std::sync::Mutex::new(Vec::<u64>::new()));
    let ex = executed.clone();
    tokio::spawn(async move {
        while let Some(mut s) = sessions.recv().await {
            let ex = ex.clone();
            tokio::spawn(async move {
                while let Some(a) = s.end.actions.recv().await {
                    ex.lock().unwrap().push(a.seq);
                    let _ = s.end.inbound.send(Inbound::Event {
                        event: format!("done{}", a.seq),
                        activation: Some(a.seq),
                        n: None,
                    });
                }
            });
        }
    });
    let opts = ConnectOptions {
        mission: "cut".into(),
        backoff_min: Duration::from_millis(5),
        backoff_max: Duration::from_millis(50),
        ping_interval: Duration::from_millis(50),
        ..ConnectOptions::default()
    };
    let (mut link, handle) = connect_with_handle(proxy.addr.to_string(), opts);
    const N: u64 = 200;
    let mut events = Vec::new();
    let mut acks = BTreeSet::new();
    let (mut connected, mut disconnected) = (0, 0);
    let mut next = 1;
    let mut cuts = 0;
    let deadline = tokio::time::Instant::now() + Duration::from_secs(30);
    while events.len() < N as usize {
        assert!(tokio::time::Instant::now() < deadline, "timed out with {} events", events.len());
        // At most 5 actions in flight, so that cuts fall in the middle of the traffic.
        while next <= N && next - 1 - (events.len() as u64) < 5 {
            link.actions.send(action(next, "go")).unwrap();
            next += 1;
        }
        if events.len() >= (cuts + 1) * 25 {
            cuts += 1;
            proxy.cut();
        }
        match timeout(Duration::from_millis(20), link.inbound.recv()).await {
            Ok(Some(Inbound::Event { event, activation, .. })) => {
                assert_eq!(
                    Some(format!("done{}", activation.unwrap())),
                    Some(event.clone()),
                    "the activation crosses the wire"
                );
                events.push(event)
            }
            Ok(Some(Inbound::Notice { .. } | Inbound::Session { .. })) => {}
            Ok(Some(Inbound::Ack { seq })) => assert!(acks.insert(seq), "ack {seq} twice"),
            Ok(Some(Inbound::Connected)) => connected += 1,
            Ok(Some(Inbound::Disconnected)) => disconnected += 1,
            Ok(Some(other)) => panic!("{other:?}"),
            Ok(None) => panic!("link closed"),
            Err(_) => {}
        }
    }
    let want: Vec<String> = (1..=N).map(|i| format!("done{i}")).collect();
    assert_eq!(events, want, "each event once, in order");
    assert_eq!(*executed.lock().unwrap(), (1..=N).collect::<Vec<_>>(), "each action once, in order");
    assert!(
        disconnected >= 3 && connected == disconnected + 1,
        "{cuts} cuts: connected {connected}, disconnected {disconnected}"
    );
    drop(link.actions);
    // Drain remaining acks; the link ends once everything is acknowledged.
    while let Ok(Some(ib)) = timeout(T, link.inbound.recv()).await {
        if let Inbound::Ack { seq } = ib {
            assert!(acks.insert(seq));
        }
    }
    let stats = timeout(T, handle).await.unwrap().unwrap().unwrap();
    assert_eq!(acks.len() as u64, N);
    assert!(stats.connections >= 4, "{stats:?}");
    assert_eq!(stats.last_event, N);
}

/// The link keeps actions while the AAC is down and sends them once it is up.
#[tokio::test]
async fn actions_wait_for_a_late_aac() {
    let probe = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = probe.local_addr().unwrap();
    drop(probe);
    let opts = ConnectOptions {
        backoff_min: Duration::from_millis(10),
        backoff_max: Duration::from_millis(80),
        ..ConnectOptions::default()
    };
    let (mut link, handle) = connect_with_handle(addr.to_string(), opts);
    for i in 1..=3 {
        link.actions.send(action(i, "a")).unwrap();
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    let listener = TcpListener::bind(addr).await.unwrap();
    let (tx, mut sessions) = mpsc::unbounded_channel();
    tokio::spawn(tcp::serve(listener, ServeOptions::default(), move |s| {
        let _ = tx.send(s);
    }));
    let mut notices = Vec::new();
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Connected));
    // Each failed attempt was told, with its backoff and the queued actions.
    let attempts: Vec<&String> = notices.iter().filter(|n| n.contains("cannot connect")).collect();
    assert!(attempts.len() >= 2, "{notices:?}");
    assert!(attempts.iter().all(|n| n.contains("retrying in")), "{notices:?}");
    assert!(attempts.last().unwrap().contains("3 actions queued"), "{notices:?}");
    assert!(notices.last().unwrap().contains("3 actions to send"), "{notices:?}");
    let mut s = timeout(T, sessions.recv()).await.unwrap().unwrap();
    for i in 1..=3 {
        assert_eq!(timeout(T, s.end.actions.recv()).await.unwrap().unwrap().seq, i);
        assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Ack { seq: i }));
    }
    drop(link.actions);
    let stats = timeout(T, handle).await.unwrap().unwrap().unwrap();
    assert_eq!(stats.connections, 1);
}

/// A player that never reached its AAC does not linger when it stops: its
/// actions were never sent, and it says so at once.
#[tokio::test]
async fn no_linger_when_the_aac_was_never_reached() {
    let probe = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = probe.local_addr().unwrap();
    drop(probe);
    let opts = ConnectOptions {
        backoff_min: Duration::from_millis(10),
        backoff_max: Duration::from_millis(20),
        linger: Duration::from_secs(3600),
        ..ConnectOptions::default()
    };
    let (link, handle) = connect_with_handle(addr.to_string(), opts);
    link.actions.send(action(1, "a")).unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    let mcl_runtime::link::Link { actions, inbound } = link;
    drop(actions);
    // Within T, not the hour of linger.
    let r = timeout(T, handle).await.expect("the link lingered").unwrap();
    assert_eq!(r, Err(LinkError::NeverConnected(vec![1])));
    assert!(r.unwrap_err().to_string().contains("never sent"));
    drop(inbound);
}

/// The player side answers garbage from the AAC with errors, never crashes,
/// drops duplicate events and keeps the session.
#[tokio::test]
async fn player_side_survives_a_garbage_aac() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, mut replies) = mpsc::unbounded_channel::<Value>();
    tokio::spawn(async move {
        let (s, _) = listener.accept().await.unwrap();
        let (rd, mut wr) = s.into_split();
        let mut rd = LineReader::new(BufReader::new(rd), 1 << 20);
        let Line::Text(hello) = rd.next_line().await.unwrap() else { panic!() };
        let hello: Value = serde_json::from_slice(&hello).unwrap();
        assert_eq!(hello["type"], "hello");
        wr.write_all(b"{\"type\":\"welcome\",\"version\":1,\"last_seq\":0,\"session\":\"s\"}\n").await.unwrap();
        wr.write_all(b"garbage\n[]\n{\"type\":\"launch\"}\n{\"type\":\"action\",\"seq\":1}\n").await.unwrap();
        wr.write_all(format!("{{\"type\":\"event\",\"event\":\"{}\"}}\n", "x".repeat(70_000)).as_bytes())
            .await
            .unwrap();
        wr.write_all(b"{\"type\":\"event\",\"event\":\"e1\",\"n\":1}\n{\"type\":\"event\",\"event\":\"e1\",\"n\":1}\n")
            .await
            .unwrap();
        wr.write_all(b"{\"type\":\"ping\"}\n{\"type\":\"error\",\"code\":\"malformed\",\"message\":\"x\"}\n")
            .await
            .unwrap();
        wr.write_all(b"{\"type\":\"perception\",\"name\":\"depth\",\"value\":[1,2],\"n\":2}\n").await.unwrap();
        wr.write_all(b"{\"type\":\"event\",\"event\":\"e9\",\"n\":5,\"activation\":4}\n").await.unwrap();
        while let Line::Text(t) = rd.next_line().await.unwrap() {
            let v: Value = serde_json::from_slice(&t).unwrap();
            if v["type"] != "ping" {
                let _ = tx.send(v);
            }
        }
    });
    let (mut link, _h) = connect_with_handle(addr.to_string(), ConnectOptions::default());
    let mut notices = Vec::new();
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Connected));
    assert_eq!(
        next_item(&mut link, &mut notices).await,
        Some(Inbound::Event { event: "e1".into(), activation: None, n: Some(1) })
    );
    assert_eq!(
        next_item(&mut link, &mut notices).await,
        Some(Inbound::Perception { name: "depth".into(), value: json!([1, 2]), n: Some(2) })
    );
    assert_eq!(
        next_item(&mut link, &mut notices).await,
        Some(Inbound::Event { event: "e9".into(), activation: Some(4), n: Some(5) })
    );
    // The player is told of every bad message, the duplicate, the gap and the AAC's error.
    let told = |what: &str| notices.iter().filter(|n| n.contains(what)).count();
    assert_eq!(told("sent a bad message"), 4, "{notices:?}");
    assert_eq!(told("gap in the event numbers: events #3..#4 never arrived"), 1, "{notices:?}");
    assert_eq!(told("exceeds the limit"), 1, "{notices:?}");
    assert_eq!(told("dropped event #1: already received"), 1, "{notices:?}");
    assert_eq!(told("the AAC reports an error (malformed): x"), 1, "{notices:?}");
    let mut codes = Vec::new();
    while codes.len() < 6 {
        let v = timeout(T, replies.recv()).await.unwrap().unwrap();
        codes.push(v["code"].as_str().unwrap_or_else(|| v["type"].as_str().unwrap()).to_string());
    }
    assert_eq!(codes, ["malformed", "malformed", "unknown_type", "malformed", "too_long", "pong"]);
    // An error from the AAC gets no reply; nothing else came.
    assert!(timeout(Duration::from_millis(200), replies.recv()).await.is_err());
}

/// A player that confirms what it handled ([`Delivered`], as `mcl run`
/// does once events are journaled): its `hello` resumes at the session and
/// event it names, its pings confirm only what it handled (not what the
/// link received), and when the AAC comes back with another session (it
/// lost its memory) the actions not acknowledged are dropped, not re-sent:
/// the player re-establishes what runs.
#[tokio::test]
async fn a_player_that_confirms_resumes_where_it_stands() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let delivered = Delivered::new(Some("s1".into()), 2);
    let opts = ConnectOptions {
        delivered: Some(delivered.clone()),
        reestablish: true,
        ping_interval: Duration::from_millis(30),
        backoff_min: Duration::from_millis(10),
        ..ConnectOptions::default()
    };
    let (mut link, _h) = connect_with_handle(addr.to_string(), opts);
    link.actions.send(action(3, "a")).unwrap();
    let mut aac = Raw::of(listener.accept().await.unwrap().0);
    let hello = aac.recv().await.unwrap();
    assert_eq!((hello["session"].as_str(), hello["last_event"].as_u64()), (Some("s1"), Some(2)), "{hello}");
    aac.send(json!({"type":"welcome","version":1,"last_seq":2,"last_event":4,"session":"s1"})).await;
    assert_eq!(aac.recv_no_ping().await.unwrap()["seq"], 3);
    aac.send(json!({"type":"ack","seq":3})).await;
    aac.send(json!({"type":"event","event":"e3","n":3})).await;
    aac.send(json!({"type":"event","event":"e4","n":4})).await;
    let mut notices = Vec::new();
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Connected));
    assert!(notices.iter().any(|n| n == "session s1 restarted=false"), "{notices:?}");
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Ack { seq: 3 }));
    for n in [3, 4] {
        let Some(Inbound::Event { n: got, .. }) = next_item(&mut link, &mut notices).await else { panic!() };
        assert_eq!(got, Some(n));
    }
    // Received, not handled yet: the AAC must keep them.
    assert_eq!(aac.next_ping().await, 2);
    aac.next_ping().await;
    delivered.set("s1", 4);
    aac.next_ping().await;
    assert_eq!(aac.next_ping().await, 4);
    // The AAC restarts without its state.
    drop(aac);
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Disconnected));
    link.actions.send(action(5, "b")).unwrap();
    let mut aac = Raw::of(listener.accept().await.unwrap().0);
    let hello = aac.recv().await.unwrap();
    assert_eq!((hello["session"].as_str(), hello["last_event"].as_u64()), (Some("s1"), Some(4)), "{hello}");
    aac.send(json!({"type":"welcome","version":1,"last_seq":0,"last_event":0,"session":"s2"})).await;
    assert_eq!(next_item(&mut link, &mut notices).await, Some(Inbound::Connected));
    assert!(notices.iter().any(|n| n == "session s2 restarted=true"), "{notices:?}");
    assert!(notices.iter().any(|n| n.contains("actions [5] not sent again")), "{notices:?}");
    // Nothing re-sent; numbers restart in the new session.
    assert_eq!(aac.next_ping().await, 0);
    link.actions.send(action(6, "c")).unwrap();
    assert_eq!(aac.recv_no_ping().await.unwrap()["seq"], 6);
}
