//! The scaling parts of the analysis (docs/coordination.md, "Scaling"):
//! vehicles that no constraint links are verified as separate groups, and
//! random walks find the deadlocks of products too large to explore.

use mcl_compiler::{Database, Db};
use mcl_coord::verify::{VerifyOptions, WitnessKind};
use mcl_coord::{analyze_with, AnalyzeOptions, Constraint, Mission, Verdict};

fn load(name: &str, text: &str) -> (Vec<Mission>, Vec<Constraint>) {
    let dir = std::env::temp_dir().join(format!("mcl-coord-scaling-{name}-{}", std::process::id()));
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

fn opts() -> AnalyzeOptions {
    AnalyzeOptions { structure: false, ..AnalyzeOptions::default() }
}

/// `teams` pairs of vehicles; in each pair, two parallel steps whose calls
/// are mutually exclusive with the other vehicle's (deadlock-free: a call
/// holds its mutexes only while it runs and waits for nothing else).
fn teams(teams: usize, extra: &str) -> String {
    let mut text = String::new();
    let mut cs = String::new();
    for t in 0..teams {
        for v in ["x", "y"] {
            text.push_str(&format!(
                "mission : {v}{t} {{ parallel {{ Surface() : a }} and {{ GotoTarget() : b }} ; \
                 parallel {{ Deploy() : c }} and {{ SendData() : d }} }}\n"
            ));
        }
        cs.push_str(&format!("  mutex {{ x{t}:a, y{t}:b }} = 1\n  mutex {{ x{t}:b, y{t}:a }} = 1\n"));
        cs.push_str(&format!("  mutex {{ x{t}:c, y{t}:d }} = 1\n  mutex {{ x{t}:d, y{t}:c }} = 1\n"));
    }
    format!("{text}constraints {{\n{cs}{extra}}}\n")
}

#[test]
fn eight_vehicles_in_four_independent_teams_are_proven_free() {
    let (ms, cs) = load("teams", &teams(4, ""));
    assert_eq!((ms.len(), cs.len()), (8, 16));
    let r = analyze_with(&ms, &cs, &opts()).unwrap();
    assert_eq!(r.verdict, Verdict::Free, "{:?}", r.problems);
    // Four products of two vehicles, not one of eight.
    let classes = &r.stats.vehicle_classes;
    let one_team = classes[0] * classes[1];
    assert!(r.stats.product_states < 4 * one_team * 64, "{} states for {classes:?}", r.stats.product_states);
    // Linking the teams makes one group: the same cap is then reached.
    let links: String = (0..3).map(|t| format!("  mutex {{ y{t}:d, x{}:a }} = 1\n", t + 1)).collect();
    let (ms, cs) = load("teams-linked", &teams(4, &links));
    let small = AnalyzeOptions {
        // The product itself, not the state equation (which proves these
        // mutexes free at once: structural_proof.rs).
        verify: VerifyOptions {
            max_product_states: 4 * one_team * 64,
            structural_threshold: u64::MAX,
            ..VerifyOptions::default()
        },
        ..opts()
    };
    let r = analyze_with(&ms, &cs, &small).unwrap();
    assert!(matches!(r.verdict, Verdict::Unknown { .. }), "{:?}", r.verdict);
}

#[test]
fn a_deadlock_in_one_team_blocks_it_while_the_others_go_on() {
    // Team 0 waits for each other (figure 6.9a); team 1 is fine.
    let text = "mission : x0 { GotoTarget() : p ; Surface() }
mission : y0 { Deploy() : q ; Surface() }
mission : x1 { Surface() : a }
mission : y1 { GotoTarget() : b }
constraints {
  order { x0:p, y0:q }
  order { y0:q, x0:p }
  mutex { x1:a, y1:b } = 1
}
";
    let (ms, cs) = load("one-team", text);
    let r = analyze_with(&ms, &cs, &opts()).unwrap();
    assert_eq!(r.verdict, Verdict::Deadlock);
    assert_eq!(r.problems.len(), 1, "{:?}", r.problems);
    let p = &r.problems[0];
    assert_eq!(p.constraints, [0, 1]);
    let mut waiting = p.waiting.clone();
    waiting.sort();
    assert_eq!(waiting, ["x0:p", "y0:q"]);
    // The counterexample replays; team 1 can still move, so the whole net is
    // not dead: the marking is one from which x0 and y0 never end.
    let mut m = r.net.initial_marking();
    for id in &p.counterexample {
        mcl_net::semantics::fire(&r.net, &mut m, r.net.transition_by_id(id).unwrap()).unwrap();
    }
    assert_eq!(p.kind, WitnessKind::Blocked);
    assert!(!mcl_net::semantics::enabled(&r.net, &m).is_empty());
}

/// Eight vehicles of three parallel steps, each calling `p` at its second
/// step; a ring of orders `vK:p` before `vK+1:p` plus the closing one: every
/// vehicle waits for the previous one.
#[test]
fn random_walks_find_the_deadlock_of_eight_linked_vehicles() {
    let mut text = String::new();
    for v in 0..8 {
        text.push_str(&format!(
            "mission : v{v} {{ parallel {{ Surface() }} and {{ Deploy() }} ; GotoTarget() : p ; \
             parallel {{ SendData() }} and {{ Surface() }} }}\n"
        ));
    }
    text.push_str("constraints {\n");
    for v in 0..8 {
        text.push_str(&format!("  order {{ v{v}:p, v{}:p }}\n", (v + 1) % 8));
    }
    text.push_str("}\n");
    let (ms, cs) = load("ring", &text);
    let r = analyze_with(&ms, &cs, &opts()).unwrap();
    assert_eq!(r.verdict, Verdict::Deadlock, "{:?}", r.verdict);
    let p = &r.problems[0];
    let mut m = r.net.initial_marking();
    for id in &p.counterexample {
        mcl_net::semantics::fire(&r.net, &mut m, r.net.transition_by_id(id).unwrap()).unwrap();
    }
    if p.kind == WitnessKind::Dead {
        assert!(mcl_net::semantics::enabled(&r.net, &m).is_empty());
    }
    assert!(!p.constraints.is_empty());
}
