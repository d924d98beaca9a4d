//! Decentralized execution, end to end through the binary (issue 6, items 4
//! and 5; docs/coordination.md): `mcl compile --out-dir` writes one PNML per
//! vehicle, and `mcl run --mock` runs every vehicle of a file with several
//! missions at once, exchanging the coordination messages the synthesis
//! requires. The trace is checked against every constraint.

use mcl_runtime::trace::{Record, RecordKind};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-coord-run-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(root()).output().expect("run mcl")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn trace(path: &Path) -> Vec<Record> {
    mcl_runtime::trace::read_trace(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Whether `r` is about `mission`.
fn of_mission(r: &Record, mission: &str) -> bool {
    r.mission.as_deref() == Some(mission)
}

/// A coordination message sent: (its record, `transition`, `to`, `seq`).
fn sends(tr: &[Record]) -> Vec<(&Record, &str, &str, u64)> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::CoordSend { seq, transition, to } => Some((r, transition.as_str(), to.as_str(), *seq)),
            _ => None,
        })
        .collect()
}

/// A coordination message received: (its record, `from`, `transition`, `event`, `seq`).
fn receives(tr: &[Record]) -> Vec<(&Record, &str, &str, &str, u64)> {
    tr.iter()
        .filter_map(|r| match &r.kind {
            RecordKind::CoordReceive { seq, event, transition, from } => {
                Some((r, from.as_str(), transition.as_str(), event.as_str(), *seq))
            }
            _ => None,
        })
        .collect()
}

/// The last record: a coordinated run's summary (`value`, `result`, `messages`).
fn summary(tr: &[Record]) -> (Option<&Value>, &str, u64) {
    let last = tr.last().expect("a record");
    assert_eq!(last.mission.as_deref(), Some("*"));
    match &last.kind {
        RecordKind::CoordSummary { value, result, messages } => (value.as_ref(), result.as_str(), *messages),
        k => panic!("the last record is not the summary: {k:?}"),
    }
}

const AUV_ASC: &str = "examples/auv-asc.mcl";
const SCENARIO: &str = "examples/scenarios/auv-asc.toml";

/// `mcl run --mock FILE --trace T extra...`: (exit status, trace, output).
fn run(file: &str, extra: &[&str], name: &str) -> (i32, Vec<Record>, Output) {
    let tp = tmp(name);
    let mut args = vec!["run", "--mock", file, "--trace", tp.to_str().unwrap()];
    args.extend_from_slice(extra);
    let out = mcl(&args);
    let code = out.status.code().unwrap_or(-1);
    let tr = if tp.exists() { trace(&tp) } else { Vec::new() };
    (code, tr, out)
}

/// A call's starts and ends in the trace: line indices and times of the
/// firings of `callN.start` and of `callN.release` (a call ends, ok, failed or aborted, by giving its task back)
/// for the calls labelled `label` in `mission`.
#[derive(Debug, Default)]
struct Call {
    starts: Vec<(usize, f64)>,
    ends: Vec<(usize, f64)>,
}

fn call(tr: &[Record], mission: &str, label: &str) -> Call {
    let mut c = Call::default();
    for (i, r) in tr.iter().enumerate() {
        let RecordKind::Fire { transition: id, call, .. } = &r.kind else { continue };
        if !of_mission(r, mission) || call.label.as_deref() != Some(label) {
            continue;
        }
        let t = r.t;
        let Some((head, tail)) = id.split_once('.') else { continue };
        if head.strip_prefix("call").is_none_or(|n| n.parse::<u32>().is_err()) {
            continue;
        }
        match tail {
            "start" => c.starts.push((i, t)),
            // A call that completes or is aborted gives its task back once, at `release`.
            "release" => c.ends.push((i, t)),
            _ => {}
        }
    }
    c
}

