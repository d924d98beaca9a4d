//! Plan execution on the Petri net player (seed 7.5): the glue between the
//! planner ([`Executor`]), the world modeler ([`WorldModeler`]), the MCL
//! compiler and the runtime (player, mock vehicle).
//!
//! For each plan step the operator's MCL mission is instantiated with the
//! step's arguments (`GotoMCLop( 45, 30 )`: the operator's body with each
//! parameter replaced by its value, Extract 7.2), compiled with
//! `mcl-compiler` and played by a [`Player`] against the vehicle — the
//! in-process [`MockVehicle`] of a scenario. Perceptions go through the world
//! modeler's scripts into facts. After each step, and whenever perceptions
//! change the facts while a step runs, the facts are compared with what the
//! plan expects ([`Executor::expects`], Definition 7.2.4); when they differ
//! the running mission is aborted (its `mission.abort` place is marked, so
//! its tasks are disabled by the nets), and a new plan is computed from the
//! current facts while the holding mission (`--holding`) runs. Every player
//! record and every planning record goes to the caller's sink as JSON
//! (the typed [`PlanRecord`]s, `kind`: `plan`, `replan`, `step`,
//! `step_end`, `facts`, `holding`, then the final `outcome`), with a
//! live-log line.
//!
//! One vehicle serves the whole run: the mock vehicle's tables are the union
//! of those of the operators file's missions (an instance has the call sites
//! of its operator), call sites and sequence numbers are renumbered so that
//! the missions played one after the other look like one stream of actions.
//! With [`run_planned_aac`] that stream goes to a vehicle's AAC through an
//! [`AacLink`] (the caller's TCP link) in real time; an AAC that mocks the
//! vehicle for a plan uses the same tables ([`Missions::mock_tables`]).

use crate::executor::{Decision, Executor};
use crate::ground::{McValue, MclInstance};
use crate::pddl::Fact;
use crate::record::{Holding, PlanKind, PlanRecord};
use crate::world::{Percept, WorldModeler};
use mcl_compiler::compile::compile_file;
use mcl_compiler::diagnostics::render_human;
use mcl_compiler::{check_file, Database, Db};
use mcl_net::{Net, Place, SourceSpan, Transition, TransitionKind};
use mcl_runtime::driver::Limits;
use mcl_runtime::journal::Input;
use mcl_runtime::link::{Action, Inbound};
use mcl_runtime::mock::{tables_of, CallInfo, MockVehicle, TaskEvents};
use mcl_runtime::player::{Outcome as PlayerOutcome, Output, Player, PlayerOptions};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::trace::{live_line, round_time, Record, RecordKind, SourceMap, Tracer};
use mcl_runtime::vehicle::VirtualVehicle;
use mcl_runtime::virtual_loop::{self, Discrete, Stop};
use mcl_syntax::ast::{Item, Value, ValueKind};
use serde_json::Value as Json;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The event that aborts a running operator mission (an event transition
/// added to each net, marking `mission.abort`).
pub const ABORT_EVENT: &str = "mclPlanAbort";

/// Call sites of the i-th mission of the operators file are renumbered
/// `i * CALL_SITE_STRIDE + c` for the mock vehicle.
const CALL_SITE_STRIDE: u32 = 1_000_000;

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Seed of the players (each mission gets `seed + n`) and of the mock.
    pub seed: u64,
    /// Virtual time (instantaneous, deterministic) or real time.
    pub virtual_time: bool,
    /// Real time: speed-up factor.
    pub speed: f64,
    /// Stop when mission time passes this.
    pub time_limit: Option<f64>,
    /// Name of a mission of the operators file run while re-planning.
    pub holding: Option<String>,
    /// Give up after this many plans.
    pub max_plans: u32,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions { seed: 0, virtual_time: true, speed: 1.0, time_limit: None, holding: None, max_plans: 100 }
    }
}

/// How the run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// `ok` (the goal holds), `fail` (no plan, or re-planning given up),
    /// `time_limit`.
    pub result: String,
    pub reason: Option<String>,
    /// Plans computed (the first included).
    pub plans: u32,
    /// Steps started.
    pub steps: u32,
    /// Mission time at the end.
    pub t: f64,
}

impl Report {
    /// 0 goal reached, 1 failed, 3 time limit.
    pub fn exit_code(&self) -> u8 {
        match self.result.as_str() {
            "ok" => 0,
            "fail" => 1,
            _ => 3,
        }
    }
}

