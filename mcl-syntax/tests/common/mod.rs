//! Helpers shared by the integration tests: a compact rendering of the tree
//! (so that tests can assert on the whole shape of a parse), a readable
//! rendering of diagnostics, and the invariants every parse must satisfy.
#![allow(dead_code)]

use mcl_syntax::ast::*;
use mcl_syntax::{LineIndex, Parse};
use std::fmt::Write as _;

/// Renders a file as one s-expression per item, one per line.
pub fn sexp(file: &SourceFile) -> String {
    file.items.iter().map(item).collect::<Vec<_>>().join("\n")
}

pub fn item(i: &Item) -> String {
    match i {
        Item::Import(x) => format!("(import {:?})", x.path),
        Item::Actions(a) => {
            let defs: Vec<String> = a
                .actions
                .iter()
                .map(|d| {
                    let mut s = format!("({} = {}", d.name.text, d.primitive.text);
                    match &d.command {
                        Some(c) => {
                            let _ = write!(s, " c:{}", c.text);
                        }
                        None => s.push_str(" c:?"),
                    }
                    for p in &d.params {
                        let _ = write!(s, " v:{}", value(p));
                    }
                    s.push(')');
                    s
                })
                .collect();
            format!("(actions{})", prefixed(&defs))
        }
        Item::Events(e) => {
            let names: Vec<String> = e.events.iter().map(|n| n.text.clone()).collect();
            format!("(events{})", prefixed(&names))
        }
        Item::Patterns(p) => {
            let pats: Vec<String> = p.patterns.iter().map(pattern).collect();
            format!("(pattern{})", prefixed(&pats))
        }
        Item::Tasks(t) => {
            let tasks: Vec<String> = t
                .tasks
                .iter()
                .map(|t| {
                    let params: Vec<&str> = t.params.iter().map(|p| p.text.as_str()).collect();
                    let mut s = format!("({}({})", t.name.text, params.join(" "));
                    if let Some(p) = &t.pattern {
                        let _ = write!(s, ": {}", p.text);
                    }
                    for b in &t.bindings {
                        let k = match b.kind {
                            BindingKind::Action => "a",
                            BindingKind::Event => "e",
                        };
                        let ts: Vec<&str> = b.transitions.iter().map(|t| t.text.as_str()).collect();
                        let _ = write!(s, " ({k} {} -> {})", b.target.text, ts.join(" "));
                    }
                    s.push(')');
                    s
                })
                .collect();
            format!("(tasks{})", prefixed(&tasks))
        }
        Item::Mission(m) => {
            let mut s = String::from(match m.kind {
                MissionKind::Mission => "(mission",
                MissionKind::PlanOp => "(mcl_plan_op",
            });
            if let Some(n) = &m.name {
                let _ = write!(s, " {}", n.text);
            }
            if !m.params.is_empty() || m.kind == MissionKind::PlanOp {
                let ps: Vec<&str> = m.params.iter().map(|p| p.text.as_str()).collect();
                let _ = write!(s, "({})", ps.join(" "));
            }
            if let Some((n, num)) = &m.placement {
                let _ = write!(s, " [{} at {}]", n.text, num.text);
            }
            let _ = write!(s, " {})", block(&m.body));
            s
        }
        Item::Constraints(c) => {
            let cs: Vec<String> = c
                .constraints
                .iter()
                .map(|c| {
                    let kw =
                        if c.bnf_spelling { format!("_{}_", c.kind.as_str()) } else { c.kind.as_str().to_string() };
                    let refs: Vec<String> = c
                        .refs
                        .iter()
                        .map(|r| match &r.mission {
                            Some(m) => format!("{}:{}", m.text, r.label.text),
                            None => r.label.text.clone(),
                        })
                        .collect();
                    let mut s = format!("({kw} {}", refs.join(" "));
                    if let Some(b) = &c.bound {
                        let _ = write!(s, " = {}", b.text);
                    }
                    s.push(')');
                    s
                })
                .collect();
            format!("(constraints{})", prefixed(&cs))
        }
        Item::Planning(_) | Item::PddlMap(_) => {
            let f = mcl_syntax::format::normalize(&SourceFile { items: vec![i.clone()] });
            format!("{:?}", f.items[0])
        }
    }
}

