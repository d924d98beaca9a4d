//! Verification of building blocks (seed 4.3.1, A.2-A.4).
//!
//! A block is placed in a *harness*: an environment that marks `begin` once,
//! may mark `abort` at any tangible marking while the block runs, and
//! consumes the outcome; control structures get a reduced block (seed
//! `N_PNBB1`, or an instantaneous one) plugged into each internal interface.
//! The whole reachability graph is explored under the MCL semantics (an
//! immediate transition always fires first; events, timers and the
//! environment's abort fire in tangible markings, in every order — a
//! superset of what the player does, so what holds here holds there) and
//! these properties are checked:
//!
//! * **common interface** — begin, abort, ok, fail on interface 1 (the checker);
//! * **1-safeness** — no place ever holds two tokens;
//! * **reachability condition** — every dead marking is a valid final
//!   marking (exactly one of ok/fail delivered, or aborted), and from every
//!   reachable marking a valid final marking can be reached (no trap);
//! * **reusability** — in every final marking, every place of the block
//!   (and of its children) is back to its initial marking;
//! * for task patterns: an abort is handled at once (through immediate
//!   transitions) and an abort at rest enables nothing.
//!
//! A violation comes with the shortest run that shows it.

use super::builder::{Builder, Iface};
use super::structures::{self, Structure};
use mcl_net::{Net, PlaceId, TransitionId, TransitionKind};
use rustc_hash::FxHashMap;
use std::collections::VecDeque;

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
    pub property: &'static str,
    pub message: String,
    /// Transition names of the block, with environment steps in parentheses.
    pub trace: Vec<String>,
}

/// The outcome of a verification.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    pub states: usize,
    pub tangible: usize,
    pub violations: Vec<Violation>,
}

impl Verdict {
    pub fn ok(&self) -> bool {
        self.violations.is_empty()
    }
}

/// A block in its harness, ready to explore.
pub struct Harness {
    pub net: Net,
    /// Exactly one of these is marked in a final marking.
    finals: Vec<PlaceId>,
    /// Marked when the environment aborted the block (tasks only).
    aborted: Option<PlaceId>,
    /// Places of the environment (not checked for reusability).
    env: Vec<PlaceId>,
    /// Transitions of the environment, shown in parentheses in traces.
    env_transitions: Vec<TransitionId>,
    abort_place: Option<PlaceId>,
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
        finals: vec![ok, fail],
        aborted: None,
        env: vec![begin, ok, fail, abort],
        env_transitions: vec![],
        abort_place: None,
        is_task: false,
    })
}

/// Adds the environment around the external interface `ext`.
fn environment(b: &mut Builder, ext: Iface) -> (PlaceId, PlaceId, PlaceId, Vec<PlaceId>, Vec<TransitionId>) {
    let idle = b.place("env.idle", 1);
    let run = b.place("env.running", 0);
    let got_ok = b.place("env.got_ok", 0);
    let got_fail = b.place("env.got_fail", 0);
    let aborted = b.place("env.aborted", 0);
    let ts = vec![
        b.imm("env.begin", &[idle], &[ext.begin, run]),
        b.imm("env.ok", &[run, ext.ok], &[got_ok]),
        b.imm("env.fail", &[run, ext.fail], &[got_fail]),
        b.transition("env.abort", TransitionKind::Event("env.abort".into()), &[run], &[ext.abort, aborted]),
    ];
    (got_ok, got_fail, aborted, vec![idle, run, got_ok, got_fail, aborted], ts)
}

/// A control structure with the given children plugged in.
pub fn structure_harness(s: &Structure, children: &[Child]) -> Harness {
    let mut b = Builder::new(s.name());
    let ext = b.iface("ext", 1);
    let (got_ok, got_fail, aborted, env, env_transitions) = environment(&mut b, ext);
    let kids = structures::build(&mut b, s, ext, "cs");
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
    Harness {
        abort_place: Some(ext.abort),
        net,
        finals: vec![got_ok, got_fail, aborted],
        aborted: Some(aborted),
        env,
        env_transitions,
        is_task: false,
    }
}

