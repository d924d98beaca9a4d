//! Event-to-action latency of the player over the AAC protocol on loopback
//! TCP (BENCHMARKS.md, "mcl-runtime: AAC over TCP").
//!
//! ```text
//! cargo run --release -p mcl-runtime --example aac_latency [-- ITERATIONS]
//! ```
//!
//! An AAC (`tcp::serve`, one thread, its own runtime) sends an event and
//! measures the time until the action it causes arrives. The player (another
//! thread and runtime) holds a [`Link`] from `tcp::connect` and runs the real
//! sans-IO [`Player`] on a one-place cyclic net whose event transition sends
//! one action. The path measured: AAC session → socket → link task → player
//! (event, firing, action) → link task → socket → AAC session. For
//! comparison, the same loop over an in-process `link::pair()`, and over TCP
//! with a trivial echo instead of the player.

use std::sync::Arc;
use std::time::{Duration, Instant};

use mcl_net::{ActionRef, NetBuilder, Place, Transition, TransitionKind};
use mcl_runtime::link::{pair, AacEnd, Inbound, Link};
use mcl_runtime::player::{Output, Player, PlayerOptions};
use mcl_runtime::tcp::{connect, serve, ConnectOptions, ServeOptions};
use tokio::sync::oneshot;

fn net() -> Arc<mcl_net::Net> {
    let mut b = NetBuilder::new("latency");
    let p = b.add_place(Place::new("p").with_tokens(1));
    let t =
        b.add_transition(Transition::new("t").with_kind(TransitionKind::Event("tick".into())).with_action(ActionRef {
            action: "act".into(),
            primitive: "BenchPrimitive".into(),
            command: "enable".into(),
            params: Vec::new(),
        }));
    b.add_input(p, t, 1).add_output(t, p, 1);
    Arc::new(b.build().unwrap())
}

/// The player side: the real player, or an echo.
async fn play(mut link: Link, real: bool) {
    let start = Instant::now();
    let mut player = Player::new(net(), PlayerOptions::default());
    let mut seq = 0;
    let send = |link: &Link, outs: Vec<Output>| {
        for o in outs {
            if let Output::Send { action, .. } = o {
                let _ = link.actions.send(action);
            }
        }
    };
    send(&link, player.start(0.0));
    while let Some(ib) = link.inbound.recv().await {
        if let Inbound::Event { event, .. } = ib {
            if real {
                let outs = player.on_event(start.elapsed().as_secs_f64(), &event);
                send(&link, outs);
            } else {
                seq += 1;
                let _ = link.actions.send(mcl_runtime::link::Action {
                    seq,
                    action: "act".into(),
                    primitive: "BenchPrimitive".into(),
                    command: "enable".into(),
                    params: Default::default(),
                    task: None,
                    call_site: None,
                });
            }
        }
    }
}

/// The AAC side: `n` event → action round trips; returns the latencies.
async fn measure(mut end: AacEnd, n: usize) -> Vec<Duration> {
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let t0 = Instant::now();
        end.inbound.send(Inbound::Event { event: "tick".into(), activation: None, n: None }).unwrap();
        let a = end.actions.recv().await.expect("player gone");
        out.push(t0.elapsed());
        std::hint::black_box(a);
    }
    out
}

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap()
}

fn over_tcp(n: usize, real: bool) -> Vec<Duration> {
    let (addr_tx, addr_rx) = std::sync::mpsc::channel();
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    let aac = std::thread::spawn(move || {
        runtime().block_on(async move {
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            addr_tx.send(listener.local_addr().unwrap()).unwrap();
            let (stx, srx) = oneshot::channel();
            let mut stx = Some(stx);
            tokio::spawn(serve(listener, ServeOptions::default(), move |s| {
                if let Some(tx) = stx.take() {
                    let _ = tx.send(s);
                }
            }));
            let mut session = srx.await.unwrap();
            // Skip the action of `start` (none here) and warm up.
            let _ = measure_warm(&mut session.end).await;
            let r = measure(session.end, n).await;
            done_tx.send(r).unwrap();
        })
    });
    let addr = addr_rx.recv().unwrap();
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let player = std::thread::spawn(move || {
        runtime().block_on(async move {
            let link = connect(addr.to_string(), ConnectOptions::default());
            tokio::select! {
                _ = play(link, real) => {}
                _ = stop_rx => {}
            }
        })
    });
    let r = done_rx.recv().unwrap();
    let _ = stop_tx.send(());
    player.join().unwrap();
    drop(aac);
    r
}

async fn measure_warm(end: &mut AacEnd) -> Vec<Duration> {
    let mut v = Vec::new();
    for _ in 0..1000 {
        let t0 = Instant::now();
        end.inbound.send(Inbound::Event { event: "tick".into(), activation: None, n: None }).unwrap();
        end.actions.recv().await.unwrap();
        v.push(t0.elapsed());
    }
    v
}

fn in_process(n: usize) -> Vec<Duration> {
    let (link, mut end) = pair();
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    let aac = std::thread::spawn(move || {
        runtime().block_on(async move {
            let _ = measure_warm(&mut end).await;
            done_tx.send(measure(end, n).await).unwrap();
        })
    });
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let player = std::thread::spawn(move || {
        runtime().block_on(async move {
            tokio::select! {
                _ = play(link, true) => {}
                _ = stop_rx => {}
            }
        })
    });
    let r = done_rx.recv().unwrap();
    let _ = stop_tx.send(());
    player.join().unwrap();
    aac.join().unwrap();
    r
}

fn report(name: &str, mut v: Vec<Duration>) {
    v.sort_unstable();
    let q = |p: f64| v[((v.len() as f64 * p) as usize).min(v.len() - 1)].as_secs_f64() * 1e6;
    let mean = v.iter().map(|d| d.as_secs_f64()).sum::<f64>() / v.len() as f64 * 1e6;
    println!(
        "{name:<34} n={:<6} p50 {:>7.1} µs  p90 {:>7.1} µs  p99 {:>7.1} µs  max {:>8.1} µs  mean {:>7.1} µs",
        v.len(),
        q(0.50),
        q(0.90),
        q(0.99),
        v.last().unwrap().as_secs_f64() * 1e6,
        mean
    );
}

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    report("in-process link::pair + player", in_process(n));
    report("loopback TCP + echo (no player)", over_tcp(n, false));
    report("loopback TCP + player", over_tcp(n, true));
}
