//! The planning model written in MCL: the `planning { ... }` blocks of an
//! .mcl program (a file and everything it imports) turned into the
//! planner's [`Domain`] and [`Problem`], and the `pddl_map { ... }` blocks
//! applied to a PDDL domain (docs/planning.md, section 1).
//!
//! The compiler checks these blocks (codes E07xx, `mcl check`, the editor);
//! this module trusts nothing and reports what it cannot convert with the
//! file, line and column, so that `mcl plan` never panics on bad input.
//!
//! Names are lower-cased as PDDL reads them (the plans, the world modeler's
//! scripts and the validator speak lower case); MCL mission names keep their
//! case.

use crate::pddl::{
    Action, Atom, CmpOp, Cond, Domain, Fact, Literal, MclArg, MclCall, NumExpr, Problem, Signature, Term, TypedName,
    Value, OBJECT,
};
use crate::sexpr::Error;
use mcl_syntax::ast::{self, Item, OpPartKind, OperandKind, PlanDef, ValueKind};
use mcl_syntax::span::LineIndex;
use mcl_syntax::{Severity, Span};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One parsed file of an .mcl program.
pub struct McFile {
    pub path: PathBuf,
    pub text: String,
    pub items: Vec<Item>,
}

impl McFile {
    fn error(&self, span: Span, message: impl Into<String>) -> Error {
        let index = LineIndex::new(&self.text);
        let lc = index.line_col(&self.text, (span.start as usize).min(self.text.len()));
        Error {
            file: self.path.display().to_string(),
            line: lc.line as usize,
            column: lc.column as usize,
            message: message.into(),
        }
    }

    fn planning(&self) -> impl Iterator<Item = &ast::PlanningBlock> {
        self.items.iter().filter_map(|i| if let Item::Planning(b) = i { Some(b) } else { None })
    }

    fn maps(&self) -> impl Iterator<Item = &ast::PddlMapping> {
        self.items.iter().filter_map(|i| if let Item::PddlMap(b) = i { Some(b) } else { None }).flat_map(|b| &b.maps)
    }
}

/// An .mcl program: the root file and the files it imports, each once.
pub struct McProgram {
    pub files: Vec<McFile>,
}

impl McProgram {
    /// Reads `path` and its imports (transitively). Unreadable files and
    /// syntax errors are errors.
    pub fn load(path: &Path) -> Result<McProgram, Vec<Error>> {
        let mut files = Vec::new();
        let mut errors = Vec::new();
        let mut seen: Vec<PathBuf> = Vec::new();
        let mut todo = vec![path.to_path_buf()];
        while let Some(p) = todo.pop() {
            let key = p.canonicalize().unwrap_or_else(|_| p.clone());
            if seen.contains(&key) {
                continue;
            }
            seen.push(key);
            let text = match mcl_net::input::read_source(&p) {
                Ok(t) => t,
                Err(e) => {
                    errors.push(Error {
                        file: p.display().to_string(),
                        line: 1,
                        column: 1,
                        message: format!("cannot read: {}", e.reason),
                    });
                    continue;
                }
            };
            let parsed = mcl_syntax::parse(&text);
            let file = McFile { path: p.clone(), text, items: parsed.file.items };
            for d in parsed.errors.iter().filter(|d| d.severity == Severity::Error) {
                errors.push(file.error(d.span, format!("{} ({})", d.message, d.code)));
            }
            let dir = p.parent().unwrap_or(Path::new(".")).to_path_buf();
            for i in &file.items {
                if let Item::Import(imp) = i {
                    todo.push(dir.join(&imp.path));
                }
            }
            files.push(file);
        }
        if errors.is_empty() {
            Ok(McProgram { files })
        } else {
            Err(errors)
        }
    }

    /// Whether the program defines a planning problem in MCL (a `planning`
    /// block with at least one definition).
    pub fn has_planning(&self) -> bool {
        self.files.iter().any(|f| f.planning().any(|b| !b.defs.is_empty()))
    }

    /// Whether the program maps PDDL actions to missions.
    pub fn has_pddl_map(&self) -> bool {
        self.files.iter().any(|f| f.maps().next().is_some())
    }
}

fn lower(n: &ast::Name) -> String {
    n.text.to_ascii_lowercase()
}

fn value_of(f: &McFile, v: &ast::Value, errors: &mut Vec<Error>) -> Option<Value> {
    match &v.kind {
        ValueKind::Number(n) => match n.text.parse::<f64>() {
            Ok(x) if x.is_finite() => Some(Value::Num(x)),
            _ => {
                errors.push(f.error(v.span, format!("`{}` is not a number the planner can use", n.text)));
                None
            }
        },
        ValueKind::Str(s) => Some(Value::Str(s.clone())),
        _ => {
            errors.push(f.error(v.span, "expected a number or a string"));
            None
        }
    }
}

