//! Composition of a mission into one Petri net (seed 4.5, Definition 4.5.1,
//! Extract 5.6).
//!
//! Composition is done by construction: a parent block creates the places of
//! its internal interfaces and hands each one to a child as the child's
//! external interface, which *is* the fusion of Definition 4.5.1. Tasks are
//! not replicated: each task has one net, guarded by a lock place, and every
//! call site gets a small adapter block (see [`call_adapter`]) that takes the
//! lock, binds the call's arguments, starts the task and routes the task's
//! outcome back to that call only. Two calls of one task that are active at
//! the same time therefore run one after the other, each with its own
//! parameters and its own outcome (seed Figure 4.13, SEED-NOTES item 3).

pub mod builder;
pub mod calls;
pub mod dot;
pub mod structure_tree;
pub mod structures;
pub mod tree_dot;
pub mod verify;

use crate::db::{Db, SourceFile};
use crate::scope::{self, DefKind, Scope};
use builder::{Builder, Iface, Part::N, Part::S};
use mcl_net::{ActionRef, CallBinding, Net, NetError, Provenance, SourceSpan, TransitionKind};
use mcl_syntax::ast::*;
use rustc_hash::FxHashMap;
use std::sync::Arc;
use structures::Structure;

/// The places of the external interface of the compiled mission.
pub const MISSION_BEGIN: &str = "mission.begin";
pub const MISSION_ABORT: &str = "mission.abort";
pub const MISSION_OK: &str = "mission.ok";
pub const MISSION_FAIL: &str = "mission.fail";

/// Why a mission could not be compiled (the checker reports the details).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CompileError {
    /// The program has errors; run `mcl check`.
    HasErrors,
    /// A pattern is read from a PNML file that could not be loaded.
    Pattern(String),
    /// The generated net is inconsistent (a compiler bug).
    Net(String),
}

impl std::fmt::Display for CompileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CompileError::HasErrors => write!(f, "the program has errors"),
            CompileError::Pattern(m) => write!(f, "{m}"),
            CompileError::Net(m) => write!(f, "internal error while building the net: {m}"),
        }
    }
}

impl std::error::Error for CompileError {}

impl From<NetError> for CompileError {
    fn from(e: NetError) -> Self {
        CompileError::Net(e.to_string())
    }
}

/// Compiles one mission of the program rooted at `root` into a net.
/// The program must be free of errors.
pub fn compile_mission(
    db: &dyn Db,
    root: SourceFile,
    mission: &Mission,
    mission_file: SourceFile,
) -> Result<Net, CompileError> {
    // The name every tool gives it (`scope::mission_names`), found by its
    // place among the missions of its file.
    let parsed = crate::queries::parse(db, mission_file);
    let names = scope::mission_names(&parsed.file);
    let place = parsed.file.items.iter().filter_map(|i| match i {
        Item::Mission(m) => Some(m),
        _ => None,
    });
    let name = place
        .zip(&names)
        .find(|(m, _)| m.span == mission.span && m.name == mission.name)
        .map(|(_, n)| n.clone())
        .unwrap_or_else(|| mission.name.as_ref().map_or_else(|| "mission".to_string(), |n| n.text.clone()));
    let mut cx = Composer {
        db,
        scope: scope::scope(db, root),
        b: Builder::new(&name),
        file_path: mission_file.path(db).display().to_string(),
        tasks: FxHashMap::default(),
        calls: 0,
        error: None,
        role: None,
        guards: Vec::new(),
    };
    cx.b.net.name(&name);
    // Room for the whole net at once: no copying as it grows.
    let (calls, children) = size_of_block(&mission.body);
    cx.b.net.reserve(2 * calls + 8 * children + 64, 6 * calls + 12 * children + 64, 17 * calls + 40 * children + 256);
    for p in &mission.params {
        cx.b.net.property("mission_param", &p.text);
    }
    cx.b.provenance = cx.prov("mission", "m", mission.span);
    let ext =
        Iface {
            begin: cx.b.net.add_place(
                mcl_net::Place::new(MISSION_BEGIN)
                    .with_tokens(1)
                    .with_interface(1)
                    .with_provenance(cx.b.provenance.clone()),
            ),
            abort: cx.b.net.add_place(
                mcl_net::Place::new(MISSION_ABORT).with_interface(1).with_provenance(cx.b.provenance.clone()),
            ),
            ok: cx
                .b
                .net
                .add_place(mcl_net::Place::new(MISSION_OK).with_interface(1).with_provenance(cx.b.provenance.clone())),
            fail: cx.b.net.add_place(
                mcl_net::Place::new(MISSION_FAIL).with_interface(1).with_provenance(cx.b.provenance.clone()),
            ),
        };
    cx.block(&mission.body, ext, "m");
    if let Some(e) = cx.error {
        return Err(e);
    }
    let handlers = std::mem::take(&mut cx.b.handlers);
    let mut net = cx.b.finish();
    if !handlers.is_empty() {
        let list: Vec<mcl_net::Handler> = handlers
            .iter()
            .filter_map(|&(t, kind)| Some(mcl_net::Handler { transition: net.transition_mut(t)?.id.to_string(), kind }))
            .collect();
        net.property(mcl_net::HANDLERS_PROPERTY, serde_json::to_string(&list).unwrap_or_default());
    }
    Ok(net.build()?)
}

