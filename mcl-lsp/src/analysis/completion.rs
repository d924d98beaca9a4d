//! Completion and signature help. The context comes from the tokens before
//! the cursor (so that it works in half-typed, unparsable text) and the
//! candidates from the program's scope.

use super::hover::{structure_text, task_header, task_text};
use super::index::missions_with_items;
use super::Analysis;
use mcl_compiler::compile::structures::Structure;
use mcl_compiler::scope::{self, DefKind};
use mcl_compiler::SourceFile;
use mcl_syntax::ast::{Item, MonitorKind, PatternBody};
use mcl_syntax::lexer::{lex, Kw, Token};
use mcl_syntax::Span;
use tower_lsp_server::ls_types::{
    CompletionItem, CompletionItemKind, CompletionTextEdit, Documentation, InsertTextFormat, MarkupContent, MarkupKind,
    ParameterInformation, ParameterLabel, SignatureHelp, SignatureInformation, TextEdit,
};

/// Where the cursor is, as far as completion cares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Context {
    TopLevel,
    /// A statement of a mission: tasks and control structures.
    Statement,
    /// The arguments of a call in a mission (its parameters, if any).
    Argument {
        mission_item: Option<usize>,
    },
    /// After `):` in a task header.
    PatternName,
    /// The start of a binding inside a task body.
    BindingStart,
    /// After `a:` / `e:` in a task body.
    Action,
    Event,
    /// After `->` or `,` in a binding: transitions of this pattern.
    Transition {
        pattern: Option<String>,
    },
    /// After `mission:` in a constraint.
    Label {
        mission: String,
    },
    /// A reference in a constraint: `mission:` names and bare labels.
    ConstraintRef,
    /// The start of a constraint.
    ConstraintStart,
    /// After `=` in an action definition.
    Primitive,
    /// After `c:` in an action definition.
    Command,
    /// Inside a pattern's arcs.
    Node {
        pattern: Option<String>,
        /// After `X ->`: the arc's source (then a transition follows a
        /// place, a place a transition).
        from: Option<String>,
    },
    None,
}

struct Scan<'s> {
    toks: Vec<(Token<'s>, Span)>,
    /// Where the word being typed starts (the cursor when none).
    prefix_start: usize,
}

fn scan(text: &str, offset: usize) -> Scan<'_> {
    let lexed = lex(text);
    let mut toks: Vec<(Token<'_>, Span)> = Vec::new();
    let mut prefix_start = offset;
    for (t, s) in lexed.tokens {
        if (s.start as usize) >= offset {
            break;
        }
        if (s.end as usize) >= offset {
            // The cursor is inside or at the end of this token.
            if matches!(t, Token::Ident(_) | Token::Kw(_)) {
                prefix_start = s.start as usize;
                break;
            }
            if matches!(t, Token::Str(_) | Token::Num(_)) && (s.end as usize) > offset {
                prefix_start = usize::MAX;
                break;
            }
        }
        toks.push((t, s));
    }
    // Inside a comment: nothing to complete.
    if lexed.comments.iter().any(|c| (c.span.start as usize) < offset && offset <= c.span.end as usize) {
        prefix_start = usize::MAX;
    }
    Scan { toks, prefix_start }
}

/// The depth-0 item keyword and the index of its token, and the brace depth
/// at the end of `toks`.
fn item_and_depth(toks: &[(Token<'_>, Span)]) -> (Option<(Kw, usize)>, usize) {
    let mut depth = 0usize;
    let mut item = None;
    for (i, (t, _)) in toks.iter().enumerate() {
        match t {
            Token::LBrace => depth += 1,
            Token::RBrace => depth = depth.saturating_sub(1),
            Token::Kw(k) if depth == 0 && k.starts_item() => item = Some((*k, i)),
            Token::Semi if depth == 0 => item = None,
            _ => {}
        }
    }
    if depth == 0 {
        return (None, 0);
    }
    (item, depth)
}

/// The tokens of the current statement at the current depth (after the last
/// `{`, `}` or `;` of this depth).
fn current_statement<'t, 's>(toks: &'t [(Token<'s>, Span)]) -> &'t [(Token<'s>, Span)] {
    let mut depth = 0i32;
    for i in (0..toks.len()).rev() {
        match toks[i].0 {
            Token::RBrace | Token::RParen | Token::RBracket => depth += 1,
            Token::LParen | Token::LBracket if depth > 0 => depth -= 1,
            Token::LBrace if depth > 0 => depth -= 1,
            Token::LBrace | Token::Semi if depth == 0 => return &toks[i + 1..],
            _ => {}
        }
    }
    toks
}

