//! The variable order: which unit (a place, or a group of places, see
//! `group.rs`) sits at which level of the diagram.
//!
//! Saturation is fast when every transition spans few levels. Two orders
//! are offered: the units in the order of the PNML file (modellers and
//! generators usually write related places together), and FORCE (Aloul,
//! Markov, Sakallah), which moves each unit towards the centre of gravity
//! of the transitions it is connected to and keeps the order of least total
//! span over a few rounds.

use serde::Serialize;

use super::group::{Layout, Unit};
use crate::model::Net;

/// How places are assigned to levels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VariableOrder {
    /// The order of the places in the net, the first place at the top.
    Pnml,
    /// The FORCE heuristic started from the PNML order.
    #[default]
    Force,
}

/// Rounds of FORCE.
const ROUNDS: usize = 32;

/// The layout of `units` (in PNML order) under the order `kind`.
pub(super) fn order(net: &Net, kind: VariableOrder, units: Vec<Unit>) -> Layout {
    let ranks: Vec<usize> = match kind {
        VariableOrder::Pnml => (0..units.len()).collect(),
        VariableOrder::Force => force(&hyperedges(net, &units), units.len()),
    };
    let mut slots: Vec<Option<Unit>> = units.into_iter().map(Some).collect();
    let ordered = ranks.iter().filter_map(|&u| slots[u].take()).collect();
    Layout::new(ordered, net.place_count())
}

/// The units each transition touches (transitions that touch two or more).
fn hyperedges(net: &Net, units: &[Unit]) -> Vec<Vec<usize>> {
    let mut unit_of = vec![0usize; net.place_count()];
    for (i, u) in units.iter().enumerate() {
        for p in u.places() {
            unit_of[p.index()] = i;
        }
    }
    net.transition_ids()
        .map(|t| {
            let mut e: Vec<usize> = net.pre(t).iter().chain(net.post(t)).map(|&(p, _)| unit_of[p.index()]).collect();
            e.sort_unstable();
            e.dedup();
            e
        })
        .filter(|e| e.len() > 1)
        .collect()
}

/// Sum over transitions of the distance between their extreme units.
fn span(edges: &[Vec<usize>], pos: &[usize]) -> u64 {
    edges
        .iter()
        .map(|e| {
            let (lo, hi) = e.iter().fold((usize::MAX, 0), |(lo, hi), &p| (lo.min(pos[p]), hi.max(pos[p])));
            (hi - lo) as u64
        })
        .sum()
}

/// FORCE from the identity order over `n` items: the items, top first.
fn force(edges: &[Vec<usize>], n: usize) -> Vec<usize> {
    // pos[u]: the rank of item u.
    let mut pos: Vec<usize> = (0..n).collect();
    let mut best = (span(edges, &pos), pos.clone());
    for _ in 0..ROUNDS {
        let mut sum = vec![0.0f64; n];
        let mut cnt = vec![0u32; n];
        for e in edges {
            let cog = e.iter().map(|&p| pos[p] as f64).sum::<f64>() / e.len() as f64;
            for &p in e {
                sum[p] += cog;
                cnt[p] += 1;
            }
        }
        let target: Vec<f64> =
            (0..n).map(|p| if cnt[p] == 0 { pos[p] as f64 } else { sum[p] / f64::from(cnt[p]) }).collect();
        let mut items: Vec<usize> = (0..n).collect();
        items.sort_by(|&a, &b| target[a].total_cmp(&target[b]).then(pos[a].cmp(&pos[b])));
        for (i, &p) in items.iter().enumerate() {
            pos[p] = i;
        }
        let s = span(edges, &pos);
        if s < best.0 {
            best = (s, pos.clone());
        }
    }
    let mut out: Vec<usize> = (0..n).collect();
    out.sort_by_key(|&u| best.1[u]);
    out
}
