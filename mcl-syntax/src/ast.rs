//! The syntax tree. Every node carries its span; names carry their own span so
//! that name resolution and the editor can point at them. Parts that failed to
//! parse are kept as `Error` nodes (or missing optional parts) so that the rest
//! of the file can still be analysed.

use crate::span::Span;

/// An identifier occurrence.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Name {
    pub text: String,
    pub span: Span,
}

/// A number as written (`-2`, `15.5`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Number {
    pub text: String,
    pub span: Span,
}

impl Number {
    pub fn value(&self) -> f64 {
        self.text.parse().unwrap_or(0.0)
    }
    /// The value as an unsigned integer, if it is one.
    pub fn as_u32(&self) -> Option<u32> {
        self.text.parse().ok()
    }
}

/// A whole source file.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct SourceFile {
    pub items: Vec<Item>,
}

/// A top-level item.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Item {
    Import(Import),
    Actions(ActionsBlock),
    Events(EventsBlock),
    Patterns(PatternsBlock),
    Tasks(TasksBlock),
    Mission(Mission),
    Constraints(ConstraintsBlock),
    Planning(PlanningBlock),
    PddlMap(PddlMapBlock),
}

impl Item {
    pub fn span(&self) -> Span {
        match self {
            Item::Import(x) => x.span,
            Item::Actions(x) => x.span,
            Item::Events(x) => x.span,
            Item::Patterns(x) => x.span,
            Item::Tasks(x) => x.span,
            Item::Mission(x) => x.span,
            Item::Constraints(x) => x.span,
            Item::Planning(x) => x.span,
            Item::PddlMap(x) => x.span,
        }
    }
}

/// `import "vehicle.mcl";`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Import {
    /// The path as written, unescaped.
    pub path: String,
    pub path_span: Span,
    pub span: Span,
}

/// `actions { name = Primitive( c: command, v: value, ... ); ... }`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ActionsBlock {
    pub actions: Vec<ActionDef>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ActionDef {
    pub name: Name,
    pub primitive: Name,
    /// `c: command`; `None` when missing (an error was reported).
    pub command: Option<Name>,
    /// The `v: value` parameters in order.
    pub params: Vec<Value>,
    pub span: Span,
}

/// A literal or symbolic value: an action parameter or a call argument.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Value {
    pub kind: ValueKind,
    pub span: Span,
}

impl Value {
    /// The value as written in the source (a string quoted, a list with its
    /// tag; `?` for one that failed to parse), for pictures and views of a
    /// mission.
    pub fn written(&self) -> String {
        match &self.kind {
            ValueKind::Number(n) => n.text.clone(),
            ValueKind::Str(s) => format!("\"{s}\""),
            ValueKind::Ident(n) => n.text.clone(),
            ValueKind::List { tag, items } => format!(
                "{}[{}]",
                tag.as_ref().map_or("", |t| t.text.as_str()),
                items.iter().map(Value::written).collect::<Vec<_>>().join(", ")
            ),
            ValueKind::Error => "?".into(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ValueKind {
    /// An identifier: a task parameter (in actions), a mission parameter or a
    /// symbolic value handed to the vehicle (in calls).
    Ident(Name),
    Number(Number),
    /// A string literal, unescaped.
    Str(String),
    /// `[a, b]` or a tagged list `path[[0, 0], [1, 1]]`.
    List {
        tag: Option<Name>,
        items: Vec<Value>,
    },
    /// A value that failed to parse.
    Error,
}

/// `events { e1; e2; }`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct EventsBlock {
    pub events: Vec<Name>,
    pub span: Span,
}

/// `pattern { ... }` (or `patterns { ... }`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PatternsBlock {
    pub patterns: Vec<Pattern>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Pattern {
    pub name: Name,
    pub body: PatternBody,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum PatternBody {
    /// `P_X : file.xml;` — a net read from a PNML file, relative to this file.
    File { path: String, path_span: Span },
    /// `{ places {...} transitions {...} arcs {...} }`
    Net(PatternNet),
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct PatternNet {
    pub places: Vec<PlaceDef>,
    pub transitions: Vec<TransitionDef>,
    pub arcs: Vec<ArcDef>,
}

/// `name(.interface)?((tokens))?;`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlaceDef {
    pub name: Name,
    pub interface: Option<Number>,
    pub tokens: Option<Number>,
    pub span: Span,
}

/// `name(.interface)?((delay))?;` — a delay makes the transition timed.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TransitionDef {
    pub name: Name,
    pub interface: Option<Number>,
    pub delay: Option<Delay>,
    pub span: Span,
}

/// The delay of a timed transition.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Delay {
    /// A fixed number of seconds: `T(30)`.
    Fixed(Number),
    /// Taken from the task parameter with this name: `T(timeout)`.
    Param(Name),
}

/// A place or transition named in an arc, optionally with its interface id.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct NodeRef {
    pub name: Name,
    pub interface: Option<Number>,
}

/// `source -> target (weight)?;`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ArcDef {
    pub source: NodeRef,
    pub target: NodeRef,
    pub weight: Option<Number>,
    pub span: Span,
}

