//! PDDL front-end: STRIPS with `:typing`, `:negative-preconditions`,
//! `:equality`, `:action-costs` and static numeric fluents used as object
//! attributes, plus the MCL extension `:mcl (Mission arg ...)` on actions and
//! string-valued attributes `(= (description cable) "power-cable")`
//! (docs/planning.md). Hand-written and tolerant: every error names the file,
//! line and column and what was expected; sections are parsed independently so
//! that one bad action does not hide the errors of the next one. Never panics.

use crate::sexpr::{self, Error, Sexpr, Source, Span};
use serde::Serialize;
use std::cell::RefCell;
use std::collections::HashSet;
use std::fmt;

/// The root of the type hierarchy.
pub const OBJECT: &str = "object";

/// A variable or an object in an atom.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Term {
    /// Index of an action parameter.
    Var(usize),
    /// An object (domain constant or problem object), lower case.
    Obj(String),
}

/// `(pred t1 ... tn)`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Atom {
    pub pred: String,
    pub args: Vec<Term>,
}

/// A possibly negated atom.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Literal {
    pub atom: Atom,
    pub positive: bool,
}

/// A numeric expression over static fluents (object attributes).
#[derive(Clone, Debug, PartialEq)]
pub enum NumExpr {
    Num(f64),
    /// `(f t1 ... tn)`; `?l.x` is `(x ?l)`.
    Fluent(String, Vec<Term>),
    Bin(char, Box<NumExpr>, Box<NumExpr>),
    Neg(Box<NumExpr>),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum CmpOp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

impl CmpOp {
    pub fn negate(self) -> CmpOp {
        match self {
            CmpOp::Lt => CmpOp::Ge,
            CmpOp::Le => CmpOp::Gt,
            CmpOp::Gt => CmpOp::Le,
            CmpOp::Ge => CmpOp::Lt,
            CmpOp::Eq => CmpOp::Ne,
            CmpOp::Ne => CmpOp::Eq,
        }
    }
    pub fn holds(self, a: f64, b: f64) -> bool {
        match self {
            CmpOp::Lt => a < b,
            CmpOp::Le => a <= b,
            CmpOp::Gt => a > b,
            CmpOp::Ge => a >= b,
            CmpOp::Eq => a == b,
            CmpOp::Ne => a != b,
        }
    }
}

/// An expression of the seed (Extract 7.1 `l1 != l2`): object (in)equality or
/// a comparison of attributes and numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum Cond {
    /// `(= ?a ?b)` when `positive`, `(not (= ?a ?b))` otherwise.
    Equal(Term, Term, bool),
    Compare(CmpOp, NumExpr, NumExpr),
}

/// An argument of the MCL mission an action runs.
#[derive(Clone, Debug, PartialEq)]
pub enum MclArg {
    /// A number, as written.
    Num(String),
    /// A double-quoted string.
    Str(String),
    /// A bare identifier passed as is (a symbolic value, e.g. `timeout`).
    Symbol(String),
    /// `?b`: the name of the object bound to a parameter.
    Object(Term),
    /// `?b.x` or `(x ?b)`: an attribute of the object.
    Attr(Term, String),
}

/// `:mcl (MclMove ?l2.x ?l2.y ?l2.z)` (Extract 7.2).
#[derive(Clone, Debug, PartialEq)]
pub struct MclCall {
    /// The mission's name, case kept (MCL is case-sensitive).
    pub name: String,
    pub args: Vec<MclArg>,
    pub line: usize,
    pub column: usize,
    /// The file the call is written in when it is not the domain's: the
    /// .mcl file of a `planning` operator or of a `pddl_map` mapping.
    pub file: Option<String>,
}

/// A typed parameter, constant, object or predicate argument.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TypedName {
    pub name: String,
    /// One type, or several for `(either a b)`.
    pub types: Vec<String>,
}

/// A predicate or function declaration.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Signature {
    pub name: String,
    pub params: Vec<TypedName>,
}

/// A planning operator (Definition 7.2.3 with the seed's expressions, cost and mcl).
#[derive(Clone, Debug, PartialEq)]
pub struct Action {
    pub name: String,
    pub params: Vec<TypedName>,
    pub pre: Vec<Literal>,
    pub conds: Vec<Cond>,
    pub add: Vec<Atom>,
    pub del: Vec<Atom>,
    /// Sum of the `(increase (total-cost) e)` effects.
    pub cost: Option<NumExpr>,
    pub mcl: Option<MclCall>,
    pub line: usize,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Domain {
    pub file: String,
    pub name: String,
    pub requirements: Vec<String>,
    /// (type, parent); `object` is implicit.
    pub types: Vec<(String, String)>,
    pub constants: Vec<TypedName>,
    pub predicates: Vec<Signature>,
    pub functions: Vec<Signature>,
    pub actions: Vec<Action>,
}

/// A value of a numeric fluent, or of a string attribute.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    Num(f64),
    Str(String),
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Num(n) => write!(f, "{}", fmt_num(*n)),
            Value::Str(s) => write!(f, "\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"")),
        }
    }
}

