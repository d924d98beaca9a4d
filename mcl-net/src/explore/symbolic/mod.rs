//! Symbolic reachability with multi-valued decision diagrams (MDDs):
//! `mcl analyze --method symbolic`, plain P/T rule.
//!
//! One level per place, the token count as the value, except that
//! mutually exclusive places (found from P-semiflows, `group.rs`) share a
//! level whose value says which of them is marked; levels in the order of
//! `order.rs`. The reachable markings are built by saturation (`saturate.rs`)
//! over the per-transition local relations of `relation.rs` in the node
//! store of `store.rs`; `count.rs` counts them exactly (a memoised path
//! count), counts the edges (for every transition, the reachable markings
//! that enable it), builds the set of dead markings and reads the place
//! bounds off the diagram; `witness.rs` finds a shortest path to a dead
//! marking. Nothing is enumerated one marking at a time, so nets with
//! billions of markings but regular structure stay cheap.
//!
//! Unbounded nets have no finite diagram: a place that would exceed
//! [`SymbolicOptions::max_tokens`] stops the exploration
//! ([`SymbolicStop::TokenLimit`]), as does a diagram that would exceed
//! [`SymbolicOptions::max_nodes`] nodes ([`SymbolicStop::NodeLimit`]);
//! the report then says `complete: false` and gives no counts.

use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::model::{Net, PlaceId, TransitionId};
use group::Layout;

mod count;
pub(crate) mod group;
mod order;
mod relation;
mod saturate;
mod store;
mod witness;

pub use order::VariableOrder;

use count::Count;
use relation::Relation;
use store::{Limit, NodeId, Res, Store, EMPTY, ONE};

/// Options of [`explore_symbolic`].
#[derive(Clone, Debug, Serialize)]
pub struct SymbolicOptions {
    /// Stop when the store holds this many nodes (memory stays bounded).
    pub max_nodes: usize,
    /// Stop when a place would hold more tokens than this (unbounded nets).
    pub max_tokens: u32,
    /// Which place goes to which level.
    pub order: VariableOrder,
    /// Look for a shortest firing sequence to a dead marking.
    pub witness: bool,
    /// Put mutually exclusive places (covered by a unit-weight P-semiflow
    /// with one token) on one level; false: one level per place.
    pub group: bool,
    /// Groups of places (one per component, e.g. a vehicle's final
    /// places): a dead marking that marks some place of every group is a
    /// proper end (*terminal*), not a deadlock. Empty (the default): every
    /// dead marking is a deadlock. Places outside the net are ignored.
    pub terminal: Vec<Vec<PlaceId>>,
}

/// Default [`SymbolicOptions::max_nodes`].
pub const DEFAULT_MAX_NODES: usize = 5_000_000;

/// Default [`SymbolicOptions::max_tokens`].
pub const DEFAULT_MAX_TOKENS: u32 = 65_535;

impl Default for SymbolicOptions {
    fn default() -> Self {
        SymbolicOptions {
            max_nodes: DEFAULT_MAX_NODES,
            max_tokens: DEFAULT_MAX_TOKENS,
            order: VariableOrder::default(),
            witness: true,
            group: true,
            terminal: Vec::new(),
        }
    }
}

/// Why a symbolic exploration stopped before the fixpoint.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum SymbolicStop {
    /// The diagrams needed more than [`SymbolicOptions::max_nodes`] nodes.
    NodeLimit {
        /// The limit.
        max_nodes: usize,
    },
    /// A place would hold more than [`SymbolicOptions::max_tokens`] tokens
    /// (the net is unbounded, or bounded above the limit).
    TokenLimit {
        /// The place's id.
        place: String,
        /// The limit.
        max_tokens: u32,
    },
}

/// A dead marking with a shortest firing sequence to it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SymbolicDead {
    /// Marked places (id, tokens).
    pub marking: Vec<(String, u32)>,
    /// Transitions fired from the initial marking.
    pub path: Vec<TransitionId>,
    /// Their ids.
    pub path_names: Vec<String>,
}

