//! Go to definition, find references, document highlights and rename.

use super::index::{
    mission_at, occurrence_at, occurrences, pattern_def, resolve, sym_file, sym_name, task_at, written_net, Occ, Role,
    Sym,
};
use super::Analysis;
use mcl_compiler::queries::program;
use mcl_compiler::scope::DefKind;
use mcl_compiler::SourceFile;
use mcl_syntax::lexer::{lex, Token};
use mcl_syntax::Span;
use std::collections::HashMap;
use tower_lsp_server::ls_types::{
    DocumentHighlight, DocumentHighlightKind, Location, PrepareRenameResponse, TextEdit, Uri, WorkspaceEdit,
};

/// The symbol under the cursor, with the occurrence it was found at.
pub fn symbol_at(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<(Occ, Sym)> {
    let occs = occurrences(a.db, file);
    let occ = occurrence_at(occs, offset)?.clone();
    let sym = resolve(a.db, file, &occ)?;
    Some((occ, sym))
}

/// Where a symbol is defined (several places for a duplicated label).
pub fn definition_spans(a: &Analysis<'_>, sym: &Sym) -> Vec<(SourceFile, Span)> {
    match sym {
        Sym::Def(d) => vec![(d.file, d.name_span)],
        Sym::Node { pattern, place, name } => {
            let Some(net) = written_net(a.db, *pattern) else {
                return pnml_node(a, *pattern, name).into_iter().collect();
            };
            let spans: Vec<Span> = if *place {
                net.places.iter().filter(|p| &p.name.text == name).map(|p| p.name.span).collect()
            } else {
                net.transitions.iter().filter(|t| &t.name.text == name).map(|t| t.name.span).collect()
            };
            spans.into_iter().map(|s| (pattern.file, s)).collect()
        }
        Sym::Label { file, item, name } => {
            let Some(m) = mission_at(a.db, *file, *item) else { return vec![] };
            mcl_syntax::visit::calls(&m.body)
                .iter()
                .filter_map(|c| c.label.as_ref().filter(|l| &l.text == name).map(|l| (*file, l.span)))
                .collect()
        }
        Sym::Param { file, item, index, name } => {
            let params = if *index == u32::MAX {
                mission_at(a.db, *file, *item).map(|m| &m.params)
            } else {
                task_at(a.db, *file, (*item, *index)).map(|t| &t.params)
            };
            params.into_iter().flatten().filter(|p| &p.text == name).map(|p| (*file, p.span)).take(1).collect()
        }
    }
}

/// Where a node of a PNML pattern is: its `id="..."` in the PNML file, or
/// else the pattern's file name in the MCL file.
fn pnml_node(a: &Analysis<'_>, pattern: mcl_compiler::scope::DefId, name: &str) -> Option<(SourceFile, Span)> {
    let p = mcl_compiler::scope::pattern(a.db, pattern)?;
    let mcl_syntax::ast::PatternBody::File { path, path_span } = &p.body else { return None };
    let full = mcl_compiler::queries::resolve_relative(a.db, pattern.file, path);
    let xml = a.file_at(&full);
    let text = a.text(xml);
    for quote in ['"', '\''] {
        let needle = format!("id={quote}{name}{quote}");
        if let Some(i) = text.find(&needle) {
            let start = i + 4;
            return Some((xml, Span::new(start, start + name.len())));
        }
    }
    Some((pattern.file, *path_span))
}

pub fn goto_definition(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Vec<Location> {
    // The path of an import opens the imported file.
    for imp in mcl_compiler::queries::imports(a.db, file) {
        if imp.path_span.contains(offset) && imp.target.text(a.db).is_some() {
            return a.location(imp.target, Span::at(0)).into_iter().collect();
        }
    }
    let Some((_, sym)) = symbol_at(a, file, offset) else { return vec![] };
    definition_spans(a, &sym).into_iter().filter_map(|(f, s)| a.location(f, s)).collect()
}

/// Every occurrence of `sym` in the files the server can see, definitions
/// included, sorted by file and position.
pub fn all_occurrences(a: &Analysis<'_>, sym: &Sym) -> Vec<(SourceFile, Occ)> {
    let name = sym_name(a.db, sym);
    let home = sym_file(sym);
    let candidates: Vec<SourceFile> = match sym {
        Sym::Param { file, .. } => vec![*file],
        _ => {
            let mut files = a.universe();
            if !files.contains(&home) {
                files.push(home);
            }
            files
                .into_iter()
                .filter(|f| a.text(*f).contains(name.as_str()))
                .filter(|f| *f == home || program(a.db, *f).files.contains(&home))
                .collect()
        }
    };
    let mut out = Vec::new();
    for f in candidates {
        for occ in occurrences(a.db, f) {
            if occ.name != name || !may_be(sym, &occ.role) {
                continue;
            }
            if resolve(a.db, f, occ).as_ref() == Some(sym) {
                out.push((f, occ.clone()));
            }
        }
    }
    out.sort_by(|x, y| (a.path(x.0), x.1.span.start).cmp(&(a.path(y.0), y.1.span.start)));
    out.dedup_by(|x, y| x.0 == y.0 && x.1.span == y.1.span);
    out
}

/// Cheap filter: roles that can name a symbol of this kind.
fn may_be(sym: &Sym, role: &Role) -> bool {
    match sym {
        Sym::Def(d) => matches!(role, Role::Def(k) | Role::Ref(k) if *k == d.kind),
        Sym::Node { .. } => matches!(
            role,
            Role::PlaceDef { .. } | Role::TransitionDef { .. } | Role::ArcEnd { .. } | Role::BindingTransition { .. }
        ),
        Sym::Label { .. } => matches!(role, Role::LabelDef { .. } | Role::LabelRef { .. }),
        Sym::Param { .. } => {
            matches!(role, Role::TaskParam { .. } | Role::MissionParam { .. } | Role::ParamUse { .. })
        }
    }
}

fn is_definition(role: &Role) -> bool {
    matches!(
        role,
        Role::Def(_)
            | Role::PlaceDef { .. }
            | Role::TransitionDef { .. }
            | Role::LabelDef { .. }
            | Role::TaskParam { .. }
            | Role::MissionParam { .. }
    )
}

pub fn references(a: &Analysis<'_>, file: SourceFile, offset: usize, include_declaration: bool) -> Vec<Location> {
    let Some((_, sym)) = symbol_at(a, file, offset) else { return vec![] };
    all_occurrences(a, &sym)
        .into_iter()
        .filter(|(_, o)| include_declaration || !is_definition(&o.role))
        .filter_map(|(f, o)| a.location(f, o.span))
        .collect()
}

pub fn highlights(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Vec<DocumentHighlight> {
    let Some((_, sym)) = symbol_at(a, file, offset) else { return vec![] };
    all_occurrences(a, &sym)
        .into_iter()
        .filter(|(f, _)| *f == file)
        .map(|(_, o)| DocumentHighlight {
            range: a.range(file, o.span),
            kind: Some(if is_definition(&o.role) { DocumentHighlightKind::WRITE } else { DocumentHighlightKind::READ }),
        })
        .collect()
}

/// Why a rename is refused.
#[derive(Debug, PartialEq, Eq)]
pub struct RenameError(pub String);

fn renamable(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Result<(Occ, Sym), RenameError> {
    let text = a.text(file);
    let on_keyword = lex(text)
        .tokens
        .iter()
        .any(|(t, s)| matches!(t, Token::Kw(_)) && s.start as usize <= offset && offset < s.end as usize);
    if on_keyword {
        return Err(RenameError("keywords cannot be renamed".into()));
    }
    let Some((occ, sym)) = symbol_at(a, file, offset) else {
        return Err(RenameError("no symbol to rename here".into()));
    };
    if let Sym::Def(d) = &sym {
        if d.in_stdlib {
            return Err(RenameError(format!("`{}` is defined by the standard library", occ.name)));
        }
    }
    if let Sym::Node { pattern, .. } = &sym {
        if pattern.in_stdlib {
            return Err(RenameError(format!("`{}` belongs to a pattern of the standard library", occ.name)));
        }
        if written_net(a.db, *pattern).is_none() {
            return Err(RenameError(format!("`{}` is defined in a PNML file", occ.name)));
        }
    }
    if let Sym::Param { index, .. } = &sym {
        if *index != u32::MAX {
            return Err(RenameError(format!(
                "`{}` is a task parameter: the actions and patterns that use it name it too",
                occ.name
            )));
        }
    }
    Ok((occ, sym))
}

pub fn prepare_rename(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Result<PrepareRenameResponse, RenameError> {
    let (occ, _) = renamable(a, file, offset)?;
    Ok(PrepareRenameResponse::RangeWithPlaceholder { range: a.range(file, occ.span), placeholder: occ.name })
}

/// Checks that `name` is one MCL identifier (not a keyword).
pub fn valid_identifier(name: &str) -> Result<(), RenameError> {
    let lexed = lex(name);
    match lexed.tokens.as_slice() {
        [(Token::Ident(s), sp)] if *s == name && sp.start == 0 && lexed.comments.is_empty() => Ok(()),
        [(Token::Kw(k), _)] => Err(RenameError(format!("`{}` is a keyword", k.as_str()))),
        _ => Err(RenameError(format!("`{name}` is not an identifier"))),
    }
}

pub fn rename(a: &Analysis<'_>, file: SourceFile, offset: usize, new_name: &str) -> Result<WorkspaceEdit, RenameError> {
    let (_, sym) = renamable(a, file, offset)?;
    valid_identifier(new_name)?;
    if let Sym::Def(d) = &sym {
        if d.kind == DefKind::Mission && new_name.is_empty() {
            return Err(RenameError("a mission name cannot be empty".into()));
        }
    }
    let occs = all_occurrences(a, &sym);
    collision(a, &sym, &occs, new_name)?;
    let mut changes: HashMap<Uri, Vec<TextEdit>> = HashMap::new();
    for (f, occ) in occs {
        if a.is_std(f) {
            continue;
        }
        let Some(uri) = a.uri(f) else { continue };
        changes.entry(uri).or_default().push(TextEdit { range: a.range(f, occ.span), new_text: new_name.to_string() });
    }
    Ok(WorkspaceEdit { changes: Some(changes), ..Default::default() })
}

/// Refuses a new name that another symbol of the same kind already has
/// where the renamed one is visible: the rename would merge them.
fn collision(a: &Analysis<'_>, sym: &Sym, occs: &[(SourceFile, Occ)], new_name: &str) -> Result<(), RenameError> {
    if sym_name(a.db, sym) == new_name {
        return Ok(()); // nothing changes
    }
    match sym {
        Sym::Def(d) => {
            let mut files: Vec<SourceFile> = occs.iter().map(|(f, _)| *f).collect();
            files.push(d.file);
            files.sort_by_key(|f| a.path(*f).to_path_buf());
            files.dedup();
            for f in files {
                if let Some(other) = mcl_compiler::scope::scope(a.db, f).get(d.kind, new_name).first() {
                    let whose = if other.in_stdlib { " in the standard library" } else { "" };
                    return Err(RenameError(format!(
                        "there is already a {} named `{new_name}`{whose}",
                        d.kind.as_str()
                    )));
                }
            }
        }
        Sym::Label { file, item, .. } => {
            let taken = occurrences(a.db, *file)
                .iter()
                .any(|o| o.name == new_name && matches!(o.role, Role::LabelDef { mission } if mission == *item));
            if taken {
                return Err(RenameError(format!(
                    "this mission already has a call labelled `{new_name}` (constraints would name both)"
                )));
            }
        }
        Sym::Param { file, item, .. } => {
            let taken = occurrences(a.db, *file)
                .iter()
                .any(|o| o.name == new_name && matches!(o.role, Role::MissionParam { mission } if mission == *item));
            if taken {
                return Err(RenameError(format!("this mission already has a parameter `{new_name}`")));
            }
        }
        Sym::Node { pattern, .. } => {
            if let Some(net) = written_net(a.db, *pattern) {
                if net.places.iter().any(|p| p.name.text == new_name) {
                    return Err(RenameError(format!("this pattern already has a place `{new_name}`")));
                }
                if net.transitions.iter().any(|t| t.name.text == new_name) {
                    return Err(RenameError(format!("this pattern already has a transition `{new_name}`")));
                }
            }
        }
    }
    Ok(())
}

/// The pattern a symbol belongs to, for hover texts.
pub fn node_pattern(a: &Analysis<'_>, file: SourceFile, key: (u32, u32)) -> Option<mcl_compiler::scope::DefId> {
    pattern_def(a.db, file, key)
}
