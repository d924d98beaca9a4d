//! The net model: places, transitions, weighted arcs, MCL annotations and
//! precomputed pre/post sets.
//!
//! A [`Net`] is immutable once built; it is made with a [`NetBuilder`], which
//! validates the structure (unique ids, weights ≥ 1, finite delays) and
//! precomputes the sparse adjacency used by firing and analysis.

use rustc_hash::FxHashMap as HashMap;
use std::fmt;
use std::sync::OnceLock;

pub use crate::name::{Name, SharedText};

/// The events that end a task in ok and in fail (net property
/// `task_events:T`, [`Net::task_events`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Deserialize)]
pub struct TaskEvents {
    /// Events that end the task in ok.
    #[serde(default)]
    pub ok: Vec<String>,
    /// Events that end the task in fail.
    #[serde(default)]
    pub fail: Vec<String>,
}

/// The calls of one task in a mission ([`Net::task_calls`]), by call site.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TaskCalls {
    /// Calls inside a monitor's condition (binding role `monitor_condition`):
    /// the task's ok event raises the monitor's `do` block.
    pub condition: Vec<u32>,
    /// Every other call.
    pub other: Vec<u32>,
}

/// A transition through which a mission leaves its nominal path: a
/// `try`'s block failed and its `catch` starts, or a monitor's condition
/// ended and its `do` block is about to run. The compiler lists them in the
/// net property [`HANDLERS_PROPERTY`] (a JSON array of these); the tracer
/// marks their firings and says how a mission ended.
#[derive(Clone, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub struct Handler {
    /// The transition's id.
    pub transition: String,
    /// What it starts.
    pub kind: HandlerKind,
}

/// What a [`Handler`] transition starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HandlerKind {
    /// The `catch` block of a `try` whose block failed.
    Catch,
    /// The `do` block of a monitor's `condition` or `while_condition`.
    Condition,
}

/// The net property that lists the [`Handler`] transitions.
pub const HANDLERS_PROPERTY: &str = "handlers";

use serde::Serialize;

/// Index of a place in a [`Net`] (its position in [`Net::places`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(transparent)]
pub struct PlaceId(pub u32);

/// Index of a transition in a [`Net`] (its position in [`Net::transitions`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(transparent)]
pub struct TransitionId(pub u32);

impl PlaceId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl TransitionId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Interface id of a place that belongs to no interface.
pub const INTERFACE_NONE: u32 = 0;
/// Interface id of the external interface {begin, abort, ok, fail} of a block.
pub const INTERFACE_EXTERNAL: u32 = 1;

/// Where a node of the compiled net comes from in the user's MCL source.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub struct Provenance {
    /// Task whose net this node belongs to.
    pub task: Option<String>,
    /// Call site (unique per compiled mission) this node serves.
    pub call_site: Option<u32>,
    /// Kind of control structure that produced the node (e.g. `sequence`).
    pub structure: Option<String>,
    /// Path of that structure in the mission's structure tree (e.g. `0.1.2`).
    pub path: Option<String>,
    /// Source location.
    pub span: Option<SourceSpan>,
}

impl Provenance {
    /// True when no field is set.
    pub fn is_empty(&self) -> bool {
        *self == Provenance::default()
    }

    /// The empty provenance, shared by every node that has none (no allocation).
    pub fn none() -> std::sync::Arc<Provenance> {
        static NONE: OnceLock<std::sync::Arc<Provenance>> = OnceLock::new();
        NONE.get_or_init(Default::default).clone()
    }
}

/// A byte range `start..end` in a source file.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct SourceSpan {
    /// Source file path as given to the compiler.
    pub file: String,
    /// First byte (inclusive).
    pub start: u32,
    /// Last byte (exclusive).
    pub end: u32,
}

/// A place.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Place {
    /// Unique id (shared namespace with transitions, as in PNML).
    pub id: Name,
    /// Human-readable name (defaults to the id, sharing its text).
    pub name: Name,
    /// Initial number of tokens.
    pub initial: u32,
    /// Interface id: [`INTERFACE_NONE`], [`INTERFACE_EXTERNAL`], or 2.. for internal interfaces.
    pub interface: u32,
    /// Source mapping, shared by the nodes that come from the same place in
    /// the source (read it as a [`Provenance`]; build it with `.into()`).
    pub provenance: std::sync::Arc<Provenance>,
}

impl Place {
    /// A place with the given id (also used as name), no tokens and no interface.
    pub fn new(id: impl Into<Name>) -> Self {
        let id = id.into();
        Place { name: id.clone(), id, initial: 0, interface: INTERFACE_NONE, provenance: Provenance::none() }
    }

    /// Sets the name.
    pub fn with_name(mut self, name: impl Into<Name>) -> Self {
        self.name = name.into();
        self
    }

    /// Sets the initial marking.
    pub fn with_tokens(mut self, tokens: u32) -> Self {
        self.initial = tokens;
        self
    }

    /// Sets the interface id.
    pub fn with_interface(mut self, interface: u32) -> Self {
        self.interface = interface;
        self
    }

    /// Sets the provenance (a [`Provenance`], or one shared with other nodes).
    pub fn with_provenance(mut self, provenance: impl Into<std::sync::Arc<Provenance>>) -> Self {
        self.provenance = provenance.into();
        self
    }
}

/// Delay of a timed transition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Delay {
    /// A fixed number of seconds (finite, ≥ 0).
    Fixed(f64),
    /// Taken from the named task parameter when the net is instantiated.
    Param(String),
}

/// How a transition is triggered (seed, Appendix A).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum TransitionKind {
    /// Fires as soon as it is enabled, before any non-immediate transition.
    Immediate,
    /// Fires when the named event arrives and the marking is tangible.
    Event(String),
    /// Fires when its delay has elapsed and the marking is tangible.
    Timed(Delay),
}

impl TransitionKind {
    /// True for [`TransitionKind::Immediate`].
    #[inline]
    pub fn is_immediate(&self) -> bool {
        matches!(self, TransitionKind::Immediate)
    }

