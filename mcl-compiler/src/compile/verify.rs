//! Verification of building blocks (seed 4.3.1, A.2-A.4).
//!
//! A block is placed in a *harness*: an environment that marks `begin` once,
//! may mark `abort` in any tangible marking while the block runs, and takes
//! the outcome; control structures get a reduced block (seed `N_PNBB1`, or an
//! instantaneous one) plugged into each internal interface. The reachability
//! graph is explored by `mcl_net::explore` under the one MCL semantics that
//! the player uses (`mcl_net::semantics::select_ready`: immediate
//! transitions first, by priority; then deferred ones; then events, timers
//! and the environment's abort, in every order), and these properties are
//! checked:
//!
//! * **common interface** — begin, abort, ok, fail on interface 1 (the checker);
//! * **1-safeness** — no place ever holds two tokens;
//! * **reachability condition** — every run from begin *without* abort ends
//!   with exactly one of ok/fail marked (the environment's abort is not a way
//!   out: a block that only an abort can end is stuck when nobody aborts it),
//!   and every run from begin followed by an abort in any running marking
//!   ends back at rest with neither ok nor fail marked;
//! * **reusability** — in every final marking, every place of the block
//!   (and of its children) is back to its initial marking;
//! * for task patterns: an abort, and the end of the task, take the task
//!   back to rest at once (through immediate transitions).
//!
//! The harness delivers to a block exactly what a composed mission can
//! deliver to it (docs/blocks.md, "the protocol between a block and its
//! children"): `begin` once, at rest; `abort` at most once, only while the
//! block runs and has not produced its result, and only in a tangible
//! marking (the environment's abort is an event). An abort at rest never
//! happens inside a mission, so what a pattern would do with one (the seed's
//! figure 4.3(c) consumes it, `abort.1 -> T1`) is not judged.
//!
//! A violation comes with the shortest run that shows it, in the block's own
//! transition names (`begin` and `abort` are the environment's steps), and,
//! where the structure of the net explains it, a note: an empty siphon that
//! keeps the transitions marking ok/fail dead, a marked trap that never lets
//! the block return to rest, places that no positive P-invariant bounds.

use super::builder::{Builder, Iface};
use super::structures::{self, Structure};
use mcl_net::explore::{explore, Options, Semantics, StateId, StateSpace};
use mcl_net::structural::{self, Limits};
use mcl_net::{Net, PlaceId, TransitionId, TransitionKind};

/// The reduced model plugged into an internal interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    /// Starts, then ends ok or fail on an event, or is aborted (seed `N_PNBB1`).
    Reduced,
    /// Ends ok or fail at once when started (the seed's `Void`, `True`).
    Instant,
}

/// A property that does not hold, with the shortest run showing it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Violation {
    /// `1-safe`, `reachability`, `exactly-one`, `reusability`, `abort`, `rest` or `size`.
    pub property: &'static str,
    pub message: String,
    /// Transition names of the block; `begin`, `abort` are the environment's
    /// steps, `ok`, `fail` the environment taking the outcome.
    pub trace: Vec<String>,
    /// For a run that never ends: the transitions it repeats forever after `trace`.
    pub cycle: Vec<String>,
    /// Explanations from the structure of the net (siphons, traps, invariants).
    pub notes: Vec<String>,
}

impl Violation {
    fn new(property: &'static str, message: String, trace: Vec<String>) -> Self {
        Violation { property, message, trace, cycle: Vec::new(), notes: Vec::new() }
    }

    /// The counterexample as one line: `begin -> T0 -> T1`, with the
    /// repeated part of an endless run after it.
    pub fn counterexample(&self) -> Option<String> {
        if self.trace.is_empty() && self.cycle.is_empty() {
            return None;
        }
        let mut s = if self.trace.is_empty() { "(start)".to_string() } else { self.trace.join(" -> ") };
        if !self.cycle.is_empty() {
            s.push_str(&format!(", then forever: {} -> ...", self.cycle.join(" -> ")));
        }
        Some(s)
    }
}

/// An immediate transition of a task that takes a token from a transition
/// waiting for an event in a marking where both are enabled: it always wins
/// (immediate transitions fire first), so the event is never waited for.
/// Typically a transition the task meant to bind to an event but left
/// unbound.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Premature {
    /// The immediate transition (the pattern's name for it).
    pub transition: String,
    /// The transition waiting for an event that it pre-empts.
    pub waiting: String,
    /// That transition's event.
    pub event: String,
    /// The place both take a token from.
    pub place: String,
    /// The shortest run to a marking where it happens.
    pub trace: Vec<String>,
}

/// The outcome of a verification.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    pub states: usize,
    pub tangible: usize,
    pub violations: Vec<Violation>,
    /// For tasks: immediate transitions that pre-empt event transitions.
    pub premature: Vec<Premature>,
}

impl Verdict {
    pub fn ok(&self) -> bool {
        self.violations.is_empty()
    }
}

