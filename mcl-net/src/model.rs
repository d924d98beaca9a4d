//! The net model: places, transitions, weighted arcs, MCL annotations and
//! precomputed pre/post sets.
//!
//! A [`Net`] is immutable once built; it is made with a [`NetBuilder`], which
//! validates the structure (unique ids, weights ≥ 1, finite delays) and
//! precomputes the sparse adjacency used by firing and analysis.

use rustc_hash::FxHashMap as HashMap;
use std::fmt;

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
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
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
}

/// A byte range `start..end` in a source file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
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
    pub id: String,
    /// Human-readable name (defaults to the id).
    pub name: String,
    /// Initial number of tokens.
    pub initial: u32,
    /// Interface id: [`INTERFACE_NONE`], [`INTERFACE_EXTERNAL`], or 2.. for internal interfaces.
    pub interface: u32,
    /// Source mapping.
    pub provenance: Provenance,
}

impl Place {
    /// A place with the given id (also used as name), no tokens and no interface.
    pub fn new(id: impl Into<String>) -> Self {
        let id = id.into();
        Place { name: id.clone(), id, initial: 0, interface: INTERFACE_NONE, provenance: Provenance::default() }
    }

    /// Sets the name.
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
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

    /// Sets the provenance.
    pub fn with_provenance(mut self, provenance: Provenance) -> Self {
        self.provenance = provenance;
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
    /// `monitor_condition` (inside the condition of a monitor) or
    /// `while_condition` (inside the condition of a while loop).
    pub role: Option<String>,
}

/// A transition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Transition {
    /// Unique id (shared namespace with places, as in PNML).
    pub id: String,
    /// Human-readable name (defaults to the id).
    pub name: String,
    /// Trigger kind.
    pub kind: TransitionKind,
    /// Actions sent when the transition fires, in order.
    pub actions: Vec<ActionRef>,
    /// Priority among enabled immediate transitions (higher first; `None` = 0).
    pub priority: Option<u32>,
    /// For the transition that starts a call: the call's arguments.
    pub binding: Option<CallBinding>,
    /// Source mapping.
    pub provenance: Provenance,
}

impl Transition {
    /// An immediate transition with the given id (also used as name).
    pub fn new(id: impl Into<String>) -> Self {
        let id = id.into();
        Transition {
            name: id.clone(),
            id,
            kind: TransitionKind::Immediate,
            actions: Vec::new(),
            priority: None,
            binding: None,
            provenance: Provenance::default(),
        }
    }

    /// Sets the name.
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
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

