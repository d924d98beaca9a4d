//! Hover texts (Markdown): tasks with their parameters, primitives, actions,
//! events and pattern; actions, events, patterns, places, transitions,
//! labels, parameters and missions with their definition; control-structure
//! keywords with what the structure does.

use super::index::{occurrence_at, occurrences, resolve, task_at, Role, Sym};
use super::Analysis;
use mcl_compiler::compile::structures::Structure;
use mcl_compiler::queries::parse;
use mcl_compiler::scope::{self, DefId, DefKind};
use mcl_compiler::SourceFile;
use mcl_syntax::ast::*;
use mcl_syntax::lexer::CommentKind;
use mcl_syntax::Span;
use std::fmt::Write as _;
use tower_lsp_server::ls_types::{Hover, HoverContents, MarkupContent, MarkupKind};

pub fn hover(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<Hover> {
    let occs = occurrences(a.db, file);
    let Some(occ) = occurrence_at(occs, offset) else {
        return section_hover(a, file, offset);
    };
    let md = match &occ.role {
        Role::Structure(s) => structure_text(s),
        Role::ConstraintKeyword(k) => {
            let mut md = constraint_text(*k);
            if let Some(link) = constraint_link_text(a, file, occ.span) {
                md.push_str("\n\n");
                md.push_str(&link);
            }
            md
        }
        Role::Symbolic => format!("```mcl\n{}\n```\nA symbolic value, passed to the vehicle as it is.", occ.name),
        Role::Primitive => primitive_text(a, file, &occ.name),
        Role::Command => format!("```mcl\nc: {}\n```\nThe command sent to the primitive.", occ.name),
        Role::ActionParam => format!(
            "```mcl\nv: {}\n```\nA parameter of the tasks that send this action: its value comes from the call.",
            occ.name
        ),
        Role::DelayParam => format!(
            "```mcl\n({})\n```\nA delay taken from the task parameter `{}`: every task using this pattern declares it.",
            occ.name, occ.name
        ),
        _ => {
            let sym = resolve(a.db, file, occ)?;
            sym_text(a, file, &sym)?
        }
    };
    Some(Hover {
        contents: HoverContents::Markup(MarkupContent { kind: MarkupKind::Markdown, value: md }),
        range: Some(a.range(file, occ.span)),
    })
}

pub fn structure_text(s: &Structure) -> String {
    let form = match s {
        Structure::Sequence(_) => "A ; B",
        Structure::IfThen => "if ( A ) { B }",
        Structure::IfThenElse => "if ( A ) { B } else { C }",
        Structure::While => "while ( A ) { B }",
        Structure::TryCatch => "try { A } catch { B }",
        Structure::Not => "not ( A )",
        Structure::ParallelAnd(_) => "parallel { A } and { B }",
        Structure::ParallelOr(_) => "parallel { A } or { B }",
        Structure::Monitor(k) if k.first() == Some(&MonitorKind::WhileCondition) && k.len() == 1 => {
            "monitor { A } while_condition ( B ) do { C }"
        }
        Structure::Monitor(_) => "monitor { A } condition ( B ) do { C }",
    };
    format!("```mcl\n{form}\n```\n**{}** (control structure)\n\n{}", s.name(), s.describe())
}

/// The keywords that open a block of a file, and what the block holds.
fn section_hover(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<Hover> {
    use mcl_syntax::lexer::{lex, Kw, Token};
    let text = a.text(file);
    // Only the token under the cursor: lex the line around it.
    let start = text[..offset.min(text.len())].rfind(['\n', '\r']).map_or(0, |i| i + 1);
    let end = text[start..].find(['\n', '\r']).map_or(text.len(), |i| start + i);
    let lexed = lex(&text[start..end]);
    let (kw, sp) = lexed.tokens.iter().find_map(|(t, sp)| match t {
        Token::Kw(k) if start + sp.start as usize <= offset && offset <= start + sp.end as usize => Some((*k, *sp)),
        _ => None,
    })?;
    let (form, what) = match kw {
        Kw::Import => {
            ("import \"file.mcl\";", "Reads the definitions of another MCL file (a path relative to this one).")
        }
        Kw::Actions => (
            "actions { name = Primitive( c: command, v: param ); }",
            "The actions: each sends one command to one primitive of the vehicle.",
        ),
        Kw::Events => ("events { name; }", "The events the vehicle sends back (a primitive ended ok, failed, ...)."),
        Kw::Pattern | Kw::Patterns => (
            "pattern { Name { places {...} transitions {...} arcs {...} } }",
            "Petri net patterns of tasks: the net every task of the pattern instantiates.",
        ),
        Kw::Places => (
            "places { begin.1; abort.1; ok.1; fail.1; p(1); }",
            "The places of the pattern: `.N` puts a place in interface N, `(k)` gives it k tokens.",
        ),
        Kw::Transitions => (
            "transitions { T0; TO(delay); }",
            "The transitions of the pattern: `(delay)` makes one timed (seconds, or a task parameter).",
        ),
        Kw::Arcs => (
            "arcs { place -> transition; transition -> place; }",
            "The arcs of the pattern, each from a place to a transition or back.",
        ),
        Kw::Tasks => (
            "tasks { Name( params ): Pattern { a: action -> T0; e: event -> T2; } }",
            "The tasks: a pattern whose transitions send the given actions and fire on the given events.",
        ),
        Kw::Mission => ("mission : name { ... }", "A mission: the control structures and task calls one vehicle runs."),
        Kw::PlanOp => {
            ("mcl_plan_op Name( params ) { ... }", "A mission operator the planner sequences (seed chapter 7).")
        }
        Kw::Constraints => (
            "constraints { mutex {...} = N  order {...}  sync {...} }",
            "Coordination constraints between the labelled calls of several missions.",
        ),
        _ => return None,
    };
    let md = format!("```mcl\n{form}\n```\n**{}** (block)\n\n{what}", kw.as_str());
    let span = Span::new(start + sp.start as usize, start + sp.end as usize);
    Some(Hover {
        contents: HoverContents::Markup(MarkupContent { kind: MarkupKind::Markdown, value: md }),
        range: Some(a.range(file, span)),
    })
}

/// The messages and bytes of the constraint whose keyword is at `span`
/// (`mcl_coord::link_report`).
fn constraint_link_text(a: &Analysis<'_>, file: SourceFile, span: Span) -> Option<String> {
    let number = parse(a.db, file)
        .file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Constraints(b) => Some(&b.constraints),
            _ => None,
        })
        .flatten()
        .position(|c| c.keyword_span == span)?;
    mcl_coord::link_report::link_report_of(a.db, file).as_ref()?.hover_text(number + 1)
}

