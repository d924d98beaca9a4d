//! Search and grounding against independent references: known optimal
//! costs, and a naive reference planner (lifted, explicit states, no
//! grounding, no pruning) on random small STRIPS problems with negative
//! preconditions, equality and action costs.

use mcl_plan::gen::{self, Rng};
use mcl_plan::pddl::{Cond, NumExpr, Term};
use mcl_plan::{parse_domain, parse_problem, Algorithm, Domain, Fact, Heuristic, Outcome, Problem};
use proptest::prelude::*;
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap, HashMap};

const ALGS: [Algorithm; 4] =
    [Algorithm::Bfs, Algorithm::Ucs, Algorithm::Astar(Heuristic::Max), Algorithm::Astar(Heuristic::Add)];

fn solve(d: &Domain, p: &Problem, alg: Algorithm) -> Option<mcl_plan::Plan> {
    match mcl_plan::solve(d, p, alg, 2_000_000).expect("grounds").outcome {
        Outcome::Plan(p) => Some(p),
        Outcome::Unsolvable => None,
        Outcome::LimitReached => panic!("limit"),
    }
}

#[test]
fn gripper_optimal_lengths() {
    for n in 1..=8usize {
        let i = gen::gripper(n);
        let d = parse_domain("d", &i.domain).unwrap();
        let p = parse_problem("p", &i.problem).unwrap();
        let want = if n % 2 == 0 { 3 * n - 1 } else { 3 * n } as u64;
        for alg in [Algorithm::Bfs, Algorithm::Ucs, Algorithm::Astar(Heuristic::Max)] {
            assert_eq!(solve(&d, &p, alg).unwrap().cost, want, "gripper {n} {alg:?}");
        }
    }
}

#[test]
fn general_costs_ucs_and_astar_hmax_agree_and_beat_bfs() {
    for seed in 1..=6 {
        let i = gen::logistics_with_costs(2, 2, 1, 2, seed);
        let d = parse_domain("d", &i.domain).unwrap();
        let p = parse_problem("p", &i.problem).unwrap();
        let ucs = solve(&d, &p, Algorithm::Ucs).unwrap();
        let astar = solve(&d, &p, Algorithm::Astar(Heuristic::Max)).unwrap();
        let bfs = solve(&d, &p, Algorithm::Bfs).unwrap();
        assert_eq!(ucs.cost, astar.cost, "seed {seed}");
        assert!(bfs.cost >= ucs.cost);
        assert_eq!(Some(ucs.cost), reference(&d, &p), "seed {seed}");
        for pl in [&ucs, &astar, &bfs] {
            assert_eq!(mcl_plan::validate(&d, &p, &pl.to_ipc()), Ok(pl.cost));
            assert!(pl.to_ipc().ends_with("(general cost)\n"));
        }
    }
}

#[test]
fn unsolvable_and_limit() {
    // A one-way door: the relaxation reaches the goal, the real problem does not.
    let d = parse_domain(
        "d",
        "(define (domain door) (:predicates (in-a) (in-b) (open))
           (:action go :precondition (and (in-a) (open)) :effect (and (in-b) (not (in-a)) (not (open))))
           (:action back :precondition (and (in-b) (open)) :effect (and (in-a) (not (in-b)))))",
    )
    .unwrap();
    let p = parse_problem("p", "(define (problem p) (:domain door) (:init (in-a) (open)) (:goal (and (in-b) (open))))")
        .unwrap();
    for alg in ALGS {
        assert!(solve(&d, &p, alg).is_none(), "{alg:?}");
    }
    let i = gen::gripper(10);
    let d = parse_domain("d", &i.domain).unwrap();
    let p = parse_problem("p", &i.problem).unwrap();
    let s = mcl_plan::solve(&d, &p, Algorithm::Bfs, 1000).unwrap();
    assert!(matches!(s.outcome, Outcome::LimitReached));
    assert!(s.stats.states <= 1000 + 100);
}

