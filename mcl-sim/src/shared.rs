//! A [`SimVehicle`] that its caller still reads after lending it to a run
//! that takes its vehicle by value (`mcl_runtime::multi::Vehicle`,
//! `mcl_plan::run::run_planned_on`): the trajectory is drawn from it once
//! the run is over.

use std::sync::{Arc, Mutex, MutexGuard};

use mcl_runtime::link::{Action, Inbound};
use mcl_runtime::vehicle::{Pose, VirtualVehicle};

use crate::sim::SimVehicle;

/// A shared handle on a simulated vehicle; clones are the same vehicle.
#[derive(Clone, Debug)]
pub struct SharedSim(Arc<Mutex<SimVehicle>>);

impl SharedSim {
    /// Shares `v`.
    pub fn new(v: SimVehicle) -> SharedSim {
        SharedSim(Arc::new(Mutex::new(v)))
    }

    /// The vehicle (a run that panicked while holding it leaves it as it was).
    pub fn lock(&self) -> MutexGuard<'_, SimVehicle> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl VirtualVehicle for SharedSim {
    fn initial(&mut self) -> Vec<(f64, Inbound)> {
        self.lock().initial()
    }
    fn on_action(&mut self, now: f64, a: &Action) {
        self.lock().on_action(now, a)
    }
    fn next_deadline(&self) -> Option<f64> {
        self.lock().next_deadline()
    }
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        self.lock().pop_due(now)
    }
    fn take_delivered(&mut self, msg: &Inbound) -> bool {
        self.lock().take_delivered(msg)
    }
    fn take_warnings(&mut self) -> Vec<String> {
        self.lock().take_warnings()
    }
    fn take_poses(&mut self) -> Vec<Pose> {
        self.lock().take_poses()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Model, World};
    use mcl_runtime::scenario::Scenario;

    #[test]
    fn a_clone_sees_what_the_run_did() {
        let v = SimVehicle::new(Arc::new(Model::default_model()), Arc::new(World::default()), Scenario::default());
        let keep = SharedSim::new(v);
        let mut lent = keep.clone();
        lent.initial();
        assert_eq!(keep.lock().track().points.len(), 1, "the initial pose");
        assert!(lent.take_poses().len() == 1 && keep.lock().take_poses().is_empty());
    }
}