/// A vehicle's AAC as the run sees it: a link that takes actions and
/// delivers events and perceptions (`Inbound::Ack`, `Connected` and
/// `Disconnected` are accepted too), in real time.
pub trait AacLink {
    /// Sends an action; an error means the link is closed for good.
    fn send(&mut self, action: Action) -> Result<(), String>;
    /// Waits up to `timeout` (`None`: without limit) for the next message:
    /// `Ok(None)` when the time is up, an error when the link is closed for good.
    fn recv(&mut self, timeout: Option<Duration>) -> Result<Option<Inbound>, String>;
}

/// Real time the run keeps taking what the AAC sends after a mission ended
/// before deciding what to do next (the perceptions that follow a task's
/// last event travel behind it).
pub const AAC_SETTLE: Duration = Duration::from_millis(20);

/// Where the actions go: a vehicle in virtual time (the in-process mock, a
/// simulated vehicle), or a vehicle's AAC.
enum Vehicle<'a> {
    Mock(Box<dyn VirtualVehicle + 'a>),
    Aac(&'a mut dyn AacLink),
}

/// Receives each trace record (JSON) with its live-log line.
pub trait RecordSink {
    fn record(&mut self, record: Json, live: Option<String>);

    /// A record of the player's kinds (an action, an event, a pose...).
    /// By default as JSON; a sink that writes trace lines should write the
    /// record itself, whose fields (an action's `params` included) keep
    /// their order, as `mcl run` writes them.
    fn record_typed(&mut self, record: &Record, live: Option<String>) {
        self.record(serde_json::to_value(record).unwrap_or_default(), live);
    }
}

/// The MCL side: the operators file compiled once (for the mock's tables and
/// the holding mission) and each operator instance compiled on demand.
pub struct Missions {
    db: Database,
    ops_path: PathBuf,
    ops_text: String,
    /// Missions of the operators file, by name: (index, net).
    compiled: HashMap<String, (usize, Net)>,
    instances: HashMap<String, Arc<Net>>,
    generated: usize,
}

fn literal(v: &McValue) -> String {
    match v {
        McValue::Num(n) => crate::pddl::fmt_num(*n),
        McValue::Str(s) => format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"")),
        McValue::Sym(s) => s.clone(),
    }
}

fn substitutions(v: &Value, params: &[String], args: &[McValue], out: &mut Vec<(usize, usize, String)>) {
    match &v.kind {
        ValueKind::Ident(n) => {
            if let Some(i) = params.iter().position(|p| *p == n.text) {
                out.push((v.span.start as usize, v.span.end as usize, literal(&args[i])));
            }
        }
        ValueKind::List { items, .. } => {
            for it in items {
                substitutions(it, params, args, out);
            }
        }
        _ => {}
    }
}

/// Adds the abort hook: an event transition [`ABORT_EVENT`] that marks
/// `mission.abort` once. `remap` rewrites source spans (from a generated
/// instance file to the operators file).
fn with_abort_hook(net: &Net, remap: Option<&dyn Fn(&mut SourceSpan)>) -> Result<Net, String> {
    let Some(abort) = net.place_by_id("mission.abort") else {
        return Err(format!("mission `{}` has no `mission.abort` place", net.name()));
    };
    let mut b = net.to_builder();
    if let Some(remap) = remap {
        for t in net.transition_ids() {
            if let Some(span) =
                b.transition_mut(t).and_then(|tr| std::sync::Arc::make_mut(&mut tr.provenance).span.as_mut())
            {
                remap(span);
            }
        }
        for p in net.place_ids() {
            if let Some(span) = b.place_mut(p).and_then(|pl| std::sync::Arc::make_mut(&mut pl.provenance).span.as_mut())
            {
                remap(span);
            }
        }
    }
    let armed = b.add_place(Place::new("plan.abortable").with_tokens(1));
    let t = b.add_transition(Transition::new("plan.abort").with_kind(TransitionKind::Event(ABORT_EVENT.into())));
    b.add_input(armed, t, 1).add_output(t, abort, 1);
    b.build().map_err(|e| format!("mission `{}`: {e}", net.name()))
}

