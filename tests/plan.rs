//! `mcl plan`, end to end through the binary: IPC output, search options,
//! the MCL operators convention (FILE.mcl with domain.pddl and problem.pddl
//! beside it), output formats, exit statuses and the plan validator.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-plan-tests-{}", std::process::id())).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn mcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).arg("plan").args(args).current_dir(root()).output().expect("run mcl")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write(dir: &Path, domain: &str, problem: &str) -> (String, String) {
    let d = dir.join("domain.pddl");
    let p = dir.join("problem.pddl");
    std::fs::write(&d, domain).unwrap();
    std::fs::write(&p, problem).unwrap();
    (d.display().to_string(), p.display().to_string())
}

fn gripper(dir: &str, balls: usize) -> (String, String) {
    let i = mcl_plan::gen::gripper(balls);
    write(&tmp(dir), &i.domain, &i.problem)
}

const SEED_PLAN: &str = "(takefixop auv)
(gotoop auv deploy inspection)
(achievealtitudeop auv)
(searchcableop auv cable)
(cabletrackingop auv cable)
(surfaceop auv)
(gotoop auv inspection recovery)
; cost = 594 (general cost)
";

#[test]
fn prints_an_ipc_plan_with_every_search() {
    let (d, p) = gripper("ipc", 4);
    for (search, heur) in [("bfs", "hadd"), ("ucs", "hadd"), ("astar", "hmax"), ("astar", "hadd"), ("gbfs", "hadd")] {
        let o = mcl(&["--domain", &d, "--problem", &p, "--search", search, "--heuristic", heur]);
        assert_eq!(o.status.code(), Some(0), "{search} {heur}: {}", stderr(&o));
        let out = stdout(&o);
        let lines: Vec<&str> = out.lines().collect();
        let last = lines.last().unwrap();
        assert!(last.starts_with("; cost = ") && last.ends_with(" (unit cost)"), "{out}");
        for l in &lines[..lines.len() - 1] {
            assert!(l.starts_with('(') && l.ends_with(')') && *l == l.to_lowercase(), "{l}");
        }
        if heur == "hmax" || search == "bfs" || search == "ucs" {
            assert_eq!(*last, "; cost = 11 (unit cost)", "{search}");
        }
    }
    // The default is A* with h_max; --stats goes to standard error.
    let o = mcl(&["--domain", &d, "--problem", &p, "--stats"]);
    assert!(stdout(&o).ends_with("; cost = 11 (unit cost)\n"));
    assert!(stderr(&o).contains("grounded 36 actions over 20 facts"), "{}", stderr(&o));
}

