//! Multi-threaded exploration without levels: the same set of states,
//! edges, dead and vanishing markings and bounds as the sequential engine,
//! in another order.
//!
//! The states are split into `k` partitions by hash, one per worker thread;
//! a worker alone owns its partition's table and arena, so no state is
//! guarded by a lock or an atomic. Each worker loops without any barrier:
//!
//! 1. it inserts the batches of successors other workers sent it (its
//!    inbox, a channel);
//! 2. it expands its own unexpanded states (its arena is its queue) and
//!    sorts their successors into one outbox per owner; a full outbox is sent
//!    as one batch (its own is inserted in place);
//! 3. when it has nothing left, it sends every partial outbox and waits for
//!    a batch.
//!
//! **Termination.** A global counter `pending` and a private counter
//! `local` per worker keep `pending + Σ local = queued states + batches sent
//! and not yet inserted`: sending a batch adds 1 to `pending`; inserting a
//! state adds 1 to `local`, expanding one or finishing a batch subtracts 1.
//! An idle worker (empty queue, outboxes sent) adds its `local` to
//! `pending`. Then `pending` equals, summed over the workers, the states
//! queued at their last such commit plus the batches they took since, plus
//! the batches in flight; it is 0 exactly when no work is left anywhere,
//! and stays 0, so a worker that reads 0 stops.
//!
//! **State limit.** Workers reserve state ids from a global count in
//! grants; one that needs an id when all are reserved stops every worker.
//! The space is then reported incomplete with at most `max_states` states,
//! possibly a few fewer (ids other workers had reserved and not used yet),
//! so a net with slightly fewer than `max_states` states may be reported
//! incomplete; a complete report is always exact.
//!
//! A state's parent is the state whose expansion first inserted it, so
//! [`StateSpace::path_to`] gives a real firing sequence, but not a shortest
//! one, and state ids follow the partitions, not BFS. Used when
//! [`super::Options::exact_order`] is false.

