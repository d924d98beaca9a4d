//! Mission checks: calls against task headers, labels, parameters,
//! `parallel` blocks that mix `and` and `or`, and missions without a name in
//! a file that has several.

use super::Cx;
use crate::codes;
use crate::scope::{self, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::visit::walk_block;
use mcl_syntax::{Diagnostic, Span};
use rustc_hash::FxHashMap;

/// What the checks of a call need to know about the task it names, looked
/// up once per task name of the item (a mission calls the same tasks many
/// times, and each lookup goes through the database).
#[derive(Clone, Copy)]
enum Callee<'a> {
    /// No such task: every call is reported.
    Undefined,
    /// Nothing to check (no node for it, or a task with a syntax error).
    Skip,
    Task {
        id: scope::DefId,
        task: &'a TaskDef,
        /// The pattern's net, when the task names a pattern that has one.
        net: Option<&'a PatternNet>,
    },
}

fn callee<'a>(cx: &Cx<'a>, name: &str) -> Callee<'a> {
    let Some(id) = cx.scope.first(DefKind::Task, name) else { return Callee::Undefined };
    let Some(task) = scope::task(cx.db, id) else { return Callee::Skip };
    // A task with a syntax error: its header may be incomplete.
    if scope::is_broken(cx.db, id, task.span) {
        return Callee::Skip;
    }
    let net = task
        .pattern
        .as_ref()
        .and_then(|p| cx.scope.first(DefKind::Pattern, &p.text))
        .and_then(|pid| scope::pattern_net(cx.db, pid))
        .and_then(Result::ok);
    Callee::Task { id, task, net }
}

pub(crate) fn check(cx: &mut Cx<'_>) {
    let mut callees: FxHashMap<&str, Callee<'_>> = FxHashMap::default();
    for item in &cx.ast().items {
        let Item::Mission(m) = item else { continue };
        let mut params: FxHashMap<&str, Span> = FxHashMap::default();
        for p in &m.params {
            if let Some(prev) = params.insert(&p.text, p.span) {
                cx.out.push(
                    Diagnostic::error(
                        codes::DUPLICATE_PARAMETER,
                        format!("parameter `{}` is declared twice", p.text),
                        p.span,
                    )
                    .with_label(prev, "first declared here"),
                );
            }
        }
        let mut labels: FxHashMap<&str, Span> = FxHashMap::default();
        walk_block(&m.body, &mut |s| match &s.kind {
            StmtKind::Call(c) => {
                if let Some(l) = &c.label {
                    if let Some(prev) = labels.insert(&l.text, l.span) {
                        cx.out.push(
                            Diagnostic::error(
                                codes::DUPLICATE_LABEL,
                                format!("label `{}` is used twice in this mission", l.text),
                                l.span,
                            )
                            .with_label(prev, "first used here")
                            .with_help("a label names one call, so that constraints can refer to it"),
                        );
                    }
                }
                let callee = match callees.get(c.name.text.as_str()) {
                    Some(x) => *x,
                    None => *callees.entry(&c.name.text).or_insert(callee(cx, &c.name.text)),
                };
                check_call(cx, c, callee);
            }
            StmtKind::Parallel { ops, .. } => {
                if let (Some(&(first, fs)), Some(&(_, other))) = (ops.first(), ops.iter().find(|(o, _)| *o != ops[0].0))
                {
                    let (a, b) = if first == ParallelOp::And { ("and", "or") } else { ("or", "and") };
                    cx.out.push(
                        Diagnostic::error(codes::MIXED_PARALLEL, "`and` and `or` are mixed in one `parallel`", other)
                            .with_label(fs, format!("this `parallel` is a parallel-{a}"))
                            .with_label(other, format!("but this branch is joined with `{b}`"))
                            .with_help("nest one parallel inside a branch of the other, e.g. `parallel { A } and { parallel { B } or { C } }`"),
                    );
                }
            }
            StmtKind::Monitor { body, handlers, .. } => check_monitor_sharing(cx, body, handlers),
            _ => {}
        });
    }
}

