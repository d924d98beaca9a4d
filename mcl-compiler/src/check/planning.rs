//! Checks of the planning model written in MCL (seed chapter 7,
//! docs/planning.md): `planning { ... }` and `pddl_map { ... }`.
//!
//! Each `planning` block is checked on its own: its types, entities,
//! functions and operators refer to each other (E0701 unknown type, E0702
//! unknown entity or unbound variable, E0703 unknown attribute or function,
//! E0704 relation used with two arities, E0706 duplicates); the `mcl` line of
//! an operator and the right side of a mapping name a mission of the program
//! with as many parameters as arguments (E0705); a mapping's attributes are
//! taken from its own parameters (E0707).

use super::Cx;
use crate::codes;
use crate::scope::{self, DefKind};
use mcl_syntax::ast::*;
use mcl_syntax::{Diagnostic, Span};
use std::collections::{HashMap, HashSet};

pub(crate) fn check(cx: &mut Cx<'_>) {
    for item in &cx.ast().items {
        match item {
            Item::Planning(b) => check_planning(cx, b),
            Item::PddlMap(b) => check_map(cx, b),
            _ => {}
        }
    }
}

/// The root of the type hierarchy (as in PDDL).
const OBJECT: &str = "object";

struct Model<'a> {
    types: HashMap<&'a str, &'a PlanType>,
    entities: HashMap<&'a str, &'a PlanEntity>,
    functions: HashMap<&'a str, &'a PlanFunction>,
    /// Relation name: arity and first use.
    relations: HashMap<&'a str, (usize, Span)>,
}

impl<'a> Model<'a> {
    /// The attributes of a type and of its ancestors.
    fn attrs(&self, ty: &str) -> Vec<&'a Name> {
        let mut out = Vec::new();
        let mut t = ty;
        for _ in 0..64 {
            let Some(pt) = self.types.get(t) else { break };
            out.extend(pt.attrs.iter());
            match &pt.parent {
                Some(p) => t = &p.text,
                None => break,
            }
        }
        out
    }
}

fn duplicate(cx: &mut Cx<'_>, what: &str, name: &Name, first: &Name) {
    cx.out.push(
        Diagnostic::error(codes::PLAN_DUPLICATE, format!("{what} `{}` is defined twice", name.text), name.span)
            .with_label(first.span, "first defined here")
            .with_help(format!("rename or remove one of the two; each {what} has one definition")),
    );
}

/// A relation that an operator's precondition or the goal needs, but that
/// no initial fact has and no operator adds, never holds; when it is spelt
/// like one that does (two edits at most), it is a misspelling. Once per
/// relation, where it is first needed; only in a block with an `initial`
/// section (other blocks may hold it otherwise). Others may be perceived by
/// the world modeler (`alarm` in examples/planning/cable): not reported.
fn check_never_holds(cx: &mut Cx<'_>, b: &PlanningBlock) {
    let facts = |pick: fn(&PlanDef) -> Vec<&PlanFact>| b.defs.iter().flat_map(pick).collect::<Vec<_>>();
    let initial = facts(|d| match d {
        PlanDef::Facts(x) if !x.goal => x.facts.iter().collect(),
        _ => Vec::new(),
    });
    if !b.defs.iter().any(|d| matches!(d, PlanDef::Facts(x) if !x.goal)) {
        return;
    }
    let added = facts(|d| match d {
        PlanDef::Operator(o) => o
            .parts
            .iter()
            .flat_map(|p| match &p.kind {
                OpPartKind::Add(v) => v.iter().collect(),
                _ => Vec::new(),
            })
            .collect(),
        _ => Vec::new(),
    });
    let needed = facts(|d| match d {
        PlanDef::Operator(o) => o
            .parts
            .iter()
            .flat_map(|p| match &p.kind {
                OpPartKind::Precond(v) => v.iter().collect(),
                _ => Vec::new(),
            })
            .collect(),
        PlanDef::Facts(x) if x.goal => x.facts.iter().collect(),
        _ => Vec::new(),
    });
    let holds: HashSet<&str> = initial.iter().chain(&added).map(|f| f.relation.text.as_str()).collect();
    let mut reported = HashSet::new();
    for f in needed {
        let r = f.relation.text.as_str();
        if f.negated.is_some() || holds.contains(r) || !reported.insert(r) {
            continue;
        }
        let near = holds.iter().filter(|h| strsim::levenshtein(r, h) <= 2);
        let Some(best) = super::closest(r, near.copied()) else { continue };
        cx.out.push(
            Diagnostic::warning(
                codes::PLAN_NEVER_HOLDS,
                format!("relation `{r}` never holds: no initial fact has it and no operator adds it"),
                f.relation.span,
            )
            .with_label(f.relation.span, "needed here")
            .with_help(format!("did you mean `{best}`?"))
            .with_note("unless the world modeler perceives it, what needs it never applies"),
        );
    }
}

