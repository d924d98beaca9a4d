//! Supervisor synthesis: supervision based on place invariants (SBPI, seed
//! A.4, Moody and Antsaklis) and its extension to the Parikh vector (seed
//! 6.16-6.18, Iordache and Antsaklis 2002).
//!
//! A constraint `L·μ + C·v ≤ b` (μ the marking, v the Parikh vector: how
//! many times each transition has fired) is enforced by one new place, the
//! *supervisor* (or monitor) place, with
//!
//! * `D_c⁺ = max(0, −L·D − C)` (arcs transition → supervisor),
//! * `D_c⁻ = max(0, L·D + C)` (arcs supervisor → transition),
//! * `μ_c0 = b − L·μ0` (v0 = 0),
//!
//! so that `μ_c = b − L·μ − C·v` at every reachable marking: the place can
//! never go negative, hence the constraint always holds. With C = 0 this is
//! the SBPI `D_c = −L·D`, `μ_c0 = b − L·μ0` (A.10, A.11).
//!
//! The constraints of seed 6.1, on [`Activity`] sets:
//!
//! * **mutex** `(M, β)`: `Σ_{a∈M} Σ_{p∈running(a)} μ(p) ≤ β` (6.5);
//! * **order** `(a, b)`: `Σ v(started(b)) − Σ v(ended(a)) ≤ 0` (6.14): the
//!   k-th start of b needs k endings of a;
//! * **sync** `S`: for every ordered pair `i ≠ j` of S (#S·(#S−1)
//!   supervisors, 6.25), `Σ v(started(j)) − Σ v(arrived(i)) ≤ μ0(waiting(i))`
//!   (6.24): j starts only after i has arrived in its waiting place as many
//!   times. An arrival that an abort later withdraws (the adapter's `cancel`)
//!   gives its credit back when the other call has not used it yet
//!   ([`Supervisor::withdrawn_by`]). That is not an arc: a supervisor may not
//!   hold an abort (the building blocks rely on an abort being processed at
//!   once), so the centralized net keeps (6.24) as printed, and the
//!   per-vehicle nets (`crate::decentral`) and the verification
//!   (`crate::verify`) apply the take-back. On the seed's compact nets
//!   nothing is ever withdrawn.

use mcl_net::{Net, NetBuilder, PlaceId, TransitionId};
use serde::Serialize;

use crate::central::Plant;
use crate::error::CoordError;
use crate::model::{Activity, Constraint, ConstraintKind};

/// Why a supervisor exists.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Origin {
    /// The supervisor of a mutex constraint.
    Mutex {
        /// Index of the constraint.
        constraint: usize,
    },
    /// The supervisor of an order constraint.
    Order {
        /// Index of the constraint.
        constraint: usize,
    },
    /// One of the #S·(#S−1) supervisors of a sync constraint: call `second`
    /// of the constraint may start only once call `first` has arrived.
    Sync {
        /// Index of the constraint.
        constraint: usize,
        /// Position of the call that must have arrived.
        first: usize,
        /// Position of the call whose start is held.
        second: usize,
    },
    /// Added by the deadlock avoidance procedure (seed Extract 6.1) to keep a
    /// siphon from emptying; `constraints` are the constraints whose
    /// supervisors the siphon contains.
    Siphon {
        /// The siphon's places (ids).
        siphon: Vec<String>,
        /// Constraints involved.
        constraints: Vec<usize>,
    },
}

impl Origin {
    /// The constraints this supervisor comes from.
    pub fn constraints(&self) -> Vec<usize> {
        match self {
            Origin::Mutex { constraint } | Origin::Order { constraint } | Origin::Sync { constraint, .. } => {
                vec![*constraint]
            }
            Origin::Siphon { constraints, .. } => constraints.clone(),
        }
    }
}