/// A number as MCL writes it: no exponent, no trailing `.0`.
pub fn fmt_num(n: f64) -> String {
    if n.fract() == 0.0 && n.abs() < 1e15 {
        format!("{}", n as i64)
    } else {
        format!("{n}")
    }
}

/// A ground atom: predicate and object names.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Fact {
    pub pred: String,
    pub args: Vec<String>,
}

impl Fact {
    pub fn new(pred: &str, args: &[&str]) -> Fact {
        Fact { pred: pred.to_ascii_lowercase(), args: args.iter().map(|a| a.to_ascii_lowercase()).collect() }
    }
}

impl fmt::Display for Fact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}", self.pred)?;
        for a in &self.args {
            write!(f, " {a}")?;
        }
        write!(f, ")")
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Problem {
    pub file: String,
    pub name: String,
    pub domain: String,
    pub objects: Vec<TypedName>,
    pub init: Vec<Fact>,
    /// `(= (f o1 ... on) v)` in `:init`.
    pub values: Vec<(String, Vec<String>, Value)>,
    /// Goal literals (positive or negated).
    pub goal: Vec<(Fact, bool)>,
    /// `(:metric minimize (total-cost))`: action costs count; otherwise every
    /// action costs 1 (as in Fast Downward and the IPC).
    pub metric: bool,
}

impl Problem {
    /// The same problem from another initial state (re-planning).
    pub fn with_init(&self, init: Vec<Fact>) -> Problem {
        Problem { init, ..self.clone() }
    }
}

type R<T> = Result<T, Error>;

struct P<'a> {
    src: Source<'a>,
    errors: Vec<Error>,
    /// Every atom of the actions read so far, in source order, so that a
    /// predicate's error is located at its use.
    uses: RefCell<Vec<PredicateUse>>,
}

/// An atom of an action: its predicate, number of arguments and place.
struct PredicateUse {
    action: String,
    pred: String,
    arity: usize,
    span: Span,
}

fn is_number(s: &str) -> bool {
    let t = s.strip_prefix('-').unwrap_or(s);
    let mut dot = false;
    let mut digits = false;
    for c in t.chars() {
        match c {
            '0'..='9' => digits = true,
            '.' if !dot => dot = true,
            _ => return false,
        }
    }
    digits
}

fn parse_number(s: &str) -> Option<f64> {
    if is_number(s) {
        s.parse::<f64>().ok().filter(|v| v.is_finite())
    } else {
        None
    }
}

impl<'a> P<'a> {
    fn err(&self, span: Span, msg: impl Into<String>) -> Error {
        self.src.error(span, msg)
    }

