//! Decentralized supervision (seed 6.3, after Iordache and Antsaklis,
//! "Decentralized supervision of Petri nets", IEEE TAC 51(2), 2006).
//!
//! Every vehicle is a subsystem `s_i` that observes its own transitions
//! (`T_o,i`) and controls its own controllable ones (`T_c,i`: the `start`
//! of its calls). A supervisor place `C` observes `T_o^C = •C ∪ C•` and
//! controls `T_c^C = C•` (the estimates of 6.3.1).
//!
//! * [`d_admissibility`] is Extract 6.2: `C` is d-admissible when one
//!   subsystem observes all of `T_o^C` and the subsystems that do together
//!   control `T_c^C`. A supervisor between two vehicles never is.
//! * [`minimize_communication`] is Extract 6.3, the integer program that
//!   chooses which firings each vehicle must be told about.
//! * [`decentralize`] is Extract 6.4: one net per vehicle, with a copy of
//!   every supervisor it takes part in, a receive transition per firing it is
//!   told about, and the list of its firings it must send.
//!
//! ## The integer program (Extract 6.3, reconstructed)
//!
//! The seed's (6.32)-(6.35) are garbled; this is Iordache and Antsaklis'
//! formulation, for supervisors `k = 1..n_c` and subsystems `i = 1..n`:
//!
//! * `α_{i,j} ∈ {0,1}`: the firing of `t_j` is communicated to `s_i` (for
//!   `t_j ∉ T_o,i`);
//! * `ε_{i,j} ∈ {0,1}`: `t_j` is controlled remotely by `s_i` (for
//!   `t_j ∉ T_c,i`);
//! * `δ_{i,k} ∈ {0,1}`: `s_i` takes part in supervisor `k` (keeps a copy of
//!   its place).
//!
//! minimize `Σ c_{i,j}·α_{i,j} + Σ f_{i,j}·ε_{i,j} + Σ h_{i,k}·δ_{i,k}`
//! (6.35) subject to
//!
//! * (6.32) `α_{i,j} ≥ δ_{i,k}` for every `k`, `i` and `t_j ∈ T_o^k \ T_o,i`:
//!   a subsystem that takes part in `k` must learn every firing `k` observes;
//! * (6.33) `Σ_i δ_{i,k} ≥ 1` for every `k`: someone implements `k`;
//! * (6.34) `δ_{x,k} ≤ ε_{x,j} + Σ_{i∈I_j} δ_{i,k}` for every `k`, `x` and
//!   `t_j ∈ T_c^k`, with `I_j = {i : t_j ∈ T_c,i}`: every transition `k`
//!   controls is controlled by a subsystem that takes part in `k`, locally or
//!   remotely.
//!
//! With these choices every supervisor is d-admissible in the system where
//! `T_o,i` is extended by the communicated firings and `T_c,i` by the
//! remotely controlled ones. The costs ([`Costs`]) are: `c` = 1 per
//! transition communicated to a vehicle (an acoustic message each time it
//! fires), `f` = 1000 per remotely controlled transition (a permission
//! round-trip before each firing: never worth it when the owner can take
//! part instead), `h` = 0.001 per participation (prefers fewer copies at
//! equal communication). The program is solved exactly by branch and bound
//! (`good_lp` with the pure-Rust `microlp` solver; the seed used lp_solve).
//!
//! The copies of a supervisor held by several vehicles stay equal when every
//! communicated firing is delivered before the receiver fires anything else
//! (the synchronous communication of Iordache and Antsaklis). With acoustic
//! delays an order or a sync only waits longer; a mutex between vehicles
//! kept by copies needs that assumption, and so does a siphon supervisor of
//! deadlock avoidance that several vehicles take from, so [`decentralize`]
//! gives each a single holder with request / grant / return messages
//! instead ([`vehicle_nets_with_tokens`], [`is_token_supervisor`]). A sync's arrival withdrawn by an abort
//! is taken back by the vehicle that holds its credit when the other call
//! has not used it yet.

