//! The breadth-first exploration engine.
//!
//! * **Packed markings.** Every place gets a bit field of `b` bits, `b` in
//!   {1, 2, 4, 8, 16, 32} (a power of two so that no field straddles two
//!   64-bit words). Exploration starts with the smallest `b` that holds the
//!   initial marking and restarts with `2b` if a place overflows; 1-safe nets
//!   thus use one bit per place.
//! * **Flat arena.** States are appended to one `Vec<u64>` in discovery order,
//!   which is also the BFS queue; `parent`/`via` give shortest paths.
//! * **Incremental hash.** `h(m) = Σ m(p)·R(p) mod 2^64` with random odd
//!   `R(p)`, so a successor's hash is `h(m) + D(t)` with `D(t)` precomputed.
//! * **Inline table.** Open addressing, linear probing; a slot holds the
//!   packed marking and a word with 32 hash bits and the state index, so a
//!   lookup touches one or two adjacent cache lines.
//! * **Batches.** Successors of several states are generated first, the table
//!   slot each one hashes to prefetched as soon as its hash is known (the
//!   misses overlap with generating the next ones), and only then looked up
//!   in order. The table lies on transparent huge pages (`hw.rs`), so that
//!   random lookups do not miss the TLB.
//! * **Trigger places.** A transition is only tested when one designated input
//!   place is marked; unmarked parts of the net cost nothing.

use super::fold::{KeyFold, LinearKey};
use super::{Options, Semantics, StateId, StateSpace, StopReason};
use crate::model::{Net, TransitionId};
use crate::semantics::{self, MarkingClass};

pub(super) const NO_PARENT: u32 = u32::MAX;

/// Successors gathered before probing the table.
pub(super) const BATCH: usize = 512;

/// How markings are packed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    pub places: usize,
    pub bits: u32,
    pub words: usize,
    per_word: usize,
    mask: u64,
    /// log2 of `bits`.
    shift: u32,
    /// The highest bit of every field.
    high: u64,
}

impl Layout {
    /// `places` fields of `bits` bits.
    pub(super) fn new(places: usize, bits: u32) -> Self {
        let per_word = (64 / bits) as usize;
        let high = (0..per_word).fold(0u64, |h, f| h | 1u64 << (f as u32 * bits + bits - 1));
        let (words, mask, shift) = (places.div_ceil(per_word).max(1), (1u64 << bits) - 1, bits.trailing_zeros());
        Layout { places, bits, words, per_word, mask, shift, high }
    }

    /// Fields per word.
    pub(super) fn per_word(&self) -> usize {
        self.per_word
    }

    /// The largest value of a field.
    pub(super) fn mask(&self) -> u64 {
        self.mask
    }

    /// (word, shift) of place `p`'s field.
    #[inline]
    pub(super) fn locate(&self, p: usize) -> (usize, u32) {
        (p / self.per_word, (p % self.per_word) as u32 * self.bits)
    }

    /// Tokens of place `p` in a packed state.
    #[inline]
    pub fn get(&self, state: &[u64], p: usize) -> u32 {
        let (w, s) = self.locate(p);
        state.get(w).map_or(0, |x| ((x >> s) & self.mask) as u32)
    }

    fn pack(&self, m: &[u32]) -> Vec<u64> {
        let mut v = vec![0u64; self.words];
        for (p, &x) in m.iter().enumerate() {
            let (w, s) = self.locate(p);
            v[w] |= u64::from(x) << s;
        }
        v
    }
}

/// Ranges of one transition's entries in the lists of [`Compiled`].
#[derive(Clone, Copy, Debug, Default)]
struct TransInfo {
    pre: (u32, u32),
    grow: (u32, u32),
    wdelta: (u32, u32),
    /// Some input weight exceeds the field maximum: never enabled.
    never: bool,
}

#[inline]
fn range(r: (u32, u32)) -> std::ops::Range<usize> {
    r.0 as usize..r.1 as usize
}

/// A transition to test when its trigger place is marked.
#[derive(Clone, Copy, Debug)]
struct Trigger {
    t: u32,
    /// The word holding all input places, [`Trigger::SPREAD`] when they
    /// lie in several words (then tested by [`Compiled::enabled`]).
    word: u32,
    /// The input weights packed like a marking (with `word`).
    pre: u64,
}