/// `order { a, b }`: the k-th start of b comes after the k-th end of a.
fn check_order(tr: &[Record], a: (&str, &str), b: (&str, &str)) -> usize {
    let (ca, cb) = (call(tr, a.0, a.1), call(tr, b.0, b.1));
    for (k, &(line, t)) in cb.starts.iter().enumerate() {
        let Some(&(end_line, end_t)) = ca.ends.get(k) else {
            panic!("{}:{} start #{} (trace line {line}) before {} ends of {}:{}", b.0, b.1, k + 1, k + 1, a.0, a.1)
        };
        assert!(end_line < line && end_t <= t, "{}:{} started before {}:{} ended", b.0, b.1, a.0, a.1);
    }
    cb.starts.len()
}

/// The checks of every coordinated AUV/ASC run, whatever the transport and
/// the clock: each mission ends ok, every constraint of the file holds, and
/// the messages sent are the messages received and the number reported.
fn check_auv_asc(code: i32, tr: &[Record], out: &Output) {
    assert_eq!(code, 0, "{}", stderr(out));
    // Every record names its mission; the summary at the end names them all ("*").
    let (_, result, messages) = summary(tr);
    for r in &tr[..tr.len() - 1] {
        assert!(of_mission(r, "auv") || of_mission(r, "asc"), "{r:?}");
    }
    for m in ["auv", "asc"] {
        let o: Vec<&str> = tr
            .iter()
            .filter(|r| of_mission(r, m))
            .filter_map(|r| match &r.kind {
                RecordKind::Outcome { result, .. } => Some(result.as_str()),
                _ => None,
            })
            .collect();
        assert_eq!(o, ["ok"], "{m}");
    }
    assert_eq!(result, "ok");

    // order { asc:deploy_auv, auv:deploy_auv }: the AUV's Altitude starts
    // only after the ASC's Deploy ended.
    assert_eq!(check_order(tr, ("asc", "deploy_auv"), ("auv", "deploy_auv")), 1);
    // The other orders of the file.
    assert_eq!(check_order(tr, ("auv", "req_georef"), ("asc", "req_georef")), 1, "one object found");
    check_order(tr, ("asc", "georeference_fail"), ("auv", "georeference_fail"));
    assert_eq!(check_order(tr, ("auv", "survey_done"), ("asc", "survey_done")), 1);
    check_order(tr, ("auv", "survey_aborted"), ("asc", "survey_aborted"));
    check_order(tr, ("auv", "survey_alarm"), ("asc", "survey_alarm"));
    // sync { auv:send_data, asc:send_data }: they start together, each after
    // the message that the other arrived.
    let (a, b) = (call(tr, "auv", "send_data"), call(tr, "asc", "send_data"));
    assert_eq!((a.starts.len(), b.starts.len()), (1, 1), "the images were sent");
    let (later, earlier) = if a.starts[0].0 > b.starts[0].0 { (&a, &b) } else { (&b, &a) };
    assert!(later.starts[0].1 >= earlier.starts[0].1);
    let (lm, em) = if a.starts[0].0 > b.starts[0].0 { ("auv", "asc") } else { ("asc", "auv") };
    // The later start was enabled by a message from the earlier one's mission.
    assert!(
        receives(&tr[..later.starts[0].0]).iter().any(|(r, from, ..)| of_mission(r, lm) && *from == em),
        "{lm}'s send_data started without a message from {em}"
    );

    // Messages: each sent is received once, the count is reported.
    let sent = sends(tr);
    let received = receives(tr);
    assert!(!sent.is_empty());
    let mut s: Vec<String> =
        sent.iter().map(|(r, _, _, seq)| format!("{}#{seq}", r.mission.as_deref().unwrap())).collect();
    let mut g: Vec<String> = received.iter().map(|(_, from, _, _, seq)| format!("{from}#{seq}")).collect();
    s.sort();
    g.sort();
    assert_eq!(s, g);
    for (_, from, transition, event, _) in &received {
        assert_eq!(*event, format!("{from}/{transition}"));
    }
    assert_eq!(messages, sent.len() as u64);
    assert!(
        stderr(out).contains(&format!("coordination: 2 missions, {} messages sent", sent.len())),
        "{}",
        stderr(out)
    );
}

