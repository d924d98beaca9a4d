//! Generated fleets (`mcl_coord::gen`, issue 17): the analysis with stubborn
//! sets of vehicles gives the verdict of the unreduced product on fleets of
//! 4 vehicles (the unreduced product of 8 passes any cap), the generator's
//! verdict on fleets of 8, and every deadlock it reports replays to a dead
//! marking of the supervised net; the plain-rule exploration of the
//! centralised supervised net with stubborn sets agrees with `mcl check`
//! on every generated fleet.

use mcl_compiler::{Database, Db};
use mcl_coord::gen::{fleet, FleetSpec};
use mcl_coord::verify::{VerifyOptions, WitnessKind};
use mcl_coord::{analyze_with, AnalyzeOptions, Constraint, Mission, Report, Verdict};
use mcl_net::explore::{explore_por_examples, DeadExample, PorReport};
use mcl_net::{Marking, PlaceId};

fn load(name: &str, text: &str) -> (Vec<Mission>, Vec<Constraint>) {
    let dir = std::env::temp_dir().join(format!("mcl-coord-fleet-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/vehicle.mcl");
    std::fs::copy(vehicle, dir.join("vehicle.mcl")).unwrap();
    let path = dir.join("m.mcl");
    std::fs::write(&path, text).unwrap();
    let db = Database::new();
    let out = mcl_coord::source::load(&db, db.file(&path)).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let _ = std::fs::remove_dir_all(&dir);
    out
}

fn opts(reduction: bool) -> AnalyzeOptions {
    AnalyzeOptions {
        structure: false,
        // No random walks, no state equation: the exhaustive product alone
        // decides.
        verify: VerifyOptions {
            reduction,
            reduction_threshold: 0,
            hunt_threshold: u64::MAX,
            structural_threshold: u64::MAX,
            ..VerifyOptions::default()
        },
        ..AnalyzeOptions::default()
    }
}

/// The counterexample of every problem fires on the supervised net and, for
/// a dead one, ends in a marking where nothing is enabled.
fn replays(r: &Report) {
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

fn cross_check(vehicles: usize, seed: u64, deadlock: bool) {
    let f = fleet(&FleetSpec { vehicles, seed, deadlock });
    let (ms, cs) = load(&format!("{vehicles}-{seed}-{deadlock}"), &f.text);
    assert_eq!(ms.len(), vehicles);
    let reduced = analyze_with(&ms, &cs, &opts(true)).unwrap();
    let full = analyze_with(&ms, &cs, &opts(false)).unwrap();
    let expect = if deadlock { Verdict::Deadlock } else { Verdict::Free };
    assert_eq!(reduced.verdict, expect, "{vehicles} vehicles, seed {seed}: {:?}\n{}", reduced.problems, f.text);
    assert_eq!(full.verdict, expect, "{vehicles} vehicles, seed {seed} (unreduced): {:?}", full.problems);
    replays(&reduced);
    replays(&full);
    // The reduction explores fewer states than the full product.
    assert!(
        reduced.stats.product_states < full.stats.product_states,
        "{} vs {}",
        reduced.stats.product_states,
        full.stats.product_states
    );
}

#[test]
fn four_vehicles_agree_with_the_unreduced_product() {
    for seed in 1..=3 {
        cross_check(4, seed, false);
        cross_check(4, seed, true);
    }
}

#[test]
fn eight_vehicles_get_the_generated_verdict() {
    for deadlock in [false, true] {
        let f = fleet(&FleetSpec { vehicles: 8, seed: 1, deadlock });
        let (ms, cs) = load(&format!("8-1-{deadlock}"), &f.text);
        let r = analyze_with(&ms, &cs, &opts(true)).unwrap();
        let expect = if deadlock { Verdict::Deadlock } else { Verdict::Free };
        assert_eq!(r.verdict, expect, "{:?} {:?}\n{}", r.problems, r.stats, f.text);
        replays(&r);
    }
}

/// Per mission, its final places in the supervised net `r.net`.
fn final_places(r: &Report, ms: &[Mission]) -> Vec<Vec<PlaceId>> {
    ms.iter()
        .map(|m| {
            let ids = m.final_places.iter().map(|&p| format!("{}/{}", m.name, m.net.place(p).unwrap().id.as_str()));
            ids.map(|id| r.net.place_by_id(&id).unwrap_or_else(|| panic!("{id}"))).collect()
        })
        .collect()
}

/// The normal end: every mission has reached one of its final places.
fn is_end(finals: &[Vec<PlaceId>], m: &Marking) -> bool {
    finals.iter().all(|ps| ps.iter().any(|&p| m.get(p) > 0))
}

/// The exhaustive exploration of the centralised supervised net `r.net`
/// under the plain rule, with stubborn sets (every reachable dead marking
/// is found): its report and its dead markings other than the normal end,
/// each with a path, after checking that the path replays.
fn central_deadlocks(r: &Report, ms: &[Mission]) -> (PorReport, Vec<DeadExample>) {
    let finals = final_places(r, ms);
    let (por, dead) = explore_por_examples(&r.net, 1_000_000, usize::MAX, |m| !is_end(&finals, m));
    assert!(por.complete, "{por:?}");
    for d in &dead {
        let mut m = r.net.initial_marking();
        for &t in &d.path {
            mcl_net::semantics::fire(&r.net, &mut m, t).unwrap();
        }
        assert_eq!(m, d.marking);
        assert!(mcl_net::semantics::enabled(&r.net, &m).is_empty());
    }
    (por, dead)
}

/// The plain rule lets every transition fire whenever it is enabled; the
/// players only restrict the order (immediate transitions first, each
/// vehicle by its own rule), and a marking is dead under their rule
/// exactly when nothing is enabled. So no dead marking but the end under
/// the plain rule proves a fleet free for the players, and a dead marking
/// that the players reach (`mcl check`'s replayed counterexample) is among
/// the plain rule's. Both directions are checked on every generated fleet:
/// a free verdict comes with the end as the only dead marking of the
/// centralised net; a deadlock verdict with dead markings that are not the
/// end, the end marking of every dead counterexample of `mcl check` among
/// them.
#[test]
fn the_centralised_net_confirms_every_verdict() {
    for vehicles in [4, 8, 12, 16] {
        for seed in 1..=2 {
            for deadlock in [false, true] {
                let f = fleet(&FleetSpec { vehicles, seed, deadlock });
                let (ms, cs) = load(&format!("n{vehicles}-{seed}-{deadlock}"), &f.text);
                let r = analyze_with(&ms, &cs, &mcl_coord::check::options()).unwrap();
                let what = format!("{vehicles} vehicles, seed {seed}, deadlock {deadlock}");
                let (por, dead) = central_deadlocks(&r, &ms);
                eprintln!(
                    "{what}: {} reduced states, {} dead markings, {} not the end",
                    por.states,
                    por.dead_markings,
                    dead.len()
                );
                assert!(por.deadlock, "{what}: the end is a dead marking");
                assert_eq!(dead.is_empty(), !deadlock, "{what}: the generator's verdict");
                if r.verdict == Verdict::Free {
                    assert!(dead.is_empty(), "{what}: {:?}", dead[0].path);
                    assert_eq!(por.dead_markings, 1, "{what}");
                } else {
                    assert_eq!(r.verdict, Verdict::Deadlock, "{what}");
                    assert!(!dead.is_empty(), "{what}");
                    assert!(r.problems.iter().any(|p| p.kind == WitnessKind::Dead), "{what}: {:?}", r.problems);
                    for p in r.problems.iter().filter(|p| p.kind == WitnessKind::Dead) {
                        let mut m = r.net.initial_marking();
                        for id in &p.counterexample {
                            let t = r.net.transition_by_id(id).unwrap();
                            mcl_net::semantics::fire(&r.net, &mut m, t).unwrap();
                        }
                        assert!(dead.iter().any(|d| d.marking == m), "{what}: {}", p.message);
                    }
                }
            }
        }
    }
}

/// The generated fleets of 4, 8, 12 and 16 vehicles (two seeds, free and
/// with a cycle of orders) under `mcl check`'s options: the verdict of
/// their construction, "free" proven by the state equation without any
/// product state, every deadlock replayed on the supervised net. Up to 8
/// vehicles every verdict is confirmed by the exhaustive product without
/// the state equation nor random walks (unreduced at 4 vehicles, with the
/// stubborn sets, exact for dead states, at 8); the centralised net
/// confirms them at every size (`the_centralised_net_confirms_every_verdict`).
#[test]
fn fleets_up_to_16_vehicles_get_conclusive_verdicts() {
    for vehicles in [4, 8, 12, 16] {
        for seed in 1..=2 {
            for deadlock in [false, true] {
                let f = fleet(&FleetSpec { vehicles, seed, deadlock });
                let (ms, cs) = load(&format!("c{vehicles}-{seed}-{deadlock}"), &f.text);
                let r = analyze_with(&ms, &cs, &mcl_coord::check::options()).unwrap();
                let expect = if deadlock { Verdict::Deadlock } else { Verdict::Free };
                let what = format!("{vehicles} vehicles, seed {seed}, deadlock {deadlock}");
                assert_eq!(r.verdict, expect, "{what}: {:?}", r.problems);
                if !deadlock {
                    assert_eq!(r.stats.structural_proofs, 1, "{what}: {:?}", r.stats);
                    assert_eq!(r.stats.product_states, 0, "{what}");
                }
                replays(&r);
                if vehicles <= 8 {
                    let full = analyze_with(&ms, &cs, &opts(vehicles > 4)).unwrap();
                    assert_eq!(full.verdict, expect, "{what} (exhaustive): {:?}", full.problems);
                    assert_eq!(full.stats.structural_proofs, 0, "{what}");
                    assert!(full.stats.product_states > 0, "{what}");
                    replays(&full);
                }
            }
        }
    }
}
