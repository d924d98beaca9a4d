//! `mcl lsp`: the language server, on standard input and output.

/// Serves the Language Server Protocol until the client says `exit`.
pub fn run() -> u8 {
    mcl_lsp::run_stdio()
}