impl Trigger {
    const SPREAD: u32 = u32::MAX;
}

/// Net data for one layout, arranged for the inner loop.
pub(super) struct Compiled {
    pub(super) layout: Layout,
    /// Where the lists of each transition are, in one record per transition.
    trans: Vec<TransInfo>,
    /// (word, input weights packed like a marking) of each word holding an
    /// input place: tested on all fields of the word at once ([`covers_packed`]).
    pre: Vec<(u32, u64)>,
    /// (word, shift, increase, place) of each place a transition adds to, to
    /// detect overflow and track bounds.
    grow: Vec<(u32, u32, u64, u32)>,
    /// (word, value added modulo 2^64): as no field leaves its range, one
    /// wrapping add per word updates all its fields.
    wdelta: Vec<(u32, u64)>,
    /// Transitions to test when place p is marked: `trig[trig_off[p]..]`.
    trig_off: Vec<u32>,
    trig: Vec<Trigger>,
    /// Transitions without input places (always enabled).
    sources: Vec<u32>,
    /// Hash change of each transition.
    pub(super) dhash: Vec<u64>,
    pub(super) initial_hash: u64,
    pub(super) initial: Vec<u64>,
    /// Hash-table keys of the sequential search ([`KeyFold`]).
    pub(super) fold: KeyFold,
    /// One-word linear keys for the sequential search, when they are shorter
    /// than the fold's ([`LinearKey`]; set by [`explore`]).
    pub(super) linear: Option<LinearKey>,
    /// Whether the MCL rule can remove enabled transitions.
    mcl_rule: bool,
    pub(super) semantics: Semantics,
}

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// MurmurHash3 finalizer: spreads the linear hash over all bits.
#[inline]
pub(super) fn mix(h: u64) -> u64 {
    let mut h = h;
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^ (h >> 33)
}

impl Compiled {
    /// Number of transitions.
    pub(super) fn transitions(&self) -> usize {
        self.trans.len()
    }

