//! Multi-threaded exploration without levels: the same set of states,
//! edges, dead and vanishing markings and bounds as the sequential engine,
//! in another order.
//!
//! * **One shared table.** Every visited marking is in one lock-free
//!   open-addressing table ([`Table`]): a slot is a meta word and the packed
//!   marking. A thread adds a marking by claiming an empty slot
//!   (compare-and-swap of the meta word from empty to busy), writing the
//!   marking, then publishing the hash tag in the meta word (release); a
//!   reader that meets a busy slot waits for the tag (a few stores away).
//!   Looking up a present marking is plain loads.
//! * **Work stealing.** New states go, with their markings, into chunks of
//!   [`CHUNK`] states on the discovering thread's deque
//!   (`crossbeam-deque`); a thread expands its own chunks and steals from
//!   the others when it has none. A batch of about [`BATCH`] successors is
//!   generated first, then looked up in the order of their table positions
//!   (as in `fixed.rs`), prefetching ahead.
//! * **Per-thread ids.** A state's id is (discovering thread, index in that
//!   thread's arena); parents and dead and vanishing states are recorded
//!   with these ids and renumbered once at the end, threads' arenas
//!   concatenated. The only shared counters are touched once per batch or
//!   chunk: `reserved` (states in the table plus room reserved by batches
//!   in progress; it bounds the table's load and enforces `max_states`)
//!   and `pending` (chunks pushed and not yet expanded).
//! * **Growth.** The table sits behind an `RwLock` that a thread holds for
//!   reading during one batch of lookups. A thread whose batch could push
//!   the load above 3/4 takes it for writing and rehashes into a table
//!   twice as large, on all threads at once (the others are waiting on the
//!   lock); this happens about log2(states) times.
//!
//! **Termination.** A chunk is counted in `pending` before it is pushed and
//! uncounted only after the batch that expanded it has pushed all the new
//! states it found, so `pending` is 0 exactly when no work is left; a
//! thread with nothing to expand or steal stops when it reads 0.
//!
//! **State limit.** A batch reserves as many ids as it has successors,
//! fewer near `max_states`; one that needs an id beyond its reservation
//! stops every thread. The space is then reported incomplete with at most
//! `max_states` states, possibly fewer (ids other batches had reserved and
//! not used), so a net with slightly fewer than `max_states` states may be
//! reported incomplete; a complete report is always exact.
//!
//! A state's parent is the state whose expansion first added it, so
//! [`StateSpace::path_to`] gives a real firing sequence, not always a
//! shortest one. Used when [`super::Options::exact_order`] is false.

use std::hint::spin_loop;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicU8, AtomicUsize, Ordering};
use std::sync::{PoisonError, RwLock, RwLockReadGuard};
use std::time::Duration;

use crossbeam_deque::{Steal, Stealer, Worker as Deque};

use super::engine::{mix, Compiled, Overflow, Stats, NO_PARENT};
use super::hw;
use super::{StateSpace, StopReason};
use crate::model::{Net, TransitionId};

/// Successors generated before they are looked up together.
const BATCH: usize = 1 << 14;
/// States per chunk of work (the unit of stealing).
const CHUNK: usize = 1024;
/// The lookups are sorted by the top bits of their home slot.
const BUCKET_BITS: u32 = 12;
/// How many lookups ahead a slot is prefetched.
const PREFETCH_AHEAD: usize = 16;
/// Slots of the first table.
const INITIAL_CAP: usize = 1 << 15;
/// Below this many slots a table is rehashed by one thread.
const PARALLEL_REHASH: usize = 1 << 16;

/// Meta word of a free slot.
const EMPTY: u64 = 0;
/// Meta word of a slot claimed by a thread that is writing its marking.
const BUSY: u64 = 1;

/// Meta word of a published slot: the hash with bit 1 set (never
/// [`EMPTY`] or [`BUSY`]); the home slot comes from bits 2 and up, so the
/// meta word alone places an entry when the table grows.
#[inline(always)]
fn tag(hash: u64) -> u64 {
    hash | 2
}