    fn expect_list<'e>(&self, e: &'e Sexpr, what: &str) -> R<&'e [Sexpr]> {
        e.list().ok_or_else(|| self.err(e.span(), format!("expected {what}, found {}", e.describe())))
    }

    /// A plain name (not a variable, not a keyword, not a number).
    fn name(&self, e: &Sexpr, what: &str) -> R<String> {
        match e.atom() {
            Some(a) if !a.starts_with('?') && !a.starts_with(':') && !is_number(&a) => Ok(a),
            _ => Err(self.err(e.span(), format!("expected {what}, found {}", e.describe()))),
        }
    }

    /// `(define (KIND name) sections...)`: returns the name and the sections.
    fn define<'e>(&mut self, top: &'e [Sexpr], kind: &str, whole: Span) -> R<(String, &'e [Sexpr])> {
        let Some(first) = top.first() else {
            return Err(self.err(whole, format!("expected `(define ({kind} NAME) ...)`, found an empty file")));
        };
        if top.len() > 1 {
            return Err(
                self.err(top[1].span(), format!("expected the end of the file after the `define` of the {kind}"))
            );
        }
        let l = self.expect_list(first, &format!("`(define ({kind} NAME) ...)`"))?;
        if l.first().and_then(|h| h.atom()).as_deref() != Some("define") {
            return Err(self.err(first.span(), format!("expected `(define ({kind} NAME) ...)`")));
        }
        let head =
            l.get(1).ok_or_else(|| self.err(first.span(), format!("expected `({kind} NAME)` after `define`")))?;
        let hl = self.expect_list(head, &format!("`({kind} NAME)`"))?;
        if hl.len() != 2 || hl[0].atom().as_deref() != Some(kind) {
            return Err(self.err(head.span(), format!("expected `({kind} NAME)`")));
        }
        let name = self.name(&hl[1], &format!("the {kind}'s name"))?;
        Ok((name, &l[2..]))
    }

    /// `a b - t c - (either u v) d`.
    fn typed_list(&self, items: &[Sexpr], what: &str) -> R<Vec<TypedName>> {
        let mut out = Vec::new();
        let mut pending: Vec<String> = Vec::new();
        let mut i = 0;
        while i < items.len() {
            let e = &items[i];
            if e.atom().as_deref() == Some("-") {
                let t = items.get(i + 1).ok_or_else(|| self.err(e.span(), "expected a type after `-`"))?;
                let types = self.type_ref(t)?;
                if pending.is_empty() {
                    return Err(self.err(e.span(), format!("expected {what} before `-`")));
                }
                for n in pending.drain(..) {
                    out.push(TypedName { name: n, types: types.clone() });
                }
                i += 2;
                continue;
            }
            let n = match e.atom() {
                Some(a) if !a.starts_with(':') && !is_number(&a) && a != "-" => a,
                _ => return Err(self.err(e.span(), format!("expected {what}, found {}", e.describe()))),
            };
            pending.push(n);
            i += 1;
        }
        for n in pending {
            out.push(TypedName { name: n, types: vec![OBJECT.to_string()] });
        }
        Ok(out)
    }

    fn type_ref(&self, t: &Sexpr) -> R<Vec<String>> {
        match t {
            Sexpr::List(l, _) if l.first().and_then(|h| h.atom()).as_deref() == Some("either") && l.len() > 1 => {
                l[1..].iter().map(|x| self.name(x, "a type")).collect()
            }
            _ => Ok(vec![self.name(t, "a type name or `(either ...)`")?]),
        }
    }

    fn term(&self, e: &Sexpr, scope: &[TypedName]) -> R<Term> {
        let a = e
            .atom()
            .ok_or_else(|| self.err(e.span(), format!("expected a variable or an object, found {}", e.describe())))?;
        if let Some(v) = a.strip_prefix('?') {
            if a.contains('.') {
                return Err(self.err(e.span(), format!("expected a variable or an object, found the attribute `{a}` (attributes only go in comparisons and in :mcl)")));
            }
            match scope.iter().position(|p| p.name == a) {
                Some(i) => Ok(Term::Var(i)),
                None => Err(self.err(e.span(), format!("unknown variable `?{v}`: not a parameter of this action"))),
            }
        } else if is_number(&a) || a.starts_with(':') {
            Err(self.err(e.span(), format!("expected a variable or an object, found `{a}`")))
        } else {
            Ok(Term::Obj(a))
        }
    }

    fn atom(&self, l: &[Sexpr], span: Span, scope: &[TypedName]) -> R<Atom> {
        let head = l.first().ok_or_else(|| self.err(span, "expected an atom `(predicate arg ...)`, found `()`"))?;
        let pred = self.name(head, "a predicate name")?;
        let args = l[1..].iter().map(|x| self.term(x, scope)).collect::<R<Vec<_>>>()?;
        Ok(Atom { pred, args })
    }

    /// An atom of a predicate in an action, recorded for `check_domain`.
    fn pred_atom(&self, l: &[Sexpr], span: Span, scope: &[TypedName]) -> R<Atom> {
        let a = self.atom(l, span, scope)?;
        let at = l.first().map_or(span, Sexpr::span);
        let arity = a.args.len();
        self.uses.borrow_mut().push(PredicateUse { action: String::new(), pred: a.pred.clone(), arity, span: at });
        Ok(a)
    }

    /// `?l.x` as a fluent term.
    fn attr_atom(&self, a: &str, span: Span, scope: &[TypedName]) -> R<Option<(Term, String)>> {
        if !a.starts_with('?') {
            return Ok(None);
        }
        let Some((v, attr)) = a.split_once('.') else { return Ok(None) };
        if attr.is_empty() || attr.contains('.') {
            return Err(self.err(span, format!("expected `?variable.attribute`, found `{a}`")));
        }
        match scope.iter().position(|p| p.name == v) {
            Some(i) => Ok(Some((Term::Var(i), attr.to_string()))),
            None => Err(self.err(span, format!("unknown variable `{v}`: not a parameter of this action"))),
        }
    }

    fn num_expr(&self, e: &Sexpr, scope: &[TypedName]) -> R<NumExpr> {
        match e {
            Sexpr::Atom(raw, span) => {
                let a = raw.to_ascii_lowercase();
                if let Some(n) = parse_number(&a) {
                    return Ok(NumExpr::Num(n));
                }
                if let Some((t, attr)) = self.attr_atom(&a, *span, scope)? {
                    return Ok(NumExpr::Fluent(attr, vec![t]));
                }
                Err(self
                    .err(*span, format!("expected a number, `?var.attribute` or `(function arg ...)`, found `{raw}`")))
            }
            Sexpr::Str(_, span) => Err(self.err(*span, "expected a numeric expression, found a string")),
            Sexpr::List(l, span) => {
                let head = l.first().ok_or_else(|| self.err(*span, "expected a numeric expression, found `()`"))?;
                let h = head.atom().unwrap_or_default();
                match (h.as_str(), l.len()) {
                    ("-", 2) => Ok(NumExpr::Neg(Box::new(self.num_expr(&l[1], scope)?))),
                    ("+" | "-" | "*" | "/", 3) => Ok(NumExpr::Bin(
                        h.chars().next().unwrap_or('+'),
                        Box::new(self.num_expr(&l[1], scope)?),
                        Box::new(self.num_expr(&l[2], scope)?),
                    )),
                    ("+" | "-" | "*" | "/", _) => Err(self.err(*span, format!("expected two operands for `{h}`"))),
                    _ => {
                        let a = self.atom(l, *span, scope)?;
                        Ok(NumExpr::Fluent(a.pred, a.args))
                    }
                }
            }
        }
    }

    /// True when `e` is written as an object term (for `=`).
    fn is_object_term(e: &Sexpr) -> bool {
        match e.atom() {
            Some(a) => !(is_number(&a) || a.starts_with('?') && a.contains('.')),
            None => false,
        }
    }

    fn cond(&self, op: &str, l: &[Sexpr], span: Span, scope: &[TypedName], positive: bool) -> R<Cond> {
        if l.len() != 3 {
            return Err(self.err(span, format!("expected two operands for `{op}`")));
        }
        if matches!(op, "=" | "!=") && Self::is_object_term(&l[1]) && Self::is_object_term(&l[2]) {
            let pos = (op == "=") == positive;
            return Ok(Cond::Equal(self.term(&l[1], scope)?, self.term(&l[2], scope)?, pos));
        }
        let mut c = match op {
            "<" => CmpOp::Lt,
            "<=" => CmpOp::Le,
            ">" => CmpOp::Gt,
            ">=" => CmpOp::Ge,
            "=" => CmpOp::Eq,
            _ => CmpOp::Ne,
        };
        if !positive {
            c = c.negate();
        }
        Ok(Cond::Compare(c, self.num_expr(&l[1], scope)?, self.num_expr(&l[2], scope)?))
    }

    fn precondition(
        &self,
        e: &Sexpr,
        scope: &[TypedName],
        pre: &mut Vec<Literal>,
        conds: &mut Vec<Cond>,
        positive: bool,
    ) -> R<()> {
        let (l, span) = match e {
            Sexpr::List(l, s) => (l.as_slice(), *s),
            _ => return Err(self.err(e.span(), format!("expected a condition `(...)`, found {}", e.describe()))),
        };
        if l.is_empty() {
            return Ok(()); // `()`: the empty conjunction
        }
        let h = l[0].atom().unwrap_or_default();
        match h.as_str() {
            "and" if positive => {
                for x in &l[1..] {
                    self.precondition(x, scope, pre, conds, true)?;
                }
                Ok(())
            }
            "not" if positive => {
                if l.len() != 2 {
                    return Err(self.err(span, "expected one condition inside `not`"));
                }
                self.precondition(&l[1], scope, pre, conds, false)
            }
            "=" | "!=" | "<" | "<=" | ">" | ">=" => {
                conds.push(self.cond(&h, l, span, scope, positive)?);
                Ok(())
            }
            "and" | "not" => Err(self.err(span, format!("`{h}` inside `not` is not supported (only atoms and comparisons can be negated)"))),
            "or" | "imply" | "exists" | "forall" | "when" => Err(self.err(
                span,
                format!("`{h}` in a precondition is not supported: this planner reads STRIPS preconditions (atoms, `not`, `=`, comparisons)"),
            )),
            _ => {
                pre.push(Literal { atom: self.pred_atom(l, span, scope)?, positive });
                Ok(())
            }
        }
    }

    fn effect(&self, e: &Sexpr, scope: &[TypedName], a: &mut Action) -> R<()> {
        let (l, span) = match e {
            Sexpr::List(l, s) => (l.as_slice(), *s),
            _ => return Err(self.err(e.span(), format!("expected an effect `(...)`, found {}", e.describe()))),
        };
        if l.is_empty() {
            return Ok(());
        }
        let h = l[0].atom().unwrap_or_default();
        match h.as_str() {
            "and" => {
                for x in &l[1..] {
                    self.effect(x, scope, a)?;
                }
                Ok(())
            }
            "not" => {
                let inner = l.get(1).and_then(|x| x.list()).filter(|_| l.len() == 2);
                match inner {
                    Some(il) => {
                        a.del.push(self.pred_atom(il, l[1].span(), scope)?);
                        Ok(())
                    }
                    None => Err(self.err(span, "expected one atom inside `not`: `(not (predicate arg ...))`")),
                }
            }
            "increase" => {
                if l.len() != 3 {
                    return Err(self.err(span, "expected `(increase (total-cost) EXPRESSION)`"));
                }
                let target = l[1].list().and_then(|t| if t.len() == 1 { t[0].atom() } else { None });
                if target.as_deref() != Some("total-cost") {
                    return Err(self.err(l[1].span(), "only `(total-cost)` can be increased: numeric fluents are static attributes here"));
                }
                let v = self.num_expr(&l[2], scope)?;
                a.cost = Some(match a.cost.take() {
                    None => v,
                    Some(old) => NumExpr::Bin('+', Box::new(old), Box::new(v)),
                });
                Ok(())
            }
            "forall" | "when" => Err(self.err(span, format!("`{h}` effects are not supported: this planner reads STRIPS effects (atoms, `not`, `increase total-cost`)"))),
            "decrease" | "assign" | "scale-up" | "scale-down" => {
                Err(self.err(span, format!("`{h}` is not supported: numeric fluents are static attributes, only `(increase (total-cost) n)` changes")))
            }
            _ => {
                a.add.push(self.pred_atom(l, span, scope)?);
                Ok(())
            }
        }
    }

    fn mcl_call(&self, e: &Sexpr, scope: &[TypedName]) -> R<MclCall> {
        let (l, span) = match e {
            Sexpr::List(l, s) if !l.is_empty() => (l.as_slice(), *s),
            _ => {
                return Err(
                    self.err(e.span(), format!("expected `(MissionName arg ...)` after :mcl, found {}", e.describe()))
                )
            }
        };
        let name = match l[0].raw_atom() {
            Some(n) if !n.starts_with('?') && !n.starts_with(':') && !is_number(n) => n.to_string(),
            _ => {
                return Err(
                    self.err(l[0].span(), format!("expected the name of an MCL mission, found {}", l[0].describe()))
                )
            }
        };
        let mut args = Vec::new();
        for x in &l[1..] {
            args.push(match x {
                Sexpr::Str(s, _) => MclArg::Str(s.clone()),
                Sexpr::Atom(raw, sp) => {
                    let a = raw.to_ascii_lowercase();
                    if is_number(raw) {
                        MclArg::Num(raw.clone())
                    } else if let Some((t, attr)) = self.attr_atom(&a, *sp, scope)? {
                        MclArg::Attr(t, attr)
                    } else if a.starts_with('?') {
                        MclArg::Object(self.term(x, scope)?)
                    } else if a.starts_with(':') {
                        return Err(self
                            .err(*sp, format!("expected an argument, found the keyword `{raw}` (is a `)` missing?)")));
                    } else {
                        MclArg::Symbol(raw.clone())
                    }
                }
                Sexpr::List(il, sp) => {
                    if il.len() != 2 {
                        return Err(self.err(*sp, "expected an attribute `(attribute ?var)` as an :mcl argument"));
                    }
                    let attr = self.name(&il[0], "an attribute name")?;
                    MclArg::Attr(self.term(&il[1], scope)?, attr)
                }
            });
        }
        let (line, column) = self.src.line_col(span.start);
        Ok(MclCall { name, args, line, column, file: None })
    }

    fn action(&self, l: &[Sexpr], span: Span) -> R<Action> {
        let name = self.name(
            l.get(1).ok_or_else(|| self.err(span, "expected the action's name after `:action`"))?,
            "the action's name",
        )?;
        let (line, _) = self.src.line_col(span.start);
        let mut a = Action {
            name,
            params: Vec::new(),
            pre: Vec::new(),
            conds: Vec::new(),
            add: Vec::new(),
            del: Vec::new(),
            cost: None,
            mcl: None,
            line,
        };
        let mut seen: HashSet<String> = HashSet::new();
        let mut i = 2;
        while i < l.len() {
            let key = l[i].atom().unwrap_or_default();
            if !key.starts_with(':') {
                return Err(self.err(
                    l[i].span(),
                    format!("expected `:parameters`, `:precondition`, `:effect` or `:mcl`, found {}", l[i].describe()),
                ));
            }
            let val = l.get(i + 1).ok_or_else(|| self.err(l[i].span(), format!("expected a value after `{key}`")))?;
            if !seen.insert(key.clone()) {
                return Err(self.err(l[i].span(), format!("`{key}` given twice in action `{}`", a.name)));
            }
            match key.as_str() {
                ":parameters" => {
                    let pl = self.expect_list(val, "a parameter list `(?x - type ...)`")?;
                    a.params = self.typed_list(pl, "a parameter `?name`")?;
                    for (k, p) in a.params.iter().enumerate() {
                        if !p.name.starts_with('?') || p.name.len() < 2 || p.name.contains('.') {
                            return Err(self.err(
                                pl.get(k).map(|x| x.span()).unwrap_or(val.span()),
                                format!("expected a parameter `?name`, found `{}`", p.name),
                            ));
                        }
                        if a.params[..k].iter().any(|q| q.name == p.name) {
                            return Err(self.err(val.span(), format!("parameter `{}` declared twice", p.name)));
                        }
                    }
                }
                ":precondition" => {
                    let (mut pre, mut conds) = (Vec::new(), Vec::new());
                    self.precondition(val, &a.params, &mut pre, &mut conds, true)?;
                    a.pre = pre;
                    a.conds = conds;
                }
                ":effect" => self.effect(val, &a.params.clone(), &mut a)?,
                ":mcl" => a.mcl = Some(self.mcl_call(val, &a.params)?),
                _ => {
                    return Err(self.err(
                        l[i].span(),
                        format!(
                            "unknown action key `{key}`: expected `:parameters`, `:precondition`, `:effect` or `:mcl`"
                        ),
                    ))
                }
            }
            if key == ":parameters"
                && (seen.contains(":precondition") || seen.contains(":effect") || seen.contains(":mcl"))
            {
                return Err(
                    self.err(l[i].span(), "`:parameters` must come before `:precondition`, `:effect` and `:mcl`")
                );
            }
            i += 2;
        }
        Ok(a)
    }

    fn signatures(&self, items: &[Sexpr], what: &str) -> R<Vec<Signature>> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < items.len() {
            let l = self.expect_list(&items[i], &format!("a {what} `(name ?x - type ...)`"))?;
            let name = self.name(
                l.first().ok_or_else(|| self.err(items[i].span(), format!("expected a {what} name")))?,
                &format!("a {what} name"),
            )?;
            let params = self.typed_list(&l[1..], "a parameter `?name`")?;
            out.push(Signature { name, params });
            i += 1;
            // `(:functions (f ?x) - number)`: skip the function type.
            if items.get(i).and_then(|x| x.atom()).as_deref() == Some("-") {
                i += 2;
            }
        }
        Ok(out)
    }
}

