//! The trace records of plan execution (`mcl plan --run`): one serde enum
//! tagged by `kind`, one variant per kind with exactly its fields, written
//! by [`crate::run`] and read back by the same types (docs/scenarios.md,
//! *Traces*; docs/planning.md). The player's own records in the same trace
//! are `mcl_runtime::trace::Record`s.

use serde::{Deserialize, Serialize};

/// One line of a plan's trace: the time, then the kind and its fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanRecord {
    /// Seconds from the start of the run, to the microsecond.
    pub t: f64,
    /// What happened.
    #[serde(flatten)]
    pub kind: PlanKind,
}

/// Whether the holding mission started or stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Holding {
    /// It runs while a new plan is computed.
    Started,
    /// A plan is ready (or none can be): it was aborted.
    Stopped,
}

/// The kinds of plan records.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanKind {
    /// A plan was computed (`plan`: its number, from 1).
    Plan {
        plan: u32,
        /// `initial` or `re-plan`.
        reason: String,
        /// The actions of the steps, in order.
        steps: Vec<String>,
        /// Each step's MCL mission call, if it has one.
        calls: Vec<Option<String>>,
        cost: u64,
    },
    /// The facts no longer fit the plan: a new one is computed from `facts`.
    Replan { reason: String, facts: Vec<String> },
    /// A step's mission starts (`step` of `of`, from 1).
    Step { step: usize, of: usize, action: String, call: String, before: Vec<String>, after: Vec<String> },
    /// A step's mission ended: `ok`, `fail`, `aborted`, ...
    StepEnd { step: usize, action: String, result: String },
    /// A perception changed the facts.
    Facts { added: Vec<String>, deleted: Vec<String>, perception: String },
    /// The holding mission started or stopped.
    Holding { mission: String, state: Holding },
    /// The planned run ended (`result`: `ok`, `fail`, `time_limit`, ...).
    Outcome {
        result: String,
        /// Plans computed.
        plans: u32,
        /// Steps started.
        steps: u32,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
    },
}

impl PlanRecord {
    /// The record as a JSON value (what a trace line holds).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    /// A plan record from a trace line's JSON value; `None` for the
    /// player's records and kinds this enum does not hold.
    pub fn from_json(v: &serde_json::Value) -> Option<Self> {
        serde_json::from_value(v.clone()).ok()
    }

    /// Its line in the live log.
    pub fn live_line(&self) -> String {
        let what = match &self.kind {
            PlanKind::Plan { plan, reason, steps, calls, cost } => {
                let mut line = format!("PLAN {plan} ({reason}): {} step(s), cost {cost}", steps.len());
                for (i, (a, c)) in steps.iter().zip(calls).enumerate() {
                    line.push_str(&format!("\n             {}. {a}  {}", i + 1, c.as_deref().unwrap_or("")));
                }
                line
            }
            PlanKind::Replan { reason, .. } => format!("REPLAN: {reason}"),
            PlanKind::Step { step, action, call, .. } => format!("step {step} {action}: {call}"),
            PlanKind::StepEnd { step, action, result } => format!("step {step} {action}: {}", result.to_uppercase()),
            PlanKind::Facts { added, deleted, .. } => {
                format!("facts    +[{}] -[{}]", added.join(" "), deleted.join(" "))
            }
            PlanKind::Holding { mission, state } => format!(
                "holding  {mission} ({})",
                match state {
                    Holding::Started => "started",
                    Holding::Stopped => "stopped",
                }
            ),
            PlanKind::Outcome { result, reason, .. } => format!(
                "PLANNED MISSION {}{}",
                result.to_uppercase(),
                reason.as_ref().map(|x| format!(": {x}")).unwrap_or_default()
            ),
        };
        format!("[{:>10.3}] {what}", self.t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_read_back_what_they_write() {
        let records = [
            PlanKind::Plan {
                plan: 1,
                reason: "initial".into(),
                steps: vec!["goto l1 l2".into()],
                calls: vec![Some("Goto( 1, 2 )".into())],
                cost: 1,
            },
            PlanKind::Replan { reason: "facts changed".into(), facts: vec!["(at l1)".into()] },
            PlanKind::Step {
                step: 1,
                of: 2,
                action: "a".into(),
                call: "M()".into(),
                before: Vec::new(),
                after: vec!["(p)".into()],
            },
            PlanKind::StepEnd { step: 1, action: "a".into(), result: "ok".into() },
            PlanKind::Facts { added: vec!["(p)".into()], deleted: Vec::new(), perception: "x".into() },
            PlanKind::Holding { mission: "hold".into(), state: Holding::Started },
            PlanKind::Outcome { result: "ok".into(), plans: 1, steps: 2, reason: None },
        ];
        for kind in records {
            let r = PlanRecord { t: 1.5, kind };
            let v = r.to_json();
            assert_eq!(PlanRecord::from_json(&v).as_ref(), Some(&r), "{v}");
        }
        let v = PlanRecord { t: 0.0, kind: PlanKind::StepEnd { step: 2, action: "b".into(), result: "fail".into() } }
            .to_json();
        assert_eq!(v, serde_json::json!({ "t": 0.0, "kind": "step_end", "step": 2, "action": "b", "result": "fail" }));
        // A player's record is none of these.
        assert_eq!(PlanRecord::from_json(&serde_json::json!({ "t": 0.0, "kind": "fire", "transition": "x" })), None);
    }
}