    /// True for a *deferred* transition: timed with a fixed delay of 0. It
    /// fires as soon as the marking is tangible, before any event or
    /// positive delay (see [`crate::semantics::select_ready`]).
    pub fn is_deferred(&self) -> bool {
        matches!(self, TransitionKind::Timed(Delay::Fixed(d)) if *d <= 0.0)
    }
}

/// An action sent to the vehicle when a transition fires.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ActionRef {
    /// MCL action name.
    pub action: String,
    /// Vehicle primitive the action drives.
    pub primitive: String,
    /// Command sent to the primitive (e.g. `enable`, `disable`).
    pub command: String,
    /// Parameters, in order.
    pub params: Vec<(String, String)>,
}

/// The arguments a call site gives to its task, attached to the transition
/// that starts the call. Actions of the task that name a task parameter
/// (`{"param": "way-point"}`) take its value from the current binding.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CallBinding {
    /// Task called.
    pub task: String,
    /// Call site id (unique in the mission).
    pub call_site: u32,
    /// The call's label (`Task(...) : label`), if any.
    pub label: Option<String>,
    /// (task parameter, value as JSON text), in header order.
    pub args: Vec<(String, String)>,
    /// Where the call sits when that matters to a mock vehicle:
    /// `monitor_condition` (inside the condition of a monitor),
    /// `while_condition` (inside the condition of a while loop) or
    /// `negated_while_condition` (there, under an odd number of `not`s).
    pub role: Option<String>,
}

/// A transition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Transition {
    /// Unique id (shared namespace with places, as in PNML).
    pub id: Name,
    /// Human-readable name (defaults to the id, sharing its text).
    pub name: Name,
    /// Trigger kind.
    pub kind: TransitionKind,
    /// Actions sent when the transition fires, in order.
    pub actions: Vec<ActionRef>,
    /// Priority among enabled immediate transitions (higher first; `None` = 0).
    pub priority: Option<u32>,
    /// For the transition that starts a call: the call's arguments (boxed:
    /// few transitions have one; set it with `Some(binding.into())`).
    pub binding: Option<Box<CallBinding>>,
    /// Source mapping, shared by the nodes that come from the same place in
    /// the source (read it as a [`Provenance`]; build it with `.into()`).
    pub provenance: std::sync::Arc<Provenance>,
}

impl Transition {
    /// An immediate transition with the given id (also used as name).
    pub fn new(id: impl Into<Name>) -> Self {
        let id = id.into();
        Transition {
            name: id.clone(),
            id,
            kind: TransitionKind::Immediate,
            actions: Vec::new(),
            priority: None,
            binding: None,
            provenance: Provenance::none(),
        }
    }

    /// Sets the name.
    pub fn with_name(mut self, name: impl Into<Name>) -> Self {
        self.name = name.into();
        self
    }

    /// Sets the kind.
    pub fn with_kind(mut self, kind: TransitionKind) -> Self {
        self.kind = kind;
        self
    }

    /// Appends an action.
    pub fn with_action(mut self, action: ActionRef) -> Self {
        self.actions.push(action);
        self
    }

    /// Sets the priority.
    pub fn with_priority(mut self, priority: u32) -> Self {
        self.priority = Some(priority);
        self
    }

    /// Sets the provenance (a [`Provenance`], or one shared with other nodes).
    pub fn with_provenance(mut self, provenance: impl Into<std::sync::Arc<Provenance>>) -> Self {
        self.provenance = provenance.into();
        self
    }

    /// Effective priority (`None` counts as 0).
    #[inline]
    pub fn effective_priority(&self) -> u32 {
        self.priority.unwrap_or(0)
    }
}

/// A weighted arc.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Arc {
    /// Input arc: the transition consumes `weight` tokens from the place.
    Input {
        /// Source place.
        place: PlaceId,
        /// Target transition.
        transition: TransitionId,
        /// Weight ≥ 1.
        weight: u32,
    },
    /// Output arc: the transition produces `weight` tokens into the place.
    Output {
        /// Source transition.
        transition: TransitionId,
        /// Target place.
        place: PlaceId,
        /// Weight ≥ 1.
        weight: u32,
    },
}

/// A node reference, as found by id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeId {
    /// A place.
    Place(PlaceId),
    /// A transition.
    Transition(TransitionId),
}

/// Compressed sparse rows: row `i` is `items[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Csr<T> {
    offsets: Vec<u32>,
    items: Vec<T>,
}

impl<T: Copy> Csr<T> {
    /// Rows given by their offsets (`offsets[0] == 0`, non-decreasing, last = `items.len()`).
    fn from_parts(offsets: Vec<u32>, items: Vec<T>) -> Self {
        debug_assert_eq!(offsets.last().map(|&o| o as usize), Some(items.len()));
        Csr { offsets, items }
    }

    #[inline]
    pub(crate) fn row(&self, i: usize) -> &[T] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&a), Some(&b)) => &self.items[a as usize..b as usize],
            _ => &[],
        }
    }
}

/// Why a net could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NetError {
    /// A place or transition has an empty id.
    EmptyId,
    /// Two nodes share an id.
    DuplicateId(String),
    /// An arc has weight 0.
    ZeroWeight {
        /// Place id.
        place: String,
        /// Transition id.
        transition: String,
    },
    /// Merged parallel arcs exceed `u32::MAX`.
    WeightOverflow {
        /// Place id.
        place: String,
        /// Transition id.
        transition: String,
    },
    /// An arc refers to a node index that does not exist.
    UnknownNode(String),
    /// A fixed delay is negative, infinite or NaN.
    InvalidDelay {
        /// Transition id.
        transition: String,
    },
    /// More places or transitions than fit in a `u32` index.
    TooLarge,
}

