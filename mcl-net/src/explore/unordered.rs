//! Multi-threaded exploration without levels: the same set of states,
//! edges, dead and vanishing markings and bounds as the sequential engine,
//! in another order.
//!
//! * **One shared table.** Every visited marking is in one lock-free
//!   open-addressing table ([`Table`]) whose slots hold nothing but the
//!   packed marking, as the sequential search's key-only table. A thread
//!   adds a marking by a compare-and-swap: of the whole slot for one-word
//!   markings; of the first word from free to claimed for wider ones, which
//!   then write the other words and publish the first (release ordering).
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
//!   lock); this happens about log2(states) times. The new table comes
//!   zeroed from the allocator, so its pages are cleared by the threads
//!   that first touch them.
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
use std::sync::{Mutex, PoisonError, RwLock, RwLockReadGuard};
use std::time::Duration;

use crossbeam_deque::{Steal, Stealer, Worker as Deque};
use rustc_hash::FxHashSet;

use super::engine::{Compiled, Overflow, Stats, NO_PARENT};
use super::fixed::hash_words;
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

/// First word of a free slot.
const EMPTY: u64 = 0;
/// First word of a slot claimed by a thread that is writing its marking.
const BUSY: u64 = 1;
/// Markings wider than a word keep their first word as `word ^ SALT`, so
/// that a stored marking never looks free or claimed; the (unlikely)
/// markings whose first word is `SALT` or `SALT ^ 1` go to a side set.
const SALT: u64 = 0xA5C3_96E1_4D2B_7F08;

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

/// The shared set of visited markings: open addressing, linear probing,
/// slot `i` is `slots[i * words..]` and holds nothing but a marking, as in
/// the sequential search's key-only table.
///
/// A one-word marking is added by a compare-and-swap of its slot from 0 (the
/// all-zero marking is a flag aside). A wider one claims its slot by a
/// compare-and-swap of the first word from [`EMPTY`] to [`BUSY`], writes the
/// other words, then publishes the first one (xor [`SALT`]) with release
/// ordering; a reader that meets a claimed slot waits for it (a few stores
/// away).
struct Table {
    slots: Vec<AtomicU64>,
    words: usize,
    mask: usize,
    /// One-word markings: whether the all-zero marking is in the table.
    zero: AtomicBool,
    /// Wider markings whose salted first word would read as free or claimed.
    side: Mutex<FxHashSet<Vec<u64>>>,
}