use good_lp::{constraint, variable, Expression, ProblemVariables, Solution, SolverModel, Variable};
use mcl_net::coord_props::{BorrowedMutex, BorrowedStart, CoordProps, CoordReceive, CoordSend, TokenKind};
use mcl_net::{Net, NetBuilder, PlaceId, TransitionId, TransitionKind};
use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::central::{centralize, Plant};
use crate::error::CoordError;
use crate::model::Mission;
use crate::supervisor::Supervisor;

/// Extract 6.2 for one supervisor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Admissibility {
    /// Supervisor place id.
    pub supervisor: String,
    /// Missions owning the transitions it observes (`T_o^C`).
    pub observed_by: Vec<String>,
    /// Missions owning the transitions it controls (`T_c^C`).
    pub controlled_in: Vec<String>,
    /// ζ: the missions that observe all of `T_o^C` by themselves.
    pub zeta: Vec<String>,
    /// True when the supervisor can be implemented without communication.
    pub d_admissible: bool,
}

fn owners(plant: &Plant, ts: impl Iterator<Item = TransitionId>) -> Vec<usize> {
    let mut v: Vec<usize> = ts.filter_map(|t| plant.owner_of_transition(t)).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Extract 6.2 for every supervisor.
pub fn d_admissibility(plant: &Plant, sups: &[Supervisor]) -> Vec<Admissibility> {
    sups.iter()
        .map(|s| {
            let obs = owners(plant, s.produced_by.iter().chain(&s.consumed_by).map(|&(t, _)| t));
            let ctl_ts: Vec<TransitionId> = s.consumed_by.iter().map(|&(t, _)| t).collect();
            let ctl = owners(plant, ctl_ts.iter().copied());
            // T_o,i ⊇ T_o^C: only possible when one mission owns them all.
            let zeta: Vec<usize> = if obs.len() <= 1 { obs.clone() } else { Vec::new() };
            let d = !zeta.is_empty()
                && ctl_ts
                    .iter()
                    .all(|&t| zeta.iter().any(|&i| plant.parts[i].owns_transition(t) && plant.controllable[t.index()]));
            let name = |v: &[usize]| v.iter().map(|&i| plant.parts[i].name.clone()).collect();
            Admissibility {
                supervisor: s.id.clone(),
                observed_by: name(&obs),
                controlled_in: name(&ctl),
                zeta: name(&zeta),
                d_admissible: d,
            }
        })
        .collect()
}

/// Costs of the integer program (6.35). Each is a function so that a
/// mission may, say, make one vehicle's messages dearer.
pub struct Costs {
    /// `c_{i,j}`: communicating the firings of transition `t` to vehicle `i`.
    pub communicate: Box<dyn Fn(usize, TransitionId) -> f64>,
    /// `f_{i,j}`: vehicle `i` controlling transition `t` of another vehicle.
    pub remote_control: Box<dyn Fn(usize, TransitionId) -> f64>,
    /// `h_{i,k}`: vehicle `i` taking part in supervisor `k`.
    pub involve: Box<dyn Fn(usize, usize) -> f64>,
}

impl Default for Costs {
    fn default() -> Self {
        Costs {
            communicate: Box::new(|_, _| 1.0),
            remote_control: Box::new(|_, _| 1000.0),
            involve: Box::new(|_, _| 0.001),
        }
    }
}

/// A solution of the integer program.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Communication {
    /// α: (vehicle told, transition) pairs.
    pub alpha: Vec<(usize, TransitionId)>,
    /// ε: (controlling vehicle, transition) pairs.
    pub epsilon: Vec<(usize, TransitionId)>,
    /// δ: (vehicle, supervisor index) pairs.
    pub delta: Vec<(usize, usize)>,
    /// Value of (6.35).
    pub cost: f64,
}