/// Hash of a packed marking: a multiply per word, then the MurmurHash3
/// finalizer.
#[inline(always)]
fn hash_words(key: &[u64]) -> u64 {
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

/// What [`Table::insert`] did.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Added {
    /// The marking was there.
    Found,
    /// This call added it.
    New,
    /// It is new, but the caller may add no more (state limit).
    Refused,
}

/// The shared set of visited markings: open addressing, linear probing.
///
/// Markings of one word are the slots themselves (0 is a free slot; the
/// all-zero marking is a flag aside): a compare-and-swap adds one. Wider
/// slots are `slots[i * stride..]`: a meta word ([`EMPTY`], [`BUSY`] or a
/// [`tag`]), then the marking's words.
struct Table {
    slots: Vec<AtomicU64>,
    stride: usize,
    mask: usize,
    /// One-word markings: whether the all-zero marking is in the table.
    zero: AtomicBool,
}

impl Table {
    fn new(cap: usize, words: usize) -> Self {
        let stride = if words == 1 { 1 } else { words + 1 };
        let n = cap * stride;
        let mut slots = Vec::with_capacity(n);
        hw::advise_huge(&mut slots);
        slots.resize_with(n, || AtomicU64::new(EMPTY));
        Table { slots, stride, mask: cap - 1, zero: AtomicBool::new(false) }
    }

    fn capacity(&self) -> usize {
        self.mask + 1
    }

    /// Most entries allowed (a load of 3/4).
    fn limit(&self) -> usize {
        self.capacity() / 4 * 3
    }

    #[inline(always)]
    fn home(&self, hash: u64) -> usize {
        (hash >> 2) as usize & self.mask
    }

    /// Prefetches the first and the last word of the home slot of `hash`.
    #[inline(always)]
    fn prefetch(&self, hash: u64) {
        let base = self.home(hash) * self.stride;
        if let (Some(a), Some(b)) = (self.slots.get(base), self.slots.get(base + self.stride - 1)) {
            hw::prefetch(a);
            hw::prefetch(b);
        }
    }

    /// Adds `key` (of the table's width) unless it is present; with `room`
    /// false a new key is not added but [`Added::Refused`]. The table must
    /// have a free slot.
    #[inline(always)]
    fn insert(&self, key: &[u64], hash: u64, room: bool) -> Added {
        if self.stride == 1 {
            return self.insert_word(key[0], hash, room);
        }
        let t = tag(hash);
        let mut pos = self.home(hash);
        loop {
            let base = pos * self.stride;
            let meta = &self.slots[base];
            let words = &self.slots[base + 1..base + 1 + key.len()];
            let mut m = meta.load(Ordering::Acquire);
            if m == EMPTY {
                if !room {
                    return Added::Refused;
                }
                match meta.compare_exchange(EMPTY, BUSY, Ordering::Acquire, Ordering::Acquire) {
                    Ok(_) => {
                        for (s, &k) in words.iter().zip(key) {
                            s.store(k, Ordering::Relaxed);
                        }
                        meta.store(t, Ordering::Release);
                        return Added::New;
                    }
                    Err(now) => m = now,
                }
            }
            // Claimed by another thread: its marking is a few stores away
            // (unless that thread was descheduled in between: then yield).
            let mut spins = 0u32;
            while m == BUSY {
                spins += 1;
                if spins < 64 {
                    spin_loop();
                } else {
                    std::thread::yield_now();
                }
                m = meta.load(Ordering::Acquire);
            }
            if m == t && words.iter().zip(key).all(|(s, &k)| s.load(Ordering::Relaxed) == k) {
                return Added::Found;
            }
            pos = (pos + 1) & self.mask;
        }
    }

    /// [`Table::insert`] for one-word markings.
    #[inline(always)]
    fn insert_word(&self, key: u64, hash: u64, room: bool) -> Added {
        if key == 0 {
            return match (self.zero.load(Ordering::Relaxed), room) {
                (true, _) => Added::Found,
                (false, false) => Added::Refused,
                (false, true) if self.zero.swap(true, Ordering::Relaxed) => Added::Found,
                (false, true) => Added::New,
            };
        }
        let mut pos = self.home(hash);
        loop {
            let s = &self.slots[pos];
            let mut v = s.load(Ordering::Relaxed);
            if v == EMPTY {
                if !room {
                    return Added::Refused;
                }
                match s.compare_exchange(EMPTY, key, Ordering::Relaxed, Ordering::Relaxed) {
                    Ok(_) => return Added::New,
                    Err(now) => v = now,
                }
            }
            if v == key {
                return Added::Found;
            }
            pos = (pos + 1) & self.mask;
        }
    }