#[test]
fn auv_asc_dry_run_respects_every_constraint() {
    let (code, tr, out) = run(AUV_ASC, &["--virtual-time", "--scenario", SCENARIO], "auv-asc.jsonl");
    check_auv_asc(code, &tr, &out);
    // In virtual time the two send_data calls start at the same instant.
    let (a, b) = (call(&tr, "auv", "send_data"), call(&tr, "asc", "send_data"));
    assert_eq!(a.starts[0].1, b.starts[0].1);
    // Only the messages the synthesis requires: each is a firing listed in
    // the sender's `coord.send`, and reaches the mission listed there.
    let dir = tmp("nets-for-trace");
    let c = mcl(&["compile", AUV_ASC, "--out-dir", dir.to_str().unwrap()]);
    assert!(c.status.success(), "{}", stderr(&c));
    let mut allowed = Vec::new();
    for m in ["auv", "asc"] {
        let net = mcl_net::read_pnml(&std::fs::read_to_string(dir.join(format!("{m}.pnml"))).unwrap()).unwrap();
        for s in property(&net, "coord.send") {
            allowed.push(format!("{m} {} -> {}", s["transition"].as_str().unwrap(), s["to"].as_str().unwrap()));
        }
    }
    for (r, transition, to, _) in sends(&tr) {
        let k = format!("{} {transition} -> {to}", r.mission.as_deref().unwrap());
        assert!(allowed.contains(&k), "{k} is not in coord.send");
    }
    // The live log names the mission on every line.
    let log = String::from_utf8_lossy(&out.stdout);
    for line in log.lines() {
        assert!(line.contains("] auv: ") || line.contains("] asc: ") || line.contains("ALL MISSIONS OK"), "{line}");
    }
    assert!(log.contains("asc: send     "), "{log}");
    assert!(log.contains("auv: receive  asc/"), "{log}");

    // Deterministic: the same run gives the same trace.
    let (_, again, _) = run(AUV_ASC, &["--virtual-time", "--scenario", SCENARIO], "auv-asc-again.jsonl");
    assert_eq!(again, tr);

    // The TCP transport (JSON lines on loopback) gives the same run.
    let (code, over_tcp, out) =
        run(AUV_ASC, &["--virtual-time", "--scenario", SCENARIO, "--transport", "tcp"], "auv-asc-tcp.jsonl");
    check_auv_asc(code, &over_tcp, &out);
    assert_eq!(over_tcp, tr);
    assert!(stderr(&out).contains("(TCP transport)"));
}

#[test]
fn auv_asc_in_real_time_over_both_transports() {
    for transport in ["in-process", "tcp"] {
        let (code, tr, out) = run(
            AUV_ASC,
            &["--scenario", SCENARIO, "--speed", "200", "--transport", transport, "-q"],
            &format!("auv-asc-real-{transport}.jsonl"),
        );
        check_auv_asc(code, &tr, &out);
    }
}

