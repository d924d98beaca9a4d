//! The compiler's promise on outcomes: for random well-formed missions (the
//! ten control structures, deep nesting, shared tasks, parallel calls of one
//! task, time-outs, labels, calls inside `while` and `if` conditions) and a
//! fixed script for every call (its outcome and duration at each of its
//! activations), the compiled net played by the player (`mcl_runtime`)
//! against a scripted vehicle ends with the result, and enables primitives
//! in the order, that an independent reference interpreter of the mission's
//! syntax tree gives.
//!
//! The reference is written from the seed's prose (4.5.3, Appendix B) and
//! the protocol of docs/blocks.md, not from the nets: a call waits for its
//! task while another call holds it; a call gives its task back once
//! everything its end causes at that instant is done; a parallel-or or a
//! monitor that decides aborts its other blocks at once (their calls never
//! start afterwards). Time is discrete (durations are whole seconds), so a
//! run is a sequence of instants; the observable trace is, for each instant,
//! the set of calls whose primitive is enabled then. The only choices left
//! are which of several calls waiting for one task gets it: the reference
//! enumerates them, and every run of the player (several seeds) must be one
//! of its runs. Instants where two answers arrive at once are ambiguous by
//! nature (the player resolves time-outs first); such cases are skipped and
//! counted, and must stay a small fraction.

use mcl_compiler::compile::compile_file;
use mcl_compiler::{check_file, Database};
use mcl_runtime::player::{Outcome, Output, Player, PlayerOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Arc;

const VEHICLE: &str = r#"
actions {
    enableA = APrimitive( c: enable, v: x ); disableA = APrimitive( c: disable, v: x );
    enableB = BPrimitive( c: enable, v: x ); disableB = BPrimitive( c: disable, v: x );
    enableT = TPrimitive( c: enable, v: x ); disableT = TPrimitive( c: disable, v: x );
}
events { aOk; aFail; bOk; bFail; tOk; tFail; }
tasks {
    A( x ): AchieveOneGoal { a: enableA -> T0; a: disableA -> T1, T6, T7; e: aOk -> T2; e: aFail -> T3; }
    B( x ): AchieveOneGoal { a: enableB -> T0; a: disableB -> T1, T6, T7; e: bOk -> T2; e: bFail -> T3; }
    Timed( x, timeout ): AchieveOneGoalTimed { a: enableT -> T0; a: disableT -> T1, T6, T7; e: tOk -> T2; e: tFail -> T3; }
}
"#;

/// The shape of a random mission (calls are numbered afterwards).
#[derive(Clone, Debug)]
enum Shape {
    Call(u8),
    Seq(Vec<Shape>),
    If(Box<Shape>, Box<Shape>, Option<Box<Shape>>),
    /// The condition is one call, scripted to fail in the end.
    While(u8, Box<Shape>),
    Try(Box<Shape>, Box<Shape>),
    Not(Box<Shape>),
    And(Vec<Shape>),
    Or(Vec<Shape>),
    /// Monitored block, handlers (while_condition?, condition, action).
    Monitor(Box<Shape>, Vec<(bool, Shape, Shape)>),
}

fn shape() -> impl Strategy<Value = Shape> {
    let leaf = (0u8..3).prop_map(Shape::Call);
    leaf.prop_recursive(4, 24, 3, |inner| {
        let b = || inner.clone().prop_map(Box::new);
        prop_oneof![
            prop::collection::vec(inner.clone(), 2..4).prop_map(Shape::Seq),
            (b(), b(), prop::option::of(b())).prop_map(|(c, t, e)| Shape::If(c, t, e)),
            ((0u8..3), b()).prop_map(|(c, body)| Shape::While(c, body)),
            (b(), b()).prop_map(|(x, y)| Shape::Try(x, y)),
            b().prop_map(Shape::Not),
            prop::collection::vec(inner.clone(), 2..4).prop_map(Shape::And),
            prop::collection::vec(inner.clone(), 2..4).prop_map(Shape::Or),
            (b(), prop::collection::vec((any::<bool>(), inner.clone(), inner.clone()), 1..3))
                .prop_map(|(m, hs)| Shape::Monitor(m, hs)),
        ]
    })
}

/// What a call does at one activation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Answer {
    Ok(u64),
    Fail(u64),
    Never,
}

