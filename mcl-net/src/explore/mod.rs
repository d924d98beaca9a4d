//! Explicit-state reachability analysis.
//!
//! [`explore`] builds the set of reachable markings breadth-first, so the
//! recorded parent of every state gives a shortest firing sequence to it.
//! Two semantics are available ([`Semantics`]): plain P/T interleaving, and the
//! MCL rule of [`crate::semantics`] in which only immediate transitions fire in
//! vanishing markings and event/timed transitions fire (nondeterministically)
//! in tangible ones.
//!
//! The engine (see `engine.rs`) packs markings into bit fields, keeps them in
//! a flat arena that doubles as the BFS queue and looks successors up in an
//! open-addressing table with the packed marking stored inline (`fixed.rs`
//! specialises it for markings of up to 8 words). With [`Options::threads`]
//! above 1, the work is shared by worker threads in one of two ways
//! ([`Options::exact_order`]):
//!
//! * `parallel.rs` (exact order, the default) partitions the states by hash
//!   and goes level by level, numbering the states exactly as the
//!   sequential search does, so dead markings come with shortest paths; the
//!   barrier at every level limits its speed-up. Used wherever a shortest
//!   counterexample or the BFS numbering matters.
//! * `unordered.rs` keeps one lock-free table shared by all threads, which
//!   expand chunks of states continuously and steal chunks from each other,
//!   with no barrier; it gives the same counts, deadlock verdict, bounds and
//!   vanishing markings, and real (not always shortest) paths. `mcl analyze
//!   --threads N` uses it unless `--shortest-paths` is given.
//!
//! `stubborn.rs`
//! explores with stubborn sets instead ([`explore_por`]: deadlocks exact,
//! fewer states); `symbolic/` builds the reachable markings as a decision
//! diagram by saturation ([`explore_symbolic`]: exact counts without
//! enumerating markings).

use std::fmt;

use serde::Serialize;

use crate::model::{Marking, Net, PlaceId, TransitionId};

mod engine;
mod fixed;
mod fold;
mod hw;
mod parallel;
mod stubborn;
pub mod symbolic;
mod unordered;

pub use stubborn::{explore_por, explore_por_examples, DeadExample, PorReport};
pub use symbolic::{explore_symbolic, SymbolicOptions, SymbolicReport};

use engine::Layout;

/// Which firing rule drives the exploration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Semantics {
    /// Every enabled transition may fire (P/T interleaving; for other tools' nets).
    Plain,
    /// The MCL rule: immediate first (by priority), then events and timers.
    #[default]
    Mcl,
}

/// Exploration options.
#[derive(Clone, Debug, Serialize)]
pub struct Options {
    /// Firing rule.
    pub semantics: Semantics,
    /// Stop after storing this many states (the report then says `complete: false`).
    pub max_states: usize,
    /// How many dead markings to describe with a shortest path.
    pub max_dead_examples: usize,
    /// Worker threads (0 = one per core, at most 8; default 1). With
    /// [`Options::exact_order`] results do not depend on it, state numbering
    /// included, except which states are kept at the BFS level where
    /// `max_states` is reached. Recording edges and cutting markings always
    /// run on one thread.
    pub threads: usize,
    /// With several threads: number the states in BFS order and keep
    /// shortest paths (the level-synchronous `parallel.rs`; default). When
    /// false, the asynchronous `unordered.rs` explores without levels:
    /// the same states, edges, dead markings, vanishing markings and bounds,
    /// but other ids, and paths that are real but not always shortest. One
    /// thread always runs the sequential BFS. The unordered engine may stop
    /// short of `max_states` (by at most the ids other threads' batches
    /// have reserved; see `unordered.rs`).
    pub exact_order: bool,
    /// Keep the edges (state, ready transition, successor) for
    /// [`StateSpace::successors`] and [`StateSpace::coreachable`].
    pub record_edges: bool,
    /// Do not expand a marking in which some place holds more than this many
    /// tokens; such states are listed by [`StateSpace::cut_states`]. With
    /// `Some(1)`, checking 1-safeness stays finite on unbounded nets.
    pub cut_above: Option<u32>,
}

