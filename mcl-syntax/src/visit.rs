//! Walking the statements of a mission.

use crate::ast::*;

/// Calls `f` on every statement of `block`, parents before children.
pub fn walk_block<'a>(block: &'a Block, f: &mut impl FnMut(&'a Stmt)) {
    for s in &block.stmts {
        walk_stmt(s, f);
    }
}

/// Calls `f` on `stmt` and then on every statement nested in it.
pub fn walk_stmt<'a>(stmt: &'a Stmt, f: &mut impl FnMut(&'a Stmt)) {
    f(stmt);
    for b in child_blocks(stmt) {
        walk_block(b, f);
    }
}

/// The blocks directly nested in a statement, in source order.
pub fn child_blocks(stmt: &Stmt) -> Vec<&Block> {
    match &stmt.kind {
        StmtKind::Call(_) | StmtKind::Error => Vec::new(),
        StmtKind::While { cond, body, .. } => vec![cond, body],
        StmtKind::If { cond, then, otherwise, .. } => {
            let mut v = vec![cond, then];
            v.extend(otherwise.iter());
            v
        }
        StmtKind::Parallel { branches, .. } => branches.iter().collect(),
        StmtKind::Try { body, catch, .. } => vec![body, catch],
        StmtKind::Not { body, .. } => vec![body],
        StmtKind::Monitor { body, handlers, .. } => {
            let mut v = vec![body];
            for h in handlers {
                v.push(&h.condition);
                v.push(&h.action);
            }
            v
        }
    }
}

/// Every task call in a block, in source order.
pub fn calls(block: &Block) -> Vec<&Call> {
    let mut out = Vec::new();
    walk_block(block, &mut |s| {
        if let StmtKind::Call(c) = &s.kind {
            out.push(c);
        }
    });
    out
}