#[test]
fn one_mission_alone_and_usage() {
    // --mission runs one mission alone, uncoordinated, as before.
    let (code, tr, _) = run(AUV_ASC, &["--virtual-time", "--mission", "asc"], "asc-alone.jsonl");
    assert_eq!(code, 0);
    assert!(tr.iter().all(|r| of_mission(r, "asc")));
    assert!(sends(&tr).is_empty());
    // The journal records one mission.
    let j = tmp("j.jsonl");
    let out = mcl(&["run", "--mock", "--virtual-time", AUV_ASC, "--journal", j.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--mission"), "{}", stderr(&out));
}

/// Three vehicles under `mutex { a:survey, b:survey, c:survey } = bound`
/// and, unless `staggered`, `order { c:survey, a:up }`. `staggered`: b and
/// c ask for the mutex 5 and 10 s later than a; otherwise all ask at 0 (a,
/// the holder, takes it; b and c ask a for it).
fn mutex_file(name: &str, bound: u32, staggered: bool) -> PathBuf {
    let vehicle = root().join("examples/vehicle.mcl");
    let (b, c) =
        if staggered { ("InitializeVehicle() ; ", "InitializeVehicle() ; StopVehicle() ; ") } else { ("", "") };
    // (Staggered, c may fail before its survey: a:up would wait for ever,
    // and the analysis refuses the order.)
    let order = if staggered { "" } else { "    order { c:survey, a:up }\n" };
    let text = format!(
        "import \"{}\";\n\
         mission : a {{ Goto( [0, 0] ) : survey ; Surface() : up }}\n\
         mission : b {{ {b}Goto( [5, 5] ) : survey ; Surface() : up }}\n\
         mission : c {{ {c}Goto( [9, 9] ) : survey }}\n\
         constraints {{\n    mutex {{ a:survey, b:survey, c:survey }} = {bound}\n{order}}}\n",
        vehicle.display()
    );
    let path = tmp(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The running intervals (trace lines) of a call's activations.
fn intervals(tr: &[Record], mission: &str, label: &str) -> Vec<(usize, usize)> {
    let c = call(tr, mission, label);
    assert_eq!(c.starts.len(), c.ends.len(), "{mission}:{label} ended as often as it started");
    c.starts.iter().zip(&c.ends).map(|(s, e)| (s.0, e.0)).collect()
}

#[test]
fn mutexes_never_overlap() {
    let at_once = mutex_file("mutex.mcl", 1, false);
    let staggered = mutex_file("mutex-staggered.mcl", 1, true);
    let runs: [(&Path, &[&str]); 6] = [
        (&at_once, &["--virtual-time"]),
        (&at_once, &["--virtual-time", "--transport", "tcp"]),
        (&staggered, &["--virtual-time"]),
        (&staggered, &["--speed", "50", "-q"]),
        // Real time, all asking at once: the holder grants one at a time.
        (&at_once, &["--speed", "50", "-q"]),
        (&at_once, &["--speed", "50", "-q", "--transport", "tcp"]),
    ];
    for (file, extra) in runs {
        let (code, tr, out) = run(file.to_str().unwrap(), extra, "mutex.jsonl");
        assert_eq!(code, 0, "{extra:?}: {}", stderr(&out));
        let mut all: Vec<(usize, usize, &str)> = Vec::new();
        for m in ["a", "b", "c"] {
            let iv = intervals(&tr, m, "survey");
            assert_eq!(iv.len(), 1);
            all.extend(iv.into_iter().map(|(s, e)| (s, e, m)));
        }
        all.sort();
        for w in all.windows(2) {
            assert!(w[0].1 < w[1].0, "{extra:?}: {} and {} run at once: {all:?}", w[0].2, w[1].2);
        }
        if *file == *at_once {
            assert_eq!(check_order(&tr, ("c", "survey"), ("a", "up")), 1);
        }
        let sent = sends(&tr).len() as u64;
        assert_eq!(summary(&tr).2, sent);
        assert_eq!(receives(&tr).len() as u64, sent);
        assert!(sent > 0);
    }
    // With a bound of 2, two of them run at once in virtual time.
    let file = mutex_file("mutex2.mcl", 2, false);
    let (code, tr, _) = run(file.to_str().unwrap(), &["--virtual-time"], "mutex2.jsonl");
    assert_eq!(code, 0);
    let mut events: Vec<(usize, i32)> = Vec::new();
    for m in ["a", "b", "c"] {
        for (s, e) in intervals(&tr, m, "survey") {
            events.push((s, 1));
            events.push((e, -1));
        }
    }
    events.sort();
    let mut running = 0;
    let mut most = 0;
    for (_, d) in events {
        running += d;
        most = most.max(running);
    }
    assert_eq!(most, 2);
}

fn property(net: &mcl_net::Net, key: &str) -> Vec<Value> {
    let (_, v) = net.properties().iter().find(|(k, _)| k == key).unwrap_or_else(|| panic!("no property {key}"));
    serde_json::from_str(v).unwrap()
}

#[test]
fn compile_out_dir_writes_one_pnml_per_vehicle() {
    let dir = tmp("vehicles");
    let _ = std::fs::remove_dir_all(&dir);
    let out = mcl(&["compile", AUV_ASC, "--out-dir", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("supervisor place"), "{}", stderr(&out));
    let mut nets = BTreeMap::new();
    for m in ["auv", "asc"] {
        let text = std::fs::read_to_string(dir.join(format!("{m}.pnml"))).unwrap();
        nets.insert(m, mcl_net::read_pnml(&text).unwrap());
    }
    // The files read back to the nets of the decentralization.
    let db = mcl_compiler::Database::new();
    let file = mcl_compiler::Db::file(&db, &root().join(AUV_ASC));
    let (missions, constraints) = mcl_coord::source::load(&db, file).unwrap();
    let report = mcl_coord::analyze(&missions, &constraints).unwrap();
    let vehicles = mcl_coord::decentralize(&missions, &report.supervisors).unwrap();
    assert_eq!(vehicles.len(), 2);
    for v in &vehicles {
        let back = &nets[v.mission.as_str()];
        assert_eq!(back.place_count(), v.net.place_count());
        assert_eq!(back.transition_count(), v.net.transition_count());
        for (p, q) in back.places().iter().zip(v.net.places()) {
            assert_eq!((&p.id, p.initial), (&q.id, q.initial));
        }
        for (t, u) in back.transitions().iter().zip(v.net.transitions()) {
            assert_eq!((&t.id, &t.kind), (&u.id, &u.kind));
        }
        let arcs = |n: &mcl_net::Net| {
            let mut a: Vec<String> = n
                .transition_ids()
                .flat_map(|t| {
                    let id = &n.transition(t).unwrap().id;
                    n.pre(t)
                        .iter()
                        .map(move |&(p, w)| format!("{} -{w}-> {id}", n.place(p).unwrap().id))
                        .chain(n.post(t).iter().map(move |&(p, w)| format!("{id} -{w}-> {}", n.place(p).unwrap().id)))
                        .collect::<Vec<_>>()
                })
                .collect();
            a.sort();
            a
        };
        assert_eq!(arcs(back), arcs(&v.net));
        assert_eq!(back.properties(), v.net.properties());
    }
    // Structure: every receive transition waits for `from/transition`, which
    // `from` sends to this vehicle; every sent transition exists; every
    // supervisor copy is connected.
    let mut sends = Vec::new();
    let mut receives = Vec::new();
    for (m, net) in &nets {
        for s in property(net, "coord.send") {
            let t = s["transition"].as_str().unwrap();
            assert!(net.transition_by_id(t).is_some(), "{m} sends an unknown transition {t}");
            sends.push(format!("{m}/{t} -> {}", s["to"].as_str().unwrap()));
        }
        for r in property(net, "coord.receive") {
            let id = r["transition"].as_str().unwrap();
            let from = r["from"].as_str().unwrap();
            let t = net.transition_by_id(id).unwrap();
            let mcl_net::TransitionKind::Event(e) = &net.transition(t).unwrap().kind else { panic!("{id}") };
            assert!(e.starts_with(&format!("{from}/")));
            assert_eq!(
                e,
                &mcl_runtime::coord::CoordMessage {
                    from: from.into(),
                    to: m.to_string(),
                    transition: e[from.len() + 1..].into(),
                    seq: 1,
                    t: 0.0
                }
                .event()
            );
            assert_eq!(e, &mcl_coord::decentral::message_event(from, &e[from.len() + 1..]));
            receives.push(format!("{e} -> {m}"));
        }
        let sups = mcl_coord::decentral::supervisor_places(net);
        assert!(!sups.is_empty(), "{m} holds supervisors");
        for p in sups {
            let touching =
                net.transition_ids().filter(|&t| net.pre(t).iter().chain(net.post(t)).any(|&(q, _)| q == p)).count();
            assert!(touching > 0, "{m}: supervisor {} has no arc", net.place(p).unwrap().id);
        }
    }
    sends.sort();
    receives.sort();
    assert_eq!(sends, receives);

    // A file with one mission keeps writing its plain net.
    let one = tmp("one");
    let out = mcl(&["compile", "examples/survey.mcl", "--out-dir", one.to_str().unwrap()]);
    assert!(out.status.success());
    let net = mcl_net::read_pnml(&std::fs::read_to_string(one.join("mission.pnml")).unwrap()).unwrap();
    assert!(net.properties().iter().all(|(k, _)| !k.starts_with("coord.")));
}

#[test]
fn deadlocking_constraints_are_refused() {
    let vehicle = root().join("examples/vehicle.mcl");
    let path = tmp("deadlock.mcl");
    std::fs::write(
        &path,
        format!(
            "import \"{}\";\n\
             mission : a {{ Goto( [0, 0] ) : x ; Surface() : y }}\n\
             mission : b {{ Goto( [5, 5] ) : x ; Surface() : y }}\n\
             constraints {{\n    order {{ a:y, b:x }}\n    order {{ b:y, a:x }}\n}}\n",
            vehicle.display()
        ),
    )
    .unwrap();
    let out = mcl(&["compile", path.to_str().unwrap(), "--out-dir", tmp("dl").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("deadlock"), "{}", stderr(&out));
    let out = mcl(&["run", "--mock", "--virtual-time", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("deadlock"), "{}", stderr(&out));
}

/// Runs the vehicle nets `vnets` in real time (`speed` times faster) over an
/// in-process transport that delays every message by `delay` of wall-clock
/// time; returns the trace (records in the order they happened).
fn run_delayed(vnets: Vec<mcl_coord::VehicleNet>, delay_ms: u64, speed: f64) -> (Vec<Record>, u8) {
    use mcl_runtime::multi::{run_real_time, SharedSink, Vehicle};
    let names: Vec<String> = vnets.iter().map(|v| v.mission.clone()).collect();
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let sink = std::sync::Arc::new(std::sync::Mutex::new(mcl_runtime::driver::Collect::default()));
    let shared: SharedSink = sink.clone();
    let end = rt.block_on(async {
        let ends = mcl_runtime::coord::delayed_in_process(&names, std::time::Duration::from_millis(delay_ms));
        let mut sources = mcl_runtime::trace::SourceMap::new();
        let mut vs = Vec::new();
        for (v, tr) in vnets.into_iter().zip(ends) {
            let net = std::sync::Arc::new(v.net);
            let scenario = mcl_runtime::scenario::Scenario { default_duration: Some(2.0), ..Default::default() };
            let tracer = mcl_runtime::trace::Tracer::new(&net, Some(v.mission.clone()), &mut sources);
            let mock = mcl_runtime::mock::MockVehicle::from_net(&net, scenario, 1);
            vs.push(Vehicle::new(&v.mission, net, Default::default(), tracer, mock, Box::new(tr)).unwrap());
        }
        let limits = mcl_runtime::driver::Limits::real_time(Some(600.0));
        run_real_time(vs, shared, mcl_runtime::clock::Clock::new(speed, 0.0), limits).await.unwrap()
    });
    let records = std::mem::take(&mut sink.lock().unwrap().0);
    (records, end.exit_code())
}

/// The missions of a mutex file and the supervisors of its analysis.
fn coordinated(path: &Path) -> (Vec<mcl_coord::Mission>, Vec<mcl_coord::Supervisor>) {
    let db = mcl_compiler::Database::new();
    let file = mcl_compiler::Db::file(&db, path);
    let (missions, constraints) = mcl_coord::source::load(&db, file).unwrap();
    let report = mcl_coord::analyze(&missions, &constraints).unwrap();
    (missions, report.supervisors)
}

/// How many of `missions`' `label` calls are running at once, at most
/// (trace order).
fn most_at_once(tr: &[Record], missions: &[&str], label: &str) -> usize {
    let mut events: Vec<(usize, i32)> = Vec::new();
    for m in missions {
        for (s, e) in intervals(tr, m, label) {
            events.push((s, 1));
            events.push((e, -1));
        }
    }
    events.sort();
    let (mut running, mut most) = (0i32, 0i32);
    for (_, d) in events {
        running += d;
        most = most.max(running);
    }
    most as usize
}

#[test]
fn a_mutex_between_vehicles_holds_when_messages_take_time() {
    // Both ask at 0; every message takes 40 ms (2 s of mission time at
    // speed 50), as long as a call.
    let file = mutex_file("mutex-delay.mcl", 1, false);
    let (missions, sups) = coordinated(&file);
    let names = ["a", "b", "c"];

    // Copies of the supervisor in every vehicle (the synchronous
    // communication of Iordache and Antsaklis) let all of them take it on
    // stale information...
    let plant = mcl_coord::centralize(&missions).unwrap();
    let costs = mcl_coord::decentral::Costs::default();
    let comm = mcl_coord::decentral::minimize_communication(&plant, &sups, &costs).unwrap();
    let copies = mcl_coord::decentral::vehicle_nets(&missions, &plant, &sups, &comm).unwrap();
    let (tr, _) = run_delayed(copies, 40, 50.0);
    assert!(most_at_once(&tr, &names, "survey") > 1, "copies kept the mutex although messages crossed");

    // ...a single holder with requests, grants and returns does not.
    let vnets = mcl_coord::decentralize(&missions, &sups).unwrap();
    let (tr, code) = run_delayed(vnets, 40, 50.0);
    assert_eq!(code, 0, "{tr:#?}");
    assert_eq!(most_at_once(&tr, &names, "survey"), 1);
    for m in names {
        assert_eq!(intervals(&tr, m, "survey").len(), 1, "{m}");
    }
    assert_eq!(check_order(&tr, ("c", "survey"), ("a", "up")), 1);
    // b and c each asked a (the holder) once, were granted once and gave
    // the token back at the end of their call.
    let (value, _, _) = summary(&tr);
    let sent = |t: &str| sends(&tr).iter().filter(|(_, transition, ..)| transition.starts_with(t)).count();
    assert_eq!((sent("coord.request."), sent("coord.lend.")), (2, 2));
    let value = value.expect("the mutex protocol's counts");
    assert_eq!(value["requests"], 2);
    assert_eq!(value["grants"], 2);
    assert_eq!(value["returns"], 2);
}

#[test]
fn a_withdrawn_sync_arrival_does_not_let_the_other_call_start() {
    // a reaches its sync call at 0, and its parallel-or withdraws it when
    // Surface() ends (one default duration); b reaches its own after two
    // tasks. Without the withdrawal, b would start on a's stale arrival.
    // b gives up too, when its three Goto calls have ended (so that no
    // nominal run waits for ever: `mcl check` accepts the file).
    let vehicle = root().join("examples/vehicle.mcl");
    let text = format!(
        "import \"{}\";\n\
         mission : a {{ parallel {{ Surface() }} or {{ ReceiveData() : s }} }}\n\
         mission : b {{ parallel {{ InitializeVehicle() ; StopVehicle() ; SendData() : s }} \
         or {{ Goto( [1, 1] ) ; Goto( [2, 2] ) ; Goto( [3, 3] ) }} }}\n\
         constraints {{\n    sync {{ a:s, b:s }}\n}}\n",
        vehicle.display()
    );
    let path = tmp("sync-withdrawn.mcl");
    std::fs::write(&path, text).unwrap();
    for extra in [&["--virtual-time"][..], &["--speed", "50", "-q"][..]] {
        let mut args = extra.to_vec();
        args.extend(["--time-limit", "100"]);
        let (code, tr, out) = run(path.to_str().unwrap(), &args, "sync-withdrawn.jsonl");
        assert!(call(&tr, "a", "s").starts.is_empty(), "{extra:?}");
        assert!(call(&tr, "b", "s").starts.is_empty(), "{extra:?}: b started on a withdrawn arrival");
        // a withdrew its call (cancel) and told b, which dropped the credit.
        let fired = |m: &str, suffix: &str| {
            tr.iter().any(|r| {
                matches!(&r.kind, RecordKind::Fire { transition, .. } if transition.ends_with(suffix))
                    && of_mission(r, m)
            })
        };
        assert!(fired("a", ".cancel"), "{extra:?}");
        assert!(fired("b", ".withdraw"), "{extra:?}");
        // b waits until its other branch ends, then withdraws its call.
        assert!(fired("b", ".cancel"), "{extra:?}");
        assert_eq!(code, 0, "{extra:?}: {}", stderr(&out));
    }
}

/// A free loopback port (bound then released).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

#[test]
fn each_vehicle_in_its_own_process_over_tcp() {
    // a holds the mutex; b asks for it; b's survey ends before a goes up.
    let vehicle = root().join("examples/vehicle.mcl");
    let text = format!(
        "import \"{}\";\n\
         mission : a {{ Goto( [0, 0] ) : survey ; Surface() : up }}\n\
         mission : b {{ Goto( [5, 5] ) : survey }}\n\
         constraints {{\n    mutex {{ a:survey, b:survey }} = 1\n    order {{ b:survey, a:up }}\n}}\n",
        vehicle.display()
    );
    let path = tmp("two-processes.mcl");
    std::fs::write(&path, text).unwrap();
    let (pa, pb) = (free_port(), free_port());
    let spawn = |me: &str, listen: u16, peer: &str, port: u16| {
        let tp = tmp(&format!("proc-{me}.jsonl"));
        let child = Command::new(env!("CARGO_BIN_EXE_mcl"))
            .args(["run", "--mock", path.to_str().unwrap(), "--vehicle", me])
            .args(["--coord-listen", &format!("127.0.0.1:{listen}")])
            .args(["--coord-peer", &format!("{peer}=127.0.0.1:{port}")])
            .args(["--speed", "50", "--time-limit", "600", "-q", "--trace", tp.to_str().unwrap()])
            .current_dir(root())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("run mcl");
        (child, tp)
    };
    let (a, ta) = spawn("a", pa, "b", pb);
    let (b, tb) = spawn("b", pb, "a", pa);
    let (oa, ob) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert_eq!(oa.status.code(), Some(0), "a: {}", stderr(&oa));
    assert_eq!(ob.status.code(), Some(0), "b: {}", stderr(&ob));
    let (tra, trb) = (trace(&ta), trace(&tb));
    assert!(tra.iter().all(|r| of_mission(r, "a") || of_mission(r, "*")));
    assert!(trb.iter().all(|r| of_mission(r, "b") || of_mission(r, "*")));
    // What one sends, the other receives; b asked a for the mutex.
    let sends = |tr: &[Record]| sends(tr).into_iter().map(|(_, t, ..)| t.to_string()).collect::<Vec<_>>();
    let receives = |tr: &[Record]| receives(tr).into_iter().map(|(_, _, t, ..)| t.to_string()).collect::<Vec<_>>();
    assert_eq!(sends(&tra), receives(&trb));
    assert_eq!(sends(&trb), receives(&tra));
    assert!(sends(&trb).iter().any(|t| t == "coord.request.mutex1"), "{:?}", sends(&trb));
    assert!(stderr(&oa).contains("coordination: `a` listens on 127.0.0.1:"), "{}", stderr(&oa));
    // Each did its call once; a went up after b's survey ended (b told it).
    assert_eq!(call(&tra, "a", "survey").starts.len(), 1);
    assert_eq!(call(&trb, "b", "survey").ends.len(), 1);
    assert_eq!(call(&tra, "a", "up").starts.len(), 1);
    // Usage errors.
    let out = mcl(&["run", "--mock", path.to_str().unwrap(), "--vehicle", "b"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--coord-peer a=HOST:PORT"), "{}", stderr(&out));
    let out = mcl(&["run", "--mock", "--virtual-time", path.to_str().unwrap(), "--vehicle", "b"]);
    assert_eq!(out.status.code(), Some(2));
    let out = mcl(&["run", "--mock", path.to_str().unwrap(), "--vehicle", "z"]);
    assert!(stderr(&out).contains("no mission `z`"), "{}", stderr(&out));
}