/// The planning model of the program as a domain and a problem.
pub fn to_model(prog: &McProgram) -> Result<(Domain, Problem), Vec<Error>> {
    let mut errors = Vec::new();
    let root = prog.files.first().map(|f| f.path.clone()).unwrap_or_default();
    let name = root.file_stem().map(|s| s.to_string_lossy().to_ascii_lowercase()).unwrap_or_else(|| "mcl".into());
    let file_name = root.display().to_string();
    let mut d = Domain { file: file_name.clone(), name: name.clone(), ..Domain::default() };
    let mut p = Problem { file: file_name, name: name.clone(), domain: name, ..Problem::default() };
    // Relations and their arity (the first use decides).
    let mut relations: BTreeMap<String, usize> = BTreeMap::new();
    let mut attrs: BTreeMap<String, ()> = BTreeMap::new();
    let mut has_goal = false;
    let entity_names: Vec<String> = prog
        .files
        .iter()
        .flat_map(|f| f.planning())
        .flat_map(|b| &b.defs)
        .filter_map(|d| if let PlanDef::Entity(e) = d { Some(lower(&e.name)) } else { None })
        .collect();
    for f in &prog.files {
        for b in f.planning() {
            for def in &b.defs {
                match def {
                    PlanDef::Type(t) => {
                        let parent = t.parent.as_ref().map(lower).unwrap_or_else(|| OBJECT.to_string());
                        d.types.push((lower(&t.name), parent));
                        for a in &t.attrs {
                            attrs.insert(lower(a), ());
                        }
                    }
                    PlanDef::Entity(e) => {
                        p.objects.push(TypedName { name: lower(&e.name), types: vec![lower(&e.ty)] });
                        for v in &e.values {
                            if let Some(x) = value_of(f, &v.value, &mut errors) {
                                p.values.push((lower(&v.name), vec![lower(&e.name)], x));
                            }
                        }
                    }
                    PlanDef::Function(x) => d.functions.push(Signature {
                        name: lower(&x.name),
                        params: x
                            .params
                            .iter()
                            .enumerate()
                            .map(|(i, t)| TypedName { name: format!("?a{i}"), types: vec![lower(t)] })
                            .collect(),
                    }),
                    PlanDef::Operator(o) => {
                        if let Some(a) = operator(f, o, &entity_names, &mut relations, &mut errors) {
                            p.metric |= a.cost.is_some();
                            d.actions.push(a);
                        }
                    }
                    PlanDef::Facts(x) => {
                        has_goal |= x.goal;
                        for fact in &x.facts {
                            let args: Vec<String> = fact.args().map(lower).collect();
                            note_relation(f, fact, &mut relations, &mut errors);
                            let g = Fact { pred: lower(&fact.relation), args };
                            if x.goal {
                                p.goal.push((g, fact.negated.is_none()));
                            } else if fact.negated.is_some() {
                                errors.push(f.error(
                                    fact.span,
                                    "the initial state lists the facts that are true: remove `not` (closed world)",
                                ));
                            } else {
                                p.init.push(g);
                            }
                        }
                        for v in &x.values {
                            if let Some(val) = value_of(f, &v.value, &mut errors) {
                                p.values.push((lower(&v.name), v.args.iter().map(lower).collect(), val));
                            }
                        }
                    }
                }
            }
        }
    }
    for a in attrs.keys() {
        if !d.functions.iter().any(|s| &s.name == a) {
            d.functions.push(Signature {
                name: a.clone(),
                params: vec![TypedName { name: "?e".into(), types: vec![OBJECT.into()] }],
            });
        }
    }
    for (r, n) in relations {
        d.predicates.push(Signature {
            name: r,
            params: (0..n).map(|i| TypedName { name: format!("?a{i}"), types: vec![OBJECT.into()] }).collect(),
        });
    }
    if !has_goal && errors.is_empty() {
        errors.push(Error {
            file: p.file.clone(),
            line: 1,
            column: 1,
            message: "the planning model has no `goal { ... }`".into(),
        });
    }
    if errors.is_empty() {
        Ok((d, p))
    } else {
        Err(errors)
    }
}

fn note_relation(f: &McFile, fact: &ast::PlanFact, relations: &mut BTreeMap<String, usize>, errors: &mut Vec<Error>) {
    let n = 1 + usize::from(fact.object.is_some());
    let r = lower(&fact.relation);
    match relations.get(&r) {
        Some(&m) if m != n => errors.push(f.error(
            fact.relation.span,
            format!(
                "relation `{}` relates {m} entit{} elsewhere, {n} here",
                fact.relation.text,
                if m == 1 { "y" } else { "ies" }
            ),
        )),
        Some(_) => {}
        None => {
            relations.insert(r, n);
        }
    }
}

