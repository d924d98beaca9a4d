//! The reachability fixpoint by saturation (Ciardo, Marmorstein,
//! Siminiceanu): events are grouped by their top level; a node at level `k`
//! is *saturated* when its children are saturated and firing any event of
//! top level `k` (followed by any sequence of events below) adds nothing.
//! Nodes are saturated bottom-up, so the fixpoint at a level runs on
//! already closed sub-diagrams instead of on whole breadth-first frontiers.

use rustc_hash::{FxHashMap, FxHashSet};

use super::relation::{get, insert_union, Relation};
use super::store::{NodeId, Res, Store, EMPTY};

/// Saturation with its two operation caches.
pub(super) struct Saturation<'a> {
    pub store: &'a mut Store,
    rel: &'a Relation,
    /// Node → its saturated form (saturated nodes map to themselves).
    sat: FxHashMap<NodeId, NodeId>,
    /// (saturated node, event) → saturated result of firing it below the top.
    relprod: FxHashMap<(NodeId, u32), NodeId>,
}

impl<'a> Saturation<'a> {
    /// A saturation over `store` with the events of `rel`.
    pub fn new(store: &'a mut Store, rel: &'a Relation) -> Self {
        Saturation { store, rel, sat: FxHashMap::default(), relprod: FxHashMap::default() }
    }

    /// The least set that contains `n` and is closed under every event.
    pub fn saturate(&mut self, n: NodeId) -> Res<NodeId> {
        let k = self.store.level(n);
        if k == 0 {
            return Ok(n);
        }
        if let Some(&r) = self.sat.get(&n) {
            return Ok(r);
        }
        let mut r: Vec<(u32, NodeId)> = Vec::with_capacity(self.store.children(n).len());
        for (v, c) in self.store.children(n).to_vec() {
            r.push((v, self.saturate(c)?));
        }
        let s = self.fixpoint(k, r)?;
        self.sat.insert(n, s);
        self.sat.insert(s, s);
        Ok(s)
    }

    /// Closes the node `r` at level `k`, whose children are saturated,
    /// under the events of top level `k`. The children stay saturated: a
    /// union of sets closed under the events below is closed under them.
    fn fixpoint(&mut self, k: u32, mut r: Vec<(u32, NodeId)>) -> Res<NodeId> {
        let rel = self.rel;
        let events = &rel.by_top[k as usize];
        if !events.is_empty() {
            let mut queue: Vec<u32> = r.iter().map(|&(v, _)| v).collect();
            let mut queued: FxHashSet<u32> = queue.iter().copied().collect();
            while let Some(i) = queue.pop() {
                queued.remove(&i);
                for &e in events {
                    let ev = &rel.events[e as usize];
                    let Some(j) = ev.local[0].1.next(k, i, rel.max_tokens)? else { continue };
                    let f = self.relprod(get(&r, i), e)?;
                    if insert_union(self.store, &mut r, j, f)? && queued.insert(j) {
                        queue.push(j);
                    }
                }
            }
        }
        self.store.make(k, &r)
    }

    /// Fires event `e` on the saturated node `q` (below the event's top
    /// level) and saturates the result.
    fn relprod(&mut self, q: NodeId, e: u32) -> Res<NodeId> {
        let rel = self.rel;
        let ev = &rel.events[e as usize];
        let k = self.store.level(q);
        if q == EMPTY || k < ev.bot {
            return Ok(q);
        }
        if let Some(&r) = self.relprod.get(&(q, e)) {
            return Ok(r);
        }
        let local = ev.at(k);
        let mut out: Vec<(u32, NodeId)> = Vec::new();
        for (i, c) in self.store.children(q).to_vec() {
            let j = match local {
                Some(effect) => match effect.next(k, i, rel.max_tokens)? {
                    Some(j) => j,
                    None => continue,
                },
                None => i,
            };
            let f = self.relprod(c, e)?;
            insert_union(self.store, &mut out, j, f)?;
        }
        let r = self.fixpoint(k, out)?;
        self.sat.insert(r, r);
        self.relprod.insert((q, e), r);
        Ok(r)
    }
}