/// The innermost unclosed `(` before the end of `toks`, with the number of
/// top-level commas after it.
fn open_paren(toks: &[(Token<'_>, Span)]) -> Option<(usize, u32)> {
    let mut stack: Vec<(usize, u32)> = Vec::new();
    for (i, (t, _)) in toks.iter().enumerate() {
        match t {
            Token::LParen | Token::LBracket => stack.push((i, 0)),
            Token::RParen | Token::RBracket => {
                stack.pop();
            }
            Token::LBrace | Token::RBrace | Token::Semi => stack.clear(),
            Token::Comma => {
                if let Some(top) = stack.last_mut() {
                    top.1 += 1;
                }
            }
            _ => {}
        }
    }
    let &(i, commas) = stack.last()?;
    matches!(toks[i].0, Token::LParen).then_some((i, commas))
}

fn ident<'s>(t: Option<&(Token<'s>, Span)>) -> Option<&'s str> {
    match t {
        Some((Token::Ident(s), _)) => Some(s),
        _ => None,
    }
}

/// Works out the completion context at `offset`.
pub fn context(a: &Analysis<'_>, file: SourceFile, offset: usize) -> (Context, usize) {
    let text = a.text(file);
    let offset = offset.min(text.len());
    let sc = scan(text, offset);
    if sc.prefix_start == usize::MAX {
        return (Context::None, offset);
    }
    let toks = &sc.toks;
    let (item, depth) = item_and_depth(toks);
    let last = toks.last().map(|t| t.0);
    let before_last = toks.len().checked_sub(2).and_then(|i| toks.get(i)).map(|t| t.0);
    let ctx = match item {
        None => match last {
            None | Some(Token::Semi | Token::RBrace) => Context::TopLevel,
            _ => Context::None,
        },
        Some((Kw::Mission | Kw::PlanOp, item_tok)) => {
            if let Some((p, _)) = open_paren(toks) {
                if matches!(toks.get(p.wrapping_sub(1)).map(|t| t.0), Some(Token::Ident(_))) && p > item_tok + 1 {
                    let mission_item = mission_item_at(a, file, offset);
                    return (Context::Argument { mission_item }, sc.prefix_start);
                }
            }
            if last == Some(Token::Colon) {
                Context::None // a label
            } else {
                Context::Statement
            }
        }
        Some((Kw::Tasks, _)) => {
            if depth == 1 {
                if last == Some(Token::Colon) && before_last == Some(Token::RParen) {
                    Context::PatternName
                } else {
                    Context::None
                }
            } else {
                let stmt = current_statement(toks);
                match stmt {
                    [] => Context::BindingStart,
                    [(Token::Ident("a"), _), (Token::Colon, _)] => Context::Action,
                    [(Token::Ident("e"), _), (Token::Colon, _)] => Context::Event,
                    _ if stmt.iter().any(|t| t.0 == Token::Arrow)
                        && matches!(last, Some(Token::Arrow | Token::Comma)) =>
                    {
                        Context::Transition { pattern: pattern_of_body(toks) }
                    }
                    _ => Context::None,
                }
            }
        }
        Some((Kw::Constraints, _)) => {
            if depth == 1 {
                match last {
                    Some(Token::LBrace | Token::RBrace | Token::Semi) => Context::ConstraintStart,
                    Some(Token::Num(_)) => Context::ConstraintStart,
                    _ => Context::None,
                }
            } else if last == Some(Token::Colon) {
                match ident(toks.len().checked_sub(2).and_then(|i| toks.get(i))) {
                    Some(m) => Context::Label { mission: m.to_string() },
                    None => Context::None,
                }
            } else if matches!(last, Some(Token::LBrace | Token::Comma)) {
                Context::ConstraintRef
            } else {
                Context::None
            }
        }
        Some((Kw::Actions, _)) => match (before_last, last) {
            (_, Some(Token::Eq)) => Context::Primitive,
            (Some(Token::Ident("c")), Some(Token::Colon)) => Context::Command,
            _ => Context::None,
        },
        Some((Kw::Pattern | Kw::Patterns, _)) => {
            // Inside `arcs { ... }`: the section keyword is just before the last `{`.
            let lb = toks.iter().rposition(|t| t.0 == Token::LBrace);
            let in_arcs = lb.is_some_and(|i| i > 0 && toks[i - 1].0 == Token::Kw(Kw::Arcs));
            if in_arcs && matches!(last, Some(Token::LBrace | Token::Semi | Token::Arrow)) {
                // The source of `X ->` or `X.1 ->`.
                let from = (last == Some(Token::Arrow))
                    .then(|| {
                        toks.iter()
                            .rev()
                            .skip(1)
                            .find(|t| !matches!(t.0, Token::Dot | Token::Num(_)))
                            .and_then(|t| ident(Some(t)))
                            .map(str::to_string)
                    })
                    .flatten();
                Context::Node { pattern: pattern_at(a, file, offset), from }
            } else {
                Context::None
            }
        }
        Some(_) => Context::None,
    };
    (ctx, sc.prefix_start)
}