    /// Sets the provenance.
    pub fn with_provenance(mut self, provenance: Provenance) -> Self {
        self.provenance = provenance;
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
    pub(crate) fn from_rows(rows: impl IntoIterator<Item = Vec<T>>) -> Self {
        let mut offsets = vec![0u32];
        let mut items = Vec::new();
        for row in rows {
            items.extend(row);
            offsets.push(items.len() as u32);
        }
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
    delta: Csr<(PlaceId, i64)>,
    consumers: Csr<TransitionId>,
    producers: Csr<TransitionId>,
    by_id: HashMap<String, NodeId>,
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
        self.by_id.get(id).copied()
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
        self.delta.row(t.index())
    }

    /// Transitions that consume from `p` (p•), sorted.
    #[inline]
    pub fn consumers(&self, p: PlaceId) -> &[TransitionId] {
        self.consumers.row(p.index())
    }

    /// Transitions that produce into `p` (•p), sorted.
    #[inline]
    pub fn producers(&self, p: PlaceId) -> &[TransitionId] {
        self.producers.row(p.index())
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
    pub fn build(self) -> Result<Net, NetError> {
        let np = self.places.len();
        let nt = self.transitions.len();
        if np >= u32::MAX as usize || nt >= u32::MAX as usize {
            return Err(NetError::TooLarge);
        }
        let mut by_id = HashMap::with_capacity_and_hasher(np + nt, Default::default());
        for (i, p) in self.places.iter().enumerate() {
            if p.id.is_empty() {
                return Err(NetError::EmptyId);
            }
            if by_id.insert(p.id.clone(), NodeId::Place(PlaceId(i as u32))).is_some() {
                return Err(NetError::DuplicateId(p.id.clone()));
            }
        }
        let mut by_event: HashMap<String, Vec<TransitionId>> = HashMap::default();
        for (i, t) in self.transitions.iter().enumerate() {
            if t.id.is_empty() {
                return Err(NetError::EmptyId);
            }
            let tid = TransitionId(i as u32);
            if by_id.insert(t.id.clone(), NodeId::Transition(tid)).is_some() {
                return Err(NetError::DuplicateId(t.id.clone()));
            }
            match &t.kind {
                TransitionKind::Timed(Delay::Fixed(d)) if !(d.is_finite() && *d >= 0.0) => {
                    return Err(NetError::InvalidDelay { transition: t.id.clone() })
                }
                TransitionKind::Event(e) => by_event.entry(e.clone()).or_default().push(tid),
                _ => {}
            }
        }

        // Merge parallel arcs, keeping the position of the first occurrence.
        let mut arcs: Vec<Arc> = Vec::with_capacity(self.arcs.len());
        let mut seen: HashMap<(bool, u32, u32), usize> =
            HashMap::with_capacity_and_hasher(self.arcs.len(), Default::default());
        for arc in &self.arcs {
            let (input, p, t, w) = match *arc {
                Arc::Input { place, transition, weight } => (true, place, transition, weight),
                Arc::Output { transition, place, weight } => (false, place, transition, weight),
            };
            let place = self.places.get(p.index()).ok_or_else(|| NetError::UnknownNode(format!("place #{}", p.0)))?;
            let trans =
                self.transitions.get(t.index()).ok_or_else(|| NetError::UnknownNode(format!("transition #{}", t.0)))?;
            if w == 0 {
                return Err(NetError::ZeroWeight { place: place.id.clone(), transition: trans.id.clone() });
            }
            match seen.get(&(input, p.0, t.0)) {
                Some(&k) => {
                    let slot = match &mut arcs[k] {
                        Arc::Input { weight, .. } | Arc::Output { weight, .. } => weight,
                    };
                    *slot = slot.checked_add(w).ok_or_else(|| NetError::WeightOverflow {
                        place: place.id.clone(),
                        transition: trans.id.clone(),
                    })?;
                }
                None => {
                    seen.insert((input, p.0, t.0), arcs.len());
                    arcs.push(*arc);
                }
            }
        }

        let mut pre = vec![Vec::new(); nt];
        let mut post = vec![Vec::new(); nt];
        let mut consumers = vec![Vec::new(); np];
        let mut producers = vec![Vec::new(); np];
        for arc in &arcs {
            match *arc {
                Arc::Input { place, transition, weight } => {
                    pre[transition.index()].push((place, weight));
                    consumers[place.index()].push(transition);
                }
                Arc::Output { transition, place, weight } => {
                    post[transition.index()].push((place, weight));
                    producers[place.index()].push(transition);
                }
            }
        }
        for row in pre.iter_mut().chain(post.iter_mut()) {
            row.sort_unstable();
        }
        for row in consumers.iter_mut().chain(producers.iter_mut()) {
            row.sort_unstable();
        }
        let delta: Vec<Vec<(PlaceId, i64)>> = (0..nt)
            .map(|t| {
                let mut d: Vec<(PlaceId, i64)> = Vec::new();
                for &(p, w) in &pre[t] {
                    d.push((p, -i64::from(w)));
                }
                for &(p, w) in &post[t] {
                    match d.iter_mut().find(|(q, _)| *q == p) {
                        Some(e) => e.1 += i64::from(w),
                        None => d.push((p, i64::from(w))),
                    }
                }
                d.retain(|&(_, x)| x != 0);
                d.sort_unstable();
                d
            })
            .collect();

        Ok(Net {
            id: self.id,
            name: self.name,
            properties: self.properties,
            places: self.places,
            transitions: self.transitions,
            arcs,
            pre: Csr::from_rows(pre),
            post: Csr::from_rows(post),
            delta: Csr::from_rows(delta),
            consumers: Csr::from_rows(consumers),
            producers: Csr::from_rows(producers),
            by_id,
            by_event,
        })
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
