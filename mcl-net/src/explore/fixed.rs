//! The sequential engine specialised for markings of `W` ≤ 8 words.
//!
//! Same algorithm as `engine::run` (see the notes in `engine.rs`), with
//! markings as `[u64; W]` values: copies, comparisons and table slots have a
//! size known at compile time, which removes the bounds checks and `memcpy`
//! calls of the slice-based version from the inner loop. Differences:
//!
//! * The table hash is computed from the packed words ([`key_hash`]: `W`
//!   multiplications), not kept incrementally, so no per-state hash array is
//!   stored or read.
//! * Unless edges are recorded (which needs the index of a found state), the
//!   table is a [`KeyTable`]: slots hold nothing but the marking (8 bytes for
//!   a one-word marking instead of 16), so the table is smaller and a cache
//!   line holds more slots. The batch is then larger ([`SORTED_BATCH`]) and
//!   looked up in the order of the table positions (a counting sort by the
//!   top bits of the home slot, stable so that equal markings meet in BFS
//!   order), each lookup prefetching the slot [`PREFETCH_AHEAD`] lookups
//!   later; the new states are numbered afterwards in BFS order, so the
//!   numbering is that of a one-by-one search.
//!   The batch holds keys only: a new state is fired again from its source
//!   (in the arena) when it is numbered.
//! * The table keys are the markings folded to `K` ≤ `W` words by the net's
//!   place invariants ([`super::fold`]); the arena keeps whole markings.
//!   With a [`super::fold::LinearKey`] (`LIN`), keys are one word, kept per
//!   state, and a successor's key is its source's plus the transition's
//!   constant.

use super::engine::{mix, Compiled, Extras, Overflow, Stats, BATCH, NO_PARENT};
use super::hw;
use super::{StateSpace, StopReason};
use crate::model::{Net, TransitionId};

#[derive(Clone, Copy)]
struct Slot<const W: usize> {
    key: [u64; W],
    /// `(low 32 bits of the mixed hash) << 32 | (state index + 1)`, 0 when empty.
    meta: u64,
}

/// Open-addressing hash set of `[u64; W]` markings (linear probing).
pub(super) struct FixedTable<const W: usize> {
    slots: Vec<Slot<W>>,
    mask: usize,
    pub(super) len: usize,
}

impl<const W: usize> FixedTable<W> {
    const EMPTY: Slot<W> = Slot { key: [0; W], meta: 0 };

    pub(super) fn new() -> Self {
        let cap = 1 << 12;
        FixedTable { slots: hw::huge_vec(cap, Self::EMPTY), mask: cap - 1, len: 0 }
    }

    pub(super) fn grow(&mut self) {
        let cap = self.slots.len() * 2;
        let mask = cap - 1;
        let mut slots = hw::huge_vec(cap, Self::EMPTY);
        for s in self.slots.iter().filter(|s| s.meta != 0) {
            let mut pos = (s.meta >> 32) as usize & mask;
            while slots[pos].meta != 0 {
                pos = (pos + 1) & mask;
            }
            slots[pos] = *s;
        }
        self.slots = slots;
        self.mask = mask;
    }

    /// Prefetches the home slot of `mixed`.
    #[inline]
    pub(super) fn prefetch(&self, mixed: u64) {
        if let Some(s) = self.slots.get(mixed as usize & self.mask) {
            hw::prefetch(s);
        }
    }

    #[inline]
    pub(super) fn find(&self, key: &[u64; W], mixed: u64) -> Result<u32, usize> {
        let tag = mixed << 32;
        let mut pos = mixed as usize & self.mask;
        loop {
            let s = &self.slots[pos];
            if s.meta == 0 {
                return Err(pos);
            }
            if s.meta & 0xFFFF_FFFF_0000_0000 == tag && s.key == *key {
                return Ok(s.meta as u32 - 1);
            }
            pos = (pos + 1) & self.mask;
        }
    }

    #[inline]
    pub(super) fn insert_at(&mut self, pos: usize, key: [u64; W], mixed: u64, idx: u32) {
        self.slots[pos] = Slot { key, meta: (mixed << 32) | (u64::from(idx) + 1) };
        self.len += 1;
    }
}

/// Hash of a packed marking for the sequential tables ([`hash_words`] on
/// `W` words, unrolled).
#[inline(always)]
pub(super) fn key_hash<const W: usize>(key: &[u64; W]) -> u64 {
    hash_words(key)
}

