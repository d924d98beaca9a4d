//! Coordination message latency on loopback: the Zenoh transport against
//! the TCP transport, in the same run (benches-scripts/zenoh-latency.sh,
//! BENCHMARKS.md). One message at a time from `a` to `b`: the time from
//! `send` to `recv`, and the time until it is acknowledged end to end.
//!
//! `cargo bench -p mcl-zenoh --bench latency -- [MESSAGES]`

use std::sync::Arc;
use std::time::{Duration, Instant};

use mcl_runtime::coord::{CoordMessage, CoordTransport, Incoming};

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

async fn measure(name: &str, mut a: Box<dyn CoordTransport>, mut b: Box<dyn CoordTransport>, n: u64) {
    // Warm-up: the first messages wait for the peers to find each other.
    let mut one_way = Vec::new();
    let mut acked = Vec::new();
    let warm = 50;
    for seq in 1..=n + warm {
        let m = CoordMessage { from: "a".into(), to: "b".into(), transition: format!("call{seq}.ok"), seq, t: 0.0 };
        let t0 = Instant::now();
        a.send(m).expect("send");
        let got = match tokio::time::timeout(Duration::from_secs(30), b.recv()).await {
            Ok(Some(Incoming::Message(m))) => m,
            Ok(Some(Incoming::Rejected(why))) => panic!("{name}: refused {why}"),
            _ => panic!("{name}: no message within 30 s"),
        };
        let t1 = t0.elapsed();
        assert_eq!(got.seq, seq);
        b.delivered(&got);
        // Spin (tokio's timers tick by the millisecond: a sleep would
        // measure the timer).
        while a.unacknowledged() > 0 {
            tokio::task::yield_now().await;
        }
        let t2 = t0.elapsed();
        if seq > warm {
            one_way.push(t1.as_secs_f64() * 1e6);
            acked.push(t2.as_secs_f64() * 1e6);
        }
    }
    for (what, v) in [("send→recv", &mut one_way), ("send→acked", &mut acked)] {
        v.sort_by(f64::total_cmp);
        println!(
            "{name:<6} {what:<11} n={n:<5} p50 {:>8.1} µs   p90 {:>8.1} µs   p99 {:>8.1} µs   max {:>8.1} µs",
            percentile(v, 0.5),
            percentile(v, 0.9),
            percentile(v, 0.99),
            v[v.len() - 1]
        );
    }
}

fn main() {
    let n: u64 = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(1000);
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    rt.block_on(async {
        let names: Vec<String> = vec!["a".into(), "b".into()];
        let mut tcp = mcl_runtime::coord::tcp_mesh(&names, "127.0.0.1").await.unwrap();
        let (tb, ta) = (tcp.pop().unwrap(), tcp.pop().unwrap());
        measure("tcp", Box::new(ta), Box::new(tb), n).await;
        // Two Zenoh sessions (two peers, as two processes would be), on loopback.
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let ep = format!("tcp/127.0.0.1:{port}");
        let na = mcl_zenoh::ZenohOptions { listen: vec![ep.clone()], ..Default::default() };
        let nb =
            mcl_zenoh::ZenohOptions { connect: vec![ep], listen: vec!["tcp/127.0.0.1:0".into()], ..Default::default() };
        let (na, nb) = (Arc::new(mcl_zenoh::Node::open(&na).unwrap()), Arc::new(mcl_zenoh::Node::open(&nb).unwrap()));
        let auth = mcl_runtime::coord::Auth::random().unwrap();
        let none = Default::default();
        let mut za = mcl_zenoh::ZenohEnd::open(na, "bench", "a", auth.clone(), &none).await.unwrap();
        let mut zb = mcl_zenoh::ZenohEnd::open(nb, "bench", "b", auth, &none).await.unwrap();
        za.add_peer("b").unwrap();
        zb.add_peer("a").unwrap();
        measure("zenoh", Box::new(za), Box::new(zb), n).await;
    });
}
