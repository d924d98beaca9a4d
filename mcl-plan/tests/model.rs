//! The planning model written in MCL (`planning { ... }`) gives the planner
//! the same domain and problem as the PDDL files: the same plans, the same
//! MCL mission instances; `pddl_map { ... }` gives plain STRIPS actions their
//! missions, and its errors name the .mcl file and line.

use mcl_plan::model::{apply_pddl_map, to_model, McProgram};
use mcl_plan::{Algorithm, Heuristic, Outcome};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).to_path_buf()
}

fn plan_text(d: &mcl_plan::Domain, p: &mcl_plan::Problem) -> Vec<String> {
    let sol = mcl_plan::solve(d, p, Algorithm::Astar(Heuristic::Max), 1_000_000).unwrap();
    let Outcome::Plan(plan) = sol.outcome else { panic!("no plan") };
    plan.steps
        .iter()
        .map(|s| format!("{} {}", s.action, s.mcl.as_ref().map(|m| m.to_string()).unwrap_or_default()))
        .collect()
}

#[test]
fn the_cable_problem_in_mcl_plans_as_in_pddl() {
    let dir = root().join("examples/planning/cable");
    let prog = McProgram::load(&dir.join("planning.mcl")).unwrap();
    assert!(prog.has_planning());
    let (d, p) = to_model(&prog).unwrap();
    assert!(p.metric, "operators with costs minimise the total cost");
    let (pd, pp) = mcl_plan::load(&dir.join("domain.pddl"), &dir.join("problem.pddl")).unwrap();
    let mcl = plan_text(&d, &p);
    assert_eq!(mcl, plan_text(&pd, &pp));
    assert_eq!(mcl.len(), 7, "{mcl:#?}");
    assert!(mcl[3].contains("SearchCableMCLop( 300, \"cable\", 1.5 )"), "{mcl:#?}");
    // The PDDL form's operators file has no planning block.
    assert!(!McProgram::load(&dir.join("cable.mcl")).unwrap().has_planning());
}

#[test]
fn pddl_map_errors_name_the_mcl_file_and_line() {
    let dir = std::env::temp_dir().join(format!("mcl-plan-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("ops.mcl");
    std::fs::write(
        &f,
        "mission Go( x ) { Goto( [x] ) }\n\npddl_map {\n    jump( a ) -> Go( a.x );\n    move( v, a ) -> Go( a.x );\n}\n",
    )
    .unwrap();
    let prog = McProgram::load(&f).unwrap();
    let (mut d, _) = mcl_plan::load(
        &root().join("examples/planning/move/domain.pddl"),
        &root().join("examples/planning/move/problem.pddl"),
    )
    .unwrap();
    let e: Vec<String> = apply_pddl_map(&prog, &mut d).unwrap_err().iter().map(|e| e.to_string()).collect();
    assert_eq!(e.len(), 2, "{e:#?}");
    assert!(e[0].contains("ops.mcl:4:5: the PDDL domain `move`"), "{e:#?}");
    assert!(e[0].contains("has no action `jump` (it has: move)"), "{e:#?}");
    assert!(e[1].contains("ops.mcl:5:5: action `move` has 3 parameter(s)"), "{e:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}
