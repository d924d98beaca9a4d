//! State-space search (seed 7.3): breadth-first search (Extract 7.4),
//! uniform-cost search (the cost-aware variant the seed describes after
//! Extract 7.5) and A* with h_add or h_max.
//!
//! States are bitsets packed in one arena (`W` words each); a Zobrist hash is
//! updated incrementally from the parent's; an open-addressing table maps
//! states to node numbers. Successors are generated through watch lists: each
//! action is tested only when one designated precondition is true. An
//! expansion allocates nothing.

use crate::ground::Task;
use crate::heuristic::{BitIter, Kind, Relaxed, INF};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// Breadth-first: fewest actions (optimal with unit costs).
    Bfs,
    /// Uniform-cost (Dijkstra): cheapest plan.
    Ucs,
    /// A* with a heuristic: cheapest plan with h_max (admissible); h_add is
    /// not admissible, so A*/h_add plans are usually, not always, cheapest.
    Astar(Kind),
    /// Greedy best-first search on the heuristic alone (seed 7.3.1.2 names
    /// best-first search): no cost guarantee, fastest on large problems.
    Greedy(Kind),
}

impl Algorithm {
    /// Optimal in plan cost (BFS is optimal in length only).
    pub fn is_cost_optimal(self) -> bool {
        matches!(self, Algorithm::Ucs | Algorithm::Astar(Kind::Max))
    }
}

/// Search statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Stats {
    /// Distinct states stored.
    pub states: u64,
    pub expanded: u64,
    pub generated: u64,
    /// Heuristic evaluations.
    pub evaluated: u64,
    /// States pruned because the relaxation cannot reach the goal.
    pub dead_ends: u64,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// A plan: ground action indices, in order.
    Plan(Vec<u32>),
    /// The reachable state space holds no goal state.
    Unsolvable,
    /// `max_states` distinct states were stored without finding a plan.
    LimitReached,
}

#[derive(Clone, Debug)]
pub struct Result {
    pub outcome: Outcome,
    pub stats: Stats,
}

/// Default bound on stored states (about 1 GiB for 100-fact tasks).
pub const DEFAULT_MAX_STATES: u64 = 20_000_000;

/// The compiled search space of one task.
pub struct Space<'t> {
    task: &'t Task,
    w: usize,
    zobrist: Vec<u64>,
    /// Fact -> actions it watches, CSR.
    watch_start: Vec<u32>,
    watch: Vec<u32>,
    always: Vec<u32>,
    goal_mask: Vec<u64>,
    goal_neg_mask: Vec<u64>,
    /// Per action, CSR: (word, bits that must be set, bits that must be clear).
    cond_start: Vec<u32>,
    conds: Vec<(u32, u64, u64)>,
    /// Per action, CSR: (word, bits deleted, bits added).
    eff_start: Vec<u32>,
    effs: Vec<(u32, u64, u64)>,
}

/// Groups two fact lists by 64-bit word: (word, mask of the first, mask of the second).
fn by_word(a: &[u32], b: &[u32]) -> Vec<(u32, u64, u64)> {
    let mut v: Vec<(u32, u64, u64)> = Vec::new();
    for (&f, first) in a.iter().map(|f| (f, true)).chain(b.iter().map(|f| (f, false))) {
        let w = f >> 6;
        let bit = 1u64 << (f & 63);
        let k = match v.iter().position(|e| e.0 == w) {
            Some(k) => k,
            None => {
                v.push((w, 0, 0));
                v.len() - 1
            }
        };
        if first {
            v[k].1 |= bit;
        } else {
            v[k].2 |= bit;
        }
    }
    v.sort_unstable_by_key(|e| e.0);
    v
}

