//! Quick fixes for the commonest errors: "did you mean" replacements,
//! declaring a missing action or event (E0102, E0103), creating a missing
//! task (E0101), fixing a call's number of arguments (E0201), and keeping an
//! unused definition quietly (W0901); and, on a deadlock with a
//! counterexample (E0406, E0601), writing a scenario that replays it next to
//! the source (`NAME.counterexample.toml`, docs/lsp.md).

use super::diagnostics::to_lsp;
use super::Analysis;
use mcl_compiler::queries::program;
use mcl_compiler::scope::{self, DefKind};
use mcl_compiler::{check_file, codes, FileDiagnostic, SourceFile};
use mcl_syntax::ast::*;
use mcl_syntax::visit::calls;
use mcl_syntax::Span;
use std::collections::HashMap;
use tower_lsp_server::ls_types::{
    CodeAction, CodeActionKind, CreateFile, CreateFileOptions, Diagnostic, DocumentChangeOperation, DocumentChanges,
    OneOf, OptionalVersionedTextDocumentIdentifier, Position, Range, ResourceOp, TextDocumentEdit, TextEdit, Uri,
    WorkspaceEdit,
};

struct Edits<'x> {
    a: &'x Analysis<'x>,
    map: HashMap<Uri, Vec<TextEdit>>,
}

impl<'x> Edits<'x> {
    fn new(a: &'x Analysis<'x>) -> Self {
        Edits { a, map: HashMap::new() }
    }
    fn add(mut self, file: SourceFile, span: Span, text: impl Into<String>) -> Self {
        if let Some(uri) = self.a.uri(file) {
            // New lines in the document's own line ends.
            let new_text = super::with_line_ends(&text.into(), self.a.text(file)).0;
            self.map.entry(uri).or_default().push(TextEdit { range: self.a.range(file, span), new_text });
        }
        self
    }
    fn finish(self) -> Option<WorkspaceEdit> {
        (!self.map.is_empty()).then(|| WorkspaceEdit { changes: Some(self.map), ..Default::default() })
    }
}

fn action(title: String, diag: &Diagnostic, edit: Option<WorkspaceEdit>, preferred: bool) -> Option<CodeAction> {
    Some(CodeAction {
        title,
        kind: Some(CodeActionKind::QUICKFIX),
        diagnostics: Some(vec![diag.clone()]),
        edit: Some(edit?),
        is_preferred: preferred.then_some(true),
        ..Default::default()
    })
}

/// The quick fixes for the diagnostics of `file` that touch `range`.
pub fn code_actions(a: &Analysis<'_>, file: SourceFile, range: Span) -> Vec<CodeAction> {
    let mut out = Vec::new();
    for fd in check_file(a.db, file) {
        let d = &fd.diag;
        if d.span.end < range.start || d.span.start > range.end {
            continue;
        }
        let lsp = to_lsp(a, file, d);
        // "did you mean `X`?"
        if let Some(best) = d.help.as_deref().and_then(did_you_mean) {
            let edit = Edits::new(a).add(file, d.span, best).finish();
            out.extend(action(format!("Replace with `{best}`"), &lsp, edit, true));
        }
        let name = a.text(file).get(d.span.range()).unwrap_or("").to_string();
        match d.code {
            codes::UNDEFINED_ACTION => out.extend(declare_action(a, file, d.span, &name, &lsp)),
            codes::UNDEFINED_EVENT => out.extend(declare_event(a, file, d.span, &name, &lsp)),
            codes::UNDEFINED_TASK => out.extend(create_task(a, file, d.span, &name, &lsp)),
            codes::ARITY => out.extend(fix_arity(a, file, d.span, &lsp)),
            codes::UNUSED if !name.is_empty() => {
                let edit = Edits::new(a).add(file, Span::at(d.span.start as usize), "_").finish();
                out.extend(action(format!("Rename to `_{name}` to keep it quietly"), &lsp, edit, false));
            }
            _ => {}
        }
    }
    out.extend(counterexample_actions(a, file, range));
    out
}

