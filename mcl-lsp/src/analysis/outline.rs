//! Document symbols (blocks, then their definitions), workspace symbols and
//! folding ranges.

use super::hover::{mission_header, task_header};
use super::Analysis;
use mcl_compiler::scope::{for_each_def, DefKind};
use mcl_compiler::SourceFile;
use mcl_syntax::ast::*;
use mcl_syntax::lexer::CommentKind;
use mcl_syntax::visit::walk_block;
use mcl_syntax::Span;
use tower_lsp_server::ls_types::{
    DocumentSymbol, FoldingRange, FoldingRangeKind, Location, SymbolInformation, SymbolKind,
};

#[allow(deprecated, clippy::too_many_arguments)] // `DocumentSymbol::deprecated` must be written out.
fn sym(
    a: &Analysis<'_>,
    file: SourceFile,
    name: String,
    detail: Option<String>,
    kind: SymbolKind,
    span: Span,
    sel: Span,
    children: Vec<DocumentSymbol>,
) -> DocumentSymbol {
    // The selection range must lie inside the range.
    let span = span.cover(sel);
    DocumentSymbol {
        name: if name.is_empty() { "?".to_string() } else { name },
        detail,
        kind,
        tags: None,
        deprecated: None,
        range: a.range(file, span),
        selection_range: a.range(file, sel),
        children: (!children.is_empty()).then_some(children),
    }
}

fn block_sel(span: Span, keyword_len: u32) -> Span {
    Span { start: span.start, end: (span.start + keyword_len).min(span.end) }
}