    /// `keep`: the places whose tokens determine the marking
    /// ([`super::fold::independent_places`]), for shorter keys.
    fn new(net: &Net, semantics: Semantics, bits: u32, keep: Option<&[bool]>) -> Self {
        let np = net.place_count();
        let layout = Layout::new(np, bits);
        let mut seed = 0x6D63_6C2D_6E65_7421u64;
        let coef: Vec<u64> = (0..np).map(|_| splitmix(&mut seed) | 1).collect();
        let loc = |p: usize| {
            let (w, s) = layout.locate(p);
            (w as u32, s)
        };
        let mut trans = Vec::with_capacity(net.transition_count());
        let mut pre: Vec<(u32, u64)> = Vec::new();
        let mut grow = Vec::new();
        let mut wdelta: Vec<(u32, u64)> = Vec::new();
        let mut dhash = Vec::new();
        let mut trig_rows: Vec<Vec<Trigger>> = vec![Vec::new(); np];
        let mut sources = Vec::new();
        for t in net.transition_ids() {
            let row = net.pre(t);
            let mut info = TransInfo {
                pre: (pre.len() as u32, 0),
                grow: (grow.len() as u32, 0),
                wdelta: (wdelta.len() as u32, 0),
                // A weight above the field maximum can never be met.
                never: row.iter().any(|&(_, w)| u64::from(w) > layout.mask),
            };
            let start = pre.len();
            for &(p, w) in row {
                let (wi, s) = loc(p.index());
                // A weight that does not fit is `never`; keep the field in range.
                let w = u64::from(w).min(layout.mask) << s;
                match pre[start..].iter_mut().find(|(x, _)| *x == wi) {
                    Some(e) => e.1 |= w,
                    None => pre.push((wi, w)),
                }
            }
            let mut dh = 0u64;
            let start = wdelta.len();
            for &(p, d) in net.delta(t) {
                let (wi, s) = loc(p.index());
                if d > 0 {
                    grow.push((wi, s, d as u64, p.0));
                }
                let add = (d as u64).wrapping_shl(s);
                match wdelta[start..].iter_mut().find(|(x, _)| *x == wi) {
                    Some(e) => e.1 = e.1.wrapping_add(add),
                    None => wdelta.push((wi, add)),
                }
                dh = dh.wrapping_add((d as u64).wrapping_mul(coef[p.index()]));
            }
            info.pre.1 = pre.len() as u32;
            info.grow.1 = grow.len() as u32;
            info.wdelta.1 = wdelta.len() as u32;
            trans.push(info);
            dhash.push(dh);
            // Trigger: the input place with the largest weight (least often sufficient).
            match row.iter().max_by_key(|&&(p, w)| (w, std::cmp::Reverse(p))) {
                // A transition that is never enabled needs no test.
                Some(_) if info.never => {}
                Some(&(p, _)) => trig_rows[p.index()].push(match &pre[range(info.pre)] {
                    &[(word, pre)] => Trigger { t: t.0, word, pre },
                    _ => Trigger { t: t.0, word: Trigger::SPREAD, pre: 0 },
                }),
                None => sources.push(t.0),
            }
        }
        let mut trig_off = vec![0u32];
        let mut trig = Vec::new();
        for r in trig_rows {
            trig.extend(r);
            trig_off.push(trig.len() as u32);
        }
        let initial_marking: Vec<u32> = net.places().iter().map(|p| p.initial).collect();
        let initial_hash =
            initial_marking.iter().zip(&coef).fold(0u64, |h, (&x, &c)| h.wrapping_add(u64::from(x).wrapping_mul(c)));
        Compiled {
            layout,
            trans,
            pre,
            grow,
            wdelta,
            trig_off,
            trig,
            sources,
            dhash,
            initial_hash,
            initial: layout.pack(&initial_marking),
            fold: KeyFold::new(&layout, keep),
            linear: None,
            // With only immediate, unprioritized transitions the MCL rule keeps
            // every enabled transition: skip it.
            mcl_rule: semantics == Semantics::Mcl
                && net.transitions().iter().any(|t| !t.kind.is_immediate() || t.priority.is_some()),
            semantics,
        }
    }
}

/// Place bounds and the largest token total, gathered while exploring.
///
/// Bounds only grow where a transition adds tokens, so they are raised in
/// [`Compiled::successor`]; totals are summed with SWAR arithmetic when a
/// state is expanded.
#[derive(Clone, Debug)]
pub(super) struct Stats {
    pub bounds: Vec<u32>,
    pub max_total: u64,
}

impl Stats {
    pub fn new(net: &Net) -> Self {
        Stats { bounds: net.places().iter().map(|p| p.initial).collect(), max_total: 0 }
    }

    /// Accounts for the token total of a packed state.
    #[inline]
    pub fn observe(&mut self, l: &Layout, state: &[u64]) {
        let total: u64 = state.iter().map(|&x| field_sum(x, l.bits)).sum();
        self.max_total = self.max_total.max(total);
    }

    pub fn merge(&mut self, other: &Stats) {
        for (a, &b) in self.bounds.iter_mut().zip(&other.bounds) {
            *a = (*a).max(b);
        }
        self.max_total = self.max_total.max(other.max_total);
    }
}

/// Sum of the `bits`-wide fields of `x`, by folding neighbouring fields into
/// fields twice as wide (no carry can cross a field).
#[inline]
fn field_sum(x: u64, bits: u32) -> u64 {
    const MASKS: [u64; 6] = [
        0x5555_5555_5555_5555,
        0x3333_3333_3333_3333,
        0x0F0F_0F0F_0F0F_0F0F,
        0x00FF_00FF_00FF_00FF,
        0x0000_FFFF_0000_FFFF,
        0x0000_0000_FFFF_FFFF,
    ];
    if bits == 1 {
        return u64::from(x.count_ones());
    }
    let mut v = x;
    let mut w = bits;
    for (i, &m) in MASKS.iter().enumerate() {
        if 1u32 << i == w {
            v = (v & m) + ((v >> w) & m);
            w *= 2;
        }
    }
    v
}

