//! Verification of the building blocks a file defines (seed 4.3.1): every
//! task (its pattern with its events and delays) and every pattern no task
//! uses must satisfy the block properties; a failure is reported with the
//! shortest counterexample.

use super::Cx;
use crate::codes;
use crate::compile::builder::Builder;
use crate::compile::{add_task_net, verify};
use crate::db::{Db, SourceFile};
use crate::scope::{self, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::Diagnostic;

/// Largest state space explored for one block.
const MAX_STATES: usize = 200_000;

/// A block to verify: a task of a file, by name.
#[salsa::interned(debug)]
pub struct TaskKey {
    pub root: SourceFile,
    #[returns(ref)]
    pub name: String,
}

/// The verdict on task `key.name` in the program rooted at `key.root`
/// (`None` when the task cannot be built, e.g. its pattern is undefined).
#[salsa::tracked(returns(ref))]
pub fn task_verdict(db: &dyn Db, key: TaskKey<'_>) -> Option<verify::Verdict> {
    let scope = scope::local_scope(db, *key.root(db));
    let mut b = Builder::new(key.name(db));
    let (_, _) = add_task_net(db, scope, &mut b, key.name(db), "").ok()??;
    let net = b.finish().build().ok()?;
    let h = verify::task_harness(&net)?;
    Some(h.verify(MAX_STATES))
}

pub(crate) fn check(cx: &mut Cx<'_>) {
    for item in &cx.ast().items {
        let Item::Tasks(block) = item else { continue };
        for t in &block.tasks {
            let Some(pname) = &t.pattern else { continue };
            let Some(pid) = cx.scope.first(DefKind::Pattern, &pname.text) else {
                continue;
            };
            let Some(pattern) = scope::pattern(cx.db, pid) else {
                continue;
            };
            if !matches!(scope::pattern_net(cx.db, pid), Some(Ok(_))) {
                continue;
            }
            // A task already reported as wrong would only fail again here.
            if cx
                .out
                .iter()
                .chain(cx.syntax_errors)
                .any(|d| d.is_error() && d.span.start >= t.span.start && d.span.end <= t.span.end)
            {
                continue;
            }
            let key = TaskKey::new(cx.db, cx.file, t.name.text.clone());
            let Some(verdict) = task_verdict(cx.db, key) else {
                continue;
            };
            for v in &verdict.violations {
                let what = match v.property {
                    "1-safe" => "is not 1-safe",
                    "reachability" => "can fail to end (reachability condition, seed 4.3.1)",
                    "reusability" => "does not return to rest (reusability, seed 4.3.1)",
                    "abort" => "does not handle abort correctly",
                    _ => "is too large to verify",
                };
                let d = Diagnostic::error(codes::BLOCK_PROPERTY, format!("task `{}` {what}", t.name.text), t.name.span)
                    .with_label(t.name.span, v.message.clone());
                let mut d = cx.def_label(d, pid, pattern.name.span, format!("pattern `{}`", pattern.name.text));
                if !v.trace.is_empty() {
                    d = d.with_note(format!("counterexample: {}", v.trace.join(" → ")));
                }
                d = d.with_help(match v.property {
                    "abort" => "an abort must take a running task back to rest at once, through immediate transitions, and do nothing at rest",
                    "reusability" => "every place outside begin/abort/ok/fail must be back to its initial marking when the task ends",
                    "1-safe" => "a place of a building block holds at most one token",
                    _ => "from begin, every run must end with exactly one of ok and fail marked (or at rest after an abort)",
                });
                cx.out.push(d);
            }
        }
    }
}