fn prefixed(xs: &[String]) -> String {
    xs.iter().map(|x| format!(" {x}")).collect()
}

fn iface(n: &Option<Number>) -> String {
    n.as_ref().map(|n| format!(".{}", n.text)).unwrap_or_default()
}

pub fn pattern(p: &Pattern) -> String {
    match &p.body {
        PatternBody::File { path, .. } => format!("({} file {:?})", p.name.text, path),
        PatternBody::Net(net) => {
            let places: Vec<String> = net
                .places
                .iter()
                .map(|pl| {
                    let toks = pl.tokens.as_ref().map(|t| format!("({})", t.text)).unwrap_or_default();
                    format!("{}{}{}", pl.name.text, iface(&pl.interface), toks)
                })
                .collect();
            let trans: Vec<String> = net
                .transitions
                .iter()
                .map(|t| {
                    let d = match &t.delay {
                        Some(Delay::Fixed(n)) => format!("({})", n.text),
                        Some(Delay::Param(n)) => format!("(${})", n.text),
                        None => String::new(),
                    };
                    format!("{}{}{}", t.name.text, iface(&t.interface), d)
                })
                .collect();
            let arcs: Vec<String> = net
                .arcs
                .iter()
                .map(|a| {
                    let w = a.weight.as_ref().map(|w| format!("({})", w.text)).unwrap_or_default();
                    format!(
                        "{}{}->{}{}{}",
                        a.source.name.text,
                        iface(&a.source.interface),
                        a.target.name.text,
                        iface(&a.target.interface),
                        w
                    )
                })
                .collect();
            format!(
                "({} (places {}) (transitions {}) (arcs {}))",
                p.name.text,
                places.join(" "),
                trans.join(" "),
                arcs.join(" ")
            )
        }
    }
}

pub fn value(v: &Value) -> String {
    match &v.kind {
        ValueKind::Ident(n) => n.text.clone(),
        ValueKind::Number(n) => n.text.clone(),
        ValueKind::Str(s) => format!("{s:?}"),
        ValueKind::List { tag, items } => {
            let items: Vec<String> = items.iter().map(value).collect();
            format!("{}[{}]", tag.as_ref().map(|t| t.text.as_str()).unwrap_or(""), items.join(" "))
        }
        ValueKind::Error => "<error>".to_string(),
    }
}

/// A block as `{a; b}`.
pub fn block(b: &Block) -> String {
    let stmts: Vec<String> = b.stmts.iter().map(stmt).collect();
    format!("{{{}}}", stmts.join("; "))
}

pub fn stmt(s: &Stmt) -> String {
    match &s.kind {
        StmtKind::Call(c) => {
            let args: Vec<String> = c.args.iter().map(value).collect();
            let label = c.label.as_ref().map(|l| format!(":{}", l.text)).unwrap_or_default();
            format!("{}({}){}", c.name.text, args.join(" "), label)
        }
        StmtKind::While { cond, body, .. } => format!("(while {} {})", block(cond), block(body)),
        StmtKind::If { cond, then, otherwise, else_written_then, .. } => {
            let mut s = format!("(if {} {}", block(cond), block(then));
            if let Some(o) = otherwise {
                let kw = if else_written_then.is_some() { "then" } else { "else" };
                let _ = write!(s, " {kw} {}", block(o));
            }
            s.push(')');
            s
        }
        StmtKind::Parallel { branches, ops, .. } => {
            let mut s = format!("(parallel {}", block(&branches[0]));
            for (b, (op, _)) in branches[1..].iter().zip(ops) {
                let op = match op {
                    ParallelOp::And => "and",
                    ParallelOp::Or => "or",
                };
                let _ = write!(s, " {op} {}", block(b));
            }
            s.push(')');
            s
        }
        StmtKind::Try { body, catch, .. } => {
            format!("(try {} catch {})", block(body), block(catch))
        }
        StmtKind::Not { body, .. } => format!("(not {})", block(body)),
        StmtKind::Monitor { body, handlers, .. } => {
            let mut s = format!("(monitor {}", block(body));
            for h in handlers {
                let kw = match h.kind {
                    MonitorKind::Condition => "condition",
                    MonitorKind::WhileCondition => "while_condition",
                };
                let _ = write!(s, " {kw} {} do {}", block(&h.condition), block(&h.action));
            }
            s.push(')');
            s
        }
        StmtKind::Error => "<error>".to_string(),
    }
}