/// One supervisor place and the constraint it enforces.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Supervisor {
    /// Id of the supervisor place.
    pub id: String,
    /// Why it exists.
    pub origin: Origin,
    /// `L` (sparse: place, weight) over the net it was synthesized for.
    pub l: Vec<(PlaceId, i64)>,
    /// `C` (sparse: transition, weight).
    pub c: Vec<(TransitionId, i64)>,
    /// `b`.
    pub b: i64,
    /// `D_c⁺`: transitions that put tokens into the supervisor place.
    pub produced_by: Vec<(TransitionId, u32)>,
    /// `D_c⁻`: transitions that take tokens from it (the ones it controls).
    pub consumed_by: Vec<(TransitionId, u32)>,
    /// `μ_c0 = b − L·μ0`.
    pub initial: i64,
    /// Transitions that take one token back when there is one, and do
    /// nothing otherwise: the withdrawals (`cancel`) of the calls whose
    /// arrivals a sync supervisor counts. Not arcs of the net: the vehicles
    /// apply them ([`crate::decentral`]) and so does the verification
    /// ([`crate::verify`]); empty for every other supervisor.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub withdrawn_by: Vec<TransitionId>,
}

impl Supervisor {
    /// Synthesizes the supervisor of `L·μ + C·v ≤ b` for `net` (equations
    /// 6.17, 6.18, A.11). `l` and `c` may list a node several times: weights
    /// add up.
    pub fn synthesize(
        net: &Net,
        id: impl Into<String>,
        origin: Origin,
        l: &[(PlaceId, i64)],
        c: &[(TransitionId, i64)],
        b: i64,
    ) -> Supervisor {
        let l = merge(l.iter().map(|&(p, w)| (p.0, w))).into_iter().map(|(p, w)| (PlaceId(p), w)).collect::<Vec<_>>();
        let c =
            merge(c.iter().map(|&(t, w)| (t.0, w))).into_iter().map(|(t, w)| (TransitionId(t), w)).collect::<Vec<_>>();
        let mut ldc = vec![0i64; net.transition_count()];
        let mut lvec = vec![0i64; net.place_count()];
        for &(p, w) in &l {
            if let Some(x) = lvec.get_mut(p.index()) {
                *x = w;
            }
        }
        // (L·D)[t] = Σ_p L[p]·D[p][t]: only transitions touching a place of L.
        let mut touched: Vec<TransitionId> = Vec::new();
        for &(p, _) in &l {
            touched.extend(net.producers(p));
            touched.extend(net.consumers(p));
        }
        touched.sort_unstable();
        touched.dedup();
        for t in touched {
            ldc[t.index()] = net.delta(t).iter().map(|&(p, d)| lvec[p.index()] * d).sum();
        }
        for &(t, w) in &c {
            if let Some(x) = ldc.get_mut(t.index()) {
                *x += w;
            }
        }
        let mut produced_by = Vec::new();
        let mut consumed_by = Vec::new();
        for (i, &x) in ldc.iter().enumerate() {
            // D_c⁺ = max(0, −(L·D + C)), D_c⁻ = max(0, L·D + C).
            if x < 0 {
                produced_by.push((TransitionId(i as u32), u32::try_from(-x).unwrap_or(u32::MAX)));
            } else if x > 0 {
                consumed_by.push((TransitionId(i as u32), u32::try_from(x).unwrap_or(u32::MAX)));
            }
        }
        let m0 = net.initial_marking();
        let initial = b - l.iter().map(|&(p, w)| w * i64::from(m0.get(p))).sum::<i64>();
        Supervisor { id: id.into(), origin, l, c, b, produced_by, consumed_by, initial, withdrawn_by: Vec::new() }
    }

    /// `D_c⁺` as a dense row over `transitions` transitions.
    pub fn d_plus(&self, transitions: usize) -> Vec<i64> {
        let mut row = vec![0; transitions];
        for &(t, w) in &self.produced_by {
            row[t.index()] = i64::from(w);
        }
        row
    }

    /// `D_c⁻` as a dense row.
    pub fn d_minus(&self, transitions: usize) -> Vec<i64> {
        let mut row = vec![0; transitions];
        for &(t, w) in &self.consumed_by {
            row[t.index()] = i64::from(w);
        }
        row
    }

    /// `D_c = D_c⁺ − D_c⁻` as a dense row (the supervisor's row of the
    /// incidence matrix).
    pub fn row(&self, transitions: usize) -> Vec<i64> {
        self.d_plus(transitions).iter().zip(self.d_minus(transitions)).map(|(a, b)| a - b).collect()
    }

    /// True when the supervisor has no arc at all (`D_c = 0`): it can neither
    /// observe nor control anything (seed Extract 6.1, step 5).
    pub fn is_void(&self) -> bool {
        self.produced_by.is_empty() && self.consumed_by.is_empty()
    }

