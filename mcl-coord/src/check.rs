//! Coordination diagnostics for `mcl check` and the language server: the
//! deadlock analysis of a file's missions under its `constraints { ... }`
//! blocks, as compiler diagnostics.
//!
//! * [`codes::DEADLOCKING_CONSTRAINTS`] (E0406, error): the constraints let
//!   the vehicles reach a deadlock (or a marking from which a mission can no
//!   longer end) that no supervisor avoids. The primary label is on one
//!   constraint involved, a secondary label on each other one; notes give the
//!   counterexample in the missions' terms (which calls started, ended,
//!   waited) and the calls that wait for ever.
//! * [`codes::CONFLICTING_CONSTRAINTS`] (E0408, error): constraints that
//!   contradict each other whatever the missions do (`crate::conflict`),
//!   reported first, with a label on each constraint involved.
//! * [`codes::COORDINATION_INCONCLUSIVE`] (W0407, warning): the analysis hit
//!   one of its caps and proved neither.
//!
//! [`coordination_diagnostics`] is a salsa query: the editor recomputes it
//! only when the file or one of its imports changes. It reports nothing for
//! a file without constraints, or while the program has errors (the
//! compiler's checks report those, among them unknown missions and labels).

use mcl_compiler::codes;
use mcl_compiler::compile::calls::{call_nodes, CallNodes};
use mcl_compiler::{Db, FileDiagnostic, SourceFile};
use mcl_syntax::ast::{self, Item};
use mcl_syntax::{Diagnostic, Span};

use crate::analysis::{AnalyzeOptions, Problem, Verdict};
use crate::model::{Constraint, Mission};
use crate::structure::Refusal;
use crate::verify::WitnessKind;

/// The coordination diagnostics of `file` (the root of its program), with the
/// default caps of the analysis.
#[salsa::tracked(returns(ref))]
pub fn coordination_diagnostics(db: &dyn Db, file: SourceFile) -> Vec<FileDiagnostic> {
    // An edit in the editor cancels this query part-way (see `interrupt`).
    diagnostics_inner(db, file, &options(), true)
}

/// [`coordination_diagnostics`] with explicit options (not memoized).
pub fn diagnostics_with(db: &dyn Db, file: SourceFile, opts: &AnalyzeOptions) -> Vec<FileDiagnostic> {
    diagnostics_inner(db, file, opts, false)
}

fn diagnostics_inner(db: &dyn Db, file: SourceFile, opts: &AnalyzeOptions, interruptible: bool) -> Vec<FileDiagnostic> {
    let parsed = mcl_compiler::parse(db, file);
    let blocks: Vec<Span> = parsed
        .file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Constraints(b) if !b.constraints.is_empty() => Some(b.span),
            _ => None,
        })
        .collect();
    let Some(&block) = blocks.first() else {
        return Vec::new();
    };
    // Errors anywhere in the program: the compiler reports them.
    let Ok((missions, constraints)) = crate::source::load(db, file) else {
        return Vec::new();
    };
    // Conflicts by construction (E0408), numbered as the analysis numbers
    // constraints: every block in order.
    let all: Vec<ast::Constraint> = parsed
        .file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Constraints(b) => Some(b.constraints.iter().cloned()),
            _ => None,
        })
        .flatten()
        .collect();
    let conflicts = crate::conflict::conflicts(&all);
    // The problems as a dry run replays them (`crate::replay`).
    let analysis = || crate::replay::analyze_replayable(&missions, &constraints, opts);
    let result = if interruptible {
        crate::interrupt::interruptible(|| db.unwind_if_revision_cancelled(), analysis)
    } else {
        analysis()
    };
    let report = match result {
        Ok(r) => r,
        // Bad references are the checker's errors (E0401-E0405); anything
        // else cannot come from a program without errors.
        Err(_) => return conflicts.into_iter().map(|diag| FileDiagnostic { file, diag }).collect(),
    };
    let diags = match &report.verdict {
        Verdict::Free => Vec::new(),
        Verdict::Unknown { reason } => vec![Diagnostic::warning(
            codes::COORDINATION_INCONCLUSIVE,
            "the deadlock analysis of these constraints is inconclusive",
            keyword(db, file, block),
        )
        .with_label(keyword(db, file, block), "not proven free of deadlock")
        .with_note(format!("the analysis stopped: {reason}"))
        .with_note(format!(
            "{} vehicles, {} constraints, {} supervisors; vehicle graphs reduced to {:?} classes, {} product states",
            missions.len(),
            constraints.len(),
            report.supervisors.len(),
            report.stats.vehicle_classes,
            report.stats.product_states
        ))
        .with_help(
            "the vehicles may still deadlock: split the missions into independent groups (constraints that \
             link fewer vehicles), or remove constraints, until the analysis concludes",
        )],
        Verdict::Deadlock => {
            reported(&report.problems).into_iter().map(|p| deadlock(p, &missions, &constraints, block)).collect()
        }
    };
    conflicts.into_iter().chain(diags).map(|diag| FileDiagnostic { file, diag }).collect()
}

