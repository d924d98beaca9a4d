//! # mcl-compiler
//!
//! The semantic layer of MCL, written as salsa queries so that `mcl check`
//! and the language server share them: source files are inputs; parsing,
//! imports, name resolution and every check are tracked queries. Diagnostics
//! are returned as query values (no accumulators).

pub mod check;
pub mod codes;
pub mod compile;
pub mod db;
pub mod diagnostics;
pub mod interface;
pub mod queries;
pub mod scope;

pub use check::{check_file, has_errors};
pub use db::{Database, Db, SourceFile};
pub use diagnostics::FileDiagnostic;
pub use queries::{parse, program};
