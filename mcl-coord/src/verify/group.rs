//! The groups of vehicles that supervisors link, each verified alone
//! (exact: they share no place), and the verdict on one group from its
//! product.

use mcl_net::{Net, TransitionId};

use super::holding;
use super::hunt::hunt;
use super::lts::Lts;
use super::product::{explore_product, Effect, Product, NOBODY};
use super::quotient::Quotient;
use super::replay::{concretize, Replay, ReplayRules};
use super::structural_proof::{self, Proof};
use super::stubborn::Deps;
use super::{VerifyOptions, VerifyStats, Witness, WitnessKind};
use crate::central::Plant;
use crate::supervisor::Supervisor;

/// The groups of vehicles that supervisors link (connected components of
/// the graph vehicle — supervisor), with their supervisors, in order.
pub(super) fn groups(plant: &Plant, sups: &[Supervisor]) -> Vec<(Vec<usize>, Vec<usize>)> {
    let nv = plant.parts.len();
    let mut parent: Vec<usize> = (0..nv).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let owner = |t: TransitionId| plant.parts.iter().position(|p| p.owns_transition(t));
    let mut sup_vehicle = Vec::with_capacity(sups.len());
    for s in sups {
        let vs: Vec<usize> = s.consumed_by.iter().chain(&s.produced_by).filter_map(|&(t, _)| owner(t)).collect();
        for w in vs.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[a] = b;
        }
        sup_vehicle.push(vs.first().copied());
    }
    let mut out: Vec<(usize, Vec<usize>, Vec<usize>)> = Vec::new(); // (root, vehicles, sups)
    for v in 0..nv {
        let r = root(&mut parent, v);
        match out.iter_mut().find(|(x, ..)| *x == r) {
            Some(g) => g.1.push(v),
            None => out.push((r, vec![v], Vec::new())),
        }
    }
    for (k, v) in sup_vehicle.into_iter().enumerate() {
        // A supervisor no transition touches is constant: any group may keep it.
        let r = root(&mut parent, v.unwrap_or(0));
        if let Some(g) = out.iter_mut().find(|(x, ..)| *x == r) {
            g.2.push(k);
        }
    }
    out.into_iter().map(|(_, vs, ss)| (vs, ss)).collect()
}

/// One group of linked vehicles: indices into the missions and supervisors.
pub(super) struct Group<'a> {
    pub(super) vehicles: &'a [usize],
    pub(super) sups: &'a [usize],
    pub(super) ltss: Vec<&'a Lts>,
    pub(super) quots: Vec<&'a Quotient>,
    /// The graphs of every vehicle of the plant for settling, built on
    /// first use (`None`: a vehicle's graph passed the cap): they only
    /// choose counterexamples, never the verdict.
    pub(super) settled: &'a dyn Fn() -> Option<&'a Settled>,
    pub(super) can_end: Vec<bool>,
    /// The group holds every vehicle.
    pub(super) whole: bool,
    /// What a replay of its counterexamples applies.
    pub(super) rules: &'a ReplayRules<'a>,
    /// The same, with the remote starts waiting for their vehicle to settle
    /// (for the settled product's counterexamples).
    pub(super) settled_rules: &'a ReplayRules<'a>,
    /// Per vehicle of the group and effect: its gated starts fire as soon
    /// as allowed ([`Product::urgent`]).
    pub(super) urgent: Vec<&'a [bool]>,
    /// Per effect: the holders of the mutexes between vehicles it consumes
    /// from (vehicles of the plant, `settle.rs`).
    pub(super) holders: &'a [Vec<usize>],
}

/// The vehicle graphs for settling (docs/coordination.md, "Settling"), of
/// every vehicle of the plant.
pub(super) struct Settled {
    /// Built with the remote starts waiting for their vehicle to settle
    /// (`None`: there are none, the plain graphs serve).
    pub(super) ltss: Option<Vec<Lts>>,
    /// Reduced with vanishing markings as a label.
    pub(super) quots: Vec<Quotient>,
}

/// The verdict on one group.
pub(super) enum GroupOutcome {
    Verified,
    Problems(Vec<Witness>),
    Unknown(String),
}

