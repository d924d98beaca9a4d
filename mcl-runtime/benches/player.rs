//! Player throughput and latency.
//!
//! `cargo bench -p mcl-runtime --bench player`
//!
//! * `player/virtual`: a large generated mission (20 parallel branches of 50
//!   calls, 200 tasks, under a try-catch and a monitor) played to its end in
//!   virtual time against the mock vehicle, with the player of this crate
//!   (incremental enabled set). Throughput in firings per second.
//! * `player/naive`: the same mission and mock with the seed's loop
//!   (Extract 5.8: after every firing, rescan every transition for the
//!   enabled ones; Extract 5.7: scan every transition for an event's).
//! * After criterion, a summary: firings per second of both, their ratio,
//!   and the event-to-action latency inside the process, p50 and p99:
//!   `Player::on_event` alone, and through the real-time driver and the
//!   in-process link (event sent on the link → action received).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, Throughput};
use mcl_compiler::compile::compile_file;
use mcl_compiler::Database;
use mcl_net::{Net, TransitionId, TransitionKind};
use mcl_runtime::clock::Clock;
use mcl_runtime::driver::{self, Discard, Limits, Session};
use mcl_runtime::link::{self, Action, Inbound};
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::player::{Outcome, Output, Player, PlayerOptions};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::trace::{SourceMap, Tracer};
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

const BRANCHES: usize = 20;
const CALLS: usize = 50;
const TASKS_PER_BRANCH: usize = 10;

/// The generated mission's source.
fn mission_source() -> String {
    let mut s = String::from("actions {\n");
    let n = BRANCHES * TASKS_PER_BRANCH;
    for i in 0..n {
        s += &format!(
            "  enableP{i} = P{i}Primitive( c: enable, v: x );\n  disableP{i} = P{i}Primitive( c: disable );\n"
        );
    }
    s += "  enableAlarm = AlarmPrimitive( c: enable );\n  disableAlarm = AlarmPrimitive( c: disable );\n";
    s += "  enableSurface = SurfacePrimitive( c: enable );\n  disableSurface = SurfacePrimitive( c: disable );\n}\nevents {\n";
    for i in 0..n {
        s += &format!("  evP{i}Ok; evP{i}Fail;\n");
    }
    s += "  evAlarmOk; evAlarmFail; evSurfaceOk; evSurfaceFail;\n}\ntasks {\n";
    let task = |name: &str, prim: &str, param: bool| {
        format!(
            "  {name}({}): AchieveOneGoal {{ a: enable{prim} -> T0; a: disable{prim} -> T1, T6, T7; e: ev{prim}Ok -> T2; e: ev{prim}Fail -> T3; }}\n",
            if param { " x " } else { "" }
        )
    };
    for i in 0..n {
        s += &task(&format!("T{i}"), &format!("P{i}"), true);
    }
    s += &task("Alarm", "Alarm", false);
    s += &task("Surface", "Surface", false);
    s += "}\nmission {\n monitor {\n  try {\n   parallel ";
    let branches: Vec<String> = (0..BRANCHES)
        .map(|b| {
            let calls: Vec<String> =
                (0..CALLS).map(|k| format!("T{}( {k} )", b * TASKS_PER_BRANCH + k % TASKS_PER_BRANCH)).collect();
            format!("{{ {} }}", calls.join(" ; "))
        })
        .collect();
    s += &branches.join(" and ");
    s += "\n  } catch { Surface() }\n } condition ( Alarm() ) do { Surface() }\n}\n";
    s
}

fn mission() -> Arc<Net> {
    let mut db = Database::new();
    let file = db.set_text(std::path::Path::new("/virtual/bench/large.mcl"), mission_source());
    let mut ms = compile_file(&db, file).expect("the generated mission compiles");
    Arc::new(ms.remove(0).net)
}

/// A player, its tracer and a mock, ready to play the mission.
struct Ready {
    player: Player,
    tracer: Tracer,
    mock: MockVehicle,
}

fn setup(net: &Arc<Net>) -> Ready {
    let mut mock = MockVehicle::from_net(net, Scenario::default(), 1);
    mock.initial();
    Ready {
        player: Player::new(net.clone(), PlayerOptions::seeded(1)),
        tracer: Tracer::new(net, None, &mut SourceMap::default()),
        mock,
    }
}

