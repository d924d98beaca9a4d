//! Questions asked of a reachable set: how many markings (exactly, as a
//! memoised path count), how many of them enable a transition (the edges),
//! which of them enable none (the dead markings), and the largest value of
//! each level (the place bounds).

use rustc_hash::{FxHashMap, FxHashSet};

use super::group::Layout;
use super::relation::Guard;
use super::store::{NodeId, Res, Store, EMPTY, ONE};

/// A number of markings: exact while it fits in a `u128`, always as an
/// approximate `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Count {
    pub exact: Option<u128>,
    pub approx: f64,
}

impl Count {
    const ZERO: Count = Count { exact: Some(0), approx: 0.0 };

    fn add(self, o: Count) -> Count {
        Count { exact: self.exact.zip(o.exact).and_then(|(a, b)| a.checked_add(b)), approx: self.approx + o.approx }
    }
}

/// Number of tuples in `n`.
pub(super) fn count(store: &Store, n: NodeId, memo: &mut FxHashMap<NodeId, Count>) -> Count {
    match n {
        EMPTY => return Count::ZERO,
        ONE => return Count { exact: Some(1), approx: 1.0 },
        _ => {}
    }
    if let Some(&c) = memo.get(&n) {
        return c;
    }
    let mut sum = Count::ZERO;
    for &(_, c) in store.children(n) {
        sum = sum.add(count(store, c, memo));
    }
    memo.insert(n, sum);
    sum
}

/// Number of tuples in `n` whose value at each level of `need` (`(level,
/// guard)`, highest level first) satisfies the guard: the markings of `n`
/// that enable a transition with those guards.
pub(super) fn count_enabled(
    store: &Store,
    n: NodeId,
    need: &[(u32, Guard)],
    counts: &mut FxHashMap<NodeId, Count>,
    memo: &mut FxHashMap<NodeId, Count>,
) -> Count {
    let Some(&(lowest, _)) = need.last() else { return count(store, n, counts) };
    let level = store.level(n);
    if n == EMPTY || level < lowest {
        return count(store, n, counts);
    }
    if let Some(&c) = memo.get(&n) {
        return c;
    }
    let guard = need.iter().find(|&&(l, _)| l == level).map(|&(_, g)| g);
    let mut sum = Count::ZERO;
    for &(v, c) in store.children(n) {
        if guard.is_none_or(|g| g.holds(v)) {
            sum = sum.add(count_enabled(store, c, need, counts, memo));
        }
    }
    memo.insert(n, sum);
    sum
}

/// The tuples of `n` that do not satisfy `need` (see [`count_enabled`]):
/// the markings of `n` that do not enable the transition. A transition
/// without input arcs is enabled everywhere (`need` empty: the result is empty).
pub(super) fn without_enabled(
    store: &mut Store,
    n: NodeId,
    need: &[(u32, Guard)],
    memo: &mut FxHashMap<NodeId, NodeId>,
) -> Res<NodeId> {
    let Some(&(lowest, _)) = need.last() else { return Ok(EMPTY) };
    let level = store.level(n);
    if n == EMPTY || level < lowest {
        // Every input place above held enough tokens.
        return Ok(EMPTY);
    }
    if let Some(&r) = memo.get(&n) {
        return Ok(r);
    }
    let guard = need.iter().find(|&&(l, _)| l == level).map(|&(_, g)| g);
    let mut out = Vec::new();
    for (v, c) in store.children(n).to_vec() {
        let r = if guard.is_some_and(|g| !g.holds(v)) { c } else { without_enabled(store, c, need, memo)? };
        if r != EMPTY {
            out.push((v, r));
        }
    }
    let r = store.make(level, &out)?;
    memo.insert(n, r);
    Ok(r)
}

/// The tuples of `n` that put no token on the places `zero` (`(level,
/// slots)`, highest level first): the markings of `n` that leave those
/// places empty.
pub(super) fn only_zero(
    store: &mut Store,
    layout: &Layout,
    n: NodeId,
    zero: &[(u32, Vec<u32>)],
    memo: &mut FxHashMap<NodeId, NodeId>,
) -> Res<NodeId> {
    let Some(&(lowest, _)) = zero.last() else { return Ok(n) };
    let level = store.level(n);
    if n == EMPTY || level < lowest {
        return Ok(n);
    }
    if let Some(&r) = memo.get(&n) {
        return Ok(r);
    }
    let slots: &[u32] = zero.iter().find(|(l, _)| *l == level).map_or(&[], |(_, s)| s);
    let mut out = Vec::new();
    for (v, c) in store.children(n).to_vec() {
        if slots.iter().any(|&s| layout.tokens(level, v, s) > 0) {
            continue;
        }
        let r = only_zero(store, layout, c, zero, memo)?;
        if r != EMPTY {
            out.push((v, r));
        }
    }
    let r = store.make(level, &out)?;
    memo.insert(n, r);
    Ok(r)
}

/// The bound of every place (net order) over the tuples of `root`, and
/// the largest number of tokens in one tuple.
pub(super) fn bounds(store: &Store, layout: &Layout, root: NodeId) -> (Vec<u32>, u64) {
    let mut values: Vec<FxHashSet<u32>> = vec![FxHashSet::default(); layout.levels() as usize + 1];
    let mut max_sum: FxHashMap<NodeId, u64> = FxHashMap::default();
    fn walk(
        store: &Store,
        layout: &Layout,
        n: NodeId,
        values: &mut [FxHashSet<u32>],
        max_sum: &mut FxHashMap<NodeId, u64>,
    ) -> u64 {
        let level = store.level(n);
        if level == 0 {
            return 0;
        }
        if let Some(&s) = max_sum.get(&n) {
            return s;
        }
        let mut best = 0;
        for &(v, c) in store.children(n) {
            values[level as usize].insert(v);
            best = best.max(u64::from(layout.total(level, v)) + walk(store, layout, c, values, max_sum));
        }
        max_sum.insert(n, best);
        best
    }
    let total = if root == EMPTY { 0 } else { walk(store, layout, root, &mut values, &mut max_sum) };
    let bounds = (0..layout.level_of.len())
        .map(|p| {
            let (level, slot) = (layout.level_of[p], layout.slot_of[p]);
            values[level as usize].iter().map(|&v| layout.tokens(level, v, slot)).max().unwrap_or(0)
        })
        .collect();
    (bounds, total)
}