#[test]
fn plans_the_cable_mission_from_its_mcl_file() {
    let o = mcl(&["examples/planning/cable/cable.mcl"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(stdout(&o), SEED_PLAN);
    assert_eq!(stderr(&o), "");
    // The same with explicit files.
    let o = mcl(&[
        "--operators",
        "examples/planning/cable/cable.mcl",
        "--domain",
        "examples/planning/cable/domain.pddl",
        "--problem",
        "examples/planning/cable/problem.pddl",
        "--search",
        "ucs",
    ]);
    assert_eq!(stdout(&o), SEED_PLAN);
}

#[test]
fn steps_and_json_formats_show_the_mcl_operator_instances() {
    let o = mcl(&["examples/planning/cable/cable.mcl", "--format", "steps"]);
    let out = stdout(&o);
    assert!(out.contains("2. (gotoop auv deploy inspection)  cost 50\n   mcl:    GotoMCLop( 45, 30 )\n"), "{out}");
    assert!(out.contains("mcl:    SearchCableMCLop( 300, \"cable\", 1.5 )"), "{out}");
    let o = mcl(&["examples/planning/cable/cable.mcl", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["cost"], 594);
    assert_eq!(v["unit_cost"], false);
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 7);
    assert_eq!(steps[6]["call"], "GotoMCLop( 0, 0 )");
    assert_eq!(steps[6]["mcl"]["mission"], "GotoMCLop");
    assert_eq!(steps[3]["mcl"]["args"], serde_json::json!([300.0, "cable", 1.5]));
    assert_eq!(steps[0]["before"][0], serde_json::json!({"pred": "position_bad", "args": ["auv"]}));
    assert!(v["stats"]["expanded"].as_u64().unwrap() > 0);
    let o = mcl(&["examples/planning/move/move.mcl", "--format", "steps"]);
    assert!(stdout(&o).contains("mcl:    MclMove( 40, 25.5, 12 )"), "{}", stdout(&o));
}

#[test]
fn exit_1_without_a_solution() {
    let dir = tmp("unsolvable");
    let (d, p) = write(
        &dir,
        "(define (domain door) (:predicates (in-a) (in-b) (open))
           (:action go :precondition (and (in-a) (open)) :effect (and (in-b) (not (in-a)) (not (open)))))",
        "(define (problem p) (:domain door) (:init (in-a) (open)) (:goal (and (in-b) (open))))",
    );
    for search in ["bfs", "ucs", "astar"] {
        let o = mcl(&["--domain", &d, "--problem", &p, "--search", search]);
        assert_eq!(o.status.code(), Some(1), "{search}");
        assert_eq!(stdout(&o), "; no solution\n");
        assert!(stderr(&o).contains("no plan"));
    }
    // --max-states reached: exit 3.
    let (d, p) = gripper("limit", 10);
    let o = mcl(&["--domain", &d, "--problem", &p, "--search", "bfs", "--max-states", "100"]);
    assert_eq!(o.status.code(), Some(3));
}

#[test]
fn exit_2_on_bad_input_with_located_errors() {
    let dir = tmp("bad");
    let (d, p) = write(
        &dir,
        "(define (domain m)\n  (:predicates (p))\n  (:action a :effect (p))",
        "(define (problem x) (:domain m) (:goal (p)))",
    );
    let o = mcl(&["--domain", &d, "--problem", &p]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(&format!("error: {d}:1:1: unclosed `(`")), "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
    let o = mcl(&["--domain", "nope.pddl", "--problem", &p]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("nope.pddl:1:1: cannot read"), "{}", stderr(&o));
    let o = mcl(&["--domain", &d]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no problem"));
    let o = mcl(&["examples/planning/cable/domain.pddl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("is not an .mcl file"));
    // An :mcl call to a mission the operators file does not define.
    let dir = tmp("badmcl");
    let dom = std::fs::read_to_string(root().join("examples/planning/cable/domain.pddl"))
        .unwrap()
        .replace("(SurfaceMCLop)", "(SurfaceMclOp)");
    let (d, _) =
        write(&dir, &dom, &std::fs::read_to_string(root().join("examples/planning/cable/problem.pddl")).unwrap());
    let o = mcl(&["examples/planning/cable/cable.mcl", "--domain", &d]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("runs the MCL mission `SurfaceMclOp`, which the operators file does not define"),
        "{}",
        stderr(&o)
    );
    // An operators file with errors.
    let bad_mcl = dir.join("ops.mcl");
    std::fs::write(&bad_mcl, "mcl_plan_op SurfaceMCLop() { NoSuchTask() }\n").unwrap();
    let o = mcl(&[
        "--operators",
        bad_mcl.to_str().unwrap(),
        "--domain",
        "examples/planning/cable/domain.pddl",
        "--problem",
        "examples/planning/cable/problem.pddl",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("have errors"), "{}", stderr(&o));
}

/// A misspelt predicate in an action is one error, at the line and column
/// where it is first written (not at the action), however often it is used.
#[test]
fn a_misspelt_predicate_is_one_error_at_its_use() {
    let dir = tmp("misspelt");
    let domain = std::fs::read_to_string(root().join("examples/planning/move/domain.pddl"))
        .unwrap()
        .replace(":precondition (and (in ?v ?l1)", ":precondition (and (inn ?v ?l1)")
        .replace("(not (in ?v ?l1))", "(not (inn ?v ?l1))");
    let (d, p) =
        write(&dir, &domain, &std::fs::read_to_string(root().join("examples/planning/move/problem.pddl")).unwrap());
    let o = mcl(&["--domain", &d, "--problem", &p]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let (line, text) = domain.lines().enumerate().find(|(_, l)| l.contains("(inn ")).unwrap();
    let column = text.find("inn").unwrap() + 1;
    let err = stderr(&o);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(
        errors,
        [format!(
            "error: {d}:{}:{column}: action `move`: unknown predicate `inn` (declared: in); also written on line {}",
            line + 1,
            line + 2
        )],
        "{err}"
    );
}

#[test]
fn validates_plans() {
    let plan = tmp("validate").join("plan.txt");
    std::fs::write(&plan, SEED_PLAN).unwrap();
    let o = mcl(&["examples/planning/cable/cable.mcl", "--validate", plan.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(stdout(&o), "valid plan; cost = 594 (general cost)\n");
    std::fs::write(&plan, SEED_PLAN.replace("(takefixop auv)\n", "")).unwrap();
    let o = mcl(&["examples/planning/cable/cable.mcl", "--validate", plan.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stdout(&o),
        "invalid plan: step 1 (gotoop auv deploy inspection): precondition (position_ok auv) does not hold\n"
    );
}

/// The planning model written in MCL (`planning { ... }`, docs/language.md
/// section 13) and the same problem in PDDL give the same plan.
#[test]
fn the_mcl_planning_model_and_the_pddl_files_give_the_same_plan() {
    let mcl_form = mcl(&["examples/planning/cable/planning.mcl"]);
    assert_eq!(mcl_form.status.code(), Some(0), "{}", stderr(&mcl_form));
    assert_eq!(stdout(&mcl_form), SEED_PLAN, "the seed's seven steps");
    let pddl_form = mcl(&["examples/planning/cable/cable.mcl"]);
    assert_eq!(stdout(&pddl_form), stdout(&mcl_form));
    for format in ["steps", "json"] {
        let a = mcl(&["examples/planning/cable/planning.mcl", "--format", format]);
        let b = mcl(&["examples/planning/cable/cable.mcl", "--format", format]);
        assert_eq!(stdout(&a), stdout(&b), "--format {format}");
    }
    // BFS: the fewest steps, the same seven.
    let a = mcl(&["examples/planning/cable/planning.mcl", "--search", "bfs"]);
    assert_eq!(stdout(&a), SEED_PLAN);

    // Extracts 7.1-7.3: move.mcl in MCL; operators.mcl with a plain STRIPS
    // domain.pddl whose action gets its mission from a `pddl_map`.
    let a = mcl(&["examples/planning/move/move.mcl", "--format", "steps"]);
    let b = mcl(&["examples/planning/move/operators.mcl", "--format", "steps"]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    assert_eq!(b.status.code(), Some(0), "{}", stderr(&b));
    assert!(stdout(&a).contains("1. (move ictineu dock survey)"), "{}", stdout(&a));
    assert!(stdout(&a).contains("mcl:    MclMove( 40, 25.5, 12 )"), "{}", stdout(&a));
    assert_eq!(stdout(&a), stdout(&b));
    assert!(!stderr(&b).contains("warning"), "the pddl_map gives `move` its mission: {}", stderr(&b));
    assert_eq!(
        stdout(&mcl(&["examples/planning/move/move.mcl"])),
        "(move ictineu dock survey)\n; cost = 1 (unit cost)\n"
    );
}

#[test]
fn errors_in_planning_blocks_and_pddl_maps_stop_mcl_plan_with_file_and_line() {
    let dir = tmp("mcl-model-errors");
    std::fs::copy(root().join("examples/vehicle.mcl"), dir.join("vehicle.mcl")).unwrap();
    // A checked error (E0702) stops `mcl plan` with the compiler's report.
    let bad = dir.join("bad.mcl");
    std::fs::write(
        &bad,
        "import \"vehicle.mcl\";\nmission Go( x ) { Goto( [x] ) }\n\nplanning {\n    type place { x; }\n    entity place a { x = 1; }\n    operator go( place p ) {\n        add { q here; }\n        mcl Go( p.x );\n    }\n    goal { a here; }\n}\n",
    )
    .unwrap();
    let o = mcl(&[bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("E0702"), "{}", stderr(&o));
    assert!(stderr(&o).contains("bad.mcl:8:15"), "{}", stderr(&o));
    // A pddl_map naming an action the PDDL domain lacks: at the mapping's line.
    let (_, _) = write(
        &dir,
        &std::fs::read_to_string(root().join("examples/planning/move/domain.pddl")).unwrap(),
        &std::fs::read_to_string(root().join("examples/planning/move/problem.pddl")).unwrap(),
    );
    let ops = dir.join("ops.mcl");
    std::fs::write(&ops, "import \"vehicle.mcl\";\nmission Go( x ) { Goto( [x] ) }\n\npddl_map {\n    jump( v, a, b ) -> Go( b.x );\n}\n")
        .unwrap();
    let o = mcl(&[ops.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("ops.mcl:5:5: the PDDL domain `move`")
            && stderr(&o).contains("has no action `jump` (it has: move)"),
        "{}",
        stderr(&o)
    );
}
