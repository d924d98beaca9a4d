//! Exhaustive verification of a supervised centralized net, one vehicle at a
//! time and then together.
//!
//! The plain product of two compiled missions is too large to explore (the
//! AUV of `examples/auv-asc.mcl` alone has 3,500 markings, its product with
//! the ASC over ten million), and the counters of order and sync supervisors
//! are unbounded when calls sit in loops. The verification therefore works
//! in three steps, each exact or a sound over-approximation:
//!
//! 1. **Vehicle graphs.** The reachable markings of each vehicle's net alone,
//!    with the *per-vehicle* firing rule (seed Appendix A applied by each
//!    vehicle's player to its own transitions, `mcl_net::semantics::
//!    select_ready`): immediate transitions first, by priority; then
//!    deferred ones (delay 0), by priority; then events and timers. A
//!    transition that a supervisor controls (*gated*) may be held: events of
//!    a marking in which a gated transition waits are recorded with a
//!    *blocked* guard (they are ready only while every waiting gated
//!    transition is held). Transitions connected to a supervisor place are
//!    *visible*; the others are silent (τ). (`lts.rs`)
//! 2. **Reduction.** Each vehicle graph is reduced modulo divergence-
//!    preserving branching bisimulation (signature refinement, Blom and
//!    Orzan), with the gated transitions waiting, the end of the mission
//!    and vanishing markings as state labels. Deadlocks, the reachability
//!    of the missions' ends and every visible behaviour are preserved.
//!    (`quotient.rs`)
//! 3. **Product.** The reduced graphs run together with the supervisor
//!    places. A supervisor place holds 0..=K tokens exactly, or `>K`
//!    (consuming from `>K` may leave `K` or `>K`): every reachable marking of
//!    the real system has an image, so *no dead image* proves *no dead
//!    marking*. The end of the missions must stay reachable from every image
//!    through *pessimistic* steps (`>K` minus one is `K`), which every real
//!    marking with that image can follow, so this proves that no vehicle can
//!    be blocked forever. A *free* verdict of this interleaving product is
//!    a proof; when it has counterexamples, a *settled* product (a
//!    vehicle's ready immediate steps and its allowed starts on its own
//!    supervisors come before any other vehicle's move, as its player
//!    does) only picks counterexamples that replay as dry runs.
//!    (`product.rs`, `group.rs`)
//! 4. **Messages in flight.** The interleaving product holds runs that no
//!    player takes, so its deadlocks are decided by the exact product of
//!    the vehicle nets as the runtime plays them, each message on its way
//!    in the FIFO of its link until it arrives (`flight.rs`): when every
//!    state reached there can still reach the end, the group is free.
//!
//! The product is explored breadth-first with stubborn sets of vehicles
//! (`stubborn.rs`): in each state only the moves of a set of vehicles that
//! no other vehicle can interfere with, in its future, are expanded, with a
//! cycle proviso on the moves that lie on a cycle of their vehicle's graph.
//! Dead states are preserved exactly; every reachable state reaches a
//! state of the reduced graph, so the end reachable from every reduced
//! state proves it reachable from every state, and a blocked state found
//! under the reduction is confirmed on the full product
//! (docs/coordination.md, "Stubborn sets").
//!
//! A dead or blocked image is turned back into a firing sequence of the real
//! net (through the vehicles' graphs) and replayed with exact token counts
//! and the exact per-vehicle firing rule (each step ready for its vehicle);
//! if the replay fails, the image came from an abstraction and the product
//! is rebuilt with a larger K (`replay.rs`).
//!
//! The per-vehicle rule allows every interleaving that the centralized player
//! (one rule for all vehicles) allows, and more: a deadlock-free verdict
//! holds for both.
//!
//! A large group whose supervisors are all resources (mutexes) that each
//! vehicle, holding any, can give back alone, is proven free from the
//! vehicles' graphs alone (`holding.rs`; docs/coordination.md,
//! "Holdings"), loops or not.
//!
//! A large group whose vehicles' graphs have no cycle is first tried by the
//! state equation of the product (`structural_proof.rs`): when no
//! combination of the vehicles' positions and path effects can be dead,
//! the group is free without exploring its product (docs/coordination.md,
//! "The state equation").
//!
//! Scaling (docs/coordination.md, "Scaling"): vehicles that no supervisor
//! links are verified as separate groups (exact: they share no place), and
//! when a group's product of class counts is large, seeded random walks look
//! for a dead state first; only a walk whose end replays on the real net is
//! reported (`group.rs`, `hunt.rs`).

