//! Graphviz rendering of a mission's control-structure tree (`mcl compile
//! --dot OUT.dot --view structure`): one box per control structure, one
//! ellipse per call (with its arguments, label and line), edges named by the
//! part of the structure they lead to. A picture a person can read whole,
//! where the net of the same mission (`--view net`) has hundreds of nodes.

use super::structure_tree::{self, StructureNode};
use mcl_syntax::ast::Mission;
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

    /// A node of the tree (the walk of [`structure_tree`]), then each of
    /// its parts, each followed by the edge to it.
    fn draw(&mut self, n: &StructureNode) -> usize {
        let line = (self.line)(n.offset);
        let id = match n.kind {
            "call" => self.node(&format!("{}\nline {line}", n.text), "ellipse"),
            "error" => self.node(&n.text, "plaintext"),
            kind => self.node(&format!("{kind}\nline {line}"), "box"),
        };
        for (part, c) in &n.children {
            let c = self.draw(c);
            self.edge(id, c, part);
        }
        id
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
    let body = t.draw(&structure_tree::block(&mission.body));
    t.edge(root, body, "");
    t.out.push_str("}\n");
    t.out
}
