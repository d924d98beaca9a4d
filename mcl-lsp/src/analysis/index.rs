//! Every name occurrence of a file with its syntactic role, and the symbol
//! each one resolves to. Navigation, rename, hover, highlighting and
//! semantic tokens are all built on this one walk of the syntax tree.

use mcl_compiler::compile::structures::Structure;
use mcl_compiler::queries::parse;
use mcl_compiler::scope::{self, DefId, DefKind};
use mcl_compiler::{Database, Db, SourceFile};
use mcl_syntax::ast::*;
use mcl_syntax::visit::walk_block;
use mcl_syntax::Span;

/// Where a name occurs and what it does there.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// The name of a definition: action, event, pattern, task, named mission.
    Def(DefKind),
    /// A use of a definition: a call (task), a binding target (action,
    /// event), a task's pattern, a constraint's mission.
    Ref(DefKind),
    /// A place or transition declared in the pattern at `(item, index)`.
    PlaceDef {
        pattern: (u32, u32),
    },
    TransitionDef {
        pattern: (u32, u32),
    },
    /// A place or transition named by an arc of the pattern at `(item, index)`.
    ArcEnd {
        pattern: (u32, u32),
    },
    /// A transition named in a binding of the task at `(item, index)`.
    BindingTransition {
        task: (u32, u32),
    },
    /// The label of a call in the mission at `item`.
    LabelDef {
        mission: u32,
    },
    /// A label in a constraint, with the mission written before it, if any.
    LabelRef {
        mission: Option<String>,
    },
    /// A parameter in the header of the task at `(item, index)`.
    TaskParam {
        task: (u32, u32),
    },
    /// A parameter in the header of the mission at `item`.
    MissionParam {
        mission: u32,
    },
    /// An identifier argument of a call in the mission at `item` that names
    /// one of the mission's parameters.
    ParamUse {
        mission: u32,
    },
    /// An identifier argument that is a symbolic value.
    Symbolic,
    /// A `v:` parameter of an action (a task parameter's name).
    ActionParam,
    /// A delay written as a task parameter: `TO(timeout)`.
    DelayParam,
    /// The primitive of an action definition.
    Primitive,
    /// The `c:` command of an action definition.
    Command,
    /// The keyword of a control structure (also `and`/`or` of a parallel,
    /// `else` (or `then`) of an if, `catch` of a try, `condition`,
    /// `while_condition` and `do` of a monitor).
    Structure(Structure),
    /// `mutex`, `order` or `sync` (or `_mutex_`, ...) of a constraint.
    ConstraintKeyword(ConstraintKind),
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Occ {
    pub span: Span,
    pub name: String,
    pub role: Role,
}

/// What an occurrence resolves to; two occurrences are the same symbol when
/// these are equal.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Sym {
    Def(DefId),
    /// A place (`place = true`) or transition of a written pattern.
    Node {
        pattern: DefId,
        place: bool,
        name: String,
    },
    /// A label of the mission at `item` of `file`.
    Label {
        file: SourceFile,
        item: u32,
        name: String,
    },
    /// A parameter of the task at `(item, index)` or of the mission at
    /// `(item, u32::MAX)`.
    Param {
        file: SourceFile,
        item: u32,
        index: u32,
        name: String,
    },
}

impl Sym {
    pub fn name(&self) -> &str {
        match self {
            Sym::Def(_) => "",
            Sym::Node { name, .. } | Sym::Label { name, .. } | Sym::Param { name, .. } => name,
        }
    }
}

/// Every occurrence of a file, in source order (a salsa query of this
/// crate: computed once per revision of the file).
pub fn occurrences(db: &Database, file: SourceFile) -> &[Occ] {
    file_occurrences(db, file)
}

