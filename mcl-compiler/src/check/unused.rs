//! Warnings for definitions nothing uses.

use super::Cx;
use crate::codes;
use crate::db::{Db, SourceFile};
use crate::queries::{file_items, parse_item, program, ItemText};
use crate::scope::{file_defs, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::visit::{calls, walk_block};
use mcl_syntax::Diagnostic;
use rustc_hash::FxHashSet;

/// The names one item uses (patterns, actions and events of tasks, tasks
/// called by a mission), sorted, and whether it is a mission.
#[salsa::tracked(returns(ref))]
pub fn item_uses<'db>(db: &'db dyn Db, item: ItemText<'db>) -> (bool, Vec<(DefKind, String)>) {
    let mut used = Vec::new();
    let mut is_mission = false;
    match parse_item(db, item).file.items.first() {
        Some(Item::Tasks(b)) => {
            for t in &b.tasks {
                if let Some(p) = &t.pattern {
                    used.push((DefKind::Pattern, p.text.clone()));
                }
                for bd in &t.bindings {
                    let k = if bd.kind == BindingKind::Action { DefKind::Action } else { DefKind::Event };
                    used.push((k, bd.target.text.clone()));
                }
            }
        }
        Some(Item::Mission(m)) => {
            is_mission = true;
            // A mission calls the same tasks many times: one copy per name.
            let names: FxHashSet<&str> = calls(&m.body).into_iter().map(|c| c.name.text.as_str()).collect();
            used.extend(names.into_iter().map(|n| (DefKind::Task, n.to_string())));
        }
        _ => {}
    }
    used.sort();
    used.dedup();
    (is_mission, used)
}

/// The names a file uses, and whether it has a mission: stays equal across
/// edits that change neither (so the unused check is not run again).
#[salsa::tracked(returns(ref))]
pub fn file_uses(db: &dyn Db, file: SourceFile) -> (bool, Vec<(DefKind, String)>) {
    let mut has_missions = false;
    let mut used = FxHashSet::default();
    for c in file_items(db, file) {
        let (m, u) = item_uses(db, c.text);
        has_missions |= *m;
        used.extend(u.iter());
    }
    let mut used: Vec<(DefKind, String)> = used.into_iter().cloned().collect();
    used.sort();
    (has_missions, used)
}

/// Unused definitions of the file.
pub(crate) fn check_definitions(cx: &mut Cx<'_>) {
    let prog = program(cx.db, cx.file);
    let mut used: FxHashSet<(DefKind, &str)> = FxHashSet::default();
    let mut has_missions = false;
    for &f in &prog.files {
        let (m, u) = file_uses(cx.db, f);
        has_missions |= *m;
        used.extend(u.iter().map(|(k, n)| (*k, n.as_str())));
    }
    // Tasks are only reported when the program has missions: a vehicle file
    // on its own declares tasks for other files to call.
    for (id, name) in file_defs(cx.db, cx.file) {
        if id.kind == DefKind::Mission || name.starts_with('_') || (id.kind == DefKind::Task && !has_missions) {
            continue;
        }
        if !used.contains(&(id.kind, name.as_str())) {
            let by = match id.kind {
                DefKind::Task => "no mission calls it",
                _ => "no task uses it",
            };
            cx.at_def(*id);
            cx.out.push(
                Diagnostic::warning(codes::UNUSED, format!("unused {} `{name}`", id.kind.as_str()), id.name_span)
                    .with_label(id.name_span, by)
                    .with_help("remove it, or prefix its name with `_` to keep it quietly"),
            );
        }
    }
}

/// Unused parameters of the mission being checked.
pub(crate) fn check_params(cx: &mut Cx<'_>) {
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
