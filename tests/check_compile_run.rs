//! `check` ⇒ `compile` ⇒ `run`, for programs we did not write (issue:
//! "Programs written by others").
//!
//! Generates programs with random user-chosen names — tasks, actions,
//! events, patterns, places, transitions, labels and missions, drawn from
//! everything the grammar allows for an identifier (`$`, `/`, `-`, `_`) and
//! from the names the compiler uses for its own nodes (`idle`, `lock`,
//! `run`, `start`, `call0`, `mission`, ...) — and random *valid* user
//! patterns (every kind of seed pattern: Extract 5.2 and compact task
//! patterns, the instantaneous shapes of figure 4.3 (a) to (d), waits and
//! time-outs, in random orders), called from random missions with every
//! control structure. Through the real `mcl` binary:
//!
//! * `mcl check` of every program is clean (no error, no warning): the
//!   patterns are valid by construction, so a refusal is a verifier that
//!   judges more than a mission can do to a block;
//! * `mcl compile` then succeeds and writes PNML whose ids are valid XML ids;
//! * `mcl run --mock --virtual-time` ends ok (exit 0) or fail (exit 1):
//!   never an internal error (2) and never stuck (3).
//!
//! `MCL_PROPERTY_CASES` (default 240) and `MCL_PROPERTY_SEED` change the run.

use mcl_syntax::gen::Rng;
use mcl_syntax::lexer::Kw;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Names the compiler or the runtime use for their own nodes and records.
const CLASHING: &[&str] = &[
    "idle", "lock", "run", "start", "stopping", "release", "cancel", "call0", "call1", "mission", "task", "env",
    "open", "stop", "kill", "done", "won_ok", "coord", "begin", "ok", "fail", "abort", "T0", "cs", "seq", "exe",
];

/// Words that cannot be names besides the keywords ([`Kw::ALL`]): the
/// constraint kinds, `at` of a mission's placement, and the one-letter
/// binding and parameter kinds `a:`, `e:`, `c:`, `v:`.
const RESERVED: &[&str] = &["mutex", "order", "sync", "at", "a", "e", "c", "v"];

fn reserved(n: &str) -> bool {
    RESERVED.contains(&n) || Kw::from_word(n).is_some()
}

/// A fresh identifier: a clashing name now and then, else random characters
/// from the whole identifier alphabet.
fn name(r: &mut Rng, used: &mut Vec<String>, clash_ok: bool) -> String {
    const START: &[u8] = b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ_$";
    const REST: &[u8] = b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_$-/";
    loop {
        let n = if clash_ok && r.chance(25) {
            r.pick(CLASHING).to_string()
        } else {
            let len = 2 + r.below(7);
            let mut s = String::new();
            s.push(*r.pick(START) as char);
            while s.len() < len {
                let c = *r.pick(REST) as char;
                // `//` and `/*` start comments; keep `/` away from them.
                if c == '/' && s.ends_with('/') {
                    continue;
                }
                s.push(c);
            }
            s
        };
        if reserved(&n) || used.contains(&n) {
            continue;
        }
        used.push(n.clone());
        return n;
    }
}

/// A user pattern and how a task binds it.
struct Shape {
    text: String,
    /// The task's binding lines: `a: ACTION -> T;`, `e: EVENT -> T;`.
    bindings: Vec<String>,
    /// A delay parameter the task header must have.
    param: Option<String>,
}

