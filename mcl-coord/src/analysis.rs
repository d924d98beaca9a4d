//! The whole centralized procedure of seed 6.1-6.2: supervisors for the
//! constraints, the centralized supervised net, and deadlock avoidance
//! (Extract 6.1) confirmed by exhaustive verification ([`crate::verify`]).
//!
//! 1. Synthesize the supervisors of every constraint ([`crate::supervisor`]).
//! 2. Verify the supervised net. If it is free of deadlock, stop.
//! 3. For every dead marking found (or a group of vehicles dead while the
//!    others may move), take the minimal siphons of the wrapped
//!    net (Extract 6.1, step 2) that are empty in it and contain an empty
//!    supervisor place: they are uncontrolled (they did empty). Synthesize the
//!    supervisor that keeps such a siphon marked (step 4); if it is valid
//!    (step 5: `D_c ≠ 0`, initial marking ≥ 0) and only holds controllable
//!    transitions, add it (step 6) and go back to 2.
//! 4. A dead marking for which no such supervisor exists is a deadlock that
//!    no supervisor can save: a [`Problem`] on the constraints whose
//!    supervisors hold the waiting calls or lie in the siphon, with the
//!    firing sequence that leads to it.
//! 5. Free of deadlock: verify again, over nominal runs only
//!    ([`verify_quiet`]: no call fails outside a condition, no alarm). A
//!    marking they reach from which a mission can end only through a
//!    failure or an alarm is a [`WitnessKind::Stuck`] problem (a call
//!    waiting for a sync partner that a `parallel ... or` withdrew, say):
//!    a dry run with the mock's default answers could stop there.
//!
//! The invariants and minimal siphons of the final net (steps 1, 3, 4) are
//! reported as well ([`crate::structure::Structure`]).

use mcl_net::structural::{minimal_siphons_within, Limits};
use mcl_net::{Net, PlaceId};
use serde::Serialize;

use crate::central::{centralize, Plant};
use crate::error::CoordError;
use crate::model::{Constraint, Mission};
use crate::structure::{analyze_structure, check_siphon_supervisor, siphon_supervisor, wrapped, Refusal, Structure};
use crate::supervisor::{apply, synthesize, Supervisor};
use crate::verify::{
    empty_places, has_off_nominal, verify, verify_quiet, Outcome, VerifyOptions, VerifyStats, Witness, WitnessKind,
};

/// Options of [`analyze_with`].
#[derive(Clone, Debug)]
pub struct AnalyzeOptions {
    /// Caps of the exhaustive verification.
    pub verify: VerifyOptions,
    /// Caps of the structural analysis (invariants, siphons).
    pub limits: Limits,
    /// Largest number of supervisors added by deadlock avoidance.
    pub max_repairs: usize,
    /// Compute the invariants and minimal siphons of the final net.
    pub structure: bool,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            verify: VerifyOptions::default(),
            limits: Limits { max_rows: 5_000, max_nodes: 2_000, max_results: 64 },
            max_repairs: 8,
            structure: true,
        }
    }
}

/// The analysis' conclusion.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "verdict", rename_all = "snake_case")]
pub enum Verdict {
    /// Proven free of deadlock: no reachable dead marking but the end of
    /// every mission, and every mission that can end alone can still end
    /// from every reachable marking.
    Free,
    /// Some reachable marking is dead or blocks a mission forever; see the
    /// problems.
    Deadlock,
    /// Not decided (a cap was reached).
    Unknown {
        /// Why.
        reason: String,
    },
}

/// A deadlock found, with what causes it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Problem {
    /// Dead marking, or a marking from which a mission can no longer end.
    pub kind: WitnessKind,
    /// Indices of the constraints involved.
    pub constraints: Vec<usize>,
    /// A firing sequence of the centralized supervised net that leads to it
    /// (transition ids `mission/id`).
    pub counterexample: Vec<String>,
    /// The marking reached (marked places, `id` or `id*k`).
    pub marking: Vec<String>,
    /// Calls held by a supervisor in that marking (`mission:label`, or the
    /// transition id when it is not the start of a labelled call).
    pub waiting: Vec<String>,
    /// For each entry of `waiting`, the start transition held (`mission/id`)
    /// and the indices of the constraints whose supervisors hold it.
    pub held_by: Vec<(String, Vec<usize>)>,
    /// An empty siphon of that marking that contains supervisor places.
    pub siphon: Option<Vec<String>>,
    /// Why no supervisor can keep that siphon marked (Extract 6.1, step 5).
    pub refusal: Option<Refusal>,
    /// A sentence for humans.
    pub message: String,
}