/// A mission node; calls carry their script.
#[derive(Clone, Debug)]
enum Node {
    Call { id: u32, task: u8, timeout: u64, label: bool, script: Vec<Answer> },
    Seq(Vec<usize>),
    If(usize, usize, Option<usize>),
    While(usize, usize),
    Try(usize, usize),
    Not(usize),
    And(Vec<usize>),
    Or(Vec<usize>),
    Monitor(usize, Vec<(bool, usize, usize)>),
}

struct Mission {
    nodes: Vec<Node>,
    parent: Vec<Option<usize>>,
    root: usize,
    calls: Vec<usize>,
}

/// A tiny deterministic generator for scripts.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

impl Mission {
    fn new(s: &Shape, seed: u64) -> Mission {
        let mut m = Mission { nodes: Vec::new(), parent: Vec::new(), root: 0, calls: Vec::new() };
        let mut rng = Rng(seed);
        m.root = m.add(s, &mut rng);
        m
    }

    fn call(&mut self, task: u8, rng: &mut Rng, cond: Option<bool>) -> usize {
        let id = self.calls.len() as u32 + 1;
        let n = 1 + rng.below(3) as usize;
        let mut script = Vec::new();
        for _ in 0..n {
            let d = 1 + rng.below(400);
            script.push(match rng.below(10) {
                0..=5 => Answer::Ok(d),
                6..=8 => Answer::Fail(d),
                _ => Answer::Never,
            });
        }
        match cond {
            // A while condition ends the loop in the end.
            Some(true) => *script.last_mut().unwrap() = Answer::Fail(1 + rng.below(400)),
            // A while_condition of a monitor stops triggering in the end.
            Some(false) => *script.last_mut().unwrap() = Answer::Never,
            None => {}
        }
        let timeout = 1 + rng.below(400);
        let label = rng.below(3) == 0;
        let i = self.push(Node::Call { id, task, timeout, label, script });
        self.calls.push(i);
        i
    }

    fn push(&mut self, n: Node) -> usize {
        self.nodes.push(n);
        self.parent.push(None);
        self.nodes.len() - 1
    }

    fn adopt(&mut self, node: usize, kids: &[usize]) -> usize {
        for &k in kids {
            self.parent[k] = Some(node);
        }
        node
    }

    fn add(&mut self, s: &Shape, rng: &mut Rng) -> usize {
        match s {
            Shape::Call(t) => self.call(*t, rng, None),
            Shape::Seq(v) => {
                let kids: Vec<usize> = v.iter().map(|x| self.add(x, rng)).collect();
                let n = self.push(Node::Seq(kids.clone()));
                self.adopt(n, &kids)
            }
            Shape::If(c, t, e) => {
                let c = self.add(c, rng);
                let t = self.add(t, rng);
                let e = e.as_ref().map(|e| self.add(e, rng));
                let n = self.push(Node::If(c, t, e));
                let mut kids = vec![c, t];
                kids.extend(e);
                self.adopt(n, &kids)
            }
            Shape::While(c, body) => {
                let c = self.call(*c, rng, Some(true));
                let b = self.add(body, rng);
                let n = self.push(Node::While(c, b));
                self.adopt(n, &[c, b])
            }
            Shape::Try(x, y) => {
                let x = self.add(x, rng);
                let y = self.add(y, rng);
                let n = self.push(Node::Try(x, y));
                self.adopt(n, &[x, y])
            }
            Shape::Not(x) => {
                let x = self.add(x, rng);
                let n = self.push(Node::Not(x));
                self.adopt(n, &[x])
            }
            Shape::And(v) | Shape::Or(v) => {
                let kids: Vec<usize> = v.iter().map(|x| self.add(x, rng)).collect();
                let n = self.push(if matches!(s, Shape::And(_)) {
                    Node::And(kids.clone())
                } else {
                    Node::Or(kids.clone())
                });
                self.adopt(n, &kids)
            }
            Shape::Monitor(body, hs) => {
                let b = self.add(body, rng);
                let mut kids = vec![b];
                let mut handlers = Vec::new();
                for (w, c, a) in hs {
                    // A while_condition restarts the monitor: its condition is one call that stops triggering.
                    let c = if *w {
                        let t = match c {
                            Shape::Call(t) => *t,
                            _ => 0,
                        };
                        self.call(t, rng, Some(false))
                    } else {
                        self.add(c, rng)
                    };
                    let a = self.add(a, rng);
                    kids.push(c);
                    kids.push(a);
                    handlers.push((*w, c, a));
                }
                let n = self.push(Node::Monitor(b, handlers));
                self.adopt(n, &kids)
            }
        }
    }