pub mod flight;
mod group;
mod holding;
mod hunt;
mod lts;
mod product;
mod quotient;
mod replay;
mod settle;
mod structural_proof;
mod stubborn;

use std::cell::OnceCell;

use mcl_net::{Marking, Net, PlaceId, TransitionId};
use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::central::Plant;
use crate::model::Mission;
use crate::supervisor::Supervisor;
use group::{groups, verify_group, Group, GroupOutcome, Settled};
use lts::{build_lts, can_end_alone, Lts, LtsError};
use product::Effect;
use quotient::{reduce, Quotient};
use replay::ReplayRules;
use settle::urgency;

/// Caps of the verification.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyOptions {
    /// Largest number of markings of one vehicle's net.
    pub max_vehicle_states: usize,
    /// Largest number of states of the product.
    pub max_product_states: usize,
    /// First value of K (tokens counted exactly in a supervisor place).
    pub counter_cap: u32,
    /// Largest K tried before giving up on a spurious counterexample.
    pub max_counter_cap: u32,
    /// Above this many combinations of the vehicles' reduced states (the
    /// product of their class counts), random walks look for a deadlock
    /// before the exhaustive product.
    pub hunt_threshold: u64,
    /// Largest total number of random-walk steps.
    pub hunt_steps: usize,
    /// Explore the product with stubborn sets of vehicles (partial-order
    /// reduction, `stubborn.rs`); off, every interleaving is expanded.
    pub reduction: bool,
    /// The reduction is used only above this many combinations of the
    /// vehicles' reduced states (the product of their class counts): a
    /// smaller product is explored whole, every interleaving, so that its
    /// counterexamples are the shortest ones and the dry-run scenarios built
    /// from them replay as often as before the reduction existed.
    pub reduction_threshold: u64,
    /// Above this many combinations of the vehicles' reduced states, a
    /// group is first tried by the holdings rule (`holding.rs`: mutexes
    /// alone, loops or not) and, without loops, by the state equation
    /// (`structural_proof.rs`), which prove it free without exploring the
    /// product; `u64::MAX`: never.
    pub structural_threshold: u64,
    /// Largest number of states of the exact product (`flight.rs`: the
    /// players with their messages in flight) that decides a deadlock the
    /// interleaving product reports; beyond it, the deadlock stands.
    pub max_flight_states: usize,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            max_vehicle_states: 2_000_000,
            max_product_states: 4_000_000,
            counter_cap: 1,
            max_counter_cap: 32,
            hunt_threshold: 1_000_000,
            hunt_steps: 200_000,
            reduction: true,
            reduction_threshold: 100_000,
            structural_threshold: 100_000,
            max_flight_states: 200_000,
        }
    }
}

/// Sizes met by a verification.
#[derive(Clone, Debug, Default, Serialize, PartialEq, Eq)]
pub struct VerifyStats {
    /// Markings of each vehicle's graph.
    pub vehicle_states: Vec<usize>,
    /// Classes of each reduced graph.
    pub vehicle_classes: Vec<usize>,
    /// States of the product.
    pub product_states: usize,
    /// K used.
    pub counter_cap: u32,
    /// Groups of vehicles proven free by the state equation, without their
    /// product (`structural_proof.rs`).
    pub structural_proofs: usize,
    /// Groups of vehicles proven free by their holdings, without their
    /// product (`holding.rs`: supervisors that are resources each vehicle
    /// gives back alone).
    pub holding_proofs: usize,
    /// True when no supervisor place ever exceeded K (the product is then
    /// exact, not an over-approximation).
    pub exact: bool,
    /// Groups whose deadlocks in the interleaving product no player reaches
    /// (the exact product, `flight.rs`, proved them free).
    pub flown_free: usize,
}