/// A task net (a pattern with its bindings) in the environment. The net must
/// have places `begin`, `abort`, `ok`, `fail`; they are wired to the
/// environment.
pub fn task_harness(task: &Net) -> Option<Harness> {
    let mut nb = task.to_builder();
    let find = |id: &str| task.place_by_id(id);
    let ext = Iface { begin: find("begin")?, abort: find("abort")?, ok: find("ok")?, fail: find("fail")? };
    let mut b = Builder::from_net(std::mem::replace(&mut nb, mcl_net::NetBuilder::new("x")));
    let (got_ok, got_fail, aborted, env, env_transitions) = environment(&mut b, ext);
    let net = b.finish().build().ok()?;
    Some(Harness {
        abort_place: Some(ext.abort),
        net,
        finals: vec![got_ok, got_fail, aborted],
        aborted: Some(aborted),
        env,
        env_transitions,
        is_task: true,
    })
}

struct Graph {
    markings: Vec<Vec<u32>>,
    index: FxHashMap<Vec<u32>, u32>,
    /// (predecessor, transition) for BFS shortest paths.
    parent: Vec<Option<(u32, TransitionId)>>,
    succ: Vec<Vec<u32>>,
    tangible: Vec<bool>,
    /// States not expanded because they are not 1-safe.
    cut: Vec<u32>,
    complete: bool,
}

fn enabled(net: &Net, m: &[u32], t: TransitionId) -> bool {
    net.pre(t).iter().all(|&(p, w)| m[p.index()] >= w)
}

/// Explores the reachability graph under the MCL semantics (immediate first;
/// every non-immediate transition may fire in a tangible marking).
fn explore(net: &Net, max_states: usize) -> Graph {
    let m0: Vec<u32> = net.places().iter().map(|p| p.initial).collect();
    let mut g = Graph {
        markings: vec![m0.clone()],
        index: FxHashMap::default(),
        parent: vec![None],
        succ: vec![],
        tangible: vec![],
        cut: vec![],
        complete: true,
    };
    g.index.insert(m0, 0);
    let mut queue = VecDeque::from([0u32]);
    let ts: Vec<TransitionId> = net.transition_ids().collect();
    while let Some(s) = queue.pop_front() {
        let m = g.markings[s as usize].clone();
        // A marking with two tokens in a place already breaks 1-safeness: it
        // is reported and not expanded, which keeps unbounded nets finite.
        if m.iter().any(|&k| k > 1) {
            if g.succ.len() <= s as usize {
                g.succ.resize(s as usize + 1, Vec::new());
                g.tangible.resize(s as usize + 1, false);
            }
            g.cut.push(s);
            continue;
        }
        let imm: Vec<TransitionId> = ts
            .iter()
            .copied()
            .filter(|&t| net.transition(t).is_some_and(|x| x.kind.is_immediate()) && enabled(net, &m, t))
            .collect();
        let is_tangible = imm.is_empty();
        let fire: Vec<TransitionId> =
            if is_tangible { ts.iter().copied().filter(|&t| enabled(net, &m, t)).collect() } else { imm };
        let mut succ = Vec::with_capacity(fire.len());
        for t in fire {
            let mut m2 = m.clone();
            for &(p, w) in net.pre(t) {
                m2[p.index()] -= w;
            }
            for &(p, w) in net.post(t) {
                m2[p.index()] = m2[p.index()].saturating_add(w);
            }
            let id = match g.index.get(&m2) {
                Some(&id) => id,
                None => {
                    if g.markings.len() >= max_states {
                        g.complete = false;
                        continue;
                    }
                    let id = g.markings.len() as u32;
                    g.index.insert(m2.clone(), id);
                    g.markings.push(m2);
                    g.parent.push(Some((s, t)));
                    queue.push_back(id);
                    id
                }
            };
            succ.push(id);
        }
        if g.succ.len() <= s as usize {
            g.succ.resize(s as usize + 1, Vec::new());
            g.tangible.resize(s as usize + 1, false);
        }
        g.succ[s as usize] = succ;
        g.tangible[s as usize] = is_tangible;
    }
    g.succ.resize(g.markings.len(), Vec::new());
    g.tangible.resize(g.markings.len(), false);
    g
}

