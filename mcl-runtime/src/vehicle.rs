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

/// Brings `vehicle` to where it stood when the virtual-time loop
/// ([`crate::virtual_loop`], [`crate::driver::run_virtual`]) fed the player
/// the journaled `input`: resuming a run against a vehicle whose state
/// follows from time and not only from the actions it received (a
/// simulated one), the vehicle is re-derived by replaying the loop. Before
/// a timer or the start, the vehicle takes every step due strictly earlier
/// (at equal times the player's timers go first); before one of its own
/// messages, it steps until it sends that message, which must be the one
/// journaled (else the journal was written against another vehicle or
/// world). `poses` gets the poses of the steps that sent nothing, in the
/// order the loop traced them. The caller then gives the vehicle the
/// input's actions, as the loop did.
pub fn catch_up(
    vehicle: &mut (impl VirtualVehicle + ?Sized),
    input: &crate::journal::Input,
    mut poses: impl FnMut(Vec<Pose>),
) -> Result<(), String> {
    let t = input.time();
    // Journaled times are read back from decimal text: equal within this.
    let eps = 1e-9 * t.abs().max(1.0);
    let want = input.message();
    while let Some(d) = vehicle.next_deadline() {
        let due = if want.is_some() { d <= t + eps } else { d < t - eps };
        if !due {
            break;
        }
        let Some((tm, m)) = vehicle.pop_due(d) else {
            poses(vehicle.take_poses());
            continue;
        };
        return match &want {
            Some(w) if same_message(w, &m) && (tm - t).abs() <= eps => Ok(()),
            _ => Err(format!(
                "the vehicle sends {} at t={tm} where the journal has {} at t={t} (was the run journaled against another vehicle model, world or scenario?)",
                describe(&m),
                want.as_ref().map_or("its next input".to_string(), describe)
            )),
        };
    }
    match want {
        Some(w) => Err(format!(
            "the vehicle does not send {} at t={t} as the journal says (was the run journaled against another vehicle model, world or scenario?)",
            describe(&w)
        )),
        None => Ok(()),
    }
}

/// The same event (name and activation) or perception (name and value,
/// numbers within 1e-9), whatever their numbers `n`.
fn same_message(a: &Inbound, b: &Inbound) -> bool {
    match (a, b) {
        (Inbound::Event { event: e1, activation: a1, .. }, Inbound::Event { event: e2, activation: a2, .. }) => {
            e1 == e2 && a1 == a2
        }
        (Inbound::Perception { name: n1, value: v1, .. }, Inbound::Perception { name: n2, value: v2, .. }) => {
            n1 == n2
                && match (v1.as_f64(), v2.as_f64()) {
                    (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(1.0),
                    _ => v1 == v2,
                }
        }
        _ => false,
    }
}

/// `event E` or `perception P = V`.
fn describe(m: &Inbound) -> String {
    match m {
        Inbound::Event { event, .. } => format!("event `{event}`"),
        Inbound::Perception { name, value, .. } => format!("perception `{name}` = {value}"),
        other => format!("{other:?}"),
    }
}
