//! The structural part of the deadlock avoidance procedure (seed 6.2,
//! Extract 6.1): the wrapped net (step 2), its invariants (step 1), its
//! minimal siphons and whether each is controlled (steps 3-4), and the
//! supervisor that keeps an uncontrolled siphon marked (steps 4-6).
//!
//! A siphon S (•S ⊆ S•) that loses all its tokens stays empty, and every
//! dead marking of an ordinary net empties one. S is *controlled* when it can
//! never be emptied:
//!
//! * by a place invariant (generalized to an inequality): there are weights
//!   `y ≥ 0` on S with `y·D ≥ 0` (no firing decreases `y·μ`) and `y·μ0 ≥ 1`
//!   (decided by a linear program);
//! * or by a trap: S contains a trap that is marked initially (a marked trap
//!   stays marked).
//!
//! An uncontrolled siphon is kept marked by the constraint `Σ_{p∈S} μ(p) ≥ 1`,
//! i.e. `−1_S·μ ≤ −1`: its supervisor has `D_c = 1_S·D` and
//! `μ_c0 = 1_S·μ0 − 1`. It cannot exist when `D_c = 0` (S carries a place
//! invariant: its token count never changes, step 5) or when `μ_c0 < 0` (S
//! is empty from the start); it may not be used when it would disable a
//! transition that no supervisor controls (an event, or an immediate
//! transition inside a block).
//!
//! (Equation 6.26 of the seed writes the constraint as `l·μ ≤ 1` with
//! `l = 1_S`; the text around it — "initially mark this siphon" — and
//! the standard construction (Ezpeleta, Colom and Martínez 1995; Iordache
//! and Antsaklis) require the opposite inequality, which is used here.)

use good_lp::{constraint, variable, Expression, ProblemVariables, SolverModel};
use mcl_net::structural::{max_trap_within, minimal_siphons_within, p_invariants, Limits};
use mcl_net::{Net, NetBuilder, PlaceId};
use serde::Serialize;

use crate::central::Plant;
use crate::supervisor::{Origin, Supervisor};

/// How a siphon is kept from emptying.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Control {
    /// By a place invariant (`y ≥ 0` on the siphon, `y·D ≥ 0`, `y·μ0 ≥ 1`).
    Invariant,
    /// By a trap inside it that is marked initially.
    Trap,
    /// Not controlled: it may empty.
    None,
}

/// A minimal siphon of the wrapped supervised net.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SiphonInfo {
    /// Its places (ids of the supervised net).
    pub places: Vec<String>,
    /// True when some place is marked initially.
    pub initially_marked: bool,
    /// How it is controlled.
    pub control: Control,
    /// True when it contains a supervisor place.
    pub has_supervisor: bool,
}

/// Result of the structural analysis.
#[derive(Clone, Debug, Serialize)]
pub struct Structure {
    /// Number of minimal P-invariants of the supervised net (step 1).
    pub invariants: usize,
    /// The P-invariants as `place id × weight` (when there are at most 64).
    pub invariant_list: Vec<Vec<(String, u64)>>,
    /// False when the invariant computation hit its cap.
    pub invariants_complete: bool,
    /// Minimal siphons of the wrapped net (step 3).
    pub siphons: Vec<SiphonInfo>,
    /// False when the siphon enumeration hit its cap.
    pub siphons_complete: bool,
}

/// Step 2 of Extract 6.1: `net` with, for every mission, one transition per
/// final place that moves its token back to the mission's initial places.
/// The new transitions are appended (`wrap.<mission>.<k>`).
pub fn wrapped(net: &Net, plant: &Plant) -> Net {
    let mut b: NetBuilder = net.to_builder();
    for part in &plant.parts {
        for (k, &f) in part.final_places.iter().enumerate() {
            let t = b.add_transition(mcl_net::Transition::new(format!("wrap.{}.{k}", part.name)));
            b.add_input(f, t, 1);
            for &p in &part.initial_places {
                b.add_output(t, p, 1);
            }
        }
    }
    b.build().expect("adding transitions keeps the net valid")
}

