//! Task checks: the pattern, the bindings of actions and events to the
//! pattern's transitions, and the parameters of the header (seed 5.4, 5.7).

use super::Cx;
use crate::codes;
use crate::scope::{self, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::{Diagnostic, Span};
use rustc_hash::{FxHashMap, FxHashSet};

pub(crate) fn check(cx: &mut Cx<'_>) {
    for item in &cx.ast().items {
        let Item::Tasks(block) = item else { continue };
        for t in &block.tasks {
            check_task(cx, t);
        }
    }
}

fn check_task(cx: &mut Cx<'_>, t: &TaskDef) {
    // A task with a syntax error is reported once, by the parser.
    if cx.has_syntax_error_in(t.span) {
        return;
    }
    // Header.
    let mut params: FxHashMap<&str, Span> = FxHashMap::default();
    for p in &t.params {
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
    // Pattern.
    // Where the pattern's transitions are (its item; a PNML pattern's nodes
    // have empty spans, shown at the start of the file that declares it).
    let mut pattern_at = None;
    let net = match &t.pattern {
        None => {
            cx.out.push(
                Diagnostic::error(
                    codes::UNDEFINED_PATTERN,
                    format!("task `{}` names no pattern", t.name.text),
                    t.name.span,
                )
                .with_help(format!(
                    "write the pattern after the header: `{}( ... ): AchieveOneGoal {{ ... }}`",
                    t.name.text
                )),
            );
            None
        }
        Some(pn) => match cx.scope.first(DefKind::Pattern, &pn.text) {
            None => {
                let d =
                    Diagnostic::error(codes::UNDEFINED_PATTERN, format!("cannot find pattern `{}`", pn.text), pn.span)
                        .with_label(pn.span, "not defined in this file or its imports");
                let d = cx.suggest(d, &pn.text, cx.scope.names(DefKind::Pattern));
                cx.out.push(d);
                None
            }
            Some(id) => match (scope::pattern(cx.db, id), scope::pattern_net(cx.db, id)) {
                // A pattern with a syntax error: its parts may be missing.
                (Some(p), _) if scope::is_broken(cx.db, id, p.span) => return,
                (Some(p), Some(Ok(net))) => {
                    let in_mcl = matches!(p.body, PatternBody::Net(_));
                    pattern_at = Some(if in_mcl { id } else { scope::DefId { item: 0, ..id } });
                    Some((p, net))
                }
                _ => None,
            },
        },
    };
    let transitions: FxHashMap<&str, &TransitionDef> =
        net.map(|(_, n)| n.transitions.iter().map(|t| (t.name.text.as_str(), t)).collect()).unwrap_or_default();
    let places: FxHashSet<&str> =
        net.map(|(_, n)| n.places.iter().map(|p| p.name.text.as_str()).collect()).unwrap_or_default();

    // Timed transitions whose delay is a task parameter.
    if let Some((pat, n)) = net {
        for tr in &n.transitions {
            if let Some(Delay::Param(p)) = &tr.delay {
                if !params.contains_key(p.text.as_str()) {
                    cx.out.push(
                        Diagnostic::error(
                            codes::DELAY_PARAM_NOT_IN_HEADER,
                            format!(
                                "task `{}` has no parameter `{}`, which pattern `{}` uses as the delay of `{}`",
                                t.name.text, p.text, pat.name.text, tr.name.text
                            ),
                            t.name.span,
                        )
                        .with_label_in(None, t.name.span, "this task's header")
                        .with_help(format!("add `{}` to the parameters of `{}`", p.text, t.name.text)),
                    );
                }
            }
        }
    }

    // Bindings.
    let mut event_of_transition: FxHashMap<&str, (&str, Span)> = FxHashMap::default();
    let mut transition_of_event: FxHashMap<&str, (&str, Span)> = FxHashMap::default();
    for b in &t.bindings {
        let (kind, defkind) = match b.kind {
            BindingKind::Action => ("action", DefKind::Action),
            BindingKind::Event => ("event", DefKind::Event),
        };
        match cx.scope.first(defkind, &b.target.text) {
            None => {
                let code = if b.kind == BindingKind::Action { codes::UNDEFINED_ACTION } else { codes::UNDEFINED_EVENT };
                let d = Diagnostic::error(code, format!("cannot find {kind} `{}`", b.target.text), b.target.span)
                    .with_label(b.target.span, format!("no {kind} with this name"));
                let d = cx.suggest(d, &b.target.text, cx.scope.names(defkind));
                let d = if d.help.is_none() {
                    d.with_help(format!("declare it in an `{kind}s {{ ... }}` block"))
                } else {
                    d
                };
                cx.out.push(d);
            }
            Some(id) if b.kind == BindingKind::Action => {
                if let Some(a) = scope::action(cx.db, id) {
                    for v in &a.params {
                        if let ValueKind::Ident(pn) = &v.kind {
                            if !params.contains_key(pn.text.as_str()) {
                                let d = Diagnostic::error(
                                    codes::ACTION_PARAM_NOT_IN_HEADER,
                                    format!(
                                        "action `{}` needs parameter `{}`, which task `{}` does not declare",
                                        a.name.text, pn.text, t.name.text
                                    ),
                                    b.target.span,
                                );
                                let d = cx.def_label(d, id, pn.span, format!("`{}` used by the action here", pn.text));
                                cx.out.push(d.with_help(format!(
                                    "add `{}` to the header: `{}( {} )`",
                                    pn.text,
                                    t.name.text,
                                    header_with(t, &pn.text)
                                )));
                            }
                        }
                    }
                }
            }
            Some(_) => {}
        }
        for tr in &b.transitions {
            if net.is_some() {
                match transitions.get(tr.text.as_str()) {
                    None => {
                        let pat = t.pattern.as_ref().map(|p| p.text.as_str()).unwrap_or("?");
                        let msg = if places.contains(tr.text.as_str()) {
                            format!("`{}` is a place of pattern `{pat}`, not a transition", tr.text)
                        } else {
                            format!("pattern `{pat}` has no transition `{}`", tr.text)
                        };
                        let d = Diagnostic::error(codes::NOT_A_TRANSITION, msg, tr.span)
                            .with_label(tr.span, format!("{kind}s are bound to transitions"));
                        let d = cx.suggest(d, &tr.text, transitions.keys().copied());
                        cx.out.push(d);
                        continue;
                    }
                    Some(def) if b.kind == BindingKind::Event && def.delay.is_some() => {
                        let d = Diagnostic::error(
                            codes::TIMED_AND_EVENT,
                            format!(
                                "`{}` is a timed transition and cannot also wait for event `{}`",
                                tr.text, b.target.text
                            ),
                            tr.span,
                        );
                        let d = match pattern_at {
                            Some(pid) => cx.def_label(d, pid, def.name.span, "declared with a delay here"),
                            None => d,
                        };
                        cx.out.push(d.with_help("bind the event to another transition, or remove the delay"));
                    }
                    Some(_) => {}
                }
            }
            if b.kind == BindingKind::Event {
                if let Some(&(other_event, prev)) = event_of_transition.get(tr.text.as_str()) {
                    if other_event != b.target.text {
                        cx.out.push(
                            Diagnostic::error(
                                codes::TRANSITION_TWO_EVENTS,
                                format!(
                                    "transition `{}` is bound to two events, `{other_event}` and `{}`",
                                    tr.text, b.target.text
                                ),
                                tr.span,
                            )
                            .with_label(prev, format!("bound to `{other_event}` here"))
                            .with_help("a transition waits for at most one event"),
                        );
                    }
                } else {
                    event_of_transition.insert(&tr.text, (&b.target.text, tr.span));
                }
                match transition_of_event.get(b.target.text.as_str()) {
                    Some(&(other_tr, prev)) if other_tr != tr.text => {
                        cx.out.push(
                            Diagnostic::error(
                                codes::EVENT_BOUND_TWICE,
                                format!("event `{}` is bound to two transitions of task `{}`: `{other_tr}` and `{}`", b.target.text, t.name.text, tr.text),
                                tr.span,
                            )
                            .with_label(prev, format!("already bound to `{other_tr}` here"))
                            .with_help("an event must fire exactly one transition of a task; add a second event or merge the transitions"),
                        );
                    }
                    Some(_) => {}
                    None => {
                        transition_of_event.insert(&b.target.text, (&tr.text, tr.span));
                    }
                }
            }
        }
    }
    check_events_without_action(cx, t);
}

/// A task that waits for events but sends no action never tells the
/// vehicle to start anything: its events come only if the vehicle sends them
/// on its own, and the mock vehicle (which answers the primitives it is
/// asked to enable) never does, so a dry run waits for ever (W0213).
fn check_events_without_action(cx: &mut Cx<'_>, t: &TaskDef) {
    let event = t.bindings.iter().find(|b| b.kind == BindingKind::Event);
    if t.bindings.iter().any(|b| b.kind == BindingKind::Action) {
        return;
    }
    let Some(event) = event else { return };
    cx.out.push(
        Diagnostic::warning(
            codes::EVENTS_WITHOUT_ACTION,
            format!("task `{}` waits for events but sends no action", t.name.text),
            t.name.span,
        )
        .with_label(t.name.span, "no `a:` binding: this task never enables a primitive")
        .with_label(event.target.span, format!("`{}` only comes if the vehicle sends it unasked", event.target.text))
        .with_note("the mock vehicle answers the primitives it is asked to enable: in a dry run this task waits for ever unless a scenario scripts its events")
        .with_help(format!(
            "bind the action that enables the primitive to the transition that starts the task (`a: enableX -> T0;`), or script the event in a scenario (`[[events]]` with `at = 10.0` and `event = \"{}\"`, docs/scenarios.md)",
            event.target.text
        )),
    );
}

fn header_with(t: &TaskDef, extra: &str) -> String {
    let mut names: Vec<&str> = t.params.iter().map(|p| p.text.as_str()).collect();
    names.push(extra);
    names.join(", ")
}