/// What is wrong in a witness marking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WitnessKind {
    /// No transition can fire and some mission has not ended.
    Dead,
    /// Transitions can fire but some mission can no longer end.
    Blocked,
    /// A nominal run ([`Mission::off_nominal`]: no call fails outside a
    /// condition, no alarm) reaches a marking from which, in nominal runs,
    /// some mission can never end ([`verify_quiet`]).
    Stuck,
}

/// A firing sequence of the supervised centralized net that ends in a
/// deadlock or in a marking from which some mission can no longer end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Witness {
    /// Dead or blocked.
    pub kind: WitnessKind,
    /// The firing sequence, from the initial marking (transition indices of
    /// the supervised net).
    pub path: Vec<TransitionId>,
    /// The marking it ends in.
    pub marking: Marking,
    /// Transitions that wait in that marking only because supervisor places
    /// lack tokens, with the indices of those supervisors.
    pub held: Vec<(TransitionId, Vec<usize>)>,
}

/// Result of a verification.
#[derive(Clone, Debug)]
pub enum Outcome {
    /// No dead marking except the end of every mission, and from every
    /// reachable marking the end of every mission that can end alone is
    /// still reachable.
    Verified(VerifyStats),
    /// Counterexamples, replayed on the real net.
    Problems(Vec<Witness>, VerifyStats),
    /// A cap was reached, or a counterexample stayed spurious.
    Unknown(String, VerifyStats),
}

/// Verifies the supervised net `snet` = plant + `sups` (supervisor places
/// appended in order).
pub fn verify(missions: &[Mission], plant: &Plant, sups: &[Supervisor], snet: &Net, opts: &VerifyOptions) -> Outcome {
    verify_mode(missions, plant, sups, snet, opts, false)
}

/// True when some mission has off-nominal answers ([`Mission::off_nominal`]):
/// only then can [`verify_quiet`] find more than [`verify`].
pub fn has_off_nominal(missions: &[Mission]) -> bool {
    missions.iter().any(|m| !m.off_nominal.is_empty())
}

/// [`verify`] restricted to nominal runs ([`Mission::off_nominal`]: no call
/// fails outside a condition, no monitor condition fires; what a mock
/// vehicle does unless told otherwise, whatever the timing). Its
/// counterexamples, of kind [`WitnessKind::Stuck`], are markings reached by
/// a nominal run from which a mission can end only through a failure or an
/// alarm: a call waiting for ever for a sync partner that a `parallel ...
/// or` withdrew, say. [`verify`] does not see them, since an alarm, always
/// possible, would let the mission end.
pub fn verify_quiet(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
) -> Outcome {
    match verify_mode(missions, plant, sups, snet, opts, true) {
        Outcome::Problems(mut ws, st) => {
            for w in &mut ws {
                w.kind = WitnessKind::Stuck;
            }
            Outcome::Problems(ws, st)
        }
        o => o,
    }
}

