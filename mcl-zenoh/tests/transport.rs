//! The Zenoh coordination transport between two real Zenoh sessions on a
//! loopback endpoint (no scouting): in order, once, acknowledged once
//! durable, re-sent to a receiver that comes back, forgeries refused.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use mcl_runtime::coord::{Auth, CoordMessage, CoordTransport, Incoming};
use mcl_zenoh::{Node, ZenohEnd, ZenohOptions};

fn msg(from: &str, to: &str, transition: &str, seq: u64) -> CoordMessage {
    CoordMessage { from: from.into(), to: to.into(), transition: transition.into(), seq, t: seq as f64 }
}

fn free_endpoint() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    format!("tcp/127.0.0.1:{port}")
}

/// A session on loopback only (a peer given no endpoint to listen on would
/// listen on every interface).
fn node(listen: &[&str], connect: &[&str]) -> Arc<Node> {
    let listen = if listen.is_empty() { &["tcp/127.0.0.1:0"][..] } else { listen };
    let o = ZenohOptions {
        listen: listen.iter().map(|s| s.to_string()).collect(),
        connect: connect.iter().map(|s| s.to_string()).collect(),
        ..Default::default()
    };
    Arc::new(Node::open(&o).unwrap())
}

async fn next(end: &mut ZenohEnd) -> Incoming {
    tokio::time::timeout(Duration::from_secs(20), end.recv()).await.expect("in time").expect("open")
}

async fn message(end: &mut ZenohEnd) -> CoordMessage {
    loop {
        if let Incoming::Message(m) = next(end).await {
            return m;
        }
    }
}

async fn all_acknowledged(end: &ZenohEnd) -> bool {
    for _ in 0..400 {
        if end.unacknowledged() == 0 {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    false
}

#[tokio::test]
async fn delivers_in_order_once_and_acknowledges() {
    let ep = free_endpoint();
    let auth = Auth::secret(b"fleet");
    let none = HashMap::new();
    let mut a = ZenohEnd::open(node(&[&ep], &[]), "t1", "a", auth.clone(), &none).await.unwrap();
    let mut b = ZenohEnd::open(node(&[], &[&ep]), "t1", "b", auth, &none).await.unwrap();
    a.add_peer("b").unwrap();
    b.add_peer("a").unwrap();
    b.accept_from(&["a".to_string()]);
    for i in 1..=20 {
        a.send(msg("a", "b", &format!("call{i}.ok"), i)).unwrap();
    }
    b.send(msg("b", "a", "coord.request.mutex1", 1)).unwrap();
    for i in 1..=20 {
        let m = message(&mut b).await;
        assert_eq!((m.transition.as_str(), m.seq), (format!("call{i}.ok").as_str(), i));
        b.delivered(&m);
    }
    let m = message(&mut a).await;
    assert_eq!(m, msg("b", "a", "coord.request.mutex1", 1));
    a.delivered(&m);
    assert!(a.send(msg("a", "nobody", "t", 21)).is_err());
    assert!(all_acknowledged(&a).await && all_acknowledged(&b).await);
    // Nothing more comes: every re-send was a duplicate.
    assert!(tokio::time::timeout(Duration::from_millis(1500), b.recv()).await.is_err());
}

#[tokio::test]
async fn a_receiver_that_comes_back_gets_what_was_not_acknowledged() {
    let ep = free_endpoint();
    let auth = Auth::secret(b"fleet");
    let none = HashMap::new();
    let mut a = ZenohEnd::open(node(&[&ep], &[]), "t2", "a", auth.clone(), &none).await.unwrap();
    a.add_peer("b").unwrap();
    let mut b = ZenohEnd::open(node(&[], &[&ep]), "t2", "b", auth.clone(), &none).await.unwrap();
    for i in 1..=3 {
        a.send(msg("a", "b", &format!("t{i}"), i)).unwrap();
    }
    // b takes 1 and 2, makes only 1 durable, and crashes (its session too).
    let m1 = message(&mut b).await;
    b.delivered(&m1);
    let _m2 = message(&mut b).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    drop(b);
    // b comes back with its journal (1 received).
    let mut b =
        ZenohEnd::open(node(&[], &[&ep]), "t2", "b", auth, &HashMap::from([("a".to_string(), 1)])).await.unwrap();
    a.send(msg("a", "b", "t4", 4)).unwrap();
    for i in 2..=4 {
        let m = message(&mut b).await;
        assert_eq!(m.seq, i);
        b.delivered(&m);
    }
    assert!(all_acknowledged(&a).await);
}

#[tokio::test]
async fn a_wrong_fleet_secret_is_refused() {
    let ep = free_endpoint();
    let none = HashMap::new();
    let mut b = ZenohEnd::open(node(&[&ep], &[]), "t3", "b", Auth::secret(b"fleet"), &none).await.unwrap();
    let mut wrong = ZenohEnd::open(node(&[], &[&ep]), "t3", "a", Auth::secret(b"guess"), &none).await.unwrap();
    wrong.add_peer("b").unwrap();
    wrong.send(msg("a", "b", "call1.release", 1)).unwrap();
    match next(&mut b).await {
        Incoming::Rejected(why) => assert!(why.contains("wrong MAC"), "{why}"),
        Incoming::Message(m) => panic!("delivered {m:?}"),
    }
    assert_eq!(wrong.unacknowledged(), 1);
}