impl fmt::Display for NetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NetError::EmptyId => write!(f, "a place or transition has an empty id"),
            NetError::DuplicateId(id) => write!(f, "duplicate node id `{id}`"),
            NetError::ZeroWeight { place, transition } => {
                write!(f, "arc between `{place}` and `{transition}` has weight 0")
            }
            NetError::WeightOverflow { place, transition } => {
                write!(f, "parallel arcs between `{place}` and `{transition}` add up to more than {}", u32::MAX)
            }
            NetError::UnknownNode(what) => write!(f, "arc refers to unknown {what}"),
            NetError::InvalidDelay { transition } => {
                write!(f, "transition `{transition}` has a delay that is negative, infinite or NaN")
            }
            NetError::TooLarge => write!(f, "net has more than 2^32 - 1 nodes"),
        }
    }
}

impl std::error::Error for NetError {}

/// A place/transition net with MCL annotations.
///
/// Arcs between the same place and transition in the same direction are merged
/// (weights added). Pre/post sets are sorted by place index.
#[derive(Clone, Debug, PartialEq)]
pub struct Net {
    id: String,
    name: String,
    properties: Vec<(String, String)>,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    arcs: Vec<Arc>,
    // Derived data.
    pre: Csr<(PlaceId, u32)>,
    post: Csr<(PlaceId, u32)>,
    /// Delta, consumers and producers: built on first use (a compiled
    /// mission is often written out or checked without them).
    adjacency: Derived,
    /// Node ids by text: built on first lookup (writing PNML needs none,
    /// and a million-call mission's table is hundreds of megabytes).
    by_id: LazyIndex,
    by_event: HashMap<String, Vec<TransitionId>>,
}

impl Net {
    /// Net id (PNML `net/@id`).
    pub fn id(&self) -> &str {
        &self.id
    }

    /// Net name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Free key/value annotations of the net (kept in order).
    pub fn properties(&self) -> &[(String, String)] {
        &self.properties
    }

    /// The transitions through which the mission leaves its nominal path
    /// (property [`HANDLERS_PROPERTY`]; none when absent or malformed).
    pub fn handlers(&self) -> Vec<Handler> {
        self.properties
            .iter()
            .filter(|(k, _)| k == HANDLERS_PROPERTY)
            .filter_map(|(_, v)| serde_json::from_str::<Vec<Handler>>(v).ok())
            .flatten()
            .collect()
    }

    /// The calls of each task, from the start transitions' bindings, split
    /// into monitor conditions and the others; by task name, call sites in
    /// increasing order.
    pub fn task_calls(&self) -> std::collections::BTreeMap<&str, TaskCalls> {
        let mut out: std::collections::BTreeMap<&str, TaskCalls> = Default::default();
        for b in self.transitions.iter().filter_map(|t| t.binding.as_deref()) {
            let calls = out.entry(b.task.as_str()).or_default();
            let list =
                if b.role.as_deref() == Some("monitor_condition") { &mut calls.condition } else { &mut calls.other };
            if !list.contains(&b.call_site) {
                list.push(b.call_site);
            }
        }
        for c in out.values_mut() {
            c.condition.sort_unstable();
            c.other.sort_unstable();
        }
        out
    }

    /// The events that end each task in ok and in fail: the properties
    /// `task_events:T` that the compiler writes for every task it
    /// instantiates, by task name (malformed ones are skipped).
    pub fn task_events(&self) -> impl Iterator<Item = (&str, TaskEvents)> + '_ {
        self.properties.iter().filter_map(|(k, v)| {
            let task = k.strip_prefix("task_events:")?;
            serde_json::from_str::<TaskEvents>(v).ok().map(|e| (task, e))
        })
    }

    /// All places; [`PlaceId`] `i` is `places()[i]`.
    pub fn places(&self) -> &[Place] {
        &self.places
    }

    /// All transitions; [`TransitionId`] `i` is `transitions()[i]`.
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }

    /// All arcs (parallel arcs merged), in insertion order.
    pub fn arcs(&self) -> &[Arc] {
        &self.arcs
    }

    /// Number of places.
    pub fn place_count(&self) -> usize {
        self.places.len()
    }

    /// Number of transitions.
    pub fn transition_count(&self) -> usize {
        self.transitions.len()
    }

    /// The place with this index.
    pub fn place(&self, p: PlaceId) -> Option<&Place> {
        self.places.get(p.index())
    }

    /// The transition with this index.
    pub fn transition(&self, t: TransitionId) -> Option<&Transition> {
        self.transitions.get(t.index())
    }

    /// Iterator over all place ids.
    pub fn place_ids(&self) -> impl ExactSizeIterator<Item = PlaceId> {
        (0..self.places.len() as u32).map(PlaceId)
    }

    /// Iterator over all transition ids.
    pub fn transition_ids(&self) -> impl ExactSizeIterator<Item = TransitionId> {
        (0..self.transitions.len() as u32).map(TransitionId)
    }

    /// Looks a node up by its id.
    pub fn node(&self, id: &str) -> Option<NodeId> {
        let ix = self.by_id.0.get_or_init(|| {
            // Ids are unique (checked by `NetBuilder::build`): the index builds.
            IdIndex::build(self.places.len(), self.transitions.len(), |code| self.code_id(code)).unwrap_or_default()
        });
        ix.find(id, |code| self.code_id(code))
    }

    /// The id of the node with index code `code` (places first, then transitions).
    #[inline]
    fn code_id(&self, code: u32) -> &str {
        node_id(&self.places, &self.transitions, code)
    }

    /// Looks a place up by its id.
    pub fn place_by_id(&self, id: &str) -> Option<PlaceId> {
        match self.node(id) {
            Some(NodeId::Place(p)) => Some(p),
            _ => None,
        }
    }

    /// Looks a transition up by its id.
    pub fn transition_by_id(&self, id: &str) -> Option<TransitionId> {
        match self.node(id) {
            Some(NodeId::Transition(t)) => Some(t),
            _ => None,
        }
    }

    /// Input places of `t` with arc weights (•t), sorted by place.
    #[inline]
    pub fn pre(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        self.pre.row(t.index())
    }

    /// Output places of `t` with arc weights (t•), sorted by place.
    #[inline]
    pub fn post(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        self.post.row(t.index())
    }

    /// Net marking change of firing `t`: `(place, post - pre)` for every place where it is non-zero.
    #[inline]
    pub fn delta(&self, t: TransitionId) -> &[(PlaceId, i64)] {
        self.adjacency().delta.row(t.index())
    }

    /// Transitions that consume from `p` (p•), sorted.
    #[inline]
    pub fn consumers(&self, p: PlaceId) -> &[TransitionId] {
        self.adjacency().consumers.row(p.index())
    }

    /// Transitions that produce into `p` (•p), sorted.
    #[inline]
    pub fn producers(&self, p: PlaceId) -> &[TransitionId] {
        self.adjacency().producers.row(p.index())
    }

    #[inline]
    fn adjacency(&self) -> &Adjacency {
        self.adjacency.0.get_or_init(|| Adjacency::new(&self.pre, &self.post, self.places.len()))
    }

    /// Transitions whose enabledness may change when `t` fires: the consumers of
    /// every place whose marking `t` changes (a transition consuming from two
    /// such places appears twice). Computed on demand: a place shared by many
    /// call sites (a task's lock) would make a precomputed table quadratic.
    #[inline]
    pub fn affected_by(&self, t: TransitionId) -> impl Iterator<Item = TransitionId> + '_ {
        self.delta(t).iter().flat_map(move |&(p, _)| self.consumers(p).iter().copied())
    }

    /// Event-driven transitions waiting for `event`.
    pub fn event_transitions(&self, event: &str) -> &[TransitionId] {
        self.by_event.get(event).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The initial marking.
    pub fn initial_marking(&self) -> Marking {
        Marking(self.places.iter().map(|p| p.initial).collect())
    }

    /// True when some transition is not immediate (the net uses MCL semantics).
    pub fn has_non_immediate(&self) -> bool {
        self.transitions.iter().any(|t| !t.kind.is_immediate())
    }

    /// A builder holding a copy of this net, to extend it.
    pub fn to_builder(&self) -> NetBuilder {
        NetBuilder {
            id: self.id.clone(),
            name: self.name.clone(),
            properties: self.properties.clone(),
            places: self.places.clone(),
            transitions: self.transitions.clone(),
            arcs: self.arcs.clone(),
        }
    }
}

