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
    // The blocks of `child_blocks`, without collecting them.
    match &stmt.kind {
        StmtKind::Call(_) | StmtKind::Error => {}
        StmtKind::While { cond, body, .. } => {
            walk_block(cond, f);
            walk_block(body, f);
        }
        StmtKind::If { cond, then, otherwise, .. } => {
            walk_block(cond, f);
            walk_block(then, f);
            if let Some(o) = otherwise {
                walk_block(o, f);
            }
        }
        StmtKind::Parallel { branches, .. } => branches.iter().for_each(|b| walk_block(b, f)),
        StmtKind::Try { body, catch, .. } => {
            walk_block(body, f);
            walk_block(catch, f);
        }
        StmtKind::Not { body, .. } => walk_block(body, f),
        StmtKind::Monitor { body, handlers, .. } => {
            walk_block(body, f);
            for h in handlers {
                walk_block(&h.condition, f);
                walk_block(&h.action, f);
            }
        }
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