/// Result of [`analyze`].
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Every supervisor: those of the constraints, in order, then those added
    /// by deadlock avoidance (origin `siphon`).
    pub supervisors: Vec<Supervisor>,
    /// How many supervisors deadlock avoidance added.
    pub added: usize,
    /// The centralized supervised net (ids `mission/id`; supervisor places
    /// `coord.*`, described in the net properties `coord.supervisor:<id>`).
    #[serde(skip)]
    pub net: Net,
    /// True only when the verdict is [`Verdict::Free`].
    pub deadlock_free: bool,
    /// The conclusion.
    #[serde(flatten)]
    pub verdict: Verdict,
    /// Deadlocks found (empty unless the verdict is [`Verdict::Deadlock`]).
    pub problems: Vec<Problem>,
    /// Invariants and siphons of the final net.
    pub structure: Option<Structure>,
    /// Sizes met by the verification.
    pub stats: VerifyStats,
}

/// [`analyze_with`] with the default options.
pub fn analyze(missions: &[Mission], constraints: &[Constraint]) -> Result<Report, CoordError> {
    analyze_with(missions, constraints, &AnalyzeOptions::default())
}

/// The centralized net with its supervisors, described in its properties.
pub fn supervised_net(plant: &Plant, sups: &[Supervisor]) -> Result<Net, CoordError> {
    let net = apply(&plant.net, sups)?;
    let mut b = net.to_builder();
    for s in sups {
        b.property(format!("coord.supervisor:{}", s.id), s.describe(&plant.net));
    }
    Ok(b.build()?)
}

/// Supervisors, deadlock avoidance and verification of `missions` under
/// `constraints` (seed 6.1-6.2).
pub fn analyze_with(
    missions: &[Mission],
    constraints: &[Constraint],
    opts: &AnalyzeOptions,
) -> Result<Report, CoordError> {
    let plant = centralize(missions)?;
    let mut sups = synthesize(&plant, constraints)?;
    let first_added = sups.len();
    let mut repairs = 0usize;
    let np = plant.net.place_count();
    let (verdict, problems, stats, net) = loop {
        let net = supervised_net(&plant, &sups)?;
        match verify(missions, &plant, &sups, &net, &opts.verify) {
            Outcome::Verified(st) if !has_off_nominal(missions) => break (Verdict::Free, Vec::new(), st, net),
            // Free of deadlock; and in nominal runs? (verify.rs, `verify_quiet`)
            Outcome::Verified(st) => match verify_quiet(missions, &plant, &sups, &net, &opts.verify) {
                // The nominal pass may be freed by the exact product too:
                // its count goes with the verdict.
                Outcome::Verified(q) => {
                    let st = VerifyStats { flown_free: st.flown_free + q.flown_free, ..st };
                    break (Verdict::Free, Vec::new(), st, net);
                }
                Outcome::Unknown(reason, _) => break (Verdict::Unknown { reason }, Vec::new(), st, net),
                Outcome::Problems(ws, _) => {
                    let problems =
                        ws.iter().map(|w| problem(&plant, &net, &sups, w, (None, None), &[], constraints)).collect();
                    break (Verdict::Deadlock, problems, st, net);
                }
            },
            Outcome::Unknown(reason, st) => break (Verdict::Unknown { reason }, Vec::new(), st, net),
            Outcome::Problems(ws, st) => {
                let wnet = wrapped(&net, &plant);
                let mut problems = Vec::new();
                let mut added = false;
                for w in &ws {
                    let mut siphon = None;
                    let mut refusal = None;
                    // A blocked witness may hold a dead group of vehicles
                    // (verify.rs): its empty siphons are candidates too.
                    {
                        let empty = empty_places(&w.marking);
                        let req: Vec<PlaceId> = empty.iter().copied().filter(|p| p.index() >= np).collect();
                        let caps = Limits { max_nodes: 2_000, max_results: 16, ..Limits::default() };
                        let sets = minimal_siphons_within(&wnet, &empty, &req, &caps).sets;
                        for s in &sets {
                            let mut cs: Vec<usize> = s
                                .iter()
                                .filter(|p| p.index() >= np)
                                .flat_map(|p| sups[p.index() - np].origin.constraints())
                                .collect();
                            cs.sort_unstable();
                            cs.dedup();
                            let cand =
                                siphon_supervisor(&net, format!("coord.siphon{}", sups.len() - first_added + 1), s, cs);
                            match check_siphon_supervisor(&cand, &plant.controllable) {
                                Ok(()) if repairs < opts.max_repairs && !added => {
                                    sups.push(cand);
                                    added = true;
                                    repairs += 1;
                                    siphon = None;
                                    refusal = None;
                                    break;
                                }
                                Ok(()) => {}
                                Err(r) => {
                                    if siphon.is_none() {
                                        siphon = Some(s.iter().map(|&p| pid(&net, p)).collect());
                                        refusal = Some(r);
                                    }
                                }
                            }
                        }
                    }
                    problems.push(problem(&plant, &net, &sups, w, (siphon, refusal), &[], constraints));
                }
                if added {
                    continue;
                }
                break (Verdict::Deadlock, problems, st, net);
            }
        }
    };
    let structure = opts.structure.then(|| analyze_structure(&net, &plant, np, &opts.limits));
    let mut problems = problems;
    // One problem per set of constraints.
    problems.dedup_by(|a, b| a.constraints == b.constraints && a.kind == b.kind);
    Ok(Report {
        added: sups.len() - first_added,
        supervisors: sups,
        net,
        deadlock_free: verdict == Verdict::Free,
        verdict,
        problems,
        structure,
        stats,
    })
}

