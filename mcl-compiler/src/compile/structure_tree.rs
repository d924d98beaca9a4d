//! A mission's control-structure tree as plain data: the one walk of the
//! syntax tree shared by the structure view's Graphviz drawing
//! ([`super::tree_dot`], `mcl compile --view structure`) and the monitor's
//! tree (`src/cmd/monitor.rs`, `GET /api/tree`).

use mcl_syntax::ast::{Block, MonitorKind, ParallelOp, Stmt, StmtKind, Value};

/// A control structure or a call.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureNode {
    /// `call`, `sequence`, `parallel-or`, `parallel-and`, `try-catch`,
    /// `monitor`, `while`, `if-then`, `if-then-else`, `not`, or `error`
    /// (a statement that did not parse).
    pub kind: &'static str,
    /// A call as written (`Altitude(altitude, timeout, "keep") : label`);
    /// `(syntax error)` for an error; empty for a structure.
    pub text: String,
    /// The byte offset where it starts in its file.
    pub offset: usize,
    /// Its parts in order, each named by the role it plays (`try`, `catch`,
    /// `branch 1`, `watched`, `condition 1`, `do 1`, ...; a sequence
    /// numbers them from 1; a `not` names its one part ``).
    pub children: Vec<(String, StructureNode)>,
}

/// The tree of a block: its statement, or a sequence of them.
pub fn block(b: &Block) -> StructureNode {
    match b.stmts.as_slice() {
        [one] => stmt(one),
        stmts => StructureNode {
            kind: "sequence",
            text: String::new(),
            offset: b.span.start as usize,
            children: stmts.iter().enumerate().map(|(i, s)| ((i + 1).to_string(), stmt(s))).collect(),
        },
    }
}

fn structure(kind: &'static str, s: &Stmt, parts: Vec<(String, &Block)>) -> StructureNode {
    StructureNode {
        kind,
        text: String::new(),
        offset: s.span.start as usize,
        children: parts.into_iter().map(|(p, b)| (p, block(b))).collect(),
    }
}

/// The tree of a statement.
pub fn stmt(s: &Stmt) -> StructureNode {
    let part = |p: &str, b| (p.to_string(), b);
    match &s.kind {
        StmtKind::Call(c) => {
            let args: Vec<String> = c.args.iter().map(Value::written).collect();
            let label = c.label.as_ref().map(|l| format!(" : {}", l.text)).unwrap_or_default();
            StructureNode {
                kind: "call",
                text: format!("{}({}){label}", c.name.text, args.join(", ")),
                offset: c.span.start as usize,
                children: Vec::new(),
            }
        }
        StmtKind::While { cond, body, .. } => structure("while", s, vec![part("condition", cond), part("do", body)]),
        StmtKind::If { cond, then, otherwise, .. } => match otherwise {
            Some(e) => structure("if-then-else", s, vec![part("condition", cond), part("then", then), part("else", e)]),
            None => structure("if-then", s, vec![part("condition", cond), part("then", then)]),
        },
        StmtKind::Parallel { branches, ops, .. } => {
            let kind =
                if ops.first().is_some_and(|(o, _)| *o == ParallelOp::Or) { "parallel-or" } else { "parallel-and" };
            structure(kind, s, branches.iter().enumerate().map(|(i, b)| (format!("branch {}", i + 1), b)).collect())
        }
        StmtKind::Try { body, catch, .. } => structure("try-catch", s, vec![part("try", body), part("catch", catch)]),
        StmtKind::Not { body, .. } => structure("not", s, vec![part("", body)]),
        StmtKind::Monitor { body, handlers, .. } => {
            let mut parts = vec![part("watched", body)];
            for (j, h) in handlers.iter().enumerate() {
                let kw = match h.kind {
                    MonitorKind::Condition => "condition",
                    MonitorKind::WhileCondition => "while_condition",
                };
                parts.push((format!("{kw} {}", j + 1), &h.condition));
                parts.push((format!("do {}", j + 1), &h.action));
            }
            structure("monitor", s, parts)
        }
        StmtKind::Error => StructureNode {
            kind: "error",
            text: "(syntax error)".into(),
            offset: s.span.start as usize,
            children: Vec::new(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_syntax::ast::Item;

    #[test]
    fn structures_and_calls_with_their_parts() {
        let text = "mission {\n    try {\n        A(1, \"x\") : a ;\n        B()\n    } catch {\n        parallel { C() } or { D() }\n    }\n}\n";
        let parsed = mcl_syntax::parse(text);
        let Some(Item::Mission(m)) = parsed.file.items.first() else { panic!("no mission") };
        let t = block(&m.body);
        assert_eq!(t.kind, "try-catch");
        let parts: Vec<&str> = t.children.iter().map(|(p, _)| p.as_str()).collect();
        assert_eq!(parts, ["try", "catch"]);
        let try_ = &t.children[0].1;
        assert_eq!((try_.kind, try_.children.len()), ("sequence", 2));
        assert_eq!(try_.children[0].1.text, "A(1, \"x\") : a");
        assert_eq!(&text[try_.children[1].1.offset..][..3], "B()");
        let par = &t.children[1].1;
        assert_eq!(par.kind, "parallel-or");
        assert_eq!(par.children[1].0, "branch 2");
        assert_eq!(par.children[1].1.text, "D()");
    }
}
