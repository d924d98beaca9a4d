//! The next-state relation, one event per transition: what a transition
//! does at each level it touches, the levels it spans (`top`, `bot`), and
//! the one-step image of a set; and the enabling guards of the transitions.
//!
//! Under the plain P/T rule a transition's effect is local: at a one-place
//! level it touches, value `i` goes to `i - pre + post` when `i >= pre`; at
//! a group level (`group.rs`) a table says which place is marked after
//! firing; every other level is left unchanged. That locality is what
//! saturation exploits.

use rustc_hash::FxHashMap;

use super::group::{Layout, Unit};
use super::store::{Limit, NodeId, Res, Store, EMPTY};
use crate::model::{Net, TransitionId};

/// What an event does at one level.
#[derive(Clone, Debug)]
pub(super) enum Local {
    /// A one-place level: `i` becomes `i - pre + post` when `i >= pre`.
    Add { pre: u32, post: u32 },
    /// A group level: `to[i]` is the value after firing from `i` (`None`:
    /// not enabled by `i`).
    Map(Vec<Option<u32>>),
}

impl Local {
    /// The value that `i` becomes at `level` (`None`: the transition is
    /// not enabled by `i`); `Err` beyond `max_tokens`.
    pub fn next(&self, level: u32, i: u32, max_tokens: u32) -> Res<Option<u32>> {
        match self {
            Local::Add { pre, post } => {
                if i < *pre {
                    return Ok(None);
                }
                let j = u64::from(i - pre) + u64::from(*post);
                if j > u64::from(max_tokens) {
                    return Err(Limit::Tokens(level));
                }
                Ok(Some(j as u32))
            }
            Local::Map(to) => Ok(to.get(i as usize).copied().flatten()),
        }
    }
}

/// One transition as a local relation on the levels it touches.
#[derive(Clone, Debug)]
pub(super) struct Event {
    /// Highest level touched.
    pub top: u32,
    /// Lowest level touched.
    pub bot: u32,
    /// `(level, effect)` for every touched level, highest level first.
    pub local: Vec<(u32, Local)>,
}

impl Event {
    /// The effect at `level`, when the event touches it.
    pub fn at(&self, level: u32) -> Option<&Local> {
        self.local.iter().find(|(l, _)| *l == level).map(|(_, e)| e)
    }
}

/// What a transition needs at one level to be enabled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Guard {
    /// A one-place level holding at least this many tokens.
    AtLeast(u32),
    /// A group level with this value (its input place marked).
    Is(u32),
    /// Never (two input places of one group, or a weight above 1 there).
    Never,
}

impl Guard {
    /// Whether value `v` satisfies the guard.
    pub fn holds(self, v: u32) -> bool {
        match self {
            Guard::AtLeast(w) => v >= w,
            Guard::Is(x) => v == x,
            Guard::Never => false,
        }
    }
}

/// `(level, slot, pre, post)` of every place `t` touches, highest level first.
fn touched(net: &Net, layout: &Layout, t: TransitionId) -> Vec<(u32, u32, u32, u32)> {
    let mut arcs: Vec<(u32, u32, u32, u32)> = Vec::new();
    let mut add = |p: crate::model::PlaceId, pre: u32, post: u32| {
        let (l, s) = (layout.level_of[p.index()], layout.slot_of[p.index()]);
        match arcs.iter_mut().find(|e| e.0 == l && e.1 == s) {
            Some(e) => {
                e.2 += pre;
                e.3 += post;
            }
            None => arcs.push((l, s, pre, post)),
        }
    };
    for &(p, w) in net.pre(t) {
        add(p, w, 0);
    }
    for &(p, w) in net.post(t) {
        add(p, 0, w);
    }
    arcs.sort_by_key(|e| (std::cmp::Reverse(e.0), e.1));
    arcs
}

/// The enabling guards of `t`, highest level first (empty: always enabled).
pub(super) fn guards(net: &Net, layout: &Layout, t: TransitionId) -> Vec<(u32, Guard)> {
    let arcs = touched(net, layout, t);
    let mut out: Vec<(u32, Guard)> = Vec::new();
    for level in levels_of(&arcs) {
        let here: Vec<_> = arcs.iter().filter(|e| e.0 == level && e.2 > 0).collect();
        let g = match (layout.unit(level), here.as_slice()) {
            (_, []) => continue,
            (Unit::Place(_), [e]) => Guard::AtLeast(e.2),
            (Unit::Group(_), [e]) if e.2 == 1 => Guard::Is(e.1 + 1),
            _ => Guard::Never,
        };
        out.push((level, g));
    }
    out
}

/// The distinct levels of `arcs` (sorted highest first), in order.
fn levels_of(arcs: &[(u32, u32, u32, u32)]) -> Vec<u32> {
    let mut l: Vec<u32> = arcs.iter().map(|e| e.0).collect();
    l.dedup();
    l
}

/// The table of a group level of `size` places for the arcs `here`.
fn group_map(size: usize, here: &[&(u32, u32, u32, u32)]) -> Vec<Option<u32>> {
    (0..=size as u32)
        .map(|v| {
            let mut m = vec![0u32; size];
            if v > 0 {
                m[v as usize - 1] = 1;
            }
            for e in here {
                let x = &mut m[e.1 as usize];
                *x = x.checked_sub(e.2)? + e.3;
            }
            // The group keeps at most one token in reachable markings.
            match m.iter().sum::<u32>() {
                0 => Some(0),
                1 => m.iter().position(|&x| x == 1).map(|i| i as u32 + 1),
                _ => None,
            }
        })
        .collect()
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
    /// The events of `net` on the levels of `layout`.
    pub fn new(net: &Net, layout: &Layout, max_tokens: u32) -> Relation {
        let mut events = Vec::new();
        let mut by_top = vec![Vec::new(); layout.levels() as usize + 1];
        for t in net.transition_ids() {
            let arcs = touched(net, layout, t);
            let local: Vec<(u32, Local)> = levels_of(&arcs)
                .into_iter()
                .map(|level| {
                    let here: Vec<_> = arcs.iter().filter(|e| e.0 == level).collect();
                    let effect = match layout.unit(level) {
                        Unit::Place(_) => Local::Add { pre: here[0].2, post: here[0].3 },
                        Unit::Group(g) => Local::Map(group_map(g.len(), &here)),
                    };
                    (level, effect)
                })
                .collect();
            if local.is_empty() {
                continue;
            }
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
                Some(effect) => match effect.next(level, i, self.max_tokens)? {
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
