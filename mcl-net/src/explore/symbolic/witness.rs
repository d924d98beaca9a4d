//! A shortest firing sequence to a dead marking: breadth-first layers by
//! one-step images (not saturation, which loses distances) until a layer
//! meets the dead set, then back from a dead marking of that layer through
//! the earlier layers, one predecessor at a time.

use rustc_hash::FxHashMap;

use super::group::Layout;
use super::relation::Relation;
use super::store::{NodeId, Res, Store, EMPTY};
use crate::model::{Net, TransitionId};

/// A shortest path from the marking `init` to a marking of `target`, as the
/// dead marking (tokens per place, net order) and the transitions fired;
/// `None` when `target` is not reachable from `init`.
pub(super) fn shortest_path(
    net: &Net,
    store: &mut Store,
    rel: &Relation,
    layout: &Layout,
    init: NodeId,
    target: NodeId,
) -> Res<Option<(Vec<u32>, Vec<TransitionId>)>> {
    let mut cache: FxHashMap<(NodeId, u32), NodeId> = FxHashMap::default();
    let mut layers = vec![init];
    let mut seen = init;
    let hit = loop {
        let frontier = *layers.last().unwrap_or(&EMPTY);
        let hit = store.intersect(frontier, target)?;
        if hit != EMPTY {
            break hit;
        }
        let mut next = EMPTY;
        for e in 0..rel.events.len() as u32 {
            let img = rel.image(store, &mut cache, frontier, e)?;
            next = store.union(next, img)?;
        }
        let new = store.diff(next, seen)?;
        if new == EMPTY {
            return Ok(None);
        }
        seen = store.union(seen, new)?;
        layers.push(new);
    };
    let dead = layout.decode(&store.pick(hit));
    let mut m = dead.clone();
    let mut path = Vec::with_capacity(layers.len() - 1);
    for layer in layers[..layers.len() - 1].iter().rev() {
        let step = net.transition_ids().find_map(|t| {
            let mut prev = m.clone();
            for &(p, w) in net.post(t) {
                let x = &mut prev[p.index()];
                *x = x.checked_sub(w)?;
            }
            for &(p, w) in net.pre(t) {
                let x = &mut prev[p.index()];
                *x = x.checked_add(w)?;
            }
            let tuple = layout.encode(&prev)?;
            store.contains(*layer, tuple).then_some((t, prev))
        });
        // Every marking of a layer has a predecessor in the one before.
        let Some((t, prev)) = step else { return Ok(None) };
        path.push(t);
        m = prev;
    }
    path.reverse();
    Ok(Some((dead, path)))
}