fn verify_mode(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
    quiet: bool,
) -> Outcome {
    let nt = plant.net.transition_count();
    let mut gated = vec![false; nt];
    let mut per_t: Vec<Effect> = vec![Effect::default(); nt];
    let mut take_back: Vec<Vec<usize>> = vec![Vec::new(); nt];
    for (k, s) in sups.iter().enumerate() {
        for &t in &s.withdrawn_by {
            per_t[t.index()].take_back.push(k);
            take_back[t.index()].push(k);
        }
        for &(t, w) in &s.consumed_by {
            gated[t.index()] = true;
            per_t[t.index()].consume.push((k, w));
        }
        for &(t, w) in &s.produced_by {
            per_t[t.index()].produce.push((k, w));
        }
    }
    // One label per distinct effect on the supervisor places.
    let mut effects: Vec<Effect> = vec![Effect::default()];
    let mut effect_ids: FxHashMap<Effect, u32> = FxHashMap::default();
    let effect_of: Vec<u32> = per_t
        .into_iter()
        .map(|e| {
            if e.consume.is_empty() && e.produce.is_empty() && e.take_back.is_empty() {
                return 0;
            }
            let next = effects.len() as u32;
            *effect_ids.entry(e.clone()).or_insert_with(|| {
                effects.push(e);
                next
            })
        })
        .collect();
    let urgency = urgency(plant, sups, &effects, nt);
    let mut stats = VerifyStats::default();
    let mut ltss = Vec::new();
    for (m, part) in missions.iter().zip(&plant.parts) {
        match build_lts(m, part.transitions.start, &effect_of, &gated, &[], quiet, opts.max_vehicle_states) {
            Ok(l) => {
                stats.vehicle_states.push(l.len());
                ltss.push(l);
            }
            Err(LtsError::TooMany) => {
                return Outcome::Unknown(
                    format!("mission `{}` has more than {} markings", m.name, opts.max_vehicle_states),
                    stats,
                )
            }
            Err(LtsError::Unbounded) => {
                return Outcome::Unknown(
                    format!("mission `{}` is not bounded (a place exceeds 200 tokens)", m.name),
                    stats,
                )
            }
        }
    }
    let quots: Vec<Quotient> = ltss.iter().map(|l| reduce(l, false)).collect();
    // The graphs for settling (`product.rs`), built only when a product
    // has counterexamples to choose among: the remote starts wait for their
    // vehicle to settle, and vanishing markings are a label.
    let settled_graphs: OnceCell<Option<Settled>> = OnceCell::new();
    let settled = || {
        settled_graphs
            .get_or_init(|| {
                let remote_ltss = if urgency.remote.iter().any(|&r| r) {
                    let built = missions.iter().zip(&plant.parts).map(|(m, part)| {
                        let t0 = part.transitions.start;
                        build_lts(m, t0, &effect_of, &gated, &urgency.remote, quiet, opts.max_vehicle_states).ok()
                    });
                    Some(built.collect::<Option<Vec<Lts>>>()?)
                } else {
                    None
                };
                let quots = remote_ltss.as_ref().unwrap_or(&ltss).iter().map(|l| reduce(l, true)).collect();
                Some(Settled { ltss: remote_ltss, quots })
            })
            .as_ref()
    };
    stats.vehicle_classes = quots.iter().map(|q| q.n).collect();
    // Which vehicles can end when nothing holds them.
    let can_end: Vec<bool> = ltss.iter().map(can_end_alone).collect();
    // The off-nominal answers, in centralized ids.
    let mut quiet_ts: Vec<Vec<PlaceId>> = vec![Vec::new(); if quiet { nt } else { 0 }];
    if quiet {
        for (m, part) in missions.iter().zip(&plant.parts) {
            for (t, ps) in &m.off_nominal {
                if let Some(x) = quiet_ts.get_mut((t.0 + part.transitions.start) as usize) {
                    *x = ps.iter().map(|p| PlaceId(p.0 + part.places.start)).collect();
                }
            }
        }
    }
    let vehicles: Vec<std::ops::Range<u32>> = plant.parts.iter().map(|p| p.transitions.clone()).collect();
    let finals: Vec<Vec<PlaceId>> = plant.parts.iter().map(|p| p.final_places.clone()).collect();
    let rules = ReplayRules {
        vehicles: &vehicles,
        take_back: &take_back,
        quiet: &quiet_ts,
        finals: &finals,
        remote: &[],
        held: &urgency.remote,
    };
    let settled_rules = ReplayRules { remote: &urgency.remote, ..rules };

    // Vehicles that no supervisor links are independent: each group of
    // linked vehicles is verified alone (docs/coordination.md).
    let groups = groups(plant, sups);
    stats.exact = true;
    let mut witnesses = Vec::new();
    let mut unknown: Option<String> = None;
    // The vehicle nets that the players run, for the exact product
    // (`flight.rs`), built once a group has problems.
    let vehicle_nets: OnceCell<Option<Vec<crate::decentral::VehicleNet>>> = OnceCell::new();
    let vehicle_nets = || vehicle_nets.get_or_init(|| crate::decentralize(missions, sups).ok()).as_ref();
    for (vs, ss) in &groups {
        let g = Group {
            vehicles: vs,
            sups: ss,
            ltss: vs.iter().map(|&v| &ltss[v]).collect(),
            quots: vs.iter().map(|&v| &quots[v]).collect(),
            settled: &settled,
            can_end: vs.iter().map(|&v| can_end[v]).collect(),
            whole: groups.len() == 1,
            rules: &rules,
            settled_rules: &settled_rules,
            urgent: vs.iter().map(|&v| urgency.urgent[v].as_slice()).collect(),
            holders: &urgency.holders,
        };
        match verify_group(&g, plant, &effects, sups, snet, opts, &mut stats) {
            GroupOutcome::Verified => {}
            GroupOutcome::Problems(ws) => {
                // The interleaving product holds runs that no player takes:
                // the exact product decides (docs/coordination.md,
                // "Messages in flight").
                let can: Vec<bool> = vs.iter().map(|&v| can_end[v]).collect();
                let flown =
                    vehicle_nets().map(|nets| flight::fly(missions, nets, vs, &can, quiet, opts.max_flight_states));
                if flown == Some(flight::Flown::Free) {
                    stats.flown_free += 1;
                } else {
                    witnesses.extend(ws);
                }
            }
            GroupOutcome::Unknown(r) => {
                unknown.get_or_insert(r);
            }
        }
    }
    if !witnesses.is_empty() {
        return Outcome::Problems(witnesses, stats);
    }
    match unknown {
        Some(r) => Outcome::Unknown(r, stats),
        None => Outcome::Verified(stats),
    }
}

