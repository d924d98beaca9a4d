//! The ten control structures as Petri net building blocks (seed 4.5,
//! Appendix B), generated for any number of children.
//!
//! Every block has the external interface {begin, abort, ok, fail} and one
//! internal interface per child. The protocol between a block and a child:
//!
//! * the block marks the child's `begin` once and then waits for exactly one
//!   of its `ok`/`fail`;
//! * the block marks the child's `abort` only while the child runs and has not
//!   produced its outcome, and only in a *tangible* marking (no immediate
//!   transition enabled). A child aborted this way returns to rest through
//!   immediate transitions and marks no outcome.
//!
//! The second rule removes the race between a late result and an abort
//! (SEED-NOTES item 2): a block that decides on its own to stop a child
//! (parallel-or, monitor) does it with a *deferred* transition, a timed
//! transition with delay 0, which fires only once every immediate cascade has
//! settled — by then a child that was about to finish has finished, and its
//! outcome has been consumed as a "late" result. Aborts that arrive from the
//! parent are forwarded by immediate transitions: they start in a tangible
//! marking, so the same holds for the whole cascade. Symmetrically, what a
//! block does *after* aborting children (end, run a do-block, restart) is
//! deferred too, so that an aborted child has returned to rest before it can
//! be started again.

use super::builder::{Builder, Iface, Part, Part::N, Part::S};
use mcl_net::PlaceId;
use mcl_syntax::ast::MonitorKind;

/// A control structure and the number of its children.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Structure {
    /// `A ; B ; ...` — children in order.
    Sequence(usize),
    /// `if ( A ) { B }` — children [A, B]. If A fails the block ends ok.
    IfThen,
    /// `if ( A ) { B } else { C }` — children [A, B, C].
    IfThenElse,
    /// `while ( A ) { B }` — children [A, B].
    While,
    /// `try { A } catch { B }` — children [A, B].
    TryCatch,
    /// `not ( A )` — child [A].
    Not,
    /// `parallel { A } and { B } ...` — all run; ok iff all end ok.
    ParallelAnd(usize),
    /// `parallel { A } or { B } ...` — the first to end decides, the others are aborted.
    ParallelOr(usize),
    /// `monitor { A } condition ( B ) do { C } ...` — children [A, B1, C1, B2, C2, ...].
    Monitor(Vec<MonitorKind>),
}

impl Structure {
    /// The structure's name as used in documentation and provenance.
    pub fn name(&self) -> &'static str {
        match self {
            Structure::Sequence(_) => "sequence",
            Structure::IfThen => "if-then",
            Structure::IfThenElse => "if-then-else",
            Structure::While => "while-do",
            Structure::TryCatch => "try-catch",
            Structure::Not => "not",
            Structure::ParallelAnd(_) => "parallel-and",
            Structure::ParallelOr(_) => "parallel-or",
            Structure::Monitor(k) if k.len() == 1 && k[0] == MonitorKind::WhileCondition => {
                "monitor-while_condition-do"
            }
            Structure::Monitor(k) if k.len() == 1 => "monitor-condition-do",
            Structure::Monitor(_) => "monitor",
        }
    }

    /// The number of children (internal interfaces).
    pub fn arity(&self) -> usize {
        match self {
            Structure::Sequence(n) | Structure::ParallelAnd(n) | Structure::ParallelOr(n) => *n,
            Structure::IfThen | Structure::While | Structure::TryCatch => 2,
            Structure::IfThenElse => 3,
            Structure::Not => 1,
            Structure::Monitor(k) => 1 + 2 * k.len(),
        }
    }

    /// What the structure does, in one paragraph (hover text, docs).
    pub fn describe(&self) -> &'static str {
        match self {
            Structure::Sequence(_) => "Runs its blocks one after the other. Ends fail as soon as one fails; ends ok when the last one ends ok.",
            Structure::IfThen => "Runs the condition; if it ends ok runs the then-block and ends with its result; if it ends fail, ends ok without running anything else.",
            Structure::IfThenElse => "Runs the condition; if it ends ok runs the then-block, otherwise the else-block, and ends with the result of the block it ran.",
            Structure::While => "Runs the condition; while it ends ok runs the body and starts again. Ends ok when the condition ends fail, and fail as soon as the body fails.",
            Structure::TryCatch => "Runs the try-block; ends ok if it ends ok. If it fails, runs the catch-block and ends with its result.",
            Structure::Not => "Runs its block and inverts the result: ok becomes fail and fail becomes ok.",
            Structure::ParallelAnd(_) => "Runs every branch at the same time and waits for all of them. Ends ok if every branch ended ok, fail otherwise.",
            Structure::ParallelOr(_) => "Runs every branch at the same time. The first branch to end decides the result; the others are aborted first (their primitives are disabled).",
            Structure::Monitor(_) => "Runs the monitored block and the conditions at the same time. If the monitored block ends first, the conditions are aborted and its result is the result. If a condition ends first (ok or fail), everything else is aborted and its do-block runs: after `condition` the do-block's result is the result; after `while_condition` an ok do-block starts the whole monitor again (a failing one ends it with fail).",
        }
    }
}