/// Default [`Options::max_states`].
pub const DEFAULT_MAX_STATES: usize = 5_000_000;

impl Default for Options {
    fn default() -> Self {
        Options {
            semantics: Semantics::Mcl,
            max_states: DEFAULT_MAX_STATES,
            max_dead_examples: 10,
            threads: 1,
            exact_order: true,
            record_edges: false,
            cut_above: None,
        }
    }
}

impl Options {
    /// Default options with the plain P/T semantics.
    pub fn plain() -> Self {
        Options { semantics: Semantics::Plain, ..Options::default() }
    }
}

/// Why an exploration stopped before the whole state space was built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// [`Options::max_states`] states were stored.
    StateLimit,
    /// A place would hold more than `u32::MAX` tokens.
    TokenOverflow,
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::StateLimit => write!(f, "state limit reached"),
            StopReason::TokenOverflow => write!(f, "a place exceeded 2^32 - 1 tokens"),
        }
    }
}

/// Index of a state in a [`StateSpace`] (BFS discovery order; 0 is the initial marking).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(transparent)]
pub struct StateId(pub u32);

const NO_PARENT: u32 = u32::MAX;

/// The reachable markings of a net, with a BFS tree for shortest paths.
#[derive(Clone, Debug)]
pub struct StateSpace {
    semantics: Semantics,
    layout: Layout,
    /// `layout.words` words per state, in BFS order.
    arena: Vec<u64>,
    parent: Vec<u32>,
    via: Vec<u32>,
    dead: Vec<u32>,
    vanishing: Vec<u64>,
    edges: u64,
    stop: Option<StopReason>,
    /// Highest token count of each place seen.
    bounds: Vec<u32>,
    /// Highest token total of an expanded state.
    max_total: u64,
    /// With [`Options::record_edges`]: `succ[succ_off[s]..succ_off[s + 1]]`.
    succ_off: Vec<u32>,
    succ: Vec<(TransitionId, StateId)>,
    /// States not expanded because of [`Options::cut_above`].
    cut: Vec<u32>,
}

impl StateSpace {
    /// Number of stored states.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// True only for an empty space (never returned by [`explore`]).
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Firing rule used.
    pub fn semantics(&self) -> Semantics {
        self.semantics
    }

    /// Number of (state, ready transition) pairs of the expanded states.
    pub fn edges(&self) -> u64 {
        self.edges
    }

    /// True when every reachable state was stored and expanded.
    pub fn complete(&self) -> bool {
        self.stop.is_none()
    }

    /// Why the exploration stopped early, if it did.
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// All state ids, in BFS order (unless [`Options::exact_order`] was false).
    pub fn states(&self) -> impl ExactSizeIterator<Item = StateId> {
        (0..self.len() as u32).map(StateId)
    }

    /// Tokens in place `p` in state `s` (0 when out of range).
    pub fn tokens(&self, s: StateId, p: PlaceId) -> u32 {
        let w = self.layout.words;
        match self.arena.get(s.0 as usize * w..(s.0 as usize + 1) * w) {
            Some(state) => self.layout.get(state, p.index()),
            None => 0,
        }
    }

    /// The marking of state `s`.
    pub fn marking(&self, s: StateId) -> Marking {
        Marking((0..self.layout.places as u32).map(|p| self.tokens(s, PlaceId(p))).collect())
    }

    /// A firing sequence from the initial marking to `s`: a shortest one
    /// unless [`Options::exact_order`] was false.
    pub fn path_to(&self, s: StateId) -> Vec<TransitionId> {
        let mut path = Vec::new();
        let mut cur = s.0;
        while let (Some(&p), Some(&t)) = (self.parent.get(cur as usize), self.via.get(cur as usize)) {
            if p == NO_PARENT {
                break;
            }
            path.push(TransitionId(t));
            cur = p;
        }
        path.reverse();
        path
    }

