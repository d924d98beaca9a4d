//! The Model Checking Contest nets of `tests/data/mcc` (a copy of
//! `shared/data/mcc`) against their oracle.

use std::path::PathBuf;

use mcl_net::{analyze, read_pnml, Options, Semantics};

fn mcc_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mcc")
}

/// The three nets with 1.8 to 2.9 million states (benchmarks).
const LARGE: [&str; 3] = ["SharedMemory-PT-000010", "Kanban-PT-00005", "FMS-PT-00005"];

fn check(names: &dyn Fn(&str) -> bool, configs: &[(Semantics, usize)]) {
    let dir = mcc_dir();
    let oracle: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let oracle = oracle.as_object().unwrap();
    let mut checked = 0;
    for (name, expect) in oracle {
        if !names(name) {
            continue;
        }
        let text = std::fs::read_to_string(dir.join(format!("{name}.pnml"))).unwrap();
        let net = read_pnml(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        for &(semantics, threads) in configs {
            let opts = Options { semantics, threads, ..Options::default() };
            let start = std::time::Instant::now();
            let r = analyze(&net, &opts);
            eprintln!(
                "{name} {semantics:?} ({threads} threads): {} states, {} edges in {:.2?}",
                r.states,
                r.edges,
                start.elapsed()
            );
            assert!(r.complete, "{name}");
            assert_eq!(r.states, expect["states"].as_u64().unwrap(), "{name} states");
            assert_eq!(r.edges, expect["edges"].as_u64().unwrap(), "{name} edges");
            assert_eq!(r.deadlock, expect["deadlock"].as_bool().unwrap(), "{name} deadlock");
            assert_eq!(r.one_safe, expect["one_safe"].as_bool().unwrap(), "{name} one_safe");
            assert_eq!(r.deadlock, !r.dead_examples.is_empty());
            // Nets without MCL data have only immediate transitions: both
            // semantics coincide, and every dead example is reached by its path.
            for d in &r.dead_examples {
                let mut m = net.initial_marking();
                for &t in &d.path {
                    mcl_net::semantics::fire(&net, &mut m, t).unwrap();
                }
                assert!(mcl_net::semantics::enabled(&net, &m).is_empty());
            }
        }
        checked += 1;
    }
    assert!(checked > 0);
}

#[test]
fn mcc_nets_match_oracle() {
    check(&|n| !LARGE.contains(&n), &[(Semantics::Plain, 1), (Semantics::Mcl, 1), (Semantics::Plain, 2)]);
}

/// ~2-3 million states each (a few seconds each: mcl-net is optimised in
/// the test profile). Nets without MCL data have only immediate
/// transitions, so one semantics is enough.
#[test]
fn mcc_large_nets_match_oracle() {
    check(&|n| LARGE.contains(&n), &[(Semantics::Plain, 1)]);
}