/// The problems that E0406 reports, one per set of constraints involved,
/// in the order of the diagnostics.
pub fn reported(problems: &[Problem]) -> Vec<&Problem> {
    let mut seen: Vec<&[usize]> = Vec::new();
    let mut out = Vec::new();
    for p in problems {
        if !seen.contains(&p.constraints.as_slice()) {
            seen.push(&p.constraints);
            out.push(p);
        }
    }
    out
}

/// The options of the analysis behind the diagnostics.
pub fn options() -> AnalyzeOptions {
    AnalyzeOptions { structure: false, ..AnalyzeOptions::default() }
}

/// The keyword that opens a constraints block (the whole block when its
/// text is not at hand).
fn keyword(db: &dyn Db, file: SourceFile, block: Span) -> Span {
    let text = file.text(db).as_deref().unwrap_or("");
    let rest = text.get(block.start as usize..block.end as usize).unwrap_or("");
    match rest.find(|c: char| c.is_whitespace() || c == '{') {
        Some(n) if n > 0 => Span { start: block.start, end: block.start + n as u32 },
        _ => block,
    }
}

fn span_of(c: &Constraint, fallback: Span) -> Span {
    c.span.map_or(fallback, |(s, e)| Span { start: s, end: e.max(s) })
}

/// The diagnostic of one problem.
fn deadlock(p: &Problem, missions: &[Mission], constraints: &[Constraint], block: Span) -> Diagnostic {
    let calls = Calls::new(missions);
    let waiting: Vec<String> = p.waiting.iter().map(|w| format!("`{w}`")).collect();
    let what = match p.kind {
        WitnessKind::Dead => "a deadlock",
        WitnessKind::Blocked => "a state where a mission can never end",
        WitnessKind::Stuck => "a state where, with no failure and no alarm, a mission can never end",
    };
    let message = if waiting.is_empty() {
        format!("these constraints can lead to {what}")
    } else {
        let verb = if waiting.len() == 1 { "waits" } else { "wait" };
        format!("these constraints can lead to {what}: {} {verb} for ever", and(&waiting))
    };
    // Which calls each constraint holds in the marking reached.
    let holds = |k: usize| -> Vec<String> {
        p.held_by.iter().zip(&p.waiting).filter(|((_, ks), _)| ks.contains(&k)).map(|(_, w)| format!("`{w}`")).collect()
    };
    let label_of = |k: usize| -> String {
        let h = holds(k);
        if h.is_empty() {
            format!("constraint {} is involved", k + 1)
        } else {
            format!("constraint {} holds {}", k + 1, and(&h))
        }
    };
    let (primary, others): (Span, &[usize]) = match p.constraints.split_first() {
        Some((&k, rest)) => (span_of(&constraints[k], block), rest),
        None => (block, &[]),
    };
    let mut d = Diagnostic::error(codes::DEADLOCKING_CONSTRAINTS, message, primary);
    match p.constraints.first() {
        Some(&k) => d = d.with_label(primary, label_of(k)),
        None => d = d.with_label(block, "the missions deadlock under these constraints"),
    }
    for &k in others {
        d = d.with_label(span_of(&constraints[k], block), label_of(k));
    }
    let steps: Vec<String> = p.counterexample.iter().filter_map(|t| calls.describe(t)).collect();
    d = d.with_note(if steps.is_empty() {
        "counterexample: it is reached from the start, before any call".to_string()
    } else {
        format!("counterexample: {}", steps.join(", then "))
    });
    let mut state = Vec::new();
    for (m, mission) in missions.iter().enumerate() {
        let prefix = format!("{}/", mission.name);
        let ended = mission.final_places.iter().any(|&fp| {
            let id = mission.net.place(fp).map(|x| format!("{prefix}{}", x.id)).unwrap_or_default();
            p.marking.iter().any(|mk| mk == &id || mk.starts_with(&format!("{id}*")))
        });
        let held: Vec<String> = p
            .held_by
            .iter()
            .zip(&p.waiting)
            .filter(|((t, _), _)| t.starts_with(&prefix))
            .map(|((_, ks), w)| {
                let by: Vec<String> = ks.iter().map(|k| format!("{}", k + 1)).collect();
                format!("waits at `{w}` (held by constraint {})", by.join(", "))
            })
            .collect();
        let running = calls.running(m, &p.marking);
        let s = if ended {
            "has ended".to_string()
        } else if !held.is_empty() {
            held.join(", ")
        } else if !running.is_empty() {
            format!("runs {}", and(&running))
        } else {
            "cannot move".to_string()
        };
        state.push(format!("`{}` {s}", mission.name));
    }
    d = d.with_note(format!(
        "{}: {}",
        match p.kind {
            WitnessKind::Dead => "then nothing can fire",
            WitnessKind::Blocked => "then some mission can never end",
            WitnessKind::Stuck => "then, unless some call fails or an alarm fires, some mission can never end",
        },
        state.join("; ")
    ));
    match p.refusal {
        Some(Refusal::Void) | Some(Refusal::InitiallyEmpty) => {
            d = d.with_note("no supervisor can avoid it: the calls involved wait for each other from the start")
        }
        Some(Refusal::Uncontrollable) => {
            d = d.with_note(
                "no supervisor can avoid it without holding an event, a timer or the inside of a task, which a \
                 supervisor never does",
            )
        }
        None => {}
    }
    if p.kind == WitnessKind::Stuck {
        return d.with_help(
            "a call held by a sync or an order waits until its partner comes; a partner withdrawn by an abort \
             (another branch of a `parallel ... or` that ends first, a failure in a `try`) never does: keep the \
             partners out of branches that can be aborted, or drop the constraint",
        );
    }
    d.with_help(match p.constraints.len() {
        0 => "the missions deadlock with these constraints; change the missions or the constraints".to_string(),
        1 => "remove or change this constraint (a call it holds can wait for a call that never comes)".to_string(),
        _ => "remove or change one of these constraints so that they no longer wait for each other".to_string(),
    })
}