    /// Adds the entries of slots `range` to `to` (no thread is inserting
    /// into `self`).
    fn rehash_into(&self, range: std::ops::Range<usize>, to: &Table) {
        if self.stride == 1 {
            for s in &self.slots[range] {
                let key = s.load(Ordering::Relaxed);
                if key != EMPTY {
                    to.insert_word(key, hash_words(&[key]), true);
                }
            }
            to.zero.store(self.zero.load(Ordering::Relaxed), Ordering::Relaxed);
            return;
        }
        let w = self.stride - 1;
        let mut key = vec![0u64; w];
        for pos in range {
            let base = pos * self.stride;
            let m = self.slots[base].load(Ordering::Relaxed);
            if m == EMPTY {
                continue;
            }
            for (k, s) in key.iter_mut().zip(&self.slots[base + 1..base + 1 + w]) {
                *k = s.load(Ordering::Relaxed);
            }
            // `m` is a tag: it gives the same tag and home slot as the hash.
            to.insert(&key, m, true);
        }
    }
}

/// Why the workers stop early; a larger value wins.
const HALT_NONE: u8 = 0;
const HALT_LIMIT: u8 = 1;
const HALT_TOKENS: u8 = 2;
const HALT_WIDEN: u8 = 3;

/// States to expand: their markings and ids (`thread << 32 | local index`).
struct Chunk {
    keys: Vec<u64>,
    ids: Vec<u64>,
}

impl Chunk {
    fn new(w: usize) -> Self {
        Chunk { keys: Vec::with_capacity(CHUNK * w), ids: Vec::with_capacity(CHUNK) }
    }
}

/// What the threads share.
struct Shared<'a> {
    c: &'a Compiled,
    net: &'a Net,
    threads: usize,
    table: RwLock<Table>,
    /// States in the table plus ids reserved by batches in progress.
    reserved: AtomicUsize,
    max_states: usize,
    /// Chunks pushed and not yet expanded (see the module comment).
    pending: AtomicUsize,
    /// One of the `HALT_*` values.
    halt: AtomicU8,
    stealers: Vec<Stealer<Chunk>>,
}

impl Shared<'_> {
    fn halted(&self) -> bool {
        self.halt.load(Ordering::Relaxed) != HALT_NONE
    }

    fn stop(&self, why: u8) {
        self.halt.fetch_max(why, Ordering::Relaxed);
    }

    /// Read access to a table with room for `n` more states, and how many
    /// of them may be new (fewer than `n` near `max_states`). Grows the
    /// table first when the reservation would load it above 3/4.
    fn room(&self, n: usize) -> (RwLockReadGuard<'_, Table>, usize) {
        loop {
            let g = self.table.read().unwrap_or_else(PoisonError::into_inner);
            let mut cur = self.reserved.load(Ordering::Relaxed);
            loop {
                let take = n.min(self.max_states.saturating_sub(cur));
                if cur + take > g.limit() {
                    break;
                }
                match self.reserved.compare_exchange_weak(cur, cur + take, Ordering::Relaxed, Ordering::Relaxed) {
                    Ok(_) => return (g, take),
                    Err(now) => cur = now,
                }
            }
            let seen = g.capacity();
            drop(g);
            self.grow(seen);
        }
    }

    /// Doubles the table unless another thread already grew it past `seen`
    /// slots; rehashes on all threads when it is large.
    fn grow(&self, seen: usize) {
        let mut g = self.table.write().unwrap_or_else(PoisonError::into_inner);
        if g.capacity() != seen {
            return;
        }
        let new = Table::new(seen * 2, self.c.layout.words);
        let old: &Table = &g;
        let k = self.threads;
        if seen < PARALLEL_REHASH || k == 1 {
            old.rehash_into(0..seen, &new);
        } else {
            let new = &new;
            std::thread::scope(|s| {
                for i in 0..k {
                    s.spawn(move || old.rehash_into(seen * i / k..seen * (i + 1) / k, new));
                }
            });
        }
        *g = new;
    }
}