/// Plays the mission in virtual time with this crate's player; returns the firings.
fn run_player(r: Ready) -> u64 {
    let Ready { player, tracer, mut mock } = r;
    let mut sink = Discard;
    let mut s = Session::new(player, tracer, &mut sink);
    let end = driver::run_virtual(&mut s, &mut mock, Limits::default()).unwrap();
    assert_eq!(end, driver::End::Outcome(Outcome::Ok));
    s.player.fired_count()
}

/// The seed's player (Extracts 5.7-5.9): the enabled set is recomputed by
/// scanning every transition after every firing.
struct Naive<'a> {
    net: &'a Net,
    m: Vec<u32>,
    rng: ChaCha8Rng,
    now: f64,
    /// Timed transitions: when their timer started.
    since: HashMap<u32, f64>,
    bindings: HashMap<String, (u32, Vec<(String, Value)>)>,
    seq: u64,
    fired: u64,
}

impl<'a> Naive<'a> {
    fn new(net: &'a Net) -> Self {
        Naive {
            net,
            m: net.initial_marking().0,
            rng: ChaCha8Rng::seed_from_u64(1),
            now: 0.0,
            since: HashMap::new(),
            bindings: HashMap::new(),
            seq: 0,
            fired: 0,
        }
    }

    fn enabled(&self, t: TransitionId) -> bool {
        mcl_net::semantics::is_enabled_with(self.net, t, |p| self.m[p.index()])
    }

    /// Extract 5.8's enabledTransitions(): every enabled transition not bound to an event.
    fn enabled_transitions(&self) -> Vec<TransitionId> {
        self.net
            .transition_ids()
            .filter(|&t| !matches!(self.net.transitions()[t.index()].kind, TransitionKind::Event(_)) && self.enabled(t))
            .collect()
    }

    /// ready2fireTransitions(): immediate first (Appendix A), else timed whose timer expired;
    /// starts the timers of newly enabled timed transitions.
    fn ready(&mut self, q: &[TransitionId]) -> Vec<TransitionId> {
        let imm: Vec<TransitionId> =
            q.iter().copied().filter(|&t| self.net.transitions()[t.index()].kind.is_immediate()).collect();
        self.since.retain(|t, _| q.contains(&TransitionId(*t)));
        if !imm.is_empty() {
            return imm;
        }
        let mut due = Vec::new();
        for &t in q {
            if let TransitionKind::Timed(d) = &self.net.transitions()[t.index()].kind {
                let start = *self.since.entry(t.0).or_insert(self.now);
                let d = match d {
                    mcl_net::Delay::Fixed(x) => *x,
                    mcl_net::Delay::Param(_) => 60.0,
                };
                if start + d <= self.now {
                    due.push(t);
                }
            }
        }
        due
    }

    /// Extract 5.9.
    fn fire(&mut self, t: TransitionId, out: &mut Vec<Action>) {
        let tr = &self.net.transitions()[t.index()];
        for &(p, d) in self.net.delta(t) {
            self.m[p.index()] = (i64::from(self.m[p.index()]) + d) as u32;
        }
        self.since.remove(&t.0);
        self.fired += 1;
        if let Some(b) = &tr.binding {
            let args =
                b.args.iter().map(|(k, v)| (k.clone(), serde_json::from_str(v).unwrap_or(Value::Null))).collect();
            self.bindings.insert(b.task.clone(), (b.call_site, args));
        }
        let task = tr.provenance.task.clone();
        for a in &tr.actions {
            self.seq += 1;
            let mut params = mcl_runtime::params::Params::new();
            for (name, json) in &a.params {
                let v = if json.contains("\"param\"") {
                    task.as_ref()
                        .and_then(|t| self.bindings.get(t))
                        .and_then(|b| b.1.iter().find(|(k, _)| k == name))
                        .map(|(_, v)| v.clone())
                        .unwrap_or(Value::Null)
                } else {
                    serde_json::from_str(json).unwrap_or(Value::Null)
                };
                params.insert(name.clone(), v);
            }
            out.push(Action {
                seq: self.seq,
                action: a.action.clone(),
                primitive: a.primitive.clone(),
                command: a.command.clone(),
                params,
                task: task.clone(),
                call_site: tr
                    .provenance
                    .call_site
                    .or_else(|| task.as_ref().and_then(|t| self.bindings.get(t)).map(|b| b.0)),
            });
        }
    }

    /// Extract 5.8: fire ready transitions until none is ready.
    fn play(&mut self, out: &mut Vec<Action>) {
        loop {
            let q = self.enabled_transitions();
            let qf = self.ready(&q);
            if qf.is_empty() {
                return;
            }
            let t = qf[mcl_net::semantics::uniform_index(&mut self.rng, qf.len())];
            self.fire(t, out);
        }
    }