/// Whether a call of task `name` can last: the task binds an event or its
/// pattern has a timed transition (an instantaneous task, such as the seed's
/// `Void`, holds its net for no time at all).
fn can_wait(cx: &Cx<'_>, name: &str) -> bool {
    let Some(task) = cx.scope.first(DefKind::Task, name).and_then(|id| scope::task(cx.db, id)) else { return false };
    if task.bindings.iter().any(|b| b.kind == BindingKind::Event) {
        return true;
    }
    task.pattern
        .as_ref()
        .and_then(|p| cx.scope.first(DefKind::Pattern, &p.text))
        .and_then(|pid| scope::pattern_net(cx.db, pid))
        .and_then(Result::ok)
        .is_some_and(|net| net.transitions.iter().any(|t| t.delay.is_some()))
}

/// A task is one net shared by its calls (seed 5.7): two calls that are
/// active at once run one after the other. A monitor's condition runs
/// beside its watched block and normally ends only when what it watches
/// happens, so a task called both in the watched block and in a condition
/// (or in two conditions) makes one wait for the other: the block cannot
/// run while the condition holds the task, or the condition does not watch
/// while the block holds it. Reported once per task and monitor (W0303).
fn check_monitor_sharing(cx: &mut Cx<'_>, body: &Block, handlers: &[MonitorHandler]) {
    fn calls(b: &Block) -> Vec<&Call> {
        let mut out = Vec::new();
        walk_block(b, &mut |s| {
            if let StmtKind::Call(c) = &s.kind {
                out.push(c);
            }
        });
        out
    }
    // (task, where it is first called, in what) for the watched block and each condition seen so far.
    let mut seen: Vec<(&str, Span, &'static str)> =
        calls(body).into_iter().map(|c| (c.name.text.as_str(), c.name.span, "the watched block")).collect();
    let mut reported: Vec<&str> = Vec::new();
    for h in handlers {
        let here = calls(&h.condition);
        for c in &here {
            let name = c.name.text.as_str();
            if reported.contains(&name) || !can_wait(cx, name) {
                continue;
            }
            let Some(&(_, first, place)) = seen.iter().find(|(n, ..)| *n == name) else { continue };
            reported.push(name);
            cx.out.push(
                Diagnostic::warning(
                    codes::MONITOR_SHARES_TASK,
                    format!("task `{name}` is called both in {place} of this monitor and in its condition: the two calls cannot run at once"),
                    c.name.span,
                )
                .with_label(c.name.span, "this call waits while the other holds the task, or holds it while the other waits")
                .with_label(first, format!("`{name}` is also called here, in {place}"))
                .with_note("a task is one net shared by all its calls (seed 5.7): a second call waits until the first has ended; a condition normally ends only when what it watches happens")
                .with_help("use a task of its own for the condition (another task on the same primitive), or call this task outside the monitor"),
            );
        }
        seen.extend(here.into_iter().map(|c| (c.name.text.as_str(), c.name.span, "another condition")));
    }
}

/// E0114: a file with several missions names each of them. Anonymous ones
/// would be run as `mission1`, `mission2`, ... vehicles at once, a name
/// that changes when a mission is added above them.
pub(crate) fn check_unnamed(cx: &mut Cx<'_>) {
    let unnamed = scope::unnamed_missions(cx.db, cx.file);
    let Some(&(first, span)) = unnamed.first() else { return };
    let mut d = Diagnostic::error(codes::UNNAMED_MISSIONS, "a file with several missions must name each of them", span);
    cx.at_item(cx.file, first);
    for &(part, span) in unnamed {
        d = cx.item_label(d, cx.file, part, span, "this mission has no name");
    }
    cx.out.push(d.with_help(
        "name each mission (`mission : auv { ... }`): the named missions of one file run together, one per vehicle, \
         coordinated by the file's constraints (docs/coordination.md)",
    ));
}

fn check_call(cx: &mut Cx<'_>, c: &Call, callee: Callee<'_>) {
    let (id, task, net) = match callee {
        Callee::Task { id, task, net } => (id, task, net),
        Callee::Skip => return,
        Callee::Undefined => {
            let mut d =
                Diagnostic::error(codes::UNDEFINED_TASK, format!("cannot find task `{}`", c.name.text), c.name.span)
                    .with_label(c.name.span, "not defined in this file or its imports");
            if cx.scope.first(DefKind::Mission, &c.name.text).is_some() {
                d = d.with_help(format!(
                    "`{}` is a mission; missions cannot be called from other missions",
                    c.name.text
                ));
            } else {
                d = cx.suggest(d, &c.name.text, cx.scope.names(DefKind::Task));
                if d.help.is_none() {
                    d = d.with_help("declare it in a `tasks { ... }` block, or import the file that declares it");
                }
            }
            cx.out.push(d);
            return;
        }
    };
    // A syntax error inside the parentheses already explains what is wrong.
    let broken_args = cx
        .syntax_errors
        .iter()
        .any(|e| e.is_error() && e.span.start >= c.args_span.start && e.span.start <= c.args_span.end);
    if task.params.len() != c.args.len() && !broken_args {
        let header = task.params.iter().map(|p| p.text.as_str()).collect::<Vec<_>>().join(", ");
        let header = if header.is_empty() { String::new() } else { format!(" {header} ") };
        let n = task.params.len();
        let plural = if n == 1 { "" } else { "s" };
        let d = Diagnostic::error(
            codes::ARITY,
            format!(
                "task `{}` takes {n} argument{plural} but {} {} given",
                c.name.text,
                c.args.len(),
                if c.args.len() == 1 { "was" } else { "were" }
            ),
            c.args_span,
        )
        .with_label(c.args_span, format!("expected {n} argument{plural}"));
        let mut d = cx.def_label(d, id, task.name.span, format!("`{}({header})` is declared here", task.name.text));
        if n == 1 && c.args.len() > 1 {
            d = d.with_help(
                "a composite value (a way-point, a path) is one argument: write it as a list, e.g. `[24, 12]`",
            );
        }
        cx.out.push(d);
        return;
    }
    if let Some(net) = net {
        check_delay_arguments(cx, c, id, task, net);
    }
}

/// The arguments that give the delay of a timed transition of the task's
/// pattern (`TO(timeout)`) must be positive numbers of seconds, or symbols
/// (identifiers) whose value is given at run time (`--set timeout=60`, a
/// scenario's `[symbols]`).
fn check_delay_arguments(cx: &mut Cx<'_>, c: &Call, id: scope::DefId, task: &TaskDef, net: &PatternNet) {
    // Most patterns have no parameter delay: no allocation for them.
    fn delay_param(t: &TransitionDef) -> Option<&str> {
        match &t.delay {
            Some(Delay::Param(p)) => Some(p.text.as_str()),
            _ => None,
        }
    }
    for (k, p) in net.transitions.iter().enumerate().filter_map(|(k, t)| Some((k, delay_param(t)?))) {
        if net.transitions[..k].iter().any(|t| delay_param(t) == Some(p)) {
            continue;
        }
        let Some(i) = task.params.iter().position(|x| x.text == p) else { continue };
        let Some(arg) = c.args.get(i) else { continue };
        let problem = match &arg.kind {
            ValueKind::Number(n) if n.value() > 0.0 && n.value().is_finite() => continue,
            ValueKind::Number(n) => format!("`{}` is not a positive number of seconds", n.text),
            ValueKind::Ident(_) | ValueKind::Error => continue,
            ValueKind::Str(s) => match s.trim().parse::<f64>() {
                Ok(x) if x > 0.0 && x.is_finite() => continue,
                Ok(_) => format!("\"{s}\" is not a positive number of seconds"),
                Err(_) => format!("the string \"{s}\" is not a number of seconds"),
            },
            ValueKind::List { .. } => "a list is not a number of seconds".to_string(),
        };
        let d = Diagnostic::error(
            codes::BAD_DELAY_ARGUMENT,
            format!("the time-out `{p}` of task `{}` must be a positive number of seconds", c.name.text),
            arg.span,
        )
        .with_label(arg.span, problem);
        let d = cx.def_label(
            d,
            id,
            task.name.span,
            format!("`{p}` is the delay of a timed transition of `{}`", task.name.text),
        );
        cx.out.push(d.with_help(format!(
            "give a number of seconds above 0, e.g. `60`, or a symbol such as `{p}` whose value is given at run time (`mcl run --set {p}=60`)"
        )));
    }
}
