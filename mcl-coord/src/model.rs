//! Missions, their labelled activities, and coordination constraints.
//!
//! A constraint names calls as `mission:label`. Before the supervisor
//! equations of seed chapter 6 apply, each labelled call must be mapped to
//! the nodes of its mission's net that mean *waiting*, *started*, *running*
//! and *ended* (SEED-NOTES item 9). An [`Activity`] is that mapping:
//!
//! * for a compiled mission ([`Mission::from_compiled`]) it is read from the
//!   call adapter (`mcl_compiler::compile::calls`): waiting = the adapter's
//!   begin place, started = `start`, running = {`run`, `stopping`}, ended =
//!   {`ok`, `fail`, `release`}, withdrawn = {`cancel`};
//! * for a compact net (seed Figure 6.2: one place per task) it is built with
//!   [`Activity::region`] from the task's place, or a path of places (the
//!   regions of seed Figure 6.9b).

use mcl_net::{Net, PlaceId, TransitionId};
use serde::Serialize;

use mcl_compiler::compile::calls::{call_nodes, CallNodes};

/// The nodes of one mission's net that a constraint on a labelled call uses.
/// All ids are local to the mission's net.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Activity {
    /// The label (`Task( ... ) : label`, or the name given to a compact place).
    pub label: String,
    /// Places where the call waits before it starts (the seed's `P^wait`).
    pub waiting: Vec<PlaceId>,
    /// Transitions that put the call into a waiting place (`•P^wait`).
    pub arrived: Vec<TransitionId>,
    /// Transitions that take the call out of its waiting place without
    /// starting it (an abort while waiting: the adapter's `cancel`). No
    /// supervisor of the centralized net uses them (see
    /// [`crate::supervisor`]); the per-vehicle nets take a withdrawn sync
    /// arrival back ([`crate::decentral`]).
    pub withdrawn: Vec<TransitionId>,
    /// Transitions that start the call (`P^wait•`; the adapter's `start`).
    pub started: Vec<TransitionId>,
    /// Places marked while the call runs (`P`; `run` and `stopping`).
    pub running: Vec<PlaceId>,
    /// Transitions after which the call no longer runs (`P•`; the adapter's
    /// `release`: a call that completes or is aborted ends there, once).
    pub ended: Vec<TransitionId>,
}

impl Activity {
    /// The activity of one call adapter of a compiled mission.
    pub fn call(net: &Net, call: &CallNodes, label: impl Into<String>) -> Activity {
        Activity {
            label: label.into(),
            waiting: vec![call.begin],
            arrived: call.arrived(net).to_vec(),
            withdrawn: vec![call.cancel],
            started: vec![call.start],
            running: call.running().to_vec(),
            ended: call.ended().to_vec(),
        }
    }

    /// The activity of a set of places of a compact net that a token runs
    /// through (one task place, or a path of places: a *region*).
    ///
    /// * running = `places`;
    /// * started = transitions that put a token into the region without
    ///   taking one from it; ended = transitions that take a token from it
    ///   without putting one back;
    /// * waiting = the input places of the started transitions, arrived =
    ///   their producers. After a PW-transformation of the first place
    ///   ([`crate::compact::pw_transform`]) this is exactly `P^wait` and
    ///   `•P^wait`.
    pub fn region(net: &Net, label: impl Into<String>, places: &[PlaceId]) -> Activity {
        let inside = |p: PlaceId| places.contains(&p);
        let mut started = Vec::new();
        let mut ended = Vec::new();
        for t in net.transition_ids() {
            let takes = net.pre(t).iter().any(|&(p, _)| inside(p));
            let puts = net.post(t).iter().any(|&(p, _)| inside(p));
            if puts && !takes {
                started.push(t);
            }
            if takes && !puts {
                ended.push(t);
            }
        }
        let mut waiting: Vec<PlaceId> = started.iter().flat_map(|&t| net.pre(t).iter().map(|&(p, _)| p)).collect();
        waiting.sort_unstable();
        waiting.dedup();
        let mut arrived: Vec<TransitionId> = waiting.iter().flat_map(|&p| net.producers(p).iter().copied()).collect();
        arrived.sort_unstable();
        arrived.dedup();
        Activity {
            label: label.into(),
            waiting,
            arrived,
            withdrawn: Vec::new(),
            started,
            running: places.to_vec(),
            ended,
        }
    }
}