/// A marking: tokens per place, indexed by [`PlaceId`].
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(transparent)]
pub struct Marking(pub Vec<u32>);

impl Marking {
    /// Tokens in `p` (0 if `p` is out of range).
    #[inline]
    pub fn get(&self, p: PlaceId) -> u32 {
        self.0.get(p.index()).copied().unwrap_or(0)
    }

    /// Number of places.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// True for the marking of a net without places.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Total number of tokens.
    pub fn total(&self) -> u64 {
        self.0.iter().map(|&x| u64::from(x)).sum()
    }

    /// Non-zero entries.
    pub fn support(&self) -> impl Iterator<Item = (PlaceId, u32)> + '_ {
        self.0.iter().enumerate().filter(|(_, &n)| n > 0).map(|(i, &n)| (PlaceId(i as u32), n))
    }

    /// Renders the non-zero entries as `name` or `name*k`, using place names of `net`.
    pub fn display(&self, net: &Net) -> String {
        let mut out = Vec::new();
        for (p, n) in self.support() {
            let name = net.place(p).map(|pl| pl.name.as_str()).unwrap_or("?");
            if n == 1 {
                out.push(name.to_string());
            } else {
                out.push(format!("{name}*{n}"));
            }
        }
        format!("{{{}}}", out.join(", "))
    }
}

impl std::ops::Index<PlaceId> for Marking {
    type Output = u32;
    fn index(&self, p: PlaceId) -> &u32 {
        &self.0[p.index()]
    }
}

/// Builds a [`Net`]; validation happens in [`NetBuilder::build`].
#[derive(Clone, Debug, Default)]
pub struct NetBuilder {
    id: String,
    name: String,
    properties: Vec<(String, String)>,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    arcs: Vec<Arc>,
}

impl NetBuilder {
    /// A builder for a net with this id (also used as name).
    pub fn new(id: impl Into<String>) -> Self {
        let id = id.into();
        NetBuilder { name: id.clone(), id, ..Default::default() }
    }

    /// Sets the net name.
    pub fn name(&mut self, name: impl Into<String>) -> &mut Self {
        self.name = name.into();
        self
    }

    /// Adds a key/value annotation to the net.
    pub fn property(&mut self, key: impl Into<String>, value: impl Into<String>) -> &mut Self {
        self.properties.push((key.into(), value.into()));
        self
    }

    /// Reserves room for that many more places, transitions and arcs.
    pub fn reserve(&mut self, places: usize, transitions: usize, arcs: usize) -> &mut Self {
        self.places.reserve(places);
        self.transitions.reserve(transitions);
        self.arcs.reserve(arcs);
        self
    }

    /// Adds a place and returns its index.
    pub fn add_place(&mut self, place: Place) -> PlaceId {
        self.places.push(place);
        PlaceId(self.places.len() as u32 - 1)
    }

    /// Adds a transition and returns its index.
    pub fn add_transition(&mut self, transition: Transition) -> TransitionId {
        self.transitions.push(transition);
        TransitionId(self.transitions.len() as u32 - 1)
    }

    /// Adds an input arc `place -> transition`.
    pub fn add_input(&mut self, place: PlaceId, transition: TransitionId, weight: u32) -> &mut Self {
        self.arcs.push(Arc::Input { place, transition, weight });
        self
    }

    /// Adds an output arc `transition -> place`.
    pub fn add_output(&mut self, transition: TransitionId, place: PlaceId, weight: u32) -> &mut Self {
        self.arcs.push(Arc::Output { transition, place, weight });
        self
    }

    /// The place added with this index, to amend it.
    pub fn place_mut(&mut self, p: PlaceId) -> Option<&mut Place> {
        self.places.get_mut(p.index())
    }

    /// The transition added with this index, to amend it.
    pub fn transition_mut(&mut self, t: TransitionId) -> Option<&mut Transition> {
        self.transitions.get_mut(t.index())
    }

    /// The transition added with this index.
    pub fn transition_ref(&self, t: TransitionId) -> Option<&Transition> {
        self.transitions.get(t.index())
    }