/// Parses a domain file. `file` names it in errors.
pub fn parse_domain(file: &str, text: &str) -> Result<Domain, Vec<Error>> {
    let mut p = P { src: Source::new(file, text), errors: Vec::new(), uses: RefCell::default() };
    let top = sexpr::read(&p.src).map_err(|e| vec![e])?;
    let (name, sections) = p.define(&top, "domain", Span::default()).map_err(|e| vec![e])?;
    let mut d = Domain { file: file.to_string(), name, ..Domain::default() };
    for s in sections {
        let r: R<()> = (|| {
            let l = p.expect_list(s, "a section `(:keyword ...)`")?;
            let key = l.first().and_then(|h| h.atom()).unwrap_or_default();
            match key.as_str() {
                ":requirements" => {
                    for r in &l[1..] {
                        match r.atom() {
                            Some(a) if a.starts_with(':') => d.requirements.push(a),
                            _ => return Err(p.err(r.span(), format!("expected a requirement `:name`, found {}", r.describe()))),
                        }
                    }
                }
                ":types" => {
                    for t in p.typed_list(&l[1..], "a type name")? {
                        if t.types.len() != 1 {
                            return Err(p.err(s.span(), format!("type `{}`: `either` is not allowed as a supertype", t.name)));
                        }
                        d.types.push((t.name, t.types[0].clone()));
                    }
                }
                ":constants" => d.constants.extend(p.typed_list(&l[1..], "a constant")?),
                ":predicates" => d.predicates.extend(p.signatures(&l[1..], "predicate")?),
                ":functions" => d.functions.extend(p.signatures(&l[1..], "function")?),
                ":action" => {
                    // The atoms of an action that does not parse are not checked.
                    let mark = p.uses.borrow().len();
                    match p.action(l, s.span()) {
                        Ok(a) => {
                            p.uses.borrow_mut()[mark..].iter_mut().for_each(|u| u.action = a.name.clone());
                            d.actions.push(a);
                        }
                        Err(e) => {
                            p.uses.borrow_mut().truncate(mark);
                            return Err(e);
                        }
                    }
                }
                ":durative-action" | ":derived" | ":process" | ":event" => {
                    return Err(p.err(s.span(), format!("`{key}` is not supported: this planner reads STRIPS actions")))
                }
                _ => {
                    return Err(p.err(
                        s.span(),
                        format!("expected `:requirements`, `:types`, `:constants`, `:predicates`, `:functions` or `:action`, found {}", s.describe()),
                    ))
                }
            }
            Ok(())
        })();
        if let Err(e) = r {
            p.errors.push(e);
        }
    }
    let more = check_domain(&p, &d);
    p.errors.extend(more);
    if p.errors.is_empty() {
        Ok(d)
    } else {
        Err(p.errors)
    }
}

