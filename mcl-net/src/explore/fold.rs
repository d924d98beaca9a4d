//! Shorter hash-table keys for the sequential search, from the net's place
//! invariants.
//!
//! Every reachable marking is `m0 + C·x` (`C` the incidence matrix, `x` a
//! firing count vector). When the rows of `C` of a set `K` of places span
//! all its rows, the tokens on `K` therefore determine the whole marking: a
//! place outside `K` holds `m0(p) + Σ α_k (m(k) − m0(k))`. The table then
//! needs the fields of `K` only. A [`KeyFold`] keeps them in the first
//! `⌈|K| / fields per word⌉` words of the packed marking: the fields of the
//! other places there are cleared, and the fields of `K` in the later words
//! are moved into the cleared ones. The arena keeps the full marking.
//!
//! FMS-PT-00005 (22 places, 4-bit fields: two words) has 16 independent
//! rows, so its keys are one word; SharedMemory-PT-000010 (131 1-safe
//! places: three words) has 110, so two.

use super::engine::Layout;
use crate::model::Net;

/// Larger nets keep whole markings as keys: the elimination below costs
/// `places² · transitions`, and the fold is only used for markings of at
/// most four words.
const MAX_PLACES: usize = 256;
const MAX_WORK: usize = 1 << 24;
/// Markings of more words keep whole keys (fewer specialised searches).
pub(super) const MAX_WORDS: usize = 4;

/// A maximal set of places whose rows of the incidence matrix are linearly
/// independent (over the rationals), chosen greedily in place order:
/// `Some(keep)` with `keep[p]` true for the places of the set, `None` when
/// every place is needed or the net is too large to check.
pub(super) fn independent_places(net: &Net) -> Option<Vec<bool>> {
    let (np, nt) = (net.place_count(), net.transition_count());
    if np > MAX_PLACES || np.saturating_mul(np).saturating_mul(nt.max(1)) > MAX_WORK {
        return None;
    }
    let mut rows = vec![vec![0i128; nt]; np];
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            rows[p.index()][t.index()] += i128::from(d);
        }
    }
    // Fraction-free elimination: `basis` holds reduced rows with distinct
    // pivot columns; a row reduced to zero depends on the kept ones.
    let mut basis: Vec<(usize, Vec<i128>)> = Vec::new();
    let mut keep = vec![false; np];
    for (p, mut r) in rows.into_iter().enumerate() {
        for (piv, b) in &basis {
            let (a, f) = (b[*piv], r[*piv]);
            if f == 0 {
                continue;
            }
            for (x, &y) in r.iter_mut().zip(b) {
                *x = x.checked_mul(a)?.checked_sub(y.checked_mul(f)?)?;
            }
            let g = r.iter().fold(0i128, |g, &x| gcd(g, x));
            if g > 1 {
                r.iter_mut().for_each(|x| *x /= g);
            }
        }
        if let Some(piv) = r.iter().position(|&x| x != 0) {
            basis.push((piv, r));
            keep[p] = true;
        }
    }
    keep.contains(&false).then_some(keep)
}

fn gcd(a: i128, b: i128) -> i128 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// One run of adjacent fields moved from a later word into the key.
#[derive(Clone, Copy, Debug)]
pub(super) struct Move {
    src: u32,
    shr: u32,
    mask: u64,
    dst: u32,
    shl: u32,
}

/// How a packed marking of `layout.words` words becomes a key of
/// [`KeyFold::words`] words (see the module notes).
#[derive(Clone, Debug)]
pub(super) struct KeyFold {
    /// Words of a key.
    pub words: usize,
    /// The fields of the first `words` words that stay in the key.
    keep: Vec<u64>,
    moves: Vec<Move>,
}

impl KeyFold {
    /// The identity: keys are whole markings.
    pub fn whole(layout: &Layout) -> Self {
        KeyFold { words: layout.words, keep: vec![u64::MAX; layout.words], moves: Vec::new() }
    }