fn operator(
    f: &McFile,
    o: &ast::PlanOperator,
    entities: &[String],
    relations: &mut BTreeMap<String, usize>,
    errors: &mut Vec<Error>,
) -> Option<Action> {
    let before = errors.len();
    let params: Vec<String> = o.params.iter().map(|p| lower(&p.name)).collect();
    let term = |n: &ast::Name, errors: &mut Vec<Error>| -> Term {
        let l = lower(n);
        match params.iter().position(|p| *p == l) {
            Some(i) => Term::Var(i),
            None => {
                if !entities.contains(&l) {
                    errors.push(f.error(
                        n.span,
                        format!("`{}` is neither a parameter of operator `{}` nor an entity", n.text, o.name.text),
                    ));
                }
                Term::Obj(l)
            }
        }
    };
    let num = |x: &ast::PlanOperand, errors: &mut Vec<Error>| -> NumExpr {
        match &x.kind {
            OperandKind::Literal(v) => match value_of(f, v, errors) {
                Some(Value::Num(n)) => NumExpr::Num(n),
                _ => {
                    errors.push(f.error(x.span, "expected a number"));
                    NumExpr::Num(0.0)
                }
            },
            OperandKind::Attr(e, a) => NumExpr::Fluent(lower(a), vec![term(e, errors)]),
            OperandKind::Function(n, args) => NumExpr::Fluent(lower(n), args.iter().map(|a| term(a, errors)).collect()),
            OperandKind::Name(n) => {
                errors.push(f.error(
                    x.span,
                    format!("`{}` is an entity, not a number: compare its attributes (`{}.x`)", n.text, n.text),
                ));
                NumExpr::Num(0.0)
            }
        }
    };
    let mut a = Action {
        name: lower(&o.name),
        params: o
            .params
            .iter()
            .map(|p| TypedName { name: format!("?{}", lower(&p.name)), types: vec![lower(&p.ty)] })
            .collect(),
        pre: Vec::new(),
        conds: Vec::new(),
        add: Vec::new(),
        del: Vec::new(),
        cost: None,
        mcl: None,
        line: f.error(o.name.span, "").line,
    };
    for part in &o.parts {
        match &part.kind {
            OpPartKind::Precond(v) | OpPartKind::Add(v) | OpPartKind::Del(v) => {
                for fact in v {
                    note_relation(f, fact, relations, errors);
                    let atom =
                        Atom { pred: lower(&fact.relation), args: fact.args().map(|n| term(n, errors)).collect() };
                    match &part.kind {
                        OpPartKind::Precond(_) => a.pre.push(Literal { atom, positive: fact.negated.is_none() }),
                        _ if fact.negated.is_some() => errors.push(f.error(
                            fact.span,
                            format!("`not` has no meaning in `{}`: a deleted fact goes in `del`", part.kind.keyword()),
                        )),
                        OpPartKind::Add(_) => a.add.push(atom),
                        _ => a.del.push(atom),
                    }
                }
            }
            OpPartKind::Expression(v) => {
                for x in v {
                    let op = match x.op.as_str() {
                        "!=" => CmpOp::Ne,
                        "==" | "=" => CmpOp::Eq,
                        "<" => CmpOp::Lt,
                        "<=" => CmpOp::Le,
                        ">" => CmpOp::Gt,
                        ">=" => CmpOp::Ge,
                        other => {
                            errors.push(f.error(x.op_span, format!("unknown comparison `{other}`")));
                            continue;
                        }
                    };
                    match (&x.left.kind, &x.right.kind, op) {
                        (OperandKind::Name(l), OperandKind::Name(r), CmpOp::Eq | CmpOp::Ne) => {
                            a.conds.push(Cond::Equal(term(l, errors), term(r, errors), op == CmpOp::Eq))
                        }
                        _ => a.conds.push(Cond::Compare(op, num(&x.left, errors), num(&x.right, errors))),
                    }
                }
            }
            OpPartKind::Cost(c) => {
                if a.cost.is_some() {
                    errors.push(f.error(part.keyword_span, format!("operator `{}` has two costs", o.name.text)));
                }
                a.cost = Some(num(c, errors));
            }
            OpPartKind::Mcl(c) => {
                if a.mcl.is_some() {
                    errors
                        .push(f.error(part.keyword_span, format!("operator `{}` runs two MCL missions", o.name.text)));
                }
                let mut args = Vec::new();
                for x in &c.args {
                    args.push(match &x.kind {
                        OperandKind::Literal(v) => match &v.kind {
                            ValueKind::Number(n) => MclArg::Num(n.text.clone()),
                            ValueKind::Str(s) => MclArg::Str(s.clone()),
                            _ => MclArg::Symbol(String::new()),
                        },
                        OperandKind::Attr(e, at) => MclArg::Attr(term(e, errors), lower(at)),
                        OperandKind::Name(n) => {
                            let l = lower(n);
                            match params.iter().position(|p| *p == l) {
                                Some(i) => MclArg::Object(Term::Var(i)),
                                None if entities.contains(&l) => MclArg::Object(Term::Obj(l)),
                                None => MclArg::Symbol(n.text.clone()),
                            }
                        }
                        OperandKind::Function(n, _) => {
                            errors.push(f.error(
                                x.span,
                                format!("`{}( ... )`: an `mcl` argument is a parameter, an attribute `p.x`, a number, a string or a symbol", n.text),
                            ));
                            continue;
                        }
                    });
                }
                let lc = f.error(c.name.span, "");
                a.mcl = Some(MclCall {
                    name: c.name.text.clone(),
                    args,
                    line: lc.line,
                    column: lc.column,
                    file: Some(lc.file),
                });
            }
        }
    }
    (errors.len() == before).then_some(a)
}