/// A valid pattern of a random kind, with random node names and orders.
fn pattern(r: &mut Rng, pname: &str, enable: &str, disable: &str, ok: &str, fail: &str) -> Shape {
    let mut used: Vec<String> = ["begin", "abort", "ok", "fail"].iter().map(|s| s.to_string()).collect();
    let mut n = |r: &mut Rng| name(r, &mut used, true);
    let places: Vec<String>;
    let transitions: Vec<String>;
    let arcs: Vec<(String, String)>;
    let bindings: Vec<String>;
    let param: Option<String>;
    let iface = |v: &mut Vec<String>| v.extend(["begin.1", "abort.1", "ok.1", "fail.1"].map(String::from));
    match r.below(7) {
        // A compact task pattern (figure 4.3(d) around a primitive).
        0 => {
            let (w, en, tok, tfail, tab) = (n(r), n(r), n(r), n(r), n(r));
            let mut p = vec![w.clone()];
            iface(&mut p);
            places = p;
            transitions = vec![en.clone(), tok.clone(), tfail.clone(), tab.clone()];
            arcs = vec![
                ("begin.1".into(), en.clone()),
                (en.clone(), w.clone()),
                (w.clone(), tok.clone()),
                (tok.clone(), "ok.1".into()),
                (w.clone(), tfail.clone()),
                (tfail.clone(), "fail.1".into()),
                (w.clone(), tab.clone()),
                ("abort.1".into(), tab.clone()),
            ];
            bindings = vec![
                format!("a: {enable} -> {en};"),
                format!("a: {disable} -> {tok}, {tfail}, {tab};"),
                format!("e: {ok} -> {tok};"),
                format!("e: {fail} -> {tfail};"),
            ];
            param = None;
        }
        // The seed's AchieveOneGoal (Extract 5.2), every node renamed.
        1 => {
            let pn: Vec<String> = (0..9).map(|_| n(r)).collect();
            let tn: Vec<String> = (0..10).map(|_| n(r)).collect();
            let [is_exe, is_ok, is_fail, en, dis, off, exe, pok, pfail] =
                [0, 1, 2, 3, 4, 5, 6, 7, 8].map(|i| pn[i].clone());
            let [tt0, tt1, tt2, tt3, t0, t1, t2, t3, t6, t7] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9].map(|i| tn[i].clone());
            let mut p: Vec<String> = pn.iter().map(|x| if *x == off { format!("{x}(1)") } else { x.clone() }).collect();
            iface(&mut p);
            places = p;
            transitions = tn.clone();
            let a = |x: &str, y: &str| (x.to_string(), y.to_string());
            arcs = vec![
                a("begin.1", &tt0),
                a(&tt0, &is_exe),
                a(&tt0, &en),
                a(&en, &t0),
                a(&t0, &exe),
                a(&exe, &t1),
                a(&exe, &t2),
                a(&exe, &t3),
                a(&t1, &off),
                a(&off, &tt0),
                a(&t2, &pok),
                a(&t3, &pfail),
                a(&pok, &t6),
                a(&pfail, &t7),
                a(&t6, &off),
                a(&t7, &off),
                a(&t2, &is_ok),
                a(&t3, &is_fail),
                a(&tt1, &dis),
                a(&dis, &t1),
                a(&dis, &t6),
                a(&dis, &t7),
                a(&tt2, &dis),
                a(&tt3, &dis),
                a(&is_ok, &tt2),
                a(&is_exe, &tt2),
                a(&is_exe, &tt1),
                a(&is_exe, &tt3),
                a(&is_fail, &tt3),
                a("abort.1", &tt1),
                a(&tt2, "ok.1"),
                a(&tt3, "fail.1"),
            ];
            bindings = vec![
                format!("a: {enable} -> {t0};"),
                format!("a: {disable} -> {t1}, {t6}, {t7};"),
                format!("e: {ok} -> {t2};"),
                format!("e: {fail} -> {t3};"),
            ];
            param = None;
        }
        // Instantaneous shapes of figure 4.3: (a), (b), (c), (c) as `abort.1 -> T`, (d).
        2 => {
            let (t_ok, t_fail, t_ab) = (n(r), n(r), n(r));
            let kind = r.below(5);
            let mut p = Vec::new();
            iface(&mut p);
            places = p;
            let mut t = vec![t_ok.clone()];
            let mut a = vec![("begin.1".to_string(), t_ok.clone()), (t_ok.clone(), "ok.1".to_string())];
            if kind == 1 || kind == 4 {
                t.push(t_fail.clone());
                a.push(("begin.1".into(), t_fail.clone()));
                a.push((t_fail.clone(), "fail.1".into()));
            }
            if kind == 2 || kind == 4 {
                t.push(t_ab.clone());
                a.push(("begin.1".into(), t_ab.clone()));
                a.push(("abort.1".into(), t_ab.clone()));
            }
            if kind == 3 {
                t.push(t_ab.clone());
                a.push(("abort.1".into(), t_ab.clone()));
            }
            transitions = t;
            arcs = a;
            bindings = vec![];
            param = None;
        }
        // A wait: a fixed delay or one from a task parameter.
        3 => {
            let (tw, tab) = (n(r), n(r));
            let delay = if r.chance(50) { format!("{}", 1 + r.below(20)) } else { n(r) };
            let mut p = Vec::new();
            iface(&mut p);
            places = p;
            transitions = vec![format!("{tw}({delay})"), tab.clone()];
            arcs = vec![
                ("begin.1".into(), tw.clone()),
                (tw.clone(), "ok.1".into()),
                ("begin.1".into(), tab.clone()),
                ("abort.1".into(), tab.clone()),
            ];
            bindings = vec![];
            param = delay.parse::<u32>().is_err().then_some(delay);
        }
        // A time-out around a primitive (figure 4.7, compact).
        4 => {
            let (w, go, done, broken, late, stop) = (n(r), n(r), n(r), n(r), n(r), n(r));
            let limit = n(r);
            let mut p = vec![w.clone()];
            iface(&mut p);
            places = p;
            transitions = vec![go.clone(), done.clone(), broken.clone(), format!("{late}({limit})"), stop.clone()];
            arcs = vec![
                ("begin.1".into(), go.clone()),
                (go.clone(), w.clone()),
                (w.clone(), done.clone()),
                (done.clone(), "ok.1".into()),
                (w.clone(), broken.clone()),
                (broken.clone(), "fail.1".into()),
                (w.clone(), late.clone()),
                (late.clone(), "fail.1".into()),
                (w.clone(), stop.clone()),
                ("abort.1".into(), stop.clone()),
            ];
            bindings = vec![
                format!("a: {enable} -> {go};"),
                format!("a: {disable} -> {done}, {broken}, {late}, {stop};"),
                format!("e: {ok} -> {done};"),
                format!("e: {fail} -> {broken};"),
            ];
            param = Some(limit);
        }
        // Waiting for one event only (an ok with no fail: a detector).
        5 => {
            let (w, en, t0, tab) = (n(r), n(r), n(r), n(r));
            let mut p = vec![w.clone()];
            iface(&mut p);
            places = p;
            transitions = vec![en.clone(), t0.clone(), tab.clone()];
            arcs = vec![
                ("begin.1".into(), en.clone()),
                (en.clone(), w.clone()),
                (w.clone(), t0.clone()),
                (t0.clone(), "ok.1".into()),
                (w.clone(), tab.clone()),
                ("abort.1".into(), tab.clone()),
            ];
            bindings = vec![
                format!("a: {enable} -> {en};"),
                format!("a: {disable} -> {t0}, {tab};"),
                format!("e: {ok} -> {t0};"),
            ];
            param = None;
        }
        // A guard place marked at rest, taken while running (the seed's `off`).
        _ => {
            let (guard, w, go, done, broken, stop) = (n(r), n(r), n(r), n(r), n(r), n(r));
            let mut p = vec![format!("{guard}(1)"), w.clone()];
            iface(&mut p);
            places = p;
            transitions = vec![go.clone(), done.clone(), broken.clone(), stop.clone()];
            arcs = vec![
                ("begin.1".into(), go.clone()),
                (guard.clone(), go.clone()),
                (go.clone(), w.clone()),
                (w.clone(), done.clone()),
                (done.clone(), "ok.1".into()),
                (done.clone(), guard.clone()),
                (w.clone(), broken.clone()),
                (broken.clone(), "fail.1".into()),
                (broken.clone(), guard.clone()),
                (w.clone(), stop.clone()),
                ("abort.1".into(), stop.clone()),
                (stop.clone(), guard.clone()),
            ];
            bindings = vec![
                format!("a: {enable} -> {go};"),
                format!("a: {disable} -> {done}, {broken}, {stop};"),
                format!("e: {ok} -> {done};"),
                format!("e: {fail} -> {broken};"),
            ];
            param = None;
        }
    }
    let (mut places, mut transitions, mut arcs) = (places, transitions, arcs);
    r.shuffle(&mut places);
    r.shuffle(&mut transitions);
    r.shuffle(&mut arcs);
    let mut text = format!("    {pname} {{\n        places {{ ");
    for p in &places {
        let _ = write!(text, "{p}; ");
    }
    text.push_str("}\n        transitions { ");
    for t in &transitions {
        let _ = write!(text, "{t}; ");
    }
    text.push_str("}\n        arcs { ");
    for (a, b) in &arcs {
        let _ = write!(text, "{a} -> {b}; ");
    }
    text.push_str("}\n    }\n");
    Shape { text, bindings, param }
}