    /// Places that transition `t` puts tokens in (arcs added so far; a linear scan).
    pub fn postset(&self, t: TransitionId) -> Vec<PlaceId> {
        self.arcs
            .iter()
            .filter_map(|a| match *a {
                Arc::Output { transition, place, .. } if transition == t => Some(place),
                _ => None,
            })
            .collect()
    }

    /// Transitions that take tokens from place `p` (arcs added so far; a linear scan).
    pub fn consumers_of(&self, p: PlaceId) -> Vec<TransitionId> {
        self.arcs
            .iter()
            .filter_map(|a| match *a {
                Arc::Input { place, transition, .. } if place == p => Some(transition),
                _ => None,
            })
            .collect()
    }

    /// Number of places added so far.
    pub fn place_count(&self) -> usize {
        self.places.len()
    }

    /// Number of transitions added so far.
    pub fn transition_count(&self) -> usize {
        self.transitions.len()
    }

    /// Validates the net and precomputes its adjacency.
    ///
    /// Linear in the size of the net: ids are indexed by an open-addressing
    /// table of node indices (no id is copied), and the adjacency rows are
    /// built by counting sort, without a vector per row.
    pub fn build(self) -> Result<Net, NetError> {
        let np = self.places.len();
        let nt = self.transitions.len();
        if np + nt >= u32::MAX as usize || self.arcs.len() >= u32::MAX as usize {
            return Err(NetError::TooLarge);
        }
        for p in &self.places {
            if p.id.is_empty() {
                return Err(NetError::EmptyId);
            }
        }
        let mut by_event: HashMap<String, Vec<TransitionId>> = HashMap::default();
        for (i, t) in self.transitions.iter().enumerate() {
            if t.id.is_empty() {
                return Err(NetError::EmptyId);
            }
            let tid = TransitionId(i as u32);
            match &t.kind {
                TransitionKind::Timed(Delay::Fixed(d)) if !(d.is_finite() && *d >= 0.0) => {
                    return Err(NetError::InvalidDelay { transition: t.id.to_string() })
                }
                TransitionKind::Event(e) => match by_event.get_mut(e.as_str()) {
                    Some(v) => v.push(tid),
                    None => {
                        by_event.insert(e.clone(), vec![tid]);
                    }
                },
                _ => {}
            }
        }
        // Unique ids, checked without the index (built on the first
        // lookup, [`Net::node`]: writing PNML needs none).
        let id_of = |c: u32| node_id(&self.places, &self.transitions, c);
        if !IdIndex::unique(np + nt, id_of) {
            // The first id, in node order, that an earlier node has.
            let mut seen = rustc_hash::FxHashSet::default();
            let dup = (0..(np + nt) as u32).map(id_of).find(|id| !seen.insert(*id)).unwrap_or_default();
            return Err(NetError::DuplicateId(dup.to_string()));
        }

        // Validate the arcs, in order.
        let ids = |p: PlaceId, t: TransitionId| {
            (self.places[p.index()].id.to_string(), self.transitions[t.index()].id.to_string())
        };
        for arc in &self.arcs {
            let (p, t, w) = match *arc {
                Arc::Input { place, transition, weight } => (place, transition, weight),
                Arc::Output { transition, place, weight } => (place, transition, weight),
            };
            if p.index() >= np {
                return Err(NetError::UnknownNode(format!("place #{}", p.0)));
            }
            if t.index() >= nt {
                return Err(NetError::UnknownNode(format!("transition #{}", t.0)));
            }
            if w == 0 {
                let (place, transition) = ids(p, t);
                return Err(NetError::ZeroWeight { place, transition });
            }
        }

        // Pre and post sets by counting sort; parallel arcs (rare) take the general path.
        let (mut in_off, mut out_off) = (vec![0u32; nt + 1], vec![0u32; nt + 1]);
        for arc in &self.arcs {
            match *arc {
                Arc::Input { transition, .. } => in_off[transition.index() + 1] += 1,
                Arc::Output { transition, .. } => out_off[transition.index() + 1] += 1,
            }
        }
        for i in 0..nt {
            in_off[i + 1] += in_off[i];
            out_off[i + 1] += out_off[i];
        }
        let mut in_items = vec![(PlaceId(0), 0u32); in_off[nt] as usize];
        let mut out_items = vec![(PlaceId(0), 0u32); out_off[nt] as usize];
        {
            // Fill cursors: the start of each row, moved along.
            let (mut in_fill, mut out_fill) = (in_off[..nt].to_vec(), out_off[..nt].to_vec());
            for arc in &self.arcs {
                match *arc {
                    Arc::Input { place, transition, weight } => {
                        let slot = &mut in_fill[transition.index()];
                        in_items[*slot as usize] = (place, weight);
                        *slot += 1;
                    }
                    Arc::Output { transition, place, weight } => {
                        let slot = &mut out_fill[transition.index()];
                        out_items[*slot as usize] = (place, weight);
                        *slot += 1;
                    }
                }
            }
        }
        let sort_rows = |offsets: &[u32], items: &mut [(PlaceId, u32)]| -> bool {
            let mut parallel = false;
            for t in 0..nt {
                let row = &mut items[offsets[t] as usize..offsets[t + 1] as usize];
                // Rows are short: insertion sort by place, noting equal places.
                for i in 1..row.len() {
                    let x = row[i];
                    let mut j = i;
                    while j > 0 && row[j - 1].0 > x.0 {
                        row[j] = row[j - 1];
                        j -= 1;
                    }
                    row[j] = x;
                    parallel |= j > 0 && row[j - 1].0 == x.0;
                }
            }
            parallel
        };
        let parallel_in = sort_rows(&in_off, &mut in_items);
        let parallel_out = sort_rows(&out_off, &mut out_items);
        let (pre, post) = (Csr::from_parts(in_off, in_items), Csr::from_parts(out_off, out_items));
        let (arcs, pre, post) = if parallel_in || parallel_out {
            drop((pre, post));
            merge_parallel_arcs(&self.arcs, &self.places, &self.transitions)?
        } else {
            (self.arcs, pre, post)
        };

        Ok(Net {
            id: self.id,
            name: self.name,
            properties: self.properties,
            places: self.places,
            transitions: self.transitions,
            arcs,
            pre,
            post,
            adjacency: Derived::default(),
            by_id: LazyIndex::default(),
            by_event,
        })
    }
}

