//! Verification of the building blocks a program defines (seed 4.3.1):
//! every task (its pattern with its events and delays) and every pattern no
//! task uses (alone: its transitions immediate, or timed where they have a
//! delay) must satisfy the block properties; a failure is reported at the
//! pattern with the shortest counterexample.

use super::Cx;
use crate::codes;
use crate::compile::builder::Builder;
use crate::compile::{add_pattern_net, add_task_net, verify};
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

/// A block to verify: a pattern of a file that no task uses, by name.
#[salsa::interned(debug)]
pub struct PatternKey {
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

/// The verdict on pattern `key.name` alone, with no task binding its
/// transitions (`None` when it cannot be built).
#[salsa::tracked(returns(ref))]
pub fn pattern_verdict(db: &dyn Db, key: PatternKey<'_>) -> Option<verify::Verdict> {
    let scope = scope::local_scope(db, *key.root(db));
    let pid = scope.first(DefKind::Pattern, key.name(db))?;
    let net = scope::pattern_net(db, pid)?.ok()?;
    let mut b = Builder::new(key.name(db));
    let file_path = pid.file.path(db).display().to_string();
    add_pattern_net(&mut b, net, &file_path, None, &Default::default(), Default::default(), "").ok()??;
    let net = b.finish().build().ok()?;
    let h = verify::task_harness(&net)?;
    Some(h.verify(MAX_STATES))
}

/// The main message of a violation of pattern `pattern`.
fn what(property: &str) -> &'static str {
    match property {
        "1-safe" => "is not 1-safe",
        "reachability" => "can fail to end with exactly one of ok and fail (reachability condition, seed 4.3.1)",
        "exactly-one" => "violates \"exactly one of ok/fail\" (reachability condition, seed 4.3.1)",
        "reusability" => "does not return to rest (reusability, seed 4.3.1)",
        "abort" => "does not handle abort correctly",
        "rest" => "does not return to rest at once when it ends",
        _ => "is too large to verify",
    }
}

fn help(property: &str) -> &'static str {
    match property {
        "abort" => "an abort must take a running task back to rest at once, through immediate transitions",
        "rest" => "when ok or fail is marked, the remaining transitions (e.g. the primitive's disable) must be immediate, so that the task is at rest before its next call starts",
        "reusability" => "every place outside begin/abort/ok/fail must be back to its initial marking when the task ends",
        "1-safe" => "a place of a building block holds at most one token",
        "exactly-one" => "every run must mark exactly one of ok and fail, and an aborted run neither",
        "size" => "split the pattern, or make it smaller",
        _ => "from begin, every run without abort must end with exactly one of ok and fail marked, and every run with an abort back at rest",
    }
}

fn with_details(mut d: Diagnostic, v: &verify::Violation) -> Diagnostic {
    if let Some(c) = v.counterexample() {
        d = d.with_note(format!("counterexample: {c}"));
    }
    for n in &v.notes {
        d = d.with_note(n.clone());
    }
    d.with_help(help(v.property))
}

pub(crate) fn check(cx: &mut Cx<'_>) {
    for item in &cx.ast().items {
        match item {
            Item::Tasks(block) => check_tasks(cx, block),
            Item::Patterns(block) => check_unused_patterns(cx, block),
            _ => {}
        }
    }
}