fn splitmix(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl<'t> Space<'t> {
    pub fn new(task: &'t Task) -> Space<'t> {
        let nf = task.num_facts();
        let w = nf.div_ceil(64).max(1);
        let mut seed = 0x5EED_u64;
        let zobrist = (0..nf).map(|_| splitmix(&mut seed)).collect();
        // Each action watches the precondition with the fewest watchers so far
        // (balancing the lists); actions without preconditions are always tested.
        let mut owner = vec![u32::MAX; task.actions.len()];
        let mut load = vec![0u32; nf];
        let mut always = Vec::new();
        for (ai, a) in task.actions.iter().enumerate() {
            match a.pre.iter().min_by_key(|&&f| load[f as usize]) {
                Some(&f) => {
                    owner[ai] = f;
                    load[f as usize] += 1;
                }
                None => always.push(ai as u32),
            }
        }
        let mut watch_start = vec![0u32; nf + 1];
        for f in 0..nf {
            watch_start[f + 1] = watch_start[f] + load[f];
        }
        let mut fill = watch_start.clone();
        let mut watch = vec![0u32; watch_start[nf] as usize];
        for (ai, &f) in owner.iter().enumerate() {
            if f != u32::MAX {
                watch[fill[f as usize] as usize] = ai as u32;
                fill[f as usize] += 1;
            }
        }
        let mut goal_mask = vec![0u64; w];
        for &g in &task.goal {
            goal_mask[(g >> 6) as usize] |= 1 << (g & 63);
        }
        let mut goal_neg_mask = vec![0u64; w];
        for &g in &task.goal_neg {
            goal_neg_mask[(g >> 6) as usize] |= 1 << (g & 63);
        }
        let (mut cond_start, mut conds, mut eff_start, mut effs) = (vec![0u32], Vec::new(), vec![0u32], Vec::new());
        for a in &task.actions {
            conds.extend(by_word(&a.pre, &a.pre_neg));
            cond_start.push(conds.len() as u32);
            effs.extend(by_word(&a.del, &a.add));
            eff_start.push(effs.len() as u32);
        }
        Space {
            task,
            w,
            zobrist,
            watch_start,
            watch,
            always,
            goal_mask,
            goal_neg_mask,
            cond_start,
            conds,
            eff_start,
            effs,
        }
    }

    /// Words per state.
    pub fn words(&self) -> usize {
        self.w
    }

    pub fn pack(&self, facts: &[u32]) -> Vec<u64> {
        let mut s = vec![0u64; self.w];
        for &f in facts {
            s[(f >> 6) as usize] |= 1 << (f & 63);
        }
        s
    }

    pub fn hash(&self, s: &[u64]) -> u64 {
        BitIter { words: s, w: 0, cur: s[0] }.fold(0, |h, f| h ^ self.zobrist[f as usize])
    }

    #[inline]
    pub fn is_goal(&self, s: &[u64]) -> bool {
        s.iter().zip(&self.goal_mask).all(|(x, g)| x & g == *g)
            && s.iter().zip(&self.goal_neg_mask).all(|(x, g)| x & g == 0)
    }

    #[inline]
    pub fn applicable(&self, s: &[u64], a: u32) -> bool {
        let (b, e) = (self.cond_start[a as usize] as usize, self.cond_start[a as usize + 1] as usize);
        self.conds[b..e].iter().all(|&(w, set, clear)| {
            let x = s[w as usize];
            x & set == set && x & clear == 0
        })
    }

    /// Calls `f` with every action applicable in `s`.
    #[inline]
    pub fn for_each_applicable(&self, s: &[u64], mut f: impl FnMut(u32)) {
        for fact in (BitIter { words: s, w: 0, cur: s[0] }) {
            let (b, e) = (self.watch_start[fact as usize] as usize, self.watch_start[fact as usize + 1] as usize);
            for &a in &self.watch[b..e] {
                if self.applicable(s, a) {
                    f(a);
                }
            }
        }
        for &a in &self.always {
            if self.applicable(s, a) {
                f(a);
            }
        }
    }

    /// Writes the successor of `s` by `a` into `out`; returns its hash.
    #[inline]
    pub fn apply(&self, s: &[u64], h: u64, a: u32, out: &mut [u64]) -> u64 {
        copy(out, s);
        let mut h = h;
        let (b, e) = (self.eff_start[a as usize] as usize, self.eff_start[a as usize + 1] as usize);
        for &(w, del, add) in &self.effs[b..e] {
            let old = out[w as usize];
            let new = (old & !del) | add;
            out[w as usize] = new;
            let mut diff = old ^ new;
            while diff != 0 {
                h ^= self.zobrist[(w as usize) * 64 + diff.trailing_zeros() as usize];
                diff &= diff - 1;
            }
        }
        h
    }
}

/// Word-by-word equality (short states: cheaper than a `memcmp` call).
#[inline(always)]
fn same(a: &[u64], b: &[u64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y)
}

/// Word-by-word copy (short states: cheaper than a `memmove` call).
#[inline(always)]
fn copy(dst: &mut [u64], src: &[u64]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

/// Distinct states with their search data.
struct Store {
    w: usize,
    words: Vec<u64>,
    nodes: Vec<Node>,
    /// Slots: `(low 32 bits of the hash) << 32 | node`, or `FREE`. The hash
    /// tag rejects most mismatches without touching the node.
    table: Vec<u64>,
    mask: usize,
    /// 64 - log2(table size): slots are the high bits of a multiplicative mix
    /// (Zobrist hashes are linear, their low bits alone cluster).
    shift: u32,
}

/// A search node: the state's hash, its best cost so far, its heuristic
/// value, and how it was reached.
#[derive(Clone, Copy)]
struct Node {
    hash: u64,
    g: u64,
    h: u64,
    parent: u32,
    via: u32,
}

#[inline(always)]
fn slot(hash: u64, shift: u32) -> usize {
    (hash.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize
}

const EMPTY: u32 = u32::MAX;
const FREE: u64 = u64::MAX;

impl Store {
    fn new(w: usize) -> Store {
        Store { w, words: Vec::new(), nodes: Vec::new(), table: vec![FREE; 1024], mask: 1023, shift: 64 - 10 }
    }
    fn len(&self) -> usize {
        self.nodes.len()
    }
    fn state(&self, id: u32) -> &[u64] {
        &self.words[id as usize * self.w..(id as usize + 1) * self.w]
    }
    fn grow(&mut self) {
        let n = self.table.len() * 2;
        self.table = vec![FREE; n];
        self.mask = n - 1;
        self.shift -= 1;
        for id in 0..self.len() {
            let h = self.nodes[id].hash;
            let mut i = slot(h, self.shift);
            while self.table[i] != FREE {
                i = (i + 1) & self.mask;
            }
            self.table[i] = (h << 32) | id as u64;
        }
    }
    /// The node of `s`, inserted if new: (id, inserted).
    #[inline]
    fn insert(&mut self, s: &[u64], hash: u64, parent: u32, via: u32, g: u64) -> (u32, bool) {
        if (self.len() + 1) * 2 > self.table.len() {
            self.grow();
        }
        let mut i = slot(hash, self.shift);
        let tag = hash << 32;
        loop {
            let e = self.table[i];
            if e == FREE {
                let nid = self.len() as u32;
                self.table[i] = tag | nid as u64;
                self.words.extend_from_slice(s);
                self.nodes.push(Node { hash, g, h: 0, parent, via });
                return (nid, true);
            }
            let id = e as u32;
            if e & !0xFFFF_FFFF == tag && same(self.state(id), s) {
                return (id, false);
            }
            i = (i + 1) & self.mask;
        }
    }
    /// [`Store::insert`] for states of `W` words (`W = 0`: any length).
    #[inline(always)]
    fn insert_w<const W: usize>(&mut self, s: &[u64], hash: u64, parent: u32, via: u32, g: u64) -> (u32, bool) {
        if W == 0 {
            return self.insert(s, hash, parent, via, g);
        }
        let s = &s[..W];
        if (self.len() + 1) * 2 > self.table.len() {
            self.grow();
        }
        let mut i = slot(hash, self.shift);
        let tag = hash << 32;
        loop {
            let e = self.table[i];
            if e == FREE {
                let nid = self.len() as u32;
                self.table[i] = tag | nid as u64;
                self.words.extend_from_slice(s);
                self.nodes.push(Node { hash, g, h: 0, parent, via });
                return (nid, true);
            }
            let id = e as usize & 0xFFFF_FFFF;
            if e & !0xFFFF_FFFF == tag && same(&self.words[id * W..id * W + W], s) {
                return (id as u32, false);
            }
            i = (i + 1) & self.mask;
        }
    }

    fn path(&self, mut id: u32) -> Vec<u32> {
        let mut out = Vec::new();
        while self.nodes[id as usize].parent != EMPTY {
            out.push(self.nodes[id as usize].via);
            id = self.nodes[id as usize].parent;
        }
        out.reverse();
        out
    }
}

/// Searches a plan from the task's initial state.
pub fn search(task: &Task, alg: Algorithm, max_states: u64) -> Result {
    search_from(task, &task.init, alg, max_states)
}

/// Searches a plan from the state made of `init` (fact indices of `task`).
pub fn search_from(task: &Task, init: &[u32], alg: Algorithm, max_states: u64) -> Result {
    let mut stats = Stats::default();
    if !task.goal_reachable {
        return Result { outcome: Outcome::Unsolvable, stats };
    }
    let sp = Space::new(task);
    let root = sp.pack(init);
    let hash = sp.hash(&root);
    let mut store = Store::new(sp.w);
    store.insert(&root, hash, EMPTY, EMPTY, 0);
    stats.states = 1;
    let outcome = match alg {
        Algorithm::Bfs => bfs(&sp, &mut store, &mut stats, max_states),
        Algorithm::Ucs => best_first(&sp, &mut store, &mut stats, max_states, None, false),
        Algorithm::Astar(k) => {
            let mut h = Relaxed::new(task, k);
            best_first(&sp, &mut store, &mut stats, max_states, Some(&mut h), false)
        }
        Algorithm::Greedy(k) => {
            let mut h = Relaxed::new(task, k);
            best_first(&sp, &mut store, &mut stats, max_states, Some(&mut h), true)
        }
    };
    stats.states = store.len() as u64;
    Result { outcome, stats }
}

fn bfs(sp: &Space<'_>, store: &mut Store, stats: &mut Stats, max_states: u64) -> Outcome {
    // States of one to four words get a copy of the loop where their length
    // is a constant (unrolled comparisons, copies and effect loops).
    match sp.w {
        1 => bfs_w::<1>(sp, store, stats, max_states),
        2 => bfs_w::<2>(sp, store, stats, max_states),
        3 => bfs_w::<3>(sp, store, stats, max_states),
        4 => bfs_w::<4>(sp, store, stats, max_states),
        _ => bfs_w::<0>(sp, store, stats, max_states),
    }
}

/// Breadth-first search over states of `W` words (`W = 0`: any length).
fn bfs_w<const W: usize>(sp: &Space<'_>, store: &mut Store, stats: &mut Stats, max_states: u64) -> Outcome {
    if sp.is_goal(store.state(0)) {
        return Outcome::Plan(Vec::new());
    }
    let w = if W == 0 { sp.w } else { W };
    debug_assert_eq!(w, sp.w);
    let mut cur_buf = vec![0u64; w];
    let mut child_buf = vec![0u64; w];
    let cur = &mut cur_buf[..w];
    let child = &mut child_buf[..w];
    let mut found = EMPTY;
    let mut next = 0usize;
    while next < store.len() {
        let id = next as u32;
        next += 1;
        copy(cur, &store.words[id as usize * w..id as usize * w + w]);
        let (h, g) = (store.nodes[id as usize].hash, store.nodes[id as usize].g);
        stats.expanded += 1;
        let mut limit = false;
        let cur: &[u64] = cur;
        sp.for_each_applicable(cur, |a| {
            if found != EMPTY || limit {
                return;
            }
            stats.generated += 1;
            let ch = sp.apply(cur, h, a, child);
            // An action that changes nothing leads back to the state itself.
            if ch == h && same(child, cur) {
                return;
            }
            let (cid, new) = store.insert_w::<W>(child, ch, id, a, g + sp.task.actions[a as usize].cost);
            if new {
                if sp.is_goal(child) {
                    found = cid;
                } else if store.len() as u64 >= max_states {
                    limit = true;
                }
            }
        });
        if found != EMPTY {
            return Outcome::Plan(store.path(found));
        }
        if limit {
            return Outcome::LimitReached;
        }
    }
    Outcome::Unsolvable
}

/// Uniform-cost search (no heuristic), A* (f = g + h) or greedy best-first (f = h).
fn best_first(
    sp: &Space<'_>,
    store: &mut Store,
    stats: &mut Stats,
    max_states: u64,
    mut heur: Option<&mut Relaxed>,
    greedy: bool,
) -> Outcome {
    let w = sp.w;
    let key = |g: u64, h: u64| if greedy { h } else { g.saturating_add(h) };
    // (f, h, id): lowest f, then lowest h, then oldest node.
    let mut open: BinaryHeap<Reverse<(u64, u64, u32)>> = BinaryHeap::new();
    let h0 = match heur.as_deref_mut() {
        Some(hr) => {
            stats.evaluated += 1;
            hr.eval(store.state(0))
        }
        None => 0,
    };
    if h0 == INF {
        stats.dead_ends += 1;
        return Outcome::Unsolvable;
    }
    store.nodes[0].h = h0;
    open.push(Reverse((h0, h0, 0)));
    let mut cur = vec![0u64; w];
    let mut child = vec![0u64; w];
    let mut closed: Vec<bool> = vec![false; 1];
    while let Some(Reverse((f, h, id))) = open.pop() {
        let g = store.nodes[id as usize].g;
        if f != key(g, h) || h != store.nodes[id as usize].h || closed[id as usize] {
            continue; // stale entry
        }
        copy(&mut cur, store.state(id));
        if sp.is_goal(&cur) {
            return Outcome::Plan(store.path(id));
        }
        closed[id as usize] = true;
        stats.expanded += 1;
        let hash = store.nodes[id as usize].hash;
        let mut limit = false;
        sp.for_each_applicable(&cur, |a| {
            stats.generated += 1;
            let ch = sp.apply(&cur, hash, a, &mut child);
            let ng = g.saturating_add(sp.task.actions[a as usize].cost);
            let (cid, new) = store.insert(&child, ch, id, a, ng);
            let c = cid as usize;
            if new {
                closed.push(false);
                let hv = match heur.as_deref_mut() {
                    Some(hr) => {
                        stats.evaluated += 1;
                        hr.eval(&child)
                    }
                    None => 0,
                };
                store.nodes[c].h = hv;
                if hv == INF {
                    stats.dead_ends += 1;
                    closed[c] = true;
                } else {
                    open.push(Reverse((key(ng, hv), hv, cid)));
                }
                if store.len() as u64 >= max_states {
                    limit = true;
                }
            } else if ng < store.nodes[c].g && store.nodes[c].h != INF && !greedy {
                // A cheaper path: update and (re)open.
                store.nodes[c].g = ng;
                store.nodes[c].parent = id;
                store.nodes[c].via = a;
                closed[c] = false;
                open.push(Reverse((key(ng, store.nodes[c].h), store.nodes[c].h, cid)));
            }
        });
        if limit {
            return Outcome::LimitReached;
        }
    }
    Outcome::Unsolvable
}