#[test]
fn types_prune_grounding() {
    // logistics: trucks are never loaded into planes etc.
    let i = gen::logistics(2, 2, 1, 2, 1);
    let d = parse_domain("d", &i.domain).unwrap();
    let p = parse_problem("p", &i.problem).unwrap();
    let t = mcl_plan::ground(&d, &p).unwrap();
    // Only reachable, well-typed actions: every drive-truck stays in its city.
    for ai in 0..t.actions.len() as u32 {
        let n = t.action_name(ai);
        if n.starts_with("(drive-truck truck1") {
            assert!(n.ends_with("city1)"), "{n}");
        }
        assert!(!n.contains("(load-truck truck"), "{n}");
    }
    // either-typed parameters, subtypes and constants.
    let d = parse_domain(
        "d",
        "(define (domain e) (:types car boat - vehicle dock)
           (:constants home - dock)
           (:predicates (at ?v - vehicle ?d - dock) (seen ?v - (either car boat)))
           (:action look :parameters (?v - (either car boat)) :precondition (at ?v home) :effect (seen ?v)))",
    )
    .unwrap();
    let p = parse_problem("p", "(define (problem p) (:domain e) (:objects c - car b - boat x - dock) (:init (at c home) (at b x)) (:goal (seen c)))").unwrap();
    let t = mcl_plan::ground(&d, &p).unwrap();
    assert_eq!(t.actions.len(), 1, "look b is unreachable: (at b home) never holds");
    assert_eq!(solve(&d, &p, Algorithm::Bfs).unwrap().to_ipc(), "(look c)\n; cost = 1 (unit cost)\n");
}

#[test]
fn h_values_on_a_small_chain() {
    // a -> b -> c, goal c: h_add = h_max = 2; two goals: h_add sums.
    let d = parse_domain(
        "d",
        "(define (domain chain) (:predicates (a) (b) (c) (d))
           (:action ab :precondition (a) :effect (b))
           (:action bc :precondition (b) :effect (c))
           (:action bd :precondition (b) :effect (d)))",
    )
    .unwrap();
    let p = parse_problem("p", "(define (problem p) (:domain chain) (:init (a)) (:goal (and (c) (d))))").unwrap();
    assert_eq!(mcl_plan::initial_h(&d, &p, Heuristic::Add).unwrap(), Some(4));
    assert_eq!(mcl_plan::initial_h(&d, &p, Heuristic::Max).unwrap(), Some(2));
    assert_eq!(solve(&d, &p, Algorithm::Ucs).unwrap().cost, 3);
}

// --- the reference planner ------------------------------------------------

fn eval(e: &NumExpr, p: &Problem, args: &[String]) -> Option<f64> {
    Some(match e {
        NumExpr::Num(n) => *n,
        NumExpr::Neg(x) => -eval(x, p, args)?,
        NumExpr::Bin(op, x, y) => {
            let (x, y) = (eval(x, p, args)?, eval(y, p, args)?);
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                _ => x / y,
            }
        }
        NumExpr::Fluent(f, ts) => {
            let objs: Vec<String> = ts.iter().map(|t| obj(t, args)).collect();
            match p.values.iter().find(|(n, a, _)| n == f && *a == objs).map(|(_, _, v)| v)? {
                mcl_plan::pddl::Value::Num(n) => *n,
                _ => return None,
            }
        }
    })
}

fn obj(t: &Term, args: &[String]) -> String {
    match t {
        Term::Var(v) => args[*v].clone(),
        Term::Obj(o) => o.clone(),
    }
}