/// A block in its harness, ready to explore.
pub struct Harness {
    pub net: Net,
    /// Marked when the environment took the block's ok / fail.
    got: Vec<PlaceId>,
    /// The block's own ok and fail places.
    outcome: Vec<PlaceId>,
    /// Marked when the environment aborted the block.
    aborted: Option<PlaceId>,
    /// Places of the environment (not checked for reusability, not shown).
    env: Vec<PlaceId>,
    /// Places of the block's external interface.
    interface: Vec<PlaceId>,
    /// Transitions of the environment: begin, ok, fail, abort.
    env_transitions: Vec<TransitionId>,
    /// The environment's abort.
    env_abort: Option<TransitionId>,
    is_task: bool,
}

/// A compiled mission: it starts with `mission.begin` marked and must end
/// with exactly one of `mission.ok`, `mission.fail` marked and every other
/// place back to its initial marking, whatever its tasks do.
pub fn mission_harness(net: Net) -> Option<Harness> {
    let begin = net.place_by_id(super::MISSION_BEGIN)?;
    let ok = net.place_by_id(super::MISSION_OK)?;
    let fail = net.place_by_id(super::MISSION_FAIL)?;
    let abort = net.place_by_id(super::MISSION_ABORT)?;
    Some(Harness {
        net,
        got: vec![ok, fail],
        outcome: vec![],
        aborted: None,
        env: vec![begin, ok, fail, abort],
        interface: vec![begin, ok, fail, abort],
        env_transitions: vec![],
        env_abort: None,
        is_task: false,
    })
}

struct Env {
    got: Vec<PlaceId>,
    aborted: PlaceId,
    places: Vec<PlaceId>,
    transitions: Vec<TransitionId>,
    abort: TransitionId,
}

/// Adds the environment around the external interface `ext`.
fn environment(b: &mut Builder, ext: Iface) -> Env {
    let idle = b.place("env.idle", 1);
    let run = b.place("env.running", 0);
    let got_ok = b.place("env.got_ok", 0);
    let got_fail = b.place("env.got_fail", 0);
    let aborted = b.place("env.aborted", 0);
    let abort = b.transition("env.abort", TransitionKind::Event("env.abort".into()), &[run], &[ext.abort, aborted]);
    let transitions = vec![
        b.imm("env.begin", &[idle], &[ext.begin, run]),
        b.imm("env.ok", &[run, ext.ok], &[got_ok]),
        b.imm("env.fail", &[run, ext.fail], &[got_fail]),
        abort,
    ];
    Env { got: vec![got_ok, got_fail], aborted, places: vec![idle, run, got_ok, got_fail, aborted], transitions, abort }
}

fn harness(net: Net, ext: Iface, env: Env, is_task: bool) -> Harness {
    Harness {
        net,
        got: env.got,
        outcome: vec![ext.ok, ext.fail],
        aborted: Some(env.aborted),
        env: env.places,
        interface: vec![ext.begin, ext.abort, ext.ok, ext.fail],
        env_transitions: env.transitions,
        env_abort: Some(env.abort),
        is_task,
    }
}

/// A control structure with the given children plugged in.
pub fn structure_harness(s: &Structure, children: &[Child]) -> Harness {
    let mut b = Builder::new(s.name());
    let ext = b.iface("ext", 1);
    let env = environment(&mut b, ext);
    let kids = structures::build(&mut b, s, ext, "cs").0;
    for (i, (k, c)) in kids.iter().zip(children.iter().cycle()).enumerate() {
        let n = format!("child{i}");
        match c {
            Child::Reduced => {
                let exe = b.place(format!("{n}.exe"), 0);
                b.imm(format!("{n}.start"), &[k.begin], &[exe]);
                b.transition(format!("{n}.end_ok"), TransitionKind::Event(format!("{n}.ok")), &[exe], &[k.ok]);
                b.transition(format!("{n}.end_fail"), TransitionKind::Event(format!("{n}.fail")), &[exe], &[k.fail]);
                b.imm(format!("{n}.abort"), &[k.abort, exe], &[]);
            }
            Child::Instant => {
                b.imm(format!("{n}.now_ok"), &[k.begin], &[k.ok]);
                b.imm(format!("{n}.now_fail"), &[k.begin], &[k.fail]);
            }
        }
    }
    let net = b.finish().build().expect("generated structure nets are well formed");
    harness(net, ext, env, false)
}

/// A task net (a pattern with its bindings) in the environment. The net must
/// have places `begin`, `abort`, `ok`, `fail`; they are wired to the
/// environment.
pub fn task_harness(task: &Net) -> Option<Harness> {
    let find = |id: &str| task.place_by_id(id);
    let ext = Iface { begin: find("begin")?, abort: find("abort")?, ok: find("ok")?, fail: find("fail")? };
    let mut b = Builder::from_net(task.to_builder());
    let env = environment(&mut b, ext);
    let net = b.finish().build().ok()?;
    Some(harness(net, ext, env, true))
}