    fn text(&self, n: usize) -> String {
        match &self.nodes[n] {
            Node::Call { id, task, timeout, label, .. } => {
                let call = match task {
                    0 => format!("A( {id} )"),
                    1 => format!("B( {id} )"),
                    _ => format!("Timed( {id}, {timeout} )"),
                };
                if *label {
                    format!("{call} : l{id}")
                } else {
                    call
                }
            }
            Node::Seq(v) => v.iter().map(|&k| self.text(k)).collect::<Vec<_>>().join(" ; "),
            Node::If(c, t, None) => format!("if ( {} ) {{ {} }}", self.text(*c), self.text(*t)),
            Node::If(c, t, Some(e)) => {
                format!("if ( {} ) {{ {} }} else {{ {} }}", self.text(*c), self.text(*t), self.text(*e))
            }
            Node::While(c, b) => format!("while ( {} ) {{ {} }}", self.text(*c), self.text(*b)),
            Node::Try(x, y) => format!("try {{ {} }} catch {{ {} }}", self.text(*x), self.text(*y)),
            Node::Not(x) => format!("not ( {} )", self.text(*x)),
            Node::And(v) | Node::Or(v) => {
                let op = if matches!(self.nodes[n], Node::And(_)) { " } and { " } else { " } or { " };
                format!("parallel {{ {} }}", v.iter().map(|&k| self.text(k)).collect::<Vec<_>>().join(op))
            }
            Node::Monitor(b, hs) => {
                let mut s = format!("monitor {{ {} }}", self.text(*b));
                for (w, c, a) in hs {
                    let kw = if *w { "while_condition" } else { "condition" };
                    s.push_str(&format!(" {kw} ( {} ) do {{ {} }}", self.text(*c), self.text(*a)));
                }
                s
            }
        }
    }
}

/// A run: per instant, the calls enabled then (sorted); and the result.
type Trace = (Vec<(u64, Vec<u32>)>, &'static str);

/// Why a case is not compared.
#[derive(Debug)]
enum Skip {
    /// Two answers (or an answer and a time-out) at the same instant.
    Tie,
    /// Too many activations or choices to enumerate.
    Size,
}

// ---------------------------------------------------------------------------
// The reference interpreter.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CallState {
    Idle,
    Waiting,
    Running,
}

struct Sim<'m> {
    m: &'m Mission,
    /// Choices to replay, and the number of alternatives seen at each.
    choices: Vec<usize>,
    seen: Vec<usize>,
    active: Vec<bool>,
    /// Per node: branches still running (And), the outcome so far, open (Or/Monitor).
    pending: Vec<usize>,
    failed: Vec<bool>,
    open: Vec<bool>,
    /// Monitor: which part runs: None (parallel part) or Some(handler).
    doing: Vec<Option<usize>>,
    seq_at: Vec<usize>,
    calls: Vec<CallState>,
    activations: Vec<usize>,
    /// Per call node: (instant of its answer, ok?) when scheduled.
    answer: Vec<Option<(u64, bool)>>,
    /// Per task: the call node holding it.
    holder: [Option<usize>; 3],
    now: u64,
    trace: Vec<(u64, Vec<u32>)>,
    result: Option<bool>,
    steps: usize,
}

