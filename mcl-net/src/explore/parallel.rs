//! Multi-threaded breadth-first exploration with the same result as the
//! sequential engine, state numbering included.
//!
//! The state space is split into `k` partitions by hash; each partition has
//! its own table and arena and is only ever touched by one thread at a time,
//! so no locks or atomics guard the states. The search goes level by level;
//! a level is processed in chunks, each in two parallel phases:
//!
//! 1. *expand*: every partition computes the successors of the next slice of
//!    its frontier and sorts them into one outbox per owning partition;
//! 2. *insert*: every partition looks up the successors it owns, inserting the
//!    new ones.
//!
//! Each new state remembers the smallest key `(parent id, rank of the
//! transition among the parent's ready transitions)` it was reached by. At the
//! end of a level the new states of all partitions are merged by that key and
//! numbered: this is exactly the order in which the sequential BFS discovers
//! them, so ids, parents and shortest paths are identical.

use std::sync::atomic::{AtomicUsize, Ordering};

use super::engine::{mix, Compiled, Overflow, Stats, Table, NO_PARENT};
use super::{StateSpace, StopReason};
use crate::model::{Net, TransitionId};

/// Frontier states expanded per partition and chunk.
const CHUNK: usize = 32768;
/// Successors whose table slots are read ahead together.
const WINDOW: usize = 256;
/// Below this many frontier states per chunk, phases run on the calling thread.
const PARALLEL_MIN: usize = 1024;

/// Successors sent to one partition.
#[derive(Default)]
struct Outbox {
    words: Vec<u64>,
    /// (linear hash, mixed hash, key = parent id << 32 | rank, transition).
    meta: Vec<(u64, u64, u64, u32)>,
}

struct Part {
    table: Table,
    arena: Vec<u64>,
    hashes: Vec<u64>,
    /// Global id of each local state (valid for finished levels).
    gid: Vec<u32>,
    parent: Vec<u32>,
    via: Vec<u32>,
    /// Keys of the states of the level being built (local index − `level_start`).
    key: Vec<u64>,
    level_start: usize,
    /// Local indices of the frontier still to expand.
    cursor: usize,
    frontier_end: usize,
    dead: Vec<u32>,
    vanishing: Vec<u32>,
    edges: u64,
    stats: Stats,
}

/// What stopped a phase early.
enum Halt {
    Widen,
    Stop(StopReason),
}

impl Part {
    fn new(words: usize, net: &Net) -> Self {
        Part {
            stats: Stats::new(net),
            table: Table::new(words),
            arena: Vec::new(),
            hashes: Vec::new(),
            gid: Vec::new(),
            parent: Vec::new(),
            via: Vec::new(),
            key: Vec::new(),
            level_start: 0,
            cursor: 0,
            frontier_end: 0,
            dead: Vec::new(),
            vanishing: Vec::new(),
            edges: 0,
        }
    }

    fn len(&self) -> usize {
        self.hashes.len()
    }

    /// Phase 1 on up to `CHUNK` frontier states, into `out` (one per owner).
    fn expand(&mut self, c: &Compiled, net: &Net, out: &mut [Outbox]) -> Result<(), Halt> {
        let w = c.layout.words;
        let parts = out.len();
        let mut ready: Vec<TransitionId> = Vec::new();
        let mut cur = vec![0u64; w];
        let end = self.frontier_end.min(self.cursor + CHUNK);
        for s in self.cursor..end {
            cur.copy_from_slice(&self.arena[s * w..(s + 1) * w]);
            self.stats.observe(&c.layout, &cur);
            if c.ready_in(net, &cur, &mut ready) {
                self.vanishing.push(s as u32);
            }
            if ready.is_empty() {
                self.dead.push(s as u32);
                continue;
            }
            self.edges += ready.len() as u64;
            let h = self.hashes[s];
            let g = u64::from(self.gid[s]);
            for (rank, &t) in ready.iter().enumerate() {
                let h2 = h.wrapping_add(c.dhash[t.index()]);
                let mixed = mix(h2);
                let o = &mut out[owner(mixed, parts)];
                let base = o.words.len();
                o.words.extend_from_slice(&cur);
                match c.successor(&mut o.words[base..], t.index(), &mut self.stats.bounds) {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return Err(Halt::Widen),
                    Err(Overflow::Stop) => return Err(Halt::Stop(StopReason::TokenOverflow)),
                }
                o.meta.push((h2, mixed, (g << 32) | rank as u64, t.0));
            }
        }
        self.cursor = end;
        Ok(())
    }