/// A call adapter (see [`super::compile_mission`]) between the environment
/// and a reduced task guarded by its lock place, as in a compiled mission.
pub fn call_adapter_harness() -> Harness {
    let mut b = Builder::new("call-adapter");
    let ext = b.iface("call", 1);
    let env = environment(&mut b, ext);
    let task = b.iface("task", 2);
    let lock = b.place("task.idle", 1);
    super::adapter(&mut b, &[super::builder::Part::S("adapter")], ext, task, lock, &[]);
    let exe = b.place("task.exe", 0);
    b.imm("task.t_start", &[task.begin], &[exe]);
    b.transition("task.t_ok", TransitionKind::Event("task.ok".into()), &[exe], &[task.ok]);
    b.transition("task.t_fail", TransitionKind::Event("task.fail".into()), &[exe], &[task.fail]);
    b.imm("task.t_abort", &[task.abort, exe], &[]);
    let net = b.finish().build().expect("the call adapter is well formed");
    harness(net, ext, env, false)
}

/// The options of every block exploration.
fn options(max_states: usize) -> Options {
    Options {
        semantics: Semantics::Mcl,
        max_states,
        max_dead_examples: 0,
        threads: 1,
        exact_order: true,
        record_edges: true,
        // A marking with two tokens in a place already breaks 1-safeness: it
        // is reported and not expanded, which keeps unbounded nets finite.
        cut_above: Some(1),
    }
}

impl Harness {
    /// The state space of the harness under the MCL semantics, with its
    /// edges (`mcl_net::explore`, the engine of `mcl analyze`).
    pub fn state_space(&self, max_states: usize) -> StateSpace {
        explore(&self.net, &options(max_states))
    }

    /// The reachability graph in the DOT language: tangible markings as
    /// ellipses labelled with their marked places, vanishing markings as
    /// dots, final markings in bold; edges labelled with the transition.
    /// `None` when it has more than `max_states` states.
    pub fn reachability_dot(&self, max_states: usize) -> Option<String> {
        use std::fmt::Write;
        let ss = self.state_space(max_states + 1);
        if ss.len() > max_states || !ss.complete() {
            return None;
        }
        let mut out = String::from("digraph reachability {\n  rankdir=TB; node [fontname=\"Helvetica\", fontsize=9]; edge [fontname=\"Helvetica\", fontsize=8];\n");
        for s in ss.states() {
            let marked: Vec<String> = self
                .net
                .places()
                .iter()
                .enumerate()
                .filter(|&(i, p)| ss.tokens(s, PlaceId(i as u32)) > 0 && p.id.as_str() != "env.idle")
                .map(|(_, p)| p.id.to_string())
                .collect();
            let dead = ss.successors(s).is_empty();
            let fin = dead && self.is_good_end(&ss, s);
            let i = s.0;
            if !ss.is_vanishing(s) || dead {
                let _ = writeln!(
                    out,
                    "  s{i} [shape=ellipse{}, label=\"{}\"];",
                    if fin { ", penwidth=2" } else { "" },
                    marked.join("\\n")
                );
            } else {
                let _ = writeln!(out, "  s{i} [shape=point, width=0.08, tooltip=\"{}\"];", marked.join(" "));
            }
        }
        for s in ss.states() {
            for &(t, d) in ss.successors(s) {
                let name = self.net.transition(t).map(|x| x.id.to_string()).unwrap_or_default();
                let _ = writeln!(out, "  s{} -> s{} [label=\"{name}\"];", s.0, d.0);
            }
        }
        out.push_str("}\n");
        Some(out)
    }

    /// A transition as a step of a counterexample.
    fn step(&self, t: TransitionId) -> String {
        let name = self.net.transition(t).map(|x| x.id.to_string()).unwrap_or_default();
        if self.env_transitions.contains(&t) {
            name.trim_start_matches("env.").to_string()
        } else {
            name
        }
    }

    fn trace(&self, ss: &StateSpace, s: StateId) -> Vec<String> {
        ss.path_to(s).into_iter().map(|t| self.step(t)).collect()
    }

    fn is_env(&self, p: PlaceId) -> bool {
        self.env.contains(&p)
    }

    fn place_name(&self, p: PlaceId) -> String {
        self.net.place(p).map(|x| x.id.to_string()).unwrap_or_default()
    }

    /// The block's marked places in `s` (not the environment's), as `{a, b}`.
    fn describe(&self, ss: &StateSpace, s: StateId) -> String {
        let marked: Vec<String> = (0..self.net.place_count() as u32)
            .map(PlaceId)
            .filter(|&p| !self.is_env(p))
            .filter_map(|p| match ss.tokens(s, p) {
                0 => None,
                1 => Some(self.place_name(p)),
                k => Some(format!("{}×{k}", self.place_name(p))),
            })
            .collect();
        if marked.is_empty() {
            "no marked place".to_string()
        } else {
            format!("{{{}}}", marked.join(", "))
        }
    }