/// Optional work of a sequential run: recording the edges, and not expanding
/// markings above [`Options::cut_above`].
pub(super) struct Extras {
    record: bool,
    cut_above: Option<u32>,
    counts: Vec<u32>,
    succ: Vec<(TransitionId, StateId)>,
    pub cut: Vec<u32>,
}

impl Extras {
    pub fn new(opts: &Options) -> Self {
        Extras {
            record: opts.record_edges,
            cut_above: opts.cut_above,
            counts: Vec::new(),
            succ: Vec::new(),
            cut: Vec::new(),
        }
    }

    /// Whether state `s` must not be expanded (and is then listed as cut).
    #[inline]
    pub fn cut(&mut self, l: &Layout, s: usize, state: &[u64]) -> bool {
        match self.cut_above {
            Some(b) if (0..l.places).any(|p| l.get(state, p) > b) => {
                self.cut.push(s as u32);
                true
            }
            _ => false,
        }
    }

    #[inline]
    pub fn edge(&mut self, s: u32, t: u32, target: u32) {
        if self.record {
            if self.counts.len() <= s as usize {
                self.counts.resize(s as usize + 1, 0);
            }
            self.counts[s as usize] += 1;
            self.succ.push((TransitionId(t), StateId(target)));
        }
    }

    /// (successor offsets per state, successors); both empty when not recording.
    pub fn finish(mut self, states: usize) -> (Vec<u32>, Vec<(TransitionId, StateId)>, Vec<u32>) {
        if !self.record {
            return (Vec::new(), Vec::new(), self.cut);
        }
        self.counts.resize(states, 0);
        let mut off = Vec::with_capacity(states + 1);
        off.push(0u32);
        for &c in &self.counts {
            off.push(off.last().copied().unwrap_or(0) + c);
        }
        (off, self.succ, self.cut)
    }
}

/// A place would overflow its bit field.
pub(super) enum Overflow {
    /// Retry with wider fields.
    Widen,
    /// Fields are already 32 bits wide: stop exploring.
    Stop,
}

impl Compiled {
    /// Fills `ready` with the transitions that may fire in `cur` (all enabled
    /// ones, filtered by the MCL rule under [`Semantics::Mcl`]); returns
    /// whether the state is vanishing.
    #[inline]
    pub(super) fn ready_in(&self, net: &Net, cur: &[u64], ready: &mut Vec<TransitionId>) -> bool {
        let l = &self.layout;
        ready.clear();
        ready.extend(self.sources.iter().map(|&t| TransitionId(t)));
        for (wi, &word) in cur.iter().enumerate() {
            let mut x = word;
            while x != 0 {
                let start = x.trailing_zeros() & !(l.bits - 1);
                x &= !(l.mask << start);
                let p = wi * l.per_word + (start >> l.shift) as usize;
                let (a, b) = (self.trig_off[p] as usize, self.trig_off[p + 1] as usize);
                for tr in &self.trig[a..b] {
                    let on = match cur.get(tr.word as usize) {
                        Some(&m) => covers_packed(m, tr.pre, l.high),
                        None => self.enabled(cur, tr.t as usize),
                    };
                    if on {
                        ready.push(TransitionId(tr.t));
                    }
                }
            }
        }
        if self.mcl_rule {
            semantics::select_ready(net, ready) == MarkingClass::Vanishing
        } else {
            // Only immediate transitions: every live marking is vanishing.
            self.semantics == Semantics::Mcl && !ready.is_empty()
        }
    }

    /// [`Compiled::ready_in`] for markings of `W` words, with the loop
    /// bounds and field sizes known to the compiler.
    #[inline]
    pub(super) fn ready_fixed<const W: usize>(&self, net: &Net, cur: &[u64; W], ready: &mut Vec<TransitionId>) -> bool {
        match (self.mcl_rule, self.layout.bits) {
            (false, 1) => self.scan::<W, 1>(cur, ready),
            (false, 2) => self.scan::<W, 2>(cur, ready),
            (false, 4) => self.scan::<W, 4>(cur, ready),
            (false, 8) => self.scan::<W, 8>(cur, ready),
            _ => return self.ready_in(net, cur, ready),
        }
        self.semantics == Semantics::Mcl && !ready.is_empty()
    }

