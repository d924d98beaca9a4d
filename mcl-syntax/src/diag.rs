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
        Diagnostic { severity, code, message: message.into(), span, labels: Vec::new(), help: None, notes: Vec::new() }
    }
    /// Adds a secondary label in the same file.
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label { span, message: message.into(), file: None });
        self
    }
    /// Adds a secondary label in another file.
    pub fn with_label_in(mut self, file: Option<String>, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label { span, message: message.into(), file });
        self
    }
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
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