    fn at_rest(&self, ss: &StateSpace, s: StateId) -> bool {
        self.net
            .places()
            .iter()
            .enumerate()
            .all(|(i, p)| self.is_env(PlaceId(i as u32)) || ss.tokens(s, PlaceId(i as u32)) == p.initial)
    }

    fn got(&self, ss: &StateSpace, s: StateId) -> u32 {
        self.got.iter().map(|&p| ss.tokens(s, p)).sum()
    }

    fn was_aborted(&self, ss: &StateSpace, s: StateId) -> bool {
        self.aborted.is_some_and(|a| ss.tokens(s, a) > 0)
    }

    /// A valid end: exactly one outcome taken (or aborted with none), and no
    /// outcome left in the block's ok/fail places.
    fn is_good_end(&self, ss: &StateSpace, s: StateId) -> bool {
        let left: u32 = self.outcome.iter().map(|&p| ss.tokens(s, p)).sum();
        let got = self.got(ss, s);
        left == 0 && ((got == 1 && !self.was_aborted(ss, s)) || (got == 0 && self.was_aborted(ss, s)))
    }

    /// Explores and checks every property.
    pub fn verify(&self, max_states: usize) -> Verdict {
        let ss = self.state_space(max_states);
        let mut violations: Vec<Violation> = Vec::new();
        let push = |v: Violation, vs: &mut Vec<Violation>| {
            if !vs.iter().any(|x: &Violation| x.property == v.property) {
                vs.push(v);
            }
        };
        // 1-safeness: the first cut state (BFS order) is at the shortest depth.
        if let Some(s) = ss.cut_states().next() {
            let p = (0..self.net.place_count() as u32).map(PlaceId).find(|&p| ss.tokens(s, p) > 1);
            let name = p.map(|p| self.place_name(p)).unwrap_or_default();
            let mut v = Violation::new(
                "1-safe",
                format!("place `{name}` can hold two tokens: {}", self.describe(&ss, s)),
                self.trace(&ss, s),
            );
            v.notes.extend(self.uncovered_note(&p.into_iter().collect::<Vec<_>>()));
            push(v, &mut violations);
        }
        let complete = ss.complete();
        let n = ss.len();
        if complete {
            let dead: Vec<bool> = {
                let mut d = vec![false; n];
                for s in ss.dead_states() {
                    d[s.0 as usize] = true;
                }
                d
            };
            // Runs without abort: from begin, every run must reach a marking
            // where the environment took ok or fail, without the
            // environment's abort.
            let env_abort = self.env_abort;
            let reach_outcome = coreachable(&ss, |s| self.got(&ss, s) > 0, |t| Some(t) != env_abort);
            let mut cut = vec![false; n];
            for s in ss.cut_states() {
                cut[s.0 as usize] = true;
            }
            let stuck_without_abort: Vec<bool> = ss
                .states()
                .map(|s| !self.was_aborted(&ss, s) && !reach_outcome[s.0 as usize] && !cut[s.0 as usize])
                .collect();
            let no_cut = !cut.iter().any(|&c| c);
            let found = if no_cut { bottom(&ss, &stuck_without_abort, |t| Some(t) != env_abort) } else { None };
            if let Some((s, cycle)) = found {
                let m = self.describe(&ss, s);
                let message = if cycle.is_empty() {
                    if self.env_abort.is_some() {
                        format!("without an abort the block gets stuck in {m}: neither ok nor fail can be marked")
                    } else {
                        format!("the mission gets stuck in {m}: neither ok nor fail can be marked")
                    }
                } else {
                    format!("the block can loop forever ({m} is reached again and again) without marking ok or fail")
                };
                let mut v = Violation::new("reachability", message, self.trace(&ss, s));
                v.cycle = cycle.iter().map(|&t| self.step(t)).collect();
                v.notes.extend(self.siphon_note(&ss, s));
                push(v, &mut violations);
            }
            // Final markings: exactly one outcome, nothing left behind.
            for s in ss.dead_states() {
                let got = self.got(&ss, s);
                let left: Vec<PlaceId> = self.outcome.iter().copied().filter(|&p| ss.tokens(s, p) > 0).collect();
                if got > 1 || (got == 1 && !left.is_empty()) {
                    push(
                        Violation::new(
                            "exactly-one",
                            "the block marks both ok and fail: a run must end with exactly one of ok and fail"
                                .to_string(),
                            self.trace(&ss, s),
                        ),
                        &mut violations,
                    );
                } else if self.was_aborted(&ss, s) && !left.is_empty() {
                    let which: Vec<String> = left.iter().map(|&p| format!("`{}`", self.place_name(p))).collect();
                    push(
                        Violation::new(
                            "exactly-one",
                            format!(
                                "after an abort the block marks {}: an aborted block must end with neither ok nor fail",
                                which.join(" and ")
                            ),
                            self.trace(&ss, s),
                        ),
                        &mut violations,
                    );
                } else if (got == 1 || self.was_aborted(&ss, s)) && !self.at_rest(&ss, s) {
                    let left: Vec<PlaceId> = (0..self.net.place_count() as u32)
                        .map(PlaceId)
                        .filter(|&p| !self.is_env(p) && ss.tokens(s, p) != self.net.place(p).map_or(0, |x| x.initial))
                        .collect();
                    let what = if self.was_aborted(&ss, s) { "after an abort" } else { "the block ended but" };
                    let mut v = Violation::new(
                        "reusability",
                        format!("{what} left tokens behind: {}", self.describe(&ss, s)),
                        self.trace(&ss, s),
                    );
                    v.notes.extend(self.trap_note(&ss, s, &left));
                    push(v, &mut violations);
                }
            }
            // Every run, once aborted or ended, goes on to a valid end at rest.
            let reach_end = coreachable(&ss, |s| dead[s.0 as usize] && self.is_good_end(&ss, s), |_| true);
            let stuck_later: Vec<bool> = ss
                .states()
                .map(|s| {
                    let i = s.0 as usize;
                    !reach_end[i] && !dead[i] && !stuck_without_abort[i] && !cut[i]
                })
                .collect();
            let found = if no_cut { bottom(&ss, &stuck_later, |_| true) } else { None };
            if let Some((s, cycle)) = found {
                let what = if self.was_aborted(&ss, s) { "after an abort" } else { "after ending" };
                let mut v = Violation::new(
                    "reachability",
                    format!("{what} the block never returns to rest: it loops in {}", self.describe(&ss, s)),
                    self.trace(&ss, s),
                );
                v.cycle = cycle.iter().map(|&t| self.step(t)).collect();
                push(v, &mut violations);
            }
            if self.is_task {
                self.task_checks(&ss, &dead, &mut violations);
            }
        }
        if !complete {
            violations.push(Violation::new(
                "size",
                format!("more than {max_states} states: the block is too large to verify"),
                vec![],
            ));
        }
        let tangible = ss.states().filter(|&s| !ss.is_vanishing(s)).count();
        let premature = if self.is_task && complete { self.premature(&ss) } else { Vec::new() };
        Verdict { states: n, tangible, violations, premature }
    }