    /// The enabled transitions of `cur` (fields of `BITS` bits) into `ready`.
    #[inline(always)]
    fn scan<const W: usize, const BITS: u32>(&self, cur: &[u64; W], ready: &mut Vec<TransitionId>) {
        let field = (1u64 << BITS) - 1;
        let per_word = (64 / BITS) as usize;
        let high = self.layout.high;
        ready.clear();
        ready.extend(self.sources.iter().map(|&t| TransitionId(t)));
        let (off, trig) = (&self.trig_off[..], &self.trig[..]);
        for (wi, &word) in cur.iter().enumerate() {
            let mut x = word;
            while x != 0 {
                let start = x.trailing_zeros() & !(BITS - 1);
                x &= !(field << start);
                let p = wi * per_word + (start / BITS) as usize;
                let (Some(&a), Some(&b)) = (off.get(p), off.get(p + 1)) else {
                    continue;
                };
                for tr in trig.get(a as usize..b as usize).unwrap_or(&[]) {
                    let on = match cur.get(tr.word as usize) {
                        // 1-bit fields: covered when every input bit is set.
                        Some(&m) if BITS == 1 => m & tr.pre == tr.pre,
                        Some(&m) => covers_packed(m, tr.pre, high),
                        None => self.enabled(cur, tr.t as usize),
                    };
                    if on {
                        ready.push(TransitionId(tr.t));
                    }
                }
            }
        }
    }

    /// Turns `state` (a copy of the source state) into the successor by `t`.
    /// Raises `bounds` to the new token counts of the places `t` adds to.
    #[inline(always)]
    pub(super) fn successor(&self, state: &mut [u64], t: usize, bounds: &mut [u32]) -> Result<(), Overflow> {
        self.check(state, t, bounds)?;
        if let Some(info) = self.trans.get(t) {
            for &(dw, add) in &self.wdelta[range(info.wdelta)] {
                let word = &mut state[dw as usize];
                *word = word.wrapping_add(add);
            }
        }
        Ok(())
    }

    /// What [`Compiled::successor`] checks and records of the successor of
    /// `state` by `t`, without computing it.
    #[inline(always)]
    pub(super) fn check(&self, state: &[u64], t: usize, bounds: &mut [u32]) -> Result<(), Overflow> {
        let l = &self.layout;
        let Some(info) = self.trans.get(t) else {
            return Ok(());
        };
        for &(gw, sh, d, p) in &self.grow[range(info.grow)] {
            let v = ((state[gw as usize] >> sh) & l.mask) + d;
            if v > l.mask {
                return Err(if l.bits == 32 { Overflow::Stop } else { Overflow::Widen });
            }
            if let Some(b) = bounds.get_mut(p as usize) {
                *b = (*b).max(v as u32);
            }
        }
        Ok(())
    }

    /// Turns `state` into the successor by `t`, known not to overflow (an
    /// earlier [`Compiled::successor`] of the same state and transition).
    #[inline]
    pub(super) fn fire(&self, state: &mut [u64], t: usize) {
        if let Some(info) = self.trans.get(t) {
            for &(dw, add) in &self.wdelta[range(info.wdelta)] {
                if let Some(word) = state.get_mut(dw as usize) {
                    *word = word.wrapping_add(add);
                }
            }
        }
    }

    /// Whether transition `t` is enabled in the packed state `cur`.
    #[inline]
    fn enabled(&self, cur: &[u64], t: usize) -> bool {
        let Some(info) = self.trans.get(t) else {
            return false;
        };
        !info.never
            && self.pre[range(info.pre)]
                .iter()
                .all(|&(w, p)| cur.get(w as usize).is_some_and(|&m| covers_packed(m, p, self.layout.high)))
    }
}

/// `semantics::covers` on every field of a packed word at once: whether each
/// field of `m` holds at least the same field of `p`, where `high` has the
/// top bit of every field set. The fields below the top bits are subtracted
/// with the top bits of `m` forced to 1, so no field borrows from its
/// neighbour; a field of `m` is short exactly when its top bit is 0 where
/// `p`'s is 1, or both top bits are equal and the lower bits borrowed.
#[inline(always)]
fn covers_packed(m: u64, p: u64, high: u64) -> bool {
    let low = (m | high).wrapping_sub(p & !high);
    let short = (!m & p) | (!(m ^ p) & !low);
    short & high == 0
}