impl Harness {
    /// The reachability graph in the DOT language: tangible markings as
    /// ellipses labelled with their marked places, vanishing markings as
    /// dots, final markings in bold; edges labelled with the transition.
    /// `None` when it has more than `max_states` states.
    pub fn reachability_dot(&self, max_states: usize) -> Option<String> {
        use std::fmt::Write;
        let g = explore(&self.net, max_states + 1);
        if g.markings.len() > max_states {
            return None;
        }
        let mut out = String::from("digraph reachability {\n  rankdir=TB; node [fontname=\"Helvetica\", fontsize=9]; edge [fontname=\"Helvetica\", fontsize=8];\n");
        for (i, m) in g.markings.iter().enumerate() {
            let marked: Vec<&str> = self
                .net
                .places()
                .iter()
                .zip(m)
                .filter(|(p, &k)| k > 0 && !p.id.starts_with("env.idle"))
                .map(|(p, _)| p.id.as_str())
                .collect();
            let fin = g.succ[i].is_empty() && self.is_final(m);
            if g.tangible[i] || g.succ[i].is_empty() {
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
        for (i, succ) in g.succ.iter().enumerate() {
            let m = &g.markings[i];
            for &j in succ {
                // Find the transition that leads from i to j.
                let t = self.net.transition_ids().find(|&t| {
                    enabled(&self.net, m, t) && {
                        let mut m2 = m.clone();
                        for &(p, w) in self.net.pre(t) {
                            m2[p.index()] -= w;
                        }
                        for &(p, w) in self.net.post(t) {
                            m2[p.index()] += w;
                        }
                        m2 == g.markings[j as usize]
                    }
                });
                let name = t.and_then(|t| self.net.transition(t)).map(|x| x.id.to_string()).unwrap_or_default();
                let _ = writeln!(out, "  s{i} -> s{j} [label=\"{name}\"];");
            }
        }
        out.push_str("}\n");
        Some(out)
    }

    fn trace(&self, g: &Graph, mut s: u32) -> Vec<String> {
        let mut out = Vec::new();
        while let Some((p, t)) = g.parent[s as usize] {
            let name = self.net.transition(t).map(|x| x.id.to_string()).unwrap_or_default();
            out.push(if self.env_transitions.contains(&t) {
                format!("({})", name.trim_start_matches("env."))
            } else {
                name
            });
            s = p;
        }
        out.reverse();
        out
    }

    fn describe(&self, m: &[u32]) -> String {
        let marked: Vec<String> = self
            .net
            .places()
            .iter()
            .zip(m)
            .filter(|(_, &k)| k > 0)
            .map(|(p, &k)| if k == 1 { p.id.to_string() } else { format!("{}×{k}", p.id) })
            .collect();
        format!("{{{}}}", marked.join(", "))
    }

    fn at_rest(&self, m: &[u32]) -> bool {
        self.net.places().iter().enumerate().all(|(i, p)| self.env.iter().any(|e| e.index() == i) || m[i] == p.initial)
    }

    fn is_final(&self, m: &[u32]) -> bool {
        self.finals.iter().map(|p| m[p.index()]).sum::<u32>() == 1
    }

    /// Explores and checks every property.
    pub fn verify(&self, max_states: usize) -> Verdict {
        let g = explore(&self.net, max_states);
        let mut violations = Vec::new();
        let push = |v: Violation, vs: &mut Vec<Violation>| {
            if !vs.iter().any(|x: &Violation| x.property == v.property) {
                vs.push(v);
            }
        };
        // BFS order means the first state found is at the shortest depth.
        for s in 0..g.markings.len() as u32 {
            let m = &g.markings[s as usize];
            if let Some((i, _)) = m.iter().enumerate().find(|(_, &k)| k > 1) {
                push(
                    Violation {
                        property: "1-safe",
                        message: format!(
                            "place `{}` holds {} tokens in {}",
                            self.net.places()[i].id,
                            m[i],
                            self.describe(m)
                        ),
                        trace: self.trace(&g, s),
                    },
                    &mut violations,
                );
            }
            if g.succ[s as usize].is_empty() && g.complete && !g.cut.contains(&s) {
                if !self.is_final(m) {
                    push(
                        Violation {
                            property: "reachability",
                            message: format!(
                                "deadlock: no transition can fire in {} and the block has not ended",
                                self.describe(m)
                            ),
                            trace: self.trace(&g, s),
                        },
                        &mut violations,
                    );
                } else if !self.at_rest(m) {
                    push(
                        Violation {
                            property: "reusability",
                            message: format!("the block ended but left tokens behind: {}", self.describe(m)),
                            trace: self.trace(&g, s),
                        },
                        &mut violations,
                    );
                }
            }
            if self.is_task
                && g.tangible[s as usize]
                && self.aborted.is_some_and(|a| m[a.index()] == 1)
                && !self.at_rest(m)
                && !g.succ[s as usize].is_empty()
            {
                push(
                    Violation {
                        property: "abort",
                        message: format!(
                            "after an abort the task waits in {} instead of returning to rest at once",
                            self.describe(m)
                        ),
                        trace: self.trace(&g, s),
                    },
                    &mut violations,
                );
            }
        }
        // No trap: from every state a final state is reachable (backward search).
        if g.complete && g.cut.is_empty() {
            let mut pred: Vec<Vec<u32>> = vec![Vec::new(); g.markings.len()];
            for (s, succ) in g.succ.iter().enumerate() {
                for &t in succ {
                    pred[t as usize].push(s as u32);
                }
            }
            let mut good = vec![false; g.markings.len()];
            let mut stack: Vec<u32> = (0..g.markings.len() as u32)
                .filter(|&s| g.succ[s as usize].is_empty() && self.is_final(&g.markings[s as usize]))
                .collect();
            for &s in &stack {
                good[s as usize] = true;
            }
            while let Some(s) = stack.pop() {
                for &p in &pred[s as usize] {
                    if !good[p as usize] {
                        good[p as usize] = true;
                        stack.push(p);
                    }
                }
            }
            if let Some(s) = (0..g.markings.len() as u32).find(|&s| !good[s as usize] && !g.succ[s as usize].is_empty())
            {
                push(
                    Violation {
                        property: "reachability",
                        message: format!(
                            "from {} the block can never end: it loops forever",
                            self.describe(&g.markings[s as usize])
                        ),
                        trace: self.trace(&g, s),
                    },
                    &mut violations,
                );
            }
        }
        if let (true, Some(abort_place)) = (self.is_task, self.abort_place) {
            // An abort at rest must be inert.
            let mut m: Vec<u32> = self.net.places().iter().map(|p| p.initial).collect();
            m[abort_place.index()] += 1;
            let env_ts = &self.env_transitions;
            if let Some(t) = self.net.transition_ids().find(|&t| !env_ts.contains(&t) && enabled(&self.net, &m, t)) {
                push(
                    Violation {
                        property: "abort",
                        message: format!(
                            "an abort at rest fires `{}`: abort must only act on a running task",
                            self.net.transition(t).map(|x| x.id.as_str()).unwrap_or("?")
                        ),
                        trace: vec!["(abort)".into()],
                    },
                    &mut violations,
                );
            }
        }
        if !g.complete {
            violations.push(Violation {
                property: "size",
                message: format!("more than {max_states} states: the block is too large to verify"),
                trace: vec![],
            });
        }
        let tangible = g.tangible.iter().filter(|&&t| t).count();
        Verdict { states: g.markings.len(), tangible, violations }
    }
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
    fn a_broken_structure_is_caught_with_a_counterexample() {
        // A sequence whose abort forgets the second child: aborting while B runs deadlocks.
        let mut b = Builder::new("broken");
        let ext = b.iface("cs", 1);
        let (got_ok, got_fail, aborted, env, env_transitions) = environment(&mut b, ext);
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
        let h = Harness {
            abort_place: Some(ext.abort),
            net,
            finals: vec![got_ok, got_fail, aborted],
            aborted: Some(aborted),
            env,
            env_transitions,
            is_task: false,
        };
        let v = h.verify(10_000);
        assert!(!v.ok());
        let r = v.violations.iter().find(|v| v.property == "reusability").expect("stray abort token");
        // The abort is never forwarded: the child ends on its own and its result is left behind.
        assert_eq!(r.trace, vec!["(begin)", "start", "c.start", "(abort)", "c.ok", "ok"]);
    }
}