    /// Immediate transitions of the block that, in some marking reached
    /// without an abort, are enabled together with a transition waiting for
    /// an event and share an input place with it, when that event was not
    /// being waited for before: the immediate cascade that leads there
    /// started in a tangible marking (or at the start) where the event's
    /// transition was not enabled, so the event is never waited for. (A
    /// cascade that starts while the event is awaited, such as a time-out
    /// that disables the primitive, is the pattern's design.) One finding
    /// per immediate transition, with the shortest run (states are in BFS
    /// order).
    fn premature(&self, ss: &StateSpace) -> Vec<Premature> {
        let net = &self.net;
        let own = |t: &TransitionId| !self.env_transitions.contains(t);
        let immediate: Vec<TransitionId> = net
            .transition_ids()
            .filter(own)
            .filter(|&t| net.transition(t).is_some_and(|x| x.kind.is_immediate()))
            .collect();
        let waiting: Vec<(TransitionId, String)> = net
            .transition_ids()
            .filter(own)
            .filter_map(|t| match &net.transition(t)?.kind {
                TransitionKind::Event(e) => Some((t, e.clone())),
                _ => None,
            })
            .collect();
        if immediate.is_empty() || waiting.is_empty() {
            return Vec::new();
        }
        let mut preds: Vec<Vec<StateId>> = vec![Vec::new(); ss.len()];
        for s in ss.states() {
            for &(_, d) in ss.successors(s) {
                preds[d.0 as usize].push(s);
            }
        }
        let enabled = |s: StateId, t: TransitionId| mcl_net::semantics::is_enabled_with(net, t, |p| ss.tokens(s, p));
        // For each event transition, the states that a cascade reaches which
        // started where it was not enabled: a cascade starts in a tangible
        // state (or the start) and goes on through vanishing states. One
        // forward pass per event transition, linear in the state space.
        let origin = |x: StateId| !ss.is_vanishing(x) || preds[x.0 as usize].is_empty();
        let fresh: Vec<Vec<bool>> = waiting
            .iter()
            .map(|&(e, _)| {
                let mut fresh = vec![false; ss.len()];
                let mut stack = Vec::new();
                for x in ss.states() {
                    if preds[x.0 as usize].is_empty() && !enabled(x, e) && !fresh[x.0 as usize] {
                        fresh[x.0 as usize] = true;
                        stack.push(x);
                    }
                    if origin(x) && !enabled(x, e) {
                        for &(_, d) in ss.successors(x) {
                            if !std::mem::replace(&mut fresh[d.0 as usize], true) {
                                stack.push(d);
                            }
                        }
                    }
                }
                while let Some(x) = stack.pop() {
                    if origin(x) {
                        continue;
                    }
                    for &(_, d) in ss.successors(x) {
                        if !std::mem::replace(&mut fresh[d.0 as usize], true) {
                            stack.push(d);
                        }
                    }
                }
                fresh
            })
            .collect();
        let mut found: Vec<Premature> = Vec::new();
        for s in ss.states() {
            if self.was_aborted(ss, s) {
                continue;
            }
            for &t in &immediate {
                let tname = self.step(t);
                if found.iter().any(|f| f.transition == tname) || !enabled(s, t) {
                    continue;
                }
                let hit = waiting.iter().zip(&fresh).find_map(|((e, event), fresh)| {
                    let shared = net.pre(t).iter().find(|(p, _)| net.pre(*e).iter().any(|(q, _)| q == p))?.0;
                    (enabled(s, *e) && fresh[s.0 as usize]).then(|| (*e, event.clone(), shared))
                });
                if let Some((e, event, place)) = hit {
                    found.push(Premature {
                        transition: tname,
                        waiting: self.step(e),
                        event,
                        place: self.place_name(place),
                        trace: self.trace(ss, s),
                    });
                }
            }
        }
        found
    }