    /// Extract 5.7: the first enabled transition bound to the event fires.
    fn receive_event(&mut self, ev: &str, out: &mut Vec<Action>) {
        let found = self.net.transition_ids().find(|&t| {
            matches!(&self.net.transitions()[t.index()].kind, TransitionKind::Event(e) if e == ev) && self.enabled(t)
        });
        if let Some(t) = found {
            self.fire(t, out);
        }
        self.play(out);
    }

    fn next_timer(&self) -> Option<f64> {
        self.net
            .transition_ids()
            .filter_map(|t| match &self.net.transitions()[t.index()].kind {
                TransitionKind::Timed(mcl_net::Delay::Fixed(d)) if self.enabled(t) => {
                    Some(self.since.get(&t.0).copied().unwrap_or(self.now) + d)
                }
                _ => None,
            })
            .min_by(f64::total_cmp)
    }
}

/// Plays the mission with the naive loop and the same mock; returns the firings.
fn run_naive(net: &Arc<Net>, mut mock: MockVehicle) -> u64 {
    let mut p = Naive::new(net);
    let ok = net.place_by_id("mission.ok").unwrap();
    let mut out = Vec::new();
    p.play(&mut out);
    loop {
        for a in out.drain(..) {
            mock.on_action(p.now, &a);
        }
        if p.m[ok.index()] > 0 {
            return p.fired;
        }
        let tm = mock.next_deadline();
        let tp = p.next_timer().filter(|&d| d > p.now);
        match (tp, tm) {
            (Some(a), b) if b.is_none_or(|b| a <= b) => {
                p.now = a;
                p.play(&mut out);
            }
            (_, Some(b)) => {
                p.now = p.now.max(b);
                if let Some((_, Inbound::Event { event, .. })) = mock.pop_due(b) {
                    p.receive_event(&event, &mut out);
                }
            }
            _ => panic!("the naive player is stuck"),
        }
    }
}

