//! Moving trees and diagnostics by a byte offset: an item parsed alone (with
//! spans relative to its start) is placed back into its file.

use crate::ast::*;
use crate::diag::Diagnostic;
use crate::lexer::Comment;
use crate::parser::Parse;
use crate::span::Span;

/// Adds `by` to every span inside a value.
pub trait Shift {
    fn shift(&mut self, by: u32);
}

impl Shift for Span {
    fn shift(&mut self, by: u32) {
        self.start += by;
        self.end += by;
    }
}

impl<T: Shift> Shift for Vec<T> {
    fn shift(&mut self, by: u32) {
        self.iter_mut().for_each(|x| x.shift(by));
    }
}

impl<T: Shift> Shift for Option<T> {
    fn shift(&mut self, by: u32) {
        if let Some(x) = self {
            x.shift(by);
        }
    }
}

impl<A: Shift, B: Shift> Shift for (A, B) {
    fn shift(&mut self, by: u32) {
        self.0.shift(by);
        self.1.shift(by);
    }
}

impl Shift for Name {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
    }
}

impl Shift for Number {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
    }
}

impl Shift for Comment {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
    }
}

/// Labels in other files keep their spans.
impl Shift for Diagnostic {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
        for l in &mut self.labels {
            if l.file.is_none() {
                l.span.shift(by);
            }
        }
    }
}

impl Shift for Parse {
    fn shift(&mut self, by: u32) {
        self.file.items.shift(by);
        self.comments.shift(by);
        self.errors.shift(by);
    }
}

impl Shift for Item {
    fn shift(&mut self, by: u32) {
        match self {
            Item::Import(i) => {
                i.path_span.shift(by);
                i.span.shift(by);
            }
            Item::Actions(b) => {
                b.span.shift(by);
                for a in &mut b.actions {
                    a.name.shift(by);
                    a.primitive.shift(by);
                    a.command.shift(by);
                    a.params.shift(by);
                    a.span.shift(by);
                }
            }
            Item::Events(b) => {
                b.span.shift(by);
                b.events.shift(by);
            }
            Item::Patterns(b) => {
                b.span.shift(by);
                for p in &mut b.patterns {
                    p.name.shift(by);
                    p.span.shift(by);
                    match &mut p.body {
                        PatternBody::File { path_span, .. } => path_span.shift(by),
                        PatternBody::Net(n) => n.shift(by),
                    }
                }
            }
            Item::Tasks(b) => {
                b.span.shift(by);
                for t in &mut b.tasks {
                    t.name.shift(by);
                    t.params.shift(by);
                    t.pattern.shift(by);
                    t.span.shift(by);
                    for bd in &mut t.bindings {
                        bd.target.shift(by);
                        bd.transitions.shift(by);
                        bd.span.shift(by);
                    }
                }
            }
            Item::Mission(m) => {
                m.keyword_span.shift(by);
                m.name.shift(by);
                m.params.shift(by);
                m.placement.shift(by);
                m.body.shift(by);
                m.span.shift(by);
            }
            Item::Constraints(b) => {
                b.span.shift(by);
                for c in &mut b.constraints {
                    c.keyword_span.shift(by);
                    c.bound.shift(by);
                    c.span.shift(by);
                    for r in &mut c.refs {
                        r.mission.shift(by);
                        r.label.shift(by);
                        r.span.shift(by);
                    }
                }
            }
            Item::Planning(b) => b.spans_mut(&mut |s| s.shift(by)),
            Item::PddlMap(b) => b.spans_mut(&mut |s| s.shift(by)),
        }
    }
}

impl Shift for PatternNet {
    fn shift(&mut self, by: u32) {
        for p in &mut self.places {
            p.name.shift(by);
            p.interface.shift(by);
            p.tokens.shift(by);
            p.span.shift(by);
        }
        for t in &mut self.transitions {
            t.name.shift(by);
            t.interface.shift(by);
            match &mut t.delay {
                Some(Delay::Fixed(n)) => n.shift(by),
                Some(Delay::Param(n)) => n.shift(by),
                None => {}
            }
            t.span.shift(by);
        }
        for a in &mut self.arcs {
            a.source.name.shift(by);
            a.source.interface.shift(by);
            a.target.name.shift(by);
            a.target.interface.shift(by);
            a.weight.shift(by);
            a.span.shift(by);
        }
    }
}

impl Shift for Value {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
        match &mut self.kind {
            ValueKind::Ident(n) => n.shift(by),
            ValueKind::Number(n) => n.shift(by),
            ValueKind::List { tag, items } => {
                tag.shift(by);
                items.shift(by);
            }
            ValueKind::Str(_) | ValueKind::Error => {}
        }
    }
}

impl Shift for Block {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
        self.stmts.shift(by);
    }
}

impl Shift for Stmt {
    fn shift(&mut self, by: u32) {
        self.span.shift(by);
        match &mut self.kind {
            StmtKind::Call(c) => {
                c.name.shift(by);
                c.args.shift(by);
                c.args_span.shift(by);
                c.label.shift(by);
                c.span.shift(by);
            }
            StmtKind::While { keyword, cond, body } => {
                keyword.shift(by);
                cond.shift(by);
                body.shift(by);
            }
            StmtKind::If { keyword, cond, then, otherwise, else_written_then } => {
                keyword.shift(by);
                cond.shift(by);
                then.shift(by);
                otherwise.shift(by);
                else_written_then.shift(by);
            }
            StmtKind::Parallel { keyword, branches, ops } => {
                keyword.shift(by);
                branches.shift(by);
                for (_, s) in ops {
                    s.shift(by);
                }
            }
            StmtKind::Try { keyword, body, catch } => {
                keyword.shift(by);
                body.shift(by);
                catch.shift(by);
            }
            StmtKind::Not { keyword, body } => {
                keyword.shift(by);
                body.shift(by);
            }
            StmtKind::Monitor { keyword, body, handlers } => {
                keyword.shift(by);
                body.shift(by);
                for h in handlers {
                    h.keyword_span.shift(by);
                    h.condition.shift(by);
                    h.action.shift(by);
                    h.span.shift(by);
                }
            }
            StmtKind::Error => {}
        }
    }
}

/// Parses `src` item by item ([`crate::parser::split_items`],
/// [`crate::parser::parse_item`]) and assembles the results: the same as
/// [`crate::parse`], the way the compiler's incremental queries see a file.
pub fn parse_by_items(src: &str) -> Parse {
    let mut out = Parse { file: SourceFile::default(), comments: Vec::new(), errors: Vec::new() };
    for b in crate::parser::split_items(src) {
        let mut p = crate::parser::parse_item(&src[b.start..b.end], b.next);
        p.shift(b.start as u32);
        out.file.items.append(&mut p.file.items);
        out.comments.append(&mut p.comments);
        out.errors.append(&mut p.errors);
    }
    out.errors.sort_by_key(|d| (d.span.start, d.span.end));
    out
}