/// Why decentralization failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DecentralizeError {
    /// The missions or constraints are wrong.
    Coord(CoordError),
    /// The integer program has no solution (a supervisor controls a
    /// transition that no vehicle controls).
    Infeasible(String),
    /// The solution controls a transition from another vehicle, which the
    /// per-vehicle nets do not implement (raise `Costs::remote_control`).
    RemoteControl(String),
}

impl std::fmt::Display for DecentralizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DecentralizeError::Coord(e) => write!(f, "{e}"),
            DecentralizeError::Infeasible(m) => write!(f, "no communication policy: {m}"),
            DecentralizeError::RemoteControl(m) => write!(f, "remote control is not supported: {m}"),
        }
    }
}

impl std::error::Error for DecentralizeError {}

impl From<CoordError> for DecentralizeError {
    fn from(e: CoordError) -> Self {
        DecentralizeError::Coord(e)
    }
}

/// Extract 6.3: the communication policy of least cost.
pub fn minimize_communication(
    plant: &Plant,
    sups: &[Supervisor],
    costs: &Costs,
) -> Result<Communication, DecentralizeError> {
    let n = plant.parts.len();
    let owner = |t: TransitionId| plant.owner_of_transition(t).unwrap_or(usize::MAX);
    let mut vars = ProblemVariables::new();
    let mut alpha: FxHashMap<(usize, u32), Variable> = FxHashMap::default();
    let mut eps: FxHashMap<(usize, u32), Variable> = FxHashMap::default();
    let mut delta: Vec<Vec<Variable>> = Vec::new();
    let mut objective = Expression::from(0.0);
    for (k, _) in sups.iter().enumerate() {
        let row: Vec<Variable> = (0..n).map(|_| vars.add(variable().binary())).collect();
        for (i, v) in row.iter().enumerate() {
            objective += (costs.involve)(i, k) * *v;
        }
        delta.push(row);
    }
    for s in sups {
        for &(t, _) in s.produced_by.iter().chain(&s.consumed_by) {
            for i in (0..n).filter(|&i| i != owner(t)) {
                alpha.entry((i, t.0)).or_insert_with(|| {
                    let v = vars.add(variable().binary());
                    objective += (costs.communicate)(i, t) * v;
                    v
                });
            }
        }
        for &(t, _) in &s.consumed_by {
            for i in (0..n).filter(|&i| i != owner(t)) {
                eps.entry((i, t.0)).or_insert_with(|| {
                    let v = vars.add(variable().binary());
                    objective += (costs.remote_control)(i, t) * v;
                    v
                });
            }
        }
    }
    let mut model = vars.minimise(objective.clone()).using(good_lp::microlp);
    for (k, s) in sups.iter().enumerate() {
        // (6.32)
        let mut observed: Vec<TransitionId> = s.produced_by.iter().chain(&s.consumed_by).map(|&(t, _)| t).collect();
        observed.sort_unstable();
        observed.dedup();
        for i in 0..n {
            for &t in observed.iter().filter(|&&t| owner(t) != i) {
                model = model.with(constraint!(alpha[&(i, t.0)] >= delta[k][i]));
            }
        }
        // (6.33)
        let mut sum = Expression::from(0.0);
        for v in &delta[k] {
            sum += *v;
        }
        model = model.with(constraint!(sum >= 1.0));
        // (6.34)
        for &(t, _) in &s.consumed_by {
            let local: Vec<usize> = (0..n)
                .filter(|&i| owner(t) == i && plant.controllable.get(t.index()).copied().unwrap_or(false))
                .collect();
            for x in 0..n {
                if local.contains(&x) {
                    continue;
                }
                let mut rhs = Expression::from(0.0);
                if let Some(e) = eps.get(&(x, t.0)) {
                    rhs += *e;
                }
                for &i in &local {
                    rhs += delta[k][i];
                }
                model = model.with(constraint!(delta[k][x] <= rhs));
            }
        }
    }
    let sol = model.solve().map_err(|e| DecentralizeError::Infeasible(e.to_string()))?;
    let on = |v: &Variable| sol.value(*v) > 0.5;
    let mut out = Communication::default();
    for (&(i, t), v) in &alpha {
        if on(v) {
            out.alpha.push((i, TransitionId(t)));
        }
    }
    for (&(i, t), v) in &eps {
        if on(v) {
            out.epsilon.push((i, TransitionId(t)));
        }
    }
    for (k, row) in delta.iter().enumerate() {
        for (i, v) in row.iter().enumerate() {
            if on(v) {
                out.delta.push((i, k));
            }
        }
    }
    out.alpha.sort_unstable();
    out.epsilon.sort_unstable();
    out.delta.sort_unstable();
    out.cost = out.alpha.iter().map(|&(i, t)| (costs.communicate)(i, t)).sum::<f64>()
        + out.epsilon.iter().map(|&(i, t)| (costs.remote_control)(i, t)).sum::<f64>()
        + out.delta.iter().map(|&(i, k)| (costs.involve)(i, k)).sum::<f64>();
    Ok(out)
}