/// What a symbolic exploration found. Counts are exact integers (`None`
/// only beyond 2^128, then see the `_approx` fields); all of them are 0 when
/// the exploration is not `complete`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SymbolicReport {
    /// The fixpoint was reached.
    pub complete: bool,
    /// Why not, when it was not.
    pub stop: Option<SymbolicStop>,
    /// Reachable markings.
    pub states: Option<u128>,
    /// Reachable markings, as a float.
    pub states_approx: f64,
    /// (reachable marking, enabled transition) pairs.
    pub edges: Option<u128>,
    /// Some reachable marking enables no transition and is not terminal
    /// ([`SymbolicOptions::terminal`]).
    pub deadlock: bool,
    /// Reachable markings that enable no transition (terminal ones included).
    pub dead_markings: Option<u128>,
    /// The dead markings that are terminal (0 without [`SymbolicOptions::terminal`]).
    pub terminal_markings: Option<u128>,
    /// Every place holds at most one token in every reachable marking.
    pub one_safe: bool,
    /// The largest bound of a place.
    pub max_tokens: u32,
    /// The bound of every place, in net order.
    pub bounds: Vec<u32>,
    /// The most tokens in one reachable marking.
    pub max_tokens_per_marking: u64,
    /// A dead, not terminal, marking reached by a shortest path (with
    /// [`SymbolicOptions::witness`]).
    pub dead_example: Option<SymbolicDead>,
    /// The variable order used.
    pub order: VariableOrder,
    /// Levels of the diagram (places, less those merged into groups).
    pub levels: usize,
    /// Nodes of the diagram of the reachable markings.
    pub mdd_nodes: usize,
    /// Nodes created in all (the peak of the store).
    pub nodes_created: usize,
}

/// Stack for the recursive diagram operations (depth grows with the number of places).
const STACK_BYTES: usize = 512 << 20;

/// Explores `net` under the plain P/T rule with decision diagrams.
pub fn explore_symbolic(net: &Net, opts: &SymbolicOptions) -> SymbolicReport {
    // The operations recurse once per level; a large stack keeps nets with
    // thousands of places safe. Fall back to this thread if none can be made.
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("mcl-symbolic".into())
            .stack_size(STACK_BYTES)
            .spawn_scoped(s, || run(net, opts))
            .ok()
            .and_then(|h| h.join().ok())
    })
    .unwrap_or_else(|| run(net, opts))
}

fn run(net: &Net, opts: &SymbolicOptions) -> SymbolicReport {
    let layout = order::order(net, opts.order, group::units(net, opts.group));
    let rel = Relation::new(net, &layout, opts.max_tokens);
    let mut store = Store::new(opts.max_nodes);
    let mut report = SymbolicReport {
        complete: false,
        stop: None,
        states: Some(0),
        states_approx: 0.0,
        edges: Some(0),
        deadlock: false,
        dead_markings: Some(0),
        terminal_markings: Some(0),
        one_safe: false,
        max_tokens: 0,
        bounds: Vec::new(),
        max_tokens_per_marking: 0,
        dead_example: None,
        order: opts.order,
        levels: layout.units.len(),
        mdd_nodes: 0,
        nodes_created: 0,
    };
    match fill(net, opts, &rel, &mut store, &layout, &mut report) {
        Ok(()) => report.complete = true,
        Err(limit) => {
            let stop = match limit {
                Limit::Nodes => SymbolicStop::NodeLimit { max_nodes: opts.max_nodes },
                Limit::Tokens(level) => SymbolicStop::TokenLimit {
                    place: net.places()[layout.unit(level).places()[0].index()].id.to_string(),
                    max_tokens: opts.max_tokens,
                },
            };
            let nodes = store.len();
            report = SymbolicReport { stop: Some(stop), nodes_created: nodes, ..report };
            report.dead_example = None;
        }
    }
    report.nodes_created = store.len();
    report
}

