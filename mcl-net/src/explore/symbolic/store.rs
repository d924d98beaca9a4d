//! The MDD node store: hash-consed nodes (a unique table), the set
//! operations on them (union, intersection, difference) with their
//! operation caches, and the node limit that keeps memory bounded.
//!
//! Diagrams are quasi-reduced: a node at level `k` has children at level
//! `k - 1` only, level 0 holds the two terminals [`EMPTY`] and [`ONE`]. A
//! node stores its non-empty children only, as `(value, child)` pairs
//! sorted by value, so a node never denotes the empty set.

use rustc_hash::{FxHashMap, FxHasher};
use std::hash::{Hash, Hasher};

/// Index of a node in the [`Store`].
pub(super) type NodeId = u32;

/// The empty set (terminal).
pub(super) const EMPTY: NodeId = 0;
/// The set holding the empty tuple (terminal).
pub(super) const ONE: NodeId = 1;

/// Why a symbolic exploration stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Limit {
    /// The store reached its node limit.
    Nodes,
    /// A place would hold more than the token limit (level given).
    Tokens(u32),
}

/// Result of an operation that may create nodes.
pub(super) type Res<T> = Result<T, Limit>;

const NO_NEXT: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Node {
    level: u32,
    /// `edges[start..start + len]`.
    start: u32,
    len: u32,
    /// Next node with the same hash in the unique table.
    next: u32,
}

/// Hash-consed nodes and the set operations.
pub(super) struct Store {
    nodes: Vec<Node>,
    edges: Vec<(u32, NodeId)>,
    unique: FxHashMap<u64, u32>,
    union_cache: FxHashMap<(NodeId, NodeId), NodeId>,
    inter_cache: FxHashMap<(NodeId, NodeId), NodeId>,
    diff_cache: FxHashMap<(NodeId, NodeId), NodeId>,
    max_nodes: usize,
}

fn hash_node(level: u32, edges: &[(u32, NodeId)]) -> u64 {
    let mut h = FxHasher::default();
    level.hash(&mut h);
    edges.hash(&mut h);
    h.finish()
}

impl Store {
    /// An empty store (the two terminals) that refuses to grow past `max_nodes`.
    pub(super) fn new(max_nodes: usize) -> Store {
        let term = |_| Node { level: 0, start: 0, len: 0, next: NO_NEXT };
        Store {
            nodes: (0..2).map(term).collect(),
            edges: Vec::new(),
            unique: FxHashMap::default(),
            union_cache: FxHashMap::default(),
            inter_cache: FxHashMap::default(),
            diff_cache: FxHashMap::default(),
            max_nodes: max_nodes.max(16),
        }
    }

    /// Nodes created so far (terminals included).
    pub(super) fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Level of node `n` (0 for the terminals).
    pub(super) fn level(&self, n: NodeId) -> u32 {
        self.nodes[n as usize].level
    }

    /// The `(value, child)` pairs of node `n`, sorted by value.
    pub(super) fn children(&self, n: NodeId) -> &[(u32, NodeId)] {
        let node = self.nodes[n as usize];
        &self.edges[node.start as usize..(node.start + node.len) as usize]
    }

    /// The child of `n` under `value` ([`EMPTY`] when absent).
    pub(super) fn child(&self, n: NodeId, value: u32) -> NodeId {
        let c = self.children(n);
        match c.binary_search_by_key(&value, |&(v, _)| v) {
            Ok(i) => c[i].1,
            Err(_) => EMPTY,
        }
    }

    /// The unique node at `level` with the non-empty children `edges`
    /// (sorted by value); [`EMPTY`] when `edges` is empty.
    pub(super) fn make(&mut self, level: u32, edges: &[(u32, NodeId)]) -> Res<NodeId> {
        debug_assert!(edges.windows(2).all(|w| w[0].0 < w[1].0));
        debug_assert!(edges.iter().all(|&(_, c)| c != EMPTY));
        if edges.is_empty() {
            return Ok(EMPTY);
        }
        let h = hash_node(level, edges);
        let head = self.unique.get(&h).copied().unwrap_or(NO_NEXT);
        let mut at = head;
        while at != NO_NEXT {
            let node = self.nodes[at as usize];
            if node.level == level && self.children(at) == edges {
                return Ok(at);
            }
            at = node.next;
        }
        if self.nodes.len() >= self.max_nodes {
            return Err(Limit::Nodes);
        }
        let id = self.nodes.len() as NodeId;
        let start = self.edges.len() as u32;
        self.edges.extend_from_slice(edges);
        self.nodes.push(Node { level, start, len: edges.len() as u32, next: head });
        self.unique.insert(h, id);
        Ok(id)
    }

