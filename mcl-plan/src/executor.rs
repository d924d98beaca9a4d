//! Plan execution monitoring and re-planning (seed 7.5).
//!
//! The executor holds the current plan and, each time it is asked, compares
//! the facts of the knowledge database with what the plan expects:
//!
//! - the goal holds: [`Decision::Done`];
//! - the last step's MCL mission ended in fail: [`Decision::Replan`];
//! - [`Policy::Regression`] (default): run the *latest* step whose `needs`
//!   (the facts the rest of the plan relies on) all hold — the expected next
//!   step when the world behaved as planned, a later one when something went
//!   better than planned (facts that do not matter to the rest of the plan
//!   may differ); if no step's needs hold, or if the step chosen is not past
//!   the step that just ended in ok (its effects were not observed),
//!   [`Decision::Replan`];
//! - [`Policy::Strict`] (the seed's literal rule): run the next step only if
//!   the facts are exactly the ones the plan predicted (F_i), else re-plan.
//!
//! The runtime calls [`Executor::next_step`] with the world modeler's facts,
//! runs the step's MCL mission instance on the player, reports its outcome
//! with [`Executor::step_ended`], and on [`Decision::Replan`] calls
//! [`Executor::replan`] with the current facts.

use crate::pddl::{Domain, Fact, Problem};
use crate::plan::{Plan, Step};
use crate::search::Algorithm;
use crate::{solve, Outcome};
use std::collections::BTreeSet;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Policy {
    #[default]
    Regression,
    Strict,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Run this step (index into [`Executor::plan`]'s steps).
    Run(usize),
    /// The facts differ from what the plan needs, or a step failed: call [`Executor::replan`].
    Replan,
    /// The goal holds.
    Done,
    /// No plan reaches the goal from the current facts (or re-planning was
    /// given up): the reason.
    Failed(String),
}

pub struct Executor {
    domain: Domain,
    problem: Problem,
    alg: Algorithm,
    policy: Policy,
    plan: Plan,
    /// The step expected next.
    next: usize,
    /// The last step reported by [`Executor::step_ended`] and its outcome.
    last: Option<(usize, bool)>,
    failed: Option<String>,
    pub replans: u32,
    /// Re-planning is given up after this many plans (default 100).
    pub max_replans: u32,
    pub max_states: u64,
}

impl Executor {
    /// Plans from the problem's initial state.
    pub fn new(domain: Domain, problem: Problem, alg: Algorithm) -> Result<Executor, String> {
        let mut ex = Executor {
            domain,
            problem,
            alg,
            policy: Policy::default(),
            plan: Plan {
                steps: Vec::new(),
                cost: 0,
                unit_cost: true,
                goal: Vec::new(),
                goal_false: Vec::new(),
                actions: Vec::new(),
            },
            next: 0,
            last: None,
            failed: None,
            replans: 0,
            max_replans: 100,
            max_states: crate::search::DEFAULT_MAX_STATES,
        };
        let init = ex.problem.init.clone();
        ex.make_plan(&init)?;
        ex.replans = 0;
        Ok(ex)
    }

    pub fn with_policy(mut self, policy: Policy) -> Executor {
        self.policy = policy;
        self
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    pub fn step(&self, i: usize) -> &Step {
        &self.plan.steps[i]
    }

    fn make_plan(&mut self, facts: &[Fact]) -> Result<(), String> {
        let p = self.problem.with_init(facts.to_vec());
        let sol = solve(&self.domain, &p, self.alg, self.max_states)
            .map_err(|e| e.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("\n"))?;
        match sol.outcome {
            Outcome::Plan(plan) => {
                self.plan = plan;
                self.next = 0;
                self.last = None;
                self.failed = None;
                self.replans += 1;
                Ok(())
            }
            Outcome::Unsolvable => Err("no plan reaches the goal from the current facts".to_string()),
            Outcome::LimitReached => Err("the planner gave up (state limit reached)".to_string()),
        }
    }

    /// Computes a new plan from `current`. On failure, later calls of
    /// [`next_step`](Self::next_step) answer [`Decision::Failed`].
    pub fn replan(&mut self, current: &BTreeSet<Fact>) -> Result<&Plan, String> {
        if self.replans > self.max_replans {
            let why = format!("gave up after {} re-plans", self.max_replans);
            self.failed = Some(why.clone());
            return Err(why);
        }
        // Facts of predicates the domain does not know (a script may make
        // them for other purposes) cannot matter to the plan.
        let known =
            |f: &&Fact| self.domain.predicates.iter().any(|p| p.name == f.pred && p.params.len() == f.args.len());
        let facts: Vec<Fact> = current.iter().filter(known).cloned().collect();
        match self.make_plan(&facts) {
            Ok(()) => Ok(&self.plan),
            Err(e) => {
                self.failed = Some(e.clone());
                Err(e)
            }
        }
    }

    /// Reports how the MCL mission of step `i` ended (`ok` or fail).
    pub fn step_ended(&mut self, i: usize, ok: bool) {
        self.last = Some((i, ok));
        if ok {
            self.next = i + 1;
        }
    }

    /// The last step reported, if it ended in fail.
    pub fn last_failed(&self) -> Option<usize> {
        match self.last {
            Some((i, false)) => Some(i),
            _ => None,
        }
    }

    /// The step expected next (after the last one that ended in ok).
    pub fn next_index(&self) -> usize {
        self.next
    }

    /// Whether the facts still fit the plan while step `running` runs
    /// (checked whenever perceptions change the facts): the goal holds, or
    /// some step from `running` on has its needs (policy `Regression`; the
    /// running step's effects may already be observed), or the facts are
    /// those predicted before or after the running step (policy `Strict`).
    pub fn expects(&self, current: &BTreeSet<Fact>, running: usize) -> bool {
        if self.goal_holds(current) {
            return true;
        }
        match self.policy {
            Policy::Regression => (running..self.plan.steps.len()).any(|i| {
                let st = &self.plan.steps[i];
                st.needs.iter().all(|f| current.contains(f)) && !st.needs_false.iter().any(|f| current.contains(f))
            }),
            Policy::Strict => {
                let Some(st) = self.plan.steps.get(running) else { return false };
                let preds: BTreeSet<&str> = st.before.iter().chain(&st.after).map(|f| f.pred.as_str()).collect();
                let actual: BTreeSet<&Fact> = current.iter().filter(|f| preds.contains(f.pred.as_str())).collect();
                actual == st.before.iter().collect() || actual == st.after.iter().collect()
            }
        }
    }

    /// How the facts differ from what step `i` of the plan expects (the goal
    /// when `i` is past the last step): the facts it needs that are missing,
    /// and the facts that hold although it needs them false or the plan
    /// predicted neither before nor after the step.
    pub fn divergence(&self, current: &BTreeSet<Fact>, i: usize) -> (Vec<Fact>, Vec<Fact>) {
        let Some(st) = self.plan.steps.get(i) else {
            let missing = self.plan.goal.iter().filter(|f| !current.contains(f)).cloned().collect();
            let extra = self.plan.goal_false.iter().filter(|f| current.contains(f)).cloned().collect();
            return (missing, extra);
        };
        let missing = st.needs.iter().filter(|f| !current.contains(f)).cloned().collect();
        // Fluent facts (of predicates some action changes) predicted neither before nor after the step.
        let fluent: BTreeSet<&str> =
            self.domain.actions.iter().flat_map(|a| a.add.iter().chain(&a.del)).map(|a| a.pred.as_str()).collect();
        let known: BTreeSet<&Fact> = st.before.iter().chain(&st.after).collect();
        let extra = current
            .iter()
            .filter(|f| st.needs_false.contains(f) || (fluent.contains(f.pred.as_str()) && !known.contains(f)))
            .cloned()
            .collect();
        (missing, extra)
    }

    fn goal_holds(&self, current: &BTreeSet<Fact>) -> bool {
        self.problem.goal.iter().all(|(g, pos)| current.contains(g) == *pos)
    }

    /// What to do now, given the facts of the knowledge database.
    pub fn next_step(&mut self, current: &BTreeSet<Fact>) -> Decision {
        if let Some(why) = &self.failed {
            return Decision::Failed(why.clone());
        }
        if self.goal_holds(current) {
            return Decision::Done;
        }
        if let Some((_, false)) = self.last {
            return Decision::Replan;
        }
        match self.policy {
            Policy::Strict => {
                let Some(st) = self.plan.steps.get(self.next) else { return Decision::Replan };
                // Compare the fluent facts the plan predicted with the current ones.
                let predicted: BTreeSet<&Fact> = st.before.iter().collect();
                let preds: BTreeSet<&str> = self
                    .plan
                    .steps
                    .iter()
                    .flat_map(|s| s.before.iter().chain(&s.after))
                    .map(|f| f.pred.as_str())
                    .collect();
                let actual: BTreeSet<&Fact> = current.iter().filter(|f| preds.contains(f.pred.as_str())).collect();
                if predicted == actual {
                    Decision::Run(self.next)
                } else {
                    Decision::Replan
                }
            }
            Policy::Regression => {
                let chosen = (0..self.plan.steps.len()).rev().find(|&i| {
                    let st = &self.plan.steps[i];
                    st.needs.iter().all(|f| current.contains(f)) && !st.needs_false.iter().any(|f| current.contains(f))
                });
                match (chosen, self.last) {
                    (Some(i), Some((j, true))) if i <= j => Decision::Replan,
                    (Some(i), _) => Decision::Run(i),
                    (None, _) => Decision::Replan,
                }
            }
        }
    }
}