/// Hash of a packed marking, for every table of the explorer: a multiply
/// per word, then the MurmurHash3 finalizer.
#[inline(always)]
pub(super) fn hash_words(key: &[u64]) -> u64 {
    const K: [u64; 8] = [
        0x9E37_79B9_7F4A_7C15,
        0xC2B2_AE3D_27D4_EB4F,
        0x1656_67B1_9E37_79F9,
        0x85EB_CA77_C2B2_AE63,
        0x27D4_EB2F_1656_67C5,
        0xD6E8_FEB8_6659_FD93,
        0xA076_1D64_78BD_642F,
        0xE703_7ED1_A0B4_28DB,
    ];
    let mut h = 0u64;
    for (i, &k) in key.iter().enumerate() {
        h = h.wrapping_add(k.wrapping_mul(K[i % 8])).rotate_left(23);
    }
    mix(h)
}

/// The set of visited markings of the sequential search.
trait Visited<const W: usize> {
    fn new() -> Self;
    fn len(&self) -> usize;
    fn capacity(&self) -> usize;
    fn grow(&mut self);
    fn prefetch(&self, hash: u64);
    /// Home slot position of `hash`.
    fn home(&self, hash: u64) -> usize;
    /// `Ok(state index)` (0 when the table keeps no indices) or `Err(where to insert)`.
    fn find(&self, key: &[u64; W], hash: u64) -> Result<u32, usize>;
    fn insert_at(&mut self, pos: usize, key: [u64; W], hash: u64, idx: u32);
}

impl<const W: usize> Visited<W> for FixedTable<W> {
    fn new() -> Self {
        FixedTable::new()
    }
    #[inline]
    fn len(&self) -> usize {
        self.len
    }
    #[inline]
    fn capacity(&self) -> usize {
        self.slots.len()
    }
    fn grow(&mut self) {
        FixedTable::grow(self)
    }
    #[inline(always)]
    fn prefetch(&self, hash: u64) {
        FixedTable::prefetch(self, hash)
    }
    #[inline(always)]
    fn home(&self, hash: u64) -> usize {
        hash as usize & self.mask
    }
    #[inline(always)]
    fn find(&self, key: &[u64; W], hash: u64) -> Result<u32, usize> {
        FixedTable::find(self, key, hash)
    }
    #[inline(always)]
    fn insert_at(&mut self, pos: usize, key: [u64; W], hash: u64, idx: u32) {
        FixedTable::insert_at(self, pos, key, hash, idx)
    }
}

/// Open-addressing hash set of `[u64; W]` markings (linear probing) whose
/// slots hold only the marking: the all-zero marking marks an empty slot and
/// is kept aside as a flag. Positions come from [`key_hash`], recomputed when
/// the table grows.
pub(super) struct KeyTable<const W: usize> {
    slots: Vec<[u64; W]>,
    mask: usize,
    len: usize,
    has_zero: bool,
}

/// The position [`KeyTable::find`] gives for the all-zero marking.
const ZERO_POS: usize = usize::MAX;

impl<const W: usize> Visited<W> for KeyTable<W> {
    fn new() -> Self {
        let cap = 1 << 12;
        KeyTable { slots: hw::huge_vec(cap, [0; W]), mask: cap - 1, len: 0, has_zero: false }
    }
    #[inline]
    fn len(&self) -> usize {
        self.len
    }
    #[inline]
    fn capacity(&self) -> usize {
        self.slots.len()
    }
    fn grow(&mut self) {
        let cap = self.slots.len() * 2;
        let mask = cap - 1;
        let mut slots = hw::huge_vec(cap, [0u64; W]);
        for k in self.slots.iter().filter(|k| **k != [0; W]) {
            let mut pos = key_hash(k) as usize & mask;
            while slots[pos] != [0; W] {
                pos = (pos + 1) & mask;
            }
            slots[pos] = *k;
        }
        self.slots = slots;
        self.mask = mask;
    }
    #[inline(always)]
    fn prefetch(&self, hash: u64) {
        if let Some(s) = self.slots.get(hash as usize & self.mask) {
            hw::prefetch(s);
        }
    }
    #[inline(always)]
    fn home(&self, hash: u64) -> usize {
        hash as usize & self.mask
    }
    #[inline(always)]
    fn find(&self, key: &[u64; W], hash: u64) -> Result<u32, usize> {
        if *key == [0; W] {
            return if self.has_zero { Ok(0) } else { Err(ZERO_POS) };
        }
        let mut pos = hash as usize & self.mask;
        loop {
            let s = &self.slots[pos];
            if s == key {
                return Ok(0);
            }
            if *s == [0; W] {
                return Err(pos);
            }
            pos = (pos + 1) & self.mask;
        }
    }
    #[inline(always)]
    fn insert_at(&mut self, pos: usize, key: [u64; W], _hash: u64, _idx: u32) {
        match self.slots.get_mut(pos) {
            Some(s) => *s = key,
            None => self.has_zero = true,
        }
        self.len += 1;
    }
}

