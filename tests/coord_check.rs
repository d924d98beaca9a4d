//! `mcl check` runs the coordination analysis: figure 6.9a of the seed,
//! written in MCL (tests/ui/e0406_order_cycle.mcl), is an error E0406 on both
//! orders with a counterexample (and E0408: the orders conflict by
//! construction), in the human and the JSON output; keeping
//! one order makes the file clean.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    dir.canonicalize().unwrap_or(dir)
}

fn mcl(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(dir).output().expect("run mcl")
}

const FIGURE: &str = "tests/ui/e0406_order_cycle.mcl";

#[test]
fn figure_6_9a_is_reported_in_json_with_both_orders_and_a_counterexample() {
    let out = mcl(&["check", "--format", "json", FIGURE], &root());
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Vec<Value> = serde_json::from_slice(&out.stdout).expect("JSON array");
    let e: Vec<&Value> = v.iter().filter(|d| d["code"] == "E0406").collect();
    assert_eq!(e.len(), 1, "{v:#?}");
    let d = e[0];
    assert_eq!(d["severity"], "error");
    assert!(d["file"].as_str().unwrap().ends_with("e0406_order_cycle.mcl"), "{d}");
    // Primary: the first order (line 16, 1-based), a label on the second.
    let text = std::fs::read_to_string(root().join(FIGURE)).unwrap();
    let line_of = |needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() as u64 + 1;
    assert_eq!(d["range"]["start"]["line"], line_of("order { v1:p2, v2:p5 }"), "{d}");
    let labels = d["labels"].as_array().unwrap();
    let label_lines: Vec<u64> = labels.iter().map(|l| l["range"]["start"]["line"].as_u64().unwrap()).collect();
    assert_eq!(label_lines, [line_of("order { v1:p2, v2:p5 }"), line_of("order { v2:p5, v1:p2 }")], "{d}");
    let notes: Vec<&str> = d["notes"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect();
    assert!(
        notes.iter().any(|n| n.starts_with("counterexample:") && n.contains("v1 `GotoTarget() : p2` is reached")),
        "{notes:?}"
    );
    assert!(notes.iter().any(|n| n.contains("`v2` waits at `v2:p5` (held by constraint 1)")), "{notes:?}");
    assert!(d["help"].as_str().is_some_and(|h| !h.is_empty()), "{d}");
}

#[test]
fn figure_6_9a_in_the_human_output_and_repaired_by_keeping_one_order() {
    let out = mcl(&["check", "--color", "never", FIGURE], &root());
    let s = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(1), "{s}");
    assert!(s.contains("[E0406] Error: these constraints can lead to a deadlock"), "{s}");
    assert!(s.contains("constraint 2 holds `v1:p2`"), "{s}");
    assert!(s.contains("[E0408] Error: constraints 1 and 2 conflict"), "{s}");
    assert!(s.contains("checked 2 files: 2 errors, 0 warnings"), "{s}");

    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("coord-check-fixed");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(root().join("tests/ui/vehicle.mcl"), dir.join("vehicle.mcl")).unwrap();
    let text = std::fs::read_to_string(root().join(FIGURE)).unwrap();
    std::fs::write(dir.join("fixed.mcl"), text.replace("    order { v2:p5, v1:p2 }\n", "")).unwrap();
    let out = mcl(&["check", "--color", "never", "fixed.mcl"], &dir);
    let s = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(0), "{s}");
    assert!(s.contains("0 errors, 0 warnings"), "{s}");
}