/// Optimal plan cost by Dijkstra over sets of facts, grounding every action
/// over every well-typed tuple of objects.
fn reference(d: &Domain, p: &Problem) -> Option<u64> {
    let objects: Vec<String> = d.constants.iter().chain(&p.objects).map(|o| o.name.clone()).collect();
    let decl: HashMap<&str, &str> =
        d.constants.iter().chain(&p.objects).map(|o| (o.name.as_str(), o.types[0].as_str())).collect();
    let parent: HashMap<&str, &str> = d.types.iter().map(|(t, p)| (t.as_str(), p.as_str())).collect();
    let is_a = |o: &str, want: &str| {
        let mut t = decl[o];
        loop {
            if t == want || want == "object" {
                return true;
            }
            match parent.get(t) {
                Some(&p) => t = p,
                None => return false,
            }
        }
    };
    let mut ground: Vec<(usize, Vec<String>)> = Vec::new();
    for (ai, a) in d.actions.iter().enumerate() {
        let n = a.params.len();
        let mut idx = vec![0usize; n];
        loop {
            let args: Vec<String> = idx.iter().map(|&i| objects[i].clone()).collect();
            if a.params.iter().zip(&args).all(|(prm, o)| prm.types.iter().any(|t| is_a(o, t))) {
                ground.push((ai, args));
            }
            let mut k = 0;
            while k < n {
                idx[k] += 1;
                if idx[k] < objects.len() {
                    break;
                }
                idx[k] = 0;
                k += 1;
            }
            if k == n {
                break;
            }
        }
    }
    let init: BTreeSet<Fact> = p.init.iter().cloned().collect();
    let mut dist: HashMap<BTreeSet<Fact>, u64> = HashMap::new();
    dist.insert(init.clone(), 0);
    let mut heap = BinaryHeap::new();
    heap.push(Reverse((0u64, init)));
    while let Some(Reverse((g, s))) = heap.pop() {
        if dist.get(&s) != Some(&g) {
            continue;
        }
        if p.goal.iter().all(|(f, pos)| s.contains(f) == *pos) {
            return Some(g);
        }
        for (ai, args) in &ground {
            let a = &d.actions[*ai];
            let inst = |at: &mcl_plan::pddl::Atom| Fact {
                pred: at.pred.clone(),
                args: at.args.iter().map(|t| obj(t, args)).collect(),
            };
            if !a.pre.iter().all(|l| s.contains(&inst(&l.atom)) == l.positive) {
                continue;
            }
            let conds_ok = a.conds.iter().all(|c| match c {
                Cond::Equal(x, y, pos) => (obj(x, args) == obj(y, args)) == *pos,
                Cond::Compare(op, x, y) => match (eval(x, p, args), eval(y, p, args)) {
                    (Some(x), Some(y)) => op.holds(x, y),
                    _ => false,
                },
            });
            if !conds_ok {
                continue;
            }
            let mut t = s.clone();
            for at in &a.del {
                t.remove(&inst(at));
            }
            for at in &a.add {
                t.insert(inst(at));
            }
            let c = if p.metric { a.cost.as_ref().map(|e| eval(e, p, args).unwrap() as u64).unwrap_or(0) } else { 1 };
            let ng = g + c;
            if dist.get(&t).is_none_or(|&old| ng < old) {
                dist.insert(t.clone(), ng);
                heap.push(Reverse((ng, t)));
            }
        }
    }
    None
}

