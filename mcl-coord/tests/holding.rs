//! The proof by holdings (`verify/holding.rs`, docs/coordination.md,
//! "Holdings"): looping fleets linked only by mutexes are proven free
//! without their product, with the product's verdict where the product is
//! small enough to compare; fleets whose supervisors are not all resources
//! (orders, syncs) never get a verdict from it.

use mcl_compiler::{Database, Db};
use mcl_coord::verify::{VerifyOptions, WitnessKind};
use mcl_coord::{analyze_with, AnalyzeOptions, Constraint, Mission, Report, Verdict};

fn load(name: &str, text: &str) -> (Vec<Mission>, Vec<Constraint>) {
    let dir = std::env::temp_dir().join(format!("mcl-coord-holding-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/vehicle.mcl");
    std::fs::copy(vehicle, dir.join("vehicle.mcl")).unwrap();
    let path = dir.join("m.mcl");
    std::fs::write(&path, format!("import \"vehicle.mcl\";\n{text}")).unwrap();
    let db = Database::new();
    let out = mcl_coord::source::load(&db, db.file(&path)).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let _ = std::fs::remove_dir_all(&dir);
    out
}

/// The proofs without a product tried on every group (`proofs`) or never.
fn opts(proofs: bool) -> AnalyzeOptions {
    AnalyzeOptions {
        structure: false,
        verify: VerifyOptions {
            structural_threshold: if proofs { 0 } else { u64::MAX },
            hunt_threshold: u64::MAX,
            ..VerifyOptions::default()
        },
        ..AnalyzeOptions::default()
    }
}

/// `n` vehicles, each looping over two parallel steps of two calls, and the
/// constraints `cs`.
fn looping(n: usize, cs: &str) -> String {
    let mut text = String::new();
    for v in 0..n {
        text.push_str(&format!(
            "mission : v{v} {{ while ( True() ) {{ parallel {{ Surface() : a }} and {{ GotoTarget() : b }} ; \
             parallel {{ Deploy() : c }} and {{ SendData() : d }} }} }}\n"
        ));
    }
    format!("{text}constraints {{\n{cs}}}\n")
}

/// The ring of `tests/ui/clean_mutex_ring_loops.mcl` over `n` vehicles:
/// `vK:a` against `vK+1:b`, and `vK:c` against `vK+n/2:d`.
fn ring(n: usize) -> String {
    let mut cs = String::new();
    for v in 0..n {
        cs.push_str(&format!("  mutex {{ v{v}:a, v{}:b }} = 1\n", (v + 1) % n));
    }
    for v in 0..n / 2 {
        cs.push_str(&format!("  mutex {{ v{v}:c, v{}:d }} = 1\n", v + n / 2));
    }
    cs
}

fn analyze(name: &str, text: &str, proofs: bool) -> Report {
    let (ms, cs) = load(name, text);
    analyze_with(&ms, &cs, &opts(proofs)).unwrap()
}

#[test]
fn a_looping_mutex_ring_is_proven_free_by_holdings() {
    let r = analyze("ring6", &looping(6, &ring(6)), true);
    assert_eq!(r.verdict, Verdict::Free, "{:?}", r.problems);
    assert_eq!(r.stats.holding_proofs, 1, "{:?}", r.stats);
    assert_eq!(r.stats.product_states, 0, "{:?}", r.stats);
}

#[test]
fn the_proof_agrees_with_the_product_where_it_fits() {
    // Three vehicles: the product is explored whole without the proof.
    let text = looping(3, &ring(3));
    let proved = analyze("ring3-proof", &text, true);
    let explored = analyze("ring3-product", &text, false);
    assert_eq!(proved.verdict, Verdict::Free, "{:?}", proved.problems);
    assert_eq!(proved.stats.holding_proofs, 1);
    assert_eq!(explored.verdict, Verdict::Free, "{:?}", explored.problems);
    assert_eq!(explored.stats.holding_proofs, 0);
    assert!(explored.stats.product_states > 0);
}

#[test]
fn capacities_above_one_and_calls_in_several_mutexes_are_resources_too() {
    let cs = "  mutex { v0:a, v1:a, v2:a } = 2\n  mutex { v0:a, v1:b } = 1\n  mutex { v2:c, v0:d, v1:c } = 2\n";
    let text = looping(3, cs);
    let proved = analyze("cap2-proof", &text, true);
    assert_eq!(proved.verdict, Verdict::Free, "{:?}", proved.problems);
    assert_eq!(proved.stats.holding_proofs, 1, "{:?}", proved.stats);
    let explored = analyze("cap2-product", &text, false);
    assert_eq!(explored.verdict, Verdict::Free, "{:?}", explored.problems);
}

#[test]
fn a_deadlock_through_mutexes_and_orders_in_loops_is_found_not_proven_away() {
    // v0:c waits for v1:d to end and v1:c for v0:d, while each vehicle's
    // d waits for its own c through the orders of the second step: the
    // orders are no resources, the rule does not apply.
    let cs = "  mutex { v0:a, v1:b } = 1\n  order { v1:d, v0:c }\n  order { v0:d, v1:c }\n  \
              order { v0:c, v0:d }\n  order { v1:c, v1:d }\n";
    let r = analyze("order-cycle", &looping(2, cs), true);
    assert_eq!(r.verdict, Verdict::Deadlock, "{:?}", r.verdict);
    assert_eq!(r.stats.holding_proofs, 0, "{:?}", r.stats);
    for p in &r.problems {
        let mut m = r.net.initial_marking();
        for id in &p.counterexample {
            let t = r.net.transition_by_id(id).unwrap_or_else(|| panic!("{id}"));
            mcl_net::semantics::fire(&r.net, &mut m, t).unwrap_or_else(|e| panic!("{id}: {e:?}"));
        }
        if p.kind == WitnessKind::Dead {
            assert!(mcl_net::semantics::enabled(&r.net, &m).is_empty(), "{}", p.message);
        }
    }
}

#[test]
fn a_sync_between_looping_vehicles_is_no_resource() {
    // Free (the partners meet at every turn), but a sync is no resource:
    // the product decides, not the rule.
    let cs = "  mutex { v0:a, v1:b } = 1\n  sync { v0:c, v1:c }\n";
    let r = analyze("sync", &looping(2, cs), true);
    assert_eq!(r.stats.holding_proofs, 0, "{:?}", r.stats);
    assert!(r.stats.product_states > 0, "{:?}", r.stats);
}
