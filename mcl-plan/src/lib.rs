//! `mcl-plan`: the on-board planner of MCL (seed chapter 7).
//!
//! Planning operators are STRIPS actions (preconditions, add and delete
//! lists, expressions over objects and their attributes, costs) whose bodies
//! are small MCL missions (`:mcl (MclMove ?l2.x ?l2.y ?l2.z)`, Extract 7.2).
//! Domains and problems are written in PDDL (see docs/planning.md).
//!
//! Pipeline: [`pddl`] parses, [`ground`] grounds with type-aware pruning and
//! relaxed reachability, [`search`] runs BFS, uniform-cost search, A* or greedy best-first with
//! h_add / h_max ([`heuristic`]), [`plan`] turns the actions found into steps
//! (MCL operator instance, facts expected before and after), [`validate`]
//! replays any plan. [`world`] turns perceptions into facts with the seed's
//! fact-provider scripts and [`executor`] decides, step after step, whether
//! to run, skip ahead or re-plan; [`run`] executes plans on the player
//! against the mock vehicle (compiling each operator instance). [`gen`] writes classic benchmark problems.

pub mod executor;
pub mod gen;
pub mod ground;
pub mod heuristic;
pub mod mcl;
pub mod model;
pub mod pddl;
pub mod plan;
pub mod record;
pub mod run;
pub mod search;
pub mod sexpr;
pub mod validate;
pub mod world;

pub use ground::{ground, McValue, MclInstance, Task};
pub use heuristic::Kind as Heuristic;
pub use pddl::{parse_domain, parse_problem, Domain, Fact, Problem};
pub use plan::{Plan, Step};
pub use search::{Algorithm, Stats};
pub use sexpr::Error;
pub use validate::validate;

use std::path::Path;
use std::time::{Duration, Instant};

/// What a planning run found.
#[derive(Clone, Debug)]
pub enum Outcome {
    Plan(Plan),
    /// No plan exists (proved by exhausting the reachable states, or because
    /// a goal fact is unreachable even ignoring delete effects).
    Unsolvable,
    /// The search stored `max_states` states without finding a plan.
    LimitReached,
}

/// The result of [`solve`].
#[derive(Clone, Debug)]
pub struct Solution {
    pub outcome: Outcome,
    pub stats: Stats,
    /// Number of ground actions and reachable facts.
    pub actions: usize,
    pub facts: usize,
    pub ground_time: Duration,
    pub search_time: Duration,
}

/// Reads and parses a domain and a problem file.
pub fn load(domain: &Path, problem: &Path) -> Result<(Domain, Problem), Vec<Error>> {
    let read = |p: &Path| {
        mcl_net::input::read_source(p).map_err(|e| {
            let message = format!("cannot read: {}", e.reason);
            vec![Error { file: p.display().to_string(), line: 1, column: 1, message }]
        })
    };
    let dt = read(domain)?;
    let pt = read(problem)?;
    let d = parse_domain(&domain.display().to_string(), &dt);
    let p = parse_problem(&problem.display().to_string(), &pt);
    match (d, p) {
        (Ok(d), Ok(p)) => Ok((d, p)),
        (d, p) => Err(d.err().unwrap_or_default().into_iter().chain(p.err().unwrap_or_default()).collect()),
    }
}

/// Grounds and searches.
pub fn solve(domain: &Domain, problem: &Problem, alg: Algorithm, max_states: u64) -> Result<Solution, Vec<Error>> {
    let t0 = Instant::now();
    let task = ground(domain, problem)?;
    let ground_time = t0.elapsed();
    let t1 = Instant::now();
    let r = search::search(&task, alg, max_states);
    let search_time = t1.elapsed();
    let outcome = match r.outcome {
        search::Outcome::Plan(p) => Outcome::Plan(Plan::new(&task, &task.init, &p)),
        search::Outcome::Unsolvable => Outcome::Unsolvable,
        search::Outcome::LimitReached => Outcome::LimitReached,
    };
    Ok(Solution {
        outcome,
        stats: r.stats,
        actions: task.actions.len(),
        facts: task.num_facts(),
        ground_time,
        search_time,
    })
}

/// The heuristic value of the problem's initial state (h_add or h_max), or
/// `None` when the relaxation cannot reach the goal.
pub fn initial_h(domain: &Domain, problem: &Problem, kind: Heuristic) -> Result<Option<u64>, Vec<Error>> {
    let task = ground(domain, problem)?;
    if !task.goal_reachable {
        return Ok(None);
    }
    let mut h = heuristic::Relaxed::new(&task, kind);
    let v = h.eval_facts(task.init.iter().copied());
    Ok((v != heuristic::INF).then_some(v))
}