/// One vehicle's net with its part of the supervision (Extract 6.4).
#[derive(Clone, Debug)]
pub struct VehicleNet {
    /// Mission name.
    pub mission: String,
    /// The mission's net (original ids) with a copy of every supervisor
    /// place it takes part in (`coord.*`) and one event-driven receive
    /// transition per firing of another vehicle it is told about.
    pub net: Net,
    /// (own transition id, mission to tell) for every firing to send.
    pub send: Vec<(String, String)>,
    /// (receive transition id, mission it comes from).
    pub receive: Vec<(String, String)>,
}

/// The event that delivers to a vehicle the firing of transition `id` of
/// mission `mission`: `mission/id`.
pub fn message_event(mission: &str, id: &str) -> String {
    format!("{mission}/{id}")
}

/// Extract 6.4 with a given communication policy: every supervisor of
/// `comm.delta` kept as copies (see [`vehicle_nets_with_tokens`] for the
/// mutexes between vehicles).
pub fn vehicle_nets(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    comm: &Communication,
) -> Result<Vec<VehicleNet>, DecentralizeError> {
    vehicle_nets_with_tokens(missions, plant, sups, comm, &[])
}

/// Net property of a vehicle net: the mutex supervisors between vehicles
/// that it implements with a single holder (see [`vehicle_nets_with_tokens`]),
/// one [`BorrowedMutex`] for each whose calls of this vehicle must ask the
/// holder (none for the holder's own calls).
pub const TOKENS_PROPERTY: &str = mcl_net::coord_props::TOKENS_PROPERTY;

/// True when `s` links several vehicles and is implemented by a single
/// holder with request / grant / return messages rather than by copies
/// ([`decentralize`]): a mutex, or a supervisor of deadlock avoidance
/// (`coord.siphonN`) whose every vehicle gives back only tokens it took
/// ([`gives_back_only_taken`]). Copies of such a supervisor stay equal only
/// under synchronous delivery; a single holder keeps it whatever the delays.
pub fn is_token_supervisor(plant: &Plant, s: &Supervisor) -> bool {
    let vehicles = owners(plant, s.produced_by.iter().chain(&s.consumed_by).map(|&(t, _)| t));
    if vehicles.len() < 2 {
        return false;
    }
    match s.origin {
        crate::supervisor::Origin::Mutex { .. } => true,
        crate::supervisor::Origin::Siphon { .. } => vehicles.iter().all(|&i| gives_back_only_taken(plant, s, i)),
        _ => false,
    }
}