/// `tasks { ... }`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TasksBlock {
    pub tasks: Vec<TaskDef>,
    pub span: Span,
}

/// `Goto( way-point ): AchieveOneGoal { a: enableGoto -> T0; e: ok -> T2; }`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TaskDef {
    pub name: Name,
    pub params: Vec<Name>,
    pub pattern: Option<Name>,
    pub bindings: Vec<Binding>,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    Action,
    Event,
}

/// `a: action -> T1, T2;` or `e: event -> T3;`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Binding {
    pub kind: BindingKind,
    pub target: Name,
    pub transitions: Vec<Name>,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MissionKind {
    /// `mission ...`
    Mission,
    /// `mcl_plan_op ...` (a planning operator's mission, seed chapter 7).
    PlanOp,
}

/// A mission: `mission { ... }`, `mission : auv { ... }`,
/// `mission MclMove( x, y, z ) { ... }`, `mcl_plan_op Op( ... ) { ... }`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Mission {
    pub kind: MissionKind,
    pub keyword_span: Span,
    pub name: Option<Name>,
    pub params: Vec<Name>,
    /// The BNF's optional `[ ID at NUM ]` after the name.
    pub placement: Option<(Name, Number)>,
    pub body: Block,
    pub span: Span,
}

/// A `;`-separated sequence of statements (one statement when there is no `;`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Block {
    pub stmts: Vec<Stmt>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Stmt {
    pub kind: StmtKind,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParallelOp {
    And,
    Or,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MonitorKind {
    /// `condition ( B ) do { C }`: when B ends ok, A is aborted and C runs once.
    Condition,
    /// `while_condition ( B ) do { C }`: C runs and then the monitor starts again.
    WhileCondition,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct MonitorHandler {
    pub kind: MonitorKind,
    pub keyword_span: Span,
    pub condition: Block,
    pub action: Block,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum StmtKind {
    Call(Call),
    /// `while ( A ) { B }`
    While {
        keyword: Span,
        cond: Block,
        body: Block,
    },
    /// `if ( A ) { B } (else { C })?`
    If {
        keyword: Span,
        cond: Block,
        then: Block,
        otherwise: Option<Block>,
        /// Set when the else branch was written `then { C }` (seed Table B.4).
        else_written_then: Option<Span>,
    },
    /// `parallel { A } and { B } or ...`; `ops.len() == branches.len() - 1`.
    Parallel {
        keyword: Span,
        branches: Vec<Block>,
        ops: Vec<(ParallelOp, Span)>,
    },
    /// `try { A } catch { B }`
    Try {
        keyword: Span,
        body: Block,
        catch: Block,
    },
    /// `not ( A )`
    Not {
        keyword: Span,
        body: Block,
    },
    /// `monitor { A } (condition|while_condition) ( B ) do { C } ...`
    Monitor {
        keyword: Span,
        body: Block,
        handlers: Vec<MonitorHandler>,
    },
    /// A statement that failed to parse.
    Error,
}

/// `Task( arg, ... ) : label`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Call {
    pub name: Name,
    pub args: Vec<Value>,
    /// The span of `( ... )`.
    pub args_span: Span,
    pub label: Option<Name>,
    pub span: Span,
}

/// `constraints { ... }`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ConstraintsBlock {
    pub constraints: Vec<Constraint>,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConstraintKind {
    Mutex,
    Order,
    Sync,
}

impl ConstraintKind {
    pub fn as_str(self) -> &'static str {
        match self {
            ConstraintKind::Mutex => "mutex",
            ConstraintKind::Order => "order",
            ConstraintKind::Sync => "sync",
        }
    }
}

/// `mutex { m:l, ... } = N`, `order { m:l, m:l }`, `sync { m:l, ... }` (or
/// the BNF spellings `_mutex_`, `_order_`, `_sync_`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Constraint {
    pub kind: ConstraintKind,
    pub keyword_span: Span,
    /// True for the BNF spelling `_mutex_` etc.
    pub bnf_spelling: bool,
    pub refs: Vec<LabelRef>,
    /// `= N` of a mutex.
    pub bound: Option<Number>,
    pub span: Span,
}

/// `mission:label`, or a bare `label` (BNF `listId`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct LabelRef {
    pub mission: Option<Name>,
    pub label: Name,
    pub span: Span,
}