/// Domain-level checks: known types, predicates with the right arity.
fn check_domain(p: &P<'_>, d: &Domain) -> Vec<Error> {
    let mut errs = Vec::new();
    // A supertype named after `-` is declared by that use (a subtype of `object`).
    let types: HashSet<&str> = d.types.iter().flat_map(|(t, p)| [t.as_str(), p.as_str()]).chain([OBJECT]).collect();
    let check_types = |errs: &mut Vec<Error>, tn: &TypedName, line: usize| {
        for t in &tn.types {
            if !types.contains(t.as_str()) {
                errs.push(Error {
                    file: d.file.clone(),
                    line,
                    column: 1,
                    message: format!("`{}` has the undeclared type `{t}`", tn.name),
                });
            }
        }
    };
    for c in &d.constants {
        check_types(&mut errs, c, 0);
    }
    for s in d.predicates.iter().chain(&d.functions) {
        for x in &s.params {
            check_types(&mut errs, x, 0);
        }
    }
    for a in &d.actions {
        for x in &a.params {
            check_types(&mut errs, x, a.line);
        }
    }
    // Each atom where it is written; an unknown predicate once, at its
    // first use (one misspelling, one error).
    let uses = p.uses.borrow();
    let mut unknown = HashSet::new();
    for u in uses.iter() {
        match d.predicates.iter().find(|s| s.name == u.pred) {
            None if unknown.insert(&u.pred) => {
                let declared: Vec<&str> = d.predicates.iter().map(|s| s.name.as_str()).collect();
                let mut message = format!("action `{}`: unknown predicate `{}`", u.action, u.pred);
                if !declared.is_empty() {
                    message.push_str(&format!(" (declared: {})", declared.join(", ")));
                }
                let mut again: Vec<String> = uses
                    .iter()
                    .filter(|v| v.pred == u.pred)
                    .skip(1)
                    .map(|v| p.src.line_col(v.span.start).0.to_string())
                    .collect();
                again.dedup();
                if !again.is_empty() {
                    message.push_str(&format!("; also written on line {}", again.join(", ")));
                }
                errs.push(p.src.error(u.span, message));
            }
            Some(s) if s.params.len() != u.arity => errs.push(p.src.error(
                u.span,
                format!(
                    "action `{}`: predicate `{}` takes {} argument(s), given {}",
                    u.action,
                    u.pred,
                    s.params.len(),
                    u.arity
                ),
            )),
            _ => {}
        }
    }
    let mut names = HashSet::new();
    for a in &d.actions {
        if !names.insert(&a.name) {
            errs.push(Error {
                file: d.file.clone(),
                line: a.line,
                column: 1,
                message: format!("action `{}` defined twice", a.name),
            });
        }
    }
    // `line 0` errors have no position: report them at the top of the file.
    for e in &mut errs {
        if e.line == 0 {
            let (l, c) = p.src.line_col(0);
            e.line = l;
            e.column = c;
        }
    }
    errs
}

