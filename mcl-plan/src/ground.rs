//! Grounding: from a lifted domain and problem to a propositional task.
//!
//! Parameters only range over objects of their type (subtypes included);
//! static predicates (never in an effect) are checked against the initial
//! state while joining and vanish from the ground actions; the set of ground
//! actions is the fixpoint of relaxed reachability (delete effects and
//! negative preconditions ignored), so only actions whose preconditions can
//! all become true are kept, and only facts that can become true get an index.

use crate::pddl::{Action, Atom, Cond, Domain, Fact, MclArg, NumExpr, Problem, Term, Value, OBJECT};
use crate::sexpr::Error;
use serde::Serialize;
use std::collections::{HashMap, HashSet};
use std::fmt;

/// One argument of an MCL mission call, resolved.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum McValue {
    Num(f64),
    /// A string, written in double quotes.
    Str(String),
    /// An identifier passed as is (an object name or a symbolic value).
    #[serde(serialize_with = "ser_sym")]
    Sym(String),
}

fn ser_sym<S: serde::Serializer>(s: &str, ser: S) -> Result<S::Ok, S::Error> {
    ser.serialize_str(s)
}

/// An instance of an MCL mission operator: `MclMove( 10, 4.5, 2 )`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MclInstance {
    pub mission: String,
    pub args: Vec<McValue>,
}

impl fmt::Display for MclInstance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}(", self.mission)?;
        for (i, a) in self.args.iter().enumerate() {
            write!(f, "{}", if i == 0 { " " } else { ", " })?;
            match a {
                McValue::Num(n) => write!(f, "{}", crate::pddl::fmt_num(*n))?,
                McValue::Str(s) => write!(f, "{}", Value::Str(s.clone()))?,
                McValue::Sym(s) => write!(f, "{s}")?,
            }
        }
        write!(f, "{})", if self.args.is_empty() { "" } else { " " })
    }
}

/// A ground action: preconditions and effects over fact indices.
#[derive(Clone, Debug)]
pub struct GroundAction {
    /// Index into the domain's actions.
    pub op: u32,
    /// Object indices bound to the parameters.
    pub args: Box<[u32]>,
    pub pre: Box<[u32]>,
    /// Facts that must be false (`:negative-preconditions`).
    pub pre_neg: Box<[u32]>,
    pub add: Box<[u32]>,
    pub del: Box<[u32]>,
    pub cost: u64,
    pub mcl: Option<MclInstance>,
}

/// A grounded planning task.
#[derive(Clone, Debug)]
pub struct Task {
    pub objects: Vec<String>,
    pub predicates: Vec<String>,
    pub op_names: Vec<String>,
    /// Reachable fluent facts: predicate index and object indices.
    pub facts: Vec<(u32, Box<[u32]>)>,
    pub actions: Vec<GroundAction>,
    /// Fluent facts true in the initial state (sorted).
    pub init: Vec<u32>,
    pub goal: Vec<u32>,
    pub goal_neg: Vec<u32>,
    /// False when a goal fact can never become true.
    pub goal_reachable: bool,
    /// No `:metric`: every action costs 1.
    pub unit_cost: bool,
    /// Facts that hold in every state (static predicates of the initial state).
    pub static_facts: Vec<Fact>,
    fact_index: HashMap<(u32, Box<[u32]>), u32>,
    pred_index: HashMap<String, u32>,
    obj_index: HashMap<String, u32>,
}

impl Task {
    pub fn fact(&self, f: u32) -> Fact {
        let (p, args) = &self.facts[f as usize];
        Fact {
            pred: self.predicates[*p as usize].clone(),
            args: args.iter().map(|&o| self.objects[o as usize].clone()).collect(),
        }
    }
    /// The index of a fact, if it is a reachable fluent fact of this task.
    pub fn fact_id(&self, f: &Fact) -> Option<u32> {
        let p = *self.pred_index.get(&f.pred)?;
        let args: Option<Box<[u32]>> = f.args.iter().map(|a| self.obj_index.get(a).copied()).collect();
        self.fact_index.get(&(p, args?)).copied()
    }
    /// `(name arg ...)` in lower case, as in IPC plans.
    pub fn action_name(&self, a: u32) -> String {
        let ga = &self.actions[a as usize];
        let mut s = format!("({}", self.op_names[ga.op as usize]);
        for &o in ga.args.iter() {
            s.push(' ');
            s.push_str(&self.objects[o as usize]);
        }
        s.push(')');
        s
    }
    pub fn num_facts(&self) -> usize {
        self.facts.len()
    }
}