/// True when the firings of vehicle `i` never give `s` more tokens than
/// they took from it, whatever the run: a weighting `y ≥ 0` of the
/// vehicle's places exists, zero on its initially marked places, with
/// `y·D(t) = taken(t) − given(t)` for each of its transitions `t`. Then
/// `y·μ` is the number of tokens the vehicle holds, never negative, so its
/// gifts can be sent to a holder as the return of tokens it was lent (a
/// linear program, `microlp`). A mutex's calls have it by construction
/// (`y` = 1 on the running places).
pub fn gives_back_only_taken(plant: &Plant, s: &Supervisor, i: usize) -> bool {
    let part = &plant.parts[i];
    let mut vars = ProblemVariables::new();
    let y: Vec<Variable> = part.places.clone().map(|_| vars.add(variable().min(0.0))).collect();
    let at = |p: PlaceId| (p.0 - part.places.start) as usize;
    let objective: Expression = y.iter().copied().sum();
    let mut model = vars.minimise(objective).using(good_lp::microlp);
    let m0 = plant.net.initial_marking();
    for p in part.places.clone().map(PlaceId) {
        if m0.get(p) > 0 {
            model = model.with(constraint!(y[at(p)] == 0.0));
        }
    }
    let weight = |arcs: &[(TransitionId, u32)], t: TransitionId| -> f64 {
        arcs.iter().filter(|&&(x, _)| x == t).map(|&(_, w)| f64::from(w)).sum()
    };
    for t in part.transitions.clone().map(TransitionId) {
        let mut effect = Expression::from(0.0);
        for &(p, w) in plant.net.post(t) {
            if part.owns_place(p) {
                effect += f64::from(w) * y[at(p)];
            }
        }
        for &(p, w) in plant.net.pre(t) {
            if part.owns_place(p) {
                effect -= f64::from(w) * y[at(p)];
            }
        }
        let held = weight(&s.consumed_by, t) - weight(&s.produced_by, t);
        model = model.with(constraint!(effect == held));
    }
    model.solve().is_ok()
}