    /// States in which no transition is enabled, by increasing id.
    pub fn dead_states(&self) -> impl ExactSizeIterator<Item = StateId> + '_ {
        self.dead.iter().map(|&s| StateId(s))
    }

    /// True when `s` is vanishing (always false under [`Semantics::Plain`]).
    pub fn is_vanishing(&self, s: StateId) -> bool {
        let i = s.0 as usize;
        self.vanishing.get(i / 64).is_some_and(|w| w & (1u64 << (i % 64)) != 0)
    }

    /// Number of vanishing states.
    pub fn vanishing_count(&self) -> u64 {
        self.vanishing.iter().map(|w| u64::from(w.count_ones())).sum()
    }

    /// Highest token count of each place over the stored states (and their
    /// successors, when the exploration stopped early).
    pub fn bounds(&self) -> &[u32] {
        &self.bounds
    }

    /// Largest total number of tokens in one expanded state.
    pub fn max_tokens(&self) -> u64 {
        self.max_total
    }

    /// True when the edges were recorded ([`Options::record_edges`]).
    pub fn has_edges(&self) -> bool {
        !self.succ_off.is_empty()
    }

    /// The ready transitions of `s` with the states they lead to, in the order
    /// the firing rule lists them (empty unless [`Options::record_edges`]).
    pub fn successors(&self, s: StateId) -> &[(TransitionId, StateId)] {
        let i = s.0 as usize;
        match (self.succ_off.get(i), self.succ_off.get(i + 1)) {
            (Some(&a), Some(&b)) => self.succ.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// For every state, whether some state satisfying `target` can be reached
    /// from it (itself included), following the recorded edges. Without
    /// [`Options::record_edges`] only the targets themselves are marked.
    pub fn coreachable(&self, mut target: impl FnMut(StateId) -> bool) -> Vec<bool> {
        let n = self.len();
        let mut reach: Vec<bool> = (0..n as u32).map(|s| target(StateId(s))).collect();
        if !self.has_edges() {
            return reach;
        }
        // Reverse adjacency, then a backward search from the targets.
        let mut count = vec![0u32; n + 1];
        for &(_, d) in &self.succ {
            if let Some(c) = count.get_mut(d.0 as usize + 1) {
                *c += 1;
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        let mut preds = vec![0u32; self.succ.len()];
        for s in 0..n {
            for &(_, d) in self.successors(StateId(s as u32)) {
                if let Some(f) = fill.get_mut(d.0 as usize) {
                    preds[*f as usize] = s as u32;
                    *f += 1;
                }
            }
        }
        let mut stack: Vec<u32> = (0..n as u32).filter(|&s| reach[s as usize]).collect();
        while let Some(d) = stack.pop() {
            let (a, b) = (count[d as usize] as usize, count[d as usize + 1] as usize);
            for &p in &preds[a..b] {
                if !reach[p as usize] {
                    reach[p as usize] = true;
                    stack.push(p);
                }
            }
        }
        reach
    }

    /// States not expanded because of [`Options::cut_above`], in BFS order.
    pub fn cut_states(&self) -> impl ExactSizeIterator<Item = StateId> + '_ {
        self.cut.iter().map(|&s| StateId(s))
    }

    /// Bits used per place in the packed markings (1, 2, 4, 8, 16 or 32).
    pub fn bits_per_place(&self) -> u32 {
        self.layout.bits
    }
}

/// Explores the reachable markings of `net` under `opts`.
pub fn explore(net: &Net, opts: &Options) -> StateSpace {
    engine::explore(net, opts)
}

/// A dead marking with a path to it (shortest unless [`Options::exact_order`] was false).
#[derive(Clone, Debug, Serialize)]
pub struct DeadMarking {
    /// State index.
    pub state: StateId,
    /// Marked places as `(place id, tokens)`.
    pub marking: Vec<(String, u32)>,
    /// Firing sequence from the initial marking, as transition indices.
    pub path: Vec<TransitionId>,
    /// The same sequence as transition names.
    pub path_names: Vec<String>,
}

/// Bound of one place.
#[derive(Clone, Debug, Serialize)]
pub struct PlaceBound {
    /// Place id.
    pub place: String,
    /// Highest token count seen.
    pub bound: u32,
}

/// Result of [`analyze`].
#[derive(Clone, Debug, Serialize)]
pub struct AnalysisReport {
    /// Net id.
    pub net: String,
    /// Firing rule used.
    pub semantics: Semantics,
    /// Number of reachable markings stored.
    pub states: u64,
    /// Number of (reachable marking, ready transition) pairs.
    pub edges: u64,
    /// False when exploration stopped early; counts and bounds are then lower bounds.
    pub complete: bool,
    /// Why exploration stopped early.
    pub stop_reason: Option<StopReason>,
    /// Some reachable marking enables no transition.
    pub deadlock: bool,
    /// Number of dead markings.
    pub dead_markings: u64,
    /// Up to [`Options::max_dead_examples`] dead markings, by increasing state id.
    pub dead_examples: Vec<DeadMarking>,
    /// Every place holds at most one token in every reachable marking.
    pub one_safe: bool,
    /// The largest bound of a place: the most tokens any one place holds in
    /// a reachable marking (MCC `MaxTokenInPlace`; 1 for a 1-safe net with
    /// a marked place).
    pub max_tokens: u32,
    /// The most tokens in one reachable marking, all places together (MCC
    /// `MaxTokenPerMarking`).
    pub max_tokens_per_marking: u64,
    /// Bound of each place, in place order.
    pub bounds: Vec<PlaceBound>,
    /// Vanishing markings (MCL semantics only; 0 under plain semantics).
    pub vanishing_states: u64,
    /// Markings not expanded because of [`Options::cut_above`].
    pub cut_states: u64,
}

/// Explores `net` and summarizes the state space.
pub fn analyze(net: &Net, opts: &Options) -> AnalysisReport {
    let ss = explore(net, opts);
    report(net, &ss, opts.max_dead_examples)
}

/// Summarizes an explored state space.
pub fn report(net: &Net, ss: &StateSpace, max_dead_examples: usize) -> AnalysisReport {
    let (bounds, max_tokens) = (ss.bounds(), ss.max_tokens());
    let dead_examples = ss
        .dead_states()
        .take(max_dead_examples)
        .map(|s| {
            let path = ss.path_to(s);
            DeadMarking {
                state: s,
                marking: ss
                    .marking(s)
                    .support()
                    .map(|(p, n)| (net.place(p).map_or_else(String::new, |pl| pl.id.to_string()), n))
                    .collect(),
                path_names: path
                    .iter()
                    .map(|&t| net.transition(t).map_or_else(String::new, |tr| tr.name.to_string()))
                    .collect(),
                path,
            }
        })
        .collect();
    AnalysisReport {
        net: net.id().to_string(),
        semantics: ss.semantics(),
        states: ss.len() as u64,
        edges: ss.edges(),
        complete: ss.complete(),
        stop_reason: ss.stop_reason(),
        deadlock: ss.dead_states().len() > 0,
        dead_markings: ss.dead_states().len() as u64,
        dead_examples,
        one_safe: bounds.iter().all(|&b| b <= 1),
        max_tokens: bounds.iter().copied().max().unwrap_or(0),
        max_tokens_per_marking: max_tokens,
        bounds: net
            .places()
            .iter()
            .zip(bounds)
            .map(|(p, &b)| PlaceBound { place: p.id.to_string(), bound: b })
            .collect(),
        vanishing_states: ss.vanishing_count(),
        cut_states: ss.cut.len() as u64,
    }
}