/// The number of calls and of structure children in `block`, to size the net.
fn size_of_block(block: &Block) -> (usize, usize) {
    let (mut calls, mut children) = (0, block.stmts.len());
    let is_call = |s: &Stmt| matches!(s.kind, StmtKind::Call(_));
    calls += block.stmts.iter().filter(|s| is_call(s)).count();
    let mut add = |b: &Block| {
        let (c, k) = size_of_block(b);
        calls += c;
        children += k;
    };
    for s in &block.stmts {
        match &s.kind {
            StmtKind::Call(_) => {}
            StmtKind::While { cond, body, .. } => {
                add(cond);
                add(body);
            }
            StmtKind::If { cond, then, otherwise, .. } => {
                add(cond);
                add(then);
                if let Some(o) = otherwise {
                    add(o);
                }
            }
            StmtKind::Try { body, catch, .. } => {
                add(body);
                add(catch);
            }
            StmtKind::Not { body, .. } => add(body),
            StmtKind::Parallel { branches, .. } => branches.iter().for_each(&mut add),
            StmtKind::Monitor { body, handlers, .. } => {
                add(body);
                for h in handlers {
                    add(&h.condition);
                    add(&h.action);
                }
            }
            StmtKind::Error => {}
        }
    }
    (calls, children)
}

struct TaskNet {
    iface: Iface,
    lock: mcl_net::PlaceId,
    params: Arc<[String]>,
}

struct Composer<'a> {
    db: &'a dyn Db,
    scope: &'a Scope,
    b: Builder,
    /// The mission's file, as shown in provenance (computed once).
    file_path: String,
    tasks: FxHashMap<String, TaskNet>,
    calls: u32,
    error: Option<CompileError>,
    /// The role given to calls compiled now (inside a condition).
    role: Option<&'static str>,
    /// The `open` places of the enclosing structures that may abort the
    /// calls compiled now on their own (see [`Structure::competes`]).
    guards: Vec<mcl_net::PlaceId>,
}