/// "Write a dry run of this counterexample": for each E0406 or E0601 that
/// touches `range` and whose counterexample replays
/// (`mcl_coord::replay`), an edit that creates the scenario next to the
/// source: `NAME.counterexample.toml`, or `NAME.counterexample-K.toml` for
/// the K-th of several counterexamples of the file (the order of `mcl
/// check`), replaced if it exists.
fn counterexample_actions(a: &Analysis<'_>, file: SourceFile, range: Span) -> Vec<CodeAction> {
    use mcl_coord::replay::{counterexample_scenarios, has_counterexample};
    let touches =
        |d: &FileDiagnostic| d.file == file && d.diag.span.end >= range.start && d.diag.span.start <= range.end;
    let coord = mcl_coord::coordination_diagnostics(a.db, file);
    let all: Vec<&FileDiagnostic> =
        check_file(a.db, file).iter().chain(coord.iter()).filter(|d| d.file == file && has_counterexample(d)).collect();
    if !all.iter().any(|d| touches(d)) {
        return Vec::new();
    }
    let path = a.path(file);
    let stem = path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
    let mut out = Vec::new();
    for r in counterexample_scenarios(a.db, file, |d| has_counterexample(d) && touches(d)) {
        let Ok(text) = r.scenario else { continue };
        let d = &r.diagnostic.diag;
        let k =
            all.iter().map(|x| &x.diag).position(|x| x.code == d.code && x.span == d.span && x.message == d.message);
        let name = match (all.len(), k) {
            (1, _) | (_, None) => format!("{stem}.counterexample.toml"),
            (_, Some(k)) => format!("{stem}.counterexample-{}.toml", k + 1),
        };
        let Some(uri) = Uri::from_file_path(path.with_file_name(&name)) else { continue };
        let at = Position { line: 0, character: 0 };
        let edit = WorkspaceEdit {
            document_changes: Some(DocumentChanges::Operations(vec![
                DocumentChangeOperation::Op(ResourceOp::Create(CreateFile {
                    uri: uri.clone(),
                    options: Some(CreateFileOptions { overwrite: Some(true), ignore_if_exists: None }),
                    annotation_id: None,
                })),
                DocumentChangeOperation::Edit(TextDocumentEdit {
                    text_document: OptionalVersionedTextDocumentIdentifier { uri, version: None },
                    edits: vec![OneOf::Left(TextEdit { range: Range { start: at, end: at }, new_text: text })],
                }),
            ])),
            ..Default::default()
        };
        let lsp = to_lsp(a, file, d);
        out.extend(action(format!("Write a dry run of this counterexample to {name}"), &lsp, Some(edit), false));
    }
    out
}

fn did_you_mean(help: &str) -> Option<&str> {
    let rest = help.strip_prefix("did you mean `")?;
    rest.strip_suffix("`?")
}

/// Where to add a definition of `kind`: the last block of that kind in this
/// file, else in the nearest imported file that has one; `None` when no file
/// of the program has one.
fn block_for(a: &Analysis<'_>, file: SourceFile, want: fn(&Item) -> Option<Span>) -> Option<(SourceFile, Span)> {
    let here = a.ast(file).items.iter().filter_map(want).next_back();
    if let Some(s) = here {
        return Some((file, s));
    }
    let files = &program(a.db, file).files;
    for &f in files.iter().rev() {
        if a.is_std(f) || f == file {
            continue;
        }
        if let Some(s) = a.ast(f).items.iter().filter_map(want).next_back() {
            return Some((f, s));
        }
    }
    None
}