/// The adjacency derived from the pre and post sets.
#[derive(Clone, Debug)]
struct Adjacency {
    delta: Csr<(PlaceId, i64)>,
    consumers: Csr<TransitionId>,
    producers: Csr<TransitionId>,
}

/// [`Adjacency`] once computed; a function of the net, so any two are equal.
#[derive(Clone, Debug, Default)]
struct Derived(OnceLock<Adjacency>);

impl PartialEq for Derived {
    fn eq(&self, _: &Derived) -> bool {
        true
    }
}

/// [`IdIndex`] once built; a function of the net, so any two are equal.
#[derive(Clone, Debug, Default)]
struct LazyIndex(OnceLock<IdIndex>);

impl PartialEq for LazyIndex {
    fn eq(&self, _: &LazyIndex) -> bool {
        true
    }
}

impl Adjacency {
    fn new(pre: &Csr<(PlaceId, u32)>, post: &Csr<(PlaceId, u32)>, np: usize) -> Adjacency {
        let nt = pre.offsets.len().saturating_sub(1);
        // Consumers and producers: transitions in increasing order, so rows come sorted.
        let by_place = |adj: &Csr<(PlaceId, u32)>| -> Csr<TransitionId> {
            let mut offsets = vec![0u32; np + 1];
            for &(p, _) in &adj.items {
                offsets[p.index() + 1] += 1;
            }
            for i in 0..np {
                offsets[i + 1] += offsets[i];
            }
            let mut fill = offsets.clone();
            let mut items = vec![TransitionId(0); adj.items.len()];
            for t in 0..nt {
                for &(p, _) in adj.row(t) {
                    let slot = &mut fill[p.index()];
                    items[*slot as usize] = TransitionId(t as u32);
                    *slot += 1;
                }
            }
            Csr::from_parts(offsets, items)
        };
        let consumers = by_place(pre);
        let producers = by_place(post);

        // Delta: merge of the pre and post rows (both sorted by place).
        let mut d_off = Vec::with_capacity(nt + 1);
        d_off.push(0u32);
        let mut d_items: Vec<(PlaceId, i64)> = Vec::with_capacity(pre.items.len() + post.items.len());
        for t in 0..nt {
            let (a, b) = (pre.row(t), post.row(t));
            let (mut i, mut j) = (0, 0);
            while i < a.len() || j < b.len() {
                let (p, x) = match (a.get(i), b.get(j)) {
                    (Some(&(p, w)), Some(&(q, _))) if p < q => {
                        i += 1;
                        (p, -i64::from(w))
                    }
                    (Some(&(p, w)), Some(&(q, v))) if p == q => {
                        i += 1;
                        j += 1;
                        (p, i64::from(v) - i64::from(w))
                    }
                    (_, Some(&(q, v))) => {
                        j += 1;
                        (q, i64::from(v))
                    }
                    (Some(&(p, w)), None) => {
                        i += 1;
                        (p, -i64::from(w))
                    }
                    (None, None) => unreachable!("loop condition"),
                };
                if x != 0 {
                    d_items.push((p, x));
                }
            }
            d_off.push(d_items.len() as u32);
        }

        Adjacency { delta: Csr::from_parts(d_off, d_items), consumers, producers }
    }
}

/// Merges parallel arcs (the general case): rows of arcs per transition,
/// inputs and outputs apart, sorted by place then position; the first of
/// parallel arcs keeps the sum of their weights and the others are dropped.
/// Returns the arcs and the pre and post sets.
#[allow(clippy::type_complexity)]
fn merge_parallel_arcs(
    arcs_in: &[Arc],
    places: &[Place],
    transitions: &[Transition],
) -> Result<(Vec<Arc>, Csr<(PlaceId, u32)>, Csr<(PlaceId, u32)>), NetError> {
    let nt = transitions.len();
    let ids = |p: PlaceId, t: TransitionId| (places[p.index()].id.to_string(), transitions[t.index()].id.to_string());
    // Rows of arcs per transition, inputs and outputs apart, sorted by
    // place then position: parallel arcs are neighbours, the first one
    // keeps the sum of their weights and the others are dropped.
    let mut weights: Vec<u32> = Vec::with_capacity(arcs_in.len());
    let mut in_off = vec![0u32; nt + 1];
    let mut out_off = vec![0u32; nt + 1];
    for arc in arcs_in {
        match *arc {
            Arc::Input { transition, weight, .. } => {
                in_off[transition.index() + 1] += 1;
                weights.push(weight);
            }
            Arc::Output { transition, weight, .. } => {
                out_off[transition.index() + 1] += 1;
                weights.push(weight);
            }
        }
    }
    for i in 0..nt {
        in_off[i + 1] += in_off[i];
        out_off[i + 1] += out_off[i];
    }
    let mut in_rows = vec![(0u32, 0u32); in_off[nt] as usize];
    let mut out_rows = vec![(0u32, 0u32); out_off[nt] as usize];
    {
        let mut in_fill = in_off.clone();
        let mut out_fill = out_off.clone();
        for (k, arc) in arcs_in.iter().enumerate() {
            match *arc {
                Arc::Input { place, transition, .. } => {
                    let slot = &mut in_fill[transition.index()];
                    in_rows[*slot as usize] = (place.0, k as u32);
                    *slot += 1;
                }
                Arc::Output { transition, place, .. } => {
                    let slot = &mut out_fill[transition.index()];
                    out_rows[*slot as usize] = (place.0, k as u32);
                    *slot += 1;
                }
            }
        }
    }
    let mut dropped = vec![false; arcs_in.len()];
    // Merges each row in place; returns the adjacency (place, weight) as CSR.
    let mut merge = |off: &[u32], rows: &mut [(u32, u32)]| -> Result<Csr<(PlaceId, u32)>, NetError> {
        let mut offsets = Vec::with_capacity(nt + 1);
        offsets.push(0u32);
        let mut items: Vec<(PlaceId, u32)> = Vec::with_capacity(rows.len());
        for t in 0..nt {
            let row = &mut rows[off[t] as usize..off[t + 1] as usize];
            if row.len() > 1 {
                row.sort_unstable();
            }
            let mut i = 0;
            while i < row.len() {
                let (p, first) = row[i];
                let mut w = weights[first as usize];
                let mut j = i + 1;
                while j < row.len() && row[j].0 == p {
                    let k = row[j].1 as usize;
                    w = w.checked_add(weights[k]).ok_or_else(|| {
                        let (place, transition) = ids(PlaceId(p), TransitionId(t as u32));
                        NetError::WeightOverflow { place, transition }
                    })?;
                    dropped[k] = true;
                    j += 1;
                }
                weights[first as usize] = w;
                items.push((PlaceId(p), w));
                i = j;
            }
            offsets.push(items.len() as u32);
        }
        Ok(Csr::from_parts(offsets, items))
    };
    let pre = merge(&in_off, &mut in_rows)?;
    let post = merge(&out_off, &mut out_rows)?;
    let arcs: Vec<Arc> = arcs_in
        .iter()
        .zip(&dropped)
        .enumerate()
        .filter(|(_, (_, &d))| !d)
        .map(|(k, (arc, _))| match *arc {
            Arc::Input { place, transition, .. } => Arc::Input { place, transition, weight: weights[k] },
            Arc::Output { transition, place, .. } => Arc::Output { transition, place, weight: weights[k] },
        })
        .collect();
    Ok((arcs, pre, post))
}