/// Parses a problem file.
pub fn parse_problem(file: &str, text: &str) -> Result<Problem, Vec<Error>> {
    let mut p = P { src: Source::new(file, text), errors: Vec::new(), uses: RefCell::default() };
    let top = sexpr::read(&p.src).map_err(|e| vec![e])?;
    let (name, sections) = p.define(&top, "problem", Span::default()).map_err(|e| vec![e])?;
    let mut pr = Problem { file: file.to_string(), name, ..Problem::default() };
    let mut has_goal = false;
    for s in sections {
        let r: R<()> = (|| {
            let l = p.expect_list(s, "a section `(:keyword ...)`")?;
            let key = l.first().and_then(|h| h.atom()).unwrap_or_default();
            match key.as_str() {
                ":domain" => {
                    pr.domain = p.name(
                        l.get(1).ok_or_else(|| p.err(s.span(), "expected the domain's name"))?,
                        "the domain's name",
                    )?;
                }
                ":requirements" => {}
                ":objects" => pr.objects.extend(p.typed_list(&l[1..], "an object")?),
                ":init" => {
                    for x in &l[1..] {
                        let il = p.expect_list(
                            x,
                            "an initial fact `(predicate object ...)` or `(= (function object ...) value)`",
                        )?;
                        if il.first().and_then(|h| h.atom()).as_deref() == Some("=") {
                            if il.len() != 3 {
                                return Err(p.err(x.span(), "expected `(= (function object ...) value)`"));
                            }
                            let fl = match &il[1] {
                                Sexpr::List(fl, _) => fl.as_slice(),
                                a @ Sexpr::Atom(..) => std::slice::from_ref(a),
                                other => return Err(p.err(other.span(), "expected `(function object ...)`")),
                            };
                            let f = ground_fact(&p, fl, il[1].span())?;
                            let v = match &il[2] {
                                Sexpr::Str(s, _) => Value::Str(s.clone()),
                                e => match e.atom().and_then(|a| parse_number(&a)) {
                                    Some(n) => Value::Num(n),
                                    None => {
                                        return Err(p.err(
                                            e.span(),
                                            format!("expected a number or a string, found {}", e.describe()),
                                        ))
                                    }
                                },
                            };
                            pr.values.push((f.pred, f.args, v));
                        } else {
                            pr.init.push(ground_fact(&p, il, x.span())?);
                        }
                    }
                }
                ":goal" => {
                    has_goal = true;
                    let g = l.get(1).ok_or_else(|| p.err(s.span(), "expected a goal after `:goal`"))?;
                    goal(&p, g, true, &mut pr.goal)?;
                }
                ":metric" => {
                    let ok = l.len() == 3
                        && l[1].atom().as_deref() == Some("minimize")
                        && l[2].list().is_some_and(|t| t.len() == 1 && t[0].atom().as_deref() == Some("total-cost"));
                    if !ok {
                        return Err(p.err(s.span(), "expected `(:metric minimize (total-cost))`"));
                    }
                    pr.metric = true;
                }
                _ => {
                    return Err(p.err(
                        s.span(),
                        format!(
                            "expected `:domain`, `:objects`, `:init`, `:goal` or `:metric`, found {}",
                            s.describe()
                        ),
                    ))
                }
            }
            Ok(())
        })();
        if let Err(e) = r {
            p.errors.push(e);
        }
    }
    if !has_goal && p.errors.is_empty() {
        p.errors.push(p.err(Span::default(), format!("problem `{}` has no `(:goal ...)`", pr.name)));
    }
    if p.errors.is_empty() {
        Ok(pr)
    } else {
        Err(p.errors)
    }
}