/// One vehicle's mission: its net and what the coordination needs to know
/// about it.
#[derive(Clone, Debug)]
pub struct Mission {
    /// Mission name (`mission : name { ... }`), used in `name:label`.
    pub name: String,
    /// The mission's net.
    pub net: Net,
    /// Places marked when the mission starts and empty once it has ended
    /// (`mission.begin`; `P1` of a compact net). Step 2 of the deadlock
    /// procedure (seed Extract 6.1) joins the final places to them.
    pub initial_places: Vec<PlaceId>,
    /// Places whose marking means the mission has ended (`mission.ok`,
    /// `mission.fail`; the last place of a compact net).
    pub final_places: Vec<PlaceId>,
    /// Per transition: may a supervisor disable it? Immediate transitions that
    /// the player fires; never an event or a timer (the vehicle decides those).
    pub controllable: Vec<bool>,
    /// The labelled activities.
    pub activities: Vec<Activity>,
    /// Off-nominal answers: event transition `t` is one while one of the
    /// places is marked (a call holds the task: its `run` place). A
    /// *nominal run* is one without them: every call outside a condition
    /// ends ok, tests (`if` and `while` conditions) answer either way, and
    /// no monitor condition fires (no alarm), which is what a mock vehicle
    /// does unless told otherwise. Besides the absence of deadlock, the
    /// verification proves that in no nominal run does a mission wait for
    /// ever ([`crate::verify::WitnessKind::Stuck`]).
    pub off_nominal: Vec<(TransitionId, Vec<PlaceId>)>,
}

impl Mission {
    /// A mission on any net, without activities: every immediate transition
    /// is controllable. Add activities with [`Mission::with_activity`].
    pub fn new(name: impl Into<String>, net: Net, initial_places: Vec<PlaceId>, final_places: Vec<PlaceId>) -> Self {
        let controllable = net.transitions().iter().map(|t| t.kind.is_immediate()).collect();
        Mission {
            name: name.into(),
            net,
            initial_places,
            final_places,
            controllable,
            activities: Vec::new(),
            off_nominal: Vec::new(),
        }
    }

    /// Adds an activity.
    pub fn with_activity(mut self, a: Activity) -> Self {
        self.activities.push(a);
        self
    }

    /// A mission compiled by `mcl_compiler`: one activity per labelled call
    /// (two calls with one label make two activities with that label; a
    /// constraint then applies to both).
    ///
    /// The controllable transitions are the `start` transitions of the call
    /// adapters: a supervisor may hold a call before it starts, exactly as a
    /// busy task lock does, never anything inside a block nor an abort.
    ///
    /// The `cancel` transitions get priority 1 (above every other immediate
    /// transition): a call that a supervisor releases at the very moment its
    /// parent aborts it is cancelled, not started and then aborted in the
    /// middle of its task's start (which the building blocks do not allow).
    pub fn from_compiled(name: impl Into<String>, net: Net) -> Self {
        let calls = call_nodes(&net);
        let mut b = net.to_builder();
        for c in &calls {
            if let Some(t) = b.transition_mut(c.cancel) {
                t.priority = Some(1);
            }
        }
        let net = b.build().expect("changing a priority keeps the net valid");
        let mut controllable = vec![false; net.transition_count()];
        let mut activities = Vec::new();
        for c in &calls {
            controllable[c.start.index()] = true;
            if let Some(l) = &c.label {
                activities.push(Activity::call(&net, c, l.clone()));
            }
        }
        let pid = |id: &str| net.place_by_id(id);
        let initial_places = pid(mcl_compiler::compile::MISSION_BEGIN).into_iter().collect();
        let final_places = [mcl_compiler::compile::MISSION_OK, mcl_compiler::compile::MISSION_FAIL]
            .iter()
            .filter_map(|id| pid(id))
            .collect();
        let off_nominal = off_nominal(&net, &calls);
        Mission { name: name.into(), net, initial_places, final_places, controllable, activities, off_nominal }
    }

    /// The activities labelled `label`.
    pub fn activities_labelled<'a>(&'a self, label: &'a str) -> impl Iterator<Item = &'a Activity> + 'a {
        self.activities.iter().filter(move |a| a.label == label)
    }
}