/// A random untyped STRIPS problem: 2-4 predicates of arity 0-2, 1-3
/// actions of 0-2 parameters with random positive and negative
/// preconditions, (in)equalities, add and delete lists and costs 1-3; 2-3
/// objects; random initial state and goal.
fn random_problem(seed: u64, costs: bool) -> (String, String) {
    let mut r = Rng::new(seed);
    let npred = 2 + r.below(3);
    let arity: Vec<usize> = (0..npred).map(|_| r.below(3)).collect();
    let nobj = 2 + r.below(2);
    let objs: Vec<String> = (0..nobj).map(|i| format!("o{i}")).collect();
    let mut dom = String::from(
        "(define (domain rnd) (:requirements :strips :negative-preconditions :equality :action-costs)\n (:predicates",
    );
    for (i, a) in arity.iter().enumerate() {
        dom.push_str(&format!(" (p{i}{})", (0..*a).map(|k| format!(" ?x{k}")).collect::<String>()));
    }
    dom.push_str(")\n (:functions (total-cost) - number)\n");
    let nact = 1 + r.below(3);
    for ai in 0..nact {
        let np = r.below(3);
        let params: Vec<String> = (0..np).map(|k| format!("?v{k}")).collect();
        let atom = |r: &mut Rng| -> String {
            let pi = r.below(npred);
            let args: String = (0..arity[pi])
                .map(|_| {
                    if np > 0 && r.below(4) != 0 {
                        format!(" {}", params[r.below(np)])
                    } else {
                        format!(" {}", objs[r.below(nobj)])
                    }
                })
                .collect();
            format!("(p{pi}{args})")
        };
        let mut pre = Vec::new();
        for _ in 0..r.below(3) {
            let a = atom(&mut r);
            pre.push(if r.below(4) == 0 { format!("(not {a})") } else { a });
        }
        if np == 2 && r.below(2) == 0 {
            pre.push(if r.below(2) == 0 { "(not (= ?v0 ?v1))".to_string() } else { "(= ?v0 ?v1)".to_string() });
        }
        let mut eff = Vec::new();
        for _ in 0..1 + r.below(2) {
            eff.push(atom(&mut r));
        }
        for _ in 0..r.below(3) {
            eff.push(format!("(not {})", atom(&mut r)));
        }
        eff.push(format!("(increase (total-cost) {})", 1 + r.below(3)));
        dom.push_str(&format!(
            " (:action a{ai} :parameters ({}) :precondition (and {}) :effect (and {}))\n",
            params.join(" "),
            pre.join(" "),
            eff.join(" ")
        ));
    }
    dom.push(')');
    let all_facts: Vec<String> = (0..npred)
        .flat_map(|pi| {
            let combos: Vec<Vec<usize>> = match arity[pi] {
                0 => vec![vec![]],
                1 => (0..nobj).map(|a| vec![a]).collect(),
                _ => (0..nobj).flat_map(|a| (0..nobj).map(move |b| vec![a, b])).collect(),
            };
            combos
                .into_iter()
                .map(move |c| format!("(p{pi}{})", c.iter().map(|&o| format!(" o{o}")).collect::<String>()))
        })
        .collect();
    let init: Vec<&String> = all_facts.iter().filter(|_| r.below(3) == 0).collect();
    let mut goal: Vec<String> = Vec::new();
    for _ in 0..1 + r.below(2) {
        let f = &all_facts[r.below(all_facts.len())];
        goal.push(if r.below(5) == 0 { format!("(not {f})") } else { f.clone() });
    }
    let prob = format!(
        "(define (problem rnd) (:domain rnd) (:objects {}) (:init {}) (:goal (and {})){})",
        objs.join(" "),
        init.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(" "),
        goal.join(" "),
        if costs { " (:metric minimize (total-cost))" } else { "" }
    );
    (dom, prob)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

    #[test]
    fn random_problems_agree_with_the_reference(seed in any::<u64>(), costs in any::<bool>()) {
        let (dt, pt) = random_problem(seed, costs);
        let d = parse_domain("d", &dt).unwrap_or_else(|e| panic!("{e:?}\n{dt}"));
        let p = parse_problem("p", &pt).unwrap_or_else(|e| panic!("{e:?}\n{pt}"));
        let want = reference(&d, &p);
        let hmax = mcl_plan::initial_h(&d, &p, Heuristic::Max).unwrap();
        let hadd = mcl_plan::initial_h(&d, &p, Heuristic::Add).unwrap();
        for alg in ALGS {
            let got = solve(&d, &p, alg);
            prop_assert_eq!(got.is_some(), want.is_some(), "{:?} solvable?\n{}\n{}", alg, dt, pt);
            if let Some(plan) = got {
                prop_assert_eq!(mcl_plan::validate(&d, &p, &plan.to_ipc()), Ok(plan.cost), "{:?}\n{}\n{}\n{}", alg, dt, pt, plan.to_ipc());
                if alg.is_cost_optimal() || !costs && alg == Algorithm::Bfs {
                    prop_assert_eq!(Some(plan.cost), want, "{:?} optimal\n{}\n{}\n{}", alg, dt, pt, plan.to_ipc());
                }
            }
        }
        // h_max is admissible; h_add >= h_max; both infinite only on unsolvable problems.
        match (want, hmax, hadd) {
            (Some(c), Some(hm), Some(ha)) => { prop_assert!(hm <= c); prop_assert!(ha >= hm); }
            (Some(_), _, _) => prop_assert!(false, "finite cost but infinite heuristic"),
            (None, hm, ha) => prop_assert_eq!(hm.is_some(), ha.is_some()),
        }
    }
}