/// What a thread leaves: the states it discovered, and what it saw while
/// expanding states (ids as in [`Chunk`]).
struct Part {
    arena: Vec<u64>,
    /// Parent's id ([`u64::MAX`] for the initial state).
    parent: Vec<u64>,
    via: Vec<u32>,
    dead: Vec<u64>,
    vanishing: Vec<u64>,
    edges: u64,
    stats: Stats,
}

/// One thread; `W` is the marking's width in words, 0 for "as the layout
/// says" (markings wider than 8 words).
struct Worker<'a, const W: usize> {
    me: usize,
    sh: &'a Shared<'a>,
    deque: Deque<Chunk>,
    words: usize,
    part: Part,
    /// The batch: successors, (hash, parent's index in `parents`,
    /// transition) of each, and the ids of the states expanded.
    succs: Vec<u64>,
    meta: Vec<(u64, u32, u32)>,
    parents: Vec<u64>,
    order: Vec<u32>,
    counts: Vec<u32>,
    fresh: Vec<bool>,
    ready: Vec<TransitionId>,
}

impl<'a, const W: usize> Worker<'a, W> {
    fn new(me: usize, sh: &'a Shared<'a>, deque: Deque<Chunk>) -> Self {
        Worker {
            me,
            sh,
            deque,
            words: sh.c.layout.words,
            part: Part {
                arena: Vec::new(),
                parent: Vec::new(),
                via: Vec::new(),
                dead: Vec::new(),
                vanishing: Vec::new(),
                edges: 0,
                stats: Stats::new(sh.net),
            },
            succs: Vec::with_capacity(BATCH * sh.c.layout.words),
            meta: Vec::with_capacity(BATCH),
            parents: Vec::new(),
            order: Vec::new(),
            counts: Vec::new(),
            fresh: Vec::new(),
            ready: Vec::new(),
        }
    }

    /// The marking's width (a constant when `W` > 0).
    #[inline(always)]
    fn w(&self) -> usize {
        if W == 0 {
            self.words
        } else {
            W
        }
    }

    fn run(mut self) -> Part {
        if let Err(why) = self.work() {
            self.sh.stop(why);
        }
        self.part
    }

    fn work(&mut self) -> Result<(), u8> {
        let mut idle = 0u32;
        loop {
            if self.sh.halted() {
                return Ok(());
            }
            self.succs.clear();
            self.meta.clear();
            self.parents.clear();
            let mut taken = 0;
            while self.meta.len() < BATCH {
                let Some(chunk) = self.next_chunk() else { break };
                taken += 1;
                self.expand(&chunk)?;
            }
            if taken == 0 {
                if self.sh.pending.load(Ordering::Acquire) == 0 {
                    return Ok(());
                }
                idle = backoff(idle);
                continue;
            }
            idle = 0;
            self.look_up()?;
            self.sh.pending.fetch_sub(taken, Ordering::AcqRel);
        }
    }

    /// A chunk of this thread's own, else one stolen from another thread.
    fn next_chunk(&mut self) -> Option<Chunk> {
        if let Some(c) = self.deque.pop() {
            return Some(c);
        }
        let k = self.sh.stealers.len();
        for i in 1..k {
            let st = &self.sh.stealers[(self.me + i) % k];
            loop {
                match st.steal_batch_and_pop(&self.deque) {
                    Steal::Success(c) => return Some(c),
                    Steal::Empty => break,
                    Steal::Retry => spin_loop(),
                }
            }
        }
        None
    }