/// A task call: the task, its argument count.
#[derive(Clone)]
struct Task {
    name: String,
    arity: usize,
}

fn call(
    r: &mut Rng,
    tasks: &[Task],
    allowed: &[usize],
    labels: &mut Vec<String>,
    used: &mut Vec<String>,
) -> (String, Vec<usize>) {
    let i = *r.pick(allowed);
    let t = &tasks[i];
    let args: Vec<String> = (0..t.arity).map(|_| format!("{}", 1 + r.below(30))).collect();
    let label = if r.chance(30) {
        let l = name(r, used, true);
        labels.push(l.clone());
        format!(" : {l}")
    } else {
        String::new()
    };
    (format!("{}( {} ){label}", t.name, args.join(", ")), vec![i])
}

/// A random block calling tasks of `allowed` (indices into `tasks`), with
/// the tasks it calls. A monitor's condition calls none of the tasks of its
/// watched block: they would wait for each other (W0303).
fn block(
    r: &mut Rng,
    tasks: &[Task],
    allowed: &[usize],
    depth: usize,
    labels: &mut Vec<String>,
    used: &mut Vec<String>,
) -> (String, Vec<usize>) {
    if depth == 0 || r.chance(35) {
        return call(r, tasks, allowed, labels, used);
    }
    let mut called = Vec::new();
    let mut b = |r: &mut Rng, allowed: &[usize], called: &mut Vec<usize>| {
        let (text, ts) = block(r, tasks, allowed, depth - 1, labels, used);
        called.extend(ts);
        text
    };
    let text = match r.below(8) {
        0 => format!("{} ; {}", b(r, allowed, &mut called), b(r, allowed, &mut called)),
        1 => format!("parallel {{ {} }} and {{ {} }}", b(r, allowed, &mut called), b(r, allowed, &mut called)),
        2 => format!(
            "parallel {{ {} }} or {{ {} }} or {{ {} }}",
            b(r, allowed, &mut called),
            b(r, allowed, &mut called),
            b(r, allowed, &mut called)
        ),
        3 => format!(
            "if ( {} ) {{ {} }} else {{ {} }}",
            b(r, allowed, &mut called),
            b(r, allowed, &mut called),
            b(r, allowed, &mut called)
        ),
        4 => format!("try {{ {} }} catch {{ {} }}", b(r, allowed, &mut called), b(r, allowed, &mut called)),
        5 => format!("not ( {} )", b(r, allowed, &mut called)),
        6 => {
            let watched = b(r, allowed, &mut called);
            let free: Vec<usize> = allowed.iter().copied().filter(|i| !called.contains(i)).collect();
            if free.is_empty() {
                format!("{watched} ; {}", b(r, allowed, &mut called))
            } else {
                let cond = b(r, &free, &mut called);
                format!("monitor {{ {watched} }} condition ( {cond} ) do {{ {} }}", b(r, allowed, &mut called))
            }
        }
        _ => format!("if ( {} ) {{ {} }}", b(r, allowed, &mut called), b(r, allowed, &mut called)),
    };
    (text, called)
}