impl Missions {
    /// Compiles the operators file (it must have no errors).
    pub fn load(ops_path: &Path) -> Result<Missions, String> {
        let ops_text = mcl_net::input::read_source(ops_path).map_err(|e| e.to_string())?;
        let db = Database::new();
        let f = db.file(ops_path);
        let nets = match compile_file(&db, f) {
            Ok(ms) => ms,
            Err(_) => {
                let diags: Vec<_> = check_file(&db, f).iter().filter(|d| d.diag.is_error()).cloned().collect();
                return Err(format!(
                    "{}the mission operators in `{}` have errors",
                    render_human(&db, &diags, false),
                    ops_path.display()
                ));
            }
        };
        let compiled = nets.into_iter().enumerate().map(|(i, m)| (m.name, (i, m.net))).collect();
        Ok(Missions {
            db,
            ops_path: ops_path.to_path_buf(),
            ops_text,
            compiled,
            instances: HashMap::new(),
            generated: 0,
        })
    }

    /// The mock vehicle's tables: task events and call sites of every
    /// mission of the operators file (call sites renumbered per mission).
    pub fn mock_tables(&self) -> (HashMap<String, TaskEvents>, HashMap<u32, CallInfo>) {
        let mut tasks = HashMap::new();
        let mut calls = HashMap::new();
        for (i, net) in self.compiled.values() {
            let (t, c) = tables_of(net);
            tasks.extend(t);
            for (site, info) in c {
                calls.insert(*i as u32 * CALL_SITE_STRIDE + site, info);
            }
        }
        (tasks, calls)
    }

    /// Index of a mission of the operators file (for call-site renumbering).
    fn index_of(&self, name: &str) -> u32 {
        self.compiled.get(name).map_or(0, |(i, _)| *i as u32)
    }

    /// The holding mission `name` (a mission of the operators file without parameters).
    pub fn holding(&self, name: &str) -> Result<Arc<Net>, String> {
        let Some((_, net)) = self.compiled.get(name) else {
            let mut names: Vec<&str> = self.compiled.keys().map(String::as_str).collect();
            names.sort();
            return Err(format!(
                "holding mission `{name}`: `{}` defines no mission of that name (it defines: {})",
                self.ops_path.display(),
                names.join(", ")
            ));
        };
        if net.properties().iter().any(|(k, _)| k == "mission_param") {
            return Err(format!("holding mission `{name}` has parameters; give a mission without parameters"));
        }
        Ok(Arc::new(with_abort_hook(net, None)?))
    }

    /// The net of an operator instance: the operator's body with its
    /// parameters replaced by the instance's arguments, compiled as a
    /// mission of a file that imports the operators file.
    pub fn instance(&mut self, call: &MclInstance) -> Result<Arc<Net>, String> {
        let key = call.to_string();
        if let Some(n) = self.instances.get(&key) {
            return Ok(n.clone());
        }
        let parsed = mcl_syntax::parse(&self.ops_text);
        let m = parsed
            .file
            .items
            .iter()
            .find_map(|it| match it {
                Item::Mission(m) if m.name.as_ref().is_some_and(|n| n.text == call.mission) => Some(m),
                _ => None,
            })
            .ok_or_else(|| {
                format!("`{}` does not define the mission operator `{}`", self.ops_path.display(), call.mission)
            })?;
        let params: Vec<String> = m.params.iter().map(|p| p.text.clone()).collect();
        if params.len() != call.args.len() {
            return Err(format!(
                "`{key}`: `{}` takes {} argument(s) ({})",
                call.mission,
                params.len(),
                params.join(", ")
            ));
        }
        let mut subst = Vec::new();
        for c in mcl_syntax::visit::calls(&m.body) {
            for a in &c.args {
                substitutions(a, &params, &call.args, &mut subst);
            }
        }
        let (start, end) = (m.body.span.start as usize, m.body.span.end as usize);
        subst.sort_by_key(|s| s.0);
        let mut body = self.ops_text[start..end].to_string();
        for (s, e, text) in subst.iter().rev() {
            body.replace_range(s - start..e - start, text);
        }
        let (body, wrap) = if body.trim_start().starts_with('{') { (body, 0) } else { (format!("{{\n{body}\n}}"), 2) };
        self.generated += 1;
        let dir = self.ops_path.parent().unwrap_or(Path::new("."));
        let file_name = self.ops_path.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default();
        let path = dir.join(format!(".plan-{}-{}.mcl", call.mission, self.generated));
        let header = format!(
            "// {key}: generated by mcl plan --run\nimport \"{file_name}\";\nmission {}Instance() ",
            call.mission
        );
        let text = format!("{header}{body}\n");
        let f = self.db.set_text(&path, text);
        let generated = f.path(&self.db).display().to_string();
        let ops_file = self.db.file(&self.ops_path).path(&self.db).display().to_string();
        // A byte of the generated file back to the operators file.
        let body_at = header.len() + wrap;
        let back = |g: u32| -> u32 {
            let Some(rel) = (g as usize).checked_sub(body_at) else { return start as u32 };
            let mut delta: isize = 0;
            for (s, e, text) in &subst {
                let new_s = (s - start) as isize + delta;
                if (rel as isize) < new_s {
                    break;
                }
                if (rel as isize) < new_s + text.len() as isize {
                    return *s as u32;
                }
                delta += text.len() as isize - (e - s) as isize;
            }
            ((start + rel) as isize - delta).clamp(start as isize, end as isize) as u32
        };
        let remap = |span: &mut SourceSpan| {
            if span.file == generated {
                span.file = ops_file.clone();
                span.start = back(span.start);
                span.end = back(span.end).max(span.start);
            }
        };
        let nets = match compile_file(&self.db, f) {
            Ok(ms) => ms,
            Err(_) => {
                let diags: Vec<_> = check_file(&self.db, f).iter().filter(|d| d.diag.is_error()).cloned().collect();
                return Err(format!(
                    "{}cannot compile the instance `{key}` of the mission operator `{}`",
                    render_human(&self.db, &diags, false),
                    call.mission
                ));
            }
        };
        let net = nets.into_iter().next().ok_or_else(|| format!("`{key}`: no mission compiled"))?.net;
        let net = Arc::new(with_abort_hook(&net, Some(&remap))?);
        self.instances.insert(key, net.clone());
        Ok(net)
    }
}