fn check_planning(cx: &mut Cx<'_>, b: &PlanningBlock) {
    check_never_holds(cx, b);
    let mut m =
        Model { types: HashMap::new(), entities: HashMap::new(), functions: HashMap::new(), relations: HashMap::new() };
    // Definitions first: a name may be used before it is defined.
    for d in &b.defs {
        match d {
            PlanDef::Type(t) => {
                if t.name.text == OBJECT {
                    cx.out.push(
                        Diagnostic::error(codes::PLAN_DUPLICATE, "type `object` is predefined", t.name.span)
                            .with_help("`object` is the root of every type; choose another name"),
                    );
                } else if let Some(first) = m.types.get(t.name.text.as_str()) {
                    duplicate(cx, "type", &t.name, &first.name);
                } else {
                    m.types.insert(&t.name.text, t);
                }
            }
            PlanDef::Entity(e) => match m.entities.get(e.name.text.as_str()) {
                Some(first) => duplicate(cx, "entity", &e.name, &first.name),
                None => {
                    m.entities.insert(&e.name.text, e);
                }
            },
            PlanDef::Function(f) => match m.functions.get(f.name.text.as_str()) {
                Some(first) => duplicate(cx, "function", &f.name, &first.name),
                None => {
                    m.functions.insert(&f.name.text, f);
                }
            },
            PlanDef::Operator(_) | PlanDef::Facts(_) => {}
        }
    }
    let mut operators: HashMap<&str, &Name> = HashMap::new();
    for d in &b.defs {
        match d {
            PlanDef::Type(t) => {
                if let Some(p) = &t.parent {
                    check_type(cx, &m, p);
                }
                let mut seen: HashMap<&str, &Name> = HashMap::new();
                for a in &t.attrs {
                    match seen.get(a.text.as_str()) {
                        Some(first) => duplicate(cx, "attribute", a, first),
                        None => {
                            seen.insert(&a.text, a);
                        }
                    }
                }
            }
            PlanDef::Entity(e) => {
                if check_type(cx, &m, &e.ty) {
                    let attrs = m.attrs(&e.ty.text);
                    for v in &e.values {
                        if !attrs.iter().any(|a| a.text == v.name.text) {
                            let d = Diagnostic::error(
                                codes::PLAN_UNKNOWN_ATTRIBUTE,
                                format!("type `{}` has no attribute `{}`", e.ty.text, v.name.text),
                                v.name.span,
                            )
                            .with_label(v.name.span, format!("not an attribute of `{}`", e.ty.text));
                            let d = cx.suggest(d, &v.name.text, attrs.iter().map(|a| a.text.as_str()));
                            let d = if d.help.is_none() {
                                d.with_help(format!(
                                    "declare it in the type: `type {} {{ {}; }}`",
                                    e.ty.text, v.name.text
                                ))
                            } else {
                                d
                            };
                            cx.out.push(d);
                        }
                        if !matches!(v.value.kind, ValueKind::Number(_) | ValueKind::Str(_)) {
                            cx.out.push(
                                Diagnostic::error(
                                    codes::PLAN_UNKNOWN_ATTRIBUTE,
                                    format!("the value of attribute `{}` must be a number or a string", v.name.text),
                                    v.value.span,
                                )
                                .with_help("write `x = 3.5;` or `description = \"cable\";`"),
                            );
                        }
                    }
                }
            }
            PlanDef::Function(f) => {
                for t in &f.params {
                    check_type(cx, &m, t);
                }
            }
            PlanDef::Operator(o) => {
                if let Some(first) = operators.get(o.name.text.as_str()) {
                    duplicate(cx, "operator", &o.name, first);
                } else {
                    operators.insert(&o.name.text, &o.name);
                }
                check_operator(cx, &mut m, o);
            }
            PlanDef::Facts(x) => {
                let params = Params(Vec::new());
                for f in &x.facts {
                    check_fact(cx, &mut m, &params, f);
                }
                for v in &x.values {
                    check_function_use(cx, &m, &params, &v.name, &v.args);
                    if !matches!(v.value.kind, ValueKind::Number(_) | ValueKind::Str(_)) {
                        cx.out.push(Diagnostic::error(
                            codes::PLAN_UNKNOWN_ATTRIBUTE,
                            format!("the value of `{}( ... )` must be a number or a string", v.name.text),
                            v.value.span,
                        ));
                    }
                }
            }
        }
    }
}

