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
    /// The models of some missions (`--vehicle-model NAME=FILE`), instead of `model`.
    pub models: BTreeMap<String, Arc<Model>>,
}

/// One `--vehicle-model` argument: `NAME=FILE` (the model of mission NAME,
/// NAME made of letters, digits, `_` and `-`) or `FILE` (every other vehicle's).
pub fn model_arg(arg: &str) -> (Option<&str>, &Path) {
    match arg.split_once('=') {
        Some((name, file)) if !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '-') => {
            (Some(name), Path::new(file))
        }
        _ => (None, Path::new(arg)),
    }
}

/// Loads `--vehicle-model` (default: the bundled model of
/// `examples/vehicle.mcl`; `NAME=FILE` for one mission) and `--world`
/// (default: [`World::default`]). Prints a located error and returns exit
/// status 2 on a bad file; `missions` are the names a `NAME=` may give.
pub fn load(o: &Options, missions: &[String]) -> Result<Setup, u8> {
    let mut default = None;
    let mut per = Vec::new();
    for a in &o.vehicle_model {
        match model_arg(a) {
            (Some(name), file) => {
                if !missions.iter().any(|m| m == name) {
                    eprintln!(
                        "error: --vehicle-model {a}: `{}` has no mission `{name}` (missions: {})",
                        o.file.display(),
                        missions.join(", ")
                    );
                    return Err(2);
                }
                per.push((name.to_string(), file));
            }
            (None, _) if default.is_some() => {
                eprintln!("error: --vehicle-model: give one FILE for every vehicle, and NAME=FILE for one mission");
                return Err(2);
            }
            (None, file) => default = Some(file),
        }
    }
    let mut setup = load_files(default, o.world.as_deref())?;
    for (name, file) in per {
        match Model::load(file) {
            Ok(m) => {
                setup.models.insert(name, Arc::new(m));
            }
            Err(e) => {
                eprintln!("error: {e}");
                return Err(2);
            }
        }
    }
    Ok(setup)
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
        (Ok(model), Ok(world)) => Ok(Setup { model: Arc::new(model), world: Arc::new(world), models: BTreeMap::new() }),
        (m, w) => {
            for e in [m.err(), w.err()].into_iter().flatten() {
                eprintln!("error: {e}");
            }
            Err(2)
        }
    }
}

impl Setup {
    /// The model of `mission`'s vehicle.
    fn model_of(&self, mission: &str) -> &Arc<Model> {
        self.models.get(mission).unwrap_or(&self.model)
    }

    /// The symbols the model of `mission` and the world give (the world's
    /// win); the scenario's and `--set` go on top.
    pub fn symbols_of(&self, mission: &str) -> BTreeMap<String, Value> {
        let mut s = self.model_of(mission).symbols.clone();
        s.extend(self.world.symbols.clone());
        s
    }

    /// The simulated vehicle of a single run (or a plan), with `scenario`'s
    /// faults on top.
    pub fn vehicle(&self, scenario: Scenario) -> SimVehicle {
        SimVehicle::new(self.model.clone(), self.world.clone(), scenario)
    }

    /// The simulated vehicle of `mission` (its model), one of several in
    /// the world, where the world starts it ([`World::start_of`]), playing
    /// `net` (the labels of its calls) with the scenario's draws seeded by
    /// `seed`.
    pub fn vehicle_of(&self, mission: &str, net: &mcl_net::Net, scenario: Scenario, seed: u64) -> SharedSim {
        SharedSim::new(self.single(mission, net, scenario, seed))
    }

    /// [`Setup::vehicle_of`], not shared: the vehicle of a single run.
    pub fn single(&self, mission: &str, net: &mcl_net::Net, scenario: Scenario, seed: u64) -> SimVehicle {
        let v = SimVehicle::new(self.model_of(mission).clone(), self.world.clone(), scenario);
        v.starting_at(self.world.start_of(mission)).with_program(net, seed)
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

/// Resuming a simulated run (`--resume`): re-derives the vehicle for one
/// journaled `input` whose outputs the player replayed (`outs`): the
/// vehicle steps as the virtual-time loop made it before that input
/// ([`mcl_runtime::vehicle::catch_up`]), then takes the input's actions;
/// the records go to `sink` as the run wrote them (poses and warnings
/// included). The first difference from the journal goes to `error`, and
/// nothing more is done after it.
pub fn replay_input(
    v: &mut SimVehicle,
    input: &mcl_runtime::journal::Input,
    outs: &[mcl_runtime::player::Output],
    tracer: &mcl_runtime::trace::Tracer,
    sink: &mut dyn mcl_runtime::driver::Sink,
    error: &mut Option<String>,
) {
    use mcl_runtime::driver::pose_record;
    use mcl_runtime::player::Output;
    use mcl_runtime::trace::Record;
    if error.is_some() {
        return;
    }
    let mission = tracer.mission().map(str::to_string);
    let caught = mcl_runtime::vehicle::catch_up(v, input, |poses| {
        for p in &poses {
            sink.record(&pose_record(mission.as_deref(), p));
        }
    });
    if let Err(e) = caught {
        *error = Some(format!("the simulated vehicle differs from the journal: {e}"));
        return;
    }
    let mut now = input.time();
    for out in outs {
        sink.record(&tracer.record(out));
        if let Output::Send { t, .. } = out {
            now = *t;
        }
    }
    for out in outs {
        if let Output::Send { t, action } = out {
            v.on_action(*t, action);
        }
    }
    for w in v.take_warnings() {
        sink.record(&Record { mission: mission.clone(), ..Record::warning(now, w) });
    }
    for p in v.take_poses() {
        sink.record(&pose_record(mission.as_deref(), &p));
    }
}
