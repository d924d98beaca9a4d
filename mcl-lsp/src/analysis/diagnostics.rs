//! Compiler diagnostics as LSP diagnostics (UTF-16 positions, related
//! information for labels, including labels in other files).

use super::Analysis;
use mcl_compiler::queries::syntax_errors;
use mcl_compiler::{check_file, codes, SourceFile};
use mcl_syntax::Severity;
use tower_lsp_server::ls_types::{
    Diagnostic, DiagnosticRelatedInformation, DiagnosticSeverity, DiagnosticTag, NumberOrString,
};

pub const SOURCE: &str = "mcl";

pub fn to_lsp(a: &Analysis<'_>, file: SourceFile, d: &mcl_syntax::Diagnostic) -> Diagnostic {
    let severity = match d.severity {
        Severity::Error => DiagnosticSeverity::ERROR,
        Severity::Warning => DiagnosticSeverity::WARNING,
        Severity::Info => DiagnosticSeverity::INFORMATION,
        Severity::Hint => DiagnosticSeverity::HINT,
    };
    let mut message = d.message.clone();
    if let Some(h) = &d.help {
        message.push_str("\nhelp: ");
        message.push_str(h);
    }
    for n in &d.notes {
        message.push_str("\nnote: ");
        message.push_str(n);
    }
    let related: Vec<DiagnosticRelatedInformation> = d
        .labels
        .iter()
        .filter(|l| !(l.file.is_none() && l.span == d.span))
        .filter_map(|l| {
            let lf = a.label_file(file, l.file.as_deref());
            Some(DiagnosticRelatedInformation { location: a.location(lf, l.span)?, message: l.message.clone() })
        })
        .collect();
    let tags = matches!(d.code, codes::UNUSED | codes::UNUSED_PARAMETER).then(|| vec![DiagnosticTag::UNNECESSARY]);
    Diagnostic {
        range: a.range(file, d.span),
        severity: Some(severity),
        code: Some(NumberOrString::String(d.code.to_string())),
        code_description: None,
        source: Some(SOURCE.to_string()),
        message,
        related_information: (!related.is_empty()).then_some(related),
        tags,
        data: None,
    }
}

/// The syntax errors of a file (available as soon as it is parsed).
pub fn syntax(a: &Analysis<'_>, file: SourceFile) -> Vec<Diagnostic> {
    syntax_errors(a.db, file).iter().map(|d| to_lsp(a, file, d)).collect()
}

/// Every diagnostic of a file, with the file as the root of its program,
/// including the coordination analysis of its constraints (E0406, W0407).
pub fn full(a: &Analysis<'_>, file: SourceFile) -> Vec<Diagnostic> {
    let mut all = semantic(a, file);
    all.extend(coordination(a, file));
    all
}

/// The compiler's diagnostics of a file (syntax, names, blocks, missions):
/// fast, published before the coordination analysis.
pub fn semantic(a: &Analysis<'_>, file: SourceFile) -> Vec<Diagnostic> {
    check_file(a.db, file).iter().map(|fd| to_lsp(a, file, &fd.diag)).collect()
}

/// The coordination analysis of a file's constraints (E0406, W0407): an
/// exploration that can take seconds, interrupted by the next edit.
pub fn coordination(a: &Analysis<'_>, file: SourceFile) -> Vec<Diagnostic> {
    mcl_coord::coordination_diagnostics(a.db, file).iter().map(|fd| to_lsp(a, file, &fd.diag)).collect()
}
