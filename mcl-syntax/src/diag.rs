//! Diagnostics shared by every layer: a stable code, a message, a primary span,
//! labelled secondary spans and an optional help line.

use crate::span::Span;
use serde::{Deserialize, Serialize};

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
    Info,
    Hint,
}

impl Severity {
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Info => "info",
            Severity::Hint => "hint",
        }
    }
}

/// A secondary location. `file` is `None` when it is in the same file as the
/// diagnostic, otherwise the path of the other file.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Label {
    pub span: Span,
    pub message: String,
    pub file: Option<String>,
}

/// One diagnostic, located in one file.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Diagnostic {
    pub severity: Severity,
    /// Stable code such as `E0101`; see `mcl explain CODE`.
    pub code: &'static str,
    pub message: String,
    pub span: Span,
    pub labels: Vec<Label>,
    pub help: Option<String>,
    /// Extra lines shown after the labels (e.g. a counterexample).
    pub notes: Vec<String>,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>, span: Span) -> Self {
        Self::new(Severity::Error, code, message, span)
    }
    pub fn warning(code: &'static str, message: impl Into<String>, span: Span) -> Self {
        Self::new(Severity::Warning, code, message, span)
    }
    pub fn new(severity: Severity, code: &'static str, message: impl Into<String>, span: Span) -> Self {
        let message = bounded(message.into());
        Diagnostic { severity, code, message, span, labels: Vec::new(), help: None, notes: Vec::new() }
    }
    /// Adds a secondary label in the same file.
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label { span, message: bounded(message.into()), file: None });
        self
    }
    /// Adds a secondary label in another file.
    pub fn with_label_in(mut self, file: Option<String>, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label { span, message: bounded(message.into()), file });
        self
    }
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(bounded(help.into()));
        self
    }
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(bounded(note.into()));
        self
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// The longest name (a run of letters, digits, `_` and `$`) that a
/// diagnostic's text shows whole; a longer one is cut after this many
/// characters and an ellipsis, so that a 10 MB identifier gives a short
/// message.
pub const MAX_NAME_CHARS: usize = 64;
/// The longest text of a message, label, help or note, in characters.
pub const MAX_TEXT_CHARS: usize = 4000;

/// `text` with its long names cut (see [`MAX_NAME_CHARS`]) and cut as a
/// whole after [`MAX_TEXT_CHARS`] characters.
pub fn bounded(text: String) -> String {
    if text.len() <= MAX_NAME_CHARS {
        return text;
    }
    let is_name = |c: char| c.is_alphanumeric() || c == '_' || c == '$';
    let (mut run, mut count) = (0usize, 0usize);
    let mut cut = false;
    for c in text.chars() {
        run = if is_name(c) { run + 1 } else { 0 };
        count += 1;
        if run > MAX_NAME_CHARS || count > MAX_TEXT_CHARS {
            cut = true;
            break;
        }
    }
    if !cut {
        return text;
    }
    let mut out = String::new();
    let (mut run, mut count) = (0usize, 0usize);
    for c in text.chars() {
        run = if is_name(c) { run + 1 } else { 0 };
        if run > MAX_NAME_CHARS {
            if run == MAX_NAME_CHARS + 1 {
                out.push('…');
                count += 1;
            }
            continue;
        }
        if count >= MAX_TEXT_CHARS {
            out.push('…');
            break;
        }
        out.push(c);
        count += 1;
    }
    out
}

/// Codes of the syntax layer. Every code has a long explanation in
/// `mcl-compiler/explain/` (`mcl explain CODE`).
pub mod codes {
    /// A character that cannot start any token.
    pub const UNKNOWN_CHAR: &str = "E0001";
    /// A string literal without its closing quote.
    pub const UNTERMINATED_STRING: &str = "E0002";
    /// A `/* */` comment without its closing `*/`.
    pub const UNTERMINATED_COMMENT: &str = "E0003";
    /// A malformed number such as `01` or `1.`.
    pub const BAD_NUMBER: &str = "E0004";
    /// A token the grammar does not allow here.
    pub const UNEXPECTED_TOKEN: &str = "E0010";
    /// An opening delimiter without its closing one.
    pub const UNCLOSED_DELIMITER: &str = "E0011";
    /// A closing delimiter with no opening one.
    pub const UNMATCHED_CLOSE: &str = "E0012";
    /// A block that must hold a statement is empty.
    pub const EMPTY_BLOCK: &str = "E0013";
    /// An action definition without its `c: command`.
    pub const MISSING_COMMAND: &str = "E0014";
    /// A non-canonical spelling that is accepted (warning).
    pub const NON_CANONICAL: &str = "W0015";
    /// Blocks or control structures nested deeper than the parser's limit.
    pub const NESTING_TOO_DEEP: &str = "E0016";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_names_and_texts_are_cut() {
        let name = "a".repeat(10_000_000);
        let d = Diagnostic::error(codes::UNEXPECTED_TOKEN, format!("undefined task `{name}`"), Span::default())
            .with_label(Span::default(), format!("`{name}` here"))
            .with_help("short help");
        let shown = format!("undefined task `{}…`", "a".repeat(MAX_NAME_CHARS));
        assert_eq!(d.message, shown);
        assert_eq!(d.labels[0].message, format!("`{}…` here", "a".repeat(MAX_NAME_CHARS)));
        assert_eq!(d.help.as_deref(), Some("short help"));
        let words = "word ".repeat(10_000);
        assert_eq!(bounded(words).chars().count(), MAX_TEXT_CHARS + 1);
        let fine = format!("`{}` and `{}`", "b".repeat(MAX_NAME_CHARS), "é".repeat(10));
        assert_eq!(bounded(fine.clone()), fine);
    }
}
