//! What the virtual-time driver needs from a vehicle that lives beside the
//! player: the mock ([`crate::mock::MockVehicle`]) or a simulated vehicle
//! (crate `mcl-sim`). The driver asks it for its next deadline, takes the
//! messages that are due, and tells it every action the player sends.

use crate::link::{Action, Inbound};

/// Where a vehicle is, at mission time `t` (a `pose` trace record).
///
/// Frame: `x` east and `y` north in metres from the world's origin, `z`
/// depth in metres (0 at the surface, positive down), `yaw` in radians
/// (0 towards +x, counter-clockwise).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    /// Seconds from the start of the mission.
    pub t: f64,
    /// East, metres.
    pub x: f64,
    /// North, metres.
    pub y: f64,
    /// Depth, metres (≥ 0).
    pub z: f64,
    /// Heading, radians.
    pub yaw: f64,
}

/// A vehicle in virtual time. Deterministic: the same actions at the same
/// times give the same messages.
pub trait VirtualVehicle {
    /// Schedules what the vehicle sends whatever the mission does (scripted
    /// events and perceptions); called once, before the mission starts.
    fn initial(&mut self) -> Vec<(f64, Inbound)>;
    /// The player sent `a` at mission time `now`.
    fn on_action(&mut self, now: f64, a: &Action);
    /// The time of the next message it will send, if any. `None` means it
    /// will send nothing more unless it receives an action (the driver then
    /// reports the mission stuck if the player waits for nothing else).
    fn next_deadline(&self) -> Option<f64>;
    /// Removes and returns the first message due at or before `now`, with
    /// its time.
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)>;
    /// Removes the earliest scheduled message equal to `msg` (a resumed run
    /// has it in its journal already). False if there is none.
    fn take_delivered(&mut self, msg: &Inbound) -> bool;
    /// Warnings since the last call.
    fn take_warnings(&mut self) -> Vec<String>;
    /// Poses reached since the last call, in time order (none for a vehicle
    /// that does not move, such as the mock).
    fn take_poses(&mut self) -> Vec<Pose> {
        Vec::new()
    }
}
