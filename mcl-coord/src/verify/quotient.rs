//! Step 2: a vehicle graph reduced modulo divergence-preserving branching
//! bisimulation (signature refinement, Blom and Orzan), with the gated
//! transitions waiting, the end of the mission and vanishing markings (an
//! immediate step ready: the vehicle settles, `product.rs`) as state labels.
//! Deadlocks, the reachability of the missions' ends and every visible
//! behaviour are preserved.

use rustc_hash::FxHashMap;

use super::lts::{Edge, Lts, TAU};

/// A vehicle graph reduced modulo divergence-preserving branching bisimulation.
pub(super) struct Quotient {
    /// The class of each marking.
    pub(super) block: Vec<u32>,
    /// Number of classes.
    pub(super) n: usize,
    off: Vec<u32>,
    edges: Vec<(u32, u32)>,
    /// The waiting gated transitions of each class (their effects).
    pub(super) gates: Vec<Vec<u32>>,
    /// Classes in which the mission has ended.
    pub(super) fin: Vec<bool>,
    /// Classes whose every marking is vanishing ([`Lts::vanishing`]; a
    /// state label like the end and the gates when reduced for settling):
    /// the vehicle leaves them by an immediate step before its next input.
    pub(super) unstable: Vec<bool>,
}

impl Quotient {
    /// The (label, class) edges out of class `c`.
    pub(super) fn out(&self, c: u32) -> &[(u32, u32)] {
        &self.edges[self.off[c as usize] as usize..self.off[c as usize + 1] as usize]
    }
}

/// A signature: the current block, divergence, and the (label, block) pairs.
type SigKey<'a> = (u32, bool, &'a [(u32, u32)]);

/// Reduces `lts` modulo divergence-preserving branching bisimulation, by
/// signature refinement (Blom and Orzan): the end of the mission and the
/// waiting gated transitions label the states; inert steps (silent, within
/// a class) are collapsed through the strongly connected components of the
/// inert graph, and a class with an inert cycle is divergent (it keeps a
/// silent self-loop).
///
/// With `settling`, vanishing markings are a state label too, so that a
/// class is all vanishing or all tangible ([`Quotient::unstable`]); the
/// product applies settling only to such quotients (`product.rs`).
pub(super) fn reduce(lts: &Lts, settling: bool) -> Quotient {
    let n = lts.len();
    // Initial partition: end of mission, vanishing, waiting gated transitions.
    let mut keys: FxHashMap<(bool, bool, Vec<u32>), u32> = FxHashMap::default();
    let mut block: Vec<u32> = (0..n as u32)
        .map(|s| {
            let k = (lts.fin[s as usize], settling && lts.vanishing[s as usize], lts.gates(s).to_vec());
            let next = keys.len() as u32;
            *keys.entry(k).or_insert(next)
        })
        .collect();
    let mut count = keys.len();
    let mut div = vec![false; n];
    loop {
        let inert = |s: u32, e: &Edge, block: &[u32]| e.label == TAU && block[e.to as usize] == block[s as usize];
        let mut scc_of = vec![u32::MAX; n];
        let mut sigs: Vec<(Vec<(u32, u32)>, bool)> = Vec::new();
        {
            let block_ref = &block;
            let mut emit = |scc: &[u32]| {
                let id = sigs.len() as u32;
                for &s in scc {
                    scc_of[s as usize] = id;
                }
                let mut sig: Vec<(u32, u32)> = Vec::new();
                let mut d = scc.len() > 1;
                for &s in scc {
                    for e in lts.out(s) {
                        if inert(s, e, block_ref) {
                            let o = scc_of[e.to as usize];
                            if o == id {
                                d = true; // inert self-loop
                            } else {
                                let (os, od) = &sigs[o as usize];
                                sig.extend_from_slice(os);
                                d |= *od;
                            }
                        } else {
                            sig.push((e.label, block_ref[e.to as usize]));
                        }
                    }
                }
                sig.sort_unstable();
                sig.dedup();
                sigs.push((sig, d));
            };
            mcl_net::graph::tarjan(
                n,
                |s, out: &mut Vec<u32>| {
                    out.extend(lts.out(s).iter().filter(|e| inert(s, e, block_ref)).map(|e| e.to));
                },
                &mut emit,
            );
        }
        let mut ids: FxHashMap<SigKey<'_>, u32> = FxHashMap::default();
        let mut nb = vec![0u32; n];
        for s in 0..n {
            let (sig, d) = &sigs[scc_of[s] as usize];
            let next = ids.len() as u32;
            nb[s] = *ids.entry((block[s], *d, sig.as_slice())).or_insert(next);
            div[s] = *d;
        }
        let new_count = ids.len();
        drop(ids);
        block = nb;
        if new_count == count {
            break;
        }
        count = new_count;
    }
    let mut edges: Vec<Vec<(u32, u32)>> = vec![Vec::new(); count];
    let mut gates = vec![Vec::new(); count];
    let mut fin = vec![false; count];
    let mut unstable = vec![true; count];
    for s in 0..n as u32 {
        let b = block[s as usize];
        unstable[b as usize] &= lts.vanishing[s as usize];
        for e in lts.out(s) {
            let tb = block[e.to as usize];
            if !(e.label == TAU && tb == b) {
                edges[b as usize].push((e.label, tb));
            }
        }
        if div[s as usize] {
            edges[b as usize].push((TAU, b));
        }
        gates[b as usize] = lts.gates(s).to_vec();
        fin[b as usize] = lts.fin[s as usize];
    }
    let mut off = vec![0u32];
    let mut flat = Vec::new();
    for mut e in edges {
        e.sort_unstable();
        e.dedup();
        flat.extend(e);
        off.push(flat.len() as u32);
    }
    Quotient { block, n: count, off, edges: flat, gates, fin, unstable }
}

#[cfg(test)]
impl Quotient {
    /// A quotient given by its edges (label, class) per class, for tests:
    /// class 0 initial, no gates, no end.
    pub(super) fn from_edges(out: &[Vec<(u32, u32)>]) -> Quotient {
        let mut off = vec![0u32];
        let mut edges = Vec::new();
        for es in out {
            edges.extend_from_slice(es);
            off.push(edges.len() as u32);
        }
        let n = out.len();
        Quotient {
            block: vec![0],
            n,
            off,
            edges,
            gates: vec![Vec::new(); n],
            fin: vec![false; n],
            unstable: vec![false; n],
        }
    }
}