impl Composer<'_> {
    fn prov(&self, structure: &str, path: &str, span: mcl_syntax::Span) -> Arc<Provenance> {
        Arc::new(self.prov_record(structure, path, span))
    }

    fn prov_record(&self, structure: &str, path: &str, span: mcl_syntax::Span) -> Provenance {
        Provenance {
            task: None,
            call_site: None,
            structure: Some(structure.to_string()),
            path: Some(path.to_string()),
            span: Some(SourceSpan { file: self.file_path.clone(), start: span.start, end: span.end }),
        }
    }

    fn block(&mut self, block: &Block, ext: Iface, path: &str) {
        match block.stmts.as_slice() {
            [single] => self.stmt(single, ext, path),
            stmts => {
                self.b.provenance = self.prov("sequence", path, block.span);
                let (kids, _) = structures::build(&mut self.b, &Structure::Sequence(stmts.len()), ext, path);
                for (i, (s, k)) in stmts.iter().zip(kids).enumerate() {
                    self.stmt(s, k, &format!("{path}.{i}"));
                }
            }
        }
    }

    fn structure(&mut self, s: Structure, span: mcl_syntax::Span, ext: Iface, path: &str, children: &[&Block]) {
        self.b.provenance = self.prov(s.name(), path, span);
        let (kids, open) = structures::build(&mut self.b, &s, ext, path);
        for (i, (blk, k)) in children.iter().zip(kids).enumerate() {
            let saved = self.role;
            match (&s, i) {
                (Structure::While, 0) => self.role = Some("while_condition"),
                // A test: either answer is normal (mcl-coord's nominal runs).
                (Structure::IfThen | Structure::IfThenElse, 0) if self.role.is_none() => {
                    self.role = Some("if_condition")
                }
                (Structure::Monitor(_), i) if i % 2 == 1 => self.role = Some("monitor_condition"),
                // Under an odd number of `not`s, a call that fails keeps the loop going.
                (Structure::Not, _) => {
                    self.role = match self.role {
                        Some("while_condition") => Some("negated_while_condition"),
                        Some("negated_while_condition") => Some("while_condition"),
                        r => r,
                    }
                }
                _ => {}
            }
            let guarded = open.filter(|_| s.competes(i));
            self.guards.extend(guarded);
            self.block(blk, k, &format!("{path}.{i}"));
            if guarded.is_some() {
                self.guards.pop();
            }
            self.role = saved;
        }
    }

    fn stmt(&mut self, s: &Stmt, ext: Iface, path: &str) {
        match &s.kind {
            StmtKind::Call(c) => self.call(c, ext, path),
            StmtKind::While { cond, body, .. } => self.structure(Structure::While, s.span, ext, path, &[cond, body]),
            StmtKind::If { cond, then, otherwise: None, .. } => {
                self.structure(Structure::IfThen, s.span, ext, path, &[cond, then])
            }
            StmtKind::If { cond, then, otherwise: Some(o), .. } => {
                self.structure(Structure::IfThenElse, s.span, ext, path, &[cond, then, o])
            }
            StmtKind::Try { body, catch, .. } => self.structure(Structure::TryCatch, s.span, ext, path, &[body, catch]),
            StmtKind::Not { body, .. } => self.structure(Structure::Not, s.span, ext, path, &[body]),
            StmtKind::Parallel { branches, ops, .. } => {
                let n = branches.len();
                let st = if ops.iter().all(|(o, _)| *o == ParallelOp::And) {
                    Structure::ParallelAnd(n)
                } else {
                    Structure::ParallelOr(n)
                };
                let children: Vec<&Block> = branches.iter().collect();
                self.structure(st, s.span, ext, path, &children)
            }
            StmtKind::Monitor { body, handlers, .. } => {
                let kinds = handlers.iter().map(|h| h.kind).collect();
                let mut children = vec![body];
                for h in handlers {
                    children.push(&h.condition);
                    children.push(&h.action);
                }
                self.structure(Structure::Monitor(kinds), s.span, ext, path, &children)
            }
            StmtKind::Error => self.error = Some(CompileError::HasErrors),
        }
    }

    /// The adapter of one call site (see the module documentation).
    fn call(&mut self, c: &Call, ext: Iface, path: &str) {
        let Some(task) = self.task_net(&c.name.text) else {
            self.error.get_or_insert(CompileError::HasErrors);
            return;
        };
        let (tiface, lock, params) = (task.iface, task.lock, task.params.clone());
        self.calls += 1;
        let id = self.calls;
        let mut prov = self.prov_record("call", path, c.span);
        prov.task = Some(c.name.text.clone());
        prov.call_site = Some(id);
        self.b.provenance = Arc::new(prov);
        let n = id as usize;
        let guards = self.guards.clone();
        let start = adapter(&mut self.b, &[S("call"), N(n)], ext, tiface, lock, &guards);
        let args: Vec<(String, String)> = params.iter().cloned().zip(c.args.iter().map(value_json)).collect();
        let label = c.label.as_ref().map(|l| l.text.clone());
        if let Some(t) = self.b.net.transition_mut(start) {
            t.binding = Some(Box::new(CallBinding {
                task: c.name.text.clone(),
                call_site: id,
                label,
                args,
                role: self.role.map(String::from),
            }));
        }
    }

    /// The net of a task, created on first use.
    fn task_net(&mut self, name: &str) -> Option<&TaskNet> {
        if !self.tasks.contains_key(name) {
            let net = self.instantiate_task(name)?;
            self.tasks.insert(name.to_string(), net);
        }
        self.tasks.get(name)
    }

    fn instantiate_task(&mut self, name: &str) -> Option<TaskNet> {
        let (iface, params) = match add_task_net(self.db, self.scope, &mut self.b, name, &format!("task.{name}.")) {
            Ok(x) => x?,
            Err(e) => {
                self.error = Some(e);
                return None;
            }
        };
        let (ok, fail) = task_outcome_events(self.db, self.scope, name);
        self.b.net.property(format!("task_events:{name}"), serde_json::json!({ "ok": ok, "fail": fail }).to_string());
        self.b.provenance = Arc::new(Provenance { task: Some(name.to_string()), ..Default::default() });
        let lock = self.b.place(format!("lock.{name}"), 1);
        Some(TaskNet { iface, lock, params: params.into() })
    }
}