/// What a mission played on the player is for.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Step(usize),
    Holding,
}

struct Running {
    player: Player,
    tracer: Tracer,
    role: Role,
    /// Index of its operator in the operators file (call-site renumbering).
    index: u32,
}

fn percept(v: &Json) -> Percept {
    match v {
        Json::Number(n) => n.as_f64().map_or(Percept::Text(n.to_string()), Percept::Num),
        Json::Bool(b) => Percept::Num(if *b { 1.0 } else { 0.0 }),
        Json::String(s) => Percept::parse(s),
        other => Percept::Text(other.to_string()),
    }
}

fn list(facts: &[Fact]) -> String {
    facts.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(" ")
}

fn strs(facts: &[Fact]) -> Vec<String> {
    facts.iter().map(|f| f.to_string()).collect()
}

/// The run: executor, world, mock, the mission playing, the clock.
struct Run<'a> {
    ex: Executor,
    world: WorldModeler,
    missions: Missions,
    vehicle: Vehicle<'a>,
    /// The AAC link closed while running.
    link_error: Option<String>,
    sink: &'a mut dyn RecordSink,
    opts: RunOptions,
    sources: SourceMap,
    running: Option<Running>,
    holding: Option<Arc<Net>>,
    t: f64,
    seq: u64,
    players: u64,
    steps: u32,
    /// Why the running step was aborted.
    aborted: Option<String>,
    /// Why the executor is aborting the running mission now (set during
    /// [`Run::abort_running`]): the player's outcome is then `aborted`, not
    /// `stuck`.
    aborting: Option<&'static str>,
    started: Instant,
}

