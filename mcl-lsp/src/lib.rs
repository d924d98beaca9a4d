//! # mcl-lsp
//!
//! The MCL language server, `mcl lsp` (LSP over standard input and output).
//!
//! * [`analysis`]: every editor feature as a plain function over a database
//!   snapshot (`mcl_compiler::Database`): diagnostics, hover, go to
//!   definition, references, rename, completion, signature help, symbols,
//!   semantic tokens, folding, inlay hints, quick fixes. No tokio, no
//!   transport: unit tests call these directly with `$0` cursor fixtures.
//! * [`host`]: the mutable database and the open documents; edits are
//!   applied in order by one thread, readers use snapshots that salsa
//!   cancels when the next edit arrives.
//! * `server`: the tower-lsp-server glue (ordering of edits, requests on the
//!   blocking pool, `ContentModified` on cancellation, the diagnostics
//!   publisher).
//!
//! The compiler crate knows nothing of this one: the server only calls its
//! salsa queries (`parse`, `program`, `scope`, `check_file`).

pub mod analysis;
mod format;
pub mod framing;
pub mod host;
mod server;

pub use server::{run_stdio, serve, service, Backend, Ordered};
