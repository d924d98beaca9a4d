//! Plan validator: replays a plan on the lifted domain, independently of the
//! grounding and of the search (it shares only the parser), checking types,
//! preconditions, expressions and the goal, and adding up the cost.

use crate::pddl::{Action, Cond, Domain, Fact, NumExpr, Problem, Term, Value, OBJECT};
use crate::sexpr::{self, Source};
use std::collections::{HashMap, HashSet};

/// Parses an IPC plan: one `(action arg ...)` per line, `;` comments.
pub fn parse_plan(text: &str) -> Result<Vec<(String, Vec<String>)>, String> {
    let src = Source::new("plan", text);
    let top = sexpr::read(&src).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for e in top {
        let l = e.list().ok_or_else(|| {
            src.error(e.span(), format!("expected `(action arg ...)`, found {}", e.describe())).to_string()
        })?;
        let mut names = Vec::new();
        for x in l {
            match x.atom() {
                Some(a) => names.push(a),
                None => {
                    return Err(src.error(x.span(), format!("expected a name, found {}", x.describe())).to_string())
                }
            }
        }
        if names.is_empty() {
            return Err(src.error(e.span(), "expected `(action arg ...)`, found `()`").to_string());
        }
        let name = names.remove(0);
        out.push((name, names));
    }
    Ok(out)
}

/// Replays `plan` (IPC text) from the problem's initial state. Returns the
/// plan's cost (action costs with `:metric`, else its length), or why it is
/// not a valid plan.
pub fn validate(domain: &Domain, problem: &Problem, plan: &str) -> Result<u64, String> {
    validate_steps(domain, problem, &parse_plan(plan)?)
}

/// [`validate`] for an already parsed plan.
pub fn validate_steps(domain: &Domain, problem: &Problem, plan: &[(String, Vec<String>)]) -> Result<u64, String> {
    // Objects and their types.
    let mut obj_types: HashMap<&str, Vec<&str>> = HashMap::new();
    for o in domain.constants.iter().chain(&problem.objects) {
        obj_types.entry(o.name.as_str()).or_default().extend(o.types.iter().map(|t| t.as_str()));
    }
    let parent: HashMap<&str, &str> = domain.types.iter().map(|(t, p)| (t.as_str(), p.as_str())).collect();
    let is_a = |o: &str, want: &str| -> bool {
        let Some(ts) = obj_types.get(o) else { return false };
        ts.iter().any(|&t| {
            let mut t = t;
            for _ in 0..=parent.len() + 1 {
                if t == want {
                    return true;
                }
                match parent.get(t) {
                    Some(&p) if t != OBJECT => t = p,
                    _ => return want == OBJECT,
                }
            }
            false
        })
    };
    let values: HashMap<(String, Vec<String>), Value> =
        problem.values.iter().map(|(f, a, v)| ((f.clone(), a.clone()), v.clone())).collect();
    let mut state: HashSet<Fact> = problem.init.iter().cloned().collect();
    let mut cost = 0u64;
    for (i, (name, args)) in plan.iter().enumerate() {
        let step = format!("step {} ({name}{}{})", i + 1, if args.is_empty() { "" } else { " " }, args.join(" "));
        let a: &Action = domain
            .actions
            .iter()
            .find(|a| &a.name == name)
            .ok_or_else(|| format!("{step}: no action `{name}` in domain `{}`", domain.name))?;
        if a.params.len() != args.len() {
            return Err(format!("{step}: `{name}` takes {} argument(s), given {}", a.params.len(), args.len()));
        }
        for (p, o) in a.params.iter().zip(args) {
            if !obj_types.contains_key(o.as_str()) {
                return Err(format!("{step}: unknown object `{o}`"));
            }
            if !p.types.iter().any(|t| is_a(o, t)) {
                return Err(format!("{step}: `{o}` is not of type {} (parameter {})", p.types.join(" or "), p.name));
            }
        }
        let obj = |t: &Term| -> String {
            match t {
                Term::Var(v) => args[*v].clone(),
                Term::Obj(o) => o.clone(),
            }
        };
        let inst = |at: &crate::pddl::Atom| Fact { pred: at.pred.clone(), args: at.args.iter().map(obj).collect() };
        for l in &a.pre {
            let f = inst(&l.atom);
            if state.contains(&f) != l.positive {
                return Err(format!(
                    "{step}: precondition {}{f}{} does not hold",
                    if l.positive { "" } else { "(not " },
                    if l.positive { "" } else { ")" }
                ));
            }
        }
        let eval = |e: &NumExpr| eval(e, &values, &obj);
        for c in &a.conds {
            let ok = match c {
                Cond::Equal(x, y, pos) => (obj(x) == obj(y)) == *pos,
                Cond::Compare(op, x, y) => match (eval(x), eval(y)) {
                    (Some(x), Some(y)) => op.holds(x, y),
                    _ => false,
                },
            };
            if !ok {
                return Err(format!("{step}: an expression of `{name}` is false ({c:?})"));
            }
        }
        for at in &a.del {
            state.remove(&inst(at));
        }
        for at in &a.add {
            state.insert(inst(at));
        }
        cost += if problem.metric {
            match &a.cost {
                None => 0,
                Some(e) => match eval(e) {
                    Some(c) if c >= 0.0 && c.fract() == 0.0 => c as u64,
                    other => return Err(format!("{step}: the cost is not a non-negative integer ({other:?})")),
                },
            }
        } else {
            1
        };
    }
    for (g, pos) in &problem.goal {
        if state.contains(g) != *pos {
            return Err(format!(
                "the goal {}{g}{} does not hold at the end of the plan",
                if *pos { "" } else { "(not " },
                if *pos { "" } else { ")" }
            ));
        }
    }
    Ok(cost)
}

fn eval(e: &NumExpr, values: &HashMap<(String, Vec<String>), Value>, obj: &dyn Fn(&Term) -> String) -> Option<f64> {
    Some(match e {
        NumExpr::Num(n) => *n,
        NumExpr::Neg(x) => -eval(x, values, obj)?,
        NumExpr::Bin(op, x, y) => {
            let (x, y) = (eval(x, values, obj)?, eval(y, values, obj)?);
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                _ if y == 0.0 => return None,
                _ => x / y,
            }
        }
        NumExpr::Fluent(f, args) => match values.get(&(f.clone(), args.iter().map(obj).collect()))? {
            Value::Num(n) => *n,
            Value::Str(_) => return None,
        },
    })
}
