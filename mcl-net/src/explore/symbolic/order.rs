//! The variable order: which place sits at which level of the diagram.
//!
//! Saturation is fast when every transition spans few levels. Two orders
//! are offered: the places in the order of the PNML file (modellers and
//! generators usually write related places together), and FORCE (Aloul,
//! Markov, Sakallah), which moves each place towards the centre of gravity
//! of the transitions it is connected to and keeps the order of least total
//! span over a few rounds.

use serde::Serialize;

use crate::model::{Net, PlaceId};

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

/// The places of `net`, top level first.
pub(super) fn order(net: &Net, kind: VariableOrder) -> Vec<PlaceId> {
    let pnml: Vec<PlaceId> = net.place_ids().collect();
    match kind {
        VariableOrder::Pnml => pnml,
        VariableOrder::Force => force(net, pnml),
    }
}

/// The places each transition touches.
fn hyperedges(net: &Net) -> Vec<Vec<usize>> {
    net.transition_ids()
        .map(|t| {
            let mut e: Vec<usize> = net.pre(t).iter().chain(net.post(t)).map(|&(p, _)| p.index()).collect();
            e.sort_unstable();
            e.dedup();
            e
        })
        .filter(|e| e.len() > 1)
        .collect()
}

/// Sum over transitions of the distance between their extreme places.
fn span(edges: &[Vec<usize>], pos: &[usize]) -> u64 {
    edges
        .iter()
        .map(|e| {
            let (lo, hi) = e.iter().fold((usize::MAX, 0), |(lo, hi), &p| (lo.min(pos[p]), hi.max(pos[p])));
            (hi - lo) as u64
        })
        .sum()
}

fn force(net: &Net, start: Vec<PlaceId>) -> Vec<PlaceId> {
    let np = start.len();
    let edges = hyperedges(net);
    // pos[p]: the rank of place p.
    let mut pos: Vec<usize> = vec![0; np];
    for (i, p) in start.iter().enumerate() {
        pos[p.index()] = i;
    }
    let mut best = (span(&edges, &pos), pos.clone());
    for _ in 0..ROUNDS {
        let mut sum = vec![0.0f64; np];
        let mut n = vec![0u32; np];
        for e in &edges {
            let cog = e.iter().map(|&p| pos[p] as f64).sum::<f64>() / e.len() as f64;
            for &p in e {
                sum[p] += cog;
                n[p] += 1;
            }
        }
        let target: Vec<f64> =
            (0..np).map(|p| if n[p] == 0 { pos[p] as f64 } else { sum[p] / f64::from(n[p]) }).collect();
        let mut places: Vec<usize> = (0..np).collect();
        places.sort_by(|&a, &b| target[a].total_cmp(&target[b]).then(pos[a].cmp(&pos[b])));
        for (i, &p) in places.iter().enumerate() {
            pos[p] = i;
        }
        let s = span(&edges, &pos);
        if s < best.0 {
            best = (s, pos.clone());
        }
    }
    let mut out = start;
    out.sort_by_key(|p| best.1[p.index()]);
    out
}