/// Open-addressing hash set of packed markings, stored inline.
///
/// Slot `i` is `slots[i * stride..(i + 1) * stride]`: the marking's `words`
/// words, then a meta word `(low 32 bits of the mixed hash) << 32 | (state
/// index + 1)`, 0 when empty. The slot position is the low bits of the mixed
/// hash, so growing needs nothing but the table (capacity ≤ 2^32).
pub(super) struct Table {
    slots: Vec<u64>,
    stride: usize,
    words: usize,
    mask: usize,
    pub(super) len: usize,
}

impl Table {
    pub(super) fn new(words: usize) -> Self {
        let cap = 1usize << 12;
        Table { slots: super::hw::huge_vec(cap * (words + 1), 0), stride: words + 1, words, mask: cap - 1, len: 0 }
    }

    pub(super) fn capacity(&self) -> usize {
        self.mask + 1
    }

    /// Doubles the capacity. Entries are placed by the hash bits kept in
    /// their meta word and visited in slot order, so that the writes go to
    /// two nearly sequential streams.
    pub(super) fn grow(&mut self) {
        let cap = self.capacity() * 2;
        let mask = cap - 1;
        let mut slots = super::hw::huge_vec(cap * self.stride, 0u64);
        for old in self.slots.chunks_exact(self.stride) {
            let meta = old[self.words];
            if meta == 0 {
                continue;
            }
            let mut pos = (meta >> 32) as usize & mask;
            while slots[pos * self.stride + self.words] != 0 {
                pos = (pos + 1) & mask;
            }
            slots[pos * self.stride..(pos + 1) * self.stride].copy_from_slice(old);
        }
        self.slots = slots;
        self.mask = mask;
    }

    /// Prefetches the first and the meta word of the home slot of `mixed`
    /// (a slot may straddle two cache lines).
    #[inline]
    pub(super) fn prefetch(&self, mixed: u64) {
        let base = (mixed as usize & self.mask) * self.stride;
        if let (Some(a), Some(b)) = (self.slots.get(base), self.slots.get(base + self.words)) {
            super::hw::prefetch(a);
            super::hw::prefetch(b);
        }
    }

    /// Finds `key`; returns `Ok(state index)` or `Err(free slot position)`.
    #[inline]
    pub(super) fn find(&self, key: &[u64], mixed: u64) -> Result<u32, usize> {
        let tag = mixed << 32;
        let mut pos = mixed as usize & self.mask;
        loop {
            let base = pos * self.stride;
            let meta = self.slots[base + self.words];
            if meta == 0 {
                return Err(pos);
            }
            if meta & 0xFFFF_FFFF_0000_0000 == tag && key.iter().enumerate().all(|(i, &k)| self.slots[base + i] == k) {
                return Ok(meta as u32 - 1);
            }
            pos = (pos + 1) & self.mask;
        }
    }

    #[inline]
    pub(super) fn insert_at(&mut self, pos: usize, key: &[u64], mixed: u64, idx: u32) {
        let slot = &mut self.slots[pos * self.stride..(pos + 1) * self.stride];
        slot[..self.words].copy_from_slice(key);
        slot[self.words] = (mixed << 32) | (u64::from(idx) + 1);
        self.len += 1;
    }
}

/// Smallest field width that holds `x` tokens.
fn bits_for(x: u32) -> u32 {
    [1, 2, 4, 8, 16, 32].into_iter().find(|&b| b == 32 || x < (1u32 << b)).unwrap_or(32)
}