/// The off-nominal answers of every call ([`Mission::off_nominal`]): all
/// the events of a task called in a monitor condition; the fail events
/// (net property `task_events:T`) of a task called outside any condition.
/// A task's net is shared by its calls: its events are off-nominal only
/// while such a call holds it (its `run` place is marked).
fn off_nominal(net: &Net, calls: &[CallNodes]) -> Vec<(TransitionId, Vec<PlaceId>)> {
    let fail_events: std::collections::HashMap<&str, Vec<String>> =
        net.task_events().map(|(task, e)| (task, e.fail)).collect();
    // Per task: the `run` places of its calls for which all its events are
    // off-nominal (monitor conditions), and of those for which its fail
    // events are (calls outside any condition; tests answer either way).
    let mut by_task: std::collections::BTreeMap<&str, (Vec<PlaceId>, Vec<PlaceId>)> = Default::default();
    for c in calls {
        let entry = by_task.entry(c.task.as_str()).or_default();
        match c.role.as_deref() {
            Some("monitor_condition") => entry.0.push(c.run),
            None => entry.1.push(c.run),
            Some(_) => {}
        }
    }
    let mut out = Vec::new();
    for t in net.transition_ids() {
        let Some(tr) = net.transition(t) else { continue };
        let mcl_net::TransitionKind::Event(e) = &tr.kind else { continue };
        let Some((task, _)) = tr.id.strip_prefix("task.").and_then(|r| r.split_once('.')) else { continue };
        let Some((monitor, plain)) = by_task.get(task) else { continue };
        let mut places = monitor.clone();
        if fail_events.get(task).is_some_and(|f| f.iter().any(|x| x == e)) {
            places.extend(plain);
        }
        if !places.is_empty() {
            out.push((t, places));
        }
    }
    out
}

/// `mission:label`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct CallRef {
    /// Mission name.
    pub mission: String,
    /// Call label.
    pub label: String,
}

impl CallRef {
    /// `mission:label`.
    pub fn new(mission: impl Into<String>, label: impl Into<String>) -> Self {
        CallRef { mission: mission.into(), label: label.into() }
    }
}

impl std::fmt::Display for CallRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.mission, self.label)
    }
}

/// The three coordination constraints of seed 6.1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ConstraintKind {
    /// At most `bound` of the calls run at once (Definition 6.1.1).
    Mutex {
        /// β ≥ 1.
        bound: u32,
    },
    /// The second call starts only after the first has ended, once per
    /// ending (Definition 6.1.3, counted with the Parikh vector).
    Order,
    /// The calls start together: none starts before all have arrived
    /// (Definition 6.1.5).
    Sync,
}

/// A coordination constraint, as written in a `constraints { ... }` block.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Constraint {
    /// Which constraint.
    #[serde(flatten)]
    pub kind: ConstraintKind,
    /// The calls it names, in order.
    pub calls: Vec<CallRef>,
    /// Where it is written (byte range in its file), if it comes from MCL.
    pub span: Option<(u32, u32)>,
}

impl Constraint {
    /// `mutex { calls } = bound`.
    pub fn mutex(calls: impl IntoIterator<Item = CallRef>, bound: u32) -> Self {
        Constraint { kind: ConstraintKind::Mutex { bound }, calls: calls.into_iter().collect(), span: None }
    }

    /// `order { first, second }`.
    pub fn order(first: CallRef, second: CallRef) -> Self {
        Constraint { kind: ConstraintKind::Order, calls: vec![first, second], span: None }
    }

    /// `sync { calls }`.
    pub fn sync(calls: impl IntoIterator<Item = CallRef>) -> Self {
        Constraint { kind: ConstraintKind::Sync, calls: calls.into_iter().collect(), span: None }
    }
}

impl std::fmt::Display for Constraint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let calls: Vec<String> = self.calls.iter().map(|c| c.to_string()).collect();
        match self.kind {
            ConstraintKind::Mutex { bound } => write!(f, "mutex {{ {} }} = {bound}", calls.join(", ")),
            ConstraintKind::Order => write!(f, "order {{ {} }}", calls.join(", ")),
            ConstraintKind::Sync => write!(f, "sync {{ {} }}", calls.join(", ")),
        }
    }
}