/// One program: a vehicle with random patterns and tasks, one mission.
fn program(r: &mut Rng) -> String {
    let mut used: Vec<String> = Vec::new();
    let mut out = String::new();
    let ntasks = 1 + r.below(4);
    let mut actions = String::from("actions {\n");
    let mut events = String::from("events { ");
    let mut patterns = String::from("pattern {\n");
    let mut task_defs = String::from("tasks {\n");
    let mut tasks = Vec::new();
    for _ in 0..ntasks {
        let (prim, en, dis, ok, fail) = (
            name(r, &mut used, false),
            name(r, &mut used, false),
            name(r, &mut used, false),
            name(r, &mut used, false),
            name(r, &mut used, false),
        );
        let pname = name(r, &mut used, true);
        let shape = pattern(r, &pname, &en, &dis, &ok, &fail);
        let tname = name(r, &mut used, true);
        if shape.bindings.iter().any(|b| b.contains(&en)) {
            let _ = writeln!(actions, "    {en} = {prim}( c: enable );\n    {dis} = {prim}( c: disable );");
        }
        if shape.bindings.iter().any(|b| b.contains(&format!("e: {ok} "))) {
            let _ = write!(events, "{ok}; ");
        }
        if shape.bindings.iter().any(|b| b.contains(&format!("e: {fail} "))) {
            let _ = write!(events, "{fail}; ");
        }
        patterns.push_str(&shape.text);
        let params: Vec<String> = shape.param.iter().cloned().collect();
        let _ = writeln!(task_defs, "    {tname}( {} ): {pname} {{ {} }}", params.join(", "), shape.bindings.join(" "));
        tasks.push(Task { name: tname, arity: params.len() });
    }
    actions.push_str("}\n");
    events.push_str("}\n");
    patterns.push_str("}\n");
    task_defs.push_str("}\n");
    if actions != "actions {\n}\n" {
        out.push_str(&actions);
    }
    if events != "events { }\n" {
        out.push_str(&events);
    }
    out.push_str(&patterns);
    out.push_str(&task_defs);
    // Every task is called at least once (no "unused" warning).
    let mut labels = Vec::new();
    let all: Vec<usize> = (0..tasks.len()).collect();
    let mut body: Vec<String> = (0..tasks.len()).map(|i| call(r, &tasks, &[i], &mut labels, &mut used).0).collect();
    body.push(block(r, &tasks, &all, 3, &mut labels, &mut used).0);
    r.shuffle(&mut body);
    let header = if r.chance(50) { format!("mission : {} ", name(r, &mut used, true)) } else { "mission ".to_string() };
    let _ = writeln!(out, "{header}{{\n    {}\n}}", body.join(" ;\n    "));
    out
}