// ---------------------------------------------------------------------------
// Planning (seed chapter 7, docs/planning.md).

/// `planning { ... }`: types, entities, functions, operators, initial state
/// and goal of a planning problem (seed 7.2, Extracts 7.1-7.2, Table 8.1).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanningBlock {
    pub keyword_span: Span,
    pub defs: Vec<PlanDef>,
    pub span: Span,
}

/// One definition of a `planning` block.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum PlanDef {
    Type(PlanType),
    Entity(PlanEntity),
    Function(PlanFunction),
    Operator(PlanOperator),
    /// `initial { ... }` or `goal { ... }`.
    Facts(PlanFacts),
}

impl PlanDef {
    pub fn span(&self) -> Span {
        match self {
            PlanDef::Type(x) => x.span,
            PlanDef::Entity(x) => x.span,
            PlanDef::Function(x) => x.span,
            PlanDef::Operator(x) => x.span,
            PlanDef::Facts(x) => x.span,
        }
    }
}

/// `type location { x; y; z; }`, `type robot;`, `type auv : robot;`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanType {
    pub keyword_span: Span,
    pub name: Name,
    pub parent: Option<Name>,
    /// The attributes every entity of the type has.
    pub attrs: Vec<Name>,
    pub span: Span,
}

/// `entity location dock { x = 0; y = 0; z = 0; }` or `entity robot auv;`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanEntity {
    pub keyword_span: Span,
    pub ty: Name,
    pub name: Name,
    pub values: Vec<AttrValue>,
    pub span: Span,
}

/// `x = 0;` in an entity.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct AttrValue {
    pub name: Name,
    pub value: Value,
    pub span: Span,
}

/// `function distance( zone, zone );`: a value per tuple of entities, given
/// in `initial` as `distance( deploy, recovery ) = 5;`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanFunction {
    pub keyword_span: Span,
    pub name: Name,
    /// The types of the arguments.
    pub params: Vec<Name>,
    pub span: Span,
}

/// `operator move( vehicle v, location l1, location l2 ) { ... }`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanOperator {
    pub keyword_span: Span,
    pub name: Name,
    pub params: Vec<TypedParam>,
    pub parts: Vec<OpPart>,
    pub span: Span,
}

/// `vehicle v`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TypedParam {
    pub ty: Name,
    pub name: Name,
}

/// One part of an operator.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct OpPart {
    pub keyword_span: Span,
    pub kind: OpPartKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum OpPartKind {
    /// `precond { v in l1; not v busy; }`
    Precond(Vec<PlanFact>),
    /// `add { ... }`
    Add(Vec<PlanFact>),
    /// `del { ... }`
    Del(Vec<PlanFact>),
    /// `expression { l1 != l2; }`
    Expression(Vec<PlanExpr>),
    /// `cost 1;`, `cost distance( a, b );`
    Cost(PlanOperand),
    /// `mcl MclMove( l2.x, l2.y, l2.z );`
    Mcl(PlanCall),
}

