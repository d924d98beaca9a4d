//! The next-state relation, one event per transition: what a transition
//! does at each level it touches (consumes `pre`, produces `post`), the
//! levels it spans (`top`, `bot`), and the one-step image of a set.
//!
//! Under the plain P/T rule a transition's effect is local: at a level it
//! touches, value `i` goes to `i - pre + post` when `i >= pre`; every other
//! level is left unchanged. That locality is what saturation exploits.

use rustc_hash::FxHashMap;

use super::store::{Limit, NodeId, Res, Store, EMPTY};
use crate::model::Net;

/// One transition as a local relation on the levels it touches.
#[derive(Clone, Debug)]
pub(super) struct Event {
    /// Highest level touched.
    pub top: u32,
    /// Lowest level touched.
    pub bot: u32,
    /// `(level, pre, post)` for every touched level, highest level first.
    pub local: Vec<(u32, u32, u32)>,
}

impl Event {
    /// `(pre, post)` at `level`, when the event touches it.
    pub fn at(&self, level: u32) -> Option<(u32, u32)> {
        self.local.iter().find(|&&(l, _, _)| l == level).map(|&(_, a, b)| (a, b))
    }

    /// The value that `i` becomes at touched level `level` (`None`: the
    /// transition is not enabled by `i`); `Err` beyond `max_tokens`.
    pub fn next(&self, level: u32, pre: u32, post: u32, i: u32, max_tokens: u32) -> Res<Option<u32>> {
        if i < pre {
            return Ok(None);
        }
        let j = u64::from(i - pre) + u64::from(post);
        if j > u64::from(max_tokens) {
            return Err(Limit::Tokens(level));
        }
        Ok(Some(j as u32))
    }
}

/// The events of a net, indexed by their top level.
pub(super) struct Relation {
    /// Every transition that touches some place.
    pub events: Vec<Event>,
    /// `by_top[k]`: the events whose top level is `k`.
    pub by_top: Vec<Vec<u32>>,
    /// Largest token count a place may reach before the exploration stops.
    pub max_tokens: u32,
}

impl Relation {
    /// The events of `net`, where `level_of[p]` is the level of place `p`
    /// (levels `1..=levels`).
    pub fn new(net: &Net, level_of: &[u32], levels: u32, max_tokens: u32) -> Relation {
        let mut events = Vec::new();
        let mut by_top = vec![Vec::new(); levels as usize + 1];
        for t in net.transition_ids() {
            let mut local: Vec<(u32, u32, u32)> = Vec::new();
            for &(p, w) in net.pre(t) {
                local.push((level_of[p.index()], w, 0));
            }
            for &(p, w) in net.post(t) {
                let l = level_of[p.index()];
                match local.iter_mut().find(|e| e.0 == l) {
                    Some(e) => e.2 += w,
                    None => local.push((l, 0, w)),
                }
            }
            if local.is_empty() {
                continue;
            }
            local.sort_by_key(|e| std::cmp::Reverse(e.0));
            let (top, bot) = (local[0].0, local[local.len() - 1].0);
            by_top[top as usize].push(events.len() as u32);
            events.push(Event { top, bot, local });
        }
        Relation { events, by_top, max_tokens }
    }

    /// The markings reached from `n` by firing event `e` once (no closure).
    pub fn image(
        &self,
        store: &mut Store,
        cache: &mut FxHashMap<(NodeId, u32), NodeId>,
        n: NodeId,
        e: u32,
    ) -> Res<NodeId> {
        let ev = &self.events[e as usize];
        let level = store.level(n);
        if n == EMPTY || level < ev.bot {
            return Ok(n);
        }
        if let Some(&r) = cache.get(&(n, e)) {
            return Ok(r);
        }
        let local = if level <= ev.top { ev.at(level) } else { None };
        let mut out: Vec<(u32, NodeId)> = Vec::new();
        for (i, c) in store.children(n).to_vec() {
            let j = match local {
                Some((pre, post)) => match ev.next(level, pre, post, i, self.max_tokens)? {
                    Some(j) => j,
                    None => continue,
                },
                None => i,
            };
            let f = self.image(store, cache, c, e)?;
            insert_union(store, &mut out, j, f)?;
        }
        let r = store.make(level, &out)?;
        cache.insert((n, e), r);
        Ok(r)
    }
}

/// The child under `value` in the sorted pairs `out` ([`EMPTY`] when absent).
pub(super) fn get(out: &[(u32, NodeId)], value: u32) -> NodeId {
    match out.binary_search_by_key(&value, |&(v, _)| v) {
        Ok(i) => out[i].1,
        Err(_) => EMPTY,
    }
}

/// `out[value] ∪= f`; returns whether `out` changed.
pub(super) fn insert_union(store: &mut Store, out: &mut Vec<(u32, NodeId)>, value: u32, f: NodeId) -> Res<bool> {
    if f == EMPTY {
        return Ok(false);
    }
    match out.binary_search_by_key(&value, |&(v, _)| v) {
        Ok(i) => {
            let u = store.union(out[i].1, f)?;
            let changed = u != out[i].1;
            out[i].1 = u;
            Ok(changed)
        }
        Err(i) => {
            out.insert(i, (value, f));
            Ok(true)
        }
    }
}