impl<'m> Sim<'m> {
    fn new(m: &'m Mission, choices: Vec<usize>) -> Self {
        let n = m.nodes.len();
        Sim {
            m,
            choices,
            seen: Vec::new(),
            active: vec![false; n],
            pending: vec![0; n],
            failed: vec![false; n],
            open: vec![false; n],
            doing: vec![None; n],
            seq_at: vec![0; n],
            calls: vec![CallState::Idle; n],
            activations: vec![0; n],
            answer: vec![None; n],
            holder: [None; 3],
            now: 0,
            trace: Vec::new(),
            result: None,
            steps: 0,
        }
    }

    fn choose(&mut self, n: usize) -> usize {
        let i = self.seen.len();
        self.seen.push(n);
        self.choices.get(i).copied().unwrap_or(0).min(n - 1)
    }

    fn start(&mut self, n: usize) {
        self.active[n] = true;
        self.steps += 1;
        match &self.m.nodes[n] {
            Node::Call { .. } => {
                // The call waits for its task; tasks are handed out once the instant's cascade is done.
                self.calls[n] = CallState::Waiting;
            }
            Node::Seq(v) => {
                self.seq_at[n] = 0;
                self.start(v[0]);
            }
            Node::If(c, ..) | Node::While(c, _) | Node::Try(c, _) | Node::Not(c) => self.start(*c),
            Node::And(v) => {
                self.pending[n] = v.len();
                self.failed[n] = false;
                for &k in v {
                    self.start(k);
                }
            }
            Node::Or(v) => {
                self.open[n] = true;
                for &k in v {
                    self.start(k);
                }
            }
            Node::Monitor(b, hs) => {
                self.open[n] = true;
                self.doing[n] = None;
                self.start(*b);
                for &(_, c, _) in hs {
                    self.start(c);
                }
            }
        }
    }

    /// Aborts a running node and everything running under it.
    fn abort(&mut self, n: usize) {
        if !self.active[n] {
            return;
        }
        self.active[n] = false;
        match &self.m.nodes[n] {
            Node::Call { .. } => {
                if self.calls[n] == CallState::Running {
                    // Disabled; it gives its task back at the end of the instant.
                    let t = self.task(n);
                    self.holder[t] = None;
                }
                self.calls[n] = CallState::Idle;
                self.answer[n] = None;
            }
            Node::Seq(v) | Node::And(v) | Node::Or(v) => {
                for k in v.clone() {
                    self.abort(k);
                }
            }
            Node::If(c, t, e) => {
                for k in [Some(*c), Some(*t), *e].into_iter().flatten() {
                    self.abort(k);
                }
            }
            Node::While(x, y) | Node::Try(x, y) => {
                self.abort(*x);
                self.abort(*y);
            }
            Node::Not(x) => self.abort(*x),
            Node::Monitor(b, hs) => {
                self.abort(*b);
                for &(_, c, a) in hs {
                    self.abort(c);
                    self.abort(a);
                }
            }
        }
    }

    fn task(&self, n: usize) -> usize {
        match &self.m.nodes[n] {
            Node::Call { task, .. } => *task as usize,
            _ => unreachable!(),
        }
    }