/// E0701 when `t` names no type; true when it does.
fn check_type(cx: &mut Cx<'_>, m: &Model<'_>, t: &Name) -> bool {
    if t.text == OBJECT || m.types.contains_key(t.text.as_str()) {
        return true;
    }
    let d = Diagnostic::error(codes::PLAN_UNKNOWN_TYPE, format!("unknown type `{}`", t.text), t.span)
        .with_label(t.span, "no `type` of the planning block has this name");
    let d = cx.suggest(d, &t.text, m.types.keys().copied());
    let d = if d.help.is_none() { d.with_help(format!("declare it: `type {};`", t.text)) } else { d };
    cx.out.push(d);
    false
}

/// The typed parameters of the operator being checked (empty outside operators).
struct Params<'a>(Vec<&'a TypedParam>);

impl<'a> Params<'a> {
    fn get(&self, n: &str) -> Option<&'a TypedParam> {
        self.0.iter().copied().find(|p| p.name.text == n)
    }
}

/// The type of a parameter or entity named `n`, or E0702.
fn resolve<'a>(cx: &mut Cx<'_>, m: &Model<'a>, params: &Params<'a>, n: &'a Name) -> Option<&'a str> {
    if let Some(p) = params.get(&n.text) {
        return Some(&p.ty.text);
    }
    if let Some(e) = m.entities.get(n.text.as_str()) {
        return Some(&e.ty.text);
    }
    let in_op = !params.0.is_empty();
    let msg = if in_op {
        format!("`{}` is neither a parameter of the operator nor an entity", n.text)
    } else {
        format!("unknown entity `{}`", n.text)
    };
    let d = Diagnostic::error(codes::PLAN_UNBOUND, msg, n.span)
        .with_label(n.span, if in_op { "unbound variable" } else { "no `entity` of the planning block has this name" });
    let names: Vec<&str> = params.0.iter().map(|p| p.name.text.as_str()).chain(m.entities.keys().copied()).collect();
    let d = cx.suggest(d, &n.text, names.into_iter());
    let d = if d.help.is_some() {
        d
    } else if in_op {
        d.with_help(format!(
            "add it to the operator's parameters, e.g. `( TYPE {}, ... )`, or define the entity",
            n.text
        ))
    } else {
        d.with_help(format!("define it: `entity TYPE {};`", n.text))
    };
    cx.out.push(d);
    None
}

fn check_fact<'a>(cx: &mut Cx<'_>, m: &mut Model<'a>, params: &Params<'a>, f: &'a PlanFact) {
    for n in f.args() {
        resolve(cx, m, params, n);
    }
    let n = 1 + usize::from(f.object.is_some());
    match m.relations.get(f.relation.text.as_str()) {
        Some(&(k, first)) if k != n => cx.out.push(
            Diagnostic::error(
                codes::PLAN_RELATION_ARITY,
                format!(
                    "relation `{}` relates {} here but {} where it is first used",
                    f.relation.text,
                    entities(n),
                    entities(k)
                ),
                f.relation.span,
            )
            .with_label(first, format!("first used with {}", entities(k)))
            .with_help(
                "a fact is `entity relation` (a quality) or `entity relation entity`; a relation keeps one form",
            ),
        ),
        Some(_) => {}
        None => {
            m.relations.insert(&f.relation.text, (n, f.relation.span));
        }
    }
}

fn entities(n: usize) -> String {
    if n == 1 {
        "one entity".into()
    } else {
        format!("{n} entities")
    }
}

