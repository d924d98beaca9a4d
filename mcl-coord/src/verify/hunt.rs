//! Random walks through the product, for the groups whose product is too
//! large to explore first (docs/coordination.md, "Scaling").

use super::lts::Lts;
use super::product::{Product, ProductGraph};
use super::replay::{concretize, Replay};
use super::{Witness, WitnessKind};

/// Random walks through the product, looking for a dead state that replays
/// on the real net (a deadlock found this way is real; finding none proves
/// nothing). Seeded: the same input gives the same walks. With `guide`
/// (per vehicle, the classes from which it can still reach its class in a
/// candidate dead state of the state equation, `structural_proof.rs`), a
/// walk only takes moves that keep every vehicle on its way there, and
/// stops where none is left.
pub(super) fn hunt(
    p: &Product<'_>,
    init: Vec<u32>,
    ltss: &[&Lts],
    replay: &Replay<'_>,
    budget: usize,
    guide: Option<&[Vec<bool>]>,
) -> Option<Witness> {
    let mut rng: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move |n: usize| {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng % n as u64) as usize
    };
    let depth: usize = 64 + 8 * p.quots.iter().map(|q| q.n).sum::<usize>();
    let mut used = 0usize;
    let mut succ = Vec::new();
    let mut over = false;
    let mut tried = 0;
    while used < budget {
        let mut g = ProductGraph::rooted(&init);
        let mut cur = init.clone();
        crate::interrupt::poll();
        for step in 0..depth {
            used += 1;
            succ.clear();
            p.successors(&cur, 0..p.nv, &mut succ, &mut over);
            let dead = succ.is_empty();
            if let Some(on_way) = guide {
                succ.retain(|(x, v, ..)| on_way[*v][x[*v] as usize]);
                if succ.is_empty() && !dead {
                    break;
                }
            }
            if dead {
                let is_end = (0..p.nv).all(|v| p.quots[v].fin[cur[v] as usize]);
                if !is_end {
                    tried += 1;
                    if let Some(w) = concretize(&g, step as u32, ltss, p.quots, replay, WitnessKind::Dead) {
                        return Some(w);
                    }
                    if tried > 64 {
                        return None;
                    }
                }
                break;
            }
            let (x, v, label, _) = succ.swap_remove(next(succ.len()));
            g.states.extend_from_slice(&x);
            g.parent.push((step as u32, v as u32, label));
            cur = x;
        }
    }
    None
}
