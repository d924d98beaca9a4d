//! Coordinated vehicles in separate processes (`mcl run --vehicle`) survive
//! a crash of any of them, and refuse forged or replayed coordination
//! (issue 12, items 2 and 3; docs/coordination.md, *Crashes* and *The TCP
//! link*). Every process is bounded in time: a test that hangs fails.

mod auv_asc_common;
use auv_asc_common::{actions, call, check, fired, received, receives, sends, AUV_ASC, SCENARIO};
use mcl_runtime::trace::{Record, RecordKind};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-coord-fault-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn trace(path: &Path) -> Vec<Record> {
    mcl_runtime::trace::read_trace(path).unwrap_or_else(|e| panic!("{e}"))
}

fn lines(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad line {l}: {e}")))
        .collect()
}

/// A free loopback port (bound then released).
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// Waits for `child`, killing it after `limit` (then panics: nothing may
/// hang). Returns its status, its standard error and its standard output
/// (when piped; a short run's output fits the pipe).
fn wait(mut child: Child, limit: Duration, what: &str) -> (ExitStatus, String, String) {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let (mut err, mut out) = (String::new(), String::new());
            if let Some(mut e) = child.stderr.take() {
                let _ = e.read_to_string(&mut err);
            }
            if let Some(mut o) = child.stdout.take() {
                let _ = o.read_to_string(&mut out);
            }
            return (status, err, out);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = e.read_to_string(&mut err);
            }
            panic!("{what} still runs after {limit:?}: {err}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

const LIMIT: Duration = Duration::from_secs(40);

/// One vehicle of `examples/auv-asc.mcl` in its own process, journaled,
/// aborted after `crash_after` journal syncs (as `kill -9` would) and then
/// restarted with `--resume` until it ends. Returns the exit status of its
/// last run, the trace of its last run (which holds the whole run: the
/// replay rebuilds it) and its journal.
fn vehicle(
    me: &str,
    listen: u16,
    peer: (&str, u16),
    crash_after: Option<u64>,
    tag: &str,
) -> (i32, Vec<Record>, Vec<Value>) {
    vehicle_of(&[AUV_ASC, "--scenario", SCENARIO], me, listen, peer, crash_after, tag)
}

/// [`vehicle`] for another file (`FILE`, or `FILE --scenario S`).
fn vehicle_of(
    file: &[&str],
    me: &str,
    listen: u16,
    peer: (&str, u16),
    crash_after: Option<u64>,
    tag: &str,
) -> (i32, Vec<Record>, Vec<Value>) {
    let journal = tmp(&format!("{tag}-{me}.journal"));
    let mut crash = crash_after;
    for life in 0.. {
        let trace_path = tmp(&format!("{tag}-{me}-{life}.jsonl"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mcl"));
        cmd.args(["run", "--mock"])
            .args(file)
            .args(["--vehicle", me])
            .args(["--coord-listen", &format!("127.0.0.1:{listen}")])
            .args(["--coord-peer", &format!("{}=127.0.0.1:{}", peer.0, peer.1)])
            .args(["--coord-token", "fleet secret"])
            .args(["--speed", "100", "--time-limit", "3000", "-q", "--trace", trace_path.to_str().unwrap()])
            .args([if life == 0 { "--journal" } else { "--resume" }, journal.to_str().unwrap()]);
        if let Some(n) = crash.take() {
            cmd.args(["--crash-after", &n.to_string()]);
        }
        let child = cmd.current_dir(root()).stderr(Stdio::piped()).stdout(Stdio::null()).spawn().expect("run mcl");
        let (status, err, _) = wait(child, LIMIT, me);
        match status.code() {
            Some(code) => {
                assert!(life <= 1, "{me}: more lives than crashes");
                return (code, trace(&trace_path), lines(&journal));
            }
            None => assert!(crash_after.is_some() && life == 0, "{me} died unexpectedly: {err}"),
        }
    }
    unreachable!()
}

/// Both vehicles at once, `auv` crashing after `auv_crash` syncs and `asc`
/// after `asc_crash` (each restarted at once).
fn auv_asc(auv_crash: Option<u64>, asc_crash: Option<u64>, tag: &str) -> [(i32, Vec<Record>, Vec<Value>); 2] {
    let (pa, pc) = (free_port(), free_port());
    let tag2 = tag.to_string();
    let asc = std::thread::spawn(move || vehicle("asc", pc, ("auv", pa), asc_crash, &tag2));
    let auv = vehicle("auv", pa, ("asc", pc), auv_crash, tag);
    [auv, asc.join().unwrap()]
}

#[test]
fn vehicles_killed_and_resumed_keep_every_constraint() {
    let reference = auv_asc_common::reference(&root(), &tmp("reference.jsonl"));
    // Crash points (journal syncs; the exact moment varies a little with
    // the timing of the messages): asc right after the AUV arrived at the
    // send_data sync (the AUV waits for it), asc once its own arrival is
    // sent, the AUV after deployment while the ASC works, the AUV while it
    // waits for the ASC at the sync, both vehicles in one run.
    let cases: [(Option<u64>, Option<u64>, &str); 5] = [
        (None, Some(6), "asc-at-sync"),
        (None, Some(9), "asc-after-arrival"),
        (Some(4), None, "auv-early"),
        (Some(7), None, "auv-at-sync"),
        (Some(10), Some(8), "both"),
    ];
    for (auv_crash, asc_crash, tag) in cases {
        let runs = auv_asc(auv_crash, asc_crash, tag);
        check(&runs, &reference, tag);
        // The crashed vehicle says it resumed.
        for (k, crash) in [auv_crash, asc_crash].iter().enumerate() {
            if crash.is_some() {
                assert!(
                    runs[k].1.iter().any(|r| matches!(&r.kind,
                        RecordKind::Link { message } if message.starts_with("resumed from the journal"))),
                    "{tag}"
                );
            }
        }
    }
}

/// The file of two vehicles that share a mutex: a holds it, b asks a for
/// it; b's survey ends before a goes up.
fn mutex_file(name: &str) -> PathBuf {
    let vehicle = root().join("examples/vehicle.mcl");
    let text = format!(
        "import \"{}\";\n\
         mission : a {{ Goto( [0, 0] ) : survey ; Surface() : up }}\n\
         mission : b {{ Goto( [5, 5] ) : survey }}\n\
         constraints {{\n    mutex {{ a:survey, b:survey }} = 1\n    order {{ b:survey, a:up }}\n}}\n",
        vehicle.display()
    );
    let path = tmp(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_lent_mutex_token_survives_a_crash_of_its_holder_or_its_borrower() {
    // b crashes once its survey has started on a's token; a crashes once
    // it has lent the token to b. The token stays lent while b is down (the
    // holder never takes it back); each comes back from its journal.
    let path = mutex_file("mutex-crash.mcl");
    let file = path.to_str().unwrap().to_string();
    for (a_crash, b_crash, tag) in [(None, Some(3), "borrower"), (Some(4), None, "holder")] {
        let (pa, pb) = (free_port(), free_port());
        let (f2, tag2) = (file.clone(), tag.to_string());
        let b = std::thread::spawn(move || vehicle_of(&[&f2], "b", pb, ("a", pa), b_crash, &tag2));
        let (ca, tra, _) = vehicle_of(&[&file], "a", pa, ("b", pb), a_crash, tag);
        let (cb, trb, _) = b.join().unwrap();
        assert_eq!((ca, cb), (0, 0), "{tag}");
        // a lent its token once, after its own survey ended; b's survey
        // started once, on that token, and a went up after b's survey ended.
        let lends: Vec<usize> = tra
            .iter()
            .enumerate()
            .filter(|(_, r)| {
                matches!(&r.kind, RecordKind::CoordSend { transition, .. } if transition == "coord.lend.mutex1.b")
            })
            .map(|(i, _)| i)
            .collect();
        assert_eq!(lends.len(), 1, "{tag}: lent once");
        assert!(call(&tra, "survey", ".release")[0] < lends[0], "{tag}: lent while a held it");
        let b_start = call(&trb, "survey", ".start");
        assert_eq!(b_start.len(), 1, "{tag}");
        assert!(received(&trb, "a", "coord.lend.mutex1.b").is_some_and(|g| g < b_start[0]), "{tag}");
        let b_end = fired(&trb[call(&trb, "survey", ".release")[0]]);
        let up = call(&tra, "up", ".start");
        assert!(received(&tra, "b", b_end).is_some_and(|r| up.len() == 1 && r < up[0]), "{tag}");
        for tr in [&tra, &trb] {
            for (k, cmds) in actions(tr) {
                assert_eq!(cmds, ["enable", "disable"], "{tag}: {k}");
            }
        }
    }
}

/// A loopback proxy from `listen` to `to` that keeps what the client sends.
fn proxy(to: u16) -> (u16, Arc<Mutex<Vec<String>>>) {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let keep = seen.clone();
    std::thread::spawn(move || {
        for client in l.incoming().take(500) {
            let Ok(client) = client else { return };
            // The other vehicle may not listen yet (a loaded machine starts
            // it later): drop this connection, the client connects again.
            let Ok(server) = TcpStream::connect(("127.0.0.1", to)) else { continue };
            let (mut c2, mut s2) = (client.try_clone().unwrap(), server.try_clone().unwrap());
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut s2, &mut c2);
            });
            let keep = keep.clone();
            std::thread::spawn(move || {
                let mut server = server;
                for line in BufReader::new(client).lines() {
                    let Ok(line) = line else { return };
                    keep.lock().unwrap().push(line.clone());
                    if server.write_all(format!("{line}\n").as_bytes()).is_err() {
                        return;
                    }
                }
            });
        }
    });
    (port, seen)
}

/// Sends `lines` on a new connection to `port`, waits a little for the
/// answer.
fn inject(port: u16, lines: &[String]) -> String {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(500))).unwrap();
    for l in lines {
        let _ = s.write_all(format!("{l}\n").as_bytes());
    }
    let mut back = String::new();
    let _ = s.read_to_string(&mut back);
    back
}

