//! Diagnostics located in files, and their renderings: ariadne for people,
//! JSON for scripts (the format documented in the README).

use crate::db::{Db, SourceFile};
use crate::queries::line_index;
use ariadne::{Color, Config, Label, Report, ReportKind};
use mcl_syntax::{Diagnostic, Severity, Span};
use serde_json::{json, Value};
use std::path::Path;

/// A diagnostic and the file it is in.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FileDiagnostic {
    pub file: SourceFile,
    pub diag: Diagnostic,
}

/// Shows `path` relative to the current folder when it is inside it.
pub fn display_path(path: &Path) -> String {
    let cwd = std::env::current_dir().ok();
    match cwd.as_deref().and_then(|c| path.strip_prefix(c).ok()) {
        Some(rel) => rel.display().to_string(),
        None => path.display().to_string(),
    }
}

fn clamp(text: &str, span: Span) -> std::ops::Range<usize> {
    let len = text.len();
    let mut s = (span.start as usize).min(len);
    let mut e = (span.end as usize).min(len).max(s);
    while !text.is_char_boundary(s) {
        s -= 1;
    }
    while !text.is_char_boundary(e) {
        e += 1;
    }
    // An empty span is drawn on the character after it, so that it shows on
    // the right line; at a line end it is drawn on the last character.
    if s == e {
        match text[s..].chars().next() {
            Some(c) if c != '\n' && c != '\r' => e = s + c.len_utf8(),
            _ => {
                if let Some(c) = text[..s].chars().next_back().filter(|c| *c != '\n') {
                    s -= c.len_utf8();
                }
            }
        }
    }
    s..e
}

/// Renders diagnostics as rustc-style reports.
pub fn render_human(db: &dyn Db, diags: &[FileDiagnostic], color: bool) -> String {
    let mut out = Vec::new();
    for fd in diags {
        let path = display_path(fd.file.path(db));
        let text = fd.file.text(db).as_deref().unwrap_or("").to_string();
        let d = &fd.diag;
        let kind = match d.severity {
            Severity::Error => ReportKind::Error,
            Severity::Warning => ReportKind::Warning,
            Severity::Info | Severity::Hint => ReportKind::Advice,
        };
        let main_color = if d.is_error() { Color::Red } else { Color::Yellow };
        let mut sources: Vec<(String, String)> = vec![(path.clone(), text.clone())];
        let char_offsets = |t: &str, r: std::ops::Range<usize>| {
            let s = t[..r.start].chars().count();
            s..s + t[r].chars().count()
        };
        let main = clamp(&text, d.span);
        let mut report = Report::build(kind, (path.clone(), char_offsets(&text, main.clone())))
            .with_config(Config::default().with_color(color))
            .with_code(d.code)
            .with_message(&d.message);
        let has_main_label = d.labels.iter().any(|l| l.file.is_none() && l.span == d.span);
        if !has_main_label {
            report = report.with_label(
                Label::new((path.clone(), char_offsets(&text, main))).with_message("here").with_color(main_color),
            );
        }
        for l in &d.labels {
            let (lpath, ltext) = match &l.file {
                None => (path.clone(), text.clone()),
                Some(other) => {
                    let p = Path::new(other);
                    let f = db.file(p);
                    let t = f.text(db).as_deref().unwrap_or("").to_string();
                    let shown = display_path(f.path(db));
                    if !sources.iter().any(|(n, _)| n == &shown) {
                        sources.push((shown.clone(), t.clone()));
                    }
                    (shown, t)
                }
            };
            let r = clamp(&ltext, l.span);
            let c = if l.file.is_none() && l.span == d.span { main_color } else { Color::Blue };
            report =
                report.with_label(Label::new((lpath, char_offsets(&ltext, r))).with_message(&l.message).with_color(c));
        }
        if let Some(h) = &d.help {
            report = report.with_help(h);
        }
        for n in &d.notes {
            report = report.with_note(n);
        }
        let _ = report.finish().write(ariadne::sources(sources), &mut out);
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn range_json(db: &dyn Db, file: SourceFile, span: Span) -> Value {
    let text = file.text(db).as_deref().unwrap_or("");
    let idx = line_index(db, file);
    let s = idx.line_col(text, span.start as usize);
    let e = idx.line_col(text, span.end as usize);
    json!({"start": {"line": s.line, "column": s.column}, "end": {"line": e.line, "column": e.column}})
}

/// One JSON object per diagnostic (the stable format of `mcl check --format json`).
pub fn to_json(db: &dyn Db, fd: &FileDiagnostic) -> Value {
    let d = &fd.diag;
    let labels: Vec<Value> = d
        .labels
        .iter()
        .map(|l| {
            let (file, shown) = match &l.file {
                None => (fd.file, display_path(fd.file.path(db))),
                Some(p) => {
                    let f = db.file(Path::new(p));
                    (f, display_path(f.path(db)))
                }
            };
            json!({"file": shown, "range": range_json(db, file, l.span), "message": l.message})
        })
        .collect();
    json!({
        "severity": d.severity.as_str(),
        "code": d.code,
        "message": d.message,
        "file": display_path(fd.file.path(db)),
        "range": range_json(db, fd.file, d.span),
        "labels": labels,
        "help": d.help,
        "notes": d.notes,
    })
}
