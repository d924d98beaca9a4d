//! Graphviz rendering of a mission's control-structure tree (`mcl compile
//! --dot OUT.dot --view structure`): one box per control structure, one
//! ellipse per call (with its arguments, label and line), edges named by the
//! part of the structure they lead to. A picture a person can read whole,
//! where the net of the same mission (`--view net`) has hundreds of nodes.

use mcl_syntax::ast::{Block, Mission, MonitorKind, ParallelOp, Stmt, StmtKind, Value};
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n")
}

struct Tree<'a> {
    out: String,
    next: usize,
    /// The line of a byte offset of the mission's file.
    line: &'a dyn Fn(usize) -> usize,
}

impl Tree<'_> {
    fn node(&mut self, label: &str, shape: &str) -> usize {
        let id = self.next;
        self.next += 1;
        let _ = writeln!(self.out, "  n{id} [label=\"{}\", shape={shape}];", esc(label));
        id
    }

    fn edge(&mut self, from: usize, to: usize, label: &str) {
        let _ = writeln!(self.out, "  n{from} -> n{to} [label=\"{}\"];", esc(label));
    }

    /// A block: its statement, or a sequence of them.
    fn block(&mut self, b: &Block) -> usize {
        match b.stmts.as_slice() {
            [one] => self.stmt(one),
            stmts => {
                let seq = self.node(&format!("sequence\nline {}", (self.line)(b.span.start as usize)), "box");
                for (i, s) in stmts.iter().enumerate() {
                    let c = self.stmt(s);
                    self.edge(seq, c, &format!("{}", i + 1));
                }
                seq
            }
        }
    }

    fn structure(&mut self, name: &str, s: &Stmt, parts: &[(&str, &Block)]) -> usize {
        let id = self.node(&format!("{name}\nline {}", (self.line)(s.span.start as usize)), "box");
        for (label, b) in parts {
            let c = self.block(b);
            self.edge(id, c, label);
        }
        id
    }

    fn stmt(&mut self, s: &Stmt) -> usize {
        match &s.kind {
            StmtKind::Call(c) => {
                let args: Vec<String> = c.args.iter().map(Value::written).collect();
                let label = c.label.as_ref().map(|l| format!(" : {}", l.text)).unwrap_or_default();
                let text =
                    format!("{}({}){label}\nline {}", c.name.text, args.join(", "), (self.line)(c.span.start as usize));
                self.node(&text, "ellipse")
            }
            StmtKind::While { cond, body, .. } => self.structure("while", s, &[("condition", cond), ("do", body)]),
            StmtKind::If { cond, then, otherwise, .. } => match otherwise {
                Some(e) => self.structure("if-then-else", s, &[("condition", cond), ("then", then), ("else", e)]),
                None => self.structure("if-then", s, &[("condition", cond), ("then", then)]),
            },
            StmtKind::Parallel { branches, ops, .. } => {
                let kind =
                    if ops.first().is_some_and(|(o, _)| *o == ParallelOp::Or) { "parallel-or" } else { "parallel-and" };
                let labels: Vec<String> = (1..=branches.len()).map(|i| format!("branch {i}")).collect();
                let parts: Vec<(&str, &Block)> = labels.iter().map(String::as_str).zip(branches.iter()).collect();
                self.structure(kind, s, &parts)
            }
            StmtKind::Try { body, catch, .. } => self.structure("try-catch", s, &[("try", body), ("catch", catch)]),
            StmtKind::Not { body, .. } => self.structure("not", s, &[("", body)]),
            StmtKind::Monitor { body, handlers, .. } => {
                let id = self.node(&format!("monitor\nline {}", (self.line)(s.span.start as usize)), "box");
                let c = self.block(body);
                self.edge(id, c, "watched");
                for (j, h) in handlers.iter().enumerate() {
                    let kw = match h.kind {
                        MonitorKind::Condition => "condition",
                        MonitorKind::WhileCondition => "while_condition",
                    };
                    let cond = self.block(&h.condition);
                    self.edge(id, cond, &format!("{kw} {}", j + 1));
                    let act = self.block(&h.action);
                    self.edge(id, act, &format!("do {}", j + 1));
                }
                id
            }
            StmtKind::Error => self.node("(syntax error)", "plaintext"),
        }
    }
}

/// The control-structure tree of `mission` (named `name`) in the DOT
/// language; `line` gives the line of a byte offset of its file.
pub fn structure_dot(mission: &Mission, name: &str, line: &dyn Fn(usize) -> usize) -> String {
    let mut t = Tree { out: String::new(), next: 0, line };
    let _ = writeln!(
        t.out,
        "digraph \"{}\" {{\n  rankdir=TB; node [fontname=\"Helvetica\", fontsize=10]; edge [fontname=\"Helvetica\", fontsize=9];",
        esc(name)
    );
    let root = t.node(&format!("mission {name}"), "box, style=bold");
    let body = t.block(&mission.body);
    t.edge(root, body, "");
    t.out.push_str("}\n");
    t.out
}
