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

/// The longest source line a report shows whole; a longer one is shown cut
/// to this many characters around its labels, with ellipses.
pub const MAX_LINE_CHARS: usize = 240;

/// What a report shows of one file: the lines its labels cover, each cut to
/// [`MAX_LINE_CHARS`] around the labels, and where each byte offset of the
/// file lands in it (so that a 10 MB line prints a bounded report). The
/// lines before are empty, so that line numbers stay right (ariadne's
/// `with_display_line_offset` does not number the margin).
struct Excerpt {
    text: String,
    /// Kept pieces of the file: byte start, byte end, start in `text` (chars).
    pieces: Vec<(usize, usize, usize)>,
    /// Lines shown cut: line number (from 1), characters, column (from 1)
    /// where the cut line starts.
    cut: Vec<(usize, usize, usize)>,
}

impl Excerpt {
    fn new(file: &str, ranges: &[std::ops::Range<usize>]) -> Excerpt {
        let lo = ranges.iter().map(|r| r.start).min().unwrap_or(0);
        let hi = ranges.iter().map(|r| r.end).max().unwrap_or(0).max(lo);
        // A label at the end of a file that ends with a newline is shown on
        // the last line.
        let line_of = if lo == file.len() && file.ends_with('\n') { lo - 1 } else { lo };
        let start = file[..line_of].rfind('\n').map_or(0, |i| i + 1);
        let end = file[hi..].find('\n').map_or(file.len(), |i| hi + i + 1);
        let first_line = file.as_bytes()[..start].iter().filter(|b| **b == b'\n').count();
        let mut ex = Excerpt { text: "\n".repeat(first_line), pieces: Vec::new(), cut: Vec::new() };
        let mut chars = first_line;
        let mut line_start = start;
        let mut line_no = first_line + 1;
        while line_start < end {
            let line_end = file[line_start..end].find('\n').map_or(end, |i| line_start + i + 1);
            let line = &file[line_start..line_end];
            let n = line.strip_suffix('\n').unwrap_or(line).chars().count();
            if n <= MAX_LINE_CHARS {
                ex.pieces.push((line_start, line_end, chars));
                ex.text.push_str(line);
                chars += line.chars().count();
            } else {
                // A window that starts a little before the first label on the line.
                let anchor = ranges
                    .iter()
                    .filter(|r| r.start < line_end && r.end >= line_start)
                    .map(|r| r.start.clamp(line_start, line_end))
                    .min()
                    .unwrap_or(line_start);
                let content_end = line_start + line.strip_suffix('\n').unwrap_or(line).len();
                let anchor = anchor.min(content_end);
                let before = &file[line_start..anchor];
                let ws = before.char_indices().rev().nth(40).map_or(line_start, |(i, _)| line_start + i);
                let we = file[ws..content_end].char_indices().nth(MAX_LINE_CHARS).map_or(content_end, |(i, _)| ws + i);
                if ws > line_start {
                    ex.text.push('…');
                    chars += 1;
                }
                let kept = &file[ws..we];
                ex.pieces.push((ws, we, chars));
                ex.text.push_str(kept);
                chars += kept.chars().count();
                if we < content_end {
                    ex.text.push('…');
                    chars += 1;
                }
                if content_end < line_end {
                    ex.pieces.push((content_end, line_end, chars));
                    ex.text.push('\n');
                    chars += 1;
                }
                let column = file[line_start..ws].chars().count() + 1;
                ex.cut.push((line_no, n, column));
            }
            line_start = line_end;
            line_no += 1;
        }
        ex
    }

    /// The place of a byte offset of the file in the excerpt, in characters
    /// (an offset in a part cut away lands on the nearest ellipsis).
    fn at(&self, file: &str, x: usize) -> usize {
        let i = self.pieces.partition_point(|p| p.0 <= x);
        let Some(&(s, e, c)) = i.checked_sub(1).and_then(|i| self.pieces.get(i)) else { return 0 };
        c + file[s..x.min(e)].chars().count()
    }

    fn range(&self, file: &str, r: &std::ops::Range<usize>) -> std::ops::Range<usize> {
        let s = self.at(file, r.start);
        s..self.at(file, r.end).max(s)
    }
}

/// Renders diagnostics as rustc-style reports.
pub fn render_human(db: &dyn Db, diags: &[FileDiagnostic], color: bool) -> String {
    let mut out = Vec::new();
    for fd in diags {
        let d = &fd.diag;
        let kind = match d.severity {
            Severity::Error => ReportKind::Error,
            Severity::Warning => ReportKind::Warning,
            Severity::Info | Severity::Hint => ReportKind::Advice,
        };
        let main_color = if d.is_error() { Color::Red } else { Color::Yellow };
        // The files shown (the diagnostic's first) and the labels in each.
        let mut files: Vec<(String, &str)> =
            vec![(display_path(fd.file.path(db)), fd.file.text(db).as_deref().unwrap_or(""))];
        let main = clamp(files[0].1, d.span);
        let mut labels: Vec<(usize, std::ops::Range<usize>, &str, Color)> = Vec::new();
        if !d.labels.iter().any(|l| l.file.is_none() && l.span == d.span) {
            labels.push((0, main.clone(), "here", main_color));
        }
        for l in &d.labels {
            let fi = match &l.file {
                None => 0,
                Some(other) => {
                    let f = db.file(Path::new(other));
                    let shown = display_path(f.path(db));
                    match files.iter().position(|(n, _)| n == &shown) {
                        Some(i) => i,
                        None => {
                            files.push((shown, f.text(db).as_deref().unwrap_or("")));
                            files.len() - 1
                        }
                    }
                }
            };
            let c = if l.file.is_none() && l.span == d.span { main_color } else { Color::Blue };
            labels.push((fi, clamp(files[fi].1, l.span), &l.message, c));
        }
        let excerpts: Vec<Excerpt> = files
            .iter()
            .enumerate()
            .map(|(fi, (_, text))| {
                let mut ranges: Vec<_> = labels.iter().filter(|l| l.0 == fi).map(|l| l.1.clone()).collect();
                if fi == 0 {
                    ranges.push(main.clone());
                }
                Excerpt::new(text, &ranges)
            })
            .collect();
        let mut report = Report::build(kind, (files[0].0.clone(), excerpts[0].range(files[0].1, &main)))
            .with_config(Config::default().with_color(color))
            .with_code(d.code)
            .with_message(&d.message);
        for (fi, r, message, c) in &labels {
            let span = (files[*fi].0.clone(), excerpts[*fi].range(files[*fi].1, r));
            report = report.with_label(Label::new(span).with_message(message).with_color(*c));
        }
        if let Some(h) = &d.help {
            report = report.with_help(h);
        }
        for n in &d.notes {
            report = report.with_note(n);
        }
        for ((name, _), ex) in files.iter().zip(&excerpts) {
            for (line, n, column) in &ex.cut {
                report = report.with_note(format!(
                    "{name}:{line} has {n} characters: shown cut to {MAX_LINE_CHARS} from column {column}"
                ));
            }
        }
        let sources = files
            .iter()
            .zip(excerpts)
            .map(|((name, _), ex)| (name.clone(), ariadne::Source::from(ex.text)))
            .collect::<std::collections::HashMap<_, _>>();
        let _ = report.finish().write(ariadne::FnCache::new(no_source).with_sources(sources), &mut out);
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Every source of a report is given up front.
fn no_source(id: &String) -> Result<String, String> {
    Err(format!("no source `{id}`"))
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