#[test]
fn forged_and_replayed_coordination_is_refused_and_logged() {
    // b reaches a through a proxy that keeps b's lines.
    let path = mutex_file("forged.mcl");
    let secret = tmp("fleet.secret");
    std::fs::write(&secret, "  correct horse battery staple\n").unwrap();
    let (pa, pb) = (free_port(), free_port());
    let (via, seen) = proxy(pa);
    let spawn = |me: &str, listen: u16, peer: &str, port: u16, speed: &str| {
        let tp = tmp(&format!("forged-{me}.jsonl"));
        let child = Command::new(env!("CARGO_BIN_EXE_mcl"))
            .args(["run", "--mock", path.to_str().unwrap(), "--vehicle", me])
            .args(["--coord-listen", &format!("127.0.0.1:{listen}")])
            .args(["--coord-peer", &format!("{peer}=127.0.0.1:{port}")])
            .args(["--coord-token-file", secret.to_str().unwrap()])
            .args(["--speed", speed, "--time-limit", "600", "--trace", tp.to_str().unwrap()])
            .current_dir(root())
            .stderr(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("run mcl");
        (child, tp)
    };
    // a is slow enough (20x) for the lines below to arrive while it runs.
    let (a, ta) = spawn("a", pa, "b", pb, "20");
    let (b, tb) = spawn("b", pb, "a", via, "20");
    // Wait until b has sent a message through the proxy.
    let start = Instant::now();
    let captured = loop {
        let s = seen.lock().unwrap().clone();
        if s.iter().any(|l| l.contains(r#""type":"msg""#)) {
            break s;
        }
        assert!(start.elapsed() < LIMIT, "b sent nothing: {s:?}");
        std::thread::sleep(Duration::from_millis(20));
    };
    let msg = captured.iter().find(|l| l.contains(r#""type":"msg""#)).unwrap().clone();
    // 1. A forged message: one plain line that would let a go up at once.
    let forged = r#"{"from":"b","to":"a","transition":"call1.release","seq":1,"t":0}"#.to_string();
    inject(pa, &[forged]);
    // 2. A captured message alone, without a handshake.
    inject(pa, std::slice::from_ref(&msg));
    // 3. The captured conversation replayed (hello, auth, messages).
    let back = inject(pa, &captured);
    assert!(back.contains("authentication failed"), "{back}");
    // 4. A hello and a guessed proof.
    let hello = captured[0].clone();
    assert!(hello.contains(r#""type":"hello""#), "{hello}");
    let back = inject(pa, &[hello, r#"{"type":"auth","proof":"00"}"#.into()]);
    assert!(back.contains(r#""type":"challenge""#), "{back}");

    let (sa, ea, log) = wait(a, LIMIT, "a");
    let (sb, eb, _) = wait(b, LIMIT, "b");
    assert_eq!(sa.code(), Some(0), "a: {ea}");
    assert_eq!(sb.code(), Some(0), "b: {eb}");
    let (tra, trb) = (trace(&ta), trace(&tb));
    let refused: Vec<&str> = tra
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::CoordReject { message } => Some(message.as_str()),
            _ => None,
        })
        .collect();
    assert!(refused.len() >= 4, "{refused:?}");
    assert!(refused.iter().any(|m| m.contains("no hello")), "{refused:?}");
    assert!(refused.iter().any(|m| m.contains("did not prove the fleet secret")), "{refused:?}");
    // Never applied: a received only what b sent, and went up after b's
    // survey ended.
    let got: Vec<&str> = receives(&tra).into_iter().map(|(_, t)| t).collect();
    assert_eq!(sends(&trb), got);
    assert!(!call(&trb, "survey", ".release").is_empty());
    let up = call(&tra, "up", ".start");
    let told = tra.iter().position(
        |r| matches!(&r.kind, RecordKind::CoordReceive { transition, .. } if transition.ends_with(".release")),
    );
    assert!(told.is_some_and(|t| up.len() == 1 && t < up[0]), "a went up before b's survey ended");
    // The live log says so too.
    assert!(log.contains("a: REFUSED  coordination: connection from 127.0.0.1:"), "{log}");
}

#[test]
fn a_listener_beyond_loopback_needs_a_secret() {
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_mcl"))
            .args(["run", "--mock", AUV_ASC, "--vehicle", "auv", "--coord-peer", "asc=127.0.0.1:9"])
            .args(extra)
            .current_dir(root())
            .output()
            .unwrap()
    };
    let out = run(&["--coord-listen", "0.0.0.0:0"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not a loopback address") && err.contains("--coord-token-file"), "{err}");
    assert!(err.contains("--coord-insecure"), "{err}");
    // An empty secret is no secret.
    let empty = tmp("empty.secret");
    std::fs::write(&empty, "\n").unwrap();
    let out = run(&["--coord-listen", "0.0.0.0:0", "--coord-token-file", empty.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("empty"));
    // The options go with --vehicle.
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--virtual-time", AUV_ASC, "--coord-token", "x"])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // --journal of several missions in one process names --vehicle.
    let out = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--virtual-time", AUV_ASC, "--journal"])
        .arg(tmp("j.jsonl"))
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--vehicle"));
}