use std::sync::atomic::{AtomicI64, AtomicU8, AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::time::Duration;

use super::engine::{mix, Compiled, Overflow, Stats, Table, NO_PARENT};
use super::fixed::FixedTable;
use super::{StateSpace, StopReason};
use crate::model::{Net, TransitionId};

/// Successors per batch sent to another worker.
const SEND: usize = 1024;
/// States expanded between two looks at the inbox.
const EXPAND: usize = 64;
/// State ids a worker reserves from the global count at once.
const GRANT: usize = 4096;
/// Successors whose table slots are read ahead together.
const WINDOW: usize = 256;
/// How long an idle worker waits for a batch before it looks at the counters again.
const IDLE_WAIT: Duration = Duration::from_micros(200);

/// Successors found by one worker for one owner.
struct Batch {
    /// Worker that expanded the parents.
    from: u32,
    /// The packed successors, `words` words each.
    words: Vec<u64>,
    /// (linear hash, parent's local index, transition) per successor.
    meta: Vec<(u64, u32, u32)>,
}

impl Batch {
    fn new(from: usize, w: usize) -> Self {
        Batch { from: from as u32, words: Vec::with_capacity(SEND * w), meta: Vec::with_capacity(SEND) }
    }
}

/// A worker's hash set of packed markings: the slice-based [`Table`] for
/// any width, or a [`FixedTable`] for markings of `W` ≤ 8 words (fixed-size
/// compares and copies).
trait Keys: Send {
    fn create(words: usize) -> Self;
    fn len(&self) -> usize;
    fn capacity(&self) -> usize;
    fn grow(&mut self);
    fn prefetch(&self, mixed: u64);
    /// `Ok(local index)` or `Err(free slot)`; `key` has the layout's width.
    fn find(&self, key: &[u64], mixed: u64) -> Result<u32, usize>;
    fn insert_at(&mut self, pos: usize, key: &[u64], mixed: u64, idx: u32);
}

impl Keys for Table {
    fn create(words: usize) -> Self {
        Table::new(words)
    }
    fn len(&self) -> usize {
        self.len
    }
    fn capacity(&self) -> usize {
        Table::capacity(self)
    }
    fn grow(&mut self) {
        Table::grow(self)
    }
    #[inline]
    fn prefetch(&self, mixed: u64) {
        Table::prefetch(self, mixed)
    }
    #[inline]
    fn find(&self, key: &[u64], mixed: u64) -> Result<u32, usize> {
        Table::find(self, key, mixed)
    }
    #[inline]
    fn insert_at(&mut self, pos: usize, key: &[u64], mixed: u64, idx: u32) {
        Table::insert_at(self, pos, key, mixed, idx)
    }
}

impl<const W: usize> Keys for FixedTable<W> {
    fn create(_: usize) -> Self {
        FixedTable::new()
    }
    fn len(&self) -> usize {
        self.len
    }
    fn capacity(&self) -> usize {
        FixedTable::capacity(self)
    }
    fn grow(&mut self) {
        FixedTable::grow(self)
    }
    #[inline]
    fn prefetch(&self, mixed: u64) {
        FixedTable::prefetch(self, mixed)
    }
    #[inline]
    fn find(&self, key: &[u64], mixed: u64) -> Result<u32, usize> {
        // `run` picks `W` equal to the layout's width, the length of `key`.
        let mut k = [0u64; W];
        k.copy_from_slice(key);
        FixedTable::find(self, &k, mixed)
    }
    #[inline]
    fn insert_at(&mut self, pos: usize, key: &[u64], mixed: u64, idx: u32) {
        let mut k = [0u64; W];
        k.copy_from_slice(key);
        FixedTable::insert_at(self, pos, k, mixed, idx)
    }
}

/// Why the workers stop early; a larger value wins.
const HALT_NONE: u8 = 0;
const HALT_LIMIT: u8 = 1;
const HALT_TOKENS: u8 = 2;
const HALT_WIDEN: u8 = 3;

/// What the workers share.
struct Shared {
    /// See the module comment.
    pending: AtomicI64,
    /// One of the `HALT_*` values.
    halt: AtomicU8,
    /// State ids reserved so far.
    reserved: AtomicUsize,
    max_states: usize,
}

impl Shared {
    fn halted(&self) -> bool {
        self.halt.load(Ordering::Relaxed) != HALT_NONE
    }

    fn stop(&self, why: u8) {
        self.halt.fetch_max(why, Ordering::Relaxed);
    }
}

/// What a worker leaves: its partition.
struct Part {
    arena: Vec<u64>,
    /// Parent as `worker << 32 | local index` ([`u64::MAX`] for the initial state).
    parent: Vec<u64>,
    via: Vec<u32>,
    dead: Vec<u32>,
    vanishing: Vec<u32>,
    edges: u64,
    stats: Stats,
}

struct Worker<'a, T> {
    me: usize,
    c: &'a Compiled,
    net: &'a Net,
    sh: &'a Shared,
    table: T,
    hashes: Vec<u64>,
    part: Part,
    /// Next local state to expand.
    cursor: usize,
    /// Private share of the termination counter.
    local: i64,
    /// State ids reserved and not used yet.
    grant: usize,
    out: Vec<Batch>,
}

impl<'a, T: Keys> Worker<'a, T> {
    fn new(me: usize, k: usize, c: &'a Compiled, net: &'a Net, sh: &'a Shared) -> Self {
        let w = c.layout.words;
        Worker {
            me,
            c,
            net,
            sh,
            table: T::create(w),
            hashes: Vec::new(),
            part: Part {
                arena: Vec::new(),
                parent: Vec::new(),
                via: Vec::new(),
                dead: Vec::new(),
                vanishing: Vec::new(),
                edges: 0,
                stats: Stats::new(net),
            },
            cursor: 0,
            local: 0,
            grant: 0,
            out: (0..k).map(|_| Batch::new(me, w)).collect(),
        }
    }

    fn len(&self) -> usize {
        self.hashes.len()
    }

    /// Reserves state ids; false when the limit is reached. Grants shrink
    /// near the limit, so that few ids stay reserved and unused by other
    /// workers when one of them finds none left.
    fn reserve(&mut self) -> bool {
        let k = self.out.len();
        let mut cur = self.sh.reserved.load(Ordering::Relaxed);
        loop {
            if cur >= self.sh.max_states {
                return false;
            }
            let take = GRANT.min(((self.sh.max_states - cur) / (2 * k)).max(1));
            match self.sh.reserved.compare_exchange_weak(cur, cur + take, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => {
                    self.grant = take;
                    return true;
                }
                Err(now) => cur = now,
            }
        }
    }

