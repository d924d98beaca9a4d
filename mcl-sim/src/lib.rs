//! A vehicle simulator for dry runs of missions (`mcl run --sim`): a
//! kinematic vehicle in a simulated world, answering the player's actions
//! through the behaviours of a vehicle model, in virtual time.
//!
//! * [`world`]: the world file (seabed, current, cable, objects, wall,
//!   battery, navigation), shared by every vehicle in it;
//! * [`model`]: the vehicle model file (limits; primitive → behaviour,
//!   arguments, events);
//! * [`behaviour`]: what each behaviour does and when it ends;
//! * [`sim`]: [`SimVehicle`], the [`mcl_runtime::vehicle::VirtualVehicle`]
//!   the virtual-time driver plays against (one per vehicle);
//! * [`shared`]: [`SharedSim`], a vehicle lent to a run and read after it;
//! * [`trajectory`]: the trajectory picture (SVG), of one vehicle or several.
//!
//! Sans-IO and deterministic: the same actions at the same times give the
//! same poses and messages. See `docs/simulator.md`.

pub mod behaviour;
pub mod error;
pub mod model;
pub mod shared;
pub mod sim;
pub mod trajectory;
pub mod world;

pub use model::Model;
pub use shared::SharedSim;
pub use sim::SimVehicle;
pub use world::World;