pub fn document_symbols(a: &Analysis<'_>, file: SourceFile) -> Vec<DocumentSymbol> {
    let ast = a.ast(file);
    let text = a.text(file);
    let mut out = Vec::new();
    for item in &ast.items {
        match item {
            Item::Import(i) => out.push(sym(
                a,
                file,
                format!("import \"{}\"", i.path),
                None,
                SymbolKind::FILE,
                i.span,
                i.path_span,
                vec![],
            )),
            Item::Actions(b) => {
                let kids = b
                    .actions
                    .iter()
                    .map(|ad| {
                        let detail = text.get(ad.primitive.span.start as usize..ad.span.end as usize).map(|s| {
                            s.split_whitespace().collect::<Vec<_>>().join(" ").trim_end_matches(';').to_string()
                        });
                        sym(a, file, ad.name.text.clone(), detail, SymbolKind::METHOD, ad.span, ad.name.span, vec![])
                    })
                    .collect();
                out.push(sym(
                    a,
                    file,
                    "actions".into(),
                    None,
                    SymbolKind::NAMESPACE,
                    b.span,
                    block_sel(b.span, 7),
                    kids,
                ));
            }
            Item::Events(b) => {
                let kids = b
                    .events
                    .iter()
                    .map(|e| sym(a, file, e.text.clone(), None, SymbolKind::EVENT, e.span, e.span, vec![]))
                    .collect();
                out.push(sym(
                    a,
                    file,
                    "events".into(),
                    None,
                    SymbolKind::NAMESPACE,
                    b.span,
                    block_sel(b.span, 6),
                    kids,
                ));
            }
            Item::Patterns(b) => {
                let kids = b
                    .patterns
                    .iter()
                    .map(|p| {
                        let (detail, nodes) = match &p.body {
                            PatternBody::File { path, .. } => (Some(path.clone()), vec![]),
                            PatternBody::Net(n) => {
                                let mut nodes: Vec<DocumentSymbol> = n
                                    .places
                                    .iter()
                                    .map(|pl| {
                                        sym(
                                            a,
                                            file,
                                            pl.name.text.clone(),
                                            Some("place".into()),
                                            SymbolKind::FIELD,
                                            pl.span,
                                            pl.name.span,
                                            vec![],
                                        )
                                    })
                                    .collect();
                                nodes.extend(n.transitions.iter().map(|t| {
                                    sym(
                                        a,
                                        file,
                                        t.name.text.clone(),
                                        Some("transition".into()),
                                        SymbolKind::EVENT,
                                        t.span,
                                        t.name.span,
                                        vec![],
                                    )
                                }));
                                (Some(format!("{} places, {} transitions", n.places.len(), n.transitions.len())), nodes)
                            }
                        };
                        sym(a, file, p.name.text.clone(), detail, SymbolKind::CLASS, p.span, p.name.span, nodes)
                    })
                    .collect();
                out.push(sym(
                    a,
                    file,
                    "pattern".into(),
                    None,
                    SymbolKind::NAMESPACE,
                    b.span,
                    block_sel(b.span, 7),
                    kids,
                ));
            }
            Item::Tasks(b) => {
                let kids = b
                    .tasks
                    .iter()
                    .map(|t| {
                        sym(
                            a,
                            file,
                            t.name.text.clone(),
                            Some(task_header(t)),
                            SymbolKind::FUNCTION,
                            t.span,
                            t.name.span,
                            vec![],
                        )
                    })
                    .collect();
                out.push(sym(a, file, "tasks".into(), None, SymbolKind::NAMESPACE, b.span, block_sel(b.span, 5), kids));
            }
            Item::Mission(m) => {
                let mut kids = Vec::new();
                walk_block(&m.body, &mut |s| {
                    if let StmtKind::Call(c) = &s.kind {
                        if let Some(l) = &c.label {
                            let detail =
                                text.get(c.span.range()).map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "));
                            kids.push(sym(a, file, l.text.clone(), detail, SymbolKind::KEY, c.span, l.span, vec![]));
                        }
                    }
                });
                let name = match &m.name {
                    Some(n) => n.text.clone(),
                    None => "mission".to_string(),
                };
                let sel = m.name.as_ref().map_or(m.keyword_span, |n| n.span);
                out.push(sym(a, file, name, Some(mission_header(a, file, m)), SymbolKind::MODULE, m.span, sel, kids));
            }
            Item::Constraints(b) => {
                let kids = b
                    .constraints
                    .iter()
                    .map(|c| {
                        let refs = c
                            .refs
                            .iter()
                            .map(|r| match &r.mission {
                                Some(m) => format!("{}:{}", m.text, r.label.text),
                                None => r.label.text.clone(),
                            })
                            .collect::<Vec<_>>()
                            .join(", ");
                        sym(
                            a,
                            file,
                            format!("{} {{ {refs} }}", c.kind.as_str()),
                            None,
                            SymbolKind::OPERATOR,
                            c.span,
                            c.keyword_span,
                            vec![],
                        )
                    })
                    .collect();
                out.push(sym(
                    a,
                    file,
                    "constraints".into(),
                    None,
                    SymbolKind::NAMESPACE,
                    b.span,
                    block_sel(b.span, 11),
                    kids,
                ));
            }
            Item::Planning(b) => {
                let kids = b
                    .defs
                    .iter()
                    .filter_map(|d| {
                        let (word, name, kind) = match d {
                            PlanDef::Type(t) => ("type", &t.name, SymbolKind::CLASS),
                            PlanDef::Entity(x) => ("entity", &x.name, SymbolKind::OBJECT),
                            PlanDef::Function(x) => ("function", &x.name, SymbolKind::FUNCTION),
                            PlanDef::Operator(o) => ("operator", &o.name, SymbolKind::METHOD),
                            PlanDef::Facts(_) => return None,
                        };
                        Some(sym(a, file, name.text.clone(), Some(word.into()), kind, d.span(), name.span, vec![]))
                    })
                    .collect();
                out.push(sym(a, file, "planning".into(), None, SymbolKind::NAMESPACE, b.span, b.keyword_span, kids));
            }
            Item::PddlMap(b) => {
                let kids = b
                    .maps
                    .iter()
                    .map(|m| {
                        sym(a, file, m.action.text.clone(), None, SymbolKind::METHOD, m.span, m.action.span, vec![])
                    })
                    .collect();
                out.push(sym(a, file, "pddl_map".into(), None, SymbolKind::NAMESPACE, b.span, b.keyword_span, kids));
            }
        }
    }
    out
}

/// True when the letters of `query` appear in `name` in order (case-insensitive).
pub fn fuzzy_match(query: &str, name: &str) -> bool {
    let mut it = name.chars().flat_map(char::to_lowercase);
    query.chars().flat_map(char::to_lowercase).all(|q| it.any(|c| c == q))
}