/// What a coordination constraint asks (docs/language.md, seed 6.1).
pub fn constraint_text(k: ConstraintKind) -> String {
    let (form, name, what) = match k {
        ConstraintKind::Mutex => (
            "mutex { m1:a, m2:b, ... } = N",
            "mutex",
            "At most N of the listed calls run at the same time; a call that would exceed N waits before it starts.",
        ),
        ConstraintKind::Order => (
            "order { m1:a, m2:b }",
            "order",
            "The call `m2:b` does not start before the call `m1:a` has ended; repeated calls are counted (the n-th start of `m2:b` waits for the n-th end of `m1:a`).",
        ),
        ConstraintKind::Sync => (
            "sync { m1:a, m2:b, ... }",
            "sync",
            "The listed calls start together: each waits until all the others are ready to start.",
        ),
    };
    format!(
        "```mcl\n{form}\n```\n**{name}** (coordination constraint)\n\n{what} The compiler enforces it with supervisor places between the vehicles' nets (see `mcl explain E0406` for deadlocks)."
    )
}

fn primitive_text(a: &Analysis<'_>, file: SourceFile, name: &str) -> String {
    let mut out = format!("```mcl\n{name}\n```\nA primitive of the vehicle. Its actions:\n");
    let sc = scope::scope(a.db, file);
    let mut actions: Vec<(String, String)> = Vec::new();
    for id in sc.defs.iter().filter(|((k, _), _)| *k == DefKind::Action).flat_map(|(_, v)| v.iter()) {
        if let Some(ad) = scope::action(a.db, *id) {
            if ad.primitive.text == name {
                actions.push((ad.name.text.clone(), slice(a, id.file, ad.span)));
            }
        }
    }
    actions.sort();
    for (_, def) in actions {
        let _ = writeln!(out, "- `{def}`");
    }
    out
}

