//! Relaxation heuristics (seed 7.3.1.2, Definition 7.3.1): delete effects
//! ignored, Δ(s, f) = 0 for f ∈ s, Δ(s, f) = min over achievers a of
//! cost(a) + Δ(s, pre(a)). h_add (Bonet & Geffner) sums the Δ of a set of
//! facts, eq. (7.5); h_max takes their maximum and is admissible. Both are
//! computed by a generalised Dijkstra over facts with per-action counters.
//! Negative preconditions are ignored (a further relaxation).

use crate::ground::Task;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Infinite cost: the goal is unreachable even in the relaxation (a dead end).
pub const INF: u64 = u64::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// h_add: sum.
    Add,
    /// h_max: maximum.
    Max,
}

/// Precomputed structure and scratch buffers: evaluating a state allocates nothing.
pub struct Relaxed {
    kind: Kind,
    /// Fact -> actions with that (positive) precondition, CSR.
    pre_of_start: Vec<u32>,
    pre_of: Vec<u32>,
    pre_count: Vec<u32>,
    no_pre: Vec<u32>,
    add_start: Vec<u32>,
    add: Vec<u32>,
    cost: Vec<u64>,
    goal: Vec<u32>,
    is_goal: Vec<bool>,
    dist: Vec<u64>,
    done: Vec<bool>,
    counter: Vec<u32>,
    acc: Vec<u64>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl Relaxed {
    pub fn new(task: &Task, kind: Kind) -> Relaxed {
        let nf = task.num_facts();
        let na = task.actions.len();
        let mut deg = vec![0u32; nf + 1];
        for a in &task.actions {
            for &f in a.pre.iter() {
                deg[f as usize + 1] += 1;
            }
        }
        for i in 0..nf {
            deg[i + 1] += deg[i];
        }
        let mut pre_of = vec![0u32; deg[nf] as usize];
        let mut fill = deg.clone();
        let mut no_pre = Vec::new();
        for (ai, a) in task.actions.iter().enumerate() {
            if a.pre.is_empty() {
                no_pre.push(ai as u32);
            }
            for &f in a.pre.iter() {
                pre_of[fill[f as usize] as usize] = ai as u32;
                fill[f as usize] += 1;
            }
        }
        let mut add_start = Vec::with_capacity(na + 1);
        let mut add = Vec::new();
        add_start.push(0);
        for a in &task.actions {
            add.extend_from_slice(&a.add);
            add_start.push(add.len() as u32);
        }
        let mut is_goal = vec![false; nf];
        for &g in &task.goal {
            is_goal[g as usize] = true;
        }
        Relaxed {
            kind,
            pre_of_start: deg,
            pre_of,
            pre_count: task.actions.iter().map(|a| a.pre.len() as u32).collect(),
            no_pre,
            add_start,
            add,
            cost: task.actions.iter().map(|a| a.cost).collect(),
            goal: task.goal.clone(),
            is_goal,
            dist: vec![INF; nf],
            done: vec![false; nf],
            counter: vec![0; na],
            acc: vec![0; na],
            heap: BinaryHeap::new(),
        }
    }

    #[inline]
    fn combine(&self, a: u64, b: u64) -> u64 {
        match self.kind {
            Kind::Add => a.saturating_add(b),
            Kind::Max => a.max(b),
        }
    }

    fn fire(&mut self, a: usize, v: u64) {
        for k in self.add_start[a] as usize..self.add_start[a + 1] as usize {
            let f = self.add[k] as usize;
            if v < self.dist[f] {
                self.dist[f] = v;
                self.heap.push(Reverse((v, f as u32)));
            }
        }
    }

    /// The heuristic value of the state given by its true facts.
    pub fn eval_facts(&mut self, facts: impl Iterator<Item = u32>) -> u64 {
        if self.goal.is_empty() {
            return 0;
        }
        self.dist.fill(INF);
        self.done.fill(false);
        self.counter.copy_from_slice(&self.pre_count);
        self.acc.fill(0);
        self.heap.clear();
        for f in facts {
            self.dist[f as usize] = 0;
            self.heap.push(Reverse((0, f)));
        }
        for i in 0..self.no_pre.len() {
            let a = self.no_pre[i] as usize;
            let c = self.cost[a];
            self.fire(a, c);
        }
        let mut goals_left = self.goal.len();
        while let Some(Reverse((d, f))) = self.heap.pop() {
            let fu = f as usize;
            if self.done[fu] || d > self.dist[fu] {
                continue;
            }
            self.done[fu] = true;
            if self.is_goal[fu] {
                goals_left -= 1;
                if goals_left == 0 {
                    break;
                }
            }
            for k in self.pre_of_start[fu] as usize..self.pre_of_start[fu + 1] as usize {
                let a = self.pre_of[k] as usize;
                self.acc[a] = self.combine(self.acc[a], d);
                self.counter[a] -= 1;
                if self.counter[a] == 0 {
                    let v = self.acc[a].saturating_add(self.cost[a]);
                    self.fire(a, v);
                }
            }
        }
        let mut h = 0u64;
        for &g in &self.goal {
            let d = self.dist[g as usize];
            if d == INF {
                return INF;
            }
            h = self.combine(h, d);
        }
        h
    }

    /// The heuristic value of a packed state (bit i = fact i).
    pub fn eval(&mut self, state: &[u64]) -> u64 {
        let it = BitIter { words: state, w: 0, cur: state.first().copied().unwrap_or(0) };
        self.eval_facts(it)
    }
}

/// Iterates the set bits of a packed state.
pub struct BitIter<'a> {
    pub words: &'a [u64],
    pub w: usize,
    pub cur: u64,
}

impl Iterator for BitIter<'_> {
    type Item = u32;
    #[inline]
    fn next(&mut self) -> Option<u32> {
        loop {
            if self.cur != 0 {
                let b = self.cur.trailing_zeros();
                self.cur &= self.cur - 1;
                return Some((self.w * 64) as u32 + b);
            }
            self.w += 1;
            if self.w >= self.words.len() {
                return None;
            }
            self.cur = self.words[self.w];
        }
    }
}