/// `e.attr`: `e` is bound and its type has `attr`.
fn check_attr<'a>(cx: &mut Cx<'_>, m: &Model<'a>, params: &Params<'a>, e: &'a Name, a: &Name) {
    let Some(ty) = resolve(cx, m, params, e) else { return };
    let attrs = m.attrs(ty);
    if attrs.iter().any(|x| x.text == a.text) {
        return;
    }
    let d = Diagnostic::error(
        codes::PLAN_UNKNOWN_ATTRIBUTE,
        format!("`{}` is a `{ty}`, which has no attribute `{}`", e.text, a.text),
        a.span,
    )
    .with_label(a.span, format!("not an attribute of `{ty}`"));
    let d = cx.suggest(d, &a.text, attrs.iter().map(|x| x.text.as_str()));
    let d = if d.help.is_none() {
        let known: Vec<&str> = attrs.iter().map(|x| x.text.as_str()).collect();
        if known.is_empty() {
            d.with_help(format!("`{ty}` has no attributes; declare them: `type {ty} {{ {}; }}`", a.text))
        } else {
            d.with_help(format!("the attributes of `{ty}` are: {}", known.join(", ")))
        }
    } else {
        d
    };
    cx.out.push(d);
}

/// `f( a, b )`: a declared function, with as many arguments as parameters.
fn check_function_use<'a>(cx: &mut Cx<'_>, m: &Model<'a>, params: &Params<'a>, f: &Name, args: &'a [Name]) {
    for a in args {
        resolve(cx, m, params, a);
    }
    match m.functions.get(f.text.as_str()) {
        None => {
            let d = Diagnostic::error(codes::PLAN_UNKNOWN_ATTRIBUTE, format!("unknown function `{}`", f.text), f.span)
                .with_label(f.span, "no `function` of the planning block has this name");
            let d = cx.suggest(d, &f.text, m.functions.keys().copied());
            let d = if d.help.is_none() {
                d.with_help(format!("declare it: `function {}( TYPE, ... );`", f.text))
            } else {
                d
            };
            cx.out.push(d);
        }
        Some(decl) if decl.params.len() != args.len() => cx.out.push(
            Diagnostic::error(
                codes::PLAN_RELATION_ARITY,
                format!("function `{}` takes {} argument(s), given {}", f.text, decl.params.len(), args.len()),
                f.span,
            )
            .with_label(decl.name.span, "declared here"),
        ),
        Some(_) => {}
    }
}

fn check_operand<'a>(cx: &mut Cx<'_>, m: &Model<'a>, params: &Params<'a>, x: &'a PlanOperand, symbols: bool) {
    match &x.kind {
        OperandKind::Name(n) => {
            // In `mcl`, a name that is neither a parameter nor an entity is a symbolic value.
            let known = params.get(&n.text).is_some() || m.entities.contains_key(n.text.as_str());
            if !symbols || known {
                resolve(cx, m, params, n);
            }
        }
        OperandKind::Attr(e, a) => check_attr(cx, m, params, e, a),
        OperandKind::Function(f, args) => check_function_use(cx, m, params, f, args),
        OperandKind::Literal(_) => {}
    }
}

fn check_operator<'a>(cx: &mut Cx<'_>, m: &mut Model<'a>, o: &'a PlanOperator) {
    let mut seen: HashMap<&str, &Name> = HashMap::new();
    for p in &o.params {
        check_type(cx, m, &p.ty);
        match seen.get(p.name.text.as_str()) {
            Some(first) => cx.out.push(
                Diagnostic::error(
                    codes::DUPLICATE_PARAMETER,
                    format!("parameter `{}` is declared twice", p.name.text),
                    p.name.span,
                )
                .with_label(first.span, "first declared here"),
            ),
            None => {
                seen.insert(&p.name.text, &p.name);
            }
        }
    }
    let params = Params(o.params.iter().collect());
    let mut once: HashMap<&str, Span> = HashMap::new();
    for part in &o.parts {
        match &part.kind {
            OpPartKind::Precond(v) | OpPartKind::Add(v) | OpPartKind::Del(v) => {
                for f in v {
                    check_fact(cx, m, &params, f);
                    if f.negated.is_some() && !matches!(part.kind, OpPartKind::Precond(_)) {
                        cx.out.push(
                            Diagnostic::error(
                                codes::PLAN_UNBOUND,
                                format!("`not` has no meaning in `{}`", part.kind.keyword()),
                                f.span,
                            )
                            .with_help("a fact the operator makes false goes in `del`"),
                        );
                    }
                }
            }
            OpPartKind::Expression(v) => {
                for x in v {
                    check_operand(cx, m, &params, &x.left, false);
                    check_operand(cx, m, &params, &x.right, false);
                }
            }
            OpPartKind::Cost(c) => check_operand(cx, m, &params, c, false),
            OpPartKind::Mcl(c) => {
                for a in &c.args {
                    check_operand(cx, m, &params, a, true);
                }
                check_mission_call(cx, c);
            }
        }
        if matches!(part.kind, OpPartKind::Cost(_) | OpPartKind::Mcl(_)) {
            let k = part.kind.keyword();
            match once.get(k) {
                Some(&first) => cx.out.push(
                    Diagnostic::error(
                        codes::PLAN_DUPLICATE,
                        format!("operator `{}` has two `{k}` lines", o.name.text),
                        part.keyword_span,
                    )
                    .with_label(first, "the first one"),
                ),
                None => {
                    once.insert(k, part.keyword_span);
                }
            }
        }
    }
}