struct Types {
    ids: HashMap<String, usize>,
    parent: Vec<usize>,
}

impl Types {
    fn new(d: &Domain) -> Result<Types, String> {
        let mut ids = HashMap::new();
        ids.insert(OBJECT.to_string(), 0);
        // Supertypes named only after `-` are types too (subtypes of `object`).
        for (t, p) in &d.types {
            for x in [t, p] {
                let n = ids.len();
                ids.entry(x.clone()).or_insert(n);
            }
        }
        let mut parent = vec![0; ids.len()];
        for (t, p) in &d.types {
            if t == OBJECT {
                continue;
            }
            let pid = *ids.get(p).ok_or_else(|| format!("type `{t}` has the undeclared supertype `{p}`"))?;
            parent[ids[t]] = pid;
        }
        // Reject cycles.
        for start in 0..parent.len() {
            let mut t = start;
            for _ in 0..=parent.len() {
                t = parent[t];
            }
            if t != 0 {
                return Err("the type hierarchy has a cycle".to_string());
            }
        }
        Ok(Types { ids, parent })
    }
    fn is_sub(&self, mut t: usize, of: usize) -> bool {
        for _ in 0..=self.parent.len() {
            if t == of {
                return true;
            }
            if t == 0 {
                return false;
            }
            t = self.parent[t];
        }
        false
    }
}

const NONE: u32 = u32::MAX;

struct Ctx<'a> {
    d: &'a Domain,
    p: &'a Problem,
    obj_index: HashMap<String, u32>,
    objects: Vec<String>,
    pred_index: HashMap<String, u32>,
    fluent: Vec<bool>,
    /// Per predicate: tuples true initially (static preds) or reachable (fluent preds).
    tuples: Vec<Vec<Box<[u32]>>>,
    static_set: HashSet<(u32, Box<[u32]>)>,
    fact_index: HashMap<(u32, Box<[u32]>), u32>,
    facts: Vec<(u32, Box<[u32]>)>,
    values: HashMap<(String, Box<[u32]>), Value>,
    /// Per action, per parameter: the objects it ranges over.
    domains: Vec<Vec<Vec<u32>>>,
    errors: Vec<Error>,
    /// Join steps left before grounding gives up.
    budget: std::cell::Cell<u64>,
    /// The action being grounded when a limit was reached.
    blown: std::cell::Cell<Option<usize>>,
}

fn err(file: &str, line: usize, msg: String) -> Error {
    Error { file: file.to_string(), line: line.max(1), column: 1, message: msg }
}

/// Grounds `problem` in `domain`. Errors: unknown predicates, objects or
/// types, wrong arities, costs that are not non-negative integers, MCL
/// arguments naming attributes that an object lacks.
pub fn ground(d: &Domain, p: &Problem) -> Result<Task, Vec<Error>> {
    ground_with_budget(d, p, DEFAULT_BUDGET)
}

/// Join steps [`ground`] takes before giving up on a problem too large to ground.
pub const DEFAULT_BUDGET: u64 = 200_000_000;
/// The most ground actions grounding makes before giving up (an action with
/// 8 parameters over 60 objects would have 1.7e14 of them).
pub const MAX_GROUND_ACTIONS: usize = 1_000_000;
/// The most reachable facts grounding indexes before giving up.
pub const MAX_FACTS: usize = 1_000_000;

