//! The compact nets of seed chapter 6 (one place per task, Figure 6.1) and
//! the PW-transformation (Definition 6.1.2).
//!
//! Compiled missions need no PW-transformation: a call adapter already waits
//! in its begin place before its `start` transition, which is exactly the
//! `P^wait → T^wait → P` of the transformation.

use mcl_net::{Arc, Net, NetBuilder, NetError, PlaceId, TransitionId};

/// A sequence of tasks as a compact net: `places[0] -transitions[0]->
/// places[1] -> ...`, with one token in `places[0]` (seed Figure 6.2).
pub fn sequence(id: &str, places: &[&str], transitions: &[&str]) -> Net {
    assert_eq!(places.len(), transitions.len() + 1, "a sequence of n places has n - 1 transitions");
    let mut b = NetBuilder::new(id);
    let ps: Vec<PlaceId> = places
        .iter()
        .enumerate()
        .map(|(i, p)| b.add_place(mcl_net::Place::new(*p).with_tokens(u32::from(i == 0))))
        .collect();
    for (i, t) in transitions.iter().enumerate() {
        let t = b.add_transition(mcl_net::Transition::new(*t));
        b.add_input(ps[i], t, 1).add_output(t, ps[i + 1], 1);
    }
    b.build().expect("a sequence is a valid net")
}

/// The PW-transformation of `place` (seed Definition 6.1.2): a new place
/// `wait_id` takes over every input arc of `place`, and a new transition
/// `transition_id` moves its token into `place`:
/// `•P^wait = •P`, `P^wait• = {T^wait}`, `T^wait• = {P}`, `•P = {T^wait}`.
///
/// The new place and transition are appended (their indices are the old
/// counts); every other index is kept.
pub fn pw_transform(net: &Net, place: PlaceId, wait_id: &str, transition_id: &str) -> Result<Net, NetError> {
    let mut b = NetBuilder::new(net.id());
    b.name(net.name());
    for (k, v) in net.properties() {
        b.property(k.clone(), v.clone());
    }
    for p in net.places() {
        b.add_place(p.clone());
    }
    for t in net.transitions() {
        b.add_transition(t.clone());
    }
    let wait = b.add_place(mcl_net::Place::new(wait_id));
    let tw = b.add_transition(mcl_net::Transition::new(transition_id));
    for arc in net.arcs() {
        match *arc {
            Arc::Output { transition, place: p, weight } if p == place => {
                b.add_output(transition, wait, weight);
            }
            Arc::Input { place: p, transition, weight } => {
                b.add_input(p, transition, weight);
            }
            Arc::Output { transition, place: p, weight } => {
                b.add_output(transition, p, weight);
            }
        }
    }
    b.add_input(wait, tw, 1).add_output(tw, place, 1);
    b.build()
}

/// Looks a place up by id (panics with the id when absent: for tests and
/// examples that build their own nets).
pub fn place(net: &Net, id: &str) -> PlaceId {
    net.place_by_id(id).unwrap_or_else(|| panic!("no place `{id}` in net `{}`", net.id()))
}

/// Looks a transition up by id (panics with the id when absent).
pub fn transition(net: &Net, id: &str) -> TransitionId {
    net.transition_by_id(id).unwrap_or_else(|| panic!("no transition `{id}` in net `{}`", net.id()))
}
