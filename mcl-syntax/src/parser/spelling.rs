//! Warnings for the spellings the grammar accepts but the formatter does
//! not write (`codes::NON_CANONICAL`).

use crate::ast::*;
use crate::diag::{codes, Diagnostic};

/// Warnings for accepted but non-canonical spellings.
pub(super) fn lint_spellings(file: &SourceFile, out: &mut Vec<Diagnostic>) {
    fn block(b: &Block, out: &mut Vec<Diagnostic>) {
        for s in &b.stmts {
            stmt(s, out);
        }
    }
    fn stmt(s: &Stmt, out: &mut Vec<Diagnostic>) {
        match &s.kind {
            StmtKind::If { cond, then, otherwise, else_written_then, .. } => {
                if let Some(span) = else_written_then {
                    out.push(
                        Diagnostic::warning(
                            codes::NON_CANONICAL,
                            "the else branch of `if` is written `then`; the canonical keyword is `else`",
                            *span,
                        )
                        .with_label(*span, "accepted for compatibility with the seed's Table B.4")
                        .with_help("write `else { ... }`"),
                    );
                }
                block(cond, out);
                block(then, out);
                if let Some(o) = otherwise {
                    block(o, out);
                }
            }
            StmtKind::While { cond, body, .. } => {
                block(cond, out);
                block(body, out);
            }
            StmtKind::Parallel { branches, .. } => branches.iter().for_each(|b| block(b, out)),
            StmtKind::Try { body, catch, .. } => {
                block(body, out);
                block(catch, out);
            }
            StmtKind::Not { body, .. } => block(body, out),
            StmtKind::Monitor { body, handlers, .. } => {
                block(body, out);
                for h in handlers {
                    block(&h.condition, out);
                    block(&h.action, out);
                }
            }
            StmtKind::Call(_) | StmtKind::Error => {}
        }
    }
    for item in &file.items {
        if let Item::Mission(m) = item {
            block(&m.body, out);
        }
    }
}