/// Gives the actions of a PDDL domain the MCL missions of the program's
/// `pddl_map` blocks. An action with a `:mcl` field and a mapping takes the
/// mapping. Errors: a mapping names an unknown action, gives it the wrong
/// number of parameters, or uses a name that is not one of them.
pub fn apply_pddl_map(prog: &McProgram, d: &mut Domain) -> Result<(), Vec<Error>> {
    let mut errors = Vec::new();
    let mut seen: Vec<String> = Vec::new();
    for f in &prog.files {
        for m in f.maps() {
            let name = lower(&m.action);
            if seen.contains(&name) {
                errors.push(f.error(m.action.span, format!("action `{}` is mapped twice", m.action.text)));
                continue;
            }
            seen.push(name.clone());
            let known: Vec<String> = d.actions.iter().map(|a| a.name.clone()).collect();
            let Some(a) = d.actions.iter_mut().find(|a| a.name == name) else {
                errors.push(f.error(
                    m.action.span,
                    format!(
                        "the PDDL domain `{}` ({}) has no action `{}` (it has: {})",
                        d.name,
                        d.file,
                        m.action.text,
                        if known.is_empty() { "none".into() } else { known.join(", ") }
                    ),
                ));
                continue;
            };
            if a.params.len() != m.params.len() {
                let ps: Vec<&str> = a.params.iter().map(|p| p.name.as_str()).collect();
                errors.push(f.error(
                    m.action.span,
                    format!(
                        "action `{}` has {} parameter(s) ({}) in {}, the mapping names {}",
                        a.name,
                        a.params.len(),
                        ps.join(" "),
                        d.file,
                        m.params.len()
                    ),
                ));
                continue;
            }
            let names: Vec<String> = m.params.iter().map(lower).collect();
            let var = |n: &ast::Name, errors: &mut Vec<Error>| -> Option<usize> {
                let p = names.iter().position(|x| *x == lower(n));
                if p.is_none() {
                    errors.push(f.error(
                        n.span,
                        format!(
                            "`{}` is not a parameter of the mapping `{}( {} )`",
                            n.text,
                            m.action.text,
                            names.join(", ")
                        ),
                    ));
                }
                p
            };
            let mut args = Vec::new();
            for x in &m.call.args {
                match &x.kind {
                    OperandKind::Literal(v) => match &v.kind {
                        ValueKind::Number(n) => args.push(MclArg::Num(n.text.clone())),
                        ValueKind::Str(s) => args.push(MclArg::Str(s.clone())),
                        _ => {}
                    },
                    OperandKind::Attr(e, at) => {
                        if let Some(i) = var(e, &mut errors) {
                            args.push(MclArg::Attr(Term::Var(i), lower(at)));
                        }
                    }
                    OperandKind::Name(n) => match names.iter().position(|x| *x == lower(n)) {
                        Some(i) => args.push(MclArg::Object(Term::Var(i))),
                        None => args.push(MclArg::Symbol(n.text.clone())),
                    },
                    OperandKind::Function(n, _) => errors.push(f.error(
                        x.span,
                        format!("`{}( ... )`: a mapping argument is a parameter, an attribute `p.x`, a number, a string or a symbol", n.text),
                    )),
                }
            }
            let lc = f.error(m.call.name.span, "");
            a.mcl = Some(MclCall {
                name: m.call.name.text.clone(),
                args,
                line: lc.line,
                column: lc.column,
                file: Some(lc.file),
            });
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors)
    }
}
