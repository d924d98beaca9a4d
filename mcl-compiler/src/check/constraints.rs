//! Constraint checks (seed 6.4): every `mission:label` names a labelled call
//! of a mission of the program (E0401-E0403; naming an unlabelled call by
//! its task points at the call), arities and bounds (E0404, E0405). Whether
//! the constraints deadlock is `mcl_coord::check` (E0406, W0407).

use super::Cx;
use crate::codes;
use crate::scope::{missions, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::visit::calls;
use mcl_syntax::{Diagnostic, Span};

pub(crate) fn check(cx: &mut Cx<'_>) {
    let all = missions(cx.db, cx.file);
    for item in &cx.ast().items {
        let Item::Constraints(block) = item else {
            continue;
        };
        for c in &block.constraints {
            check_constraint(cx, &all, c);
        }
    }
}

fn check_constraint(cx: &mut Cx<'_>, all: &[(crate::db::SourceFile, &Mission)], c: &Constraint) {
    let kind = c.kind.as_str();
    let n = c.refs.len();
    let arity_ok = match c.kind {
        ConstraintKind::Order => n == 2,
        ConstraintKind::Mutex | ConstraintKind::Sync => n >= 2,
    };
    if !arity_ok {
        let want = if c.kind == ConstraintKind::Order {
            "exactly two calls: the one that must end first, then the one that waits"
        } else {
            "at least two calls"
        };
        cx.out.push(Diagnostic::error(
            codes::CONSTRAINT_ARITY,
            format!("`{kind}` names {n} call{} but needs {want}", if n == 1 { "" } else { "s" }),
            c.span,
        ));
    }
    match (c.kind, &c.bound) {
        (ConstraintKind::Mutex, None) => cx.out.push(
            Diagnostic::error(
                codes::CONSTRAINT_BOUND,
                "a `mutex` needs a bound: how many of its calls may run at once",
                c.span,
            )
            .with_help("add `= 1` after the braces for a mutual exclusion"),
        ),
        (ConstraintKind::Mutex, Some(b)) if b.as_u32().is_none_or(|v| v == 0) => cx.out.push(Diagnostic::error(
            codes::CONSTRAINT_BOUND,
            format!("the bound of a `mutex` must be a whole number >= 1, found `{}`", b.text),
            b.span,
        )),
        (ConstraintKind::Order | ConstraintKind::Sync, Some(b)) => cx.out.push(
            Diagnostic::error(codes::CONSTRAINT_BOUND, format!("`{kind}` takes no bound"), b.span)
                .with_help("only `mutex { ... } = N` has a bound"),
        ),
        _ => {}
    }
    for r in &c.refs {
        match &r.mission {
            Some(mname) => {
                let Some((mfile, m)) = all.iter().find(|(_, m)| m.name.as_ref().is_some_and(|n| n.text == mname.text))
                else {
                    let names = all.iter().filter_map(|(_, m)| m.name.as_ref().map(|n| n.text.as_str()));
                    let d = Diagnostic::error(
                        codes::UNKNOWN_MISSION,
                        format!("there is no mission named `{}`", mname.text),
                        mname.span,
                    )
                    .with_label(mname.span, "unknown mission");
                    let d = cx.suggest(d, &mname.text, names);
                    let d =
                        if d.help.is_none() { d.with_help("name a mission with `mission : name { ... }`") } else { d };
                    cx.out.push(d);
                    continue;
                };
                if is_operator(m) {
                    // Seed 6.4 coordinates the missions vehicles run; an
                    // operator (or a mission with parameters) only runs as
                    // a step of a plan, instantiated by the planner.
                    let what = if m.kind == MissionKind::PlanOp {
                        "a planning operator (`mcl_plan_op`)"
                    } else {
                        "a parametrised mission, a planning operator"
                    };
                    let d = Diagnostic::error(
                        codes::CONSTRAINT_ON_OPERATOR,
                        format!("`{}` is {what}, not a vehicle's mission", mname.text),
                        mname.span,
                    )
                    .with_label(mname.span, "constraints name the missions vehicles run");
                    let d = match cx.scope.get(DefKind::Mission, &mname.text).iter().find(|id| id.file == *mfile) {
                        Some(&id) => cx.def_label(d, id, m.keyword_span.cover(mname_def_span(m)), "defined here"),
                        None => d,
                    };
                    let d = d.with_help(
                        "constrain calls of a named mission (`mission : name { ... }`); an operator's calls run only as steps of a plan",
                    );
                    cx.out.push(d);
                    continue;
                }
                let labels: Vec<&str> =
                    calls(&m.body).into_iter().filter_map(|c| c.label.as_ref().map(|l| l.text.as_str())).collect();
                if !labels.contains(&r.label.text.as_str()) {
                    let d = Diagnostic::error(
                        codes::UNKNOWN_LABEL,
                        format!("mission `{}` has no call labelled `{}`", mname.text, r.label.text),
                        r.label.span,
                    )
                    .with_label(r.label.span, "unknown label");
                    let d = match unlabelled_call(cx, *mfile, m, &r.label.text) {
                        Some((task, span)) => {
                            let label = r.label.text.to_ascii_lowercase();
                            cx.absolute_label(d, *mfile, span, format!("this `{task}` call has no label")).with_help(
                                format!(
                                "label the call to constrain it: `{task}( ... ) : {label}`, then name `{label}` here"
                            ),
                            )
                        }
                        None => {
                            let d = cx.suggest(d, &r.label.text, labels.iter().copied());
                            if d.help.is_none() {
                                d.with_help(format!("label a call with `Task( ... ) : {}`", r.label.text))
                            } else {
                                d
                            }
                        }
                    };
                    cx.out.push(d);
                }
            }
            None => {
                let owners: Vec<&Mission> = all
                    .iter()
                    .filter(|(_, m)| {
                        calls(&m.body).iter().any(|c| c.label.as_ref().is_some_and(|l| l.text == r.label.text))
                    })
                    .map(|(_, m)| *m)
                    .collect();
                match owners.len() {
                    0 => cx.out.push(
                        Diagnostic::error(
                            codes::UNKNOWN_LABEL,
                            format!("no mission has a call labelled `{}`", r.label.text),
                            r.label.span,
                        )
                        .with_help(format!("label a call with `Task( ... ) : {}`", r.label.text)),
                    ),
                    1 if is_operator(owners[0]) => {
                        let m = owners[0];
                        let what = m.name.as_ref().map_or("an operator".to_string(), |n| format!("`{}`", n.text));
                        cx.out.push(
                            Diagnostic::error(
                                codes::CONSTRAINT_ON_OPERATOR,
                                format!("the call labelled `{}` is in {what}, a planning operator, not a vehicle's mission", r.label.text),
                                r.label.span,
                            )
                            .with_help("constrain calls of a named mission (`mission : name { ... }`); an operator's calls run only as steps of a plan"),
                        );
                    }
                    1 => {}
                    _ => {
                        let names: Vec<String> = owners
                            .iter()
                            .filter_map(|m| m.name.as_ref().map(|n| format!("`{}:{}`", n.text, r.label.text)))
                            .collect();
                        cx.out.push(
                            Diagnostic::error(
                                codes::AMBIGUOUS_LABEL,
                                format!("label `{}` is used by {} missions", r.label.text, owners.len()),
                                r.label.span,
                            )
                            .with_help(format!("say which one: {}", names.join(" or "))),
                        );
                    }
                }
            }
        }
    }
}

/// A constraint that names a call by its task instead of a label
/// (`auv:Surface` for an unlabelled `Surface()` call): the task's name and
/// the absolute span of the first unlabelled call of that task in the
/// mission.
fn unlabelled_call(cx: &Cx<'_>, mfile: crate::db::SourceFile, m: &Mission, name: &str) -> Option<(String, Span)> {
    // The mission as parsed with its whole file (absolute spans).
    let name_of = |x: &Mission| x.name.as_ref().map(|n| n.text.clone());
    let parsed = crate::queries::parse(cx.db, mfile);
    let m = parsed.file.items.iter().find_map(|i| match i {
        Item::Mission(x) if name_of(x) == name_of(m) => Some(x),
        _ => None,
    })?;
    let call = calls(&m.body).into_iter().find(|c| c.label.is_none() && c.name.text.eq_ignore_ascii_case(name))?;
    Some((call.name.text.clone(), call.span))
}

/// The span of a mission's name where it is defined (relative to the mission).
fn mname_def_span(m: &Mission) -> Span {
    m.name.as_ref().map_or(m.keyword_span, |n| n.span)
}

/// An operator of the planner: `mcl_plan_op`, or a mission with parameters.
fn is_operator(m: &Mission) -> bool {
    m.kind == MissionKind::PlanOp || !m.params.is_empty()
}