/// The id of node `code`: place `code`, or transition `code - places.len()`.
#[inline]
fn node_id<'a>(places: &'a [Place], transitions: &'a [Transition], code: u32) -> &'a str {
    let c = code as usize;
    match places.get(c) {
        Some(p) => &p.id,
        None => &transitions[c - places.len()].id,
    }
}

/// Node ids by text without copying them: an open-addressing table (linear
/// probing, load ≤ 1/2) of node codes (places first, then transitions), each
/// with 32 bits of its id's hash; ids are compared through the nodes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct IdIndex {
    /// (code + 1, hash) per slot; code + 1 = 0 for an empty slot.
    slots: Vec<(u32, u32)>,
    /// Number of places: codes below are places.
    places: u32,
}

impl IdIndex {
    /// The index of the ids of `places` places and `transitions`
    /// transitions (`id_of(code)`), or `None` if two nodes share an id.
    ///
    /// Built by partitions of the table (radix partitioning on the hash):
    /// inserting in node order would touch the whole table at random, a cache
    /// miss per node once the table outgrows the cache.
    fn build<'a>(places: usize, transitions: usize, id_of: impl Fn(u32) -> &'a str) -> Option<Self> {
        let n = places + transitions;
        let size = Self::size(n);
        let mut ix = IdIndex { slots: vec![(0, 0); size], places: places as u32 };
        let pbits = Self::partition_bits(size);
        if pbits == 0 {
            return (0..n as u32).all(|c| ix.insert(Self::hash(id_of(c)), c, &id_of)).then_some(ix);
        }
        Self::by_partition(n, pbits, &id_of).iter().all(|&(h, c)| ix.insert(h, c, &id_of)).then_some(ix)
    }

    /// Table size for `n` nodes: load at most 1/2.
    fn size(n: usize) -> usize {
        (2 * n).next_power_of_two().max(8)
    }

    /// Partitions of at least 4096 slots (32 KiB), at most 1024 of them
    /// (0: too small to partition).
    fn partition_bits(size: usize) -> u32 {
        size.trailing_zeros().saturating_sub(12).min(10)
    }

    /// True when the `n` ids `id_of(0..n)` are all different, without the
    /// whole table: equal ids have equal hashes, so they fall in the same
    /// partition, and each partition is checked with a small table of its
    /// own (what stays is the list of hashes by partition, 16 bytes a node,
    /// instead of the table's 16 to 32 and that list).
    fn unique<'a>(n: usize, id_of: impl Fn(u32) -> &'a str) -> bool {
        let pbits = Self::partition_bits(Self::size(n));
        if pbits == 0 {
            return Self::build(n, 0, id_of).is_some();
        }
        let part = |h: u64| h >> (64 - pbits);
        let order = Self::by_partition(n, pbits, &id_of);
        let mut table: Vec<(u32, u32)> = Vec::new();
        for run in order.chunk_by(|a, b| part(a.0) == part(b.0)) {
            let size = Self::size(run.len());
            let mask = size - 1;
            table.clear();
            table.resize(size, (0, 0));
            for &(h, c) in run {
                // The partition is the hash's high bits: probe by the low ones.
                let tag = (h >> 32) as u32;
                let mut i = h as usize & mask;
                loop {
                    let (k, t) = table[i];
                    if k == 0 {
                        table[i] = (c + 1, tag);
                        break;
                    }
                    if t == tag && id_of(k - 1) == id_of(c) {
                        return false;
                    }
                    i = (i + 1) & mask;
                }
            }
        }
        true
    }

    /// (hash, code) of the `n` nodes grouped by partition (the hash's high
    /// `pbits` bits), in node order within a partition.
    fn by_partition<'a>(n: usize, pbits: u32, id_of: &impl Fn(u32) -> &'a str) -> Vec<(u64, u32)> {
        // Each id is hashed twice (to count, then to place) rather than
        // keeping a vector of hashes: less memory at the peak of a build.
        let part = |h: u64| (h >> (64 - pbits)) as usize;
        let mut offsets = vec![0u32; (1 << pbits) + 1];
        for c in 0..n as u32 {
            offsets[part(Self::hash(id_of(c))) + 1] += 1;
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        // (hash, code) by partition, so that the inserts read them in order.
        let mut order = vec![(0u64, 0u32); n];
        for c in 0..n as u32 {
            let h = Self::hash(id_of(c));
            let slot = &mut offsets[part(h)];
            order[*slot as usize] = (h, c);
            *slot += 1;
        }
        order
    }

    #[inline]
    fn hash(id: &str) -> u64 {
        use std::hash::BuildHasher;
        rustc_hash::FxBuildHasher.hash_one(id)
    }

    /// The first slot to probe for hash `h`: its high bits, so that
    /// partitions by high bits are runs of slots.
    #[inline]
    fn home(&self, h: u64) -> usize {
        let bits = self.slots.len().trailing_zeros();
        if bits == 0 {
            0
        } else {
            (h >> (64 - bits)) as usize
        }
    }

    /// Adds `code` with hash `h`; false if a node with the same id is already there.
    fn insert<'a>(&mut self, h: u64, code: u32, id_of: &impl Fn(u32) -> &'a str) -> bool {
        let tag = h as u32;
        let mask = self.slots.len() - 1;
        let mut i = self.home(h);
        loop {
            let (c, t) = self.slots[i];
            if c == 0 {
                self.slots[i] = (code + 1, tag);
                return true;
            }
            if t == tag && id_of(c - 1) == id_of(code) {
                return false;
            }
            i = (i + 1) & mask;
        }
    }

    /// The node with id `id`.
    fn find<'a>(&self, id: &str, id_of: impl Fn(u32) -> &'a str) -> Option<NodeId> {
        let mask = self.slots.len().checked_sub(1)?;
        let h = Self::hash(id);
        let tag = h as u32;
        let mut i = self.home(h);
        loop {
            let (c, t) = self.slots[i];
            if c == 0 {
                return None;
            }
            if t == tag && id_of(c - 1) == id {
                let code = c - 1;
                return Some(if code < self.places {
                    NodeId::Place(PlaceId(code))
                } else {
                    NodeId::Transition(TransitionId(code - self.places))
                });
            }
            i = (i + 1) & mask;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builder_merges_parallel_arcs_and_computes_sets() {
        let mut b = NetBuilder::new("n");
        let p = b.add_place(Place::new("p").with_tokens(2));
        let q = b.add_place(Place::new("q"));
        let t = b.add_transition(Transition::new("t"));
        b.add_input(p, t, 1).add_input(p, t, 1).add_output(t, q, 1).add_output(t, p, 1);
        let net = b.build().unwrap();
        assert_eq!(net.arcs().len(), 3);
        assert_eq!(net.pre(t), &[(p, 2)]);
        assert_eq!(net.post(t), &[(p, 1), (q, 1)]);
        assert_eq!(net.delta(t), &[(p, -1), (q, 1)]);
        assert_eq!(net.consumers(p), &[t]);
        assert_eq!(net.producers(q), &[t]);
        assert_eq!(net.affected_by(t).collect::<Vec<_>>(), vec![t]);
        assert_eq!(net.place_by_id("q"), Some(q));
        assert_eq!(net.transition_by_id("p"), None);
    }

    #[test]
    fn ids_are_found_and_derived_tables_do_not_change_equality() {
        let mut b = NetBuilder::new("n");
        let ps: Vec<_> = (0..3000).map(|i| b.add_place(Place::new(format!("p{i}")))).collect();
        let ts: Vec<_> = (0..3000).map(|i| b.add_transition(Transition::new(format!("t{i}")))).collect();
        for i in 0..3000 {
            b.add_input(ps[i], ts[i], 1).add_output(ts[i], ps[(i + 1) % 3000], 1);
        }
        let net = b.build().unwrap();
        let fresh = net.clone();
        for i in 0..3000 {
            assert_eq!(net.place_by_id(&format!("p{i}")), Some(ps[i]));
            assert_eq!(net.transition_by_id(&format!("t{i}")), Some(ts[i]));
            assert_eq!(net.consumers(ps[i]), &[ts[i]]);
        }
        assert_eq!(net.node("p3000"), None);
        assert_eq!(net, fresh);

        // Duplicates are found in large nets too (partitioned index), and
        // reported as the first repeated id in node order.
        let mut b = NetBuilder::new("n");
        for i in 0..3000 {
            b.add_place(Place::new(format!("p{i}")));
        }
        b.add_transition(Transition::new("p2999"));
        b.add_transition(Transition::new("p7"));
        assert_eq!(b.build(), Err(NetError::DuplicateId("p2999".into())));

        // Many partitions (the check never builds the whole index).
        let mut b = NetBuilder::new("n");
        for i in 0..40_000 {
            b.add_place(Place::new(format!("p{i}")));
        }
        assert!(b.clone().build().is_ok());
        b.add_transition(Transition::new("p39999"));
        assert_eq!(b.build(), Err(NetError::DuplicateId("p39999".into())));
    }

    #[test]
    fn builder_rejects_bad_nets() {
        let mut b = NetBuilder::new("n");
        b.add_place(Place::new("x"));
        b.add_transition(Transition::new("x"));
        assert_eq!(b.build(), Err(NetError::DuplicateId("x".into())));

        let mut b = NetBuilder::new("n");
        let p = b.add_place(Place::new("p"));
        let t = b.add_transition(Transition::new("t"));
        b.add_input(p, t, 0);
        assert!(matches!(b.build(), Err(NetError::ZeroWeight { .. })));

        let mut b = NetBuilder::new("n");
        let p = b.add_place(Place::new("p"));
        b.add_input(p, TransitionId(3), 1);
        assert!(matches!(b.build(), Err(NetError::UnknownNode(_))));

        let mut b = NetBuilder::new("n");
        b.add_transition(Transition::new("t").with_kind(TransitionKind::Timed(Delay::Fixed(f64::NAN))));
        assert!(matches!(b.build(), Err(NetError::InvalidDelay { .. })));

        let mut b = NetBuilder::new("n");
        let p = b.add_place(Place::new("p"));
        let t = b.add_transition(Transition::new("t"));
        b.add_output(t, p, u32::MAX).add_output(t, p, 1);
        assert!(matches!(b.build(), Err(NetError::WeightOverflow { .. })));
    }
}
