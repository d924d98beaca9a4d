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