/// A place or transition as declared (its name alone for a PNML pattern).
fn node_text(a: &Analysis<'_>, file: SourceFile, span: Span, name: &str) -> String {
    if span.is_empty() {
        name.to_string()
    } else {
        slice(a, file, span).trim_end_matches(';').to_string()
    }
}

fn slice(a: &Analysis<'_>, file: SourceFile, span: Span) -> String {
    let text = a.text(file).get(span.range()).unwrap_or("");
    // One line, spaces collapsed.
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The comment lines just above `start` (a definition's documentation).
pub fn leading_comment(a: &Analysis<'_>, file: SourceFile, start: usize) -> Option<String> {
    let text = a.text(file);
    let comments = &parse(a.db, file).comments;
    let mut lines: Vec<String> = Vec::new();
    let mut cursor = start;
    for c in comments.iter().rev().filter(|c| (c.span.end as usize) <= start) {
        let between = text.get(c.span.end as usize..cursor).unwrap_or("x");
        if !between.chars().all(char::is_whitespace) || between.matches('\n').count() > 1 {
            break;
        }
        let line_start = text[..c.span.start as usize].rfind(['\n', '\r']).map_or(0, |i| i + 1);
        if !text[line_start..c.span.start as usize].chars().all(char::is_whitespace) {
            break; // a comment after code on the line above
        }
        let raw = text.get(c.span.range()).unwrap_or("");
        let body: Vec<String> = match c.kind {
            CommentKind::Line => vec![raw.trim_start_matches('/').trim().to_string()],
            CommentKind::Block => raw
                .trim_start_matches("/*")
                .trim_end_matches("*/")
                .lines()
                .map(|l| l.trim().trim_start_matches('*').trim().to_string())
                .collect(),
        };
        for l in body.into_iter().rev() {
            lines.push(l);
        }
        cursor = c.span.start as usize;
    }
    lines.reverse();
    while lines.first().is_some_and(|l| l.is_empty() || l.chars().all(|c| c == '-' || c == '=')) {
        lines.remove(0);
    }
    if lines.is_empty() {
        None
    } else {
        Some(lines.join("\n"))
    }
}

fn where_defined(a: &Analysis<'_>, here: SourceFile, there: SourceFile) -> String {
    if there == here {
        String::new()
    } else if a.is_std(there) {
        "\n\n*Defined by the standard library.*".to_string()
    } else {
        let name = a.path(there).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        format!("\n\n*Defined in `{name}`.*")
    }
}

fn doc(a: &Analysis<'_>, file: SourceFile, start: u32) -> String {
    leading_comment(a, file, start as usize).map(|c| format!("\n\n---\n{c}")).unwrap_or_default()
}

pub fn task_header(t: &TaskDef) -> String {
    let params = t.params.iter().map(|p| p.text.as_str()).collect::<Vec<_>>().join(", ");
    let params = if params.is_empty() { String::new() } else { format!(" {params} ") };
    match &t.pattern {
        Some(p) => format!("{}({params}): {}", t.name.text, p.text),
        None => format!("{}({params})", t.name.text),
    }
}

/// The Markdown description of a task (hover and completion documentation).
pub fn task_text(a: &Analysis<'_>, root: SourceFile, id: DefId) -> Option<String> {
    let t = scope::task(a.db, id)?;
    let sc = scope::scope(a.db, root);
    let mut out = format!("```mcl\n{}\n```\n", task_header(t));
    let mut prims: Vec<String> = Vec::new();
    let mut actions = String::new();
    let mut events = String::new();
    for b in &t.bindings {
        let trs = b.transitions.iter().map(|t| format!("`{}`", t.text)).collect::<Vec<_>>().join(", ");
        match b.kind {
            BindingKind::Action => {
                let def = sc
                    .first(DefKind::Action, &b.target.text)
                    .and_then(|aid| scope::action(a.db, aid).map(|d| (aid, d)));
                match def {
                    Some((aid, d)) => {
                        if !prims.contains(&d.primitive.text) {
                            prims.push(d.primitive.text.clone());
                        }
                        let full = slice(a, aid.file, d.span);
                        let rhs =
                            full.split_once('=').map(|(_, r)| r.trim().trim_end_matches(';').trim()).unwrap_or("");
                        let _ = writeln!(actions, "- `{}` → {trs}: `{rhs}`", b.target.text);
                    }
                    None => {
                        let _ = writeln!(actions, "- `{}` → {trs} (undefined)", b.target.text);
                    }
                }
            }
            BindingKind::Event => {
                let _ = writeln!(events, "- `{}` → {trs}", b.target.text);
            }
        }
    }
    if !prims.is_empty() {
        let p = prims.iter().map(|p| format!("`{p}`")).collect::<Vec<_>>().join(", ");
        let _ = writeln!(out, "Task on primitive{} {p}.\n", if prims.len() > 1 { "s" } else { "" });
    } else {
        out.push_str("Task.\n\n");
    }
    if !t.params.is_empty() {
        let ps = t.params.iter().map(|p| format!("`{}`", p.text)).collect::<Vec<_>>().join(", ");
        let _ = writeln!(out, "**Parameters:** {ps}\n");
    }
    if !actions.is_empty() {
        let _ = write!(out, "**Actions**\n{actions}\n");
    }
    if !events.is_empty() {
        let _ = write!(out, "**Events**\n{events}\n");
    }
    if let Some(p) = &t.pattern {
        match sc.first(DefKind::Pattern, &p.text) {
            Some(pid) => {
                let _ = write!(out, "**Pattern** `{}`: {}", p.text, pattern_summary(a, pid));
                if pid.in_stdlib {
                    out.push_str(" (standard library)");
                }
                out.push('\n');
            }
            None => {
                let _ = writeln!(out, "**Pattern** `{}` (undefined)", p.text);
            }
        }
    }
    let mut out = out.trim_end().to_string();
    out.push_str(&doc(a, id.file, t.span.start));
    out.push_str(&where_defined(a, root, id.file));
    Some(out)
}

fn pattern_summary(a: &Analysis<'_>, pid: DefId) -> String {
    match scope::pattern_net(a.db, pid) {
        Some(Ok(n)) => {
            let timed: Vec<String> = n
                .transitions
                .iter()
                .filter_map(|t| match &t.delay {
                    Some(Delay::Fixed(x)) => Some(format!("`{}({})`", t.name.text, x.text)),
                    Some(Delay::Param(x)) => Some(format!("`{}({})`", t.name.text, x.text)),
                    None => None,
                })
                .collect();
            let mut s =
                format!("{} places, {} transitions, {} arcs", n.places.len(), n.transitions.len(), n.arcs.len());
            if !timed.is_empty() {
                let _ = write!(s, "; timed: {}", timed.join(", "));
            }
            s
        }
        Some(Err(e)) => format!("cannot be read ({e})"),
        None => String::new(),
    }
}

/// Tasks of the program that bind `name` as an action or event.
fn binders(a: &Analysis<'_>, root: SourceFile, kind: BindingKind, name: &str) -> Vec<String> {
    let sc = scope::scope(a.db, root);
    let mut out = Vec::new();
    let mut ids: Vec<&DefId> = sc.defs.iter().filter(|((k, _), _)| *k == DefKind::Task).flat_map(|(_, v)| v).collect();
    ids.sort_by_key(|d| (d.file.path(a.db), d.name_span.start));
    for id in ids {
        if let Some(t) = scope::task(a.db, *id) {
            for b in t.bindings.iter().filter(|b| b.kind == kind && b.target.text == name) {
                let trs = b.transitions.iter().map(|t| format!("`{}`", t.text)).collect::<Vec<_>>().join(", ");
                out.push(format!("- `{}` → {trs}", t.name.text));
            }
        }
    }
    out
}

pub fn sym_text(a: &Analysis<'_>, file: SourceFile, sym: &Sym) -> Option<String> {
    Some(match sym {
        Sym::Def(d) => match d.kind {
            DefKind::Task => task_text(a, file, *d)?,
            DefKind::Action => {
                let ad = scope::action(a.db, *d)?;
                let mut s = format!(
                    "```mcl\n{}\n```\nAction sent to primitive `{}`.",
                    slice(a, d.file, ad.span),
                    ad.primitive.text
                );
                let by = binders(a, file, BindingKind::Action, &ad.name.text);
                if !by.is_empty() {
                    let _ = write!(s, "\n\n**Sent by**\n{}", by.join("\n"));
                }
                s.push_str(&doc(a, d.file, ad.span.start));
                s.push_str(&where_defined(a, file, d.file));
                s
            }
            DefKind::Event => {
                let name = a.text(d.file).get(d.name_span.range()).unwrap_or("");
                let mut s = format!("```mcl\nevents {{ {name}; }}\n```\nEvent sent by a primitive.");
                let by = binders(a, file, BindingKind::Event, name);
                if !by.is_empty() {
                    let _ = write!(s, "\n\n**Fires**\n{}", by.join("\n"));
                }
                s.push_str(&where_defined(a, file, d.file));
                s
            }
            DefKind::Pattern => {
                let p = scope::pattern(a.db, *d)?;
                let mut s = format!("```mcl\npattern {}\n```\n", p.name.text);
                match &p.body {
                    PatternBody::File { path, .. } => {
                        let _ = write!(s, "Read from the PNML file `{path}`: ");
                    }
                    PatternBody::Net(_) => s.push_str("Task pattern: "),
                }
                s.push_str(&pattern_summary(a, *d));
                if let Some(Ok(n)) = scope::pattern_net(a.db, *d) {
                    let places = n
                        .places
                        .iter()
                        .map(|p| {
                            let mut x = p.name.text.clone();
                            if let Some(i) = &p.interface {
                                let _ = write!(x, ".{}", i.text);
                            }
                            if let Some(t) = &p.tokens {
                                let _ = write!(x, "({})", t.text);
                            }
                            format!("`{x}`")
                        })
                        .collect::<Vec<_>>()
                        .join(" ");
                    let trs = n.transitions.iter().map(|t| format!("`{}`", t.name.text)).collect::<Vec<_>>().join(" ");
                    let _ = write!(s, ".\n\n**Places** {places}\n\n**Transitions** {trs}");
                }
                s.push_str(&doc(a, d.file, p.span.start));
                s.push_str(&where_defined(a, file, d.file));
                s
            }
            DefKind::Mission => {
                let m = scope::mission(a.db, *d)?;
                mission_text(a, d.file, m) + &where_defined(a, file, d.file)
            }
        },
        Sym::Node { pattern, place, name } => {
            let net = super::index::any_net(a.db, *pattern)?;
            let pname = scope::pattern(a.db, *pattern)?.name.text.clone();
            if *place {
                let p = net.places.iter().find(|p| &p.name.text == name)?;
                let iface = p.interface.as_ref().map_or(0, |i| i.as_u32().unwrap_or(0));
                let tokens = p.tokens.as_ref().map_or("0".to_string(), |t| t.text.clone());
                let what = if iface == 1 { "interface place" } else { "place" };
                format!(
                    "```mcl\n{}\n```\n{what} of pattern `{pname}`, initial marking {tokens}.",
                    node_text(a, pattern.file, p.span, name)
                )
            } else {
                let t = net.transitions.iter().find(|t| &t.name.text == name)?;
                let kind = match &t.delay {
                    Some(Delay::Fixed(x)) => format!("timed transition ({} s)", x.text),
                    Some(Delay::Param(x)) => format!("timed transition (delay: task parameter `{}`)", x.text),
                    None => "transition".to_string(),
                };
                let ins: Vec<&str> = net
                    .arcs
                    .iter()
                    .filter(|a| &a.target.name.text == name)
                    .map(|a| a.source.name.text.as_str())
                    .collect();
                let outs: Vec<&str> = net
                    .arcs
                    .iter()
                    .filter(|a| &a.source.name.text == name)
                    .map(|a| a.target.name.text.as_str())
                    .collect();
                format!(
                    "```mcl\n{}\n```\n{kind} of pattern `{pname}`: {} → {name} → {}.",
                    node_text(a, pattern.file, t.span, name),
                    if ins.is_empty() { "∅".to_string() } else { ins.join(", ") },
                    if outs.is_empty() { "∅".to_string() } else { outs.join(", ") },
                )
            }
        }
        Sym::Label { file: mf, item, name } => {
            let m = super::index::mission_at(a.db, *mf, *item)?;
            let call = mcl_syntax::visit::calls(&m.body)
                .into_iter()
                .find(|c| c.label.as_ref().is_some_and(|l| &l.text == name))?;
            let mname = m.name.as_ref().map_or("(anonymous)".to_string(), |n| format!("`{}`", n.text));
            format!(
                "```mcl\n{}\n```\nLabel `{name}` of mission {mname}: constraints refer to this call as `{}:{name}`.",
                slice(a, *mf, call.span),
                m.name.as_ref().map_or("?", |n| n.text.as_str())
            )
        }
        Sym::Param { file: pf, item, index, name } => {
            if *index == u32::MAX {
                let m = super::index::mission_at(a.db, *pf, *item)?;
                let owner = m.name.as_ref().map_or("?".to_string(), |n| n.text.clone());
                format!("```mcl\n{name}\n```\nParameter of mission `{owner}`: its value is given by the planner.")
            } else {
                let t = task_at(a.db, *pf, (*item, *index))?;
                format!(
                    "```mcl\n{name}\n```\nParameter of task `{}`: each call gives its value.\n\n```mcl\n{}\n```",
                    t.name.text,
                    task_header(t)
                )
            }
        }
    })
}

pub fn mission_header(a: &Analysis<'_>, file: SourceFile, m: &Mission) -> String {
    let end = m.body.span.start;
    let text = a.text(file).get(m.span.start as usize..end as usize).unwrap_or("mission");
    text.split_whitespace().collect::<Vec<_>>().join(" ").trim_end_matches('{').trim_end().to_string()
}

fn mission_text(a: &Analysis<'_>, file: SourceFile, m: &Mission) -> String {
    let labels: Vec<String> = mcl_syntax::visit::calls(&m.body)
        .iter()
        .filter_map(|c| c.label.as_ref().map(|l| format!("`{}`", l.text)))
        .collect();
    let calls = mcl_syntax::visit::calls(&m.body).len();
    let kind = match (m.kind, m.params.is_empty()) {
        (MissionKind::PlanOp, _) => "Mission operator for the planner",
        (_, false) => "Parametrised mission",
        _ => "Mission",
    };
    let mut s = format!(
        "```mcl\n{} {{ ... }}\n```\n{kind}: {calls} call{}.",
        mission_header(a, file, m),
        if calls == 1 { "" } else { "s" }
    );
    if !labels.is_empty() {
        let _ = write!(s, "\n\n**Labels** {}", labels.join(" "));
    }
    s + &doc(a, file, m.span.start)
}