/// The pattern named in the header of the task body the cursor is in:
/// `Name( ... ): Pattern {`.
fn pattern_of_body(toks: &[(Token<'_>, Span)]) -> Option<String> {
    let mut depth = 0i32;
    for i in (0..toks.len()).rev() {
        match toks[i].0 {
            Token::RBrace => depth += 1,
            Token::LBrace if depth > 0 => depth -= 1,
            Token::LBrace => return ident(i.checked_sub(1).and_then(|j| toks.get(j))).map(str::to_string),
            _ => {}
        }
    }
    None
}

fn pattern_at(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<String> {
    a.ast(file).items.iter().find_map(|i| match i {
        Item::Patterns(b) => b.patterns.iter().find(|p| p.span.contains(offset)).map(|p| p.name.text.clone()),
        _ => None,
    })
}

fn mission_item_at(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<usize> {
    a.ast(file).items.iter().position(|i| matches!(i, Item::Mission(m) if m.span.contains(offset)))
}

fn escape_snippet(s: &str) -> String {
    s.replace('\\', "\\\\").replace('$', "\\$").replace('}', "\\}")
}

fn markdown(s: String) -> Documentation {
    Documentation::MarkupContent(MarkupContent { kind: MarkupKind::Markdown, value: s })
}

struct Builder<'x> {
    a: &'x Analysis<'x>,
    file: SourceFile,
    range_span: Span,
    snippets: bool,
    out: Vec<CompletionItem>,
}

impl Builder<'_> {
    fn item(
        &mut self,
        label: &str,
        kind: CompletionItemKind,
        detail: Option<String>,
        insert: Option<String>,
        doc: Option<String>,
        sort: u8,
    ) {
        let (new_text, format) = match insert {
            Some(s) if self.snippets => (s, Some(InsertTextFormat::SNIPPET)),
            Some(_) | None => (label.to_string(), None),
        };
        let range = self.a.range(self.file, self.range_span);
        self.out.push(CompletionItem {
            label: label.to_string(),
            kind: Some(kind),
            detail,
            documentation: doc.map(markdown),
            sort_text: Some(format!("{sort}{label}")),
            filter_text: Some(label.to_string()),
            insert_text_format: format,
            text_edit: Some(CompletionTextEdit::Edit(TextEdit { range, new_text })),
            ..Default::default()
        });
    }

    /// A snippet item: its plain form is `plain` when the client has no snippets.
    fn snippet(&mut self, label: &str, detail: &str, snippet: &str, plain: &str, doc: Option<String>) {
        let (new_text, format) = if self.snippets {
            (snippet.to_string(), Some(InsertTextFormat::SNIPPET))
        } else {
            (plain.to_string(), None)
        };
        let range = self.a.range(self.file, self.range_span);
        self.out.push(CompletionItem {
            label: label.to_string(),
            kind: Some(CompletionItemKind::SNIPPET),
            detail: Some(detail.to_string()),
            documentation: doc.map(markdown),
            sort_text: Some(format!("2{label}")),
            filter_text: Some(label.split_whitespace().next().unwrap_or(label).to_string()),
            insert_text_format: format,
            text_edit: Some(CompletionTextEdit::Edit(TextEdit { range, new_text })),
            ..Default::default()
        });
    }
}

fn sorted_names<'s>(names: impl Iterator<Item = &'s str>) -> Vec<&'s str> {
    let mut v: Vec<&str> = names.collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Completion items at `offset`.
pub fn completion(a: &Analysis<'_>, file: SourceFile, offset: usize, snippets: bool) -> Vec<CompletionItem> {
    let (ctx, prefix_start) = context(a, file, offset);
    let range_span = Span::new(prefix_start.min(offset), offset);
    let mut b = Builder { a, file, range_span, snippets, out: Vec::new() };
    let sc = scope::scope(a.db, file);
    match ctx {
        Context::None => {}
        Context::TopLevel => {
            let items: &[(&str, &str, &str, &str)] = &[
                ("mission", "anonymous mission", "mission {\n\t$0\n}", "mission {\n}"),
                ("mission :", "named mission", "mission : ${1:name} {\n\t$0\n}", "mission : name {\n}"),
                ("mcl_plan_op", "mission operator", "mcl_plan_op ${1:Name}( ${2:param} ) {\n\t$0\n}", "mcl_plan_op Name( param ) {\n}"),
                ("tasks", "tasks block", "tasks {\n\t$0\n}", "tasks {\n}"),
                ("actions", "actions block", "actions {\n\t$0\n}", "actions {\n}"),
                ("events", "events block", "events {\n\t$0\n}", "events {\n}"),
                ("pattern", "pattern block", "pattern {\n\t${1:Name} {\n\t\tplaces { begin.1; abort.1; ok.1; fail.1; $2 }\n\t\ttransitions { $3 }\n\t\tarcs { $0 }\n\t}\n}", "pattern {\n}"),
                ("constraints", "constraints block", "constraints {\n\t$0\n}", "constraints {\n}"),
                ("import", "import a file", "import \"${1:vehicle.mcl}\";", "import \"vehicle.mcl\";"),
            ];
            for (label, detail, snip, plain) in items {
                b.snippet(label, detail, snip, plain, None);
            }
        }
        Context::Statement => {
            let mut tasks: Vec<(&str, mcl_compiler::scope::DefId)> = sc
                .defs
                .iter()
                .filter(|((k, _), _)| *k == DefKind::Task)
                .filter_map(|((_, n), _)| Some((n.as_str(), sc.first(DefKind::Task, n)?)))
                .collect();
            tasks.sort_by_key(|(n, _)| *n);
            for (name, id) in tasks {
                let Some(t) = scope::task(a.db, id) else { continue };
                let args = t
                    .params
                    .iter()
                    .enumerate()
                    .map(|(i, p)| format!("${{{}:{}}}", i + 1, escape_snippet(&p.text)))
                    .collect::<Vec<_>>()
                    .join(", ");
                let snippet = format!("{}({args})", escape_snippet(name));
                b.item(
                    name,
                    CompletionItemKind::FUNCTION,
                    Some(task_header(t)),
                    Some(snippet),
                    task_text(a, file, id),
                    1,
                );
            }
            let structures: &[(&str, &str, &str, &str, Structure)] = &[
                ("while", "while-do", "while ( ${1:Condition()} ) {\n\t$0\n}", "while (  ) {\n}", Structure::While),
                ("if", "if-then", "if ( ${1:Condition()} ) {\n\t$0\n}", "if (  ) {\n}", Structure::IfThen),
                (
                    "if else",
                    "if-then-else",
                    "if ( ${1:Condition()} ) {\n\t$2\n} else {\n\t$0\n}",
                    "if (  ) {\n} else {\n}",
                    Structure::IfThenElse,
                ),
                (
                    "try catch",
                    "try-catch",
                    "try {\n\t$1\n} catch {\n\t$0\n}",
                    "try {\n} catch {\n}",
                    Structure::TryCatch,
                ),
                (
                    "parallel and",
                    "parallel-and",
                    "parallel {\n\t$1\n} and {\n\t$0\n}",
                    "parallel {\n} and {\n}",
                    Structure::ParallelAnd(2),
                ),
                (
                    "parallel or",
                    "parallel-or",
                    "parallel {\n\t$1\n} or {\n\t$0\n}",
                    "parallel {\n} or {\n}",
                    Structure::ParallelOr(2),
                ),
                ("not", "not", "not ( $0 )", "not (  )", Structure::Not),
                (
                    "monitor condition",
                    "monitor-condition-do",
                    "monitor {\n\t$1\n} condition ( ${2:Condition()} ) do {\n\t$0\n}",
                    "monitor {\n} condition (  ) do {\n}",
                    Structure::Monitor(vec![MonitorKind::Condition]),
                ),
                (
                    "monitor while_condition",
                    "monitor-while_condition-do",
                    "monitor {\n\t$1\n} while_condition ( ${2:Condition()} ) do {\n\t$0\n}",
                    "monitor {\n} while_condition (  ) do {\n}",
                    Structure::Monitor(vec![MonitorKind::WhileCondition]),
                ),
            ];
            for (label, detail, snip, plain, s) in structures {
                b.snippet(label, detail, snip, plain, Some(structure_text(s)));
            }
        }
        Context::Argument { mission_item } => {
            if let Some(Item::Mission(m)) = mission_item.and_then(|i| a.ast(file).items.get(i)) {
                for p in &m.params {
                    b.item(&p.text, CompletionItemKind::VARIABLE, Some("mission parameter".into()), None, None, 0);
                }
            }
        }
        Context::PatternName => {
            for name in sorted_names(sc.names(DefKind::Pattern)) {
                let std = sc.first(DefKind::Pattern, name).is_some_and(|d| d.in_stdlib);
                b.item(
                    name,
                    CompletionItemKind::CLASS,
                    Some(if std { "pattern (standard library)" } else { "pattern" }.into()),
                    None,
                    None,
                    1,
                );
            }
        }
        Context::BindingStart => {
            b.snippet("a:", "bind an action", "a: ${1:action} -> ${0:T0};", "a: ", None);
            b.snippet("e:", "bind an event", "e: ${1:event} -> ${0:T2};", "e: ", None);
        }
        Context::Action => {
            for name in sorted_names(sc.names(DefKind::Action)) {
                let detail = sc.first(DefKind::Action, name).and_then(|id| scope::action(a.db, id)).map(|ad| {
                    a.text(sc.first(DefKind::Action, name).map(|d| d.file).unwrap_or(file))
                        .get(ad.primitive.span.start as usize..ad.span.end as usize)
                        .unwrap_or("")
                        .split_whitespace()
                        .collect::<Vec<_>>()
                        .join(" ")
                });
                b.item(name, CompletionItemKind::METHOD, detail, None, None, 1);
            }
        }
        Context::Event => {
            for name in sorted_names(sc.names(DefKind::Event)) {
                b.item(name, CompletionItemKind::EVENT, Some("event".into()), None, None, 1);
            }
        }
        Context::Transition { pattern } => {
            if let Some(net) = pattern
                .and_then(|p| sc.first(DefKind::Pattern, &p))
                .and_then(|id| scope::pattern_net(a.db, id))
                .and_then(Result::ok)
            {
                for t in &net.transitions {
                    let detail = match &t.delay {
                        Some(_) => "timed transition",
                        None => "transition",
                    };
                    b.item(&t.name.text, CompletionItemKind::PROPERTY, Some(detail.into()), None, None, 1);
                }
            }
        }
        Context::Label { mission } => {
            for (_, _, m) in missions_with_items(a.db, file) {
                if m.name.as_ref().is_some_and(|n| n.text == mission) {
                    for c in mcl_syntax::visit::calls(&m.body) {
                        if let Some(l) = &c.label {
                            let detail = a
                                .text(file)
                                .get(c.name.span.range())
                                .map(|_| format!("{}( ... ) : {}", c.name.text, l.text));
                            b.item(&l.text, CompletionItemKind::REFERENCE, detail, None, None, 1);
                        }
                    }
                }
            }
        }
        Context::ConstraintRef => {
            let all = missions_with_items(a.db, file);
            for (_, _, m) in &all {
                if let Some(n) = &m.name {
                    b.item(&format!("{}:", n.text), CompletionItemKind::MODULE, Some("mission".into()), None, None, 1);
                }
            }
            for (_, _, m) in &all {
                for c in mcl_syntax::visit::calls(&m.body) {
                    if let (Some(l), Some(n)) = (&c.label, &m.name) {
                        b.item(
                            &format!("{}:{}", n.text, l.text),
                            CompletionItemKind::REFERENCE,
                            Some(format!("{}( ... )", c.name.text)),
                            None,
                            None,
                            2,
                        );
                    }
                }
            }
        }
        Context::ConstraintStart => {
            b.snippet(
                "mutex",
                "at most N of these calls at once",
                "mutex { ${1:m1:l1}, ${2:m2:l2} } = ${0:1}",
                "mutex {  } = 1",
                None,
            );
            b.snippet(
                "order",
                "the second call waits for the first to end",
                "order { ${1:m1:l1}, ${0:m2:l2} }",
                "order {  }",
                None,
            );
            b.snippet("sync", "the calls start together", "sync { ${1:m1:l1}, ${0:m2:l2} }", "sync {  }", None);
        }
        Context::Primitive => {
            let mut prims: Vec<String> = Vec::new();
            for id in sc.defs.iter().filter(|((k, _), _)| *k == DefKind::Action).flat_map(|(_, v)| v) {
                if let Some(ad) = scope::action(a.db, *id) {
                    prims.push(ad.primitive.text.clone());
                }
            }
            prims.sort();
            prims.dedup();
            for p in prims {
                b.item(&p, CompletionItemKind::CLASS, Some("primitive".into()), None, None, 1);
            }
        }
        Context::Command => {
            for c in ["enable", "disable"] {
                b.item(c, CompletionItemKind::ENUM_MEMBER, Some("command".into()), None, None, 1);
            }
        }
        Context::Node { pattern, from } => {
            let pat = a.ast(file).items.iter().find_map(|i| match i {
                Item::Patterns(bk) => bk.patterns.iter().find(|p| Some(&p.name.text) == pattern.as_ref()),
                _ => None,
            });
            if let Some(mcl_syntax::ast::Pattern { body: PatternBody::Net(n), .. }) = pat {
                // An arc joins a place and a transition.
                let from_place = from.as_ref().map(|f| n.places.iter().any(|p| &p.name.text == f));
                let from_transition = from.as_ref().map(|f| n.transitions.iter().any(|t| &t.name.text == f));
                if from_place != Some(true) {
                    for p in &n.places {
                        b.item(&p.name.text, CompletionItemKind::FIELD, Some("place".into()), None, None, 1);
                    }
                }
                if from_transition != Some(true) {
                    for t in &n.transitions {
                        b.item(&t.name.text, CompletionItemKind::PROPERTY, Some("transition".into()), None, None, 1);
                    }
                }
            }
        }
    }
    b.out
}

/// Signature help inside the parentheses of a call.
pub fn signature_help(a: &Analysis<'_>, file: SourceFile, offset: usize) -> Option<SignatureHelp> {
    let text = a.text(file);
    let sc = scan(text, offset.min(text.len()));
    if sc.prefix_start == usize::MAX {
        return None;
    }
    let toks = &sc.toks;
    let (item, _) = item_and_depth(toks);
    if !matches!(item, Some((Kw::Mission | Kw::PlanOp, _))) {
        return None;
    }
    let (p, commas) = open_paren(toks)?;
    let name = ident(p.checked_sub(1).and_then(|i| toks.get(i)))?;
    let s = scope::scope(a.db, file);
    let id = s.first(DefKind::Task, name)?;
    let t = scope::task(a.db, id)?;
    let mut label = format!("{}(", t.name.text);
    let mut params = Vec::new();
    for (i, p) in t.params.iter().enumerate() {
        label.push_str(if i == 0 { " " } else { ", " });
        let start = label.encode_utf16().count() as u32;
        label.push_str(&p.text);
        let end = label.encode_utf16().count() as u32;
        params.push(ParameterInformation { label: ParameterLabel::LabelOffsets([start, end]), documentation: None });
    }
    label.push_str(if t.params.is_empty() { ")" } else { " )" });
    Some(SignatureHelp {
        signatures: vec![SignatureInformation {
            label,
            documentation: task_text(a, file, id).map(markdown),
            parameters: Some(params),
            active_parameter: Some(commas),
        }],
        active_signature: Some(0),
        active_parameter: Some(commas),
    })
}