/// CPU time of this thread (steadier than wall time on a loaded machine).
fn thread_cpu() -> Duration {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// Median wall and CPU times of `runs` runs of `f` (setup excluded).
fn time_it<S>(setup: impl Fn() -> S, f: impl Fn(S) -> u64, runs: usize) -> (u64, Duration, Duration) {
    let mut wall = Vec::new();
    let mut cpu = Vec::new();
    let mut fired = 0;
    for _ in 0..runs {
        let s = setup();
        let (t, c) = (Instant::now(), thread_cpu());
        fired = std::hint::black_box(f(s));
        wall.push(t.elapsed());
        cpu.push(thread_cpu() - c);
    }
    wall.sort();
    cpu.sort();
    (fired, wall[runs / 2], cpu[runs / 2])
}

fn naive_mock(net: &Arc<Net>) -> MockVehicle {
    let mut mock = MockVehicle::from_net(net, Scenario::default(), 1);
    mock.initial();
    mock
}

fn percentile(v: &mut [Duration], p: f64) -> Duration {
    v.sort();
    v[((v.len() as f64 - 1.0) * p).round() as usize]
}

/// Event → first action, inside `Player::on_event`.
fn player_latency(net: &Arc<Net>) -> Vec<Duration> {
    let mut p = Player::new(net.clone(), PlayerOptions::seeded(1));
    let mut mock = MockVehicle::from_net(net, Scenario::default(), 1);
    mock.initial();
    let mut lat = Vec::new();
    let feed = |mock: &mut MockVehicle, out: &[Output], now: f64| {
        for o in out {
            if let Output::Send { action, .. } = o {
                mock.on_action(now, action);
            }
        }
    };
    let out = p.start(0.0);
    feed(&mut mock, &out, 0.0);
    while p.outcome().is_none() {
        let Some(t) = mock.next_deadline() else { break };
        let Some((t, Inbound::Event { event, .. })) = mock.pop_due(t) else { continue };
        let start = Instant::now();
        let out = p.on_event(t, &event);
        let took = start.elapsed();
        if out.iter().any(|o| matches!(o, Output::Send { .. })) {
            lat.push(took);
        }
        feed(&mut mock, &out, t);
    }
    lat
}

/// Event sent on the in-process link → action received on the AAC's end,
/// through the real-time driver (no journal, no trace).
fn link_latency(net: &Arc<Net>) -> Vec<Duration> {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let net = net.clone();
    rt.block_on(async move {
        let (mut link, mut end) = link::pair();
        let player = Player::new(net.clone(), PlayerOptions::seeded(1));
        let tracer = Tracer::new(&net, None, &mut SourceMap::default());
        let (tasks, _) = mcl_runtime::mock::tables_of(&net);
        let driver = tokio::spawn(async move {
            let mut sink = Discard;
            let mut s = Session::new(player, tracer, &mut sink);
            driver::run_real_time(&mut s, &mut link, Clock::new(1.0, 0.0), Limits::default(), Vec::new()).await
        });
        // A vehicle that answers every enable at once with the task's ok event
        // (except the alarm), one at a time.
        let mut lat = Vec::new();
        let mut pending: Vec<String> = Vec::new();
        let mut sent_at: Option<Instant> = None;
        loop {
            let Ok(Some(a)) = tokio::time::timeout(Duration::from_secs(5), end.actions.recv()).await else { break };
            if let Some(t) = sent_at.take() {
                lat.push(t.elapsed());
            }
            if a.command == "enable" && a.task.as_deref() != Some("Alarm") {
                if let Some(ev) = a.task.as_ref().and_then(|t| tasks.get(t)).and_then(|e| e.ok.first()) {
                    pending.push(ev.clone());
                }
            }
            // Answer when the player has sent everything of this step.
            if end.actions.is_empty() {
                tokio::task::yield_now().await;
            }
            if end.actions.is_empty() {
                if let Some(ev) = pending.pop() {
                    sent_at = Some(Instant::now());
                    if end.inbound.send(Inbound::Event { event: ev, activation: None, n: None }).is_err() {
                        break;
                    }
                }
            }
            if pending.is_empty()
                && end.actions.is_empty()
                && a.task.as_deref() == Some("Alarm")
                && a.command == "disable"
            {
                break;
            }
        }
        drop(end);
        let _ = driver.await;
        lat
    })
}

fn main() {
    let net = mission();
    let mut c = Criterion::default().configure_from_args();
    let fired = run_player(setup(&net));
    let naive_fired = run_naive(&net, naive_mock(&net));
    {
        let mut g = c.benchmark_group("player");
        g.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(10));
        g.throughput(Throughput::Elements(fired));
        g.bench_function("virtual", |b| b.iter_batched(|| setup(&net), run_player, BatchSize::LargeInput));
        g.throughput(Throughput::Elements(naive_fired));
        g.bench_function("naive", |b| {
            b.iter_batched(|| naive_mock(&net), |m| run_naive(&net, m), BatchSize::LargeInput)
        });
        g.finish();
    }
    c.final_summary();
    if std::env::var_os("MCL_BENCH_NO_SUMMARY").is_some() {
        return;
    }

    // Summary for BENCHMARKS.md.
    let (f1, t1, c1) = time_it(|| setup(&net), run_player, 15);
    let (f2, t2, c2) = time_it(|| naive_mock(&net), |m| run_naive(&net, m), 3);
    let rate = |f: u64, d: Duration| f as f64 / d.as_secs_f64();
    let mut lat = player_latency(&net);
    let mut link = link_latency(&net);
    println!();
    println!(
        "mission: {} places, {} transitions, {} calls; {f1} firings per run (naive: {f2})",
        net.place_count(),
        net.transition_count(),
        BRANCHES * CALLS + 2
    );
    println!(
        "player (incremental): {:>10.0} firings/s wall, {:>10.0} firings/s CPU  ({t1:?} wall, {c1:?} CPU per mission)",
        rate(f1, t1),
        rate(f1, c1)
    );
    println!(
        "naive (Extract 5.8):  {:>10.0} firings/s wall, {:>10.0} firings/s CPU  ({t2:?} wall, {c2:?} CPU per mission)",
        rate(f2, t2),
        rate(f2, c2)
    );
    println!("ratio: {:.1}x wall, {:.1}x CPU", rate(f1, t1) / rate(f2, t2), rate(f1, c1) / rate(f2, c2));
    println!(
        "event -> action, Player::on_event: p50 {:?}  p99 {:?}  ({} events)",
        percentile(&mut lat, 0.5),
        percentile(&mut lat, 0.99),
        lat.len()
    );
    if !link.is_empty() {
        println!(
            "event -> action, through the real-time driver and the in-process link: p50 {:?}  p99 {:?}  ({} events)",
            percentile(&mut link, 0.5),
            percentile(&mut link, 0.99),
            link.len()
        );
    }
}
