//! Semantic checks. `check_file` is the query that `mcl check` and the
//! language server call: every diagnostic located in one file, computed in
//! the context of the program rooted at that file.

pub mod blocks;
mod constraints;
mod definitions;
mod missions;
mod patterns;
mod planning;
mod tasks;
mod unused;

use crate::codes;
use crate::db::{Db, SourceFile};
use crate::diagnostics::FileDiagnostic;
use crate::queries::{file_items, imports, item_start, parse_item, program, syntax_errors, ItemText};
use crate::scope::{local_scope, DefId, Scope};
use mcl_syntax::{Diagnostic, Severity, Shift, Span};

/// Every diagnostic located in `file`: syntax, imports, names, tasks,
/// patterns, missions, constraints and unused definitions; sorted by position.
///
/// It only assembles: the checks of each item ([`check_item`]) and of the
/// file's definitions ([`check_definitions`]) have spans relative to items
/// and are reused across edits that do not concern them.
#[salsa::tracked(returns(ref))]
pub fn check_file(db: &dyn Db, file: SourceFile) -> Vec<FileDiagnostic> {
    let mut checked = Vec::new();
    for c in file_items(db, file) {
        let local = check_item(db, ItemCheckKey::new(db, file, c.text));
        local.place(db, file, c.start, &mut checked);
    }
    check_definitions(db, file).place(db, file, 0, &mut checked);
    // What follows from an error already reported is not reported again:
    // a name with a character the lexer refused, a name that a file that
    // could not be imported may define.
    let syntax = syntax_errors(db, file);
    let lexical: Vec<Span> = syntax.iter().filter(|d| d.code == codes::UNKNOWN_CHAR).map(|d| d.span).collect();
    let lost_import = import_failed(db, file);
    checked.retain(|d| {
        let s = d.diag.span;
        // Lexical errors are in source order and do not overlap.
        let last = lexical.partition_point(|l| l.start <= s.start);
        let in_lexical = last > 0 && s.end <= lexical[last - 1].end;
        let maybe_imported = lost_import && codes::UNDEFINED_NAMES.contains(&d.diag.code);
        !(in_lexical || maybe_imported)
    });
    let mut diags: Vec<FileDiagnostic> = program(db, file).diagnostics.clone();
    diags.extend(syntax.iter().map(|d| FileDiagnostic { file, diag: d.clone() }));
    diags.extend(checked);
    diags.sort_by(|a, b| {
        (a.diag.span.start, a.diag.span.end, a.diag.code).cmp(&(b.diag.span.start, b.diag.span.end, b.diag.code))
    });
    diags.dedup();
    diags
}

/// The checks of one item of `root`, keyed by the item's text.
#[salsa::interned(debug)]
pub struct ItemCheckKey<'db> {
    pub root: SourceFile,
    pub item: ItemText<'db>,
}

/// The diagnostics of one item (patterns, tasks, missions, constraints,
/// building blocks, unused mission parameters), with spans relative to the
/// item's start; they depend on the item's text and on the definitions of
/// the program ([`local_scope`]), not on where the item is.
#[salsa::tracked(returns(ref))]
pub fn check_item<'db>(db: &'db dyn Db, key: ItemCheckKey<'db>) -> LocalDiagnostics {
    let root = *key.root(db);
    let parsed = parse_item(db, *key.item(db));
    let mut cx = Cx::new(db, root, &parsed.file, &parsed.errors);
    patterns::check(&mut cx);
    tasks::check(&mut cx);
    missions::check(&mut cx);
    // Constraints read every mission: only their own item pays for it.
    if matches!(parsed.file.items.first(), Some(mcl_syntax::ast::Item::Constraints(_))) {
        constraints::check(&mut cx);
    }
    if matches!(parsed.file.items.first(), Some(mcl_syntax::ast::Item::Planning(_) | mcl_syntax::ast::Item::PddlMap(_)))
    {
        planning::check(&mut cx);
    }
    unused::check_params(&mut cx);
    blocks::check(&mut cx);
    cx.finish()
}

/// The checks of a file's definitions as a whole: duplicates, clashes
/// between imported files, unused definitions.
#[salsa::tracked(returns(ref))]
pub fn check_definitions(db: &dyn Db, root: SourceFile) -> LocalDiagnostics {
    static EMPTY: mcl_syntax::ast::SourceFile = mcl_syntax::ast::SourceFile { items: Vec::new() };
    let mut cx = Cx::new(db, root, &EMPTY, &[]);
    definitions::check(&mut cx);
    definitions::check_imported_clashes(&mut cx);
    missions::check_unnamed(&mut cx);
    unused::check_definitions(&mut cx);
    cx.finish()
}

/// Whether a file of the program rooted at `file` has an import that
/// could not be read: the names it would define are then unknown.
fn import_failed(db: &dyn Db, file: SourceFile) -> bool {
    program(db, file).files.iter().any(|&f| imports(db, f).iter().any(|i| i.target.text(db).is_none()))
}

/// True when any diagnostic is an error.
pub fn has_errors(diags: &[FileDiagnostic]) -> bool {
    diags.iter().any(|d| d.diag.severity == Severity::Error)
}

/// Where a span of a [`LocalDiagnostics`] is: relative to the start of item
/// `item` of `file` (the main span when `label` is `None`, else that label).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Anchor {
    pub diag: u32,
    pub label: Option<u32>,
    pub file: SourceFile,
    pub item: u32,
}