pub(super) fn explore(net: &Net, opts: &Options) -> StateSpace {
    let max = opts.max_states.clamp(1, (u32::MAX - 1) as usize);
    let initial_max = net.places().iter().map(|p| p.initial).max().unwrap_or(0);
    let mut bits = bits_for(initial_max);
    // Recording edges and cutting markings are done by the sequential engines.
    let extras = opts.record_edges || opts.cut_above.is_some();
    let sequential = opts.threads == 1 || extras;
    // Only the sequential search without extras (`fixed::run_keyed`) uses
    // the folded and linear keys.
    let keep = if sequential && !extras { super::fold::independent_places(net) } else { None };
    // One-token groups, found when a linear key may help (once).
    let mut groups: Option<Vec<Vec<crate::model::PlaceId>>> = None;
    loop {
        let mut c = Compiled::new(net, opts.semantics, bits, keep.as_deref());
        if sequential && !extras && c.layout.words <= super::fold::MAX_WORDS && c.fold.words >= 2 {
            let groups = groups.get_or_insert_with(|| super::fold::one_token_groups(net));
            let lin = LinearKey::new(net, &c.layout, keep.as_deref(), groups);
            c.linear = (lin.bits <= u64::BITS).then_some(lin);
        }
        let result = if sequential {
            let x = Extras::new(opts);
            match (c.layout.words, extras) {
                (1..=8, false) => super::fixed::run_keyed(&c, net, max, x),
                (1, true) => super::fixed::run::<1, true>(&c, net, max, x),
                (2, true) => super::fixed::run::<2, true>(&c, net, max, x),
                (3, true) => super::fixed::run::<3, true>(&c, net, max, x),
                (4, true) => super::fixed::run::<4, true>(&c, net, max, x),
                (5, true) => super::fixed::run::<5, true>(&c, net, max, x),
                (6, true) => super::fixed::run::<6, true>(&c, net, max, x),
                (7, true) => super::fixed::run::<7, true>(&c, net, max, x),
                (8, true) => super::fixed::run::<8, true>(&c, net, max, x),
                _ => run(&c, net, max, x),
            }
        } else {
            let n = if opts.threads == 0 { default_threads() } else { opts.threads };
            if opts.exact_order {
                super::parallel::run(&c, net, max, n)
            } else {
                super::unordered::run(&c, net, max, n)
            }
        };
        match result {
            Some(ss) => return ss,
            // A place overflowed its field: restart with wider fields.
            None if bits < 32 => bits *= 2,
            // 32-bit fields report overflow as a stop, never as `None`; should
            // that change, answer with the initial marking rather than loop.
            None => {
                return StateSpace {
                    semantics: c.semantics,
                    layout: c.layout,
                    arena: c.initial.clone(),
                    parent: vec![NO_PARENT],
                    via: vec![0],
                    dead: Vec::new(),
                    vanishing: Vec::new(),
                    edges: 0,
                    stop: Some(StopReason::TokenOverflow),
                    bounds: net.places().iter().map(|p| p.initial).collect(),
                    max_total: net.places().iter().map(|p| u64::from(p.initial)).sum(),
                    succ_off: Vec::new(),
                    succ: Vec::new(),
                    cut: Vec::new(),
                }
            }
        }
    }
}

/// Worker threads when [`Options::threads`] is 0: the available cores, at most 8.
fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get().min(8))
}