    /// Generates the successors of the states of `chunk` into the batch.
    fn expand(&mut self, chunk: &Chunk) -> Result<(), u8> {
        let (c, net) = (self.sh.c, self.sh.net);
        let w = self.w();
        for (cur, &id) in chunk.keys.chunks_exact(w).zip(&chunk.ids) {
            self.part.stats.observe(&c.layout, cur);
            if c.ready_in(net, cur, &mut self.ready) {
                self.part.vanishing.push(id);
            }
            if self.ready.is_empty() {
                self.part.dead.push(id);
                continue;
            }
            self.part.edges += self.ready.len() as u64;
            let p = self.parents.len() as u32;
            self.parents.push(id);
            for &t in &self.ready {
                let base = self.succs.len();
                self.succs.extend_from_slice(cur);
                let succ = &mut self.succs[base..base + w];
                match c.successor(succ, t.index(), &mut self.part.stats.bounds) {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return Err(HALT_WIDEN),
                    Err(Overflow::Stop) => return Err(HALT_TOKENS),
                }
                self.meta.push((hash_words(succ), p, t.0));
            }
        }
        Ok(())
    }

    /// Looks the batch up in table order, then records and pushes its new
    /// states in batch order.
    fn look_up(&mut self) -> Result<(), u8> {
        let n = self.meta.len();
        if n == 0 {
            return Ok(());
        }
        let w = self.w();
        let sh = self.sh;
        let (table, take) = sh.room(n);
        // A stable counting sort by the top bits of the home slot.
        let cap_bits = table.capacity().trailing_zeros();
        let shift = cap_bits - BUCKET_BITS.min(cap_bits);
        self.counts.clear();
        self.counts.resize((table.capacity() >> shift) + 1, 0);
        for m in &self.meta {
            self.counts[(table.home(m.0) >> shift) + 1] += 1;
        }
        for i in 1..self.counts.len() {
            self.counts[i] += self.counts[i - 1];
        }
        self.order.clear();
        self.order.resize(n, 0);
        for (i, m) in self.meta.iter().enumerate() {
            let b = &mut self.counts[table.home(m.0) >> shift];
            self.order[*b as usize] = i as u32;
            *b += 1;
        }
        self.fresh.clear();
        self.fresh.resize(n, false);
        let mut new = 0;
        let mut full = false;
        for (k, &i) in self.order.iter().enumerate() {
            if let Some(&j) = self.order.get(k + PREFETCH_AHEAD) {
                table.prefetch(self.meta[j as usize].0);
            }
            let i = i as usize;
            match table.insert(&self.succs[i * w..(i + 1) * w], self.meta[i].0, new < take) {
                Added::Found => {}
                Added::New => {
                    self.fresh[i] = true;
                    new += 1;
                }
                Added::Refused => {
                    full = true;
                    break;
                }
            }
        }
        drop(table);
        sh.reserved.fetch_sub(take - new, Ordering::Relaxed);
        // Number the new states and push them in chunks.
        let mut out = Chunk::new(w);
        for ((key, &(_, parent, t)), &is_new) in self.succs.chunks_exact(w).zip(&self.meta).zip(&self.fresh) {
            if !is_new {
                continue;
            }
            let id = (self.me as u64) << 32 | self.part.via.len() as u64;
            self.part.arena.extend_from_slice(key);
            self.part.parent.push(self.parents[parent as usize]);
            self.part.via.push(t);
            out.keys.extend_from_slice(key);
            out.ids.push(id);
            if out.ids.len() == CHUNK {
                push(sh, &self.deque, std::mem::replace(&mut out, Chunk::new(w)));
            }
        }
        if !out.ids.is_empty() {
            push(sh, &self.deque, out);
        }
        if full {
            return Err(HALT_LIMIT);
        }
        Ok(())
    }
}

/// Pushes a chunk onto a thread's deque, counted in `pending` first.
fn push(sh: &Shared<'_>, deque: &Deque<Chunk>, chunk: Chunk) {
    sh.pending.fetch_add(1, Ordering::AcqRel);
    deque.push(chunk);
}

/// Waits a little longer each time a thread finds no work: spins, then
/// yields, then sleeps (up to 0.8 ms), so that idle threads leave the cores
/// to working ones.
fn backoff(idle: u32) -> u32 {
    if idle < 6 {
        for _ in 0..1u32 << idle {
            spin_loop();
        }
    } else if idle < 12 {
        std::thread::yield_now();
    } else {
        std::thread::sleep(Duration::from_micros(50 << (idle - 12).min(4)));
    }
    idle.saturating_add(1)
}