    /// Node `n` ended with `ok`: its parent reacts at once.
    fn end(&mut self, n: usize, ok: bool) {
        self.active[n] = false;
        self.steps += 1;
        let Some(p) = self.m.parent[n] else {
            self.result = Some(ok);
            return;
        };
        if !self.active[p] {
            return;
        }
        match self.m.nodes[p].clone() {
            Node::Call { .. } => unreachable!(),
            Node::Seq(v) => {
                let i = self.seq_at[p];
                if ok && i + 1 < v.len() {
                    self.seq_at[p] = i + 1;
                    self.start(v[i + 1]);
                } else {
                    self.end(p, ok);
                }
            }
            Node::If(c, t, e) => {
                if n == c {
                    match (ok, e) {
                        (true, _) => self.start(t),
                        (false, Some(e)) => self.start(e),
                        (false, None) => self.end(p, true),
                    }
                } else {
                    self.end(p, ok);
                }
            }
            Node::While(c, b) => {
                if n == c {
                    if ok {
                        self.start(b)
                    } else {
                        self.end(p, true)
                    }
                } else if ok {
                    self.start(c)
                } else {
                    self.end(p, false)
                }
            }
            Node::Try(x, y) => {
                if n == x && !ok {
                    self.start(y)
                } else {
                    self.end(p, ok)
                }
            }
            Node::Not(_) => self.end(p, !ok),
            Node::And(_) => {
                self.failed[p] |= !ok;
                self.pending[p] -= 1;
                if self.pending[p] == 0 {
                    let f = self.failed[p];
                    self.end(p, !f);
                }
            }
            Node::Or(v) => {
                // The first branch to end decides; the others are aborted first.
                self.open[p] = false;
                for k in v {
                    self.abort(k);
                }
                self.end(p, ok);
            }
            Node::Monitor(b, hs) => match self.doing[p] {
                Some(j) => {
                    let (w, _, _) = hs[j];
                    if w && ok {
                        // while_condition: an ok do-block starts the whole monitor again.
                        self.start(p);
                    } else {
                        self.end(p, ok);
                    }
                }
                None => {
                    self.open[p] = false;
                    self.abort(b);
                    for &(_, c, a) in &hs {
                        self.abort(c);
                        self.abort(a);
                    }
                    if n == b {
                        self.end(p, ok);
                    } else {
                        // A condition ended first (ok or fail): its do-block runs.
                        let j = hs.iter().position(|&(_, c, _)| c == n).expect("a condition");
                        self.doing[p] = Some(j);
                        self.active[p] = true;
                        self.start(hs[j].2);
                    }
                }
            },
        }
    }

    /// The enclosing parallel-or / monitor parts of a call are all open.
    fn guards_open(&self, n: usize) -> bool {
        let mut child = n;
        while let Some(p) = self.m.parent[child] {
            match &self.m.nodes[p] {
                Node::Or(_) if !self.open[p] => return false,
                Node::Monitor(_, hs) if !self.open[p] && !hs.iter().any(|&(_, _, a)| a == child) => return false,
                _ => {}
            }
            child = p;
        }
        true
    }

    /// Hands free tasks to waiting calls (one choice per contended task).
    fn hand_out(&mut self) -> Result<(), Skip> {
        for t in 0..3 {
            if self.holder[t].is_some() {
                continue;
            }
            let waiting: Vec<usize> = self
                .m
                .calls
                .iter()
                .copied()
                .filter(|&c| self.task(c) == t && self.calls[c] == CallState::Waiting)
                .collect();
            if waiting.is_empty() {
                continue;
            }
            let c = waiting[self.choose(waiting.len())];
            assert!(self.guards_open(c), "a call waits under a structure that decided to abort it");
            self.holder[t] = Some(c);
            self.calls[c] = CallState::Running;
            let Node::Call { id, timeout, script, .. } = &self.m.nodes[c] else { unreachable!() };
            let k = self.activations[c].min(script.len() - 1);
            self.activations[c] += 1;
            if self.activations[c] > 12 {
                return Err(Skip::Size);
            }
            match self.trace.last_mut() {
                Some((at, v)) if *at == self.now => v.push(*id),
                _ => self.trace.push((self.now, vec![*id])),
            }
            let timed = t == 2;
            let answer = match script[k] {
                Answer::Ok(d) => Some((d, true)),
                Answer::Fail(d) => Some((d, false)),
                Answer::Never => None,
            };
            self.answer[c] = match (answer, timed) {
                (Some((d, _)), true) if d == *timeout => return Err(Skip::Tie),
                (Some((d, _)), true) if d > *timeout => Some((self.now + timeout, false)),
                (None, true) => Some((self.now + timeout, false)),
                (Some((d, ok)), _) => Some((self.now + d, ok)),
                (None, false) => None,
            };
        }
        Ok(())
    }

