//! The ROS 2 bridge in the commands: `mcl check --ros2 BRIDGE.toml` (the
//! vehicle that the checked programs describe, `mcl_compiler::interface`,
//! and the bridge's errors against it, `mcl_ros2::bridge`) and `mcl run
//! --ros2 BRIDGE.toml` (the bridge's engine, and its ROS 2 node on a thread
//! of its own, `mcl_ros2::node`).

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

/// The bridge engine of `mcl run --ros2 BRIDGE FILE`, or the exit status
/// after its errors are printed (2: the bridge does not fit the vehicle).
pub fn engine_for(bridge: &Path, file: &Path) -> Result<mcl_ros2::bridge::engine::Engine, u8> {
    if file.extension().is_none_or(|e| e != "mcl") {
        eprintln!("error: --ros2 needs the .mcl file, whose vehicle the bridge is checked against");
        return Err(2);
    }
    let db = Database::new();
    let root = super::source_file(&db, file).map_err(|e| {
        eprintln!("error: {e}");
        2u8
    })?;
    match mcl_ros2::bridge::load(bridge, &vehicle_of(&db, &[root])) {
        Ok(loaded) => Ok(mcl_ros2::bridge::engine::Engine::new(loaded)),
        Err(es) => {
            for e in es {
                eprintln!("{e}");
            }
            Err(2)
        }
    }
}

/// Starts the ROS 2 node serving `end` on a thread of its own (none
/// without an engine).
pub fn spawn_node(
    engine: Option<mcl_ros2::bridge::engine::Engine>,
    end: mcl_runtime::link::AacEnd,
) -> Option<std::thread::JoinHandle<()>> {
    let engine = engine?;
    Some(std::thread::spawn(move || {
        if let Err(e) = mcl_ros2::node::serve(engine, end, |w| eprintln!("warning: {w}")) {
            eprintln!("error: {e}");
        }
    }))
}

/// Waits for the node to leave (after the player closed its link).
pub fn join_node(node: Option<std::thread::JoinHandle<()>>) {
    if let Some(n) = node {
        let _ = n.join();
    }
}