/// Explores on `threads` threads; `None` means a place overflowed its field
/// (retry wider).
pub(super) fn run(c: &Compiled, net: &Net, max_states: usize, threads: usize) -> Option<StateSpace> {
    match c.layout.words {
        1 => run_with::<1>(c, net, max_states, threads),
        2 => run_with::<2>(c, net, max_states, threads),
        3 => run_with::<3>(c, net, max_states, threads),
        4 => run_with::<4>(c, net, max_states, threads),
        5 => run_with::<5>(c, net, max_states, threads),
        6 => run_with::<6>(c, net, max_states, threads),
        7 => run_with::<7>(c, net, max_states, threads),
        8 => run_with::<8>(c, net, max_states, threads),
        _ => run_with::<0>(c, net, max_states, threads),
    }
}

fn run_with<const W: usize>(c: &Compiled, net: &Net, max_states: usize, threads: usize) -> Option<StateSpace> {
    let k = threads.max(1);
    let deques: Vec<Deque<Chunk>> = (0..k).map(|_| Deque::new_fifo()).collect();
    let table = Table::new(INITIAL_CAP, c.layout.words);
    table.insert(&c.initial, hash_words(&c.initial), true);
    let sh = Shared {
        c,
        net,
        threads: k,
        table: RwLock::new(table),
        reserved: AtomicUsize::new(1),
        max_states,
        pending: AtomicUsize::new(1),
        halt: AtomicU8::new(HALT_NONE),
        stealers: deques.iter().map(Deque::stealer).collect(),
    };
    let mut workers: Vec<Worker<'_, W>> =
        deques.into_iter().enumerate().map(|(me, d)| Worker::new(me, &sh, d)).collect();
    // The initial state is thread 0's state 0, and its first chunk.
    let first = &mut workers[0];
    first.part.arena.extend_from_slice(&c.initial);
    first.part.parent.push(u64::MAX);
    first.part.via.push(0);
    first.deque.push(Chunk { keys: c.initial.clone(), ids: vec![0] });
    let parts: Vec<Part> = std::thread::scope(|s| {
        let handles: Vec<_> = workers.into_iter().map(|wk| s.spawn(move || wk.run())).collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    let stop = match sh.halt.load(Ordering::Relaxed) {
        HALT_WIDEN => return None,
        HALT_TOKENS => Some(StopReason::TokenOverflow),
        HALT_LIMIT => Some(StopReason::StateLimit),
        _ => None,
    };
    Some(assemble(c, net, parts, stop))
}

/// Concatenates the threads' states (thread 0 first, so that the initial
/// marking is state 0) and renumbers the ids.
fn assemble(c: &Compiled, net: &Net, parts: Vec<Part>, stop: Option<StopReason>) -> StateSpace {
    let mut offset = Vec::with_capacity(parts.len());
    let mut total = 0;
    for p in &parts {
        offset.push(total);
        total += p.via.len();
    }
    let global = |id: u64| (offset[(id >> 32) as usize] + (id & 0xFFFF_FFFF) as usize) as u32;
    let mut arena = Vec::with_capacity(total * c.layout.words);
    let mut parent = Vec::with_capacity(total);
    let mut via = Vec::with_capacity(total);
    let mut dead = Vec::new();
    let mut vanishing = vec![0u64; total.div_ceil(64)];
    let mut edges = 0;
    let mut stats = Stats::new(net);
    for p in &parts {
        arena.extend_from_slice(&p.arena);
        parent.extend(p.parent.iter().map(|&x| if x == u64::MAX { NO_PARENT } else { global(x) }));
        via.extend_from_slice(&p.via);
        dead.extend(p.dead.iter().map(|&x| global(x)));
        for &x in &p.vanishing {
            let g = global(x) as usize;
            vanishing[g / 64] |= 1 << (g % 64);
        }
        edges += p.edges;
        stats.merge(&p.stats);
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
