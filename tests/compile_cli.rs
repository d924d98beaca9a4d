//! `mcl compile` and `mcl analyze` through the binary: Graphviz output with
//! and without `--out-dir`, and the fields of `mcl analyze --format json`.

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-compile-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(root()).output().expect("run mcl")
}

fn files(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn dot_without_a_path_writes_one_drawing_per_mission_into_the_out_dir() {
    let dir = tmp("per-mission");
    let d = dir.to_str().unwrap();
    // `--dot` last, with no value (as `mcl compile --help` shows it optional).
    let o = mcl(&["compile", "examples/survey.mcl", "--out-dir", d, "--dot"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(files(&dir), ["mission.dot", "mission.pnml"]);
    let dot = std::fs::read_to_string(dir.join("mission.dot")).unwrap();
    assert!(dot.starts_with("digraph"), "{dot}");
    // A file with several missions: one drawing per mission.
    let dir = tmp("several");
    let o = mcl(&["compile", "examples/mission-operators.mcl", "--dot", "--out-dir", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let names = files(&dir);
    let dots = names.iter().filter(|n| n.ends_with(".dot")).count();
    let pnmls = names.iter().filter(|n| n.ends_with(".pnml")).count();
    assert!(dots > 1 && dots == pnmls, "{names:?}");
}

#[test]
fn dot_with_a_path_and_dot_misuse() {
    let dir = tmp("one");
    let dot = dir.join("m.dot");
    let pnml = dir.join("m.pnml");
    let o = mcl(&["compile", "examples/survey.mcl", "--dot", dot.to_str().unwrap(), "-o", pnml.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read_to_string(&dot).unwrap().starts_with("digraph"));
    // No path and no folder: a usage error that says what to do.
    let o = mcl(&["compile", "examples/survey.mcl", "--dot"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--dot needs a path"));
    // A path with a folder: refused rather than ignored.
    let o = mcl(&["compile", "examples/survey.mcl", "--out-dir", dir.to_str().unwrap(), "--dot=x.dot"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("takes no path"));
}

#[test]
fn analyze_json_max_tokens_is_the_largest_place_bound() {
    let o = mcl(&["analyze", "--format", "json", "tests/data/mcc/Dekker-PT-010.pnml"]);
    assert_eq!(o.status.code(), Some(0));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["one_safe"], true);
    assert_eq!(v["max_tokens"], 1, "a 1-safe net: no place holds more than one token");
    assert_eq!(v["max_tokens_per_marking"], 20, "tokens of all places in one marking");
    let largest = v["bounds"].as_array().unwrap().iter().map(|b| b["bound"].as_u64().unwrap()).max().unwrap();
    assert_eq!(v["max_tokens"].as_u64(), Some(largest));
    assert!(v.get("max_tokens_in_place").is_none());
}

/// `--method por`: the stubborn-set exploration keeps the deadlock verdict
/// and the dead markings of the full one with fewer states; the MCL rule
/// is refused.
#[test]
fn analyze_method_por_keeps_the_deadlocks() {
    let net = "tests/data/mcc/Philosophers-PT-000005.pnml";
    let full: Value = serde_json::from_slice(&mcl(&["analyze", "--format", "json", net]).stdout).unwrap();
    let o = mcl(&["analyze", "--format", "json", "--method", "por", net]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let por: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(por["deadlock"], true);
    assert_eq!(por["complete"], true);
    assert_eq!(por["dead_markings"], full["dead_markings"]);
    assert!(por["states"].as_u64().unwrap() < full["states"].as_u64().unwrap(), "{por}");
    let o = mcl(&["analyze", "--method", "por", "--semantics", "mcl", net]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("plain rule only"));
}

/// `--threads`: the unordered workers give the one-thread counts and
/// verdict; `--shortest-paths` keeps the level-synchronous engine and so
/// the one-thread dead examples, paths included.
#[test]
fn analyze_threads_keep_counts_and_verdicts() {
    let net = "tests/data/mcc/Philosophers-PT-000005.pnml";
    let one: Value = serde_json::from_slice(&mcl(&["analyze", "--format", "json", net]).stdout).unwrap();
    for extra in [&[][..], &["--shortest-paths"][..]] {
        let mut args = vec!["analyze", "--format", "json", "--threads", "3"];
        args.extend_from_slice(extra);
        args.push(net);
        let o = mcl(&args);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        for key in ["states", "edges", "deadlock", "dead_markings", "complete", "bounds"] {
            assert_eq!(v[key], one[key], "{key} with {extra:?}");
        }
        let paths =
            |r: &Value| r["dead_examples"].as_array().unwrap().iter().map(|d| d["path"].clone()).collect::<Vec<_>>();
        if !extra.is_empty() {
            assert_eq!(paths(&v), paths(&one), "shortest paths");
        } else {
            assert_eq!(paths(&v).len(), paths(&one).len());
        }
    }
}

/// `--view structure` draws the mission's control structures and calls (a
/// picture a person can read whole: tens of nodes where the net has
/// hundreds); `--view task:NAME` draws one task's net; both need `--dot`.
#[test]
fn dot_views_structure_and_task() {
    let dir = tmp("views");
    let pnml = dir.join("m.pnml");
    // The drawing of the dam inspection with `--view VIEW`.
    let draw = |view: &str| {
        let dot = dir.join(format!("{}.dot", view.replace(':', "-")));
        let out = mcl(&[
            "compile",
            "examples/dam-inspection.mcl",
            "-o",
            pnml.to_str().unwrap(),
            "--dot",
            dot.to_str().unwrap(),
            "--view",
            view,
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        std::fs::read_to_string(&dot).unwrap()
    };
    let d = draw("structure");
    assert!(d.starts_with("digraph \"mission\" {"), "{d}");
    for want in ["monitor\\nline 17", "try-catch\\nline 18", "parallel-and\\nline 21", "Goto(initial_pos)\\nline 20"] {
        assert!(d.contains(want), "{want} in {d}");
    }
    assert!(d.contains("[label=\"catch\"]") && d.contains("[label=\"watched\"]"), "{d}");
    let nodes = d.lines().filter(|l| l.contains("shape=")).count();
    let net_nodes = draw("net").lines().filter(|l| l.contains("shape=")).count();
    assert!(nodes * 10 < net_nodes, "{nodes} structure nodes vs {net_nodes} net nodes");

    let t = draw("task:Goto");
    assert!(t.contains("TT0") && t.contains("?eventGotoOk"), "{t}");
    let task = dir.join("task.dot");

    // Unknown task, unknown view, a view without --dot: usage errors.
    let bad = |args: &[&str]| mcl(args).status.code();
    let p = pnml.to_str().unwrap();
    let tk = task.to_str().unwrap();
    assert_eq!(bad(&["compile", "examples/dam-inspection.mcl", "-o", p, "--dot", tk, "--view", "task:Nope"]), Some(2));
    assert_eq!(bad(&["compile", "examples/dam-inspection.mcl", "-o", p, "--dot", tk, "--view", "tree"]), Some(2));
    assert_eq!(bad(&["compile", "examples/dam-inspection.mcl", "-o", p, "--view", "structure"]), Some(2));
}

/// Every method of `mcl analyze` agrees with `oracle.json` on every MCC net:
/// the explicit search on one thread and on the threads without levels
/// (states, edges, deadlock, 1-safeness, the same dead markings and
/// bounds), and the stubborn sets (the deadlock verdict and the full
/// search's number of dead markings, never more states). `--method
/// symbolic` has its own test below.
#[test]
fn analyze_every_method_matches_the_oracle() {
    let dir = std::path::Path::new("tests/data/mcc");
    let oracle: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let oracle = oracle.as_object().unwrap();
    assert!(oracle.len() >= 10, "{}", oracle.len());
    let run = |args: &[&str]| -> Value {
        let o = mcl(args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    for (name, expect) in oracle {
        let net = dir.join(format!("{name}.pnml"));
        let net = net.to_str().unwrap();
        let one = run(&["analyze", "--format", "json", "--semantics", "plain", net]);
        let threads = run(&["analyze", "--format", "json", "--semantics", "plain", "--threads", "2", net]);
        for (what, v) in [("one thread", &one), ("two threads", &threads)] {
            assert_eq!(v["complete"], true, "{name} {what}");
            for key in ["states", "edges", "deadlock", "one_safe"] {
                assert_eq!(v[key], expect[key], "{name} {what} {key}");
            }
        }
        for key in ["dead_markings", "bounds"] {
            assert_eq!(threads[key], one[key], "{name} {key}");
        }
        let por = run(&["analyze", "--format", "json", "--method", "por", net]);
        assert_eq!(por["complete"], true, "{name} por");
        assert_eq!(por["deadlock"], expect["deadlock"], "{name} por");
        assert_eq!(por["dead_markings"], one["dead_markings"], "{name} por");
        assert!(por["states"].as_u64().unwrap() <= one["states"].as_u64().unwrap(), "{name} por {por}");
    }
}

/// `--method symbolic`: the decision-diagram exploration gives the
/// oracle's states, edges, deadlock verdict and 1-safeness on every MCC
/// net (the large ones included), the explicit search's dead markings and
/// bounds, and a dead example whose path the net replays; the MCL rule is
/// refused, and a node limit too small gives an incomplete report.
#[test]
fn analyze_method_symbolic_matches_the_oracle() {
    let dir = std::path::Path::new("tests/data/mcc");
    let oracle: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let oracle = oracle.as_object().unwrap();
    assert!(!oracle.is_empty());
    for (name, expect) in oracle {
        let net = dir.join(format!("{name}.pnml"));
        let net = net.to_str().unwrap();
        let o = mcl(&["analyze", "--format", "json", "--method", "symbolic", net]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let sym: Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(sym["complete"], true, "{name}");
        for key in ["states", "edges", "deadlock", "one_safe"] {
            assert_eq!(sym[key], expect[key], "{name} {key}");
        }
        assert_eq!(sym["deadlock"].as_bool().unwrap(), !sym["dead_example"].is_null(), "{name}");
    }
    let net = "tests/data/mcc/Philosophers-PT-000005.pnml";
    let full: Value = serde_json::from_slice(&mcl(&["analyze", "--format", "json", net]).stdout).unwrap();
    let sym: Value =
        serde_json::from_slice(&mcl(&["analyze", "--format", "json", "--method", "symbolic", net]).stdout).unwrap();
    for key in ["dead_markings", "max_tokens", "max_tokens_per_marking"] {
        assert_eq!(sym[key], full[key], "{key}");
    }
    assert_eq!(
        sym["dead_example"]["path_names"].as_array().unwrap().len(),
        full["dead_examples"][0]["path_names"].as_array().unwrap().len(),
        "a shortest path"
    );
    let o = mcl(&["analyze", "--method", "symbolic", "--order", "pnml", net]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("reachable markings: 243") && text.contains("dead markings: 2"), "{text}");
    let o = mcl(&["analyze", "--method", "symbolic", "--semantics", "mcl", net]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("plain rule only"));
    let o = mcl(&["analyze", "--format", "json", "--method", "symbolic", "--max-states", "20", net]);
    let cut: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(cut["complete"], false);
    assert_eq!(cut["stop"]["kind"], "node_limit");
}
