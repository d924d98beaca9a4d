//! The mission state a vehicle publishes under `mcl/<vehicle>/status`
//! (docs/zenoh.md *Status*): running calls, outcome, pose when known,
//! rebuilt from the run's trace records by mcl-runtime's [`StatusTracker`].

use std::collections::BTreeMap;
use std::sync::Arc;

pub use mcl_runtime::status::{Pose, RunningCall, Status, StatusTracker};
use mcl_runtime::trace::Record;

use crate::keys;
use crate::node::Node;

/// Publishes the state of the missions of this process, each under
/// `mcl/<mission>/status` (or under one vehicle name for a single run).
pub struct StatusPublisher {
    node: Arc<Node>,
    /// The vehicle and mission names of a single run (whatever mission
    /// its records name).
    single: Option<(String, String)>,
    trackers: BTreeMap<String, StatusTracker>,
}

impl StatusPublisher {
    /// A publisher on `node`; `single`: the vehicle and the mission of a
    /// one-mission run.
    pub fn new(node: Arc<Node>, single: Option<(&str, &str)>) -> StatusPublisher {
        let single = single.map(|(v, m)| (v.to_string(), m.to_string()));
        StatusPublisher { node, single, trackers: BTreeMap::new() }
    }

    /// Takes one record of the run, and publishes the new state of its
    /// vehicle when it changed.
    pub fn record(&mut self, r: &Record) {
        let (vehicle, mission) = match (&self.single, &r.mission) {
            (Some((v, m)), _) => (v.clone(), m.clone()),
            (None, Some(m)) if m != "*" => (m.clone(), m.clone()),
            _ => return,
        };
        if keys::check_chunk("vehicle", &vehicle).is_err() {
            return;
        }
        let t = self.trackers.entry(vehicle.clone()).or_insert_with(|| StatusTracker::new(&mission));
        if t.record(r) {
            self.node.put(keys::status(&vehicle), serde_json::to_vec(t.status()).unwrap_or_default());
        }
    }
}
