//! The PDDL front-end: what it accepts, its error messages (file, line,
//! column, what was expected), and a property test that mutated PDDL files
//! never make the parser, the grounder, the search or the validator panic.

use mcl_plan::pddl::{Cond, MclArg, Term};
use mcl_plan::{gen, parse_domain, parse_problem, Algorithm, Heuristic, Outcome};
use proptest::prelude::*;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

fn example(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).expect(rel)
}

fn domain_err(text: &str) -> String {
    match parse_domain("d.pddl", text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("\n"),
    }
}

fn problem_err(text: &str) -> String {
    match parse_problem("p.pddl", text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("\n"),
    }
}

const MINI: &str = "(define (domain m) (:requirements :strips :typing)
  (:types loc)
  (:predicates (at ?l - loc))
  (:action go :parameters (?a ?b - loc)
    :precondition (and (at ?a) (not (= ?a ?b)))
    :effect (and (at ?b) (not (at ?a)))))";

#[test]
fn parses_the_seed_constructs() {
    let d = parse_domain("move", &example("examples/planning/move/domain.pddl")).unwrap();
    let mv = &d.actions[0];
    assert_eq!(mv.name, "move");
    assert_eq!(mv.params.len(), 3);
    assert!(mv.conds.contains(&Cond::Equal(Term::Var(1), Term::Var(2), false)), "l1 != l2 (Extract 7.1)");
    assert!(matches!(mv.conds[1], Cond::Compare(..)), "attribute comparison");
    // Plain STRIPS: the mission comes from the `pddl_map` of operators.mcl.
    assert!(mv.mcl.is_none());
    let mut d = d;
    let prog = mcl_plan::model::McProgram::load(&root().join("examples/planning/move/operators.mcl")).unwrap();
    mcl_plan::model::apply_pddl_map(&prog, &mut d).unwrap();
    let m = d.actions[0].mcl.as_ref().unwrap();
    assert_eq!(m.name, "MclMove", "case kept");
    assert_eq!(
        m.args,
        vec![
            MclArg::Attr(Term::Var(2), "x".into()),
            MclArg::Attr(Term::Var(2), "y".into()),
            MclArg::Attr(Term::Var(2), "z".into())
        ]
    );
    let p = parse_problem("move-p", &example("examples/planning/move/problem.pddl")).unwrap();
    assert_eq!(p.values.len(), 10);
    let d = parse_domain("cable", &example("examples/planning/cable/domain.pddl")).unwrap();
    assert_eq!(d.actions.len(), 7);
    assert_eq!(d.constants[0].name, "inspection");
    assert!(d.actions.iter().all(|a| a.cost.is_some() && a.mcl.is_some()));
    let p = parse_problem("cable-p", &example("examples/planning/cable/problem.pddl")).unwrap();
    assert!(p.metric);
}

#[test]
fn case_insensitive_and_comments() {
    let d = parse_domain("d", &MINI.to_uppercase().replace("(:REQUIREMENTS", "; comment\n(:REQUIREMENTS")).unwrap();
    assert_eq!(d.name, "m");
    assert_eq!(d.actions[0].name, "go");
}

#[test]
fn syntax_errors_name_file_line_column_and_what_was_expected() {
    let cases: &[(&str, &str)] = &[
        ("", "d.pddl:1:1: expected `(define (domain NAME) ...)`, found an empty file"),
        ("(define (domain m)", "d.pddl:1:1: unclosed `(`"),
        ("(define (domain m)))", "d.pddl:1:20: unexpected `)`"),
        ("(define (problem m))", "d.pddl:1:9: expected `(domain NAME)`"),
        ("(define (domain m)\n  (:predicates (at ?l))\n  (:action go :parameters (?a) :precondition (at ?b) :effect (at ?a)))", "d.pddl:3:50: unknown variable `?b`"),
        ("(define (domain m)\n  (:action go :parameters (?a) :bogus ()))", "d.pddl:2:32: unknown action key `:bogus`"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :effect (when (p) (p))))", "d.pddl:3:22: `when` effects are not supported"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :precondition (or (p) (p)) :effect (p)))", "d.pddl:3:28: `or` in a precondition is not supported"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :effect (and (p) (increase (fuel) 3))))", "d.pddl:3:41: only `(total-cost)` can be increased"),
        ("(define (domain m)\n (:predicates (p ?x))\n (:action go :parameters (?x) :effect (p)))", "d.pddl:3:40: action `go`: predicate `p` takes 1 argument(s), given 0"),
        ("(define (domain m)\n (:action go :effect (q)))", "d.pddl:2:23: action `go`: unknown predicate `q`"),
        ("(define (domain m)\n (:types a - b)\n (:constants c - d))", "`c` has the undeclared type `d`"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :effect (p) :mcl (?x)))", "d.pddl:3:32: expected the name of an MCL mission"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :parameters (?l) :effect (p) :mcl (Go ?k.x)))", "d.pddl:3:52: unknown variable `?k`"),
        ("(define (domain m) (:predicates (p)) (:action go :effect (p) :mcl (Go \"x)))", "unterminated string"),
        ("(define (domain m)\n (:predicates (p))\n (:action go :parameters (?a ?a) :effect (p)))", "parameter `?a` declared twice"),
    ];
    for (text, want) in cases {
        let got = domain_err(text);
        assert!(got.contains(want), "for {text:?}\n  want: {want}\n  got:  {got}");
    }
}

