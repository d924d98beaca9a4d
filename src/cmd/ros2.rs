//! The ROS 2 bridge in the commands: `mcl check --ros2 BRIDGE.toml` (the
//! vehicle that the checked programs describe, `mcl_compiler::interface`,
//! and the bridge's errors against it, `mcl_ros2::bridge`) and `mcl run
//! --ros2 BRIDGE.toml` (the bridge's engine, and its ROS 2 node on a thread
//! of its own, `mcl_ros2::node`; `mcl plan --run --ros2` drives the same
//! node through [`NodeLink`]).

use mcl_compiler::Database;
pub use mcl_ros2::bridge::vehicle_of;
use mcl_ros2::bridge::{BridgeError, Vehicle};
use std::path::Path;

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

/// The bridge engine of `mcl run --ros2 BRIDGE FILE` (and of `mcl plan
/// --run --ros2`: the vehicle of every file given), or the exit status
/// after its errors are printed (2: the bridge does not fit the vehicle).
pub fn engine_for(bridge: &Path, files: &[&Path]) -> Result<mcl_ros2::bridge::engine::Engine, u8> {
    if files.iter().any(|f| f.extension().is_none_or(|e| e != "mcl")) {
        eprintln!("error: --ros2 needs the .mcl file, whose vehicle the bridge is checked against");
        return Err(2);
    }
    let db = Database::new();
    let mut roots = Vec::new();
    for f in files {
        roots.push(super::source_file(&db, f).map_err(|e| {
            eprintln!("error: {e}");
            2u8
        })?);
    }
    match mcl_ros2::bridge::load(bridge, &vehicle_of(&db, &roots)) {
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
/// without an engine), publishing what `status` hears on its status topic.
pub fn spawn_node(
    engine: Option<mcl_ros2::bridge::engine::Engine>,
    end: mcl_runtime::link::AacEnd,
    status: Option<mcl_ros2::status::Listener>,
) -> Option<std::thread::JoinHandle<()>> {
    let engine = engine?;
    Some(std::thread::spawn(move || {
        if let Err(e) = mcl_ros2::node::serve(engine, end, status, |w| eprintln!("warning: {w}")) {
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

/// The ROS 2 node as the vehicle of `mcl plan --run --ros2`: the run's end
/// of a link pair whose AAC end the node serves on its thread.
pub struct NodeLink {
    rt: tokio::runtime::Runtime,
    link: Option<mcl_runtime::link::Link>,
    node: Option<std::thread::JoinHandle<()>>,
}

impl NodeLink {
    /// Starts the node of `engine` (none: an error), publishing what
    /// `status` hears.
    pub fn start(
        engine: Option<mcl_ros2::bridge::engine::Engine>,
        status: mcl_ros2::status::Listener,
    ) -> Result<NodeLink, String> {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| format!("cannot start the runtime: {e}"))?;
        let (link, end) = mcl_runtime::link::pair();
        let node = spawn_node(engine, end, Some(status)).ok_or("no ROS 2 bridge")?;
        Ok(NodeLink { rt, link: Some(link), node: Some(node) })
    }

    /// Closes the link: the node delivers the last commands, then leaves.
    pub fn close(mut self) {
        drop(self.link.take());
        join_node(self.node.take());
    }
}

impl mcl_plan::run::AacLink for NodeLink {
    fn send(&mut self, action: mcl_runtime::link::Action) -> Result<(), String> {
        match &self.link {
            Some(l) if l.actions.send(action).is_ok() => Ok(()),
            _ => Err("the ROS 2 node has stopped".into()),
        }
    }

    fn recv(&mut self, timeout: Option<std::time::Duration>) -> Result<Option<mcl_runtime::link::Inbound>, String> {
        let Some(link) = self.link.as_mut() else { return Err("the ROS 2 node has stopped".into()) };
        super::plan::recv_on(&self.rt, link, timeout).ok_or_else(|| "the ROS 2 node has stopped".into())
    }
}