impl Structure {
    /// True when child `i` runs in competition with the others, so that the
    /// structure itself may decide to abort it (every branch of a
    /// parallel-or; the monitored block and the conditions of a monitor).
    /// Such a child runs only while the structure's `open` place (returned
    /// by [`build`]) is marked: a call inside it starts only while `open`
    /// is marked, so no call starts once the structure has decided to abort
    /// it (stop before start, no useless enable).
    pub fn competes(&self, i: usize) -> bool {
        match self {
            Structure::ParallelOr(_) => true,
            Structure::Monitor(_) => i == 0 || i % 2 == 1,
            _ => false,
        }
    }
}

/// Builds the net of `s` on the external interface `ext` and returns the
/// internal interfaces of its children, in the order of [`Structure`], and
/// the place that is marked while competing children may still start
/// calls (see [`Structure::competes`]).
pub fn build(b: &mut Builder, s: &Structure, ext: Iface, prefix: &str) -> (Vec<Iface>, Option<PlaceId>) {
    let mut open_place = None;
    let kids: Vec<Iface> = (0..s.arity()).map(|i| b.iface_parts(&[S(prefix), S("."), N(i)], i as u32 + 2)).collect();
    // Local nodes are `prefix.p_NAME` and `prefix.t_NAME`, apart from the
    // interface places `prefix.I.begin` of the children.
    let local = |b: &mut Builder, kind: &str, name: &[Part<'_>]| {
        let mut parts: [Part<'_>; 8] = [S(""); 8];
        parts[0] = S(prefix);
        parts[1] = S(kind);
        parts[2..2 + name.len()].copy_from_slice(name);
        b.id(&parts[..2 + name.len()])
    };
    let p = |b: &mut Builder, name: &[Part<'_>]| {
        let id = local(b, ".p_", name);
        b.place(id, 0)
    };
    let ti = |b: &mut Builder, name: &[Part<'_>], inputs: &[PlaceId], outputs: &[PlaceId]| {
        let id = local(b, ".t_", name);
        b.imm(id, inputs, outputs)
    };
    let td = |b: &mut Builder, name: &[Part<'_>], inputs: &[PlaceId], outputs: &[PlaceId]| {
        let id = local(b, ".t_", name);
        b.deferred(id, inputs, outputs)
    };
    match s {
        Structure::Not => {
            let run = p(b, &[S("run")]);
            let a = kids[0];
            ti(b, &[S("start")], &[ext.begin], &[a.begin, run]);
            ti(b, &[S("ok_to_fail")], &[run, a.ok], &[ext.fail]);
            ti(b, &[S("fail_to_ok")], &[run, a.fail], &[ext.ok]);
            ti(b, &[S("abort")], &[ext.abort, run], &[a.abort]);
        }
        Structure::Sequence(n) => {
            let runs: Vec<_> = (0..*n).map(|i| p(b, &[S("run"), N(i)])).collect();
            ti(b, &[S("start")], &[ext.begin], &[kids[0].begin, runs[0]]);
            for i in 0..*n {
                if i + 1 < *n {
                    ti(b, &[S("next"), N(i)], &[runs[i], kids[i].ok], &[kids[i + 1].begin, runs[i + 1]]);
                } else {
                    ti(b, &[S("ok"), N(i)], &[runs[i], kids[i].ok], &[ext.ok]);
                }
                ti(b, &[S("fail"), N(i)], &[runs[i], kids[i].fail], &[ext.fail]);
                ti(b, &[S("abort"), N(i)], &[ext.abort, runs[i]], &[kids[i].abort]);
            }
        }
        Structure::IfThen | Structure::IfThenElse | Structure::While | Structure::TryCatch => {
            let runs: Vec<_> = (0..kids.len()).map(|i| p(b, &[S("run"), N(i)])).collect();
            let (a, bb) = (kids[0], kids[1]);
            ti(b, &[S("start")], &[ext.begin], &[a.begin, runs[0]]);
            match s {
                Structure::IfThen => {
                    ti(b, &[S("cond_ok")], &[runs[0], a.ok], &[bb.begin, runs[1]]);
                    ti(b, &[S("cond_fail")], &[runs[0], a.fail], &[ext.ok]);
                }
                Structure::IfThenElse => {
                    let c = kids[2];
                    ti(b, &[S("cond_ok")], &[runs[0], a.ok], &[bb.begin, runs[1]]);
                    ti(b, &[S("cond_fail")], &[runs[0], a.fail], &[c.begin, runs[2]]);
                    ti(b, &[S("else_ok")], &[runs[2], c.ok], &[ext.ok]);
                    ti(b, &[S("else_fail")], &[runs[2], c.fail], &[ext.fail]);
                }
                Structure::While => {
                    ti(b, &[S("cond_ok")], &[runs[0], a.ok], &[bb.begin, runs[1]]);
                    ti(b, &[S("cond_fail")], &[runs[0], a.fail], &[ext.ok]);
                }
                Structure::TryCatch => {
                    ti(b, &[S("try_ok")], &[runs[0], a.ok], &[ext.ok]);
                    let t = ti(b, &[S("try_fail")], &[runs[0], a.fail], &[bb.begin, runs[1]]);
                    b.handlers.push((t, mcl_net::HandlerKind::Catch));
                }
                _ => unreachable!("outer match"),
            }
            if *s == Structure::While {
                ti(b, &[S("body_ok")], &[runs[1], bb.ok], &[a.begin, runs[0]]);
            } else {
                ti(b, &[S("body_ok")], &[runs[1], bb.ok], &[ext.ok]);
            }
            ti(b, &[S("body_fail")], &[runs[1], bb.fail], &[ext.fail]);
            for (i, (k, r)) in kids.iter().zip(&runs).enumerate() {
                ti(b, &[S("abort"), N(i)], &[ext.abort, *r], &[k.abort]);
            }
        }
        Structure::ParallelAnd(n) => {
            let good = p(b, &[S("all_ok")]);
            let bad = p(b, &[S("some_fail")]);
            let stop = p(b, &[S("stop")]);
            let runs: Vec<_> = (0..*n).map(|i| p(b, &[S("run"), N(i)])).collect();
            let done: Vec<_> = (0..*n).map(|i| p(b, &[S("done"), N(i)])).collect();
            let mut start_out = vec![good];
            for i in 0..*n {
                start_out.push(kids[i].begin);
                start_out.push(runs[i]);
            }
            ti(b, &[S("start")], &[ext.begin], &start_out);
            for i in 0..*n {
                ti(b, &[S("ok"), N(i)], &[runs[i], kids[i].ok], &[done[i]]);
                ti(b, &[S("fail"), N(i)], &[runs[i], kids[i].fail, good], &[done[i], bad]);
                ti(b, &[S("fail"), N(i), S("_again")], &[runs[i], kids[i].fail, bad], &[done[i], bad]);
                ti(b, &[S("kill"), N(i)], &[stop, runs[i]], &[stop, kids[i].abort, done[i]]);
            }
            ti(b, &[S("end_ok")], &with(&done, good), &[ext.ok]);
            ti(b, &[S("end_fail")], &with(&done, bad), &[ext.fail]);
            ti(b, &[S("abort")], &[ext.abort, good], &[stop]);
            ti(b, &[S("abort_failing")], &[ext.abort, bad], &[stop]);
            ti(b, &[S("aborted")], &with(&done, stop), &[]);
        }
        Structure::ParallelOr(n) => {
            let open = p(b, &[S("open")]);
            open_place = Some(open);
            let won_ok = p(b, &[S("won_ok")]);
            let won_fail = p(b, &[S("won_fail")]);
            let stop = p(b, &[S("stop")]);
            let runs: Vec<_> = (0..*n).map(|i| p(b, &[S("run"), N(i)])).collect();
            let done: Vec<_> = (0..*n).map(|i| p(b, &[S("done"), N(i)])).collect();
            let mut start_out = vec![open];
            for i in 0..*n {
                start_out.push(kids[i].begin);
                start_out.push(runs[i]);
            }
            ti(b, &[S("start")], &[ext.begin], &start_out);
            for i in 0..*n {
                ti(b, &[S("first_ok"), N(i)], &[open, runs[i], kids[i].ok], &[won_ok, done[i]]);
                ti(b, &[S("first_fail"), N(i)], &[open, runs[i], kids[i].fail], &[won_fail, done[i]]);
                for (m, mname) in [(won_ok, "won_ok"), (won_fail, "won_fail")] {
                    ti(b, &[S("late_ok"), N(i), S("_"), S(mname)], &[m, runs[i], kids[i].ok], &[m, done[i]]);
                    ti(b, &[S("late_fail"), N(i), S("_"), S(mname)], &[m, runs[i], kids[i].fail], &[m, done[i]]);
                    td(b, &[S("kill"), N(i), S("_"), S(mname)], &[m, runs[i]], &[m, kids[i].abort, done[i]]);
                }
                ti(b, &[S("stop"), N(i)], &[stop, runs[i]], &[stop, kids[i].abort, done[i]]);
            }
            // Deferred: the aborted branches have settled before the result moves on.
            td(b, &[S("end_ok")], &with(&done, won_ok), &[ext.ok]);
            td(b, &[S("end_fail")], &with(&done, won_fail), &[ext.fail]);
            for (m, mname) in [(open, "open"), (won_ok, "won_ok"), (won_fail, "won_fail")] {
                ti(b, &[S("abort_"), S(mname)], &[ext.abort, m], &[stop]);
            }
            ti(b, &[S("aborted")], &with(&done, stop), &[]);
        }
        Structure::Monitor(kinds) => {
            let k = kinds.len();
            let open = p(b, &[S("open")]);
            open_place = Some(open);
            let a_ok = p(b, &[S("monitored_ok")]);
            let a_fail = p(b, &[S("monitored_fail")]);
            let stop = p(b, &[S("stop")]);
            let trig: Vec<_> = (0..k).map(|j| p(b, &[S("triggered"), N(j)])).collect();
            let do_run: Vec<_> = (0..k).map(|j| p(b, &[S("do_run"), N(j)])).collect();
            // Parallel part: the monitored block (0) and the conditions (1..=k).
            let par: Vec<Iface> = std::iter::once(kids[0]).chain((0..k).map(|j| kids[1 + 2 * j])).collect();
            let runs: Vec<_> = (0..par.len()).map(|i| p(b, &[S("run"), N(i)])).collect();
            let done: Vec<_> = (0..par.len()).map(|i| p(b, &[S("done"), N(i)])).collect();
            let mut start_out = vec![open];
            for i in 0..par.len() {
                start_out.push(par[i].begin);
                start_out.push(runs[i]);
            }
            ti(b, &[S("start")], &[ext.begin], &start_out);
            ti(b, &[S("monitored_first_ok")], &[open, runs[0], par[0].ok], &[a_ok, done[0]]);
            ti(b, &[S("monitored_first_fail")], &[open, runs[0], par[0].fail], &[a_fail, done[0]]);
            #[allow(clippy::needless_range_loop)] // j indexes trig, j + 1 runs, par and done
            for j in 0..k {
                let i = j + 1;
                let t_ok = ti(b, &[S("condition"), N(j), S("_ok")], &[open, runs[i], par[i].ok], &[trig[j], done[i]]);
                // Seed 4.5.3: whenever the condition finalizes first (ok or fail), the do-block runs.
                let t_fail =
                    ti(b, &[S("condition"), N(j), S("_fail")], &[open, runs[i], par[i].fail], &[trig[j], done[i]]);
                b.handlers.push((t_ok, mcl_net::HandlerKind::Condition));
                b.handlers.push((t_fail, mcl_net::HandlerKind::Condition));
            }
            let modes: Vec<(_, String)> = [(a_ok, "monitored_ok".to_string()), (a_fail, "monitored_fail".to_string())]
                .into_iter()
                .chain(trig.iter().enumerate().map(|(j, &p)| (p, format!("triggered{j}"))))
                .collect();
            for (m, mname) in &modes {
                for i in 0..par.len() {
                    ti(b, &[S("late_ok"), N(i), S("_"), S(mname)], &[*m, runs[i], par[i].ok], &[*m, done[i]]);
                    ti(b, &[S("late_fail"), N(i), S("_"), S(mname)], &[*m, runs[i], par[i].fail], &[*m, done[i]]);
                    td(b, &[S("kill"), N(i), S("_"), S(mname)], &[*m, runs[i]], &[*m, par[i].abort, done[i]]);
                }
            }
            // Deferred: the aborted blocks have settled before anything else starts.
            td(b, &[S("end_ok")], &with(&done, a_ok), &[ext.ok]);
            td(b, &[S("end_fail")], &with(&done, a_fail), &[ext.fail]);
            for j in 0..k {
                let c = kids[2 + 2 * j];
                td(b, &[S("do"), N(j)], &with(&done, trig[j]), &[c.begin, do_run[j]]);
                match kinds[j] {
                    MonitorKind::Condition => {
                        ti(b, &[S("do"), N(j), S("_ok")], &[do_run[j], c.ok], &[ext.ok]);
                    }
                    MonitorKind::WhileCondition => {
                        ti(b, &[S("do"), N(j), S("_ok_restart")], &[do_run[j], c.ok], &start_out);
                    }
                }
                ti(b, &[S("do"), N(j), S("_fail")], &[do_run[j], c.fail], &[ext.fail]);
                ti(b, &[S("abort_do"), N(j)], &[ext.abort, do_run[j]], &[c.abort]);
            }
            for (m, mname) in std::iter::once(&(open, "open".to_string())).chain(modes.iter()) {
                ti(b, &[S("abort_"), S(mname)], &[ext.abort, *m], &[stop]);
            }
            for i in 0..par.len() {
                ti(b, &[S("stop"), N(i)], &[stop, runs[i]], &[stop, par[i].abort, done[i]]);
            }
            ti(b, &[S("aborted")], &with(&done, stop), &[]);
        }
    }
    (kids, open_place)
}

fn with<T: Copy>(v: &[T], extra: T) -> Vec<T> {
    let mut out = v.to_vec();
    out.push(extra);
    out
}