    /// Phase 2: looks up and inserts the successors this partition owns
    /// (`outboxes[src][dst]` for every `src`, with `dst` this partition).
    fn insert(&mut self, outboxes: &[Vec<Outbox>], dst: usize, w: usize, count: &AtomicUsize, max: usize) -> bool {
        let mut full = false;
        for o in outboxes.iter().map(|row| &row[dst]) {
            while (self.table.len + o.meta.len()) * 4 > self.table.capacity() * 3 {
                self.table.grow();
            }
            // Windows small enough that prefetched slots are still cached
            // when looked up.
            for (win, metas) in o.meta.chunks(WINDOW).enumerate() {
                for m in metas {
                    self.table.prefetch(m.1);
                }
                for (j, &(h2, mixed, key, t)) in metas.iter().enumerate() {
                    let i = win * WINDOW + j;
                    let words = &o.words[i * w..(i + 1) * w];
                    match self.table.find(words, mixed) {
                        Ok(local) => {
                            let local = local as usize;
                            if local >= self.level_start {
                                let k = &mut self.key[local - self.level_start];
                                if key < *k {
                                    *k = key;
                                    self.parent[local] = (key >> 32) as u32;
                                    self.via[local] = t;
                                }
                            }
                        }
                        Err(pos) => {
                            if count.fetch_add(1, Ordering::Relaxed) >= max {
                                full = true;
                                continue;
                            }
                            let local = self.len() as u32;
                            self.table.insert_at(pos, words, mixed, local);
                            self.arena.extend_from_slice(words);
                            self.hashes.push(h2);
                            self.parent.push((key >> 32) as u32);
                            self.via.push(t);
                            self.key.push(key);
                        }
                    }
                }
            }
        }
        full
    }
}

/// Partition owning a state: the high hash bits, reduced to `0..parts`.
#[inline]
fn owner(mixed: u64, parts: usize) -> usize {
    (((mixed >> 32) * parts as u64) >> 32) as usize
}

/// Runs `f` on every partition with its item of `extra`, on threads when
/// `parallel`.
fn each<E: Send, T: Send>(
    parts: &mut [Part],
    extra: &mut [E],
    parallel: bool,
    f: impl Fn(usize, &mut Part, &mut E) -> T + Sync,
) -> Vec<T> {
    if !parallel {
        return parts.iter_mut().zip(extra.iter_mut()).enumerate().map(|(k, (p, e))| f(k, p, e)).collect();
    }
    std::thread::scope(|s| {
        let f = &f;
        let handles: Vec<_> =
            parts.iter_mut().zip(extra.iter_mut()).enumerate().map(|(k, (p, e))| s.spawn(move || f(k, p, e))).collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    })
}

/// Numbers the states of the finished level in key order, from `next_gid`.
fn number_level(parts: &mut [Part], next_gid: usize) -> usize {
    let mut lists: Vec<Vec<(u64, u32)>> = parts
        .iter()
        .map(|p| {
            let mut v: Vec<(u64, u32)> =
                p.key.iter().enumerate().map(|(i, &k)| (k, (p.level_start + i) as u32)).collect();
            v.sort_unstable();
            v
        })
        .collect();
    for p in parts.iter_mut() {
        let n = p.len();
        p.gid.resize(n, 0);
    }
    let mut heads = vec![0usize; lists.len()];
    let mut gid = next_gid;
    loop {
        let mut best: Option<(u64, usize)> = None;
        for (k, l) in lists.iter().enumerate() {
            if let Some(&(key, _)) = l.get(heads[k]) {
                if best.is_none_or(|(b, _)| key < b) {
                    best = Some((key, k));
                }
            }
        }
        let Some((_, k)) = best else { break };
        let local = lists[k][heads[k]].1 as usize;
        parts[k].gid[local] = gid as u32;
        gid += 1;
        heads[k] += 1;
    }
    for (p, l) in parts.iter_mut().zip(lists.iter_mut()) {
        l.clear();
        p.key.clear();
        p.cursor = p.level_start;
        p.frontier_end = p.len();
        p.level_start = p.len();
    }
    gid
}