impl OpPartKind {
    pub fn keyword(&self) -> &'static str {
        match self {
            OpPartKind::Precond(_) => "precond",
            OpPartKind::Add(_) => "add",
            OpPartKind::Del(_) => "del",
            OpPartKind::Expression(_) => "expression",
            OpPartKind::Cost(_) => "cost",
            OpPartKind::Mcl(_) => "mcl",
        }
    }
}

/// A fact `entity relation [entity]` (seed 7.2.1: `ictineu in dock`,
/// `cable found`), negated with `not` in preconditions and goals.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanFact {
    pub negated: Option<Span>,
    pub subject: Name,
    pub relation: Name,
    pub object: Option<Name>,
    pub span: Span,
}

impl PlanFact {
    /// The entities (or parameters) the fact relates.
    pub fn args(&self) -> impl Iterator<Item = &Name> {
        std::iter::once(&self.subject).chain(self.object.as_ref())
    }
}

/// `initial { ... }` or `goal { ... }`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanFacts {
    pub keyword_span: Span,
    pub goal: bool,
    pub facts: Vec<PlanFact>,
    /// `distance( deploy, recovery ) = 5;` (only in `initial`).
    pub values: Vec<FunctionValue>,
    pub span: Span,
}

/// `distance( deploy, recovery ) = 5;`
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FunctionValue {
    pub name: Name,
    pub args: Vec<Name>,
    pub value: Value,
    pub span: Span,
}

/// An operand of an expression, a cost or an `mcl` argument.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanOperand {
    pub kind: OperandKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum OperandKind {
    /// A parameter, an entity, or (in `mcl`) a symbolic value.
    Name(Name),
    /// `l2.x`
    Attr(Name, Name),
    /// `distance( a, b )`
    Function(Name, Vec<Name>),
    /// A number or a string.
    Literal(Value),
}

/// `l1 != l2`, `l2.z <= v.max_depth`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanExpr {
    pub left: PlanOperand,
    /// `!=`, `==` (or `=`), `<`, `<=`, `>`, `>=`.
    pub op: String,
    pub op_span: Span,
    pub right: PlanOperand,
    pub span: Span,
}

/// `MclMove( l2.x, l2.y, l2.z )`: the MCL mission operator an operator runs.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PlanCall {
    pub name: Name,
    pub args: Vec<PlanOperand>,
    pub span: Span,
}

/// `pddl_map { move( v, l1, l2 ) -> MclMove( l2.x, l2.y, l2.z ); }`: the MCL
/// missions of the actions of a PDDL domain.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PddlMapBlock {
    pub keyword_span: Span,
    pub maps: Vec<PddlMapping>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PddlMapping {
    /// The PDDL action's name.
    pub action: Name,
    /// Names for the action's parameters, in order.
    pub params: Vec<Name>,
    pub call: PlanCall,
    pub span: Span,
}

/// Calls `f` on every span of a value (to move or erase them).
pub fn value_spans_mut(v: &mut Value, f: &mut dyn FnMut(&mut Span)) {
    f(&mut v.span);
    match &mut v.kind {
        ValueKind::Ident(n) => f(&mut n.span),
        ValueKind::Number(n) => f(&mut n.span),
        ValueKind::List { tag, items } => {
            if let Some(t) = tag {
                f(&mut t.span);
            }
            for i in items {
                value_spans_mut(i, f);
            }
        }
        ValueKind::Str(_) | ValueKind::Error => {}
    }
}