/// How `siphon` is controlled in `net` (see the module documentation).
pub fn control(net: &Net, siphon: &[PlaceId]) -> Control {
    let m0 = net.initial_marking();
    // A trap inside, marked initially.
    let trap = max_trap_within(net, siphon);
    if trap.iter().any(|&p| m0.get(p) > 0) {
        return Control::Trap;
    }
    if siphon.iter().all(|&p| m0.get(p) == 0) {
        return Control::None;
    }
    // LP: weights y with y·D ≥ 0 for every transition (no firing lowers
    // y·μ), y ≤ 0 outside S and y·μ0 ≥ 1. Then Σ_{p∈S} y_p·μ(p) ≥ y·μ ≥ 1 at
    // every reachable marking, so some place of S stays marked. This is the
    // invariant control of Ezpeleta, Colom and Martínez, with an inequality.
    let np = net.place_count();
    let mut in_s = vec![false; np];
    for &p in siphon {
        in_s[p.index()] = true;
    }
    let mut vars = ProblemVariables::new();
    let y: Vec<_> = (0..np)
        .map(|p| {
            if in_s[p] {
                vars.add(variable().min(-100.0).max(100.0))
            } else {
                vars.add(variable().min(-100.0).max(0.0))
            }
        })
        .collect();
    let mut model = vars.minimise(Expression::from(0.0)).using(good_lp::microlp);
    for t in net.transition_ids() {
        let delta = net.delta(t);
        if delta.is_empty() {
            continue;
        }
        let mut e = Expression::from(0.0);
        for &(p, d) in delta {
            e += d as f64 * y[p.index()];
        }
        model = model.with(constraint!(e >= 0.0));
    }
    let mut e = Expression::from(0.0);
    for p in net.place_ids() {
        if m0.get(p) > 0 {
            e += f64::from(m0.get(p)) * y[p.index()];
        }
    }
    model = model.with(constraint!(e >= 1.0));
    match model.solve() {
        Ok(_) => Control::Invariant,
        Err(_) => Control::None,
    }
}

/// The supervisor that keeps `siphon` marked (`Σ_S μ ≥ 1`), synthesized for
/// `net` (steps 4-6 of Extract 6.1).
pub fn siphon_supervisor(net: &Net, id: impl Into<String>, siphon: &[PlaceId], constraints: Vec<usize>) -> Supervisor {
    let l: Vec<(PlaceId, i64)> = siphon.iter().map(|&p| (p, -1)).collect();
    let names = siphon.iter().map(|&p| net.place(p).map_or_else(String::new, |x| x.id.to_string())).collect();
    Supervisor::synthesize(net, id, Origin::Siphon { siphon: names, constraints }, &l, &[], -1)
}

/// Why a siphon supervisor cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Refusal {
    /// `D_c = 0`: the siphon's token count never changes (step 5).
    Void,
    /// The siphon is empty from the start (`μ_c0 < 0`).
    InitiallyEmpty,
    /// It would disable a transition that no supervisor may hold.
    Uncontrollable,
}

/// Checks a siphon supervisor against step 5 of Extract 6.1 and against the
/// controllable transitions.
pub fn check_siphon_supervisor(s: &Supervisor, controllable: &[bool]) -> Result<(), Refusal> {
    if s.is_void() {
        return Err(Refusal::Void);
    }
    if s.initial < 0 {
        return Err(Refusal::InitiallyEmpty);
    }
    if s.consumed_by.iter().any(|&(t, _)| !controllable.get(t.index()).copied().unwrap_or(false)) {
        return Err(Refusal::Uncontrollable);
    }
    Ok(())
}

/// Nets with at most this many places get every minimal siphon enumerated.
pub const SMALL_NET: usize = 120;

/// Steps 1-4 of Extract 6.1 on the supervised net `snet`, whose places
/// from `supervisor_from` on are supervisor places.
pub fn analyze_structure(snet: &Net, plant: &Plant, supervisor_from: usize, limits: &Limits) -> Structure {
    let inv = p_invariants(snet, limits);
    let invariant_list = if inv.invariants.len() <= 64 {
        inv.invariants
            .iter()
            .map(|v| {
                v.iter().map(|&(p, w)| (snet.place(p).map_or_else(String::new, |x| x.id.to_string()), w)).collect()
            })
            .collect()
    } else {
        Vec::new()
    };
    let w = wrapped(snet, plant);
    let all: Vec<PlaceId> = w.place_ids().collect();
    // Small nets (the seed's compact nets): every minimal siphon. Compiled
    // missions: those that contain a supervisor place (the others are
    // siphons of the missions alone, which are deadlock-free by construction).
    let required: Vec<PlaceId> = if w.place_count() <= SMALL_NET {
        Vec::new()
    } else {
        (supervisor_from..w.place_count()).map(|i| PlaceId(i as u32)).collect()
    };
    let found = minimal_siphons_within(&w, &all, &required, limits);
    let (sets, complete) = (found.sets, found.complete);
    let m0 = w.initial_marking();
    let siphons = sets
        .iter()
        .map(|s| SiphonInfo {
            places: s.iter().map(|&p| w.place(p).map_or_else(String::new, |x| x.id.to_string())).collect(),
            initially_marked: s.iter().any(|&p| m0.get(p) > 0),
            control: control(&w, s),
            has_supervisor: s.iter().any(|p| p.index() >= supervisor_from),
        })
        .collect();
    Structure {
        invariants: inv.invariants.len(),
        invariant_list,
        invariants_complete: inv.complete,
        siphons,
        siphons_complete: complete,
    }
}