/// Renders diagnostics as `line:col severity code message`, followed by the
/// source line with carets under the span, the labels and the help.
pub fn render_errors(src: &str, p: &Parse) -> String {
    let idx = LineIndex::new(src);
    let mut out = String::new();
    for d in &p.errors {
        let lc = idx.line_col(src, d.span.start as usize);
        let _ = writeln!(out, "{}:{} {} {} {}", lc.line, lc.column, d.severity.as_str(), d.code, d.message);
        excerpt(src, &idx, d.span, &mut out);
        for l in &d.labels {
            let lc = idx.line_col(src, l.span.start as usize);
            let _ = writeln!(out, "    label {}:{}: {}", lc.line, lc.column, l.message);
        }
        if let Some(h) = &d.help {
            let _ = writeln!(out, "    help: {h}");
        }
    }
    if out.is_empty() {
        out.push_str("(no diagnostics)\n");
    }
    out
}

fn excerpt(src: &str, idx: &LineIndex, span: mcl_syntax::Span, out: &mut String) {
    let start = idx.line_col(src, span.start as usize);
    let line0 = start.line as usize - 1;
    let ls = idx.line_start(line0);
    let le = idx.line_start(line0 + 1).min(src.len());
    let text = src[ls..le].trim_end_matches(['\n', '\r']);
    let end_col = if idx.line_of(span.end as usize) == line0 {
        idx.line_col(src, span.end as usize).column
    } else {
        text.chars().count() as u32 + 1
    };
    let width = (end_col.saturating_sub(start.column)).max(1) as usize;
    let _ = writeln!(out, "    | {text}");
    let _ = writeln!(out, "    | {}{}", " ".repeat(start.column as usize - 1), "^".repeat(width));
}

/// The invariants of every parse: spans lie within the text, on character
/// boundaries, and errors are sorted.
pub fn check_invariants(src: &str, p: &Parse) {
    let ok = |s: mcl_syntax::Span, what: &str| {
        assert!(s.start <= s.end, "{what}: reversed span {s:?}");
        assert!(s.end as usize <= src.len(), "{what}: span {s:?} beyond the text ({} bytes)", src.len());
        assert!(src.is_char_boundary(s.start as usize), "{what}: span start {s:?} not on a char boundary");
        assert!(src.is_char_boundary(s.end as usize), "{what}: span end {s:?} not on a char boundary");
    };
    for d in &p.errors {
        ok(d.span, &format!("error {} {}", d.code, d.message));
        for l in &d.labels {
            ok(l.span, &format!("label of {}", d.code));
        }
    }
    for w in p.errors.windows(2) {
        assert!(w[0].span.start <= w[1].span.start, "errors not sorted");
    }
    for c in &p.comments {
        ok(c.span, "comment");
    }
    for i in &p.file.items {
        ok(i.span(), "item");
        if let Item::Mission(m) = i {
            ok(m.body.span, "mission body");
            mcl_syntax::visit::walk_block(&m.body, &mut |s| ok(s.span, "statement"));
        }
    }
}