/// An edit adding `line` (without indentation) at the end of the block
/// `span` (which ends with `}`).
fn append_to_block(a: &Analysis<'_>, file: SourceFile, block: Span, line: &str) -> (Span, String) {
    let text = a.text(file);
    let close = (block.end as usize).saturating_sub(1);
    let line_start = text[..close].rfind(['\n', '\r']).map_or(0, |i| i + 1);
    if text[line_start..close].chars().all(char::is_whitespace) {
        // `}` alone on its line: insert a new line before it, indented one
        // level deeper than the `}`.
        let indent = &text[line_start..close];
        (Span::at(line_start), format!("{indent}    {line}\n"))
    } else {
        (Span::at(close), format!(" {line} "))
    }
}

/// Inserts a new block before the item that contains `at`.
fn new_block_before(a: &Analysis<'_>, file: SourceFile, at: usize, block: &str) -> (Span, String) {
    let item = a.ast(file).items.iter().find(|i| i.span().contains(at)).map_or(0, |i| i.span().start as usize);
    (Span::at(item), format!("{block}\n\n"))
}

fn declare_event(a: &Analysis<'_>, file: SourceFile, span: Span, name: &str, diag: &Diagnostic) -> Option<CodeAction> {
    let (f, edit_span, text) = match block_for(a, file, |i| if let Item::Events(b) = i { Some(b.span) } else { None }) {
        Some((f, block)) => {
            let (s, t) = append_to_block(a, f, block, &format!("{name};"));
            (f, s, t)
        }
        None => {
            let (s, t) = new_block_before(a, file, span.start as usize, &format!("events {{\n    {name};\n}}"));
            (file, s, t)
        }
    };
    action(format!("Declare event `{name}`"), diag, Edits::new(a).add(f, edit_span, text).finish(), false)
}

/// The primitive of the other actions the task around `at` binds, or one
/// made from the action's name (`enableSonar` → `SonarPrimitive`).
fn guess_primitive(a: &Analysis<'_>, file: SourceFile, at: usize, name: &str) -> String {
    let sc = scope::scope(a.db, file);
    for item in &a.ast(file).items {
        let Item::Tasks(b) = item else { continue };
        for t in b.tasks.iter().filter(|t| t.span.contains(at)) {
            for bd in t.bindings.iter().filter(|b| b.kind == BindingKind::Action && b.target.text != name) {
                if let Some(ad) = sc.first(DefKind::Action, &bd.target.text).and_then(|id| scope::action(a.db, id)) {
                    return ad.primitive.text.clone();
                }
            }
        }
    }
    let stem = ["enable", "disable", "Enable", "Disable"].iter().find_map(|p| name.strip_prefix(p)).unwrap_or(name);
    let mut c = stem.chars();
    match c.next() {
        Some(first) => format!("{}{}Primitive", first.to_ascii_uppercase(), c.as_str()),
        None => "Primitive".to_string(),
    }
}

fn declare_action(a: &Analysis<'_>, file: SourceFile, span: Span, name: &str, diag: &Diagnostic) -> Option<CodeAction> {
    let prim = guess_primitive(a, file, span.start as usize, name);
    let cmd = if name.to_ascii_lowercase().starts_with("disable") { "disable" } else { "enable" };
    let def = format!("{name} = {prim}( c: {cmd} );");
    let (f, edit_span, text) = match block_for(a, file, |i| if let Item::Actions(b) = i { Some(b.span) } else { None })
    {
        Some((f, block)) => {
            let (s, t) = append_to_block(a, f, block, &def);
            (f, s, t)
        }
        None => {
            let (s, t) = new_block_before(a, file, span.start as usize, &format!("actions {{\n    {def}\n}}"));
            (file, s, t)
        }
    };
    action(format!("Declare action `{name}`"), diag, Edits::new(a).add(f, edit_span, text).finish(), false)
}

fn is_identifier(s: &str) -> bool {
    super::navigation::valid_identifier(s).is_ok()
}