impl Run<'_> {
    /// Emits a plan record ([`PlanKind`]), with its live line.
    fn emit(&mut self, kind: PlanKind) {
        let r = PlanRecord { t: round_time(self.t), kind };
        let live = r.live_line();
        self.sink.record(r.to_json(), Some(live));
    }

    /// Emits a record of one of the player's kinds (a warning, a link
    /// notice...), without a live line.
    fn emit_kind(&mut self, kind: RecordKind) {
        let r = serde_json::to_value(Record::new(self.t, kind)).unwrap_or_default();
        self.sink.record(r, None);
    }

    fn emit_plan(&mut self, reason: &str) {
        let p = self.ex.plan();
        let kind = PlanKind::Plan {
            plan: self.ex.replans + 1,
            reason: reason.to_string(),
            steps: p.steps.iter().map(|s| s.action.clone()).collect(),
            calls: p.steps.iter().map(|s| s.mcl.as_ref().map(|m| m.to_string())).collect(),
            cost: p.cost,
        };
        self.emit(kind);
    }

    /// Mission time now (real time runs from the start of the run).
    fn now(&self) -> f64 {
        if self.opts.virtual_time {
            self.t
        } else {
            (self.started.elapsed().as_secs_f64() * self.opts.speed).max(self.t)
        }
    }

    /// Feeds one input to the running mission; records; forwards actions to the vehicle.
    fn apply(&mut self, input: Input) {
        let Some(run) = &mut self.running else { return };
        let out = input.apply(&mut run.player);
        let index = run.index;
        let mut records = Vec::new();
        for o in &out {
            let mut r = run.tracer.record(o);
            // An aborted mission is left with nothing to fire: that is the
            // executor's doing, not a stuck mission.
            if let (Some(why), RecordKind::Outcome { result, reason, .. }) = (self.aborting, &mut r.kind) {
                if result == "stuck" {
                    *result = "aborted".into();
                    *reason = Some(why.into());
                }
            }
            records.push(r);
            if let Output::Send { action, .. } = o {
                self.seq += 1;
                let a = Action {
                    seq: self.seq,
                    call_site: action.call_site.map(|c| index * CALL_SITE_STRIDE + c),
                    ..action.clone()
                };
                match &mut self.vehicle {
                    Vehicle::Mock(mock) => {
                        mock.on_action(self.t, &a);
                    }
                    Vehicle::Aac(link) => {
                        if let Err(e) = link.send(a) {
                            self.link_error.get_or_insert(e);
                        }
                    }
                }
            }
        }
        for r in records {
            let live = live_line(&r, false);
            self.sink.record_typed(&r, live);
        }
        let warnings = match &mut self.vehicle {
            Vehicle::Mock(mock) => mock.take_warnings(),
            Vehicle::Aac(_) => Vec::new(),
        };
        for w in warnings {
            self.emit_kind(RecordKind::Warning { message: w });
        }
        self.drain_poses();
    }

    /// Traces the poses the vehicle reached since the last call (a
    /// simulated vehicle's `pose` records; none from the mock or an AAC).
    fn drain_poses(&mut self) {
        let poses = match &mut self.vehicle {
            Vehicle::Mock(v) => v.take_poses(),
            Vehicle::Aac(_) => Vec::new(),
        };
        for p in poses {
            let r = mcl_runtime::driver::pose_record(None, &p);
            self.sink.record_typed(&r, None);
        }
    }

    /// Starts `net` on a new player.
    fn start(&mut self, net: Arc<Net>, label: String, role: Role, index: u32) {
        self.players += 1;
        let player = Player::new(net.clone(), PlayerOptions::seeded(self.opts.seed.wrapping_add(self.players)));
        let tracer = Tracer::new(&net, Some(label), &mut self.sources);
        self.running = Some(Running { player, tracer, role, index });
        self.apply(Input::Start(self.t));
    }

    /// Aborts the running mission through its abort hook, for `why`.
    fn abort_running(&mut self, why: &'static str) {
        if self.running.as_ref().is_some_and(|r| r.player.outcome().is_none()) {
            self.aborting = Some(why);
            self.apply(Input::Event(self.t, ABORT_EVENT.to_string(), None));
            self.aborting = None;
        }
    }

    /// Takes a perception: world modeler, records, and the facts check.
    fn perceive(&mut self, name: String, value: Json) {
        match &mut self.running {
            Some(_) => self.apply(Input::Perception(self.t, name.clone(), value.clone())),
            None => self.emit_kind(RecordKind::Perception { name: name.clone(), value: value.clone() }),
        }
        let before = self.world.facts().clone();
        self.world.perceive(&name, percept(&value));
        let after = self.world.facts();
        if &before == after {
            return;
        }
        let added: Vec<Fact> = after.difference(&before).cloned().collect();
        let deleted: Vec<Fact> = before.difference(after).cloned().collect();
        self.emit(PlanKind::Facts { added: strs(&added), deleted: strs(&deleted), perception: name });
        // While a step runs: does the world still fit the plan?
        let Some(Running { role: Role::Step(i), player, .. }) = &self.running else { return };
        if player.outcome().is_some() || self.ex.expects(self.world.facts(), *i) {
            return;
        }
        let i = *i;
        let (missing, extra) = self.ex.divergence(self.world.facts(), i);
        self.aborted = Some(format!(
            "facts differ from the plan while step {} {} runs: missing [{}], unexpected [{}]; step aborted",
            i + 1,
            self.ex.step(i).action,
            list(&missing),
            list(&extra)
        ));
        self.abort_running("aborted to re-plan");
        self.end_step(false);
    }

    /// The running step (or holding mission) ended.
    fn end_step(&mut self, ok: bool) {
        let Some(run) = self.running.take() else { return };
        if let Role::Step(i) = run.role {
            let result = if self.aborted.is_some() {
                "aborted"
            } else if ok {
                "ok"
            } else {
                run.player.outcome().map_or("fail", |o| o.as_str())
            };
            let action = self.ex.step(i).action.clone();
            self.emit(PlanKind::StepEnd { step: i + 1, action, result: result.to_string() });
            self.ex.step_ended(i, ok);
        }
    }

    /// Delivers what the vehicle sends at the current time (between steps):
    /// the mock's messages due now; what the AAC sends until it has been
    /// quiet for [`AAC_SETTLE`].
    fn drain_vehicle(&mut self) {
        loop {
            let m = match &mut self.vehicle {
                Vehicle::Mock(mock) => mock.pop_due(self.t).map(|(_, m)| m),
                Vehicle::Aac(link) => match link.recv(Some(AAC_SETTLE)) {
                    Ok(m) => m,
                    Err(e) => {
                        self.link_error.get_or_insert(e);
                        None
                    }
                },
            };
            let Some(m) = m else { return };
            self.t = self.now();
            self.deliver(m);
        }
    }

    fn deliver(&mut self, m: Inbound) {
        match m {
            // The activation ids are in this run's numbering of actions, not
            // in each step's player's: not checked here.
            Inbound::Event { event, .. } => match &self.running {
                Some(_) => self.apply(Input::Event(self.t, event, None)),
                None => self.emit_kind(RecordKind::UnexpectedEvent { event, reason: "no mission is running".into() }),
            },
            Inbound::Perception { name, value, .. } => self.perceive(name, value),
            Inbound::Disconnected => {
                self.emit_kind(RecordKind::Warning { message: "link to the AAC lost; reconnecting".into() })
            }
            Inbound::Connected => self.emit_kind(RecordKind::Warning { message: "link to the AAC up".into() }),
            Inbound::Notice { message } => self.emit_kind(RecordKind::Link { message }),
            Inbound::Ack { .. } | Inbound::Session { .. } => {}
        }
    }

    fn replan(&mut self, reason: String) -> Result<(), String> {
        let facts = self.world.facts().iter().map(|f| f.to_string()).collect();
        self.emit(PlanKind::Replan { reason: reason.clone(), facts });
        if let Some(net) = self.holding.clone() {
            let name = self.opts.holding.clone().unwrap_or_default();
            let index = self.missions.index_of(&name);
            self.emit(PlanKind::Holding { mission: name.clone(), state: Holding::Started });
            self.start(net, format!("holding:{name}"), Role::Holding, index);
        }
        let facts = self.world.facts().clone();
        let r = if self.ex.replans + 1 >= self.opts.max_plans {
            Err(format!("gave up after {} plans (--max-plans)", self.ex.replans + 1))
        } else {
            self.ex.replan(&facts).map(|_| ())
        };
        if let Some(name) = self.opts.holding.clone().filter(|_| self.running.is_some()) {
            self.abort_running("holding mission stopped: a plan is ready");
            self.running = None;
            self.emit(PlanKind::Holding { mission: name, state: Holding::Stopped });
        }
        match r {
            Ok(()) => {
                self.emit_plan("re-plan");
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    fn wait_until(&self, t: f64) {
        if self.opts.virtual_time {
            return;
        }
        let target = self.started + Duration::from_secs_f64((t / self.opts.speed).max(0.0));
        let now = Instant::now();
        if target > now {
            std::thread::sleep(target - now);
        }
    }

    fn finish(&mut self, result: &str, reason: Option<String>) -> Report {
        self.abort_running("the planned run ended");
        self.running = None;
        self.emit(PlanKind::Outcome {
            result: result.to_string(),
            plans: self.ex.replans + 1,
            steps: self.steps,
            reason: reason.clone(),
        });
        Report { result: result.to_string(), reason, plans: self.ex.replans + 1, steps: self.steps, t: self.t }
    }

    /// With an AAC: waits for the next message, the running mission's next
    /// deadline or the time limit, and takes it. `Some` when the run ends.
    fn wait_aac(&mut self) -> Option<Report> {
        let tp = self.running.as_ref().and_then(|r| r.player.next_deadline());
        let limit = self.opts.time_limit;
        let now = self.now();
        if limit.is_some_and(|l| now >= l && tp.is_none_or(|d| d > l)) {
            let l = limit.unwrap_or_default();
            self.t = self.t.max(l);
            return Some(self.finish("time_limit", Some(format!("the time limit of {l} s passed"))));
        }
        let wake = match (tp, limit) {
            (Some(d), Some(l)) => Some(d.min(l)),
            (d, l) => d.or(l),
        };
        let timeout = wake.map(|w| Duration::from_secs_f64(((w - now) / self.opts.speed).max(0.0)));
        let Vehicle::Aac(link) = &mut self.vehicle else { return None };
        match link.recv(timeout) {
            Err(e) => {
                self.t = self.now();
                Some(self.finish("fail", Some(e)))
            }
            Ok(Some(m)) => {
                self.t = self.now();
                self.deliver(m);
                None
            }
            Ok(None) => {
                match tp {
                    Some(d) if wake.is_some_and(|w| d <= w) => {
                        self.t = self.t.max(d);
                        self.apply(Input::Timer(d));
                    }
                    _ => self.t = self.now(),
                }
                None
            }
        }
    }

    fn go(&mut self) -> Result<Report, String> {
        match &mut self.vehicle {
            Vehicle::Mock(mock) => {
                mock.initial();
            }
            Vehicle::Aac(_) => self.started = Instant::now(),
        }
        self.emit_plan("initial");
        loop {
            if let Some(e) = self.link_error.take() {
                self.t = self.now();
                return Ok(self.finish("fail", Some(e)));
            }
            // Between missions: take what is due now, then decide.
            if self.running.is_none() {
                self.drain_vehicle();
                if self.link_error.is_some() {
                    continue;
                }
                let facts = self.world.facts().clone();
                match self.ex.next_step(&facts) {
                    Decision::Done => return Ok(self.finish("ok", None)),
                    Decision::Failed(why) => return Ok(self.finish("fail", Some(why))),
                    Decision::Replan => {
                        let reason = match self.aborted.take() {
                            Some(r) => r,
                            None => {
                                let i = self.ex.next_index();
                                let failed = self.ex.last_failed();
                                match failed {
                                    Some(j) => format!("step {} {} ended in fail", j + 1, self.ex.step(j).action),
                                    None => {
                                        let (missing, extra) = self.ex.divergence(&facts, i);
                                        format!(
                                            "facts differ from the plan before step {}: missing [{}], unexpected [{}]",
                                            i + 1,
                                            list(&missing),
                                            list(&extra)
                                        )
                                    }
                                }
                            }
                        };
                        if let Err(e) = self.replan(reason) {
                            return Ok(self.finish("fail", Some(e)));
                        }
                        continue;
                    }
                    Decision::Run(i) => {
                        self.aborted = None;
                        let st = self.ex.step(i).clone();
                        let Some(call) = st.mcl.clone() else {
                            return Ok(self.finish(
                                "fail",
                                Some(format!("step {} {} has no `:mcl` mission to run", i + 1, st.action)),
                            ));
                        };
                        let net = self.missions.instance(&call)?;
                        self.steps += 1;
                        self.emit(PlanKind::Step {
                            step: i + 1,
                            of: self.ex.plan().steps.len(),
                            action: st.action.clone(),
                            call: call.to_string(),
                            before: strs(&st.before),
                            after: strs(&st.after),
                        });
                        let index = self.missions.index_of(&call.mission);
                        self.start(net, format!("step{}:{}", i + 1, call.mission), Role::Step(i), index);
                    }
                }
            }
            // A mission runs: it may have ended already.
            if let Some(o) = self.running.as_ref().and_then(|r| r.player.outcome()) {
                self.end_step(o == PlayerOutcome::Ok);
                continue;
            }
            if matches!(self.vehicle, Vehicle::Aac(_)) {
                if let Some(report) = self.wait_aac() {
                    return Ok(report);
                }
                continue;
            }
            // Until the step ends: the one virtual-time loop (in real time
            // with a mock, each input waits for its time).
            let limits = Limits { time_limit: self.opts.time_limit, default_limit: false, connect_timeout: None };
            match virtual_loop::run_now(self, &limits)? {
                Stop::Over => {}
                Stop::Quiescent => {
                    let awaited = self.running.as_ref().map(|r| r.player.awaited_events()).unwrap_or_default();
                    let message = format!(
                        "the mission waits for {} and nothing more can happen: the step fails",
                        awaited.join(", ")
                    );
                    self.emit_kind(RecordKind::Warning { message });
                    self.abort_running("the step waits for what can no longer happen");
                    self.end_step(false);
                }
                Stop::TimeLimit(limit) => {
                    self.t = limit;
                    return Ok(self.finish("time_limit", Some(format!("the time limit of {limit} s passed"))));
                }
                Stop::ZeroTimeLoop(t) => {
                    let message = format!("{}: the step fails", virtual_loop::zero_time_message(t));
                    self.emit_kind(RecordKind::Warning { message });
                    self.abort_running("the step loops without mission time advancing");
                    self.end_step(false);
                }
            }
        }
    }
}

/// Where the next input of a running step comes from.
#[derive(Clone, Copy, Debug)]
enum Source {
    Timer,
    Vehicle,
}

/// The running step and the vehicle, for the virtual-time loop: over when
/// the step has ended (or was aborted by a perception).
impl Discrete for Run<'_> {
    type Source = Source;

    fn is_over(&mut self) -> bool {
        self.running.as_ref().is_none_or(|r| r.player.outcome().is_some())
    }

    fn deadlines(&self, out: &mut Vec<(f64, Source)>) {
        out.extend(self.running.as_ref().and_then(|r| r.player.next_deadline()).map(|t| (t, Source::Timer)));
        if let Vehicle::Mock(mock) = &self.vehicle {
            out.extend(mock.next_deadline().map(|t| (t, Source::Vehicle)));
        }
    }

    async fn step(&mut self, t: f64, source: Source) -> Result<(), String> {
        self.wait_until(t);
        self.t = self.t.max(t);
        match source {
            Source::Timer => self.apply(Input::Timer(t)),
            Source::Vehicle => {
                if let Some((_, m)) = match &mut self.vehicle {
                    Vehicle::Mock(mock) => mock.pop_due(t),
                    Vehicle::Aac(_) => None,
                } {
                    self.deliver(m);
                }
                self.drain_poses();
            }
        }
        Ok(())
    }
}

/// Runs the planned mission: plans from the problem's initial state (the
/// executor `ex` has the first plan), executes step after step against a
/// mock vehicle answering by `scenario`, re-plans on divergence. Errors are
/// bad input found while running (an operator instance that does not
/// compile, a holding mission that does not exist).
pub fn run_planned(
    ex: Executor,
    world: WorldModeler,
    operators: &Path,
    scenario: Scenario,
    opts: RunOptions,
    sink: &mut dyn RecordSink,
) -> Result<Report, String> {
    let missions = Missions::load(operators)?;
    let (tasks, calls) = missions.mock_tables();
    let mock = MockVehicle::new(tasks, calls, scenario, opts.seed);
    run_planned_on(ex, world, missions, Box::new(mock), opts, sink)
}

/// Runs the planned mission like [`run_planned`] against any vehicle in
/// virtual time (the mock, a simulated vehicle), whose tables are those of
/// `missions` ([`Missions::mock_tables`]).
pub fn run_planned_on<'a>(
    ex: Executor,
    world: WorldModeler,
    missions: Missions,
    vehicle: Box<dyn VirtualVehicle + 'a>,
    opts: RunOptions,
    sink: &'a mut dyn RecordSink,
) -> Result<Report, String> {
    run_with(ex, world, missions, Vehicle::Mock(vehicle), opts, sink)
}

