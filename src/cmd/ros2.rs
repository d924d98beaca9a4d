//! The ROS 2 bridge file in `mcl check --ros2 BRIDGE.toml`: the vehicle
//! that the checked programs describe (`mcl_compiler::interface`), and the
//! bridge's errors against it (`mcl_ros2::bridge`).

use mcl_compiler::interface::vehicle_interface;
use mcl_compiler::{Database, SourceFile};
use mcl_ros2::bridge::{BridgeError, Vehicle, VehiclePrimitive};
use std::path::Path;

/// The primitives of the programs rooted at `roots`, merged by name.
pub fn vehicle_of(db: &Database, roots: &[SourceFile]) -> Vehicle {
    let mut v = Vehicle::default();
    for &root in roots {
        for p in vehicle_interface(db, root).primitives {
            let i = match v.primitives.iter().position(|q| q.name == p.primitive) {
                Some(i) => i,
                None => {
                    v.primitives.push(VehiclePrimitive { name: p.primitive.clone(), ..Default::default() });
                    v.primitives.len() - 1
                }
            };
            let q = &mut v.primitives[i];
            for c in p.commands {
                if !q.commands.iter().any(|(n, _)| *n == c.command) {
                    q.commands.push((c.command, c.params));
                }
            }
            for e in p.events {
                if !q.events.contains(&e.event) {
                    q.events.push(e.event);
                }
            }
        }
    }
    v
}

/// The errors of the bridge file against `vehicle` (none: it is correct).
pub fn check_bridge(bridge: &Path, vehicle: &Vehicle) -> Vec<BridgeError> {
    match mcl_ros2::bridge::load(bridge, vehicle) {
        Ok(_) => Vec::new(),
        Err(es) => es,
    }
}

/// A bridge error as the JSON of `mcl check --format json`.
pub fn to_json(e: &BridgeError) -> serde_json::Value {
    serde_json::json!({
        "file": e.file.display().to_string(),
        "line": e.line,
        "column": e.column,
        "severity": "error",
        "code": "ros2",
        "message": e.message,
    })
}