fn pid(net: &Net, p: PlaceId) -> String {
    net.place(p).map_or_else(String::new, |x| x.id.to_string())
}

/// The [`Problem`] of the witness `w` of `net` (the supervised net of
/// `plant` and `sups`), with the empty siphon found in its marking and why
/// no supervisor keeps it marked; `also`: constraints involved besides
/// those of the supervisors that hold its calls or lie in the siphon.
pub(crate) fn problem(
    plant: &Plant,
    net: &Net,
    sups: &[Supervisor],
    w: &Witness,
    (siphon, refusal): (Option<Vec<String>>, Option<Refusal>),
    also: &[usize],
    constraints: &[Constraint],
) -> Problem {
    let np = plant.net.place_count();
    let mut cs: Vec<usize> =
        w.held.iter().flat_map(|(_, ss)| ss.iter().flat_map(|&s| sups[s].origin.constraints())).collect();
    cs.extend_from_slice(also);
    if let Some(sp) = &siphon {
        for id in sp {
            if let Some(p) = net.place_by_id(id).filter(|p| p.index() >= np) {
                cs.extend(sups[p.index() - np].origin.constraints());
            }
        }
    }
    cs.sort_unstable();
    cs.dedup();
    let waiting: Vec<String> = w
        .held
        .iter()
        .map(|(t, _)| {
            plant
                .activities
                .iter()
                .find(|(_, a)| a.started.contains(t))
                .map(|(m, a)| format!("{}:{}", plant.parts[*m].name, a.label))
                .unwrap_or_else(|| net.transition(*t).map_or_else(String::new, |x| x.id.to_string()))
        })
        .collect();
    let held_by: Vec<(String, Vec<usize>)> = w
        .held
        .iter()
        .map(|(t, ss)| {
            let mut ks: Vec<usize> = ss.iter().flat_map(|&s| sups[s].origin.constraints()).collect();
            ks.sort_unstable();
            ks.dedup();
            (net.transition(*t).map_or_else(String::new, |x| x.id.to_string()), ks)
        })
        .collect();
    let marking: Vec<String> =
        w.marking.support().map(|(p, n)| if n == 1 { pid(net, p) } else { format!("{}*{n}", pid(net, p)) }).collect();
    let what = match w.kind {
        WitnessKind::Dead => "deadlock",
        WitnessKind::Blocked => "blocking (a mission can no longer end)",
        WitnessKind::Stuck => "a wait for ever in a nominal run (a mission can end only through a failure or an alarm)",
    };
    let mut message = format!(
        "{what}, caused by {}",
        if cs.is_empty() {
            "the missions themselves".to_string()
        } else {
            cs.iter().map(|&k| format!("`{}`", constraints[k])).collect::<Vec<_>>().join(" and ")
        }
    );
    if !waiting.is_empty() {
        message.push_str(&format!("; waiting for ever: {}", waiting.join(", ")));
    }
    match refusal {
        Some(Refusal::Void) => message.push_str(
            "; no supervisor can avoid it: the siphon of the waiting calls keeps its token count (D_c = 0), so nothing can ever mark it",
        ),
        Some(Refusal::InitiallyEmpty) => {
            message.push_str("; no supervisor can avoid it: the siphon of the waiting calls is empty from the start")
        }
        Some(Refusal::Uncontrollable) => message
            .push_str("; the supervisor that would avoid it must hold events or block internals, which is not allowed"),
        None => {}
    }
    Problem {
        kind: w.kind,
        constraints: cs,
        counterexample: w
            .path
            .iter()
            .map(|&t| net.transition(t).map_or_else(String::new, |x| x.id.to_string()))
            .collect(),
        marking,
        waiting,
        held_by,
        siphon,
        refusal,
        message,
    }
}