fn mcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).output().expect("run the mcl binary")
}

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-check-compile-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Whether `id` is an XML NCName (ASCII subset: what our writer emits).
fn is_ncname(id: &str) -> bool {
    let mut cs = id.chars();
    matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_'))
}

fn check_one(path: &Path, text: &str) -> Result<(), String> {
    let p = path.to_str().unwrap();
    let show = |what: &str, o: &std::process::Output| {
        format!(
            "{what} (exit {:?}) on\n{text}\nstdout:\n{}\nstderr:\n{}",
            o.status.code(),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    };
    let o = mcl(&["check", "--color", "never", p]);
    let out = String::from_utf8_lossy(&o.stdout);
    if o.status.code() != Some(0) || out.contains("warning[") || out.contains("error[") {
        return Err(show("`mcl check` is not clean", &o));
    }
    let pnml = path.with_extension("pnml");
    let o = mcl(&["compile", p, "-o", pnml.to_str().unwrap()]);
    if o.status.code() != Some(0) {
        return Err(show("`mcl compile` failed after a clean check", &o));
    }
    let xml = std::fs::read_to_string(&pnml).map_err(|e| e.to_string())?;
    for attr in
        ["<net id=\"", "<page id=\"", "<place id=\"", "<transition id=\"", "<arc id=\"", "source=\"", "target=\""]
    {
        for piece in xml.split(attr).skip(1) {
            let id = piece.split('"').next().unwrap_or("");
            if !is_ncname(id) {
                return Err(format!("PNML {attr}{id}\" is not a valid XML id, for\n{text}"));
            }
        }
    }
    let o = mcl(&["run", "--mock", "--virtual-time", "-q", p]);
    match o.status.code() {
        Some(0) | Some(1) => Ok(()),
        _ => Err(show("`mcl run --mock` did not end ok or fail", &o)),
    }
}

#[test]
fn clean_check_compiles_and_runs() {
    let cases: usize = std::env::var("MCL_PROPERTY_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(240);
    let seed: u64 = std::env::var("MCL_PROPERTY_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x5EED_2026);
    let dir = scratch();
    let programs: Vec<(PathBuf, String)> = (0..cases)
        .map(|i| {
            let mut r = Rng(seed.wrapping_add(i as u64).wrapping_mul(0x9E3779B97F4A7C15) | 1);
            (dir.join(format!("p{i:04}.mcl")), program(&mut r))
        })
        .collect();
    for (path, text) in &programs {
        std::fs::write(path, text).expect("write a program");
    }
    // Two workers: the machine CI runs on has two cores.
    let failures: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|w| {
                let programs = &programs;
                s.spawn(move || {
                    programs
                        .iter()
                        .skip(w)
                        .step_by(2)
                        .filter_map(|(path, text)| check_one(path, text).err())
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("worker")).collect()
    });
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        failures.is_empty(),
        "{} of {cases} programs broke check => compile => run (seed {seed}); the first three:\n{}",
        failures.len(),
        failures.iter().take(3).cloned().collect::<Vec<_>>().join("\n\n")
    );
}

/// The two programs of the issue: the instantaneous pattern whose `T1`
/// consumes a late abort, and a pattern whose places are named like the
/// compiler's own nodes (`idle`, `lock`, `run`, ...). Both check clean
/// (their UI snapshots say so), compile, and their missions run to ok.
#[test]
fn the_issue_patterns_compile_and_run() {
    let ui = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui");
    let dir = scratch().join("issue");
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["clean_instant_late_abort", "clean_place_named_idle"] {
        let file = ui.join(format!("{name}.mcl"));
        let out = dir.join(format!("{name}.pnml"));
        let o = mcl(&["compile", file.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let xml = std::fs::read_to_string(&out).unwrap();
        assert!(xml.contains("id=\"lock.") && xml.contains("id=\"task."), "{name}: lock and task nodes apart");
        let o = mcl(&["run", "--mock", "--virtual-time", file.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        // The compiled net runs as well as the source.
        let o = mcl(&["run", "--mock", "--virtual-time", "-q", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{name} from PNML: {}", String::from_utf8_lossy(&o.stderr));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