    /// Inserts the new states of `b` (all owned by this worker).
    fn insert(&mut self, b: &Batch) -> Result<(), u8> {
        let w = self.c.layout.words;
        while (self.table.len() + b.meta.len()) * 4 > self.table.capacity() * 3 {
            self.table.grow();
        }
        let from = u64::from(b.from) << 32;
        for (win, metas) in b.meta.chunks(WINDOW).enumerate() {
            for m in metas {
                self.table.prefetch(mix(m.0));
            }
            for (j, &(h2, parent, t)) in metas.iter().enumerate() {
                let i = win * WINDOW + j;
                let key = &b.words[i * w..(i + 1) * w];
                let mixed = mix(h2);
                if let Err(pos) = self.table.find(key, mixed) {
                    if self.grant == 0 && !self.reserve() {
                        return Err(HALT_LIMIT);
                    }
                    self.grant -= 1;
                    let local = self.len() as u32;
                    self.table.insert_at(pos, key, mixed, local);
                    self.part.arena.extend_from_slice(key);
                    self.hashes.push(h2);
                    self.part.parent.push(from | u64::from(parent));
                    self.part.via.push(t);
                    self.local += 1;
                }
            }
        }
        Ok(())
    }

    /// Sends (or, for its own, inserts) the outbox of `dst`.
    fn flush(&mut self, dst: usize, tx: &[Sender<Batch>]) -> Result<(), u8> {
        if self.out[dst].meta.is_empty() {
            return Ok(());
        }
        let w = self.c.layout.words;
        if dst == self.me {
            let mut b = std::mem::replace(&mut self.out[dst], Batch { from: 0, words: Vec::new(), meta: Vec::new() });
            let r = self.insert(&b);
            b.words.clear();
            b.meta.clear();
            self.out[dst] = b;
            return r;
        }
        let b = std::mem::replace(&mut self.out[dst], Batch::new(self.me, w));
        self.sh.pending.fetch_add(1, Ordering::SeqCst);
        // A closed inbox means its worker has stopped, which only a halt does.
        let _ = tx[dst].send(b);
        Ok(())
    }

    /// Expands up to [`EXPAND`] queued states.
    fn expand(&mut self, ready: &mut Vec<TransitionId>, tx: &[Sender<Batch>]) -> Result<(), u8> {
        let c = self.c;
        let w = c.layout.words;
        let k = self.out.len();
        let end = self.len().min(self.cursor + EXPAND);
        while self.cursor < end {
            let s = self.cursor;
            self.cursor += 1;
            self.local -= 1;
            let cur = &self.part.arena[s * w..(s + 1) * w];
            self.part.stats.observe(&c.layout, cur);
            if c.ready_in(self.net, cur, ready) {
                self.part.vanishing.push(s as u32);
            }
            if ready.is_empty() {
                self.part.dead.push(s as u32);
                continue;
            }
            self.part.edges += ready.len() as u64;
            let h = self.hashes[s];
            for &t in ready.iter() {
                let h2 = h.wrapping_add(c.dhash[t.index()]);
                let dst = owner(mix(h2), k);
                let o = &mut self.out[dst];
                let base = o.words.len();
                o.words.extend_from_slice(&self.part.arena[s * w..(s + 1) * w]);
                match c.successor(&mut o.words[base..], t.index(), &mut self.part.stats.bounds) {
                    Ok(()) => {}
                    Err(Overflow::Widen) => return Err(HALT_WIDEN),
                    Err(Overflow::Stop) => return Err(HALT_TOKENS),
                }
                o.meta.push((h2, s as u32, t.0));
                if o.meta.len() >= SEND {
                    self.flush(dst, tx)?;
                }
            }
        }
        Ok(())
    }

    /// The worker's loop (see the module comment).
    fn run(mut self, rx: Receiver<Batch>, tx: Vec<Sender<Batch>>) -> Part {
        if let Err(why) = self.work(&rx, &tx) {
            self.sh.stop(why);
        }
        self.part
    }