    fn run(mut self) -> Result<(Trace, Vec<usize>), Skip> {
        self.start(self.m.root);
        loop {
            self.hand_out()?;
            if self.steps > 20_000 {
                return Err(Skip::Size);
            }
            if self.result.is_some() {
                break;
            }
            let next: Vec<(u64, usize)> =
                self.m.calls.iter().filter_map(|&c| self.answer[c].map(|(at, _)| (at, c))).collect();
            let Some(&(at, c)) = next.iter().min() else { break };
            if next.iter().filter(|(x, _)| *x == at).count() > 1 {
                return Err(Skip::Tie);
            }
            self.now = at;
            let (_, ok) = self.answer[c].take().expect("scheduled");
            let t = self.task(c);
            self.holder[t] = None;
            self.calls[c] = CallState::Idle;
            self.end(c, ok);
        }
        for (_, v) in &mut self.trace {
            v.sort_unstable();
        }
        let result = match self.result {
            Some(true) => "ok",
            Some(false) => "fail",
            None => "stuck",
        };
        Ok(((self.trace, result), self.seen))
    }
}

/// Every run of the reference (all choices of which waiting call gets a task).
fn reference(m: &Mission) -> Result<BTreeSet<Trace>, Skip> {
    let mut out = BTreeSet::new();
    let mut stack: Vec<Vec<usize>> = vec![Vec::new()];
    let mut runs = 0;
    while let Some(prefix) = stack.pop() {
        runs += 1;
        if runs > 200 {
            return Err(Skip::Size);
        }
        let (trace, seen) = Sim::new(m, prefix.clone()).run()?;
        out.insert(trace);
        // Branch on every choice after the prefix.
        for (i, &n) in seen.iter().enumerate().skip(prefix.len()) {
            for alt in 1..n {
                let mut p: Vec<usize> = prefix.clone();
                p.extend(std::iter::repeat_n(0, i - prefix.len()));
                p.push(alt);
                stack.push(p);
            }
        }
    }
    Ok(out)
}

// ---------------------------------------------------------------------------
// The compiled net, played by the player against a scripted vehicle.

fn play(m: &Mission, net: &Arc<mcl_net::Net>, seed: u64) -> Trace {
    let mut player = Player::new(net.clone(), PlayerOptions::seeded(seed));
    let by_id: BTreeMap<u32, usize> = m
        .calls
        .iter()
        .map(|&c| match &m.nodes[c] {
            Node::Call { id, .. } => (*id, c),
            _ => unreachable!(),
        })
        .collect();
    let mut activations: BTreeMap<u32, usize> = BTreeMap::new();
    // Per task prefix (a, b, t): the pending answer (instant, event).
    let mut answers: BTreeMap<&'static str, (u64, String)> = BTreeMap::new();
    let mut trace: Vec<(u64, Vec<u32>)> = Vec::new();
    let mut now: u64 = 0;
    let mut outputs = player.start(0.0);
    for _ in 0..10_000 {
        for o in outputs.drain(..) {
            let Output::Send { action, .. } = o else { continue };
            let prefix: &'static str = match action.primitive.as_str() {
                "APrimitive" => "a",
                "BPrimitive" => "b",
                _ => "t",
            };
            let id = action.params.get("x").and_then(|v| v.as_u64()).expect("x") as u32;
            if action.command == "disable" {
                answers.remove(prefix);
                continue;
            }
            match trace.last_mut() {
                Some((at, v)) if *at == now => v.push(id),
                _ => trace.push((now, vec![id])),
            }
            let Node::Call { script, .. } = &m.nodes[by_id[&id]] else { unreachable!() };
            let k = activations.entry(id).or_default();
            let answer = script[(*k).min(script.len() - 1)];
            *k += 1;
            match answer {
                Answer::Ok(d) => answers.insert(prefix, (now + d, format!("{prefix}Ok"))),
                Answer::Fail(d) => answers.insert(prefix, (now + d, format!("{prefix}Fail"))),
                Answer::Never => None,
            };
        }
        if player.outcome().is_some() {
            break;
        }
        let next_answer = answers.iter().map(|(p, (at, _))| (*at, *p)).min();
        let deadline = player.next_deadline();
        match (next_answer, deadline) {
            (Some((at, _)), Some(d)) if d <= at as f64 => {
                now = d.round() as u64;
                outputs = player.on_timer(d);
            }
            (Some((at, p)), _) => {
                now = at;
                let (_, event) = answers.remove(p).expect("pending");
                outputs = player.on_event(at as f64, &event);
            }
            (None, Some(d)) => {
                now = d.round() as u64;
                outputs = player.on_timer(d);
            }
            (None, None) => break,
        }
    }
    for (_, v) in &mut trace {
        v.sort_unstable();
    }
    let result = match player.outcome() {
        Some(Outcome::Ok) => "ok",
        Some(Outcome::Fail) => "fail",
        _ => "stuck",
    };
    (trace, result)
}