/// Partitioned BFS; `None` means a place overflowed its field (retry wider).
pub(super) fn run(c: &Compiled, net: &Net, max_states: usize, threads: usize) -> Option<StateSpace> {
    let w = c.layout.words;
    let k = threads.max(1);
    let mut parts: Vec<Part> = (0..k).map(|_| Part::new(w, net)).collect();
    let m0 = mix(c.initial_hash);
    {
        let p = &mut parts[owner(m0, k)];
        if let Err(pos) = p.table.find(&c.initial, m0) {
            p.table.insert_at(pos, &c.initial, m0, 0);
        }
        p.arena.extend_from_slice(&c.initial);
        p.hashes.push(c.initial_hash);
        p.parent.push(NO_PARENT);
        p.via.push(0);
        p.key.push(0);
    }
    let count = AtomicUsize::new(1);
    // outboxes[src][dst]: successors found by partition src, owned by dst.
    let mut outboxes: Vec<Vec<Outbox>> = (0..k).map(|_| (0..k).map(|_| Outbox::default()).collect()).collect();
    let mut total = number_level(&mut parts, 0);
    let mut stop = None;

    'levels: loop {
        if parts.iter().all(|p| p.cursor == p.frontier_end) {
            break;
        }
        // Chunks of the current level.
        while parts.iter().any(|p| p.cursor < p.frontier_end) {
            let work: usize = parts.iter().map(|p| (p.frontier_end - p.cursor).min(CHUNK)).sum();
            let parallel = k > 1 && work >= PARALLEL_MIN;
            let results = each(&mut parts, &mut outboxes, parallel, |_, p, row| p.expand(c, net, row));
            for r in results {
                match r {
                    Ok(()) => {}
                    Err(Halt::Widen) => return None,
                    Err(Halt::Stop(reason)) => {
                        stop = Some(reason);
                        break 'levels;
                    }
                }
            }
            let shared = &outboxes;
            let mut unit = vec![(); k];
            let full = each(&mut parts, &mut unit, parallel, |dst, p, _| p.insert(shared, dst, w, &count, max_states));
            // Keep the buffers (and their memory) for the next chunk.
            for o in outboxes.iter_mut().flatten() {
                o.words.clear();
                o.meta.clear();
            }
            if full.into_iter().any(|f| f) {
                stop = Some(StopReason::StateLimit);
                break 'levels;
            }
        }
        total = number_level(&mut parts, total);
    }
    if stop.is_some() {
        total = number_level(&mut parts, total);
    }
    Some(assemble(c, net, parts, total, stop))
}

/// Gathers the partitions into one state space indexed by global id.
fn assemble(c: &Compiled, net: &Net, parts: Vec<Part>, total: usize, stop: Option<StopReason>) -> StateSpace {
    let w = c.layout.words;
    let mut arena = vec![0u64; total * w];
    let mut parent = vec![NO_PARENT; total];
    let mut via = vec![0u32; total];
    let mut dead = Vec::new();
    let mut vanishing = vec![0u64; total.div_ceil(64)];
    let mut edges = 0;
    let mut stats = Stats::new(net);
    for p in parts {
        stats.merge(&p.stats);
        for (local, &g) in p.gid.iter().enumerate() {
            let g = g as usize;
            arena[g * w..(g + 1) * w].copy_from_slice(&p.arena[local * w..(local + 1) * w]);
            parent[g] = p.parent[local];
            via[g] = p.via[local];
        }
        dead.extend(p.dead.iter().map(|&l| p.gid[l as usize]));
        for &l in &p.vanishing {
            let g = p.gid[l as usize] as usize;
            vanishing[g / 64] |= 1 << (g % 64);
        }
        edges += p.edges;
    }
    dead.sort_unstable();
    StateSpace {
        semantics: c.semantics,
        layout: c.layout,
        arena,
        parent,
        via,
        dead,
        vanishing,
        edges,
        stop,
        bounds: stats.bounds,
        max_total: stats.max_total,
        succ_off: Vec::new(),
        succ: Vec::new(),
        cut: Vec::new(),
    }
}