#[salsa::tracked(returns(ref))]
fn file_occurrences(db: &dyn Db, file: SourceFile) -> Vec<Occ> {
    let ast = &parse(db, file).file;
    let text = file.text(db).as_deref().unwrap_or("");
    let mut out = Vec::new();
    let mut push = |span: Span, name: &str, role: Role| {
        if !name.is_empty() {
            out.push(Occ { span, name: name.to_string(), role })
        }
    };
    for (i, item) in ast.items.iter().enumerate() {
        let i = i as u32;
        match item {
            Item::Import(_) => {}
            Item::Actions(b) => {
                for a in &b.actions {
                    push(a.name.span, &a.name.text, Role::Def(DefKind::Action));
                    push(a.primitive.span, &a.primitive.text, Role::Primitive);
                    if let Some(c) = &a.command {
                        push(c.span, &c.text, Role::Command);
                    }
                    for v in &a.params {
                        if let ValueKind::Ident(n) = &v.kind {
                            push(n.span, &n.text, Role::ActionParam);
                        }
                    }
                }
            }
            Item::Events(b) => {
                for e in &b.events {
                    push(e.span, &e.text, Role::Def(DefKind::Event));
                }
            }
            Item::Patterns(b) => {
                for (j, p) in b.patterns.iter().enumerate() {
                    let key = (i, j as u32);
                    push(p.name.span, &p.name.text, Role::Def(DefKind::Pattern));
                    if let PatternBody::Net(n) = &p.body {
                        for pl in &n.places {
                            push(pl.name.span, &pl.name.text, Role::PlaceDef { pattern: key });
                        }
                        for t in &n.transitions {
                            push(t.name.span, &t.name.text, Role::TransitionDef { pattern: key });
                            if let Some(Delay::Param(d)) = &t.delay {
                                push(d.span, &d.text, Role::DelayParam);
                            }
                        }
                        for a in &n.arcs {
                            push(a.source.name.span, &a.source.name.text, Role::ArcEnd { pattern: key });
                            push(a.target.name.span, &a.target.name.text, Role::ArcEnd { pattern: key });
                        }
                    }
                }
            }
            Item::Tasks(b) => {
                for (j, t) in b.tasks.iter().enumerate() {
                    let key = (i, j as u32);
                    push(t.name.span, &t.name.text, Role::Def(DefKind::Task));
                    for p in &t.params {
                        push(p.span, &p.text, Role::TaskParam { task: key });
                    }
                    if let Some(p) = &t.pattern {
                        push(p.span, &p.text, Role::Ref(DefKind::Pattern));
                    }
                    for bd in &t.bindings {
                        let k = if bd.kind == BindingKind::Action { DefKind::Action } else { DefKind::Event };
                        push(bd.target.span, &bd.target.text, Role::Ref(k));
                        for tr in &bd.transitions {
                            push(tr.span, &tr.text, Role::BindingTransition { task: key });
                        }
                    }
                }
            }
            Item::Mission(m) => {
                if let Some(n) = &m.name {
                    push(n.span, &n.text, Role::Def(DefKind::Mission));
                }
                for p in &m.params {
                    push(p.span, &p.text, Role::MissionParam { mission: i });
                }
                let params: Vec<&str> = m.params.iter().map(|p| p.text.as_str()).collect();
                walk_block(&m.body, &mut |s| match &s.kind {
                    StmtKind::Call(c) => {
                        push(c.name.span, &c.name.text, Role::Ref(DefKind::Task));
                        for a in &c.args {
                            value_idents(a, &mut |n| {
                                let role = if params.contains(&n.text.as_str()) {
                                    Role::ParamUse { mission: i }
                                } else {
                                    Role::Symbolic
                                };
                                push(n.span, &n.text, role);
                            });
                        }
                        if let Some(l) = &c.label {
                            push(l.span, &l.text, Role::LabelDef { mission: i });
                        }
                    }
                    kind => {
                        if let Some((structure, mut spans)) = structure_of(kind) {
                            spans.extend(joining_keywords(text, kind));
                            for (sp, word) in spans {
                                push(sp, word, Role::Structure(structure.clone()));
                            }
                        }
                    }
                });
            }
            Item::Constraints(b) => {
                for c in &b.constraints {
                    let word = text.get(c.keyword_span.range()).unwrap_or("");
                    push(c.keyword_span, word, Role::ConstraintKeyword(c.kind));
                    for r in &c.refs {
                        if let Some(m) = &r.mission {
                            push(m.span, &m.text, Role::Ref(DefKind::Mission));
                        }
                        push(
                            r.label.span,
                            &r.label.text,
                            Role::LabelRef { mission: r.mission.as_ref().map(|m| m.text.clone()) },
                        );
                    }
                }
            }
            // The MCL mission operators that planning operators and PDDL actions run.
            Item::Planning(b) => {
                for d in &b.defs {
                    if let PlanDef::Operator(o) = d {
                        for p in &o.parts {
                            if let OpPartKind::Mcl(c) = &p.kind {
                                push(c.name.span, &c.name.text, Role::Ref(DefKind::Mission));
                            }
                        }
                    }
                }
            }
            Item::PddlMap(b) => {
                for m in &b.maps {
                    push(m.call.name.span, &m.call.name.text, Role::Ref(DefKind::Mission));
                }
            }
        }
    }
    out.sort_by_key(|o| (o.span.start, o.span.end));
    out
}

fn value_idents<'a>(v: &'a Value, f: &mut impl FnMut(&'a Name)) {
    match &v.kind {
        ValueKind::Ident(n) => f(n),
        ValueKind::List { items, .. } => items.iter().for_each(|i| value_idents(i, f)),
        _ => {}
    }
}

