//! Pattern checks: places, transitions, arcs, numbers and the common interface
//! {begin, abort, ok, fail} on interface 1 (seed 4.3.1, 5.3).

use super::Cx;
use crate::codes;
use crate::queries::resolve_relative;
use mcl_syntax::ast::*;
use mcl_syntax::{Diagnostic, Span};
use rustc_hash::FxHashMap;

/// The places of the common interface, in order.
pub const INTERFACE: [&str; 4] = ["begin", "abort", "ok", "fail"];

pub(crate) fn check(cx: &mut Cx<'_>) {
    for item in &cx.ast().items {
        let Item::Patterns(block) = item else {
            continue;
        };
        for p in &block.patterns {
            // A pattern with a syntax error is reported once, by the parser.
            if cx.has_syntax_error_in(p.span) {
                continue;
            }
            match &p.body {
                PatternBody::Net(net) => check_net(cx, p, net),
                PatternBody::File { path, path_span } => {
                    let full = resolve_relative(cx.db, cx.file, path);
                    // Anything else than a missing file (a folder, a FIFO, a
                    // file too large) is reported with its reason below.
                    if !full.exists() {
                        cx.out.push(
                            Diagnostic::error(
                                codes::PNML_NOT_FOUND,
                                format!("cannot find the PNML file `{path}` of pattern `{}`", p.name.text),
                                *path_span,
                            )
                            .with_help("the path is relative to the folder of this file"),
                        );
                        continue;
                    }
                    match crate::queries::pnml_pattern(cx.db, cx.db.file(&full)) {
                        Err(e) => cx.out.push(
                            Diagnostic::error(
                                codes::PNML_NOT_FOUND,
                                format!("cannot use the PNML file `{path}` of pattern `{}`", p.name.text),
                                *path_span,
                            )
                            .with_label(*path_span, e.clone())
                            .with_help("the file must be a PNML 2009 P/T net"),
                        ),
                        Ok(net) => {
                            // The nodes have no MCL location: point at the import.
                            let before = cx.out.len();
                            check_net(cx, p, net);
                            for d in &mut cx.out[before..] {
                                d.span = *path_span;
                                d.labels.retain(|l| l.span != mcl_syntax::Span::default());
                                d.notes.push(format!("in the net read from `{path}`"));
                            }
                        }
                    }
                }
            }
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Node {
    Place,
    Transition,
}

fn nonneg_int(cx: &mut Cx<'_>, n: &Number, what: &str) -> Option<u32> {
    match n.as_u32() {
        Some(v) => Some(v),
        None => {
            cx.out.push(
                Diagnostic::error(
                    codes::BAD_NUMBER_IN_PATTERN,
                    format!("{what} must be a whole number >= 0, found `{}`", n.text),
                    n.span,
                )
                .with_label(n.span, "not a whole number"),
            );
            None
        }
    }
}

fn check_net<'n>(cx: &mut Cx<'_>, p: &Pattern, net: &'n PatternNet) {
    // Declarations.
    let mut nodes: FxHashMap<&'n str, (Node, Span, u32)> = FxHashMap::default();
    let mut declare = |cx: &mut Cx<'_>, name: &'n Name, kind: Node, iface: u32| {
        if let Some((prev_kind, prev, _)) = nodes.get(name.text.as_str()) {
            let what = |k: Node| {
                if k == Node::Place {
                    "place"
                } else {
                    "transition"
                }
            };
            cx.out.push(
                Diagnostic::error(
                    codes::DUPLICATE_NODE,
                    format!("`{}` is declared twice in pattern `{}`", name.text, p.name.text),
                    name.span,
                )
                .with_label(*prev, format!("first declared here as a {}", what(*prev_kind)))
                .with_label(name.span, format!("declared again as a {}", what(kind)))
                .with_help("places and transitions of a pattern share one namespace"),
            );
        } else {
            nodes.insert(&name.text, (kind, name.span, iface));
        }
    };
    let mut interface_places: FxHashMap<&str, Span> = FxHashMap::default();
    for pl in &net.places {
        let iface = pl.interface.as_ref().and_then(|n| nonneg_int(cx, n, "an interface id")).unwrap_or(0);
        if let Some(t) = &pl.tokens {
            nonneg_int(cx, t, "an initial marking");
        }
        declare(cx, &pl.name, Node::Place, iface);
        if iface == 1 {
            if INTERFACE.contains(&pl.name.text.as_str()) {
                interface_places.insert(&pl.name.text, pl.name.span);
            } else {
                cx.out.push(
                    Diagnostic::error(codes::INTERFACE, format!("place `{}` is on interface 1, which holds only begin, abort, ok and fail", pl.name.text), pl.span)
                        .with_help("use interface 0 (no `.1`) for internal places, or 2..n for internal interfaces of control structures"),
                );
            }
        } else if INTERFACE.contains(&pl.name.text.as_str()) {
            cx.out.push(
                Diagnostic::error(
                    codes::INTERFACE,
                    format!("place `{}` of the common interface must be on interface 1", pl.name.text),
                    pl.span,
                )
                .with_help(format!("write `{}.1;`", pl.name.text)),
            );
            interface_places.insert(&pl.name.text, pl.name.span);
        }
    }
    let missing: Vec<&str> = INTERFACE.iter().copied().filter(|n| !interface_places.contains_key(n)).collect();
    if !missing.is_empty() {
        let list = missing.iter().map(|m| format!("`{m}.1`")).collect::<Vec<_>>().join(", ");
        cx.out.push(
            Diagnostic::error(
                codes::INTERFACE,
                format!("pattern `{}` lacks the common interface: no place {list}", p.name.text),
                p.name.span,
            )
            .with_help("every building block has the places begin.1, abort.1, ok.1 and fail.1 (seed 4.3)"),
        );
    }
    for t in &net.transitions {
        let iface = t.interface.as_ref().and_then(|n| nonneg_int(cx, n, "an interface id")).unwrap_or(0);
        if let Some(Delay::Fixed(n)) = &t.delay {
            if n.value() < 0.0 || !n.value().is_finite() {
                cx.out.push(Diagnostic::error(
                    codes::BAD_NUMBER_IN_PATTERN,
                    "a delay must be a number of seconds >= 0",
                    n.span,
                ));
            }
        }
        declare(cx, &t.name, Node::Transition, iface);
    }
    // Arcs.
    for arc in &net.arcs {
        let mut ends = Vec::new();
        for end in [&arc.source, &arc.target] {
            match nodes.get(end.name.text.as_str()) {
                None => {
                    let d = Diagnostic::error(
                        codes::UNDEFINED_NODE,
                        format!("`{}` is not a place or transition of pattern `{}`", end.name.text, p.name.text),
                        end.name.span,
                    )
                    .with_label(end.name.span, "not declared in `places` or `transitions`");
                    let d = cx.suggest(d, &end.name.text, nodes.keys().copied());
                    cx.out.push(d);
                    ends.push(None);
                }
                Some(&(kind, _, iface)) => {
                    if let Some(n) = &end.interface {
                        if n.as_u32() != Some(iface) {
                            cx.out.push(
                                Diagnostic::error(
                                    codes::INTERFACE_MISMATCH,
                                    format!("`{}` is declared on interface {iface}, not {}", end.name.text, n.text),
                                    n.span,
                                )
                                .with_help(if iface == 0 {
                                    format!("write `{}`", end.name.text)
                                } else {
                                    format!("write `{}.{iface}`", end.name.text)
                                }),
                            );
                        }
                    }
                    ends.push(Some(kind));
                }
            }
        }
        if let (Some(a), Some(b)) = (ends[0], ends[1]) {
            if a == b {
                let what = if a == Node::Place { "two places" } else { "two transitions" };
                cx.out.push(
                    Diagnostic::error(codes::BAD_ARC, format!("an arc cannot join {what}"), arc.span)
                        .with_help("arcs go from a place to a transition or from a transition to a place"),
                );
            }
        }
        if let Some(w) = &arc.weight {
            if nonneg_int(cx, w, "an arc weight") == Some(0) {
                cx.out.push(Diagnostic::error(
                    codes::BAD_NUMBER_IN_PATTERN,
                    "an arc weight must be at least 1",
                    w.span,
                ));
            }
        }
    }
}