#[test]
fn several_errors_are_reported_at_once() {
    let text = "(define (domain m)\n (:predicates (p))\n (:action a :effect (when (p) (p)))\n (:action b :effect (forall (?x) (p))))";
    let e = parse_domain("d.pddl", text).unwrap_err();
    assert_eq!(e.len(), 2, "{e:?}");
    assert_eq!((e[0].line, e[1].line), (3, 4));
}

#[test]
fn problem_errors() {
    let cases: &[(&str, &str)] = &[
        ("(define (problem p) (:domain m) (:objects a - loc) (:init (at a)))", "has no `(:goal ...)`"),
        (
            "(define (problem p)\n (:domain m)\n (:init (= (x a) high))\n (:goal (at a)))",
            "p.pddl:3:18: expected a number or a string, found `high`",
        ),
        ("(define (problem p) (:domain m) (:goal (or (at a) (at b))))", "`or` is not supported here"),
        (
            "(define (problem p) (:domain m) (:goal (at a)) (:metric maximize (total-cost)))",
            "expected `(:metric minimize (total-cost))`",
        ),
        ("(define (problem p) (:domain m) (:init (at ?x)) (:goal (at a)))", "expected an object name, found `?x`"),
    ];
    for (text, want) in cases {
        let got = problem_err(text);
        assert!(got.contains(want), "for {text:?}\n  want: {want}\n  got:  {got}");
    }
}

#[test]
fn grounding_errors() {
    let d = parse_domain("d.pddl", MINI).unwrap();
    let bad = |p: &str| {
        let p = parse_problem("p.pddl", p).unwrap();
        mcl_plan::ground(&d, &p).unwrap_err().iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n")
    };
    assert!(bad("(define (problem p) (:domain m) (:objects a - loc) (:init (at b)) (:goal (at a)))")
        .contains("unknown object `b`"));
    assert!(bad("(define (problem p) (:domain m) (:objects a - room) (:init) (:goal (at a)))")
        .contains("undeclared type `room`"));
    assert!(bad("(define (problem p) (:domain other) (:objects a - loc) (:init) (:goal (at a)))")
        .contains("is for domain `other`"));
    assert!(bad("(define (problem p) (:domain m) (:objects a - loc) (:init (at a a)) (:goal (at a)))")
        .contains("takes 1 argument(s), given 2"));
    // A missing attribute of a mission argument (the `pddl_map` of operators.mcl).
    let mut d = parse_domain("move.pddl", &example("examples/planning/move/domain.pddl")).unwrap();
    let prog = mcl_plan::model::McProgram::load(&root().join("examples/planning/move/operators.mcl")).unwrap();
    mcl_plan::model::apply_pddl_map(&prog, &mut d).unwrap();
    let p = parse_problem("p.pddl", &example("examples/planning/move/problem.pddl").replace("(= (z survey) 12)", ""))
        .unwrap();
    // z survey missing: the comparison is false, the action is not grounded, no plan.
    let s = mcl_plan::solve(&d, &p, Algorithm::Bfs, 1000);
    assert!(s.is_err() || matches!(s.unwrap().outcome, Outcome::Unsolvable));
    let p = parse_problem("p.pddl", &example("examples/planning/move/problem.pddl").replace("(= (y survey) 25.5)", ""))
        .unwrap();
    let e = mcl_plan::ground(&d, &p).map(|_| ()).unwrap_err();
    assert!(e[0].message.contains("needs attribute `y` of `survey`"), "{e:?}");
    assert!(e[0].to_string().contains("operators.mcl:27:"), "at the mapping: {}", e[0]);
}

#[test]
fn grounding_budget_stops_explosions() {
    let mut d = "(define (domain big) (:predicates (p ?a ?b ?c ?d ?e ?f)) (:action a :parameters (?a ?b ?c ?d ?e ?f) :effect (p ?a ?b ?c ?d ?e ?f)))".to_string();
    let objs: Vec<String> = (0..30).map(|i| format!("o{i}")).collect();
    let p = format!(
        "(define (problem big) (:domain big) (:objects {}) (:init) (:goal (p o1 o1 o1 o1 o1 o2)))",
        objs.join(" ")
    );
    let dd = parse_domain("d", &d).unwrap();
    let pp = parse_problem("p", &p).unwrap();
    let e = mcl_plan::ground::ground_with_budget(&dd, &pp, 100_000).map(|_| ()).unwrap_err();
    assert!(e[0].message.contains("grounding gave up"), "{e:?}");
    d.clear();
}