fn and(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [a] => a.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// The call adapters of every mission, to speak of transitions in the
/// missions' terms.
struct Calls<'a> {
    missions: &'a [Mission],
    nodes: Vec<Vec<CallNodes>>,
}

impl<'a> Calls<'a> {
    fn new(missions: &'a [Mission]) -> Self {
        Calls { missions, nodes: missions.iter().map(|m| call_nodes(&m.net)).collect() }
    }

    fn name(c: &CallNodes) -> String {
        match &c.label {
            Some(l) => format!("`{}() : {l}`", c.task),
            None => format!("`{}()`", c.task),
        }
    }

    /// `mission/id` as a step of the counterexample, when it is a step of
    /// a call (arrives, starts, ends); `None` for the internals.
    fn describe(&self, t: &str) -> Option<String> {
        let (m, id) = t.split_once(crate::central::SEP)?;
        let mi = self.missions.iter().position(|x| x.name == m)?;
        let mission = &self.missions[mi];
        let tid = mission.net.transition_by_id(id)?;
        for c in &self.nodes[mi] {
            let verb = if tid == c.start {
                "starts"
            } else if tid == c.ok {
                "ends ok"
            } else if tid == c.fail {
                "fails"
            } else if tid == c.release {
                "releases its task"
            } else if tid == c.cancel {
                "is withdrawn"
            } else if c.label.is_some() && c.arrived(&mission.net).contains(&tid) {
                "is reached"
            } else {
                continue;
            };
            return Some(format!("{m} {} {verb}", Self::name(c)));
        }
        None
    }

    /// The calls of mission `m` running in a marking (`mission/place` ids).
    fn running(&self, m: usize, marking: &[String]) -> Vec<String> {
        let mission = &self.missions[m];
        self.nodes[m]
            .iter()
            .filter(|c| {
                c.running().iter().any(|&pl| {
                    let id = mission.net.place(pl).map(|x| format!("{}/{}", mission.name, x.id)).unwrap_or_default();
                    marking.iter().any(|mk| mk == &id || mk.starts_with(&format!("{id}*")))
                })
            })
            .map(Self::name)
            .collect()
    }
}