fn check_tasks(cx: &mut Cx<'_>, block: &TasksBlock) {
    for t in &block.tasks {
        let Some(pname) = &t.pattern else { continue };
        let Some(pid) = cx.scope.first(DefKind::Pattern, &pname.text) else {
            continue;
        };
        let Some(pattern) = scope::pattern(cx.db, pid) else {
            continue;
        };
        if scope::is_broken(cx.db, pid, pattern.span) {
            continue;
        }
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
        let task_id = cx.scope.first(DefKind::Task, &t.name.text).filter(|id| id.file == cx.file);
        for v in &verdict.violations {
            let message = format!("pattern `{}` {}", pattern.name.text, what(v.property));
            let task_label = format!("with the events and delays of task `{}`", t.name.text);
            let d = match task_id {
                // The pattern is in this file: the diagnostic is at the
                // pattern, the task is a secondary label.
                Some(tid) if pid.file == cx.file => {
                    let d = Diagnostic::error(codes::BLOCK_PROPERTY, message, pattern.name.span)
                        .with_label(pattern.name.span, v.message.clone());
                    let d = cx.def_label(d, tid, t.name.span, task_label);
                    cx.at_def(pid);
                    d
                }
                // The pattern is imported: at the task, the pattern as a label.
                _ => {
                    let d = Diagnostic::error(codes::BLOCK_PROPERTY, message, t.name.span)
                        .with_label(t.name.span, format!("{task_label}: {}", v.message));
                    cx.def_label(d, pid, pattern.name.span, format!("pattern `{}`", pattern.name.text))
                }
            };
            cx.out.push(with_details(d, v));
        }
        // A task that breaks a property is reported once, by E0601.
        let premature = if verdict.ok() { verdict.premature.as_slice() } else { &[] };
        for f in premature.iter().filter(|f| !f.transition.starts_with('_')) {
            let d = Diagnostic::warning(
                codes::PREMATURE_TRANSITION,
                format!(
                    "transition `{}` of task `{}` fires at once: it has no event and no delay, and it takes `{}` before `{}` can wait for `{}`",
                    f.transition, t.name.text, f.place, f.waiting, f.event
                ),
                t.name.span,
            )
            .with_label(
                t.name.span,
                format!("`{}` is immediate here, so `{}` never waits for `{}`", f.transition, f.waiting, f.event),
            )
            .with_note(format!(
                "counterexample: {}, then `{}` fires before any event",
                if f.trace.is_empty() { "(start)".to_string() } else { f.trace.join(" -> ") },
                f.transition
            ))
            .with_help(format!(
                "bind an event to it (`e: someEvent -> {0};`) or give it a delay (`{0}(30)` in the pattern) to make it a time-out; if it must fire at once, name it `_{0}`",
                f.transition
            ));
            cx.out.push(d);
        }
    }
}

/// True when some task of the program uses pattern `name`.
fn used_by_a_task(cx: &Cx<'_>, name: &str) -> bool {
    cx.scope
        .names(DefKind::Task)
        .filter_map(|t| cx.scope.first(DefKind::Task, t))
        .filter_map(|id| scope::task(cx.db, id))
        .any(|t| t.pattern.as_ref().is_some_and(|p| p.text == name))
}

fn check_unused_patterns(cx: &mut Cx<'_>, block: &PatternsBlock) {
    for p in &block.patterns {
        if !matches!(p.body, PatternBody::Net(_)) && !matches!(p.body, PatternBody::File { .. }) {
            continue;
        }
        if cx
            .out
            .iter()
            .chain(cx.syntax_errors)
            .any(|d| d.is_error() && d.span.start >= p.span.start && d.span.end <= p.span.end)
        {
            continue;
        }
        // Only the definition in force (an earlier duplicate is reported elsewhere).
        let Some(pid) = cx.scope.first(DefKind::Pattern, &p.name.text) else { continue };
        if pid.file != cx.file || used_by_a_task(cx, &p.name.text) {
            continue;
        }
        if !matches!(scope::pattern_net(cx.db, pid), Some(Ok(_))) {
            continue;
        }
        let key = PatternKey::new(cx.db, cx.file, p.name.text.clone());
        let Some(verdict) = pattern_verdict(cx.db, key) else {
            continue;
        };
        for v in &verdict.violations {
            let d = Diagnostic::error(
                codes::BLOCK_PROPERTY,
                format!("pattern `{}` {}", p.name.text, what(v.property)),
                p.name.span,
            )
            .with_label(p.name.span, v.message.clone())
            .with_note(
                "no task uses this pattern: it was verified alone, every transition immediate (or timed where it has a delay)",
            );
            cx.out.push(with_details(d, v));
        }
    }
}