/// The adapter of one call site, with node ids `prefix.run`, `prefix.start`...
/// between the call's interface `ext` and the task's interface `task`
/// guarded by its lock place; returns the `start` transition (the caller
/// puts the call's binding on it).
///
/// * `start` (immediate) takes the lock, marks `run` and the task's begin;
///   it also reads (takes and puts back) every place of `guards`, the `open`
///   places of the enclosing structures that may abort the call on their
///   own, so that a call never starts once such a structure has decided to
///   abort it;
/// * `ok` / `fail` (immediate) pass the task's outcome to the call and keep
///   the lock (`stopping`): the task may still be firing its last immediate
///   transitions (the disable of its primitive, with this call's binding);
/// * `abort` forwards an abort to the running task (`run` → `stopping`);
///   `cancel` withdraws a call aborted while it waits for the lock;
/// * `release` (deferred, priority 0: after every other deferred
///   transition) gives the lock back from `stopping` once the marking is
///   tangible, i.e. once the task net is at rest, and once the structures
///   have aborted what they decided to abort (so that a call they abort
///   while it waits for this task is cancelled, never started).
pub fn adapter(
    b: &mut Builder,
    prefix: &[builder::Part<'_>],
    ext: Iface,
    task: Iface,
    lock: mcl_net::PlaceId,
    guards: &[mcl_net::PlaceId],
) -> mcl_net::TransitionId {
    assert!(prefix.len() < 4, "an adapter prefix has at most three parts");
    let name = |b: &mut Builder, node: &str| {
        let mut parts = [S(""); 4];
        parts[..prefix.len()].copy_from_slice(prefix);
        parts[prefix.len()] = S(node);
        b.id(&parts[..=prefix.len()])
    };
    let node = name(b, ".run");
    let run = b.place(node, 0);
    let node = name(b, ".stopping");
    let stopping = b.place(node, 0);
    let node = name(b, ".start");
    let (mut inputs, mut outputs) = (vec![ext.begin, lock], vec![run, task.begin]);
    inputs.extend_from_slice(guards);
    outputs.extend_from_slice(guards);
    let start = b.imm(node, &inputs, &outputs);
    let node = name(b, ".ok");
    b.imm(node, &[run, task.ok], &[ext.ok, stopping]);
    let node = name(b, ".fail");
    b.imm(node, &[run, task.fail], &[ext.fail, stopping]);
    let node = name(b, ".cancel");
    b.imm(node, &[ext.abort, ext.begin], &[]);
    let node = name(b, ".abort");
    b.imm(node, &[ext.abort, run], &[task.abort, stopping]);
    let node = name(b, ".release");
    b.deferred_last(node, &[stopping], &[lock]);
    start
}

/// Adds the net of task `name` (its pattern with its actions, events and
/// delays) with node ids `prefix + pattern name`. Returns its interface and
/// its parameters.
#[allow(clippy::type_complexity)]
pub fn add_task_net(
    db: &dyn Db,
    scope: &Scope,
    b: &mut Builder,
    name: &str,
    prefix: &str,
) -> Result<Option<(Iface, Vec<String>)>, CompileError> {
    let tid = match scope.first(DefKind::Task, name) {
        Some(t) => t,
        None => return Ok(None),
    };
    let Some(task) = scope::task(db, tid) else {
        return Ok(None);
    };
    let Some(pid) = task.pattern.as_ref().and_then(|p| scope.first(DefKind::Pattern, &p.text)) else {
        return Ok(None);
    };
    let net = match scope::pattern_net(db, pid) {
        Some(Ok(n)) => n,
        Some(Err(e)) => return Err(CompileError::Pattern(e.clone())),
        None => return Ok(None),
    };
    // Bindings of this task: events and actions per transition.
    let mut events: FxHashMap<&str, &str> = FxHashMap::default();
    let mut actions: FxHashMap<&str, Vec<ActionRef>> = FxHashMap::default();
    for bd in &task.bindings {
        for tr in &bd.transitions {
            match bd.kind {
                BindingKind::Event => {
                    events.insert(&tr.text, &bd.target.text);
                }
                BindingKind::Action => {
                    if let Some(a) = scope.first(DefKind::Action, &bd.target.text).and_then(|id| scope::action(db, id))
                    {
                        actions.entry(&tr.text).or_default().push(action_ref(a));
                    }
                }
            }
        }
    }
    let file_path = tid.file.path(db).display().to_string();
    let Some(iface) = add_pattern_net(b, net, &file_path, Some(name), &events, actions, prefix)? else {
        return Ok(None);
    };
    let params = task.params.iter().map(|p| p.text.clone()).collect();
    Ok(Some((iface, params)))
}

/// Adds the net of a pattern with node ids `prefix + node name`: each
/// transition waits for the event `events` binds to it, else is timed if it
/// has a delay, else immediate, and sends the `actions` bound to it.
/// `file_path` and `task` go into the provenance. Returns the interface
/// (`None` when the pattern lacks one of begin, abort, ok, fail).
pub fn add_pattern_net(
    b: &mut Builder,
    net: &PatternNet,
    file_path: &str,
    task: Option<&str>,
    events: &FxHashMap<&str, &str>,
    mut actions: FxHashMap<&str, Vec<ActionRef>>,
    prefix: &str,
) -> Result<Option<Iface>, CompileError> {
    let prov = |span: mcl_syntax::Span| {
        Arc::new(Provenance {
            task: task.map(str::to_string),
            call_site: None,
            structure: None,
            path: None,
            span: Some(SourceSpan { file: file_path.to_string(), start: span.start, end: span.end }),
        })
    };
    let mut places = FxHashMap::default();
    for pl in &net.places {
        b.provenance = prov(pl.span);
        let iface = pl.interface.as_ref().and_then(Number::as_u32).unwrap_or(0);
        let tokens = pl.tokens.as_ref().and_then(Number::as_u32).unwrap_or(0);
        let id = b.net.add_place(
            mcl_net::Place::new(format!("{prefix}{}", pl.name.text))
                .with_tokens(tokens)
                .with_interface(iface)
                .with_provenance(b.provenance.clone()),
        );
        places.insert(pl.name.text.as_str(), id);
    }
    let (Some(&begin), Some(&abort), Some(&ok), Some(&fail)) =
        (places.get("begin"), places.get("abort"), places.get("ok"), places.get("fail"))
    else {
        return Ok(None);
    };
    let iface = Iface { begin, abort, ok, fail };
    let mut transitions = FxHashMap::default();
    for t in &net.transitions {
        b.provenance = prov(t.span);
        let kind = match (events.get(t.name.text.as_str()), &t.delay) {
            (Some(e), _) => TransitionKind::Event(e.to_string()),
            (None, Some(Delay::Fixed(n))) => TransitionKind::Timed(mcl_net::Delay::Fixed(n.value())),
            (None, Some(Delay::Param(p))) => TransitionKind::Timed(mcl_net::Delay::Param(p.text.clone())),
            (None, None) => TransitionKind::Immediate,
        };
        let tid = b.transition(format!("{prefix}{}", t.name.text), kind, &[], &[]);
        if let Some(tr) = b.net.transition_mut(tid) {
            tr.actions = actions.remove(t.name.text.as_str()).unwrap_or_default();
        }
        transitions.insert(t.name.text.as_str(), tid);
    }
    for arc in &net.arcs {
        let w = arc.weight.as_ref().and_then(Number::as_u32).unwrap_or(1).max(1);
        let (s, d) = (arc.source.name.text.as_str(), arc.target.name.text.as_str());
        match (places.get(s), transitions.get(d), transitions.get(s), places.get(d)) {
            (Some(&p), Some(&t), _, _) => {
                b.net.add_input(p, t, w);
            }
            (_, _, Some(&t), Some(&p)) => {
                b.net.add_output(t, p, w);
            }
            _ => return Err(CompileError::HasErrors),
        }
    }
    Ok(Some(iface))
}

fn action_ref(a: &ActionDef) -> ActionRef {
    ActionRef {
        action: a.name.text.clone(),
        primitive: a.primitive.text.clone(),
        command: a.command.as_ref().map(|c| c.text.clone()).unwrap_or_default(),
        params: a
            .params
            .iter()
            .enumerate()
            .map(|(i, v)| match &v.kind {
                // A task parameter: resolved from the call's binding when the action is sent.
                ValueKind::Ident(n) => (n.text.clone(), serde_json::json!({ "param": n.text }).to_string()),
                _ => (format!("v{i}"), value_json(v)),
            })
            .collect(),
    }
}

/// A call argument or constant as JSON text: numbers, strings, lists; an
/// identifier (a symbol, or a parameter of a parametrised mission) is given
/// to the vehicle as a string.
pub fn value_json(v: &Value) -> String {
    fn go(v: &Value) -> serde_json::Value {
        match &v.kind {
            ValueKind::Number(n) => serde_json::from_str(&n.text).unwrap_or(serde_json::Value::Null),
            ValueKind::Str(s) => serde_json::Value::String(s.clone()),
            ValueKind::Ident(n) => serde_json::Value::String(n.text.clone()),
            ValueKind::List { items, .. } => serde_json::Value::Array(items.iter().map(go).collect()),
            ValueKind::Error => serde_json::Value::Null,
        }
    }
    go(v).to_string()
}

/// A compiled mission.
pub struct CompiledMission {
    /// The mission's name (`scope::mission_names`: `mission`, or `mission1`,
    /// `mission2`, ... for the anonymous ones of a file that has several).
    pub name: String,
    pub net: Net,
}

/// Compiles every mission defined in `file` (not those of imported files),
/// in source order. Fails if the program has errors.
pub fn compile_file(db: &dyn Db, file: SourceFile) -> Result<Vec<CompiledMission>, CompileError> {
    if crate::check::has_errors(crate::check::check_file(db, file)) {
        return Err(CompileError::HasErrors);
    }
    compile_missions(db, file)
}

/// True for the errors of the block verifier (E06xx): the nets of a program
/// whose only errors these are can still be built; they break a block
/// property (seed 4.3.1).
pub fn is_verification_error(code: &str) -> bool {
    code.starts_with("E06")
}

/// [`compile_file`] for a program whose only errors are verification errors
/// ([`is_verification_error`]), so that their counterexamples can be run
/// (`mcl run` with a scenario made by `mcl check
/// --counterexample-scenario`). Any other error fails as in `compile_file`.
pub fn compile_file_unverified(db: &dyn Db, file: SourceFile) -> Result<Vec<CompiledMission>, CompileError> {
    let diags = crate::check::check_file(db, file);
    if diags.iter().any(|d| d.diag.is_error() && !is_verification_error(d.diag.code)) {
        return Err(CompileError::HasErrors);
    }
    compile_missions(db, file)
}

fn compile_missions(db: &dyn Db, file: SourceFile) -> Result<Vec<CompiledMission>, CompileError> {
    let mut out = Vec::new();
    for item in &crate::queries::parse(db, file).file.items {
        if let Item::Mission(m) = item {
            let net = compile_mission(db, file, m, file)?;
            out.push(CompiledMission { name: net.name().to_string(), net });
        }
    }
    Ok(out)
}

/// Which events of task `name` can end it in ok and which in fail, found by
/// running the task net alone: started, settled, then each event fired in
/// each running marking, with every order of the immediate transitions.
pub fn task_outcome_events(db: &dyn Db, scope: &Scope, name: &str) -> (Vec<String>, Vec<String>) {
    let mut b = Builder::new(name);
    let Ok(Some((iface, _))) = add_task_net(db, scope, &mut b, name, "") else { return (vec![], vec![]) };
    let Ok(net) = b.finish().build() else { return (vec![], vec![]) };
    let fire = |m: &[u32], t: mcl_net::TransitionId| -> Option<Vec<u32>> {
        let mut m2 = mcl_net::Marking(m.to_vec());
        mcl_net::semantics::fire(&net, &mut m2, t).ok()?;
        Some(m2.0)
    };
    let imm: Vec<_> =
        net.transition_ids().filter(|&t| net.transition(t).is_some_and(|x| x.kind.is_immediate())).collect();
    // All tangible markings reachable from `start` through immediate transitions.
    let settle = |start: Vec<u32>| -> Vec<Vec<u32>> {
        let mut seen = rustc_hash::FxHashSet::default();
        let mut stack = vec![start];
        let mut out = Vec::new();
        while let Some(m) = stack.pop() {
            if !seen.insert(m.clone()) || seen.len() > 10_000 {
                continue;
            }
            let next: Vec<Vec<u32>> = imm.iter().filter_map(|&t| fire(&m, t)).collect();
            if next.is_empty() {
                out.push(m);
            } else {
                stack.extend(next);
            }
        }
        out
    };
    let mut m0: Vec<u32> = net.places().iter().map(|p| p.initial).collect();
    m0[iface.begin.index()] += 1;
    let running = settle(m0);
    let (mut ok, mut fail) = (Vec::new(), Vec::new());
    for t in net.transition_ids() {
        let Some(mcl_net::TransitionKind::Event(e)) = net.transition(t).map(|x| &x.kind) else { continue };
        for m in &running {
            if let Some(m2) = fire(m, t) {
                for end in settle(m2) {
                    if end[iface.ok.index()] > 0 && !ok.contains(e) {
                        ok.push(e.clone());
                    }
                    if end[iface.fail.index()] > 0 && !fail.contains(e) {
                        fail.push(e.clone());
                    }
                }
            }
        }
    }
    (ok, fail)
}