/// Diagnostics whose spans are relative: to the start of the item they were
/// computed for, or to the item an [`Anchor`] names.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct LocalDiagnostics {
    pub diags: Vec<Diagnostic>,
    pub anchors: Vec<Anchor>,
}

impl LocalDiagnostics {
    /// Makes the spans absolute (`own` is the start of the item they were
    /// computed for) and adds the diagnostics to `out`.
    pub fn place(&self, db: &dyn Db, root: SourceFile, own: u32, out: &mut Vec<FileDiagnostic>) {
        for (i, d) in self.diags.iter().enumerate() {
            let mut d = d.clone();
            let anchor = |label: Option<u32>| self.anchors.iter().find(|a| a.diag == i as u32 && a.label == label);
            let main = anchor(None).map_or(own, |a| item_start(db, a.file, a.item));
            d.span.shift(main);
            for (j, l) in d.labels.iter_mut().enumerate() {
                match anchor(Some(j as u32)) {
                    Some(a) => {
                        l.span.shift(item_start(db, a.file, a.item));
                        if a.file != root {
                            l.file = Some(a.file.path(db).display().to_string());
                        }
                    }
                    None if l.file.is_none() => l.span.shift(main),
                    None => {}
                }
            }
            out.push(FileDiagnostic { file: root, diag: d });
        }
    }
}

/// The context shared by the checks of one item (or of a file's definitions).
pub(crate) struct Cx<'a> {
    pub db: &'a dyn Db,
    /// The root of the program, the file being checked.
    pub file: SourceFile,
    /// The program's definitions, spans relative to their items.
    pub scope: &'a Scope,
    ast: &'a mcl_syntax::ast::SourceFile,
    /// The syntax errors of the item.
    pub syntax_errors: &'a [Diagnostic],
    pub out: Vec<Diagnostic>,
    anchors: Vec<Anchor>,
}

impl<'a> Cx<'a> {
    fn new(
        db: &'a dyn Db,
        file: SourceFile,
        ast: &'a mcl_syntax::ast::SourceFile,
        syntax_errors: &'a [Diagnostic],
    ) -> Self {
        Cx { db, file, scope: local_scope(db, file), ast, syntax_errors, out: Vec::new(), anchors: Vec::new() }
    }

    fn finish(self) -> LocalDiagnostics {
        LocalDiagnostics { diags: self.out, anchors: self.anchors }
    }

    /// Whether the item has a syntax error inside `span` (relative to the item).
    pub fn has_syntax_error_in(&self, span: Span) -> bool {
        self.syntax_errors.iter().any(|e| e.is_error() && e.span.start >= span.start && e.span.start <= span.end)
    }

    /// The item being checked, as a file of one item (spans relative to it).
    pub fn ast(&self) -> &'a mcl_syntax::ast::SourceFile {
        self.ast
    }

    /// Adds a label at `span` inside definition `id`'s item (a span of a
    /// node read through `id`). The diagnostic must be the next one pushed.
    pub fn def_label(&mut self, d: Diagnostic, id: DefId, span: Span, message: impl Into<String>) -> Diagnostic {
        self.item_label(d, id.file, id.item, span, message)
    }

    /// Adds a label at `span`, relative to the start of part `item` of
    /// `file`. The diagnostic must be the next one pushed.
    pub fn item_label(
        &mut self,
        d: Diagnostic,
        file: SourceFile,
        item: u32,
        span: Span,
        message: impl Into<String>,
    ) -> Diagnostic {
        let label = d.labels.len() as u32;
        self.anchors.push(Anchor { diag: self.out.len() as u32, label: Some(label), file, item });
        d.with_label(span, message)
    }

    #[allow(dead_code)]
    /// Adds a label at an absolute `span` of `file` (a span read from
    /// `queries::parse`). The diagnostic must be the next one pushed.
    pub fn absolute_label(
        &mut self,
        d: Diagnostic,
        file: SourceFile,
        span: Span,
        message: impl Into<String>,
    ) -> Diagnostic {
        // Part 0 (the prelude) starts at 0: its offsets are absolute.
        let label = d.labels.len() as u32;
        self.anchors.push(Anchor { diag: self.out.len() as u32, label: Some(label), file, item: 0 });
        d.with_label(span, message)
    }

    /// Puts the main span (and the labels without an anchor) of the next
    /// diagnostic pushed inside definition `id`'s item.
    pub fn at_def(&mut self, id: DefId) {
        self.at_item(id.file, id.item);
    }

    /// Puts the main span (and the labels without an anchor) of the next
    /// diagnostic pushed inside part `item` of `file`.
    pub fn at_item(&mut self, file: SourceFile, item: u32) {
        self.anchors.push(Anchor { diag: self.out.len() as u32, label: None, file, item });
    }

    /// Adds "did you mean" help for `name` among `candidates`.
    pub fn suggest<'n>(&self, d: Diagnostic, name: &str, candidates: impl Iterator<Item = &'n str>) -> Diagnostic {
        match closest(name, candidates) {
            Some(best) => d.with_help(format!("did you mean `{best}`?")),
            None => d,
        }
    }
}

/// The candidate closest to `name`, if it is close enough to be a typo.
pub use mcl_net::suggest::closest;