/// E0705: the call names a mission of the program with that many parameters.
fn check_mission_call(cx: &mut Cx<'_>, c: &PlanCall) {
    let name = &c.name.text;
    let Some(id) = cx.scope.first(DefKind::Mission, name) else {
        let d = Diagnostic::error(codes::PLAN_MISSION, format!("unknown MCL mission operator `{name}`"), c.name.span)
            .with_label(c.name.span, "no `mission` or `mcl_plan_op` of the program has this name");
        let d = cx.suggest(d, name, cx.scope.names(DefKind::Mission));
        let d = if d.help.is_none() {
            d.with_help(format!("define it: `mcl_plan_op {name}( ... ) {{ ... }}`, or import the file that does"))
        } else {
            d
        };
        cx.out.push(d);
        return;
    };
    let Some(mission) = scope::mission(cx.db, id) else { return };
    let want = mission.params.len();
    if want != c.args.len() {
        let ps: Vec<&str> = mission.params.iter().map(|p| p.text.as_str()).collect();
        let d = Diagnostic::error(
            codes::PLAN_MISSION,
            format!("`{name}` takes {want} argument(s), given {}", c.args.len()),
            c.span,
        );
        let span = mission.name.as_ref().map_or(mission.keyword_span, |n| n.span);
        let d = cx.def_label(d, id, span, format!("`{name}( {} )` is defined here", ps.join(", ")));
        cx.out.push(d);
    }
}

fn check_map(cx: &mut Cx<'_>, b: &PddlMapBlock) {
    // PDDL is case-insensitive: `Move` and `move` are one action.
    let mut actions: HashMap<String, &Name> = HashMap::new();
    for m in &b.maps {
        let key = m.action.text.to_ascii_lowercase();
        match actions.get(&key) {
            Some(first) => duplicate(cx, "mapping of action", &m.action, first),
            None => {
                actions.insert(key, &m.action);
            }
        }
        let mut seen: HashMap<&str, &Name> = HashMap::new();
        for p in &m.params {
            match seen.get(p.text.as_str()) {
                Some(first) => cx.out.push(
                    Diagnostic::error(
                        codes::DUPLICATE_PARAMETER,
                        format!("parameter `{}` is named twice", p.text),
                        p.span,
                    )
                    .with_label(first.span, "first named here"),
                ),
                None => {
                    seen.insert(&p.text, p);
                }
            }
        }
        for a in &m.call.args {
            let bad = match &a.kind {
                OperandKind::Attr(e, _) if !m.params.iter().any(|p| p.text == e.text) => Some(e),
                OperandKind::Function(f, _) => Some(f),
                _ => None,
            };
            if let Some(e) = bad {
                let names: Vec<&str> = m.params.iter().map(|p| p.text.as_str()).collect();
                let d = Diagnostic::error(
                    codes::PLAN_MAP_PARAMETER,
                    format!("`{}` is not a parameter of the mapping of `{}`", e.text, m.action.text),
                    e.span,
                )
                .with_label(e.span, format!("the parameters are: {}", names.join(", ")));
                let d = cx.suggest(d, &e.text, names.iter().copied());
                let d = if d.help.is_none() {
                    d.with_help("an argument is a parameter `p`, its attribute `p.x`, a number, a string or a symbol")
                } else {
                    d
                };
                cx.out.push(d);
            }
        }
        check_mission_call(cx, &m.call);
    }
}
