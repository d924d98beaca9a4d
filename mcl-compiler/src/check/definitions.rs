//! Duplicate top-level definitions (actions, events, patterns, tasks, missions).

use super::Cx;
use crate::codes;
use crate::scope::file_defs;
use mcl_syntax::Diagnostic;

pub(crate) fn check(cx: &mut Cx<'_>) {
    for (id, name) in file_defs(cx.db, cx.file) {
        let id = *id;
        // Definitions of the standard library may be overridden.
        let defs: Vec<_> = cx.scope.get(id.kind, name).iter().filter(|d| !d.in_stdlib).copied().collect();
        let Some(first) = defs.first().copied() else {
            continue;
        };
        if first == id {
            continue;
        }
        let kind = id.kind.as_str();
        let d = Diagnostic::error(
            codes::DUPLICATE_DEFINITION,
            format!("the {kind} `{name}` is defined more than once"),
            id.name_span,
        )
        .with_label(id.name_span, format!("`{name}` redefined here"));
        cx.at_def(id);
        let d = cx.def_label(d, first, first.name_span, format!("first definition of `{name}`"));
        cx.out.push(d.with_help(format!("rename one of the two {kind}s, or remove one")));
    }
}

/// Two imported files that do not import each other may define the same
/// name: the clash is reported at the import of the root that brings in the
/// second definition, unless one imported file already sees both (then that
/// file reports it).
pub(crate) fn check_imported_clashes(cx: &mut Cx<'_>) {
    use crate::queries::{imports, program};
    let closures: Vec<(&crate::queries::ResolvedImport, Vec<crate::db::SourceFile>)> = imports(cx.db, cx.file)
        .iter()
        .filter(|i| i.target.text(cx.db).is_some())
        .map(|i| (i, program(cx.db, i.target).files.clone()))
        .collect();
    let mut reported = rustc_hash::FxHashSet::default();
    let mut keys: Vec<_> = cx.scope.defs.iter().collect();
    keys.sort_by(|a, b| a.0.cmp(b.0));
    for ((kind, name), defs) in keys {
        let defs: Vec<_> = defs.iter().filter(|d| !d.in_stdlib && d.file != cx.file).collect();
        let [first, second, ..] = defs.as_slice() else {
            continue;
        };
        if first.file == second.file
            || closures.iter().any(|(_, c)| c.contains(&first.file) && c.contains(&second.file))
        {
            continue;
        }
        let Some((imp, _)) = closures.iter().find(|(_, c)| c.contains(&second.file)) else {
            continue;
        };
        if !reported.insert((*kind, name.clone())) {
            continue;
        }
        let k = kind.as_str();
        let d = Diagnostic::error(
            codes::DUPLICATE_DEFINITION,
            format!("the {k} `{name}` is defined by two imported files"),
            imp.path_span,
        )
        .with_label(imp.path_span, format!("this import brings a second `{name}`"));
        let d = cx.def_label(d, **first, first.name_span, format!("`{name}` defined here"));
        let d =
            cx.def_label(d, **second, second.name_span, format!("and again here, imported through `{}`", imp.written));
        cx.out.push(d.with_help(format!("rename one of the two {k}s, or move it to a file both import")));
    }
}
