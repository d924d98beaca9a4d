//! `mcl run --sim`: the simulated vehicle (crate `mcl-sim`) in place of the
//! mock: loading its vehicle model and world, the symbols they give, and
//! the trajectory picture. `run.rs` calls these next to its `--mock` code.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use mcl_runtime::scenario::Scenario;
use mcl_sim::{Model, SimVehicle, World};
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
    let model = match &o.vehicle_model {
        Some(p) => Model::load(p),
        None => Ok(Model::default_model()),
    };
    let world = match &o.world {
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
}

/// Writes the trajectory picture of `v` to `path`; exit status 2 if it cannot.
pub fn write_trajectory(v: &SimVehicle, path: &Path, title: &str) -> Result<(), u8> {
    let svg = mcl_sim::trajectory::svg(v.track(), v.world(), title);
    std::fs::write(path, svg).map_err(|e| {
        eprintln!("error: cannot write `{}`: {e}", path.display());
        2
    })
}