    /// The constraint as text, with node ids of `net`.
    pub fn describe(&self, net: &Net) -> String {
        let mut terms = Vec::new();
        let pname = |p: PlaceId| net.place(p).map_or_else(|| format!("p{}", p.0), |x| x.id.to_string());
        let tname = |t: TransitionId| net.transition(t).map_or_else(|| format!("t{}", t.0), |x| x.id.to_string());
        for &(p, w) in &self.l {
            terms.push(term(w, &format!("μ({})", pname(p))));
        }
        for &(t, w) in &self.c {
            terms.push(term(w, &format!("v({})", tname(t))));
        }
        let mut s = terms.join(" ");
        if let Some(rest) = s.strip_prefix("+ ") {
            s = rest.to_string();
        }
        if s.is_empty() {
            s = "0".into();
        }
        format!("{s} ≤ {}", self.b)
    }
}

fn term(w: i64, x: &str) -> String {
    match w {
        1 => format!("+ {x}"),
        -1 => format!("- {x}"),
        w if w < 0 => format!("- {}·{x}", -w),
        w => format!("+ {w}·{x}"),
    }
}

fn merge(items: impl Iterator<Item = (u32, i64)>) -> Vec<(u32, i64)> {
    let mut v: Vec<(u32, i64)> = items.collect();
    v.sort_unstable_by_key(|&(i, _)| i);
    let mut out: Vec<(u32, i64)> = Vec::with_capacity(v.len());
    for (i, w) in v {
        match out.last_mut() {
            Some((j, x)) if *j == i => *x += w,
            _ => out.push((i, w)),
        }
    }
    out.retain(|&(_, w)| w != 0);
    out
}

fn places_of(acts: &[&Activity], f: impl Fn(&Activity) -> &[PlaceId], w: i64) -> Vec<(PlaceId, i64)> {
    acts.iter().flat_map(|a| f(a).iter().map(move |&p| (p, w))).collect()
}

fn transitions_of(acts: &[&Activity], f: impl Fn(&Activity) -> &[TransitionId], w: i64) -> Vec<(TransitionId, i64)> {
    acts.iter().flat_map(|a| f(a).iter().map(move |&t| (t, w))).collect()
}

/// Checks a constraint's shape (arity, bound).
pub fn check_shape(k: usize, c: &Constraint) -> Result<(), CoordError> {
    let n = c.calls.len();
    let ok = match c.kind {
        ConstraintKind::Order => n == 2,
        ConstraintKind::Mutex { .. } | ConstraintKind::Sync => n >= 2,
    };
    if !ok {
        return Err(CoordError::Arity { constraint: k, found: n });
    }
    if c.kind == (ConstraintKind::Mutex { bound: 0 }) {
        return Err(CoordError::ZeroBound { constraint: k });
    }
    Ok(())
}

/// The supervisors of constraint `k` for the plant (one for a mutex or an
/// order, #S·(#S−1) for a sync).
pub fn constraint_supervisors(plant: &Plant, k: usize, c: &Constraint) -> Result<Vec<Supervisor>, CoordError> {
    check_shape(k, c)?;
    let groups: Vec<Vec<&Activity>> =
        c.calls.iter().map(|r| plant.resolve(r, k)).collect::<Result<Vec<_>, CoordError>>()?;
    let net = &plant.net;
    let m0 = net.initial_marking();
    let out = match c.kind {
        ConstraintKind::Mutex { bound } => {
            let all: Vec<&Activity> = groups.iter().flatten().copied().collect();
            let l = places_of(&all, |a| &a.running, 1);
            vec![Supervisor::synthesize(
                net,
                format!("coord.mutex{}", k + 1),
                Origin::Mutex { constraint: k },
                &l,
                &[],
                i64::from(bound),
            )]
        }
        ConstraintKind::Order => {
            let mut cv = transitions_of(&groups[1], |a| &a.started, 1);
            cv.extend(transitions_of(&groups[0], |a| &a.ended, -1));
            vec![Supervisor::synthesize(
                net,
                format!("coord.order{}", k + 1),
                Origin::Order { constraint: k },
                &[],
                &cv,
                0,
            )]
        }
        ConstraintKind::Sync => {
            let mut v = Vec::new();
            for (i, gi) in groups.iter().enumerate() {
                for (j, gj) in groups.iter().enumerate() {
                    if i == j {
                        continue;
                    }
                    let mut cv = transitions_of(gj, |a| &a.started, 1);
                    cv.extend(transitions_of(gi, |a| &a.arrived, -1));
                    let b: i64 = gi.iter().flat_map(|a| a.waiting.iter()).map(|&p| i64::from(m0.get(p))).sum();
                    let mut s = Supervisor::synthesize(
                        net,
                        format!("coord.sync{}.{}-{}", k + 1, i + 1, j + 1),
                        Origin::Sync { constraint: k, first: i, second: j },
                        &[],
                        &cv,
                        b,
                    );
                    s.withdrawn_by = gi.iter().flat_map(|a| a.withdrawn.iter().copied()).collect();
                    s.withdrawn_by.sort_unstable();
                    s.withdrawn_by.dedup();
                    v.push(s);
                }
            }
            v
        }
    };
    for s in &out {
        if s.initial < 0 {
            return Err(CoordError::InitiallyViolated { constraint: k, initial: s.initial });
        }
    }
    Ok(out)
}

