//! The centralized net: the disjoint union of the vehicles' nets (seed 6.1,
//! equation 6.7), with every node id prefixed by its mission's name.

use std::ops::Range;

use mcl_net::{Net, NetBuilder, PlaceId, TransitionId, TransitionKind};

use crate::error::CoordError;
use crate::model::{Activity, CallRef, Mission};

/// Separator between a mission's name and a node id in the centralized net.
pub const SEP: char = '/';

/// Where one mission sits in the centralized net.
#[derive(Clone, Debug)]
pub struct Part {
    /// Mission name.
    pub name: String,
    /// Its places (indices in the centralized net).
    pub places: Range<u32>,
    /// Its transitions.
    pub transitions: Range<u32>,
    /// Initial places, in centralized ids.
    pub initial_places: Vec<PlaceId>,
    /// Final places, in centralized ids.
    pub final_places: Vec<PlaceId>,
}

impl Part {
    /// True when `t` belongs to this mission.
    pub fn owns_transition(&self, t: TransitionId) -> bool {
        self.transitions.contains(&t.0)
    }

    /// True when `p` belongs to this mission.
    pub fn owns_place(&self, p: PlaceId) -> bool {
        self.places.contains(&p.0)
    }
}

/// The uncontrolled centralized net of several missions (the *plant*).
#[derive(Clone, Debug)]
pub struct Plant {
    /// The disjoint union; node ids are `mission/id`, event names
    /// `mission/event`.
    pub net: Net,
    /// One part per mission, in the order given.
    pub parts: Vec<Part>,
    /// Per transition of `net`: may a supervisor disable it?
    pub controllable: Vec<bool>,
    /// Every activity, with its mission's index, in centralized ids.
    pub activities: Vec<(usize, Activity)>,
}

fn shift_p(p: PlaceId, off: u32) -> PlaceId {
    PlaceId(p.0 + off)
}

fn shift_t(t: TransitionId, off: u32) -> TransitionId {
    TransitionId(t.0 + off)
}

/// Builds the centralized net: places and transitions of the first mission,
/// then the second, and so on (so its incidence matrix is block-diagonal,
/// seed equation 6.7).
pub fn centralize(missions: &[Mission]) -> Result<Plant, CoordError> {
    for (i, m) in missions.iter().enumerate() {
        if missions[..i].iter().any(|o| o.name == m.name) {
            return Err(CoordError::DuplicateMission(m.name.clone()));
        }
    }
    let id = missions.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join("+");
    let mut b = NetBuilder::new(if id.is_empty() { "centralized".to_string() } else { id });
    let mut parts = Vec::new();
    let mut controllable = Vec::new();
    let mut activities = Vec::new();
    for (mi, m) in missions.iter().enumerate() {
        let (po, to) = (b.place_count() as u32, b.transition_count() as u32);
        let pre = |s: &str| format!("{}{SEP}{s}", m.name);
        for (k, v) in m.net.properties() {
            b.property(pre(k), v.clone());
        }
        for p in m.net.places() {
            let mut p = p.clone();
            p.id = pre(&p.id).into();
            p.name = pre(&p.name).into();
            b.add_place(p);
        }
        for t in m.net.transitions() {
            let mut t = t.clone();
            t.id = pre(&t.id).into();
            t.name = pre(&t.name).into();
            if let TransitionKind::Event(e) = &t.kind {
                t.kind = TransitionKind::Event(pre(e));
            }
            b.add_transition(t);
        }
        for arc in m.net.arcs() {
            match *arc {
                mcl_net::Arc::Input { place, transition, weight } => {
                    b.add_input(shift_p(place, po), shift_t(transition, to), weight);
                }
                mcl_net::Arc::Output { transition, place, weight } => {
                    b.add_output(shift_t(transition, to), shift_p(place, po), weight);
                }
            }
        }
        controllable.extend((0..m.net.transition_count()).map(|i| m.controllable.get(i).copied().unwrap_or(false)));
        for a in &m.activities {
            let sp = |v: &[PlaceId]| v.iter().map(|&p| shift_p(p, po)).collect();
            let st = |v: &[TransitionId]| v.iter().map(|&t| shift_t(t, to)).collect();
            activities.push((
                mi,
                Activity {
                    label: a.label.clone(),
                    waiting: sp(&a.waiting),
                    arrived: st(&a.arrived),
                    withdrawn: st(&a.withdrawn),
                    started: st(&a.started),
                    running: sp(&a.running),
                    ended: st(&a.ended),
                },
            ));
        }
        parts.push(Part {
            name: m.name.clone(),
            places: po..po + m.net.place_count() as u32,
            transitions: to..to + m.net.transition_count() as u32,
            initial_places: m.initial_places.iter().map(|&p| shift_p(p, po)).collect(),
            final_places: m.final_places.iter().map(|&p| shift_p(p, po)).collect(),
        });
    }
    Ok(Plant { net: b.build()?, parts, controllable, activities })
}

impl Plant {
    /// Index of the mission named `name`.
    pub fn mission(&self, name: &str) -> Option<usize> {
        self.parts.iter().position(|p| p.name == name)
    }

    /// The activities `r` names (every call of that mission with that label).
    /// `constraint` is only used to say which constraint is wrong.
    pub fn resolve(&self, r: &CallRef, constraint: usize) -> Result<Vec<&Activity>, CoordError> {
        let m = self
            .mission(&r.mission)
            .ok_or_else(|| CoordError::UnknownMission { constraint, mission: r.mission.clone() })?;
        let acts: Vec<&Activity> =
            self.activities.iter().filter(|(mi, a)| *mi == m && a.label == r.label).map(|(_, a)| a).collect();
        if acts.is_empty() {
            return Err(CoordError::UnknownLabel { constraint, call: r.clone() });
        }
        Ok(acts)
    }

    /// The mission that owns transition `t`.
    pub fn owner_of_transition(&self, t: TransitionId) -> Option<usize> {
        self.parts.iter().position(|p| p.owns_transition(t))
    }

    /// The mission that owns place `p`.
    pub fn owner_of_place(&self, p: PlaceId) -> Option<usize> {
        self.parts.iter().position(|part| part.owns_place(p))
    }

    /// The local id of a centralized node id (`mission/id` → `id`).
    pub fn local_id(id: &str) -> &str {
        id.split_once(SEP).map_or(id, |(_, rest)| rest)
    }
}
