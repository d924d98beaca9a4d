//! Plans (Definition 7.2.4): an ordered list of steps, each an instance of an
//! MCL mission operator with the facts expected before (F_i) and after (F_e)
//! its execution, plus the facts the rest of the plan needs (the regression
//! of the goal through the remaining steps), which the executor uses to
//! decide whether the plan is still valid.

use crate::ground::{MclInstance, Task};
use crate::pddl::Fact;
use serde::Serialize;
use std::fmt::Write as _;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// `(gotoop auv deploy inspection)`.
    pub action: String,
    pub operator: String,
    pub args: Vec<String>,
    pub cost: u64,
    /// The MCL mission operator instance (`GotoMCLop( 50, 20 )`), when the action has `:mcl`.
    pub mcl: Option<MclInstance>,
    /// F_i: the predicted state when the step starts (fluent facts).
    pub before: Vec<Fact>,
    /// F_e: the predicted state when the step has ended.
    pub after: Vec<Fact>,
    /// Facts that must hold when the step starts for the remaining steps to
    /// reach the goal: its preconditions and what later steps need and no
    /// earlier step of the suffix provides.
    pub needs: Vec<Fact>,
    /// Facts that must be false then (negative preconditions and goals).
    pub needs_false: Vec<Fact>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    pub steps: Vec<Step>,
    pub cost: u64,
    /// No `:metric` in the problem: every action cost 1.
    pub unit_cost: bool,
    pub goal: Vec<Fact>,
    pub goal_false: Vec<Fact>,
    /// Ground action indices in the task the plan was made for.
    #[serde(skip)]
    pub actions: Vec<u32>,
}

impl Plan {
    /// Builds the steps of the plan `actions` applied from `init` (fact indices).
    pub fn new(task: &Task, init: &[u32], actions: &[u32]) -> Plan {
        let facts = |set: &[bool]| -> Vec<Fact> {
            set.iter().enumerate().filter(|(_, b)| **b).map(|(f, _)| task.fact(f as u32)).collect()
        };
        let mut state = vec![false; task.num_facts()];
        for &f in init {
            state[f as usize] = true;
        }
        let mut steps = Vec::with_capacity(actions.len());
        let mut cost = 0;
        for &a in actions {
            let ga = &task.actions[a as usize];
            let before = facts(&state);
            for &f in ga.del.iter() {
                state[f as usize] = false;
            }
            for &f in ga.add.iter() {
                state[f as usize] = true;
            }
            cost += ga.cost;
            steps.push(Step {
                action: task.action_name(a),
                operator: task.op_names[ga.op as usize].clone(),
                args: ga.args.iter().map(|&o| task.objects[o as usize].clone()).collect(),
                cost: ga.cost,
                mcl: ga.mcl.clone(),
                before,
                after: facts(&state),
                needs: Vec::new(),
                needs_false: Vec::new(),
            });
        }
        // Regression of the goal: K_k = goal, K_i = pre(a_i) ∪ (K_{i+1} − add(a_i)).
        let mut need = vec![false; task.num_facts()];
        let mut need_false = vec![false; task.num_facts()];
        for &g in &task.goal {
            need[g as usize] = true;
        }
        for &g in &task.goal_neg {
            need_false[g as usize] = true;
        }
        for (i, &a) in actions.iter().enumerate().rev() {
            let ga = &task.actions[a as usize];
            for &f in ga.add.iter() {
                need[f as usize] = false;
            }
            for &f in ga.del.iter() {
                need_false[f as usize] = false;
            }
            for &f in ga.pre.iter() {
                need[f as usize] = true;
            }
            for &f in ga.pre_neg.iter() {
                need_false[f as usize] = true;
            }
            steps[i].needs = facts(&need);
            steps[i].needs_false = facts(&need_false);
        }
        Plan {
            steps,
            cost,
            unit_cost: task.unit_cost,
            goal: task.goal.iter().map(|&g| task.fact(g)).collect(),
            goal_false: task.goal_neg.iter().map(|&g| task.fact(g)).collect(),
            actions: actions.to_vec(),
        }
    }

    /// The plan in the IPC format: one `(action arg ...)` per line, then
    /// `; cost = N (unit cost)` or `; cost = N (general cost)`.
    pub fn to_ipc(&self) -> String {
        let mut s = String::new();
        for st in &self.steps {
            s.push_str(&st.action);
            s.push('\n');
        }
        let _ = writeln!(s, "; cost = {} ({})", self.cost, if self.unit_cost { "unit cost" } else { "general cost" });
        s
    }

    /// A readable listing: each step with its MCL operator instance and expected facts.
    pub fn to_steps_text(&self) -> String {
        let list = |v: &[Fact]| v.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(" ");
        let mut s = String::new();
        for (i, st) in self.steps.iter().enumerate() {
            let _ = writeln!(s, "{}. {}  cost {}", i + 1, st.action, st.cost);
            match &st.mcl {
                Some(m) => {
                    let _ = writeln!(s, "   mcl:    {m}");
                }
                None => {
                    let _ = writeln!(s, "   mcl:    (none)");
                }
            }
            let _ = writeln!(s, "   before: {}", list(&st.before));
            let _ = writeln!(s, "   after:  {}", list(&st.after));
            let _ = writeln!(s, "   needs:  {}", list(&st.needs));
        }
        let _ = writeln!(s, "goal: {}", list(&self.goal));
        let _ = writeln!(s, "; cost = {} ({})", self.cost, if self.unit_cost { "unit cost" } else { "general cost" });
        s
    }
}