/// Small valid inputs to mutate.
fn corpus() -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = [
        gen::gripper(2),
        gen::blocksworld(3, 1),
        gen::logistics(2, 2, 1, 1, 1),
        gen::miconic(3, 2, 1),
        gen::logistics_with_costs(2, 2, 1, 1, 2),
    ]
    .into_iter()
    .map(|i| (i.domain, i.problem))
    .collect();
    for ex in ["cable", "move"] {
        v.push((
            example(&format!("examples/planning/{ex}/domain.pddl")),
            example(&format!("examples/planning/{ex}/problem.pddl")),
        ));
    }
    v
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize, usize),
    Insert(usize, String),
    Duplicate(usize, usize, usize),
    Replace(usize, char),
}

fn apply(text: &str, m: &Mutation) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let mut out = chars.clone();
    match m {
        Mutation::Delete(at, len) => {
            let a = at % n;
            let b = (a + len % 40).min(chars.len());
            out.drain(a..b);
        }
        Mutation::Insert(at, s) => {
            let a = at % (chars.len() + 1);
            out.splice(a..a, s.chars());
        }
        Mutation::Duplicate(at, len, to) => {
            let a = at % n;
            let b = (a + len % 60).min(chars.len());
            let piece: Vec<char> = chars[a.min(chars.len())..b].to_vec();
            let t = to % (chars.len() + 1);
            out.splice(t..t, piece);
        }
        Mutation::Replace(at, c) => {
            if !chars.is_empty() {
                out[at % chars.len()] = *c;
            }
        }
    }
    out.into_iter().collect()
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let tokens = prop::sample::select(vec![
        "(",
        ")",
        "?x",
        "?",
        "-",
        " - object",
        ":action",
        ":precondition",
        "(not ",
        "(and ",
        "(= ?a ?b)",
        "\"",
        ";",
        "\n",
        "3.5",
        "-2",
        "(increase (total-cost) 2)",
        "?l2.x",
        "(either a b)",
        ":mcl (M ?a.x)",
        "é",
        "\u{0}",
        "object",
        ")))))",
    ]);
    prop_oneof![
        (any::<usize>(), any::<usize>()).prop_map(|(a, l)| Mutation::Delete(a, l)),
        (any::<usize>(), tokens).prop_map(|(a, s)| Mutation::Insert(a, s.to_string())),
        (any::<usize>(), any::<usize>(), any::<usize>()).prop_map(|(a, l, t)| Mutation::Duplicate(a, l, t)),
        (any::<usize>(), prop::char::any()).prop_map(|(a, c)| Mutation::Replace(a, c)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, .. ProptestConfig::default() })]

    #[test]
    fn mutated_pddl_never_panics(which in 0usize..7, on_domain in any::<bool>(), muts in prop::collection::vec(mutation(), 1..4)) {
        let c = corpus();
        let (mut d, mut p) = c[which % c.len()].clone();
        for m in &muts {
            if on_domain { d = apply(&d, m) } else { p = apply(&p, m) }
        }
        let (Ok(dd), Ok(pp)) = (parse_domain("d.pddl", &d), parse_problem("p.pddl", &p)) else { return Ok(()) };
        let Ok(task) = mcl_plan::ground::ground_with_budget(&dd, &pp, 2_000_000) else { return Ok(()) };
        for alg in [Algorithm::Bfs, Algorithm::Ucs, Algorithm::Astar(Heuristic::Add), Algorithm::Astar(Heuristic::Max), Algorithm::Greedy(Heuristic::Add)] {
            let r = mcl_plan::search::search(&task, alg, 20_000);
            if let mcl_plan::search::Outcome::Plan(actions) = r.outcome {
                let plan = mcl_plan::Plan::new(&task, &task.init, &actions);
                // Every plan found replays as valid, at the cost reported.
                prop_assert_eq!(mcl_plan::validate(&dd, &pp, &plan.to_ipc()), Ok(plan.cost), "{:?}\n{}", alg, plan.to_ipc());
            }
        }
        let _ = mcl_plan::validate(&dd, &pp, "(a b c)\n(d)");
    }

    #[test]
    fn arbitrary_text_never_panics(s in "[()?:a-z \n;\"=0-9.-]{0,200}") {
        let _ = parse_domain("d", &s);
        let _ = parse_problem("p", &s);
        let _ = mcl_plan::validate::parse_plan(&s);
    }
}