#[derive(Default, Debug)]
struct Counts {
    compared: usize,
    ties: usize,
    size: usize,
}

fn check_case(shape: &Shape, seed: u64, counts: &mut Counts) -> Result<(), TestCaseError> {
    let m = Mission::new(shape, seed);
    let body = m.text(m.root);
    let expected = match reference(&m) {
        Ok(e) => e,
        Err(Skip::Tie) => {
            counts.ties += 1;
            return Ok(());
        }
        Err(Skip::Size) => {
            counts.size += 1;
            return Ok(());
        }
    };
    let mut db = Database::new();
    let dir = Path::new("/virtual/outcomes");
    db.set_text(&dir.join("vehicle.mcl"), VEHICLE);
    let file = db.set_text(&dir.join("m.mcl"), format!("import \"vehicle.mcl\";\nmission {{ {body} }}\n"));
    let diags = check_file(&db, file);
    prop_assert!(!mcl_compiler::has_errors(diags), "generated program has errors: {diags:?}\n{body}");
    let net = Arc::new(compile_file(&db, file).map_err(|e| TestCaseError::fail(e.to_string()))?.remove(0).net);
    for s in 0..4 {
        let got = play(&m, &net, seed.wrapping_add(s));
        prop_assert!(
            expected.contains(&got),
            "mission {{ {body} }}\nscripts: {:?}\nplayer (seed {}): {got:?}\nreference: {expected:#?}",
            m.calls
                .iter()
                .map(|&c| match &m.nodes[c] {
                    Node::Call { id, script, .. } => (*id, script.clone()),
                    _ => unreachable!(),
                })
                .collect::<Vec<_>>(),
            seed.wrapping_add(s)
        );
    }
    counts.compared += 1;
    Ok(())
}

#[test]
fn compiled_missions_end_and_enable_as_the_reference_interpreter_says() {
    let cases = 2000;
    let mut runner = TestRunner::new(Config { cases, max_shrink_iters: 500, ..Config::default() });
    let counts = std::cell::RefCell::new(Counts::default());
    let result = runner.run(&(shape(), any::<u64>()), |(s, seed)| check_case(&s, seed, &mut counts.borrow_mut()));
    if let Err(e) = result {
        panic!("{e}");
    }
    let c = counts.into_inner();
    println!("{c:?}");
    let skipped = c.ties + c.size;
    // Shrinking reruns cases, so count against what ran.
    let ran = c.compared + skipped;
    assert!(ran >= cases as usize, "{c:?}");
    assert!(skipped * 10 <= ran, "more than a tenth of the cases were skipped: {c:?}");
}

/// Two calls of one task in parallel, one failing, then the other.
#[test]
fn a_handmade_case() {
    let shape = Shape::And(vec![Shape::Call(0), Shape::Call(0)]);
    let mut counts = Counts::default();
    for seed in 0..50 {
        check_case(&shape, seed, &mut counts).unwrap();
    }
    assert!(counts.compared > 40, "{counts:?}");
}