/// The places of a marking that hold no token (for siphon analysis).
pub fn empty_places(m: &Marking) -> Vec<PlaceId> {
    m.0.iter().enumerate().filter(|(_, &n)| n == 0).map(|(i, _)| PlaceId(i as u32)).collect()
}

/// One vehicle's graph for the link report (`crate::link_report`): the
/// markings of mission `m`'s net alone under the per-vehicle firing rule,
/// its transitions `gated` (indexed by its own transitions) free to be
/// held, as step 1 builds them (`lts.rs`: every run of the vehicle, whatever
/// its supervisors and messages do, is a path from marking 0). Per
/// marking: its moves (transition, next marking) and the gated immediate
/// transitions enabled in it. An error beyond `max` markings or 200 tokens
/// in a place.
pub(crate) fn vehicle_graph(m: &Mission, gated: &[bool], max: usize) -> Result<VehicleGraph, String> {
    // Each gated transition its own effect, so that a marking's waiting
    // effects name its enabled gated immediate transitions.
    let effect_of: Vec<u32> = (0..gated.len() as u32).map(|t| t + 1).collect();
    let lts = lts::build_lts(m, 0, &effect_of, gated, &[], false, max).map_err(|e| match e {
        lts::LtsError::TooMany => format!("mission `{}` has more than {max} markings", m.name),
        lts::LtsError::Unbounded => format!("a place of mission `{}` exceeds 200 tokens", m.name),
    })?;
    let n = lts.len() as u32;
    Ok(VehicleGraph {
        moves: (0..n).map(|s| lts.out(s).iter().map(|e| (e.t, e.to)).collect()).collect(),
        waiting: (0..n).map(|s| lts.gates(s).iter().map(|&g| g - 1).collect()).collect(),
    })
}

/// See [`vehicle_graph`].
pub(crate) struct VehicleGraph {
    /// Per marking: (transition index, next marking).
    pub(crate) moves: Vec<Vec<(u32, u32)>>,
    /// Per marking: the gated immediate transitions enabled in it.
    pub(crate) waiting: Vec<Vec<u32>>,
}