/// The supervisors of every constraint, in order.
pub fn synthesize(plant: &Plant, constraints: &[Constraint]) -> Result<Vec<Supervisor>, CoordError> {
    let mut out = Vec::new();
    for (k, c) in constraints.iter().enumerate() {
        out.extend(constraint_supervisors(plant, k, c)?);
    }
    Ok(out)
}

/// `net` with the supervisor places appended, in order (seed A.12, A.13).
/// Supervisors must have been synthesized for `net` or for a net whose
/// nodes are a prefix of `net`'s (transition indices are kept).
pub fn apply(net: &Net, supervisors: &[Supervisor]) -> Result<Net, CoordError> {
    let mut b: NetBuilder = net.to_builder();
    for s in supervisors {
        let p = b.add_place(
            mcl_net::Place::new(s.id.clone()).with_tokens(u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX)),
        );
        for &(t, w) in &s.produced_by {
            b.add_output(t, p, w);
        }
        for &(t, w) in &s.consumed_by {
            b.add_input(p, t, w);
        }
    }
    Ok(b.build()?)
}

/// `net` (a supervised net: the plant's nodes, then the supervisor places of
/// `supervisors` in order, as [`apply`] builds it) with the take-back of
/// withdrawn sync arrivals ([`Supervisor::withdrawn_by`]) written as Petri
/// net nodes, for tools that explore nets: per supervisor `S` with
/// withdrawals, a place `S.withdrawn` that each withdrawal marks, an
/// immediate transition `S.withdraw` of priority 2 that takes it with one
/// token of `S`, and `S.forget` of priority 1 that takes it alone. Under
/// the MCL firing rule (immediate transitions first, by priority) this is
/// exactly the take-back that the verification applies: a withdrawal takes
/// a credit back at once when there is one.
pub fn with_take_backs(net: &Net, supervisors: &[Supervisor]) -> Result<Net, CoordError> {
    let mut b: NetBuilder = net.to_builder();
    let np = net.place_count() - supervisors.len();
    for (k, s) in supervisors.iter().enumerate().filter(|(_, s)| !s.withdrawn_by.is_empty()) {
        let w = add_take_back(&mut b, &s.id, PlaceId((np + k) as u32));
        for &t in &s.withdrawn_by {
            b.add_output(t, w, 1);
        }
    }
    Ok(b.build()?)
}

/// The take-back nodes of the supervisor place `sp` whose id is `id`: the
/// place `id.withdrawn` (returned; a withdrawal marks it), the immediate
/// transition `id.withdraw` of priority 2 that takes it with one token of
/// `sp`, and `id.forget` of priority 1 that takes it alone.
pub(crate) fn add_take_back(b: &mut NetBuilder, id: &str, sp: PlaceId) -> PlaceId {
    let w = b.add_place(mcl_net::Place::new(format!("{id}.withdrawn")));
    let tw = b.add_transition(mcl_net::Transition::new(format!("{id}.withdraw")).with_priority(2));
    b.add_input(w, tw, 1).add_input(sp, tw, 1);
    let tf = b.add_transition(mcl_net::Transition::new(format!("{id}.forget")).with_priority(1));
    b.add_input(w, tf, 1);
    w
}