    /// The fold that keeps the places marked in `keep` (from
    /// [`independent_places`]), or the identity when it saves no word.
    pub fn new(layout: &Layout, keep: Option<&[bool]>) -> Self {
        let Some(keep) = keep.filter(|k| k.len() == layout.places && layout.words <= MAX_WORDS) else {
            return Self::whole(layout);
        };
        let per_word = layout.per_word();
        let words = keep.iter().filter(|&&k| k).count().div_ceil(per_word).max(1);
        if words >= layout.words {
            return Self::whole(layout);
        }
        let field = layout.mask();
        let mut masks = vec![0u64; words];
        // Fields of the first words that dropped places free, in order.
        let mut free = Vec::new();
        for (p, &k) in keep.iter().enumerate().take(words * per_word) {
            let (w, s) = layout.locate(p);
            if k {
                masks[w] |= field << s;
            } else {
                free.push((w as u32, s));
            }
        }
        let mut free = free.into_iter();
        let mut moves: Vec<Move> = Vec::new();
        for (p, _) in keep.iter().enumerate().skip(words * per_word).filter(|(_, &k)| k) {
            let (w, s) = layout.locate(p);
            // There are at least as many free fields as kept places beyond.
            let Some((dw, ds)) = free.next() else {
                return Self::whole(layout);
            };
            // Extend the previous run when both ends are adjacent to it.
            if let Some(m) = moves.last_mut() {
                let width = m.mask.count_ones();
                if m.src == w as u32 && m.dst == dw && m.shr + width == s && m.shl + width == ds {
                    m.mask |= field << width;
                    continue;
                }
            }
            moves.push(Move { src: w as u32, shr: s, mask: field, dst: dw, shl: ds });
        }
        KeyFold { words, keep: masks, moves }
    }

    /// The key of the packed marking `m`.
    #[inline(always)]
    pub fn apply<const W: usize, const K: usize>(&self, m: &[u64; W]) -> [u64; K] {
        let mut k = [0u64; K];
        if K >= W {
            k[..W].copy_from_slice(m);
            return k;
        }
        for ((x, &y), &mask) in k.iter_mut().zip(m).zip(&self.keep) {
            *x = y & mask;
        }
        for mv in &self.moves {
            let v = (m.get(mv.src as usize).copied().unwrap_or(0) >> mv.shr) & mv.mask;
            if let Some(x) = k.get_mut(mv.dst as usize) {
                *x |= v << mv.shl;
            }
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::{independent_places, KeyFold};
    use crate::explore::{explore, Options};
    use crate::model::{Net, NetBuilder, Place, Transition};

    /// A cycle of five places holding 4 tokens (4-bit fields) and three
    /// cycles of five places holding one: 20 places in two words, 16
    /// independent ones, 70 · 5³ reachable markings.
    fn cycles() -> Net {
        let mut b = NetBuilder::new("cycles");
        for (c, tokens) in [4u32, 1, 1, 1].into_iter().enumerate() {
            let p: Vec<_> = (0..5)
                .map(|i| b.add_place(Place::new(format!("p{c}_{i}")).with_tokens(if i == 0 { tokens } else { 0 })))
                .collect();
            for i in 0..5 {
                let t = b.add_transition(Transition::new(format!("t{c}_{i}")));
                b.add_input(p[i], t, 1).add_output(t, p[(i + 1) % 5], 1);
            }
        }
        b.build().unwrap()
    }

    #[test]
    fn one_place_per_cycle_is_dropped() {
        let keep = independent_places(&cycles()).unwrap();
        assert_eq!(keep.iter().filter(|&&k| !k).count(), 4);
        // Greedy in place order: the last place of each cycle depends on the others.
        assert!((0..4).all(|c| !keep[c * 5 + 4]));
    }

    #[test]
    fn folded_keys_are_one_word_and_tell_all_reachable_markings_apart() {
        let net = cycles();
        let ss = explore(&net, &Options { threads: 1, ..Options::default() });
        assert_eq!(ss.len(), 70 * 125);
        assert_eq!((ss.layout.bits, ss.layout.words), (4, 2));
        let keep = independent_places(&net);
        let fold = KeyFold::new(&ss.layout, keep.as_deref());
        assert_eq!(fold.words, 1);
        let keys: HashSet<[u64; 1]> = ss.arena.chunks_exact(2).map(|m| fold.apply::<2, 1>(&[m[0], m[1]])).collect();
        assert_eq!(keys.len(), ss.len());
    }

    #[test]
    fn nets_without_invariants_keep_whole_markings() {
        let mut b = NetBuilder::new("grow");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let t = b.add_transition(Transition::new("t"));
        b.add_input(p, t, 1).add_output(t, p, 2);
        assert_eq!(independent_places(&b.build().unwrap()), None);
    }
}
