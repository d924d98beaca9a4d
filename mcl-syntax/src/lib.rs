//! # mcl-syntax
//!
//! The MCL language's syntax: a lexer that keeps comments as trivia, an
//! error-tolerant parser that always returns a tree and a list of errors, the
//! syntax tree, spans and line/column conversion, and the diagnostic type that
//! every later layer uses. This crate knows nothing about salsa, nets or LSP.

pub mod ast;
pub mod diag;
pub mod format;
pub mod gen;
pub mod lexer;
pub mod parser;
pub mod shift;
pub mod span;
pub mod visit;

pub use diag::{Diagnostic, Label, Severity};
pub use parser::{parse, parse_item, split_items, split_items_edit, ItemBounds, Parse};
pub use shift::{parse_by_items, Shift};
pub use span::{LineCol, LineIndex, Span};
