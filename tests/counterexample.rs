//! `mcl check --counterexample-scenario` through the binary: the scenario it
//! writes for a deadlock (E0406 of coordinated missions, E0601 of a task a
//! mission calls) makes `mcl run --mock --virtual-time` end stuck (exit
//! status 3) in the marking the diagnostic names, and `mcl run` says so.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run mcl")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("counterexample").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `mcl check FILE --counterexample-scenario OUT`: exit status 1 (the file
/// has errors), and the scenario's text.
fn check_writes(file: &str, out: &Path) -> String {
    let o = mcl(&["check", file, "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(&format!("written to {}", out.display())), "{err}");
    std::fs::read_to_string(out).unwrap_or_else(|e| panic!("{e}: {err}"))
}

/// `mcl run --mock --virtual-time FILE --scenario SCENARIO --trace ...`:
/// the exit status, standard error and the trace records.
fn run(file: &str, scenario: &Path) -> (Option<i32>, String, Vec<Value>) {
    let trace = scenario.with_extension("jsonl");
    let o = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        "-q",
        file,
        "--scenario",
        scenario.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    let records =
        std::fs::read_to_string(&trace).unwrap_or_default().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    (o.status.code(), stderr(&o), records)
}

/// The result of each mission's `outcome` record.
fn outcomes(records: &[Value]) -> Vec<(String, String)> {
    records
        .iter()
        .filter(|r| r["kind"] == "outcome")
        .map(|r| (r["mission"].as_str().unwrap_or("").to_string(), r["result"].as_str().unwrap().to_string()))
        .collect()
}

/// The lines of the `[counterexample.marking]` table: (mission, places).
fn marking(scenario: &str) -> Vec<(String, String)> {
    let table = scenario.split("[counterexample.marking]\n").nth(1).unwrap_or("");
    table
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_once(" = ").map(|(k, v)| (k.to_string(), v.to_string())))
        .collect()
}

#[test]
fn order_cycle_replays_to_both_vehicles_waiting() {
    let dir = out_dir("order_cycle");
    let out = dir.join("cycle.toml");
    let file = "tests/ui/e0406_order_cycle.mcl";
    let text = check_writes(file, &out);
    assert!(text.contains("code = \"E0406\"") && text.contains("at = \"tests/ui/e0406_order_cycle.mcl:16\""), "{text}");
    let m = marking(&text);
    assert_eq!(m.iter().map(|(k, _)| k.as_str()).collect::<Vec<_>>(), ["v1", "v2"], "{text}");
    let (code, err, records) = run(file, &out);
    assert_eq!(code, Some(3), "{err}");
    assert!(err.contains("the vehicle nets are built all the same"), "{err}");
    assert!(err.contains("counterexample of E0406 at tests/ui/e0406_order_cycle.mcl:16: reproduced"), "{err}");
    assert_eq!(outcomes(&records), [("v1".into(), "stuck".into()), ("v2".into(), "stuck".into())]);
    // Neither call ever started: no action was sent.
    assert!(!records.iter().any(|r| r["kind"] == "action"), "{records:?}");
}

#[test]
fn withdrawn_sync_partner_replays_to_the_auv_waiting_for_ever() {
    let dir = out_dir("sync_withdrawn");
    let out = dir.join("sync.toml");
    let file = "tests/ui/e0406_sync_partner_withdrawn.mcl";
    let text = check_writes(file, &out);
    assert!(text.contains("kind = \"stuck\"") && text.contains("waiting = [\"auv:send\"]"), "{text}");
    let (code, err, records) = run(file, &out);
    assert_eq!(code, Some(3), "{err}");
    assert!(err.contains("reproduced (`asc` ended, `auv` stuck"), "{err}");
    let mut o = outcomes(&records);
    o.sort();
    assert_eq!(o, [("asc".into(), "ok".into()), ("auv".into(), "stuck".into())]);
    // The ASC's loop test failed (its nominal answer): that withdrew the receive.
    assert!(
        records.iter().any(|r| r["kind"] == "event" && r["mission"] == "asc" && r["event"] == "eventGotoTargetFail"),
        "{records:?}"
    );
    // The AUV's send never started.
    assert!(!records.iter().any(|r| r["kind"] == "action" && r["task"] == "SendData"), "{records:?}");

    // Without the ASC's events the run ends elsewhere, and `mcl run` says so.
    let cut: String = text.split("\n[[missions.asc.events]]").next().unwrap().to_string();
    let other = dir.join("cut.toml");
    std::fs::write(&other, cut).unwrap();
    let (code, err, _) = run(file, &other);
    assert_eq!(code, Some(3), "{err}");
    assert!(err.contains("NOT reproduced"), "{err}");
}

#[test]
fn a_pattern_that_never_ends_replays_to_its_task_stuck() {
    let dir = out_dir("never_marked");
    let out = dir.join("never.toml");
    let file = "tests/ui/e0601_never_marked.mcl";
    let text = check_writes(file, &out);
    assert!(text.contains("code = \"E0601\"") && text.contains("e0601_never_marked.mcl:10"), "{text}");
    let m = marking(&text);
    assert_eq!(m.len(), 1, "{text}");
    assert_eq!(m[0].0, "mission");
    assert!(m[0].1.contains("\"task.Sonar.running\""), "{text}");
    let (code, err, records) = run(file, &out);
    assert_eq!(code, Some(3), "{err}");
    assert!(err.contains("breaks block properties (E06xx); it is run all the same"), "{err}");
    assert!(err.contains("counterexample of E0601 at tests/ui/e0601_never_marked.mcl:10: reproduced"), "{err}");
    assert_eq!(outcomes(&records), [(String::new(), "stuck".into())]);
    // The primitive was enabled, and nothing ended it.
    assert!(records.iter().any(|r| r["kind"] == "action" && r["task"] == "Sonar"), "{records:?}");
}

#[test]
fn several_counterexamples_are_numbered_and_a_violation_that_does_not_stop_the_mission_is_explained() {
    let dir = out_dir("several");
    let src = dir.join("two.mcl");
    std::fs::write(
        &src,
        "pattern {\n    P_DEAD {\n        places { begin.1; abort.1; ok.1; fail.1; run; }\n        transitions { T0; TA; }\n        arcs { begin.1 -> T0; T0 -> run; run -> TA; abort.1 -> TA; }\n    }\n}\ntasks { A(): P_DEAD { } B(): P_DEAD { } }\nmission { parallel { A() } and { B() } }\n",
    )
    .unwrap();
    let out = dir.join("cex.toml");
    let o = mcl(&["check", src.to_str().unwrap(), "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for k in [1, 2] {
        let p = dir.join(format!("cex-{k}.toml"));
        assert!(err.contains(&format!("written to {}", p.display())), "{err}");
        let (code, err, _) = run(src.to_str().unwrap(), &p);
        assert_eq!(code, Some(3), "{err}");
        assert!(err.contains(": reproduced"), "{err}");
    }
    assert!(!out.exists());

    // A leaky pattern breaks reusability but never stops its one call: no file.
    let out = dir.join("leaky.toml");
    let o = mcl(&["check", "tests/ui/e0601_leaky_pattern.mcl", "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("no scenario replays the counterexample of E0601") && err.contains("does not stop"), "{err}");
    assert!(!out.exists());
}

/// A task defined in an imported file and called by one of several
/// missions: the scenario runs that mission (`--mission`).
#[test]
fn an_imported_task_is_replayed_in_the_mission_that_calls_it() {
    let dir = out_dir("imported");
    std::fs::write(
        dir.join("lib.mcl"),
        "pattern {\n    P_DEAD {\n        places { begin.1; abort.1; ok.1; fail.1; run; }\n        transitions { T0; TA; }\n        arcs { begin.1 -> T0; T0 -> run; run -> TA; abort.1 -> TA; }\n    }\n}\ntasks { A(): P_DEAD { } B(): Instant { } }\n",
    )
    .unwrap();
    let main = dir.join("main.mcl");
    std::fs::write(&main, "import \"lib.mcl\";\nmission : one { B() ; A() }\nmission : two { B() }\n").unwrap();
    let out = dir.join("cex.toml");
    let o = mcl(&["check", main.to_str().unwrap(), "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("counterexample of E0601 at ") && err.contains("lib.mcl:"), "{err}");
    assert!(err.contains("--mission one --scenario"), "{err}");
    let o = mcl(&[
        "run",
        "--mock",
        "--virtual-time",
        "-q",
        main.to_str().unwrap(),
        "--mission",
        "one",
        "--scenario",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains(": reproduced (`one` stuck"), "{err}");
}

#[test]
fn without_the_flag_or_with_other_errors_nothing_changes() {
    let dir = out_dir("unchanged");
    // `mcl check` without the flag writes nothing and says nothing more.
    let o = mcl(&["check", "tests/ui/e0406_order_cycle.mcl"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!stderr(&o).contains("counterexample of"), "{}", stderr(&o));
    // A clean file has no counterexample.
    let out = dir.join("none.toml");
    let o = mcl(&["check", "examples/survey.mcl", "--counterexample-scenario", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("no deadlock counterexample to write"), "{}", stderr(&o));
    assert!(!out.exists());
    // A counterexample scenario does not make `mcl run` accept other errors.
    let cex = dir.join("cex.toml");
    check_writes("tests/ui/e0601_needs_abort.mcl", &cex);
    let broken = dir.join("broken.mcl");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ui/e0601_needs_abort.mcl"))
        .unwrap()
        .replace("mission { A() }", "mission { A() ; Missing() }");
    std::fs::write(&broken, text).unwrap();
    let (code, err, _) = run(broken.to_str().unwrap(), &cex);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("E0101") || err.contains("has errors"), "{err}");
    // ... and a run without such a scenario still refuses verification errors.
    let o = mcl(&["run", "--mock", "--virtual-time", "tests/ui/e0601_needs_abort.mcl"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = mcl(&["run", "--mock", "--virtual-time", "tests/ui/e0406_order_cycle.mcl"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no vehicle net was made"), "{}", stderr(&o));
}

/// Two random missions (the batch of `mcl-coord/tests/property.rs`) whose
/// counterexample needs a vehicle to start late: the verifier moves each
/// vehicle at its own pace, and `b` takes the mutex before `a` moves, while
/// a dry run starts `a` first. The scenario starts `a` late
/// (`[counterexample.start]`), and `mcl run` reproduces it.
#[test]
fn a_counterexample_that_needs_a_late_start_replays() {
    let dir = out_dir("late_start");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/vehicle.mcl"), dir.join("vehicle.mcl")).unwrap();
    let file = dir.join("late.mcl");
    std::fs::write(
        &file,
        "import \"vehicle.mcl\";\n\
         mission : a { parallel { Goto( p ) : l1 } or { try { Void() : l2 } catch { SendData() : l3 } } }\n\
         mission : b { parallel { parallel { Surface() : l1 } or { Goto( p ) : l2 } } and { parallel { Surface() : l3 } and { Void() : l4 } } }\n\
         constraints {\n mutex { a:l1, b:l3 } = 1\n sync { a:l1, b:l4 }\n}\n",
    )
    .unwrap();
    let file = file.to_str().unwrap();
    let out = dir.join("late.toml");
    let o = mcl(&["check", file, "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let mut written: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    written.sort();
    assert!(!written.is_empty(), "{err}");
    let mut late = 0;
    for scenario in &written {
        let text = std::fs::read_to_string(scenario).unwrap();
        let starts = text.contains("[counterexample.start]");
        late += usize::from(starts);
        let (code, err, records) = run(file, scenario);
        assert_eq!(code, Some(3), "{err}\n{text}");
        assert!(err.contains(": reproduced"), "{err}\n{text}");
        if starts {
            // The late vehicle fires nothing before its start time, and the
            // other vehicle moves before.
            let first = |m: &str| {
                records.iter().find(|r| r["mission"] == m && r["kind"] == "fire").and_then(|r| r["t"].as_f64())
            };
            let table = text.split("[counterexample.start]\n").nth(1).unwrap_or("");
            for line in table.lines().take_while(|l| !l.trim().is_empty()) {
                let (m, t) = line.split_once(" = ").unwrap();
                let t: f64 = t.parse().unwrap();
                assert!(t > 0.0, "{text}");
                assert!(first(m).is_none_or(|x| x >= t), "{text}\n{records:?}");
                let before =
                    records.iter().any(|r| r["mission"] != m && r["kind"] == "fire" && r["t"].as_f64() < Some(t));
                assert!(before, "nothing moved before `{m}` started\n{text}\n{records:?}");
            }
        }
    }
    assert!(late > 0, "no scenario needed a late start: {written:?}\n{err}");
}

/// A counterexample that needs a coordination message delivered late
/// (found by random seeds): the scenario's `[[counterexample.delay]]`
/// holds a message until after the other vehicle's event; the
/// dry run reproduces it, and the same scenario without the delay does not.
#[test]
fn a_late_message_replays_a_counterexample_that_needs_one() {
    let dir = out_dir("delay");
    std::fs::copy("examples/vehicle.mcl", dir.join("vehicle.mcl")).unwrap();
    let src = dir.join("m.mcl");
    std::fs::write(
        &src,
        "import \"vehicle.mcl\";\n\
         mission : a { try { try { SendData() : l1 } catch { SendData() : l2 } } catch { Surface() : l3 ; GotoTarget() : l4 } }\n\
         mission : b { monitor { Goto( p ) : l1 } condition ( Alarm() ) do { Surface() } }\n\
         constraints {\n sync { a:l1, b:l1 }\n sync { a:l4, b:l1 }\n}\n",
    )
    .unwrap();
    let out = dir.join("cex.toml");
    let o = mcl(&["check", src.to_str().unwrap(), "--counterexample-scenario", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // Two problems, one scenario each (`cex-1.toml`, `cex-2.toml`): the
    // first (`a:l1` waits for ever) needs the late message.
    let out = dir.join("cex-1.toml");
    let text = std::fs::read_to_string(&out).unwrap_or_else(|e| panic!("{e}: {}", stderr(&o)));
    assert!(text.contains("[[counterexample.delay]]"), "{text}");
    let (code, err, _) = run(src.to_str().unwrap(), &out);
    assert_eq!(code, Some(3), "{err}");
    assert!(err.contains(": reproduced"), "{err}");
    // Without the late message, the dry run ends elsewhere.
    let start = text.find("\n[[counterexample.delay]]").unwrap();
    let end = text[start + 1..].find("\n\n").map_or(text.len(), |k| start + 1 + k);
    let undelayed = dir.join("undelayed.toml");
    std::fs::write(&undelayed, format!("{}{}", &text[..start], &text[end..])).unwrap();
    let (_, err, _) = run(src.to_str().unwrap(), &undelayed);
    assert!(!err.contains(": reproduced"), "{err}");
}

/// Case seed 40 of `mcl-coord/tests/property.rs`: the analysis' path to
/// the deadlock is one that no dry run follows, so the reported problem is
/// the exact product's own run (the players with their messages in
/// flight, `mcl_coord::replay::analyze_replayable`). The diagnostic, the
/// scenario and the dry run then agree: the scenario's waiting calls and
/// message are the diagnostic's, each waiting call is one the diagnostic
/// names, and the dry run ends stuck (exit status 3) in the scenario's
/// marking, which is the diagnostic's.
#[test]
fn a_counterexample_from_the_exact_product_is_the_one_the_diagnostic_names() {
    let dir = out_dir("exact_run");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/vehicle.mcl"), dir.join("vehicle.mcl")).unwrap();
    let src = dir.join("m.mcl");
    std::fs::write(
        &src,
        "import \"vehicle.mcl\";\n\
         mission : a { monitor { parallel { Deploy() : l1 } or { SendData() : l2 } } condition ( Alarm() ) do { Surface() } }\n\
         mission : b { parallel { Void() : l1 } or { Goto( p ) : l2 } ; parallel { SendData() : l3 } and { Surface() : l4 } }\n\
         constraints {\n order { b:l1, a:l1 }\n sync { a:l2, b:l1 }\n sync { a:l2, b:l4 }\n}\n",
    )
    .unwrap();
    let file = src.to_str().unwrap();
    let o = mcl(&["check", file, "--format", "json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let diags: Vec<Value> = serde_json::from_slice(&o.stdout).unwrap();
    let e0406: Vec<&Value> = diags.iter().filter(|d| d["code"] == "E0406").collect();
    assert!(!e0406.is_empty(), "{diags:?}");
    let out = dir.join("cex.toml");
    let o = mcl(&["check", file, "--counterexample-scenario", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let scenarios: Vec<PathBuf> = if e0406.len() == 1 {
        vec![out.clone()]
    } else {
        (1..=e0406.len()).map(|k| dir.join(format!("cex-{k}.toml"))).collect()
    };
    let mut delayed = 0;
    for (d, scenario) in e0406.iter().zip(&scenarios) {
        let text = std::fs::read_to_string(scenario).unwrap_or_else(|e| panic!("{e}: {err}"));
        delayed += usize::from(text.contains("[[counterexample.delay]]"));
        let message = d["message"].as_str().unwrap();
        assert!(text.contains(&format!("message = {}", toml_string(message))), "{message}\n{text}");
        // Every call the scenario waits for is one the diagnostic names.
        let waiting = text.lines().find_map(|l| l.strip_prefix("waiting = ")).unwrap_or("[]");
        for w in waiting.trim_matches(|c| c == '[' || c == ']').split(", ").filter(|w| !w.is_empty()) {
            assert!(message.contains(&format!("`{}`", w.trim_matches('"'))), "{message}\n{text}");
        }
        let notes: Vec<&str> = d["notes"].as_array().unwrap().iter().filter_map(|n| n.as_str()).collect();
        let path = notes.iter().find_map(|n| n.strip_prefix("counterexample: ")).expect("a counterexample note");
        let state = notes.iter().find_map(|n| n.strip_prefix("then nothing can fire: ")).expect("a state note");
        let (code, err, records) = run(file, scenario);
        assert_eq!(code, Some(3), "{err}\n{text}");
        assert!(err.contains(": reproduced"), "{err}\n{text}");
        for (mission, _) in marking(&text) {
            // The calls the diagnostic's path starts are those the dry run
            // starts, in order.
            let said: Vec<&str> = path
                .split(", then ")
                .filter_map(|step| step.strip_prefix(&format!("{mission} `"))?.strip_suffix(" starts"))
                .filter_map(|call| call.split('(').next())
                .collect();
            let done: Vec<&str> = records
                .iter()
                .filter(|r| r["kind"] == "action" && r["mission"] == mission.as_str() && r["command"] == "enable")
                .filter_map(|r| r["task"].as_str())
                .collect();
            assert_eq!(said, done, "mission `{mission}`: {path}\n{records:?}");
            // It ends as the diagnostic's state says.
            let result = outcomes(&records).into_iter().find(|(m, _)| *m == mission).map(|(_, r)| r);
            let ended = state.contains(&format!("`{mission}` has ended"));
            assert_eq!(result.as_deref() != Some("stuck"), ended, "{state}\n{records:?}");
        }
    }
    assert!(delayed > 0, "no scenario needed a late message: {scenarios:?}\n{err}");
}

/// A TOML basic string.
fn toml_string(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}
