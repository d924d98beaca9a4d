//! The Model Checking Contest nets of `tests/data/mcc` (a copy of
//! `shared/data/mcc`) against their oracle.

use std::path::PathBuf;

use mcl_net::{analyze, read_pnml, Options, Semantics};

fn mcc_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mcc")
}

/// The three nets with 1.8 to 2.9 million states (benchmarks).
const LARGE: [&str; 3] = ["SharedMemory-PT-000010", "Kanban-PT-00005", "FMS-PT-00005"];

/// Checks the nets `names` accepts with every `(semantics, threads, exact
/// order)` of `configs`.
fn check(names: &dyn Fn(&str) -> bool, configs: &[(Semantics, usize, bool)]) {
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
        for &(semantics, threads, exact_order) in configs {
            let opts = Options { semantics, threads, exact_order, ..Options::default() };
            let start = std::time::Instant::now();
            let r = analyze(&net, &opts);
            eprintln!(
                "{name} {semantics:?} ({threads} threads, exact order {exact_order}): {} states, {} edges in {:.2?}",
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
    check(
        &|n| !LARGE.contains(&n),
        &[
            (Semantics::Plain, 1, true),
            (Semantics::Mcl, 1, true),
            (Semantics::Plain, 2, true),
            (Semantics::Plain, 2, false),
            (Semantics::Mcl, 3, false),
            (Semantics::Plain, 4, false),
        ],
    );
}

/// ~2-3 million states each (a few seconds each: mcl-net is optimised in
/// the test profile). Nets without MCL data have only immediate
/// transitions, so one semantics is enough; the unordered engine runs them
/// on three threads.
#[test]
fn mcc_large_nets_match_oracle() {
    check(&|n| LARGE.contains(&n), &[(Semantics::Plain, 1, true), (Semantics::Plain, 3, false)]);
}

/// `mcl analyze --method por`: the stubborn-set exploration gives the
/// oracle's deadlock verdict on every net, with no more states than the
/// full space, and (stubborn sets keep every dead marking) the number of
/// dead markings of the full exploration on the nets small enough to
/// explore here twice.
#[test]
fn mcc_deadlock_verdicts_with_stubborn_sets() {
    let dir = mcc_dir();
    let oracle: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let oracle = oracle.as_object().unwrap();
    assert!(!oracle.is_empty());
    for (name, expect) in oracle {
        let text = std::fs::read_to_string(dir.join(format!("{name}.pnml"))).unwrap();
        let net = read_pnml(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        let start = std::time::Instant::now();
        let r = mcl_net::explore::explore_por(&net, mcl_net::explore::DEFAULT_MAX_STATES);
        let full = expect["states"].as_u64().unwrap();
        eprintln!("{name} por: {} of {full} states in {:.2?}", r.states, start.elapsed());
        assert!(r.complete, "{name}");
        assert_eq!(r.deadlock, expect["deadlock"].as_bool().unwrap(), "{name} deadlock");
        assert!(r.states <= full, "{name}: {} > {full}", r.states);
        if !LARGE.contains(&name.as_str()) {
            let e = analyze(&net, &Options::plain());
            assert_eq!(r.dead_markings, e.dead_markings, "{name} dead markings");
        }
    }
}

/// `mcl analyze --method symbolic`: the decision-diagram exploration gives
/// the oracle's states, edges, deadlock verdict and 1-safeness on every
/// net, the large ones included, in both orders with mutually exclusive
/// places grouped into levels (the default) and, on the nets where that is
/// not slow (see BENCHMARKS.md), with one level per place; its dead
/// example replays on the net to a dead marking by a path as short as the
/// explicit search's shortest one.
#[test]
fn mcc_nets_match_oracle_symbolically() {
    use mcl_net::explore::symbolic::VariableOrder;
    use mcl_net::explore::{explore_symbolic, SymbolicOptions};
    let dir = mcc_dir();
    let oracle: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let oracle = oracle.as_object().unwrap();
    assert!(!oracle.is_empty());
    for (name, expect) in oracle {
        let text = std::fs::read_to_string(dir.join(format!("{name}.pnml"))).unwrap();
        let net = read_pnml(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        // Without grouping these are slow in the PNML order, and
        // SharedMemory-10 in any order (see BENCHMARKS.md).
        let slow_in_pnml_order = ["Dekker-PT-010", "Philosophers-PT-000010"];
        let mut configs = vec![(VariableOrder::Force, true), (VariableOrder::Pnml, true)];
        if name != "SharedMemory-PT-000010" {
            configs.push((VariableOrder::Force, false));
            if !slow_in_pnml_order.contains(&name.as_str()) {
                configs.push((VariableOrder::Pnml, false));
            }
        }
        for &(order, group) in &configs {
            let start = std::time::Instant::now();
            let r = explore_symbolic(&net, &SymbolicOptions { order, group, ..SymbolicOptions::default() });
            eprintln!(
                "{name} symbolic {order:?} group {group}: {} levels, {:?} states, {:?} edges, {} MDD nodes ({} created) in {:.2?}",
                r.levels,
                r.states,
                r.edges,
                r.mdd_nodes,
                r.nodes_created,
                start.elapsed()
            );
            assert!(r.complete, "{name}: {:?}", r.stop);
            if name.starts_with("SharedMemory") {
                // Each processor's states and the bus with its accesses.
                assert_eq!(r.levels < net.place_count(), group, "{name}: {} levels", r.levels);
            }
            assert_eq!(r.states, Some(u128::from(expect["states"].as_u64().unwrap())), "{name} states");
            assert_eq!(r.edges, Some(u128::from(expect["edges"].as_u64().unwrap())), "{name} edges");
            assert_eq!(r.deadlock, expect["deadlock"].as_bool().unwrap(), "{name} deadlock");
            assert_eq!(r.one_safe, expect["one_safe"].as_bool().unwrap(), "{name} one_safe");
            assert_eq!(r.deadlock, r.dead_example.is_some(), "{name} dead example");
            if LARGE.contains(&name.as_str()) {
                continue;
            }
            let e = analyze(&net, &Options::plain());
            assert_eq!(r.dead_markings, Some(u128::from(e.dead_markings)), "{name} dead markings");
            assert_eq!(r.max_tokens, e.max_tokens, "{name} max tokens");
            assert_eq!(r.max_tokens_per_marking, e.max_tokens_per_marking, "{name} tokens per marking");
            if let Some(d) = &r.dead_example {
                let mut m = net.initial_marking();
                for &t in &d.path {
                    mcl_net::semantics::fire(&net, &mut m, t).unwrap();
                }
                assert!(mcl_net::semantics::enabled(&net, &m).is_empty(), "{name}: not dead");
                let shortest = e.dead_examples.iter().map(|x| x.path.len()).min().unwrap();
                assert_eq!(d.path.len(), shortest, "{name}: not shortest");
                let marked: Vec<(String, u32)> =
                    m.support().map(|(p, k)| (net.places()[p.index()].id.to_string(), k)).collect();
                assert_eq!(marked, d.marking, "{name}: marking");
            }
        }
    }
}