/// The control structure of a statement and the spans of its keywords.
pub fn structure_of(kind: &StmtKind) -> Option<(Structure, Vec<(Span, &'static str)>)> {
    Some(match kind {
        StmtKind::While { keyword, .. } => (Structure::While, vec![(*keyword, "while")]),
        StmtKind::If { keyword, otherwise, .. } => {
            (if otherwise.is_some() { Structure::IfThenElse } else { Structure::IfThen }, vec![(*keyword, "if")])
        }
        StmtKind::Parallel { keyword, branches, ops } => {
            let s = if ops.first().is_some_and(|(o, _)| *o == ParallelOp::Or) {
                Structure::ParallelOr(branches.len())
            } else {
                Structure::ParallelAnd(branches.len())
            };
            let mut spans = vec![(*keyword, "parallel")];
            spans.extend(ops.iter().map(|(o, sp)| (*sp, if *o == ParallelOp::And { "and" } else { "or" })));
            (s, spans)
        }
        StmtKind::Try { keyword, .. } => (Structure::TryCatch, vec![(*keyword, "try")]),
        StmtKind::Not { keyword, .. } => (Structure::Not, vec![(*keyword, "not")]),
        StmtKind::Monitor { keyword, handlers, .. } => {
            let mut spans = vec![(*keyword, "monitor")];
            spans.extend(handlers.iter().map(|h| {
                (h.keyword_span, if h.kind == MonitorKind::Condition { "condition" } else { "while_condition" })
            }));
            (Structure::Monitor(handlers.iter().map(|h| h.kind).collect()), spans)
        }
        StmtKind::Call(_) | StmtKind::Error => return None,
    })
}

/// The keywords written between a structure's blocks (`else`, `then`,
/// `catch`, `do`), which the syntax tree does not keep.
fn joining_keywords(text: &str, kind: &StmtKind) -> Vec<(Span, &'static str)> {
    let gaps: Vec<(Span, Span)> = match kind {
        StmtKind::If { cond, then, otherwise, .. } => {
            let mut g = vec![(cond.span, then.span)];
            g.extend(otherwise.iter().map(|o| (then.span, o.span)));
            g
        }
        StmtKind::While { cond, body, .. } => vec![(cond.span, body.span)],
        StmtKind::Try { body, catch, .. } => vec![(body.span, catch.span)],
        StmtKind::Monitor { handlers, .. } => handlers.iter().map(|h| (h.condition.span, h.action.span)).collect(),
        _ => vec![],
    };
    let mut out = Vec::new();
    for (before, after) in gaps {
        let (s, e) = (before.end as usize, after.start as usize);
        let Some(gap) = text.get(s..e) else { continue };
        for (tok, sp) in mcl_syntax::lexer::lex(gap).tokens {
            if let mcl_syntax::lexer::Token::Kw(k) = tok {
                if matches!(k.as_str(), "else" | "then" | "catch" | "do") {
                    out.push((Span::new(s + sp.start as usize, s + sp.end as usize), k.as_str()));
                }
            }
        }
    }
    out
}

/// The occurrence under `offset` (a cursor just after a name still counts).
pub fn occurrence_at(occs: &[Occ], offset: usize) -> Option<&Occ> {
    let inside = occs.iter().find(|o| o.span.start as usize <= offset && offset < o.span.end as usize);
    inside.or_else(|| occs.iter().find(|o| o.span.end as usize == offset))
}

/// The pattern definition at `(item, index)` of `file`.
pub fn pattern_def(db: &Database, file: SourceFile, (item, index): (u32, u32)) -> Option<DefId> {
    let Item::Patterns(b) = parse(db, file).file.items.get(item as usize)? else { return None };
    let p = b.patterns.get(index as usize)?;
    // A `DefId` names the item by its part of the file (`file_items`).
    let part = mcl_compiler::queries::part_of_item(db, file, item)?;
    Some(DefId {
        kind: DefKind::Pattern,
        file,
        item: part,
        index,
        name_span: p.name.span,
        in_stdlib: file == db.stdlib(),
        local: false,
    })
}

/// The task definition at `(item, index)` of `file`.
pub fn task_at(db: &Database, file: SourceFile, (item, index): (u32, u32)) -> Option<&TaskDef> {
    match parse(db, file).file.items.get(item as usize)? {
        Item::Tasks(b) => b.tasks.get(index as usize),
        _ => None,
    }
}

/// The mission at `item` of `file`.
pub fn mission_at(db: &Database, file: SourceFile, item: u32) -> Option<&Mission> {
    match parse(db, file).file.items.get(item as usize)? {
        Item::Mission(m) => Some(m),
        _ => None,
    }
}

/// The written net of a pattern (`None` for a PNML pattern).
pub fn written_net(db: &Database, id: DefId) -> Option<&PatternNet> {
    match &scope::pattern(db, id)?.body {
        PatternBody::Net(n) => Some(n),
        PatternBody::File { .. } => None,
    }
}

/// The net of a pattern, written or read from its PNML file.
pub fn any_net(db: &Database, id: DefId) -> Option<&PatternNet> {
    scope::pattern_net(db, id)?.ok()
}

/// The missions a program sees, with their file and item index.
pub fn missions_with_items(db: &Database, root: SourceFile) -> Vec<(SourceFile, u32, &Mission)> {
    let mut out = Vec::new();
    for &f in &mcl_compiler::queries::program(db, root).files {
        for (i, item) in parse(db, f).file.items.iter().enumerate() {
            if let Item::Mission(m) = item {
                out.push((f, i as u32, m));
            }
        }
    }
    out
}

fn has_label(m: &Mission, label: &str) -> bool {
    mcl_syntax::visit::calls(&m.body).iter().any(|c| c.label.as_ref().is_some_and(|l| l.text == label))
}

/// What an occurrence of `file` resolves to, with `file` as the root of the
/// program (as `check_file` sees it).
pub fn resolve(db: &Database, file: SourceFile, occ: &Occ) -> Option<Sym> {
    let name = occ.name.as_str();
    match &occ.role {
        Role::Def(k) => {
            let defs = scope::scope(db, file).get(*k, name);
            defs.iter().find(|d| d.file == file && d.name_span == occ.span).copied().map(Sym::Def)
        }
        Role::Ref(k) => scope::scope(db, file).first(*k, name).map(Sym::Def),
        Role::PlaceDef { pattern } => {
            Some(Sym::Node { pattern: pattern_def(db, file, *pattern)?, place: true, name: name.to_string() })
        }
        Role::TransitionDef { pattern } => {
            Some(Sym::Node { pattern: pattern_def(db, file, *pattern)?, place: false, name: name.to_string() })
        }
        Role::ArcEnd { pattern } => {
            let id = pattern_def(db, file, *pattern)?;
            let net = written_net(db, id)?;
            let place = if net.places.iter().any(|p| p.name.text == name) {
                true
            } else if net.transitions.iter().any(|t| t.name.text == name) {
                false
            } else {
                return None;
            };
            Some(Sym::Node { pattern: id, place, name: name.to_string() })
        }
        Role::BindingTransition { task } => {
            let t = task_at(db, file, *task)?;
            let pid = scope::scope(db, file).first(DefKind::Pattern, &t.pattern.as_ref()?.text)?;
            let net = any_net(db, pid)?;
            net.transitions.iter().any(|t| t.name.text == name).then(|| Sym::Node {
                pattern: pid,
                place: false,
                name: name.to_string(),
            })
        }
        Role::LabelDef { mission } => Some(Sym::Label { file, item: *mission, name: name.to_string() }),
        Role::LabelRef { mission } => {
            let all = missions_with_items(db, file);
            let owner = match mission {
                Some(m) => all.iter().find(|(_, _, x)| x.name.as_ref().is_some_and(|n| n.text == *m)),
                None => {
                    let owners: Vec<_> = all.iter().filter(|(_, _, m)| has_label(m, name)).collect();
                    if owners.len() == 1 {
                        owners.first().copied()
                    } else {
                        None
                    }
                }
            }?;
            has_label(owner.2, name).then(|| Sym::Label { file: owner.0, item: owner.1, name: name.to_string() })
        }
        Role::TaskParam { task } => Some(Sym::Param { file, item: task.0, index: task.1, name: name.to_string() }),
        Role::MissionParam { mission } | Role::ParamUse { mission } => {
            Some(Sym::Param { file, item: *mission, index: u32::MAX, name: name.to_string() })
        }
        Role::Symbolic
        | Role::ActionParam
        | Role::DelayParam
        | Role::Primitive
        | Role::Command
        | Role::Structure(_)
        | Role::ConstraintKeyword(_) => None,
    }
}

/// The name of a symbol, as written in the source.
pub fn sym_name(db: &Database, sym: &Sym) -> String {
    match sym {
        Sym::Def(d) => {
            let text = d.file.text(db).as_deref().unwrap_or("");
            text.get(d.name_span.range()).unwrap_or("").to_string()
        }
        other => other.name().to_string(),
    }
}

/// The file that defines a symbol (where it can be renamed from).
pub fn sym_file(sym: &Sym) -> SourceFile {
    match sym {
        Sym::Def(d) => d.file,
        Sym::Node { pattern, .. } => pattern.file,
        Sym::Label { file, .. } | Sym::Param { file, .. } => *file,
    }
}