fn create_task(a: &Analysis<'_>, file: SourceFile, span: Span, name: &str, diag: &Diagnostic) -> Option<CodeAction> {
    // Only for calls (a mission named like this cannot be called).
    let call = a.ast(file).items.iter().find_map(|i| match i {
        Item::Mission(m) => calls(&m.body).into_iter().find(|c| c.name.span == span),
        _ => None,
    })?;
    if scope::scope(a.db, file).first(DefKind::Mission, name).is_some() {
        return None;
    }
    let mut params: Vec<String> = Vec::new();
    for (i, arg) in call.args.iter().enumerate() {
        let p = match &arg.kind {
            ValueKind::Ident(n) if is_identifier(&n.text) && !params.contains(&n.text) => n.text.clone(),
            _ => format!("arg{}", i + 1),
        };
        params.push(p);
    }
    let header = if params.is_empty() { String::new() } else { format!(" {} ", params.join(", ")) };
    let body = [
        format!("// a: enable{name} -> T0;"),
        format!("// a: disable{name} -> T1, T6, T7;"),
        format!("// e: event{name}Ok -> T2;"),
        format!("// e: event{name}Fail -> T3;"),
    ];
    let (f, edit_span, text) = match block_for(a, file, |i| if let Item::Tasks(b) = i { Some(b.span) } else { None }) {
        Some((f, block)) => {
            let src = a.text(f);
            let close = (block.end as usize).saturating_sub(1);
            let line_start = src[..close].rfind(['\n', '\r']).map_or(0, |i| i + 1);
            let indent =
                if src[line_start..close].chars().all(char::is_whitespace) { &src[line_start..close] } else { "" };
            let inner = format!("{indent}    ");
            let mut t = format!("{inner}{name}({header}): AchieveOneGoal {{\n");
            for l in &body {
                t.push_str(&format!("{inner}    {l}\n"));
            }
            t.push_str(&format!("{inner}}}\n"));
            if indent.is_empty() && line_start != close {
                (f, Span::at(close), format!("\n{t}"))
            } else {
                (f, Span::at(line_start), t)
            }
        }
        None => {
            let mut t = format!("tasks {{\n    {name}({header}): AchieveOneGoal {{\n");
            for l in &body {
                t.push_str(&format!("        {l}\n"));
            }
            t.push_str("    }\n}");
            let (s, t) = new_block_before(a, file, span.start as usize, &t);
            (file, s, t)
        }
    };
    action(format!("Create task `{name}`"), diag, Edits::new(a).add(f, edit_span, text).finish(), false)
}

fn fix_arity(a: &Analysis<'_>, file: SourceFile, args_span: Span, diag: &Diagnostic) -> Option<CodeAction> {
    let call = a.ast(file).items.iter().find_map(|i| match i {
        Item::Mission(m) => calls(&m.body).into_iter().find(|c| c.args_span == args_span),
        _ => None,
    })?;
    let t = scope::scope(a.db, file).first(DefKind::Task, &call.name.text).and_then(|id| scope::task(a.db, id))?;
    let want = t.params.len();
    let have = call.args.len();
    let close = (args_span.end as usize).saturating_sub(1);
    let (span, new_text, title) = if have < want {
        let missing: Vec<&str> = t.params[have..].iter().map(|p| p.text.as_str()).collect();
        let list = missing.join(", ");
        match call.args.last() {
            Some(last) => (
                Span::at(last.span.end as usize),
                format!(", {list}"),
                format!("Add the missing argument{}: {list}", plural(missing.len())),
            ),
            None => {
                // `Goto()` or `Goto(  )`: write `Goto( way-point )`.
                let open = args_span.start as usize + 1;
                (
                    Span::new(open, close),
                    format!(" {list} "),
                    format!("Add the missing argument{}: {list}", plural(missing.len())),
                )
            }
        }
    } else if have > want {
        let from = if want == 0 { args_span.start as usize + 1 } else { call.args[want - 1].span.end as usize };
        let to = call.args.last()?.span.end as usize;
        let extra = have - want;
        (Span::new(from, to), String::new(), format!("Remove {extra} extra argument{}", plural(extra)))
    } else {
        return None;
    };
    let edit = Edits::new(a).add(file, span, new_text).finish();
    action(title, diag, edit, true)
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