impl PlanOperand {
    pub fn spans_mut(&mut self, f: &mut dyn FnMut(&mut Span)) {
        f(&mut self.span);
        match &mut self.kind {
            OperandKind::Name(n) => f(&mut n.span),
            OperandKind::Attr(a, b) => {
                f(&mut a.span);
                f(&mut b.span);
            }
            OperandKind::Function(n, args) => {
                f(&mut n.span);
                args.iter_mut().for_each(|a| f(&mut a.span));
            }
            OperandKind::Literal(v) => value_spans_mut(v, f),
        }
    }
}

impl PlanCall {
    pub fn spans_mut(&mut self, f: &mut dyn FnMut(&mut Span)) {
        f(&mut self.span);
        f(&mut self.name.span);
        self.args.iter_mut().for_each(|a| a.spans_mut(f));
    }
}

impl PlanFact {
    pub fn spans_mut(&mut self, f: &mut dyn FnMut(&mut Span)) {
        f(&mut self.span);
        if let Some(s) = &mut self.negated {
            f(s);
        }
        f(&mut self.subject.span);
        f(&mut self.relation.span);
        if let Some(o) = &mut self.object {
            f(&mut o.span);
        }
    }
}

impl PlanningBlock {
    /// Calls `f` on every span of the block (to move or erase them).
    pub fn spans_mut(&mut self, f: &mut dyn FnMut(&mut Span)) {
        f(&mut self.keyword_span);
        f(&mut self.span);
        for d in &mut self.defs {
            match d {
                PlanDef::Type(t) => {
                    f(&mut t.keyword_span);
                    f(&mut t.span);
                    f(&mut t.name.span);
                    if let Some(p) = &mut t.parent {
                        f(&mut p.span);
                    }
                    t.attrs.iter_mut().for_each(|a| f(&mut a.span));
                }
                PlanDef::Entity(x) => {
                    f(&mut x.keyword_span);
                    f(&mut x.span);
                    f(&mut x.ty.span);
                    f(&mut x.name.span);
                    for v in &mut x.values {
                        f(&mut v.span);
                        f(&mut v.name.span);
                        value_spans_mut(&mut v.value, f);
                    }
                }
                PlanDef::Function(x) => {
                    f(&mut x.keyword_span);
                    f(&mut x.span);
                    f(&mut x.name.span);
                    x.params.iter_mut().for_each(|a| f(&mut a.span));
                }
                PlanDef::Operator(o) => {
                    f(&mut o.keyword_span);
                    f(&mut o.span);
                    f(&mut o.name.span);
                    for p in &mut o.params {
                        f(&mut p.ty.span);
                        f(&mut p.name.span);
                    }
                    for part in &mut o.parts {
                        f(&mut part.keyword_span);
                        f(&mut part.span);
                        match &mut part.kind {
                            OpPartKind::Precond(v) | OpPartKind::Add(v) | OpPartKind::Del(v) => {
                                v.iter_mut().for_each(|x| x.spans_mut(f))
                            }
                            OpPartKind::Expression(v) => {
                                for x in v {
                                    f(&mut x.span);
                                    f(&mut x.op_span);
                                    x.left.spans_mut(f);
                                    x.right.spans_mut(f);
                                }
                            }
                            OpPartKind::Cost(c) => c.spans_mut(f),
                            OpPartKind::Mcl(c) => c.spans_mut(f),
                        }
                    }
                }
                PlanDef::Facts(x) => {
                    f(&mut x.keyword_span);
                    f(&mut x.span);
                    x.facts.iter_mut().for_each(|a| a.spans_mut(f));
                    for v in &mut x.values {
                        f(&mut v.span);
                        f(&mut v.name.span);
                        v.args.iter_mut().for_each(|a| f(&mut a.span));
                        value_spans_mut(&mut v.value, f);
                    }
                }
            }
        }
    }
}

impl PddlMapBlock {
    /// Calls `f` on every span of the block (to move or erase them).
    pub fn spans_mut(&mut self, f: &mut dyn FnMut(&mut Span)) {
        f(&mut self.keyword_span);
        f(&mut self.span);
        for m in &mut self.maps {
            f(&mut m.span);
            f(&mut m.action.span);
            m.params.iter_mut().for_each(|a| f(&mut a.span));
            m.call.spans_mut(f);
        }
    }
}