/// Extract 6.4 with a given communication policy for the supervisors of
/// `sups` (copies, [`vehicle_nets`]), plus the supervisors `tokens` between
/// vehicles (mutexes and siphon supervisors, [`is_token_supervisor`]), each
/// with a **single holder** (the first mission, in the order
/// given, that has one of its calls) so that it holds however long messages
/// take. For a mutex place `coord.mutexK` and every other vehicle `B` of it:
///
/// * the holder keeps `coord.mutexK` (its own starts take from it, its own
///   ends give back), a place `coord.mutexK.lent.B` and the transitions
///   `coord.lend.mutexK.B` (event `B/coord.request.mutexK`: one token from
///   `coord.mutexK` to `lent.B`; its firing is sent to `B`: the *grant*),
///   `coord.recv.B.coord.return.mutexK` and `coord.recv.B.<end>` for every
///   end of `B`'s calls (`lent.B` back to `coord.mutexK`: the *return*);
/// * `B` has a place `coord.mutexK` (initially empty: the tokens granted to
///   it) that its starts take from, the transitions `coord.request.mutexK`
///   and `coord.return.mutexK` (events of that name, which `B`'s runtime
///   raises: no arcs / one token from `coord.mutexK`; both sent to the
///   holder) and `coord.recv.<holder>.coord.lend.mutexK.B` (the grant: one
///   token into `coord.mutexK`); its ends are sent to the holder.
///
/// `B`'s runtime asks (fires `coord.request`) when one of its calls could
/// start but for the tokens of such mutexes (in the order of their ids, one
/// at a time), and gives back (`coord.return`) the tokens no call can use
/// any more (a call withdrawn after it asked); property [`TOKENS_PROPERTY`].
/// A request waits in the holder's inbox until a token is free.
pub fn vehicle_nets_with_tokens(
    missions: &[Mission],
    plant: &Plant,
    sups: &[Supervisor],
    comm: &Communication,
    tokens: &[Supervisor],
) -> Result<Vec<VehicleNet>, DecentralizeError> {
    if let Some(&(i, t)) = comm.epsilon.first() {
        return Err(DecentralizeError::RemoteControl(format!(
            "the policy has `{}` control `{}`",
            plant.parts[i].name,
            plant.net.transition(t).map_or("?", |x| x.id.as_str())
        )));
    }
    let local_t = |t: TransitionId| -> (usize, TransitionId) {
        let o = plant.owner_of_transition(t).expect("supervisor arcs touch mission transitions");
        (o, TransitionId(t.0 - plant.parts[o].transitions.start))
    };
    // Sync credits withdrawn: (supervisor index, owner, withdrawing
    // transition) for each copy of a sync supervisor held by a vehicle
    // other than the one whose call arrives (see `withdraw`).
    let mut withdrawals: Vec<(usize, usize, usize, TransitionId)> = Vec::new();
    for &(x, k) in &comm.delta {
        if !matches!(sups[k].origin, crate::supervisor::Origin::Sync { .. }) {
            continue;
        }
        for (_, a) in &plant.activities {
            if !a.arrived.iter().any(|t| sups[k].produced_by.iter().any(|&(p, _)| p == *t)) {
                continue;
            }
            for &w in &a.withdrawn {
                if let Some(o) = plant.owner_of_transition(w).filter(|&o| o != x) {
                    withdrawals.push((x, k, o, w));
                }
            }
        }
    }
    withdrawals.sort_unstable();
    withdrawals.dedup();
    let mut out = Vec::new();
    for (i, m) in missions.iter().enumerate() {
        let mut b: NetBuilder = m.net.to_builder();
        let mut copies: FxHashMap<usize, PlaceId> = FxHashMap::default();
        let mut recv: FxHashMap<u32, TransitionId> = FxHashMap::default();
        let mut receive = Vec::new();
        let told: Vec<TransitionId> = comm.alpha.iter().filter(|&&(x, _)| x == i).map(|&(_, t)| t).collect();
        for &(x, k) in comm.delta.iter().filter(|&&(x, _)| x == i) {
            let _ = x;
            let s = &sups[k];
            let c = b.add_place(
                mcl_net::Place::new(s.id.clone()).with_tokens(u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX)),
            );
            copies.insert(k, c);
            b.property(format!("coord.supervisor:{}", s.id), s.describe(&plant.net));
            let mut arc = |t: TransitionId, w: u32, into: bool, b: &mut NetBuilder| {
                let (o, lt) = local_t(t);
                let tt = if o == i {
                    lt
                } else {
                    debug_assert!(told.contains(&t));
                    *recv.entry(t.0).or_insert_with(|| {
                        let from = &plant.parts[o].name;
                        let id = missions[o].net.transition(lt).map_or_else(String::new, |x| x.id.to_string());
                        let rid = format!("coord.recv.{from}.{id}");
                        receive.push((rid.clone(), from.clone()));
                        b.add_transition(
                            mcl_net::Transition::new(rid).with_kind(TransitionKind::Event(message_event(from, &id))),
                        )
                    })
                };
                if into {
                    b.add_output(tt, c, w);
                } else {
                    b.add_input(c, tt, w);
                }
            };
            for &(t, w) in &s.produced_by {
                arc(t, w, true, &mut b);
            }
            for &(t, w) in &s.consumed_by {
                arc(t, w, false, &mut b);
            }
        }
        // Firings of this vehicle that others must learn.
        let mut send = Vec::new();
        for &(x, t) in &comm.alpha {
            let (o, lt) = local_t(t);
            if o == i {
                let id = m.net.transition(lt).map_or_else(String::new, |x| x.id.to_string());
                send.push((id, plant.parts[x].name.clone()));
            }
        }
        // A sync's arrival withdrawn (the call cancelled by an abort before
        // it started): its credit is taken back if the other call has not
        // used it yet. The cancel's message puts a token into
        // `coord.syncK.i-j.withdrawn`; `withdraw` (priority 2, before any
        // start) takes it with a credit, else `forget` (priority 1) drops it
        // (the other call already started on that arrival).
        let mut pending: FxHashMap<usize, PlaceId> = FxHashMap::default();
        for &(x, k, o, w) in &withdrawals {
            let (_, lw) = local_t(w);
            let wid = missions[o].net.transition(lw).map_or_else(String::new, |t| t.id.to_string());
            if o == i {
                send.push((wid, plant.parts[x].name.clone()));
                continue;
            }
            if x != i {
                continue;
            }
            let Some(&c) = copies.get(&k) else { continue };
            let id = &sups[k].id;
            let p = *pending.entry(k).or_insert_with(|| crate::supervisor::add_take_back(&mut b, id, c));
            let from = plant.parts[o].name.clone();
            let tt = *recv.entry(w.0).or_insert_with(|| {
                let rid = format!("coord.recv.{from}.{wid}");
                receive.push((rid.clone(), from.clone()));
                b.add_transition(
                    mcl_net::Transition::new(rid).with_kind(TransitionKind::Event(message_event(&from, &wid))),
                )
            });
            b.add_output(tt, p, 1);
        }
        // Mutexes and siphon supervisors between vehicles: a single holder.
        let mut table = Vec::new();
        for s in tokens {
            let all = owners(plant, s.produced_by.iter().chain(&s.consumed_by).map(|&(t, _)| t));
            if !all.contains(&i) {
                continue;
            }
            let holder = owners(plant, s.consumed_by.iter().map(|&(t, _)| t)).first().copied().unwrap_or(all[0]);
            let hname = plant.parts[holder].name.clone();
            b.property(format!("coord.supervisor:{}", s.id), s.describe(&plant.net));
            let local_id = |t: TransitionId| {
                let (_, lt) = local_t(t);
                missions[plant.owner_of_transition(t).unwrap_or(0)]
                    .net
                    .transition(lt)
                    .map_or_else(String::new, |x| x.id.to_string())
            };
            let key = s.id.strip_prefix("coord.").unwrap_or(&s.id).to_string();
            if i == holder {
                let initial = u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX);
                let c = b.add_place(mcl_net::Place::new(s.id.clone()).with_tokens(initial));
                for &(t, w) in s.produced_by.iter().filter(|&&(t, _)| plant.parts[i].owns_transition(t)) {
                    b.add_output(local_t(t).1, c, w);
                }
                for &(t, w) in s.consumed_by.iter().filter(|&&(t, _)| plant.parts[i].owns_transition(t)) {
                    b.add_input(c, local_t(t).1, w);
                }
                for &o in all.iter().filter(|&&o| o != i) {
                    let from = plant.parts[o].name.clone();
                    let lent = b.add_place(mcl_net::Place::new(format!("{}.lent.{from}", s.id)));
                    let lend = format!("coord.lend.{key}.{from}");
                    let tl = b.add_transition(
                        mcl_net::Transition::new(lend.clone())
                            .with_kind(TransitionKind::Event(message_event(&from, &format!("coord.request.{key}")))),
                    );
                    b.add_input(c, tl, 1).add_output(tl, lent, 1);
                    receive.push((lend.clone(), from.clone()));
                    send.push((lend, from.clone()));
                    let back = |b: &mut NetBuilder,
                                recv: &mut FxHashMap<u32, TransitionId>,
                                receive: &mut Vec<(String, String)>,
                                gid: Option<u32>,
                                id: String,
                                w: u32| {
                        let mk = |b: &mut NetBuilder, receive: &mut Vec<(String, String)>| {
                            let rid = format!("coord.recv.{from}.{id}");
                            receive.push((rid.clone(), from.clone()));
                            b.add_transition(
                                mcl_net::Transition::new(rid)
                                    .with_kind(TransitionKind::Event(message_event(&from, &id))),
                            )
                        };
                        let tt = match gid {
                            Some(g) => *recv.entry(g).or_insert_with(|| mk(b, receive)),
                            None => mk(b, receive),
                        };
                        b.add_input(lent, tt, w).add_output(tt, c, w);
                    };
                    back(&mut b, &mut recv, &mut receive, None, format!("coord.return.{key}"), 1);
                    for &(t, w) in s.produced_by.iter().filter(|&&(t, _)| plant.parts[o].owns_transition(t)) {
                        back(&mut b, &mut recv, &mut receive, Some(t.0), local_id(t), w);
                    }
                }
            } else {
                let c = b.add_place(mcl_net::Place::new(s.id.clone()));
                let mut starts = Vec::new();
                for &(t, w) in s.consumed_by.iter().filter(|&&(t, _)| plant.parts[i].owns_transition(t)) {
                    b.add_input(c, local_t(t).1, w);
                    starts.push(BorrowedStart { transition: local_id(t), weight: w });
                }
                // Its ends give the tokens back to the holder.
                let mut ends = Vec::new();
                for &(t, _) in s.produced_by.iter().filter(|&&(t, _)| plant.parts[i].owns_transition(t)) {
                    send.push((local_id(t), hname.clone()));
                    ends.push(local_id(t));
                }
                let request = format!("coord.request.{key}");
                b.add_transition(
                    mcl_net::Transition::new(request.clone()).with_kind(TransitionKind::Event(request.clone())),
                );
                send.push((request.clone(), hname.clone()));
                let ret = format!("coord.return.{key}");
                let tr = b.add_transition(
                    mcl_net::Transition::new(ret.clone()).with_kind(TransitionKind::Event(ret.clone())),
                );
                b.add_input(c, tr, 1);
                send.push((ret.clone(), hname.clone()));
                let lend = format!("coord.lend.{key}.{}", m.name);
                let grant = format!("coord.recv.{hname}.{lend}");
                let tg = b.add_transition(
                    mcl_net::Transition::new(grant.clone())
                        .with_kind(TransitionKind::Event(message_event(&hname, &lend))),
                );
                b.add_output(tg, c, 1);
                receive.push((grant.clone(), hname.clone()));
                let kind = match s.origin {
                    crate::supervisor::Origin::Siphon { .. } => TokenKind::Siphon,
                    _ => TokenKind::Mutex,
                };
                table.push(BorrowedMutex {
                    ends,
                    grant,
                    holder: hname,
                    kind,
                    place: s.id.clone(),
                    request,
                    ret,
                    starts,
                    supervisor: s.id.clone(),
                });
            }
        }
        send.sort();
        send.dedup();
        receive.sort();
        receive.dedup();
        CoordProps {
            send: send.iter().map(|(t, to)| CoordSend { to: to.clone(), transition: t.clone() }).collect(),
            receive: receive
                .iter()
                .map(|(t, from)| CoordReceive { from: from.clone(), transition: t.clone() })
                .collect(),
            tokens: table,
        }
        .write(&mut b);
        let net = b.build().map_err(CoordError::from)?;
        out.push(VehicleNet { mission: m.name.clone(), net, send, receive });
    }
    Ok(out)
}

/// The per-vehicle nets of `missions` supervised by `sups` (the supervisors
/// of an analysis [`crate::Report`], added ones included), with the policy
/// of least communication for the default [`Costs`].
pub fn decentralize(missions: &[Mission], sups: &[Supervisor]) -> Result<Vec<VehicleNet>, DecentralizeError> {
    let plant = centralize(missions)?;
    let (tokens, copies): (Vec<Supervisor>, Vec<Supervisor>) =
        sups.iter().cloned().partition(|s| is_token_supervisor(&plant, s));
    let comm = minimize_communication(&plant, &copies, &Costs::default())?;
    vehicle_nets_with_tokens(missions, &plant, &copies, &comm, &tokens)
}

/// The places of `net` that are supervisor copies (`coord.*`).
pub fn supervisor_places(net: &Net) -> Vec<PlaceId> {
    net.place_ids().filter(|&p| net.place(p).is_some_and(|x| x.id.starts_with("coord."))).collect()
}