/// The initial marking as a diagram.
fn initial(net: &Net, store: &mut Store, layout: &Layout) -> Res<NodeId> {
    let m0 = net.initial_marking();
    let m: Vec<u32> = net.place_ids().map(|p| m0.get(p)).collect();
    // A group is a semiflow's places with one initial token in all.
    let tuple = layout.encode(&m).expect("a group holds at most one initial token");
    let mut n = ONE;
    for (i, &v) in tuple.iter().rev().enumerate() {
        n = store.make(i as u32 + 1, &[(v, n)])?;
    }
    Ok(n)
}

fn fill(
    net: &Net,
    opts: &SymbolicOptions,
    rel: &Relation,
    store: &mut Store,
    layout: &Layout,
    report: &mut SymbolicReport,
) -> Res<()> {
    let init = initial(net, store, layout)?;
    let reach = saturate::Saturation::new(store, rel).saturate(init)?;
    let mut counts: FxHashMap<NodeId, Count> = FxHashMap::default();
    let states = count::count(store, reach, &mut counts);
    // Edges, and the dead markings: those left after removing, for every
    // transition, the markings that enable it.
    let mut edges = Count { exact: Some(0), approx: 0.0 };
    let mut dead = reach;
    for t in net.transition_ids() {
        let need = relation::guards(net, layout, t);
        let e = count::count_enabled(store, reach, &need, &mut counts, &mut FxHashMap::default());
        edges = Count {
            exact: edges.exact.zip(e.exact).and_then(|(a, b)| a.checked_add(b)),
            approx: edges.approx + e.approx,
        };
        dead = count::without_enabled(store, dead, &need, &mut FxHashMap::default())?;
    }
    let dead_count = count::count(store, dead, &mut counts);
    // The dead markings where some group has no marked place.
    let stuck = if opts.terminal.is_empty() {
        dead
    } else {
        let mut stuck = EMPTY;
        for group in &opts.terminal {
            let mut zero: Vec<(u32, Vec<u32>)> = Vec::new();
            for p in group.iter().filter(|p| p.index() < layout.level_of.len()) {
                let (level, slot) = (layout.level_of[p.index()], layout.slot_of[p.index()]);
                match zero.iter_mut().find(|(l, _)| *l == level) {
                    Some((_, slots)) => slots.push(slot),
                    None => zero.push((level, vec![slot])),
                }
            }
            zero.sort_unstable_by_key(|&(l, _)| std::cmp::Reverse(l));
            let z = count::only_zero(store, layout, dead, &zero, &mut FxHashMap::default())?;
            stuck = store.union(stuck, z)?;
        }
        stuck
    };
    let terminal = store.diff(dead, stuck)?;
    let terminal_count = count::count(store, terminal, &mut counts);
    let (bounds, max_sum) = count::bounds(store, layout, reach);
    let max_tokens = bounds.iter().copied().max().unwrap_or(0);
    let mut reachable_nodes = FxHashMap::default();
    mark(store, reach, &mut reachable_nodes);
    *report = SymbolicReport {
        states: states.exact,
        states_approx: states.approx,
        edges: edges.exact,
        deadlock: stuck != EMPTY,
        dead_markings: dead_count.exact,
        terminal_markings: terminal_count.exact,
        one_safe: max_tokens <= 1,
        max_tokens,
        bounds,
        max_tokens_per_marking: max_sum,
        mdd_nodes: reachable_nodes.len(),
        ..report.clone()
    };
    if opts.witness && stuck != EMPTY {
        if let Some((m, path)) = witness::shortest_path(net, store, rel, layout, init, stuck)? {
            report.dead_example = Some(SymbolicDead {
                marking: net
                    .place_ids()
                    .filter_map(|p| {
                        let k = m[p.index()];
                        (k > 0).then(|| (net.places()[p.index()].id.to_string(), k))
                    })
                    .collect(),
                path_names: path.iter().map(|&t| net.transitions()[t.index()].id.to_string()).collect(),
                path,
            });
        }
    }
    Ok(())
}

/// Marks the nodes reachable from `n` (terminals excluded).
fn mark(store: &Store, n: NodeId, seen: &mut FxHashMap<NodeId, ()>) {
    if store.level(n) == 0 || seen.insert(n, ()).is_some() {
        return;
    }
    for &(_, c) in store.children(n) {
        mark(store, c, seen);
    }
}