/// Successors per batch when the lookups are sorted by table position.
const SORTED_BATCH: usize = 1 << 14;
/// The sort keys: the top bits of the home slot.
const BUCKET_BITS: u32 = 12;
/// How many lookups ahead the sorted pass prefetches.
const PREFETCH_AHEAD: usize = 16;

/// Runs BFS with edges recorded or markings cut (`EXTRAS`, engine.rs calls
/// it with `true`; the default search is [`run_keyed`]), with a
/// [`FixedTable`] of whole markings and their indices; `None` means a place
/// overflowed its bit field (retry wider).
pub(super) fn run<const W: usize, const EXTRAS: bool>(
    c: &Compiled,
    net: &Net,
    max_states: usize,
    extras: Extras,
) -> Option<StateSpace> {
    search::<W, W, EXTRAS, false, FixedTable<W>>(c, net, max_states, extras)
}

/// Runs the default BFS (no extras) with a [`KeyTable`] of the linear keys
/// ([`Compiled::linear`]: one word) when there are some, else of the folded
/// keys ([`Compiled::fold`]: `K` ≤ `W` words); `None` as for [`run`].
pub(super) fn run_keyed(c: &Compiled, net: &Net, max_states: usize, extras: Extras) -> Option<StateSpace> {
    macro_rules! keyed {
        ($w:literal, $k:literal) => {
            search::<$w, $k, false, false, KeyTable<$k>>(c, net, max_states, extras)
        };
    }
    macro_rules! linear {
        ($w:literal) => {
            search::<$w, 1, false, true, KeyTable<1>>(c, net, max_states, extras)
        };
    }
    if c.linear.is_some() {
        match c.layout.words {
            2 => return linear!(2),
            3 => return linear!(3),
            4 => return linear!(4),
            _ => {}
        }
    }
    match (c.layout.words, c.fold.words) {
        (1, _) => keyed!(1, 1),
        (2, 1) => keyed!(2, 1),
        (2, _) => keyed!(2, 2),
        (3, 1) => keyed!(3, 1),
        (3, 2) => keyed!(3, 2),
        (3, _) => keyed!(3, 3),
        (4, 1) => keyed!(4, 1),
        (4, 2) => keyed!(4, 2),
        (4, 3) => keyed!(4, 3),
        (4, _) => keyed!(4, 4),
        (5, _) => keyed!(5, 5),
        (6, _) => keyed!(6, 6),
        (7, _) => keyed!(7, 7),
        (8, _) => keyed!(8, 8),
        _ => super::engine::run(c, net, max_states, extras),
    }
}

/// A `K`-word key holding the linear key `k` (`K` is 1 where it is used).
#[inline(always)]
fn linear_key<const K: usize>(k: u64) -> [u64; K] {
    let mut key = [0u64; K];
    if let Some(x) = key.first_mut() {
        *x = k;
    }
    key
}

