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
//!
//! A [`LinearKey`] is shorter still on nets of one-token groups (the
//! mutually exclusive places of a unit-weight P-semiflow holding one token,
//! `symbolic/group.rs`): at most one place of a group is marked, with one
//! token, so `Σ_{p∈g} (i_p + 1)·m(p)` (`i_p` the place's index in the group)
//! says which, in `⌈log2(|g| + 1)⌉` bits. Such a sum for every group, shifted
//! to its own bit range, plus the field of every other place, is a linear
//! function of the marking that tells all reachable markings apart; when it
//! fits in 64 bits, a successor's key is its parent's plus a constant of the
//! transition. SharedMemory-PT-000010: a group of 91 places (the bus and the
//! accesses, 7 bits) and ten of 3 (2 bits each); the ten other places have
//! dependent rows: 27 bits.

use super::engine::Layout;
use crate::model::{Net, PlaceId};

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
    let c = crate::structural::incidence(net);
    let rows = (0..np).map(|p| c.row(PlaceId(p as u32)).iter().map(|&d| i128::from(d)).collect::<Vec<_>>());
    // Fraction-free elimination: `basis` holds reduced rows with distinct
    // pivot columns; a row reduced to zero depends on the kept ones.
    let mut basis: Vec<(usize, Vec<i128>)> = Vec::new();
    let mut keep = vec![false; np];
    for (p, mut r) in rows.enumerate() {
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

/// One-word keys that are a linear function of the marking (see the module
/// notes): `key(m) = Σ_p w_p·m(p) mod 2^64`.
#[derive(Clone, Debug)]
pub(super) struct LinearKey {
    /// The key of the initial marking.
    pub initial: u64,
    /// `Σ_p w_p·Δ_t(p) mod 2^64` of each transition `t`: what firing it adds
    /// to the key.
    pub delta: Vec<u64>,
    /// The bits the keys use (more than 64: some are cut).
    pub bits: u32,
}

impl LinearKey {
    /// The key of `net` with fields of `layout.bits` bits for the places
    /// outside `groups` (which must be sets of places of which every
    /// reachable marking marks at most one, with one token). With `keep`
    /// (from [`independent_places`]) only the kept places count: a group
    /// without one is left out. The keys tell reachable markings apart when
    /// [`LinearKey::bits`] is at most 64.
    pub fn new(net: &Net, layout: &Layout, keep: Option<&[bool]>, groups: &[Vec<PlaceId>]) -> Self {
        let np = net.place_count();
        let kept = |p: usize| keep.is_none_or(|k| k.get(p).copied().unwrap_or(true));
        let mut weight = vec![0u64; np];
        let mut grouped = vec![false; np];
        let mut shift = 0u32;
        for g in groups {
            for p in g {
                if let Some(x) = grouped.get_mut(p.index()) {
                    *x = true;
                }
            }
            if !g.iter().any(|p| kept(p.index())) {
                continue;
            }
            // Values 0 (none marked) ..= |g|.
            let width = u64::BITS - (g.len() as u64).leading_zeros();
            for (i, p) in g.iter().enumerate() {
                if let Some(w) = weight.get_mut(p.index()) {
                    *w = (i as u64 + 1).checked_shl(shift).unwrap_or(0);
                }
            }
            shift += width;
        }
        for p in (0..np).filter(|&p| !grouped[p] && kept(p)) {
            weight[p] = 1u64.checked_shl(shift).unwrap_or(0);
            shift += layout.bits;
        }
        let delta = net
            .transition_ids()
            .map(|t| {
                net.delta(t).iter().fold(0u64, |k, &(p, d)| k.wrapping_add((d as u64).wrapping_mul(weight[p.index()])))
            })
            .collect();
        let initial = net
            .places()
            .iter()
            .zip(&weight)
            .fold(0u64, |k, (p, &w)| k.wrapping_add(u64::from(p.initial).wrapping_mul(w)));
        LinearKey { initial, delta, bits: shift }
    }
}

/// The one-token groups of `net` (`symbolic/group.rs`).
pub(super) fn one_token_groups(net: &Net) -> Vec<Vec<PlaceId>> {
    super::symbolic::group::units(net, true)
        .into_iter()
        .filter_map(|u| match u {
            super::symbolic::group::Unit::Group(g) => Some(g),
            super::symbolic::group::Unit::Place(_) => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::{independent_places, one_token_groups, KeyFold, LinearKey};
    use crate::explore::engine::Layout;
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

    /// The three one-token cycles are groups (3 bits each), the cycle of 4
    /// tokens keeps its 4-bit fields; the keys, followed along the paths of
    /// the search, tell all reachable markings apart, with and without the
    /// places of dependent rows.
    #[test]
    fn linear_keys_tell_all_reachable_markings_apart() {
        let net = cycles();
        let ss = explore(&net, &Options { threads: 1, ..Options::default() });
        let groups = one_token_groups(&net);
        assert_eq!(groups.len(), 3);
        let keep = independent_places(&net);
        for (keep, bits) in [(None, 3 * 3 + 5 * 4), (keep.as_deref(), 3 * 3 + 4 * 4)] {
            let lin = LinearKey::new(&net, &ss.layout, keep, &groups);
            assert_eq!(lin.bits, bits);
            let keys: HashSet<u64> = ss
                .states()
                .map(|s| ss.path_to(s).iter().fold(lin.initial, |k, t| k.wrapping_add(lin.delta[t.index()])))
                .collect();
            assert_eq!(keys.len(), ss.len());
        }
    }

    /// SharedMemory-PT-000010: three words of 1-bit fields, two folded,
    /// 27 bits as a linear key (a group of 91 places, ten of 3; the ten
    /// other places have dependent rows).
    #[test]
    fn shared_memory_keys_are_one_word() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/mcc/SharedMemory-PT-000010.pnml");
        let net = crate::read_pnml(&std::fs::read_to_string(path).unwrap()).unwrap();
        let layout = Layout::new(net.place_count(), 1);
        let keep = independent_places(&net);
        assert_eq!((layout.words, KeyFold::new(&layout, keep.as_deref()).words), (3, 2));
        let lin = LinearKey::new(&net, &layout, keep.as_deref(), &one_token_groups(&net));
        assert_eq!(lin.bits, 7 + 10 * 2);
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
