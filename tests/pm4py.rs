//! Our PNML is read by a widely used third-party reader (pm4py, from PyPI)
//! with the same places, transitions, arcs and initial marking. Skipped when
//! pm4py cannot be imported, unless MCL_REQUIRE_PM4PY=1 (CI installs pm4py
//! and sets it), which makes that a failure.

use mcl_compiler::compile::compile_file;
use mcl_compiler::{Database, Db};
use std::path::Path;
use std::process::Command;

#[test]
fn pm4py_reads_our_pnml() {
    let found = mcl_testutil::runs("python3", &["-c", "import pm4py"]);
    if !mcl_testutil::have_tool("pm4py", found, "python3 -m pip install pm4py") {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("mcl-pm4py-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let db = Database::new();
    let mut checked = 0;
    for example in ["extract-5-4.mcl", "survey.mcl", "dam-inspection.mcl", "auv-asc.mcl", "pnml-pattern.mcl"] {
        let file = db.file(&root.join("examples").join(example));
        for m in compile_file(&db, file).unwrap_or_else(|e| panic!("{example}: {e}")) {
            let path = dir.join(format!("{}-{}.pnml", example, m.name));
            std::fs::write(&path, mcl_net::write_pnml(&m.net).unwrap()).unwrap();
            let out = Command::new("python3").arg(root.join("tests/pm4py_reader.py")).arg(&path).output().unwrap();
            assert!(
                out.status.success(),
                "pm4py failed on {}: {}",
                path.display(),
                String::from_utf8_lossy(&out.stderr)
            );
            let got: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            let net = &m.net;
            let mut places: Vec<&str> = net.places().iter().map(|p| p.id.as_str()).collect();
            places.sort();
            let mut transitions: Vec<&str> = net.transitions().iter().map(|t| t.id.as_str()).collect();
            transitions.sort();
            let mut arcs: Vec<serde_json::Value> = net
                .arcs()
                .iter()
                .map(|a| match *a {
                    mcl_net::Arc::Input { place, transition, weight } => serde_json::json!([
                        net.place(place).unwrap().id,
                        net.transition(transition).unwrap().id,
                        weight
                    ]),
                    mcl_net::Arc::Output { transition, place, weight } => serde_json::json!([
                        net.transition(transition).unwrap().id,
                        net.place(place).unwrap().id,
                        weight
                    ]),
                })
                .collect();
            arcs.sort_by_key(|a| a.to_string());
            let mut got_arcs = got["arcs"].as_array().unwrap().clone();
            got_arcs.sort_by_key(|a| a.to_string());
            let initial: serde_json::Map<String, serde_json::Value> =
                net.places().iter().filter(|p| p.initial > 0).map(|p| (p.id.to_string(), p.initial.into())).collect();
            assert_eq!(got["places"], serde_json::json!(places), "{example}/{}", m.name);
            assert_eq!(got["transitions"], serde_json::json!(transitions), "{example}/{}", m.name);
            assert_eq!(got_arcs, arcs, "{example}/{}", m.name);
            assert_eq!(got["initial"], serde_json::Value::Object(initial), "{example}/{}", m.name);
            checked += 1;
        }
    }
    assert!(checked >= 6);
    let _ = std::fs::remove_dir_all(&dir);
}