/// The search: markings of `W` words, table keys of `K` words (with `LIN`,
/// `K` is 1 and the keys come from [`Compiled::linear`]).
fn search<const W: usize, const K: usize, const EXTRAS: bool, const LIN: bool, T: Visited<K>>(
    c: &Compiled,
    net: &Net,
    max_states: usize,
    mut extras: Extras,
) -> Option<StateSpace> {
    let mut init = [0u64; W];
    init.copy_from_slice(&c.initial);
    let mut arena: Vec<[u64; W]> = vec![init];
    let mut parent: Vec<u32> = vec![NO_PARENT];
    let mut via: Vec<u32> = vec![0];
    let mut table = T::new();
    // With `LIN`: the linear key of each state, and each transition's change.
    let (lin0, lin_delta) = match &c.linear {
        Some(l) if LIN => (l.initial, &l.delta[..]),
        _ => (0, &[][..]),
    };
    let mut lin_keys: Vec<u64> = if LIN { vec![lin0] } else { Vec::new() };
    let k0: [u64; K] = if LIN { linear_key(lin0) } else { c.fold.apply(&init) };
    let m0 = key_hash(&k0);
    if let Err(pos) = table.find(&k0, m0) {
        table.insert_at(pos, k0, m0, 0);
    }
    let mut stats = Stats::new(net);
    let mut dead = Vec::new();
    let mut vanishing: Vec<u64> = Vec::new();
    let mut edges: u64 = 0;
    let mut stop = None;

    let mut enabled: Vec<TransitionId> = Vec::new();
    // The batch: successors, and (hash, source, transition).
    // Without extras (no index needed in the table) the lookups are sorted.
    let sorted = !EXTRAS;
    let batch = if sorted { SORTED_BATCH } else { BATCH };
    // Sorted, the batch holds keys only: a new state is fired again from
    // its source when it is numbered.
    let mut succs: Vec<[u64; W]> = Vec::with_capacity(if sorted { 0 } else { batch + c.transitions() });
    let mut keys: Vec<[u64; K]> = Vec::with_capacity(if sorted { batch + c.transitions() } else { 0 });
    let mut meta: Vec<(u64, u32, u32)> = Vec::with_capacity(batch + c.transitions());
    // Without extras: the batch in table order, and which successors are new.
    let mut order: Vec<u32> = Vec::new();
    let mut counts: Vec<u32> = Vec::new();
    let mut fresh: Vec<bool> = Vec::new();
    let mut next = 0usize;

    'bfs: while next < parent.len() {
        // 1. Expand queued states until the batch is full.
        succs.clear();
        keys.clear();
        meta.clear();
        // Room for the whole batch, so that the slots prefetched below stay put.
        while (table.len() + batch + c.transitions()) * 4 > table.capacity() * 3 {
            table.grow();
        }
        while next < parent.len() && meta.len() < batch {
            let s = next;
            next += 1;
            let cur = arena[s];
            stats.observe(&c.layout, &cur);
            if EXTRAS && extras.cut(&c.layout, s, &cur) {
                continue;
            }
            if c.ready_fixed(net, &cur, &mut enabled) {
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
            let lin_cur = if LIN { lin_keys[s] } else { 0 };
            for &t in &enabled {
                let mut succ = cur;
                // Linear keys need no successor marking: it is computed
                // again when numbered.
                let next = if LIN && sorted {
                    c.check(&cur, t.index(), &mut stats.bounds)
                } else {
                    c.successor(&mut succ, t.index(), &mut stats.bounds)
                };
                match next {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return None,
                    Err(Overflow::Stop) => {
                        stop = Some(StopReason::TokenOverflow);
                        break 'bfs;
                    }
                }
                let key = if LIN {
                    linear_key(lin_cur.wrapping_add(lin_delta.get(t.index()).copied().unwrap_or(0)))
                } else {
                    c.fold.apply::<W, K>(&succ)
                };
                let hash = key_hash(&key);
                if sorted {
                    keys.push(key);
                } else {
                    // Prefetched now, looked up after the batch: the misses
                    // overlap with the work of generating the next successors.
                    table.prefetch(hash);
                    succs.push(succ);
                }
                meta.push((hash, s as u32, t.0));
            }
        }

        if sorted {
            // 2. Look the batch up in table order (a stable counting sort
            //    by the top bits of the home slot): the lookups sweep the
            //    table once, page by page, instead of jumping at random, and
            //    equal markings meet in BFS order, so the first one is new.
            let cap_bits = table.capacity().trailing_zeros();
            let shift = cap_bits - BUCKET_BITS.min(cap_bits);
            counts.clear();
            counts.resize((table.capacity() >> shift) + 1, 0);
            for m in &meta {
                counts[(table.home(m.0) >> shift) + 1] += 1;
            }
            for i in 1..counts.len() {
                counts[i] += counts[i - 1];
            }
            order.clear();
            order.resize(meta.len(), 0);
            for (i, m) in meta.iter().enumerate() {
                let b = &mut counts[table.home(m.0) >> shift];
                order[*b as usize] = i as u32;
                *b += 1;
            }
            fresh.clear();
            fresh.resize(meta.len(), false);
            for (k, &i) in order.iter().enumerate() {
                if let Some(&j) = order.get(k + PREFETCH_AHEAD) {
                    table.prefetch(meta[j as usize].0);
                }
                let (key, hash) = (keys[i as usize], meta[i as usize].0);
                if let Err(pos) = table.find(&key, hash) {
                    table.insert_at(pos, key, hash, 0);
                    fresh[i as usize] = true;
                }
            }
            // 3. Number the new states in BFS order.
            for ((&(_, s, t), &new), key) in meta.iter().zip(&fresh).zip(&keys) {
                if !new {
                    continue;
                }
                if parent.len() >= max_states {
                    stop = Some(StopReason::StateLimit);
                    break 'bfs;
                }
                let mut succ = arena[s as usize];
                c.fire(&mut succ, t as usize);
                arena.push(succ);
                parent.push(s);
                via.push(t);
                if LIN {
                    lin_keys.push(key[0]);
                }
            }
            continue;
        }

        // 2. Look up and insert, in BFS order.
        for (succ, &(mixed, s, t)) in succs.iter().zip(&meta) {
            let key = c.fold.apply(succ);
            let pos = match table.find(&key, mixed) {
                Ok(idx) => {
                    if EXTRAS {
                        extras.edge(s, t, idx);
                    }
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
            if EXTRAS {
                extras.edge(s, t, idx);
            }
            arena.push(*succ);
            parent.push(s);
            via.push(t);
        }
    }

    let (succ_off, succ, cut) = extras.finish(parent.len());
    Some(StateSpace {
        semantics: c.semantics,
        layout: c.layout,
        arena: arena.into_flattened(),
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