/// Verifies one group: random walks first when its product is large, then
/// the product, with a larger K while counterexamples do not replay.
pub(super) fn verify_group(
    grp: &Group<'_>,
    plant: &Plant,
    effects_all: &[Effect],
    sups_all: &[Supervisor],
    snet: &Net,
    opts: &VerifyOptions,
    stats: &mut VerifyStats,
) -> GroupOutcome {
    let rules = grp.rules;
    let sups: Vec<&Supervisor> = grp.sups.iter().map(|&k| &sups_all[k]).collect();
    // Supervisor indices local to the group.
    let mut local = vec![usize::MAX; sups_all.len()];
    for (i, &k) in grp.sups.iter().enumerate() {
        local[k] = i;
    }
    let effects: Vec<Effect> = effects_all
        .iter()
        .map(|e| Effect {
            consume: e.consume.iter().filter(|(k, _)| local[*k] != usize::MAX).map(|&(k, w)| (local[k], w)).collect(),
            produce: e.produce.iter().filter(|(k, _)| local[*k] != usize::MAX).map(|&(k, w)| (local[k], w)).collect(),
            take_back: e.take_back.iter().filter(|&&k| local[k] != usize::MAX).map(|&k| local[k]).collect(),
        })
        .collect();
    let quots = &grp.quots;
    let nv = grp.vehicles.len();
    // The holders, as vehicles of the group (a mutex links its holder in).
    let holders: Vec<Vec<usize>> = grp
        .holders
        .iter()
        .map(|hs| hs.iter().filter_map(|h| grp.vehicles.iter().position(|v| v == h)).collect())
        .collect();
    let can_end = &grp.can_end;
    let group_ts: Vec<TransitionId> =
        grp.vehicles.iter().flat_map(|&v| plant.parts[v].transitions.clone().map(TransitionId)).collect();
    let group_ts = if grp.whole { None } else { Some(group_ts.as_slice()) };
    let replay = Replay { snet, nsups: sups_all.len(), group_ts, rules };
    let replay_settled = Replay { snet, nsups: sups_all.len(), group_ts, rules: grp.settled_rules };
    let max_w = sups.iter().flat_map(|s| s.consumed_by.iter().map(|&(_, w)| w)).max().unwrap_or(1);
    let max_init = sups.iter().map(|s| u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX)).max().unwrap_or(0);
    let mut cap = opts.counter_cap.max(max_w).max(max_init).max(1);
    let init_of = |quots: &[&Quotient], cap: u32| -> Vec<u32> {
        let mut init: Vec<u32> = quots.iter().map(|q| q.block[0]).collect();
        init.extend(sups.iter().map(|s| u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX).min(cap + 1)));
        init.push(NOBODY);
        init
    };
    let estimate: f64 = quots.iter().map(|q| q.n as f64).product();
    // A large product: the state equation may prove it free at once, or
    // give candidate dead states that walks are directed to.
    let mut candidates = Vec::new();
    if nv > 1 && estimate > opts.structural_threshold as f64 {
        let init: Vec<u32> = sups.iter().map(|s| u32::try_from(s.initial.max(0)).unwrap_or(u32::MAX)).collect();
        // Resources that every vehicle gives back alone: free, loops or
        // not (`holding.rs`).
        if holding::prove(quots, &effects, &init, &grp.urgent, can_end) {
            stats.holding_proofs += 1;
            return GroupOutcome::Verified;
        }
        match structural_proof::prove(quots, &effects, &init) {
            Proof::Free => {
                stats.structural_proofs += 1;
                return GroupOutcome::Verified;
            }
            Proof::Candidates(cs) => candidates = cs,
            Proof::Unknown => {}
        }
    }
    // Then look for a deadlock by random walks: directed ones first, then
    // plain ones when the product is large.
    let large = estimate > opts.hunt_threshold as f64;
    if nv > 1 && (large || !candidates.is_empty()) {
        let prod =
            Product { quots, effects: &effects, cap, nv, urgent: &grp.urgent, holders: &holders, settling: false };
        let budget = opts.hunt_steps / (2 * candidates.len()).max(1);
        let directed = candidates.iter().map(|c| (budget, Some(structural_proof::on_the_way(quots, c))));
        for (steps, guide) in directed.chain(large.then_some((opts.hunt_steps, None))) {
            if let Some(w) = hunt(&prod, init_of(quots, cap), &grp.ltss, &replay, steps, guide.as_deref()) {
                stats.counter_cap = stats.counter_cap.max(cap);
                return GroupOutcome::Problems(vec![w]);
            }
        }
    }
    // The stubborn sets of vehicles, unless turned off; a blocked state
    // found under the reduction is confirmed on the full product.
    // The exact dependencies hold while no count passes K; when one does,
    // the product is explored again with the coarse ones.
    let mut reduce = opts.reduction && estimate > opts.reduction_threshold as f64;
    let mut exact_deps = true;
    let mut deps = reduce.then(|| Deps::new(quots, &effects, sups.len(), true));
    // The verdict is the interleaving product's: it holds every run the
    // players can take over any link, so "free" is a proof. When it finds
    // problems, explored whole, the settled product (docs/coordination.md,
    // "Settling": a vehicle fires its ready immediate steps before another
    // vehicle moves, as every player does) is explored whole too, only to
    // pick counterexamples that a dry run reproduces; if it finds none (a
    // deadlock that needs a late message, or a product past the cap), the
    // interleaving product's counterexamples stand.
    let mut found: Option<(Vec<Witness>, &Settled)> = None;
    let mut reduced_first = false;
    let (mut s_ltss, mut s_quots) = (Vec::new(), Vec::new());
    loop {
        let settling = found.is_some();
        if let Some((_, st)) = &found {
            let ltss = st.ltss.as_ref();
            s_ltss = grp.vehicles.iter().map(|&v| ltss.map_or(grp_lts(grp, v), |l| &l[v])).collect();
            s_quots = grp.vehicles.iter().map(|&v| &st.quots[v]).collect();
        }
        let (quots, ltss, replay) =
            if settling { (&s_quots, &s_ltss, &replay_settled) } else { (&grp.quots, &grp.ltss, &replay) };
        let prod = Product { quots, effects: &effects, cap, nv, urgent: &grp.urgent, holders: &holders, settling };
        let g = explore_product(&prod, init_of(quots, cap), opts.max_product_states, deps.as_ref().filter(|_| reduce));
        if reduce && exact_deps && g.over {
            exact_deps = false;
            deps = Some(Deps::new(quots, &effects, sups.len(), false));
            continue;
        }
        let states = g.states.len() / g.width.max(1);
        stats.counter_cap = stats.counter_cap.max(cap);
        if let (true, Some((ws, _))) = (!g.complete || g.over, &found) {
            return GroupOutcome::Problems(ws.clone());
        }
        if !g.complete {
            stats.product_states += states;
            stats.exact &= !g.over;
            return GroupOutcome::Unknown(format!(
                "the product of {} has more than {} states",
                names(plant, grp.vehicles),
                opts.max_product_states
            ));
        }
        let is_end = |st: &[u32]| (0..nv).all(|v| quots[v].fin[st[v] as usize]);
        let is_target = |st: &[u32]| (0..nv).all(|v| !can_end[v] || quots[v].fin[st[v] as usize]);
        let n = g.pess_off.len() - 1;
        // Backward reachability of the targets over pessimistic steps; the
        // predecessors in one flat array (counting sort).
        let mut pred_off = vec![0u32; n + 1];
        for &t in &g.pess {
            pred_off[t as usize + 1] += 1;
        }
        for k in 0..n {
            pred_off[k + 1] += pred_off[k];
        }
        let mut fill = pred_off.clone();
        let mut pred = vec![0u32; g.pess.len()];
        for s in 0..n {
            for &t in &g.pess[g.pess_off[s] as usize..g.pess_off[s + 1] as usize] {
                pred[fill[t as usize] as usize] = s as u32;
                fill[t as usize] += 1;
            }
        }
        let preds = |s: u32| &pred[pred_off[s as usize] as usize..pred_off[s as usize + 1] as usize];
        let mut co = vec![false; n];
        let mut stack: Vec<u32> = (0..n as u32).filter(|&s| is_target(g.state(s))).collect();
        for &s in &stack {
            co[s as usize] = true;
        }
        while let Some(s) = stack.pop() {
            for &p in preds(s) {
                if !co[p as usize] {
                    co[p as usize] = true;
                    stack.push(p);
                }
            }
        }
        let mut is_dead = vec![false; n];
        for &s in &g.dead {
            is_dead[s as usize] = true;
        }
        let dead: Vec<u32> = g.dead.iter().copied().filter(|&s| !is_end(g.state(s))).collect();
        let blocked: Vec<u32> = (0..n as u32).filter(|&s| !co[s as usize] && !is_dead[s as usize]).collect();
        let count = |stats: &mut VerifyStats| {
            stats.product_states += states;
            stats.exact &= !g.over;
        };
        if dead.is_empty() && blocked.is_empty() {
            if let Some((ws, _)) = found {
                return GroupOutcome::Problems(ws);
            }
            count(stats);
            return GroupOutcome::Verified;
        }
        // Counterexamples: every dead state (up to a few), and the first
        // blocked state that holds some call (else the first blocked one).
        let mut witnesses = Vec::new();
        let mut spurious = false;
        let held_state = |s: u32| {
            let st = g.state(s);
            (0..nv).any(|v| quots[v].gates[st[v] as usize].iter().any(|&t| !prod.allowed(st, t)))
        };
        let mut picks: Vec<(u32, WitnessKind)> = dead.iter().take(8).map(|&s| (s, WitnessKind::Dead)).collect();
        // Under the reduction, a state that cannot reach the end in the
        // reduced graph may reach it in the full one: only the full
        // product decides (dead states are exact either way).
        if picks.is_empty() && reduce {
            reduce = false;
            reduced_first = true;
            continue;
        }
        // A dead marking explains itself; a blocked one is reported only
        // when there is none.
        if picks.is_empty() {
            if let Some(&b) = blocked.iter().find(|&&s| held_state(s)).or(blocked.first()) {
                picks.push((b, WitnessKind::Blocked));
            }
        }
        for (s, kind) in picks {
            match concretize(&g, s, ltss, quots, replay, kind) {
                Some(w) => witnesses.push(w),
                None => spurious = true,
            }
        }
        if let Some((ws, _)) = found {
            // The settled counterexamples, where they replay and are as
            // strong (a dead marking where the interleaving product has one).
            let dead_before = ws.iter().any(|w| w.kind == WitnessKind::Dead);
            let dead_here = witnesses.iter().any(|w| w.kind == WitnessKind::Dead);
            return GroupOutcome::Problems(if witnesses.is_empty() || (dead_before && !dead_here) {
                ws
            } else {
                witnesses
            });
        }
        if witnesses.is_empty() && spurious {
            if g.over && cap < opts.max_counter_cap {
                cap = (cap * 2).min(opts.max_counter_cap);
                continue;
            }
            count(stats);
            return GroupOutcome::Unknown(format!(
                "counterexamples found with supervisor places counted up to {cap} tokens do not replay"
            ));
        }
        // A blocked image reached through `>K` counts may be an artefact of
        // the abstraction: only an exact product proves it.
        if witnesses.iter().all(|w| w.kind == WitnessKind::Blocked) && g.over {
            if cap < opts.max_counter_cap {
                cap = (cap * 2).min(opts.max_counter_cap);
                continue;
            }
            count(stats);
            return GroupOutcome::Unknown(format!(
                "no deadlock, but whether every mission can always end is not decided: supervisor places \
                 exceed {cap} tokens"
            ));
        }
        count(stats);
        // A product explored whole and small enough: explored again settled.
        if !reduce && !reduced_first && states <= SETTLED_RETRY_STATES {
            if let Some(st) = (grp.settled)() {
                found = Some((witnesses, st));
                continue;
            }
        }
        return GroupOutcome::Problems(witnesses);
    }
}

/// The interleaving products with more states than this are not explored
/// again settled for counterexamples that replay as dry runs.
const SETTLED_RETRY_STATES: usize = 1_000_000;

/// The plain graph of vehicle `v` of the plant (a vehicle of `grp`).
fn grp_lts<'a>(grp: &Group<'a>, v: usize) -> &'a Lts {
    let i = grp.vehicles.iter().position(|&x| x == v).unwrap_or(0);
    grp.ltss[i]
}

fn names(plant: &Plant, vs: &[usize]) -> String {
    let n: Vec<String> = vs.iter().map(|&v| format!("`{}`", plant.parts[v].name)).collect();
    if n.len() == plant.parts.len() {
        format!("the {} vehicles", n.len())
    } else {
        format!("the vehicles {}", n.join(", "))
    }
}