impl Table {
    fn new(cap: usize, words: usize) -> Self {
        // Zeroed by the allocator (fresh pages for a large table), so that
        // the pages are first touched, and cleared, by the threads that
        // rehash and fill it, not all by the one that grows it.
        let mut slots: Vec<AtomicU64> = bytemuck::zeroed_vec(cap * words);
        hw::advise_huge(&mut slots);
        Table { slots, words, mask: cap - 1, zero: AtomicBool::new(false), side: Mutex::default() }
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

    /// Prefetches the home slot of `hash`: its first word, and its last
    /// one when the slot may straddle two cache lines (3 words or more).
    #[inline(always)]
    fn prefetch(&self, hash: u64) {
        let base = self.home(hash) * self.words;
        if let Some(a) = self.slots.get(base) {
            hw::prefetch(a);
        }
        if self.words > 2 {
            if let Some(b) = self.slots.get(base + self.words - 1) {
                hw::prefetch(b);
            }
        }
    }

    /// Adds `key` (of the table's width, hashed by [`hash_words`]) unless it
    /// is present; with `room` false a new key is not added but
    /// [`Added::Refused`]. The table must have a free slot.
    #[inline(always)]
    fn insert(&self, key: &[u64], hash: u64, room: bool) -> Added {
        let Some((&k0, rest)) = key.split_first() else {
            return Added::Found;
        };
        if rest.is_empty() {
            return self.insert_word(k0, hash, room);
        }
        let first = k0 ^ SALT;
        if first <= BUSY {
            return self.insert_side(key, room);
        }
        let mut pos = self.home(hash);
        loop {
            let base = pos * self.words;
            let head = &self.slots[base];
            let tail = &self.slots[base + 1..base + key.len()];
            let mut m = head.load(Ordering::Acquire);
            if m == EMPTY {
                if !room {
                    return Added::Refused;
                }
                match head.compare_exchange(EMPTY, BUSY, Ordering::Acquire, Ordering::Acquire) {
                    Ok(_) => {
                        for (s, &k) in tail.iter().zip(rest) {
                            s.store(k, Ordering::Relaxed);
                        }
                        head.store(first, Ordering::Release);
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
                m = head.load(Ordering::Acquire);
            }
            if m == first && tail.iter().zip(rest).all(|(s, &k)| s.load(Ordering::Relaxed) == k) {
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

    /// [`Table::insert`] for the markings kept in the side set.
    #[cold]
    fn insert_side(&self, key: &[u64], room: bool) -> Added {
        let mut side = self.side.lock().unwrap_or_else(PoisonError::into_inner);
        if side.contains(key) {
            Added::Found
        } else if !room {
            Added::Refused
        } else {
            side.insert(key.to_vec());
            Added::New
        }
    }

    /// A table twice as large with the same markings, rehashed on
    /// `threads` threads when it is large.
    fn grown(&mut self, threads: usize) -> Table {
        let cap = self.capacity();
        let mut new = Table::new(cap * 2, self.words);
        if cap < PARALLEL_REHASH || threads == 1 {
            self.rehash_into(0..cap, &new);
        } else {
            let (old, to) = (&*self, &new);
            std::thread::scope(|s| {
                for i in 0..threads {
                    s.spawn(move || old.rehash_into(cap * i / threads..cap * (i + 1) / threads, to));
                }
            });
        }
        new.zero = AtomicBool::new(self.zero.load(Ordering::Relaxed));
        new.side = std::mem::take(&mut self.side);
        new
    }

    /// Adds the entries of slots `range` to `to` (no thread is inserting
    /// into `self`; the zero flag and the side set are moved by the caller).
    fn rehash_into(&self, range: std::ops::Range<usize>, to: &Table) {
        let w = self.words;
        let mut key = vec![0u64; w];
        for pos in range {
            let base = pos * w;
            let m = self.slots[base].load(Ordering::Relaxed);
            if m == EMPTY {
                continue;
            }
            key[0] = if w == 1 { m } else { m ^ SALT };
            for (k, s) in key[1..].iter_mut().zip(&self.slots[base + 1..base + w]) {
                *k = s.load(Ordering::Relaxed);
            }
            to.insert(&key, hash_words(&key), true);
        }
    }
}

/// Why the workers stop early; a larger value wins.
const HALT_NONE: u8 = 0;
const HALT_LIMIT: u8 = 1;
const HALT_TOKENS: u8 = 2;
const HALT_WIDEN: u8 = 3;
/// A thread panicked: the others stop, and the panic reaches the caller.
const HALT_PANIC: u8 = 4;

/// Stops every thread if the thread holding it unwinds, so that none waits
/// for work the panicking one will never finish.
struct HaltOnPanic<'a>(&'a Shared<'a>);

impl Drop for HaltOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.stop(HALT_PANIC);
        }
    }
}

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
        let new = g.grown(self.threads);
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
        let _guard = HaltOnPanic(self.sh);
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
/// marking is state 0) and renumbers the ids; each thread's part is copied
/// by a thread of its own.
fn assemble(c: &Compiled, net: &Net, parts: Vec<Part>, stop: Option<StopReason>) -> StateSpace {
    let w = c.layout.words;
    let mut offset = Vec::with_capacity(parts.len());
    let mut total = 0;
    for p in &parts {
        offset.push(total);
        total += p.via.len();
    }
    let global = |id: u64| (offset[(id >> 32) as usize] + (id & 0xFFFF_FFFF) as usize) as u32;
    let mut arena = vec![0u64; total * w];
    let mut parent = vec![0u32; total];
    let mut via = vec![0u32; total];
    std::thread::scope(|s| {
        let (mut a, mut pa, mut v) = (&mut arena[..], &mut parent[..], &mut via[..]);
        for p in &parts {
            let n = p.via.len();
            let (a1, a2) = std::mem::take(&mut a).split_at_mut(n * w);
            let (p1, p2) = std::mem::take(&mut pa).split_at_mut(n);
            let (v1, v2) = std::mem::take(&mut v).split_at_mut(n);
            (a, pa, v) = (a2, p2, v2);
            let global = &global;
            s.spawn(move || {
                a1.copy_from_slice(&p.arena);
                for (d, &x) in p1.iter_mut().zip(&p.parent) {
                    *d = if x == u64::MAX { NO_PARENT } else { global(x) };
                }
                v1.copy_from_slice(&p.via);
            });
        }
    });
    let mut dead = Vec::new();
    let mut vanishing = vec![0u64; total.div_ceil(64)];
    let mut edges = 0;
    let mut stats = Stats::new(net);
    for p in &parts {
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

#[cfg(test)]
mod tests {
    use super::{hash_words, Added, Table, SALT};

    fn add(t: &Table, key: &[u64], room: bool) -> Added {
        t.insert(key, hash_words(key), room)
    }

    #[test]
    fn the_table_keeps_every_marking_across_growth() {
        for words in [1, 2, 3] {
            let mut t = Table::new(16, words);
            // Ordinary keys, the zero key, and (wider keys) the first words
            // that go to the side set.
            let mut keys: Vec<Vec<u64>> = (1..=10u64).map(|i| vec![i * 0x1234_5678_9ABC; words]).collect();
            keys.push(vec![0; words]);
            if words > 1 {
                keys.push([vec![SALT], vec![7; words - 1]].concat());
                keys.push([vec![SALT ^ 1], vec![9; words - 1]].concat());
            }
            for k in &keys {
                assert!(add(&t, k, false) == Added::Refused, "{words} words: {k:?} refused without room");
                assert!(add(&t, k, true) == Added::New, "{words} words: {k:?} new");
                assert!(add(&t, k, false) == Added::Found, "{words} words: {k:?} found");
            }
            for threads in [1, 2] {
                t = t.grown(threads);
                assert_eq!(t.capacity(), 32 << (threads - 1));
                for k in &keys {
                    assert!(add(&t, k, false) == Added::Found, "{words} words: {k:?} kept");
                }
                assert!(add(&t, &vec![5; words], false) == Added::Refused);
            }
        }
    }
}
