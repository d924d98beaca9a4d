//! Which gated starts a vehicle fires as soon as its supervisors allow them
//! (settling, docs/coordination.md, "Settling"): those on supervisors that
//! are the vehicle's own, and the holder's on a mutex between vehicles
//! (single holder, `decentral`); another vehicle's start on such a mutex
//! waits for a grant, asked for once its vehicle has settled.

use super::product::Effect;
use crate::central::Plant;
use crate::supervisor::Supervisor;

/// How the gated starts of the plant fire (settling, `product.rs`).
pub(super) struct Urgency {
    /// Per vehicle and effect: its starts fire as soon as their
    /// supervisors allow them (for each mutex between vehicles among them,
    /// the vehicle is the holder).
    pub(super) urgent: Vec<Vec<bool>>,
    /// Per transition: a start on a mutex between vehicles of a vehicle
    /// that is not its holder. It may wait for its token while its vehicle
    /// takes other steps, and fires only once its vehicle has settled (the
    /// grant answers a request sent after that).
    pub(super) remote: Vec<bool>,
    /// Per effect: the holders of the mutexes between vehicles it consumes
    /// from (vehicles of the plant). A start that another vehicle holds the
    /// mutex of is granted only once that holder has settled: not before it
    /// begins its mission.
    pub(super) holders: Vec<Vec<usize>>,
}

/// The [`Urgency`] of the starts of `plant` under `sups` (`effects`: the
/// effect table of the verification, `nt`: the plant's transitions).
pub(super) fn urgency(plant: &Plant, sups: &[Supervisor], effects: &[Effect], nt: usize) -> Urgency {
    // The holder of each mutex between vehicles (the first mission with one
    // of its calls, as `decentral` places it); `None` for the others.
    let holder: Vec<Option<usize>> = sups
        .iter()
        .map(|s| {
            crate::decentral::is_token_supervisor(plant, s)
                .then(|| s.consumed_by.iter().filter_map(|&(t, _)| plant.owner_of_transition(t)).min())
                .flatten()
        })
        .collect();
    let urgent = (0..plant.parts.len())
        .map(|v| effects.iter().map(|e| e.consume.iter().all(|&(k, _)| holder[k].is_none_or(|h| h == v))).collect())
        .collect();
    let mut remote = vec![false; nt];
    for (s, h) in sups.iter().zip(&holder) {
        let Some(h) = *h else { continue };
        for &(t, _) in &s.consumed_by {
            if let Some(x) = remote.get_mut(t.index()) {
                *x |= plant.owner_of_transition(t) != Some(h);
            }
        }
    }
    let holders = effects
        .iter()
        .map(|e| {
            let mut hs: Vec<usize> = e.consume.iter().filter_map(|&(k, _)| holder[k]).collect();
            hs.sort_unstable();
            hs.dedup();
            hs
        })
        .collect();
    Urgency { urgent, remote, holders }
}