    /// Tasks are shared by call sites through a lock that the call gives
    /// back in the first tangible marking after the task ended or was
    /// aborted: by then the task must be at rest.
    fn task_checks(&self, ss: &StateSpace, dead: &[bool], violations: &mut Vec<Violation>) {
        for s in ss.states() {
            if ss.is_vanishing(s) || dead[s.0 as usize] || self.at_rest(ss, s) {
                continue;
            }
            let (property, message) = if self.was_aborted(ss, s) {
                (
                    "abort",
                    format!(
                        "after an abort the task waits in {} instead of returning to rest at once",
                        self.describe(ss, s)
                    ),
                )
            } else if self.got(ss, s) > 0 {
                (
                    "rest",
                    format!(
                        "after ending, the task waits in {} instead of returning to rest at once; the next call of the task could start before it is at rest",
                        self.describe(ss, s)
                    ),
                )
            } else {
                continue;
            };
            if !violations.iter().any(|v| v.property == property) {
                violations.push(Violation::new(property, message, self.trace(ss, s)));
            }
        }
    }

    /// The block's places (not the environment's, not the interface).
    fn inner_places(&self) -> impl Iterator<Item = PlaceId> + '_ {
        (0..self.net.place_count() as u32).map(PlaceId).filter(|&p| !self.is_env(p) && !self.interface.contains(&p))
    }

    fn names(&self, ps: &[PlaceId]) -> String {
        ps.iter().map(|&p| format!("`{}`", self.place_name(p))).collect::<Vec<_>>().join(", ")
    }

    /// In a marking where the block is stuck: an empty siphon (a set of
    /// places that no transition can mark again once empty) holding an
    /// input place of every transition that marks ok or fail.
    fn siphon_note(&self, ss: &StateSpace, s: StateId) -> Option<String> {
        let empty: Vec<PlaceId> = self.inner_places().filter(|&p| ss.tokens(s, p) == 0).collect();
        let producers: Vec<TransitionId> = self
            .outcome
            .iter()
            .flat_map(|&p| self.net.producers(p).iter().copied())
            .filter(|t| !self.env_transitions.contains(t))
            .collect();
        if producers.is_empty() {
            let names: Vec<String> = self.outcome.iter().map(|&p| format!("`{}`", self.place_name(p))).collect();
            return Some(format!("no transition of the block marks {}", names.join(" or ")));
        }
        let needs = |set: &[PlaceId]| {
            !producers.is_empty() && producers.iter().all(|&t| self.net.pre(t).iter().any(|(p, _)| set.contains(p)))
        };
        let largest = structural::max_siphon_within(&self.net, &empty);
        if !needs(&largest) {
            return None;
        }
        // A minimal siphon inside the largest one, if one alone is enough.
        let limits = Limits { max_rows: 2_000, max_nodes: 20_000, max_results: 200 };
        let minimal = structural::minimal_siphons(&self.net, &limits)
            .sets
            .into_iter()
            .filter(|set| set.iter().all(|p| largest.contains(p)) && needs(set))
            .min_by_key(Vec::len);
        let set = minimal.unwrap_or(largest);
        let blocked: Vec<String> = producers
            .iter()
            .filter_map(|&t| {
                let p = self.net.pre(t).iter().find(|(p, _)| set.contains(p))?.0;
                Some(format!("`{}` needs `{}`", self.net.transition(t)?.id, self.place_name(p)))
            })
            .collect();
        let what = if set.len() == 1 {
            format!("place {} is empty and no transition can mark it again", self.names(&set))
        } else {
            format!("places {} are empty and no transition can mark them again", self.names(&set))
        };
        Some(format!("{what} (an unmarked siphon), so ok and fail can never be marked: {}", blocked.join(", ")))
    }

    /// For places left marked at the end: a trap among them (once marked,
    /// it stays marked, so the block can never return to rest), or the
    /// places no positive P-invariant covers.
    fn trap_note(&self, ss: &StateSpace, s: StateId, left: &[PlaceId]) -> Option<String> {
        let marked: Vec<PlaceId> = left.iter().copied().filter(|&p| ss.tokens(s, p) > 0).collect();
        let trap = structural::max_trap_within(&self.net, &marked);
        if !trap.is_empty() {
            let (verb, pron) = if trap.len() == 1 { ("is a trap", "it stays") } else { ("form a trap", "they stay") };
            return Some(format!(
                "{} {verb}: no transition takes a token out without putting one back, so once marked {pron} marked and the block can never return to rest",
                self.names(&trap)
            ));
        }
        self.uncovered_note(left)
    }

    /// The places of `focus` that no positive P-invariant covers: nothing
    /// bounds their tokens.
    fn uncovered_note(&self, focus: &[PlaceId]) -> Option<String> {
        let limits = Limits { max_rows: 5_000, max_nodes: 20_000, max_results: 500 };
        let inv = structural::p_invariants(&self.net, &limits);
        if !inv.complete {
            return None;
        }
        let covered: Vec<PlaceId> = inv.invariants.iter().flat_map(|i| i.iter().map(|&(p, _)| p)).collect();
        let uncovered: Vec<PlaceId> =
            focus.iter().copied().filter(|p| !covered.contains(p) && !self.is_env(*p)).collect();
        if uncovered.is_empty() {
            return None;
        }
        Some(format!(
            "no positive P-invariant covers {}: no weighted token count bounds {}, so a run can add tokens there without taking them out",
            self.names(&uncovered),
            if uncovered.len() == 1 { "it" } else { "them" }
        ))
    }
}

