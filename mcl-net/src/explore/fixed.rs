//! The sequential engine specialised for markings of `W` ≤ 8 words.
//!
//! Same algorithm as `engine::run` (see the notes in `engine.rs`), with
//! markings as `[u64; W]` values: copies, comparisons and table slots have a
//! size known at compile time, which removes the bounds checks and `memcpy`
//! calls of the slice-based version from the inner loop.

use super::engine::{mix, Compiled, Extras, Overflow, Stats, BATCH, NO_PARENT};
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
        FixedTable { slots: vec![Self::EMPTY; cap], mask: cap - 1, len: 0 }
    }

    pub(super) fn capacity(&self) -> usize {
        self.slots.len()
    }

    pub(super) fn grow(&mut self) {
        let cap = self.slots.len() * 2;
        let mask = cap - 1;
        let mut slots = vec![Self::EMPTY; cap];
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

    #[inline]
    pub(super) fn touch(&self, mixed: u64) -> u64 {
        self.slots[mixed as usize & self.mask].meta
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

/// Runs BFS; `None` means a place overflowed its bit field (retry wider).
///
/// `EXTRAS` compiles in the calls to `extras` (edges, cut); without it the
/// default search pays nothing for them.
pub(super) fn run<const W: usize, const EXTRAS: bool>(
    c: &Compiled,
    net: &Net,
    max_states: usize,
    mut extras: Extras,
) -> Option<StateSpace> {
    let mut init = [0u64; W];
    init.copy_from_slice(&c.initial);
    let mut arena: Vec<[u64; W]> = vec![init];
    let mut hashes: Vec<u64> = vec![c.initial_hash];
    let mut parent: Vec<u32> = vec![NO_PARENT];
    let mut via: Vec<u32> = vec![0];
    let mut table = FixedTable::<W>::new();
    let m0 = mix(c.initial_hash);
    if let Err(pos) = table.find(&init, m0) {
        table.insert_at(pos, init, m0, 0);
    }
    let mut stats = Stats::new(net);
    let mut dead = Vec::new();
    let mut vanishing: Vec<u64> = Vec::new();
    let mut edges: u64 = 0;
    let mut stop = None;

    let mut enabled: Vec<TransitionId> = Vec::new();
    // The batch: successors, and (linear hash, mixed hash, source, transition).
    let mut succs: Vec<[u64; W]> = Vec::with_capacity(2 * BATCH);
    let mut meta: Vec<(u64, u64, u32, u32)> = Vec::with_capacity(2 * BATCH);
    let mut next = 0usize;

    'bfs: while next < parent.len() {
        // 1. Expand queued states until the batch is full.
        succs.clear();
        meta.clear();
        while next < parent.len() && meta.len() < BATCH {
            let s = next;
            next += 1;
            let cur = arena[s];
            stats.observe(&c.layout, &cur);
            if EXTRAS && extras.cut(&c.layout, s, &cur) {
                continue;
            }
            if c.ready_in(net, &cur, &mut enabled) {
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
            let h = hashes[s];
            for &t in &enabled {
                let mut succ = cur;
                match c.successor(&mut succ, t.index(), &mut stats.bounds) {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return None,
                    Err(Overflow::Stop) => {
                        stop = Some(StopReason::TokenOverflow);
                        break 'bfs;
                    }
                }
                let h2 = h.wrapping_add(c.dhash[t.index()]);
                succs.push(succ);
                meta.push((h2, mix(h2), s as u32, t.0));
            }
        }

        // 2. Read the home slot of every successor (overlapping misses).
        while (table.len + meta.len()) * 4 > table.slots.len() * 3 {
            table.grow();
        }
        let mut sink = 0u64;
        for m in &meta {
            sink ^= table.touch(m.1);
        }
        std::hint::black_box(sink);

        // 3. Look up and insert, in BFS order.
        for (&key, &(h2, mixed, s, t)) in succs.iter().zip(&meta) {
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
            arena.push(key);
            hashes.push(h2);
            parent.push(s);
            via.push(t);
        }
    }

    let (succ_off, succ, cut) = extras.finish(parent.len());
    Some(StateSpace {
        semantics: c.semantics,
        layout: c.layout,
        arena: arena.as_flattened().to_vec(),
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
