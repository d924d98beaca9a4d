//! Semantic checks. `check_file` is the query that `mcl check` and the
//! language server call: every diagnostic located in one file, computed in
//! the context of the program rooted at that file.

pub mod blocks;
mod constraints;
mod definitions;
mod missions;
mod patterns;
mod tasks;
mod unused;

use crate::db::{Db, SourceFile};
use crate::diagnostics::FileDiagnostic;
use crate::queries::{parse, program};
use crate::scope::{scope, DefId, Scope};
use mcl_syntax::{Diagnostic, Severity};

/// Every diagnostic located in `file`: syntax, imports, names, tasks,
/// patterns, missions, constraints and unused definitions; sorted by position.
#[salsa::tracked(returns(ref))]
pub fn check_file(db: &dyn Db, file: SourceFile) -> Vec<FileDiagnostic> {
    let mut cx = Cx { db, file, scope: scope(db, file), out: Vec::new() };
    cx.out.extend(parse(db, file).errors.iter().cloned());
    let mut diags: Vec<FileDiagnostic> = program(db, file).diagnostics.clone();
    definitions::check(&mut cx);
    definitions::check_imported_clashes(&mut cx);
    patterns::check(&mut cx);
    tasks::check(&mut cx);
    missions::check(&mut cx);
    constraints::check(&mut cx);
    unused::check(&mut cx);
    blocks::check(&mut cx);
    diags.extend(cx.out.into_iter().map(|diag| FileDiagnostic { file, diag }));
    diags.sort_by(|a, b| {
        (a.diag.span.start, a.diag.span.end, a.diag.code).cmp(&(b.diag.span.start, b.diag.span.end, b.diag.code))
    });
    diags.dedup();
    diags
}

/// True when any diagnostic is an error.
pub fn has_errors(diags: &[FileDiagnostic]) -> bool {
    diags.iter().any(|d| d.diag.severity == Severity::Error)
}

/// The context shared by the checks of one file.
pub(crate) struct Cx<'a> {
    pub db: &'a dyn Db,
    pub file: SourceFile,
    pub scope: &'a Scope,
    pub out: Vec<Diagnostic>,
}

impl<'a> Cx<'a> {
    pub fn ast(&self) -> &'a mcl_syntax::ast::SourceFile {
        &parse(self.db, self.file).file
    }

    /// The path to show for a definition in another file (`None` if in this one).
    pub fn other_file(&self, id: DefId) -> Option<String> {
        (id.file != self.file).then(|| id.file.path(self.db).display().to_string())
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
pub fn closest<'n>(name: &str, candidates: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let mut best: Option<(f64, &str)> = None;
    for c in candidates {
        let score = strsim::jaro_winkler(&name.to_lowercase(), &c.to_lowercase());
        if score > 0.85 && best.is_none_or(|(s, b)| score > s || (score == s && c < b)) {
            best = Some((score, c));
        }
    }
    best.map(|(_, c)| c)
}