#[allow(deprecated)] // `SymbolInformation::deprecated` must be written out.
pub fn workspace_symbols(a: &Analysis<'_>, query: &str) -> Vec<SymbolInformation> {
    let mut out = Vec::new();
    for file in a.universe() {
        let mut found = Vec::new();
        for_each_def(a.db, file, |id, name| found.push((id, name.to_string())));
        for (id, name) in found {
            if !fuzzy_match(query, &name) {
                continue;
            }
            let Some(location) = a.location(file, id.name_span) else { continue };
            let kind = match id.kind {
                DefKind::Action => SymbolKind::METHOD,
                DefKind::Event => SymbolKind::EVENT,
                DefKind::Pattern => SymbolKind::CLASS,
                DefKind::Task => SymbolKind::FUNCTION,
                DefKind::Mission => SymbolKind::MODULE,
            };
            let container = a.path(file).file_name().map(|n| n.to_string_lossy().into_owned());
            out.push(SymbolInformation {
                name,
                kind,
                tags: None,
                deprecated: None,
                location,
                container_name: container,
            });
        }
        if out.len() > 2000 {
            break;
        }
    }
    out.sort_by(|x, y| {
        let exact = |s: &SymbolInformation| !s.name.to_lowercase().starts_with(&query.to_lowercase());
        (exact(x), x.name.len(), &x.name, x.location.uri.as_str()).cmp(&(
            exact(y),
            y.name.len(),
            &y.name,
            y.location.uri.as_str(),
        ))
    });
    out.truncate(500);
    out
}

/// Folding ranges: items, task and pattern bodies, the blocks of missions,
/// block comments and runs of line comments.
pub fn folding_ranges(a: &Analysis<'_>, file: SourceFile) -> Vec<FoldingRange> {
    let idx = a.line_index(file);
    let text = a.text(file);
    let mut out: Vec<FoldingRange> = Vec::new();
    let mut add = |span: Span, kind: Option<FoldingRangeKind>| {
        let s = idx.line_of(span.start as usize) as u32;
        // A block ends on its `}` line; keep that line visible.
        let mut e = idx.line_of(span.end.saturating_sub(1) as usize) as u32;
        if kind.is_none() && text.as_bytes().get(span.end.saturating_sub(1) as usize) == Some(&b'}') && e > s {
            e -= 1;
        }
        if e > s {
            out.push(FoldingRange {
                start_line: s,
                start_character: None,
                end_line: e,
                end_character: None,
                kind,
                collapsed_text: None,
            });
        }
    };
    let ast = a.ast(file);
    for item in &ast.items {
        match item {
            Item::Import(_) => {}
            Item::Actions(b) => add(b.span, None),
            Item::Events(b) => add(b.span, None),
            Item::Patterns(b) => {
                add(b.span, None);
                for p in &b.patterns {
                    add(p.span, None);
                }
            }
            Item::Tasks(b) => {
                add(b.span, None);
                for t in &b.tasks {
                    add(t.span, None);
                }
            }
            Item::Mission(m) => {
                add(m.span, None);
                walk_block(&m.body, &mut |s| {
                    for child in mcl_syntax::visit::child_blocks(s) {
                        add(child.span, None);
                    }
                });
            }
            Item::Constraints(b) => add(b.span, None),
            Item::Planning(b) => {
                add(b.span, None);
                for d in &b.defs {
                    add(d.span(), None);
                }
            }
            Item::PddlMap(b) => add(b.span, None),
        }
    }
    // Consecutive imports.
    let imports: Vec<Span> =
        ast.items.iter().filter_map(|i| if let Item::Import(x) = i { Some(x.span) } else { None }).collect();
    if let (Some(f), Some(l)) = (imports.first(), imports.last()) {
        add(f.cover(*l), Some(FoldingRangeKind::Imports));
    }
    // Comments: block comments, and runs of line comments on consecutive lines.
    let comments = &mcl_compiler::queries::parse(a.db, file).comments;
    let mut run: Option<(Span, usize)> = None;
    for c in comments {
        match c.kind {
            CommentKind::Block => add(c.span, Some(FoldingRangeKind::Comment)),
            CommentKind::Line => {
                let line = idx.line_of(c.span.start as usize);
                run = match run {
                    Some((sp, last)) if last + 1 == line => Some((sp.cover(c.span), line)),
                    Some((sp, _)) => {
                        add(sp, Some(FoldingRangeKind::Comment));
                        Some((c.span, line))
                    }
                    None => Some((c.span, line)),
                };
            }
        }
    }
    if let Some((sp, _)) = run {
        add(sp, Some(FoldingRangeKind::Comment));
    }
    out.sort_by_key(|r| (r.start_line, r.end_line));
    out.dedup_by(|x, y| x.start_line == y.start_line && x.end_line == y.end_line);
    out
}

pub fn location_of(a: &Analysis<'_>, file: SourceFile, span: Span) -> Option<Location> {
    a.location(file, span)
}
