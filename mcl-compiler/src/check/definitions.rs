//! Duplicate top-level definitions (actions, events, patterns, tasks, missions).

use super::Cx;
use crate::codes;
use crate::scope::for_each_def;
use mcl_syntax::Diagnostic;

pub(crate) fn check(cx: &mut Cx<'_>) {
    let mut found = Vec::new();
    for_each_def(cx.db, cx.file, |id, name| found.push((id, name.to_string())));
    for (id, name) in found {
        // Definitions of the standard library may be overridden.
        let defs: Vec<_> = cx.scope.get(id.kind, &name).iter().filter(|d| !d.in_stdlib).copied().collect();
        let Some(first) = defs.first().copied() else { continue };
        if first == id {
            continue;
        }
        let kind = id.kind.as_str();
        let d = Diagnostic::error(codes::DUPLICATE_DEFINITION, format!("the {kind} `{name}` is defined more than once"), id.name_span)
            .with_label(id.name_span, format!("`{name}` redefined here"))
            .with_label_in(cx.other_file(first), first.name_span, format!("first definition of `{name}`"))
            .with_help(format!("rename one of the two {kind}s, or remove one"));
        cx.out.push(d);
    }
}