/// Runs the planned mission like [`run_planned`], in real time
/// (`opts.virtual_time` is ignored), against a vehicle's AAC reached through
/// `aac`: the actions of every step's mission (and of the holding mission)
/// go to it as one stream (sequence numbers increasing over the run, call
/// sites of the i-th mission of the operators file numbered
/// `i * 1000000 + c`, as in [`Missions::mock_tables`]); its events drive the
/// running mission and its perceptions feed the world modeler. A link that
/// closes for good ends the run in `fail`.
pub fn run_planned_aac(
    ex: Executor,
    world: WorldModeler,
    operators: &Path,
    aac: &mut dyn AacLink,
    opts: RunOptions,
    sink: &mut dyn RecordSink,
) -> Result<Report, String> {
    let missions = Missions::load(operators)?;
    let opts = RunOptions { virtual_time: false, ..opts };
    run_with(ex, world, missions, Vehicle::Aac(aac), opts, sink)
}

fn run_with<'a>(
    ex: Executor,
    world: WorldModeler,
    missions: Missions,
    vehicle: Vehicle<'a>,
    opts: RunOptions,
    sink: &'a mut dyn RecordSink,
) -> Result<Report, String> {
    let holding = match &opts.holding {
        Some(h) => Some(missions.holding(h)?),
        None => None,
    };
    let mut ex = ex;
    ex.max_replans = u32::MAX; // RunOptions::max_plans bounds the plans
    let mut run = Run {
        ex,
        world,
        missions,
        vehicle,
        link_error: None,
        sink,
        opts,
        sources: SourceMap::new(),
        running: None,
        holding,
        t: 0.0,
        seq: 0,
        players: 0,
        steps: 0,
        aborted: None,
        aborting: None,
        started: Instant::now(),
    };
    run.go()
}
