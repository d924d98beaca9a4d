//! Warnings for definitions nothing uses.

use super::Cx;
use crate::codes;
use crate::queries::{parse, program};
use crate::scope::{for_each_def, missions, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::visit::{calls, walk_block};
use mcl_syntax::Diagnostic;
use rustc_hash::FxHashSet;

pub(crate) fn check(cx: &mut Cx<'_>) {
    let prog = program(cx.db, cx.file);
    let mut used: FxHashSet<(DefKind, &str)> = FxHashSet::default();
    for &f in &prog.files {
        for item in &parse(cx.db, f).file.items {
            if let Item::Tasks(b) = item {
                for t in &b.tasks {
                    if let Some(p) = &t.pattern {
                        used.insert((DefKind::Pattern, &p.text));
                    }
                    for bd in &t.bindings {
                        let k = if bd.kind == BindingKind::Action { DefKind::Action } else { DefKind::Event };
                        used.insert((k, &bd.target.text));
                    }
                }
            }
        }
    }
    let all_missions = missions(cx.db, cx.file);
    for (_, m) in &all_missions {
        for c in calls(&m.body) {
            used.insert((DefKind::Task, &c.name.text));
        }
    }
    // Tasks are only reported when the program has missions: a vehicle file
    // on its own declares tasks for other files to call.
    let has_missions = !all_missions.is_empty();
    let mut found = Vec::new();
    for_each_def(cx.db, cx.file, |id, name| found.push((id, name.to_string())));
    for (id, name) in found {
        if id.kind == DefKind::Mission || name.starts_with('_') || (id.kind == DefKind::Task && !has_missions) {
            continue;
        }
        if !used.contains(&(id.kind, name.as_str())) {
            let by = match id.kind {
                DefKind::Task => "no mission calls it",
                _ => "no task uses it",
            };
            cx.out.push(
                Diagnostic::warning(codes::UNUSED, format!("unused {} `{name}`", id.kind.as_str()), id.name_span)
                    .with_label(id.name_span, by)
                    .with_help("remove it, or prefix its name with `_` to keep it quietly"),
            );
        }
    }
    // Mission parameters.
    for item in &cx.ast().items {
        let Item::Mission(m) = item else { continue };
        let mut used_params: FxHashSet<&str> = FxHashSet::default();
        walk_block(&m.body, &mut |s| {
            if let StmtKind::Call(c) = &s.kind {
                for a in &c.args {
                    idents(a, &mut used_params);
                }
            }
        });
        for p in &m.params {
            if !used_params.contains(p.text.as_str()) && !p.text.starts_with('_') {
                cx.out.push(
                    Diagnostic::warning(codes::UNUSED_PARAMETER, format!("unused parameter `{}`", p.text), p.span)
                        .with_help("pass it to a task, or remove it"),
                );
            }
        }
    }
}

fn idents<'a>(v: &'a Value, out: &mut FxHashSet<&'a str>) {
    match &v.kind {
        ValueKind::Ident(n) => {
            out.insert(&n.text);
        }
        ValueKind::List { items, .. } => items.iter().for_each(|i| idents(i, out)),
        _ => {}
    }
}