    /// `a ∪ b` (both at the same level).
    pub(super) fn union(&mut self, a: NodeId, b: NodeId) -> Res<NodeId> {
        if a == EMPTY || a == b {
            return Ok(b);
        }
        if b == EMPTY {
            return Ok(a);
        }
        let key = (a.min(b), a.max(b));
        if let Some(&r) = self.union_cache.get(&key) {
            return Ok(r);
        }
        let level = self.level(a);
        let (ca, cb) = (self.children(a).to_vec(), self.children(b).to_vec());
        let mut out = Vec::with_capacity(ca.len().max(cb.len()));
        let (mut i, mut j) = (0, 0);
        while i < ca.len() || j < cb.len() {
            if j == cb.len() || (i < ca.len() && ca[i].0 < cb[j].0) {
                out.push(ca[i]);
                i += 1;
            } else if i == ca.len() || cb[j].0 < ca[i].0 {
                out.push(cb[j]);
                j += 1;
            } else {
                out.push((ca[i].0, self.union(ca[i].1, cb[j].1)?));
                i += 1;
                j += 1;
            }
        }
        let r = self.make(level, &out)?;
        self.union_cache.insert(key, r);
        Ok(r)
    }

    /// `a ∩ b` (both at the same level).
    pub(super) fn intersect(&mut self, a: NodeId, b: NodeId) -> Res<NodeId> {
        if a == EMPTY || b == EMPTY {
            return Ok(EMPTY);
        }
        if a == b {
            return Ok(a);
        }
        let key = (a.min(b), a.max(b));
        if let Some(&r) = self.inter_cache.get(&key) {
            return Ok(r);
        }
        let level = self.level(a);
        let (ca, cb) = (self.children(a).to_vec(), self.children(b).to_vec());
        let mut out = Vec::new();
        for (v, c) in ca {
            let d = match cb.binary_search_by_key(&v, |&(w, _)| w) {
                Ok(i) => cb[i].1,
                Err(_) => continue,
            };
            let r = self.intersect(c, d)?;
            if r != EMPTY {
                out.push((v, r));
            }
        }
        let r = self.make(level, &out)?;
        self.inter_cache.insert(key, r);
        Ok(r)
    }

    /// `a \ b` (both at the same level).
    pub(super) fn diff(&mut self, a: NodeId, b: NodeId) -> Res<NodeId> {
        if a == EMPTY || a == b {
            return Ok(EMPTY);
        }
        if b == EMPTY {
            return Ok(a);
        }
        if let Some(&r) = self.diff_cache.get(&(a, b)) {
            return Ok(r);
        }
        let level = self.level(a);
        let (ca, cb) = (self.children(a).to_vec(), self.children(b).to_vec());
        let mut out = Vec::new();
        for (v, c) in ca {
            let r = match cb.binary_search_by_key(&v, |&(w, _)| w) {
                Ok(i) => self.diff(c, cb[i].1)?,
                Err(_) => c,
            };
            if r != EMPTY {
                out.push((v, r));
            }
        }
        let r = self.make(level, &out)?;
        self.diff_cache.insert((a, b), r);
        Ok(r)
    }

    /// Whether the tuple `values` (top level first) is in the set `n`.
    pub(super) fn contains(&self, mut n: NodeId, values: impl IntoIterator<Item = u32>) -> bool {
        for v in values {
            if n == EMPTY {
                return false;
            }
            n = self.child(n, v);
        }
        n == ONE
    }

    /// Some tuple of the non-empty set `n` (top level first): the smallest
    /// value at every level.
    pub(super) fn pick(&self, mut n: NodeId) -> Vec<u32> {
        let mut out = Vec::new();
        while self.level(n) > 0 {
            let (v, c) = self.children(n)[0];
            out.push(v);
            n = c;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The set of one tuple (top level first), at levels `values.len()..=1`.
    fn single(s: &mut Store, values: &[u32]) -> NodeId {
        let mut n = ONE;
        for (i, &v) in values.iter().rev().enumerate() {
            n = s.make(i as u32 + 1, &[(v, n)]).unwrap();
        }
        n
    }

    #[test]
    fn set_operations_are_hash_consed() {
        let mut s = Store::new(1000);
        let a = single(&mut s, &[0, 1]);
        let b = single(&mut s, &[1, 1]);
        let c = single(&mut s, &[0, 1]);
        assert_eq!(a, c);
        let u = s.union(a, b).unwrap();
        assert!(s.contains(u, [0, 1]) && s.contains(u, [1, 1]) && !s.contains(u, [1, 0]));
        assert_eq!(s.intersect(u, a).unwrap(), a);
        assert_eq!(s.diff(u, a).unwrap(), b);
        assert_eq!(s.diff(a, u).unwrap(), EMPTY);
        assert_eq!(s.union(u, a).unwrap(), u);
        assert_eq!(s.pick(u), vec![0, 1]);
    }

    #[test]
    fn the_node_limit_stops_growth() {
        let mut s = Store::new(16);
        let mut r = Ok(ONE);
        for v in 0..100 {
            r = s.make(1, &[(v, ONE)]);
            if r.is_err() {
                break;
            }
        }
        assert_eq!(r, Err(Limit::Nodes));
    }
}