    fn work(&mut self, rx: &Receiver<Batch>, tx: &[Sender<Batch>]) -> Result<(), u8> {
        let mut ready = Vec::new();
        let k = self.out.len();
        loop {
            if self.sh.halted() {
                return Ok(());
            }
            while let Ok(b) = rx.try_recv() {
                self.insert(&b)?;
                self.local -= 1;
            }
            if self.cursor < self.len() {
                self.expand(&mut ready, tx)?;
                continue;
            }
            for dst in 0..k {
                self.flush(dst, tx)?;
            }
            if self.cursor < self.len() {
                continue;
            }
            self.sh.pending.fetch_add(std::mem::take(&mut self.local), Ordering::SeqCst);
            if self.sh.pending.load(Ordering::SeqCst) == 0 {
                return Ok(());
            }
            match rx.recv_timeout(IDLE_WAIT) {
                Ok(b) => {
                    self.insert(&b)?;
                    self.local -= 1;
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
        }
    }
}

/// Worker owning a state: the high hash bits, reduced to `0..k` (the table
/// slot uses the low bits).
#[inline]
fn owner(mixed: u64, k: usize) -> usize {
    (((mixed >> 32) * k as u64) >> 32) as usize
}

/// Explores on `threads` workers; `None` means a place overflowed its field
/// (retry wider).
pub(super) fn run(c: &Compiled, net: &Net, max_states: usize, threads: usize) -> Option<StateSpace> {
    match c.layout.words {
        1 => run_with::<FixedTable<1>>(c, net, max_states, threads),
        2 => run_with::<FixedTable<2>>(c, net, max_states, threads),
        3 => run_with::<FixedTable<3>>(c, net, max_states, threads),
        4 => run_with::<FixedTable<4>>(c, net, max_states, threads),
        5 => run_with::<FixedTable<5>>(c, net, max_states, threads),
        6 => run_with::<FixedTable<6>>(c, net, max_states, threads),
        7 => run_with::<FixedTable<7>>(c, net, max_states, threads),
        8 => run_with::<FixedTable<8>>(c, net, max_states, threads),
        _ => run_with::<Table>(c, net, max_states, threads),
    }
}

fn run_with<T: Keys>(c: &Compiled, net: &Net, max_states: usize, threads: usize) -> Option<StateSpace> {
    let k = threads.max(1);
    let sh = Shared {
        pending: AtomicI64::new(1),
        halt: AtomicU8::new(HALT_NONE),
        reserved: AtomicUsize::new(1),
        max_states,
    };
    let mut workers: Vec<Worker<'_, T>> = (0..k).map(|me| Worker::new(me, k, c, net, &sh)).collect();
    let m0 = mix(c.initial_hash);
    let first = owner(m0, k);
    {
        let wk = &mut workers[first];
        if let Err(pos) = wk.table.find(&c.initial, m0) {
            wk.table.insert_at(pos, &c.initial, m0, 0);
        }
        wk.part.arena.extend_from_slice(&c.initial);
        wk.hashes.push(c.initial_hash);
        wk.part.parent.push(u64::MAX);
        wk.part.via.push(0);
    }
    let (txs, rxs): (Vec<Sender<Batch>>, Vec<Receiver<Batch>>) = (0..k).map(|_| channel()).unzip();
    let parts: Vec<Part> = std::thread::scope(|s| {
        let handles: Vec<_> = workers
            .into_iter()
            .zip(rxs)
            .map(|(wk, rx)| {
                let tx = txs.clone();
                s.spawn(move || wk.run(rx, tx))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    let stop = match sh.halt.load(Ordering::Relaxed) {
        HALT_WIDEN => return None,
        HALT_TOKENS => Some(StopReason::TokenOverflow),
        HALT_LIMIT => Some(StopReason::StateLimit),
        _ => None,
    };
    Some(assemble(c, net, parts, first, stop))
}

/// Concatenates the partitions, the one holding the initial marking first
/// (so that it is state 0).
fn assemble(c: &Compiled, net: &Net, parts: Vec<Part>, first: usize, stop: Option<StopReason>) -> StateSpace {
    let w = c.layout.words;
    let k = parts.len();
    let order: Vec<usize> = std::iter::once(first).chain((0..k).filter(|&i| i != first)).collect();
    let mut offset = vec![0usize; k];
    let mut total = 0;
    for &i in &order {
        offset[i] = total;
        total += parts[i].via.len();
    }
    let mut arena = Vec::with_capacity(total * w);
    let mut parent = Vec::with_capacity(total);
    let mut via = Vec::with_capacity(total);
    let mut dead = Vec::new();
    let mut vanishing = vec![0u64; total.div_ceil(64)];
    let mut edges = 0;
    let mut stats = Stats::new(net);
    for &i in &order {
        let p = &parts[i];
        let base = offset[i];
        arena.extend_from_slice(&p.arena);
        parent.extend(p.parent.iter().map(|&x| match x {
            u64::MAX => NO_PARENT,
            x => (offset[(x >> 32) as usize] + (x & 0xFFFF_FFFF) as usize) as u32,
        }));
        via.extend_from_slice(&p.via);
        dead.extend(p.dead.iter().map(|&l| (base + l as usize) as u32));
        for &l in &p.vanishing {
            let g = base + l as usize;
            vanishing[g / 64] |= 1 << (g % 64);
        }
        edges += p.edges;
        stats.merge(&p.stats);
    }
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