/// For every state, whether a state satisfying `target` can be reached from
/// it following only the edges whose transition satisfies `edge`.
fn coreachable(
    ss: &StateSpace,
    mut target: impl FnMut(StateId) -> bool,
    edge: impl Fn(TransitionId) -> bool,
) -> Vec<bool> {
    let n = ss.len();
    let mut preds: Vec<Vec<u32>> = vec![Vec::new(); n];
    for s in ss.states() {
        for &(t, d) in ss.successors(s) {
            if edge(t) {
                preds[d.0 as usize].push(s.0);
            }
        }
    }
    let mut reach: Vec<bool> = ss.states().map(&mut target).collect();
    let mut stack: Vec<u32> = (0..n as u32).filter(|&s| reach[s as usize]).collect();
    while let Some(d) = stack.pop() {
        for &p in &preds[d as usize] {
            if !reach[p as usize] {
                reach[p as usize] = true;
                stack.push(p);
            }
        }
    }
    reach
}

/// The first state (in BFS order, so with a shortest run to it) of a bottom
/// strongly connected component of the `bad` states, following the edges
/// whose transition satisfies `edge`; with the transitions of a cycle
/// through it when the component is not a single dead state. Every
/// successor of a bad state must be bad.
fn bottom(ss: &StateSpace, bad: &[bool], edge: impl Fn(TransitionId) -> bool) -> Option<(StateId, Vec<TransitionId>)> {
    let succ = |s: u32| ss.successors(StateId(s)).iter().filter(|(t, _)| edge(*t)).map(|&(t, d)| (t, d.0));
    // Strongly connected components of the bad states (the others are
    // singletons without successors, left out).
    let n = ss.len();
    const UNSEEN: u32 = u32::MAX;
    let mut comp = vec![UNSEEN; n];
    let mut comps: Vec<Vec<u32>> = Vec::new();
    mcl_net::graph::tarjan(
        n,
        |v, out| {
            if bad[v as usize] {
                out.extend(succ(v).map(|(_, d)| d).filter(|&d| bad[d as usize]));
            }
        },
        |c| {
            if bad[c[0] as usize] {
                for &w in c {
                    comp[w as usize] = comps.len() as u32;
                }
                comps.push(c.to_vec());
            }
        },
    );
    // Bottom components: no edge leaves them.
    let best = comps
        .iter()
        .enumerate()
        .filter(|(k, c)| c.iter().all(|&s| succ(s).all(|(_, d)| comp[d as usize] == *k as u32)))
        .map(|(_, c)| *c.iter().min().expect("components are not empty"))
        .min()?;
    // A cycle through `best` inside its component (BFS), unless it is dead.
    let k = comp[best as usize];
    let mut cycle = Vec::new();
    if succ(best).next().is_some() {
        let mut parent: std::collections::HashMap<u32, (u32, TransitionId)> = Default::default();
        let mut queue = std::collections::VecDeque::from([best]);
        'bfs: while let Some(v) = queue.pop_front() {
            for (t, d) in succ(v) {
                if comp[d as usize] != k {
                    continue;
                }
                if d == best {
                    let mut cur = v;
                    cycle.push(t);
                    while cur != best {
                        let (p, t) = parent[&cur];
                        cycle.push(t);
                        cur = p;
                    }
                    cycle.reverse();
                    break 'bfs;
                }
                if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(d) {
                    e.insert((v, t));
                    queue.push_back(d);
                }
            }
        }
    }
    Some((StateId(best), cycle))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_syntax::ast::MonitorKind;

    fn all_structures() -> Vec<Structure> {
        vec![
            Structure::Not,
            Structure::Sequence(2),
            Structure::Sequence(3),
            Structure::IfThen,
            Structure::IfThenElse,
            Structure::While,
            Structure::TryCatch,
            Structure::ParallelAnd(2),
            Structure::ParallelAnd(3),
            Structure::ParallelOr(2),
            Structure::ParallelOr(3),
            Structure::Monitor(vec![MonitorKind::Condition]),
            Structure::Monitor(vec![MonitorKind::WhileCondition]),
            Structure::Monitor(vec![MonitorKind::Condition, MonitorKind::WhileCondition]),
        ]
    }

    #[test]
    fn every_structure_verifies_with_every_mix_of_children() {
        for s in all_structures() {
            let n = s.arity();
            for mask in 0..(1u32 << n) {
                let children: Vec<Child> =
                    (0..n).map(|i| if mask & (1 << i) != 0 { Child::Instant } else { Child::Reduced }).collect();
                // An instantaneous loop body with an instantaneous condition never reaches a
                // tangible marking: that is a property of the program (reported for missions), not of the block.
                if s == Structure::While && children.iter().all(|c| *c == Child::Instant) {
                    continue;
                }
                if matches!(&s, Structure::Monitor(k) if k.contains(&MonitorKind::WhileCondition))
                    && children.iter().all(|c| *c == Child::Instant)
                {
                    continue;
                }
                let v = structure_harness(&s, &children).verify(2_000_000);
                assert!(v.ok(), "{} with {children:?}: {:#?}", s.name(), v.violations);
            }
        }
    }

    #[test]
    fn the_call_adapter_verifies() {
        let v = call_adapter_harness().verify(100_000);
        assert!(v.ok(), "{:#?}", v.violations);
    }

    #[test]
    fn a_broken_structure_is_caught_with_a_counterexample() {
        // A sequence whose abort forgets the second child: aborting while B runs deadlocks.
        let mut b = Builder::new("broken");
        let ext = b.iface("cs", 1);
        let env = environment(&mut b, ext);
        let a = b.iface("a", 2);
        let run = b.place("run", 0);
        b.imm("start", &[ext.begin], &[a.begin, run]);
        b.imm("ok", &[run, a.ok], &[ext.ok]);
        b.imm("fail", &[run, a.fail], &[ext.fail]);
        // No abort transition at all.
        let exe = b.place("c.exe", 0);
        b.imm("c.start", &[a.begin], &[exe]);
        b.transition("c.ok", TransitionKind::Event("e1".into()), &[exe], &[a.ok]);
        b.transition("c.fail", TransitionKind::Event("e2".into()), &[exe], &[a.fail]);
        b.imm("c.abort", &[a.abort, exe], &[]);
        let net = b.finish().build().unwrap();
        let h = harness(net, ext, env, false);
        let v = h.verify(10_000);
        assert!(!v.ok());
        let r = v.violations.iter().find(|v| v.property == "exactly-one").expect("late outcome after abort");
        // The abort is never forwarded: the child ends on its own and its result is left behind.
        assert_eq!(r.trace, vec!["begin", "start", "c.start", "abort", "c.ok", "ok"]);
    }

    /// A block that only an abort can end is stuck when nobody aborts it.
    #[test]
    fn a_block_that_needs_an_abort_to_end_is_stuck() {
        let mut b = Builder::new("dead");
        let ext = b.iface("x", 1);
        let run = b.place("run", 0);
        b.imm("T0", &[ext.begin], &[run]);
        b.imm("TA", &[run, ext.abort], &[]);
        let task = b.finish().build().unwrap();
        // As a task net: interface places named begin/abort/ok/fail.
        let mut nb = mcl_net::NetBuilder::new("dead");
        let ids: Vec<_> = ["begin", "abort", "ok", "fail", "run"]
            .iter()
            .map(|n| nb.add_place(mcl_net::Place::new(*n).with_interface(u32::from(*n != "run"))))
            .collect();
        let t0 = nb.add_transition(mcl_net::Transition::new("T0"));
        let ta = nb.add_transition(mcl_net::Transition::new("TA"));
        nb.add_input(ids[0], t0, 1).add_output(t0, ids[4], 1);
        nb.add_input(ids[4], ta, 1).add_input(ids[1], ta, 1);
        let net = nb.build().unwrap();
        drop(task);
        let v = task_harness(&net).unwrap().verify(1000);
        let r = v.violations.iter().find(|v| v.property == "reachability").expect("stuck without abort");
        assert_eq!(r.trace, vec!["begin", "T0"]);
        assert!(r.message.contains("{run}"), "{}", r.message);
        assert!(!r.message.contains("env."), "{}", r.message);
    }
}