fn ground_fact(p: &P<'_>, l: &[Sexpr], span: Span) -> R<Fact> {
    let head = l.first().ok_or_else(|| p.err(span, "expected `(predicate object ...)`, found `()`"))?;
    let pred = p.name(head, "a predicate name")?;
    let args = l[1..].iter().map(|x| p.name(x, "an object name")).collect::<R<Vec<_>>>()?;
    Ok(Fact { pred, args })
}

fn goal(p: &P<'_>, e: &Sexpr, positive: bool, out: &mut Vec<(Fact, bool)>) -> R<()> {
    let (l, span) = match e {
        Sexpr::List(l, s) => (l.as_slice(), *s),
        _ => return Err(p.err(e.span(), format!("expected a goal `(...)`, found {}", e.describe()))),
    };
    if l.is_empty() {
        return Ok(());
    }
    match l[0].atom().unwrap_or_default().as_str() {
        "and" if positive => l[1..].iter().try_for_each(|x| goal(p, x, true, out)),
        "not" if positive && l.len() == 2 => goal(p, &l[1], false, out),
        h @ ("and" | "not" | "or" | "imply" | "exists" | "forall" | "=" | "<" | ">" | "<=" | ">=") => {
            Err(p.err(span, format!("`{h}` is not supported here: a goal is a conjunction of facts and negated facts")))
        }
        _ => {
            out.push((ground_fact(p, l, span)?, positive));
            Ok(())
        }
    }
}
