//! `mcl run --sim`: the simulated vehicle (crate `mcl-sim`) in place of the
//! mock: loading its vehicle model and world, the symbols they give, and
//! the trajectory picture. `run.rs` calls these next to its `--mock` code,
//! for one vehicle and for every vehicle of a file with several missions
//! ([`FleetVehicle`]).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use mcl_runtime::link::{Action, Inbound};
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::scenario::Scenario;
use mcl_runtime::vehicle::{Pose, VirtualVehicle};
use mcl_sim::{Model, SharedSim, SimVehicle, World};
use serde_json::Value;

use super::run::Options;

/// A vehicle model and a world, loaded.
pub struct Setup {
    pub model: Arc<Model>,
    pub world: Arc<World>,
}

/// Loads `--vehicle-model` (default: the bundled model of
/// `examples/vehicle.mcl`) and `--world` (default: [`World::default`]).
/// Prints a located error and returns exit status 2 on a bad file.
pub fn load(o: &Options) -> Result<Setup, u8> {
    load_files(o.vehicle_model.as_deref(), o.world.as_deref())
}

/// Loads a vehicle model and a world (`mcl run --sim`, `mcl plan --run
/// --sim`), the defaults when not given; a bad file is a located error
/// printed, and exit status 2.
pub fn load_files(model: Option<&Path>, world: Option<&Path>) -> Result<Setup, u8> {
    let model = match model {
        Some(p) => Model::load(p),
        None => Ok(Model::default_model()),
    };
    let world = match world {
        Some(p) => World::load(p),
        None => Ok(World::default()),
    };
    match (model, world) {
        (Ok(model), Ok(world)) => Ok(Setup { model: Arc::new(model), world: Arc::new(world) }),
        (m, w) => {
            for e in [m.err(), w.err()].into_iter().flatten() {
                eprintln!("error: {e}");
            }
            Err(2)
        }
    }
}

impl Setup {
    /// The symbols the model and the world give (the world's win); the
    /// scenario's and `--set` go on top.
    pub fn symbols(&self) -> BTreeMap<String, Value> {
        let mut s = self.model.symbols.clone();
        s.extend(self.world.symbols.clone());
        s
    }

    /// The simulated vehicle, with `scenario`'s faults on top.
    pub fn vehicle(&self, scenario: Scenario) -> SimVehicle {
        SimVehicle::new(self.model.clone(), self.world.clone(), scenario)
    }

    /// The simulated vehicle of `mission`, one of several in the world,
    /// where the world starts it ([`World::start_of`]).
    pub fn vehicle_of(&self, mission: &str, scenario: Scenario) -> SharedSim {
        SharedSim::new(self.vehicle(scenario).starting_at(self.world.start_of(mission)))
    }
}

/// A vehicle of a coordinated run: the mock (`--mock`) or a simulated
/// vehicle (`--sim`) that the run keeps a handle on for the trajectory.
pub enum FleetVehicle {
    Mock(Box<MockVehicle>),
    Sim(SharedSim),
}

impl FleetVehicle {
    fn inner(&mut self) -> &mut dyn VirtualVehicle {
        match self {
            FleetVehicle::Mock(m) => m.as_mut(),
            FleetVehicle::Sim(s) => s,
        }
    }
}

impl VirtualVehicle for FleetVehicle {
    fn initial(&mut self) -> Vec<(f64, Inbound)> {
        self.inner().initial()
    }
    fn on_action(&mut self, now: f64, a: &Action) {
        self.inner().on_action(now, a)
    }
    fn next_deadline(&self) -> Option<f64> {
        match self {
            FleetVehicle::Mock(m) => VirtualVehicle::next_deadline(m.as_ref()),
            FleetVehicle::Sim(s) => VirtualVehicle::next_deadline(s),
        }
    }
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        self.inner().pop_due(now)
    }
    fn take_delivered(&mut self, msg: &Inbound) -> bool {
        self.inner().take_delivered(msg)
    }
    fn take_warnings(&mut self) -> Vec<String> {
        self.inner().take_warnings()
    }
    fn take_poses(&mut self) -> Vec<Pose> {
        self.inner().take_poses()
    }
}

/// Writes the trajectory picture of every simulated vehicle of a
/// coordinated run (`(mission, vehicle)`, in order) to `path`; exit status
/// 2 if it cannot.
pub fn write_fleet_trajectory(vehicles: &[(String, SharedSim)], path: &Path, title: &str) -> Result<(), u8> {
    let Some((_, first)) = vehicles.first() else { return Ok(()) };
    let world = first.lock().world().clone();
    let guards: Vec<_> = vehicles.iter().map(|(_, v)| v.lock()).collect();
    let tracks: Vec<(&str, &mcl_sim::sim::Track)> =
        vehicles.iter().zip(&guards).map(|((n, _), g)| (n.as_str(), g.track())).collect();
    let svg = mcl_sim::trajectory::svg_fleet(&tracks, &world, title);
    std::fs::write(path, svg).map_err(|e| {
        eprintln!("error: cannot write `{}`: {e}", path.display());
        2
    })
}

/// Writes the trajectory picture of `v` to `path`; exit status 2 if it cannot.
pub fn write_trajectory(v: &SimVehicle, path: &Path, title: &str) -> Result<(), u8> {
    let svg = mcl_sim::trajectory::svg(v.track(), v.world(), title);
    std::fs::write(path, svg).map_err(|e| {
        eprintln!("error: cannot write `{}`: {e}", path.display());
        2
    })
}