/// [`ground`], giving up after `budget` join steps, [`MAX_GROUND_ACTIONS`]
/// ground actions or [`MAX_FACTS`] facts, with an error at the action being
/// grounded then.
pub fn ground_with_budget(d: &Domain, p: &Problem, budget: u64) -> Result<Task, Vec<Error>> {
    let pf = p.file.as_str();
    let types = Types::new(d).map_err(|m| vec![err(&d.file, 1, m)])?;
    let mut errors = Vec::new();
    if !p.domain.is_empty() && p.domain != d.name {
        errors.push(err(pf, 1, format!("problem `{}` is for domain `{}`, not `{}`", p.name, p.domain, d.name)));
    }
    // Objects: domain constants, then problem objects.
    let mut objects: Vec<String> = Vec::new();
    let mut obj_types: Vec<Vec<usize>> = Vec::new();
    let mut obj_index: HashMap<String, u32> = HashMap::new();
    for (o, file) in d.constants.iter().map(|c| (c, &d.file)).chain(p.objects.iter().map(|o| (o, &p.file))) {
        let mut ts = Vec::new();
        for t in &o.types {
            match types.ids.get(t) {
                Some(&id) => ts.push(id),
                None => errors.push(err(file, 1, format!("object `{}` has the undeclared type `{t}`", o.name))),
            }
        }
        match obj_index.get(&o.name) {
            Some(&i) => {
                let old = &mut obj_types[i as usize];
                for t in ts {
                    if !old.contains(&t) {
                        old.push(t);
                    }
                }
            }
            None => {
                obj_index.insert(o.name.clone(), objects.len() as u32);
                objects.push(o.name.clone());
                obj_types.push(ts);
            }
        }
    }
    let in_type = |o: usize, t: usize| obj_types[o].iter().any(|&ot| types.is_sub(ot, t));
    let mut objs_of_type: Vec<Vec<u32>> = vec![Vec::new(); types.parent.len()];
    for (t, v) in objs_of_type.iter_mut().enumerate() {
        *v = (0..objects.len()).filter(|&o| in_type(o, t)).map(|o| o as u32).collect();
    }
    let pred_index: HashMap<String, u32> =
        d.predicates.iter().enumerate().map(|(i, s)| (s.name.clone(), i as u32)).collect();
    if pred_index.len() != d.predicates.len() {
        errors.push(err(&d.file, 1, "a predicate is declared twice".to_string()));
    }
    for a in &d.actions {
        for at in a.pre.iter().map(|l| &l.atom).chain(&a.add).chain(&a.del) {
            match pred_index.get(&at.pred) {
                Some(&pi) if d.predicates[pi as usize].params.len() == at.args.len() => {}
                _ => errors.push(err(
                    &d.file,
                    a.line,
                    format!("action `{}`: unknown predicate or wrong arity in ({} ...)", a.name, at.pred),
                )),
            }
        }
        for t in a.pre.iter().map(|l| &l.atom).chain(&a.add).chain(&a.del).flat_map(|at| &at.args) {
            if let Term::Var(v) = t {
                if *v >= a.params.len() {
                    errors.push(err(&d.file, a.line, format!("action `{}`: bad variable", a.name)));
                }
            }
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let mut fluent = vec![false; d.predicates.len()];
    for a in &d.actions {
        for at in a.add.iter().chain(&a.del) {
            if let Some(&pi) = pred_index.get(&at.pred) {
                fluent[pi as usize] = true;
            }
        }
    }
    let resolve = |f: &Fact, what: &str, errors: &mut Vec<Error>| -> Option<(u32, Box<[u32]>)> {
        let Some(&pi) = pred_index.get(&f.pred) else {
            errors.push(err(pf, 1, format!("{what} {f}: unknown predicate `{}`", f.pred)));
            return None;
        };
        let arity = d.predicates[pi as usize].params.len();
        if arity != f.args.len() {
            errors.push(err(
                pf,
                1,
                format!("{what} {f}: `{}` takes {arity} argument(s), given {}", f.pred, f.args.len()),
            ));
            return None;
        }
        let mut args = Vec::with_capacity(arity);
        for a in &f.args {
            match obj_index.get(a) {
                Some(&o) => args.push(o),
                None => {
                    errors.push(err(pf, 1, format!("{what} {f}: unknown object `{a}`")));
                    return None;
                }
            }
        }
        Some((pi, args.into_boxed_slice()))
    };
    let mut cx = Ctx {
        d,
        p,
        obj_index: obj_index.clone(),
        objects: objects.clone(),
        pred_index: pred_index.clone(),
        fluent: fluent.clone(),
        tuples: vec![Vec::new(); d.predicates.len()],
        static_set: HashSet::new(),
        fact_index: HashMap::new(),
        facts: Vec::new(),
        values: HashMap::new(),
        domains: Vec::new(),
        errors: Vec::new(),
        budget: std::cell::Cell::new(budget),
        blown: std::cell::Cell::new(None),
    };
    let mut init = Vec::new();
    let mut static_facts = Vec::new();
    for f in &p.init {
        if let Some((pi, args)) = resolve(f, "initial fact", &mut errors) {
            if fluent[pi as usize] {
                init.push(cx.intern(pi, args));
            } else if cx.static_set.insert((pi, args.clone())) {
                cx.tuples[pi as usize].push(args);
                static_facts.push(f.clone());
            }
        }
    }
    for (fname, args, v) in &p.values {
        let mut ids = Vec::new();
        for a in args {
            match obj_index.get(a) {
                Some(&o) => ids.push(o),
                None => errors.push(err(pf, 1, format!("value of ({fname} {}): unknown object `{a}`", args.join(" ")))),
            }
        }
        if ids.len() == args.len() {
            cx.values.insert((fname.clone(), ids.into_boxed_slice()), v.clone());
        }
    }
    // Parameter domains.
    for a in &d.actions {
        let mut doms = Vec::new();
        for prm in &a.params {
            let mut v: Vec<u32> = Vec::new();
            for t in &prm.types {
                if let Some(&ti) = types.ids.get(t) {
                    v.extend(&objs_of_type[ti]);
                }
            }
            v.sort_unstable();
            v.dedup();
            doms.push(v);
        }
        cx.domains.push(doms);
    }
    // Constants written in the domain's actions must exist.
    for a in &d.actions {
        let mut check = |t: &Term| {
            if let Term::Obj(o) = t {
                if !obj_index.contains_key(o) {
                    errors.push(err(&d.file, a.line, format!("action `{}`: unknown constant `{o}`", a.name)));
                }
            }
        };
        for at in a.pre.iter().map(|l| &l.atom).chain(&a.add).chain(&a.del) {
            at.args.iter().for_each(&mut check);
        }
        for c in &a.conds {
            if let Cond::Equal(x, y, _) = c {
                check(x);
                check(y);
            }
        }
    }
    // Goals.
    let mut goal_raw = Vec::new();
    for (f, pos) in &p.goal {
        if let Some(x) = resolve(f, "goal", &mut errors) {
            goal_raw.push((x, *pos));
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }

    // Relaxed reachability fixpoint.
    let orders: Vec<Vec<usize>> = d.actions.iter().map(|a| join_order(a, &cx.fluent, &cx.pred_index)).collect();
    let mut seen: Vec<HashSet<Box<[u32]>>> = vec![HashSet::new(); d.actions.len()];
    let mut bindings: Vec<(u32, Box<[u32]>)> = Vec::new();
    loop {
        let before = cx.facts.len();
        let nb = bindings.len();
        for (ai, a) in d.actions.iter().enumerate() {
            let mut bind = vec![NONE; a.params.len()];
            let mut found = Vec::new();
            cx.join(ai, a, &orders[ai], 0, &mut bind, &mut found);
            for b in found {
                if seen[ai].insert(b.clone()) {
                    for at in &a.add {
                        let (pi, args) = cx.inst(at, &b);
                        cx.intern(pi, args);
                    }
                    bindings.push((ai as u32, b));
                }
            }
            if bindings.len() > MAX_GROUND_ACTIONS || cx.facts.len() > MAX_FACTS {
                cx.blow(ai);
            }
            if cx.budget.get() == 0 {
                cx.blown.set(cx.blown.get().or(Some(ai)));
                break;
            }
        }
        if cx.budget.get() == 0 {
            let ai = cx.blown.get().unwrap_or_default();
            return Err(vec![too_large(d, &cx.domains[ai], ai, budget)]);
        }
        if cx.facts.len() == before && bindings.len() == nb {
            break;
        }
    }

    // Ground actions.
    let mut actions = Vec::with_capacity(bindings.len());
    for (ai, b) in bindings {
        let a = &d.actions[ai as usize];
        let lit_ids = |atoms: &mut dyn Iterator<Item = &Atom>, cx: &Ctx<'_>| -> Vec<u32> {
            let mut v: Vec<u32> = atoms.filter_map(|at| cx.lookup(at, &b)).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let pre = lit_ids(&mut a.pre.iter().filter(|l| l.positive && cx.is_fluent(&l.atom)).map(|l| &l.atom), &cx);
        let pre_neg = lit_ids(&mut a.pre.iter().filter(|l| !l.positive && cx.is_fluent(&l.atom)).map(|l| &l.atom), &cx);
        let add = lit_ids(&mut a.add.iter(), &cx);
        let mut del = lit_ids(&mut a.del.iter(), &cx);
        del.retain(|f| add.binary_search(f).is_err());
        // An action needing a fact both true and false never applies.
        if pre.iter().any(|f| pre_neg.binary_search(f).is_ok()) {
            continue;
        }
        let cost = if p.metric {
            match &a.cost {
                None => 0,
                Some(e) => match cx.eval(e, &b) {
                    Some(c) if c >= 0.0 && c.fract() == 0.0 && c < 1e15 => c as u64,
                    Some(c) => {
                        cx.errors.push(err(
                            &d.file,
                            a.line,
                            format!("{}: cost {c} is not a non-negative integer", cx.name(ai, &b)),
                        ));
                        0
                    }
                    None => {
                        cx.errors.push(err(
                            &d.file,
                            a.line,
                            format!("{}: the cost needs a value that :init does not give", cx.name(ai, &b)),
                        ));
                        0
                    }
                },
            }
        } else {
            1
        };
        let mcl = a.mcl.as_ref().map(|m| cx.mcl_instance(ai, m, &b));
        actions.push(GroundAction {
            op: ai,
            args: b,
            pre: pre.into(),
            pre_neg: pre_neg.into(),
            add: add.into(),
            del: del.into(),
            cost,
            mcl,
        });
    }
    if !cx.errors.is_empty() {
        cx.errors.truncate(20);
        return Err(cx.errors);
    }
    let mut goal = Vec::new();
    let mut goal_neg = Vec::new();
    let mut goal_reachable = true;
    for ((pi, args), pos) in goal_raw {
        if !cx.fluent[pi as usize] {
            let holds = cx.static_set.contains(&(pi, args.clone()));
            if holds != pos {
                goal_reachable = false;
            }
            continue;
        }
        match cx.fact_index.get(&(pi, args)) {
            Some(&f) => {
                if pos {
                    goal.push(f)
                } else {
                    goal_neg.push(f)
                }
            }
            None => {
                if pos {
                    goal_reachable = false;
                }
            }
        }
    }
    init.sort_unstable();
    init.dedup();
    goal.sort_unstable();
    goal.dedup();
    goal_neg.sort_unstable();
    goal_neg.dedup();
    Ok(Task {
        objects,
        predicates: d.predicates.iter().map(|s| s.name.clone()).collect(),
        op_names: d.actions.iter().map(|a| a.name.clone()).collect(),
        facts: cx.facts,
        actions,
        init,
        goal,
        goal_neg,
        goal_reachable,
        unit_cost: !p.metric,
        static_facts,
        fact_index: cx.fact_index,
        pred_index,
        obj_index,
    })
}

/// The error of a grounding that gave up while grounding action `ai`: at the
/// action, with its parameters and the objects they range over.
fn too_large(d: &Domain, domains: &[Vec<u32>], ai: usize, budget: u64) -> Error {
    let a = &d.actions[ai];
    let sizes: Vec<String> = domains.iter().map(|v| v.len().to_string()).collect();
    let instances: f64 = domains.iter().map(|v| v.len() as f64).product();
    err(
        &d.file,
        a.line,
        format!(
            "grounding gave up on action `{}`: {} parameters over {} objects (up to {instances:.3e} instances) \
             exceed the limits of {MAX_GROUND_ACTIONS} ground actions, {MAX_FACTS} facts and {budget} join steps; \
             the problem is too large to ground (give the parameters preconditions on static facts, or fewer objects)",
            a.name,
            a.params.len(),
            if sizes.is_empty() { "no".to_string() } else { sizes.join(" × ") }
        ),
    )
}

/// Order in which the positive preconditions are joined: greedily the one
/// with the most already-bound variables, static predicates first on ties.
fn join_order(a: &Action, fluent: &[bool], pred_index: &HashMap<String, u32>) -> Vec<usize> {
    let pos: Vec<usize> = (0..a.pre.len()).filter(|&i| a.pre[i].positive).collect();
    let mut bound = vec![false; a.params.len()];
    let mut order = Vec::new();
    let mut left = pos;
    while !left.is_empty() {
        let score = |i: usize| {
            let at = &a.pre[i].atom;
            let vars: Vec<usize> =
                at.args.iter().filter_map(|t| if let Term::Var(v) = t { Some(*v) } else { None }).collect();
            let nb = vars.iter().filter(|&&v| bound[v]).count();
            let unbound = vars.len() - nb;
            let is_static = pred_index.get(&at.pred).is_some_and(|&p| !fluent[p as usize]);
            // Fully bound first (a filter), then fewest new variables, static first.
            (unbound == 0, std::cmp::Reverse(unbound), is_static)
        };
        let (k, _) = left.iter().enumerate().max_by_key(|(_, &i)| score(i)).unwrap_or((0, &0));
        let i = left.remove(k);
        for t in &a.pre[i].atom.args {
            if let Term::Var(v) = t {
                bound[*v] = true;
            }
        }
        order.push(i);
    }
    order
}

impl Ctx<'_> {
    fn intern(&mut self, pi: u32, args: Box<[u32]>) -> u32 {
        if let Some(&f) = self.fact_index.get(&(pi, args.clone())) {
            return f;
        }
        let id = self.facts.len() as u32;
        self.fact_index.insert((pi, args.clone()), id);
        self.tuples[pi as usize].push(args.clone());
        self.facts.push((pi, args));
        id
    }

    fn is_fluent(&self, at: &Atom) -> bool {
        self.pred_index.get(&at.pred).is_some_and(|&p| self.fluent[p as usize])
    }

    fn obj(&self, t: &Term, b: &[u32]) -> u32 {
        match t {
            Term::Var(v) => b[*v],
            Term::Obj(o) => self.obj_index.get(o).copied().unwrap_or(NONE),
        }
    }

    fn inst(&self, at: &Atom, b: &[u32]) -> (u32, Box<[u32]>) {
        (self.pred_index[&at.pred], at.args.iter().map(|t| self.obj(t, b)).collect())
    }

    fn lookup(&self, at: &Atom, b: &[u32]) -> Option<u32> {
        let k = self.inst(at, b);
        self.fact_index.get(&k).copied()
    }

    fn name(&self, ai: u32, b: &[u32]) -> String {
        let mut s = format!("({}", self.d.actions[ai as usize].name);
        for &o in b {
            s.push(' ');
            s.push_str(&self.objects[o as usize]);
        }
        s + ")"
    }

    fn eval(&self, e: &NumExpr, b: &[u32]) -> Option<f64> {
        Some(match e {
            NumExpr::Num(n) => *n,
            NumExpr::Neg(x) => -self.eval(x, b)?,
            NumExpr::Bin(op, x, y) => {
                let (x, y) = (self.eval(x, b)?, self.eval(y, b)?);
                match op {
                    '+' => x + y,
                    '-' => x - y,
                    '*' => x * y,
                    _ => {
                        if y == 0.0 {
                            return None;
                        }
                        x / y
                    }
                }
            }
            NumExpr::Fluent(f, args) => {
                let ids: Box<[u32]> = args.iter().map(|t| self.obj(t, b)).collect();
                match self.values.get(&(f.clone(), ids))? {
                    Value::Num(n) => *n,
                    Value::Str(_) => return None,
                }
            }
        })
    }

    fn conds_hold(&self, a: &Action, b: &[u32]) -> bool {
        a.conds.iter().all(|c| match c {
            Cond::Equal(x, y, pos) => (self.obj(x, b) == self.obj(y, b)) == *pos,
            Cond::Compare(op, x, y) => match (self.eval(x, b), self.eval(y, b)) {
                (Some(x), Some(y)) => op.holds(x, y),
                _ => false,
            },
        })
    }

    /// Negative preconditions over static predicates, checked against the initial state.
    fn static_negs_hold(&self, a: &Action, b: &[u32]) -> bool {
        a.pre
            .iter()
            .filter(|l| !l.positive && !self.is_fluent(&l.atom))
            .all(|l| !self.static_set.contains(&self.inst(&l.atom, b)))
    }

    /// Spends the whole budget: action `ai` makes too many ground actions or facts.
    fn blow(&self, ai: usize) {
        self.budget.set(0);
        self.blown.set(self.blown.get().or(Some(ai)));
    }

    /// Takes one step of the budget; false when it is spent.
    #[inline]
    fn tick(&self) -> bool {
        let b = self.budget.get();
        if b == 0 {
            return false;
        }
        self.budget.set(b - 1);
        true
    }

    fn join(
        &self,
        ai: usize,
        a: &Action,
        order: &[usize],
        depth: usize,
        bind: &mut Vec<u32>,
        out: &mut Vec<Box<[u32]>>,
    ) {
        if !self.tick() {
            return;
        }
        if depth == order.len() {
            self.enumerate_free(ai, a, 0, bind, out);
            return;
        }
        let at = &a.pre[order[depth]].atom;
        let pi = self.pred_index[&at.pred] as usize;
        let n = self.tuples[pi].len();
        let mut newly: Vec<usize> = Vec::with_capacity(at.args.len());
        for ti in 0..n {
            let tup = &self.tuples[pi][ti];
            newly.clear();
            let mut ok = true;
            for (k, t) in at.args.iter().enumerate() {
                let o = tup[k];
                match t {
                    Term::Obj(name) => {
                        if self.obj_index.get(name) != Some(&o) {
                            ok = false;
                        }
                    }
                    Term::Var(v) => {
                        if bind[*v] == NONE {
                            if self.domains[ai][*v].binary_search(&o).is_ok() {
                                bind[*v] = o;
                                newly.push(*v);
                            } else {
                                ok = false;
                            }
                        } else if bind[*v] != o {
                            ok = false;
                        }
                    }
                }
                if !ok {
                    break;
                }
            }
            if ok {
                self.join(ai, a, order, depth + 1, bind, out);
            }
            for &v in &newly {
                bind[v] = NONE;
            }
        }
    }

    fn enumerate_free(&self, ai: usize, a: &Action, k: usize, bind: &mut Vec<u32>, out: &mut Vec<Box<[u32]>>) {
        if !self.tick() {
            return;
        }
        if k == bind.len() {
            if self.conds_hold(a, bind) && self.static_negs_hold(a, bind) {
                if out.len() >= MAX_GROUND_ACTIONS {
                    return self.blow(ai);
                }
                out.push(bind.clone().into_boxed_slice());
            }
            return;
        }
        if bind[k] != NONE {
            return self.enumerate_free(ai, a, k + 1, bind, out);
        }
        for i in 0..self.domains[ai][k].len() {
            bind[k] = self.domains[ai][k][i];
            self.enumerate_free(ai, a, k + 1, bind, out);
        }
        bind[k] = NONE;
    }

    fn mcl_instance(&mut self, ai: u32, m: &crate::pddl::MclCall, b: &[u32]) -> MclInstance {
        let mut args = Vec::new();
        for x in &m.args {
            args.push(match x {
                MclArg::Num(t) => McValue::Num(t.parse().unwrap_or(0.0)),
                MclArg::Str(s) => McValue::Str(s.clone()),
                MclArg::Symbol(s) => McValue::Sym(s.clone()),
                MclArg::Object(t) => McValue::Sym(self.objects.get(self.obj(t, b) as usize).cloned().unwrap_or_default()),
                MclArg::Attr(t, attr) => {
                    let o = self.obj(t, b);
                    match self.values.get(&(attr.clone(), vec![o].into_boxed_slice())) {
                        Some(Value::Num(n)) => McValue::Num(*n),
                        Some(Value::Str(s)) => McValue::Str(s.clone()),
                        None => {
                            let oname = self.objects.get(o as usize).cloned().unwrap_or_default();
                            let e = err(
                                m.file.as_deref().unwrap_or(&self.d.file),
                                m.line,
                                format!(
                                    "{}: the mission's argument needs attribute `{attr}` of `{oname}`, which {} does not give (add `(= ({attr} {oname}) VALUE)` to :init)",
                                    self.name(ai, b),
                                    self.p.file
                                ),
                            );
                            self.errors.push(e);
                            McValue::Num(0.0)
                        }
                    }
                }
            });
        }
        MclInstance { mission: m.name.clone(), args }
    }
}