/// Runs BFS; `None` means a place overflowed its bit field (retry wider).
pub(super) fn run(c: &Compiled, net: &Net, max_states: usize, mut extras: Extras) -> Option<StateSpace> {
    let l = c.layout;
    let w = l.words;
    let mut arena: Vec<u64> = c.initial.clone();
    let mut hashes: Vec<u64> = vec![c.initial_hash];
    let mut parent: Vec<u32> = vec![NO_PARENT];
    let mut via: Vec<u32> = vec![0];
    let mut table = Table::new(w);
    let m0 = mix(c.initial_hash);
    if let Err(pos) = table.find(&c.initial, m0) {
        table.insert_at(pos, &c.initial, m0, 0);
    }
    let mut stats = Stats::new(net);
    let mut dead = Vec::new();
    let mut vanishing: Vec<u64> = Vec::new();
    let mut edges: u64 = 0;
    let mut stop = None;

    let mut cur: Vec<u64> = vec![0; w];
    let mut enabled: Vec<TransitionId> = Vec::new();
    let mut succs: Vec<u64> = Vec::with_capacity(BATCH * w);
    // Per successor: (linear hash, mixed hash, source state, transition).
    let mut meta: Vec<(u64, u64, u32, u32)> = Vec::with_capacity(BATCH);
    let mut next = 0usize;

    'bfs: while next < parent.len() {
        // 1. Expand queued states until the batch is full.
        succs.clear();
        meta.clear();
        // Room for the whole batch, so that the slots prefetched below stay put.
        while (table.len + BATCH + c.transitions()) * 4 > table.capacity() * 3 {
            table.grow();
        }
        while next < parent.len() && meta.len() < BATCH {
            let s = next;
            next += 1;
            cur.copy_from_slice(&arena[s * w..(s + 1) * w]);
            stats.observe(&l, &cur);
            if extras.cut(&l, s, &cur) {
                continue;
            }
            let h = hashes[s];

            let is_vanishing = c.ready_in(net, &cur, &mut enabled);
            if is_vanishing {
                if vanishing.len() <= s / 64 {
                    vanishing.resize(s / 64 + 1, 0);
                }
                vanishing[s / 64] |= 1u64 << (s % 64);
            }
            if enabled.is_empty() {
                dead.push(s as u32);
                continue;
            }
            edges += enabled.len() as u64;
            for &t in &enabled {
                let base = succs.len();
                succs.extend_from_slice(&cur);
                match c.successor(&mut succs[base..], t.index(), &mut stats.bounds) {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return None,
                    Err(Overflow::Stop) => {
                        stop = Some(StopReason::TokenOverflow);
                        break 'bfs;
                    }
                }
                let h2 = h.wrapping_add(c.dhash[t.index()]);
                let mixed = mix(h2);
                table.prefetch(mixed);
                meta.push((h2, mixed, s as u32, t.0));
            }
        }

        // 2. Look up and insert, in BFS order.
        for (i, &(h2, mixed, s, t)) in meta.iter().enumerate() {
            let key = &succs[i * w..(i + 1) * w];
            let pos = match table.find(key, mixed) {
                Ok(idx) => {
                    extras.edge(s, t, idx);
                    continue;
                }
                Err(pos) => pos,
            };
            if parent.len() >= max_states {
                stop = Some(StopReason::StateLimit);
                break 'bfs;
            }
            let idx = parent.len() as u32;
            table.insert_at(pos, key, mixed, idx);
            extras.edge(s, t, idx);
            arena.extend_from_slice(key);
            hashes.push(h2);
            parent.push(s);
            via.push(t);
        }
    }

    let (succ_off, succ, cut) = extras.finish(parent.len());
    Some(StateSpace {
        semantics: c.semantics,
        layout: l,
        arena,
        parent,
        via,
        dead,
        vanishing,
        edges,
        stop,
        bounds: stats.bounds,
        max_total: stats.max_total,
        succ_off,
        succ,
        cut,
    })
}

#[cfg(test)]
mod tests {
    use super::{covers_packed, splitmix, Layout};

    /// Field by field, as `semantics::covers` reads them.
    fn covers_by_field(l: &Layout, m: u64, p: u64) -> bool {
        (0..l.per_word as u32).all(|f| (m >> (f * l.bits)) & l.mask >= (p >> (f * l.bits)) & l.mask)
    }

    #[test]
    fn packed_cover_test_agrees_with_field_by_field() {
        for bits in [1, 2, 4, 8, 16, 32] {
            let l = Layout::new(64, bits);
            // Every pair of values in the two lowest fields (up to 8 bits each),
            // with random fields above.
            let span = 1u64 << (2 * bits).min(16);
            let mut seed = u64::from(bits);
            let step = ((span / 1024) as usize).max(1);
            for a in (0..span).step_by(step) {
                for b in (0..span).step_by(step) {
                    let (ra, rb) = (splitmix(&mut seed), splitmix(&mut seed));
                    let hi = !(span - 1);
                    for (m, p) in [(a, b), (a | (ra & hi), b | (rb & hi)), (a | (ra & hi), b)] {
                        assert_eq!(
                            covers_packed(m, p, l.high),
                            covers_by_field(&l, m, p),
                            "bits {bits}: {m:#x} {p:#x}"
                        );
                    }
                }
            }
        }
    }
}
