//! The monitor (docs/monitor.md): `mcl run --monitor` serves a live view of
//! the run ([`start_live`], [`linger`]), and `mcl monitor TRACE...` serves
//! the same page replaying trace files ([`run`]).

use std::path::PathBuf;
use std::sync::Arc;

use mcl_compiler::compile::structure_tree::{self, StructureNode};
use mcl_monitor::tree::{MissionTree, Node};
use mcl_monitor::{Hub, Mode, Monitor};
use mcl_runtime::operator;
use mcl_runtime::trace::{read_trace, Record};
use mcl_syntax::ast::Item;

/// The monitor of a live run: the hub its trace sink feeds, and the
/// operator's commands for the drivers (with `--operator-token`).
pub struct Live {
    /// Where the run's records go.
    pub hub: Arc<Hub>,
    /// The operator's commands for each vehicle (empty without `--operator-token`).
    commands: Vec<(String, operator::Receiver)>,
}

impl Live {
    /// The operator's commands for the vehicle of `mission` (None without
    /// `--operator-token`, or once taken).
    pub fn commands_for(&mut self, mission: &str) -> Option<operator::Receiver> {
        let k = self.commands.iter().position(|(n, _)| n == mission)?;
        Some(self.commands.swap_remove(k).1)
    }
}

/// Starts the server of `mcl run --monitor=ADDR` for the run of `title`
/// whose vehicles run the missions `vehicles`, and says where it is on
/// stderr. Err: the exit status.
pub fn start_live(addr: &str, title: String, operator_token: Option<String>, vehicles: &[String]) -> Result<Live, u8> {
    let mut hub = Hub::new(Mode::Live, title.clone());
    let mut commands = Vec::new();
    if let Some(token) = operator_token {
        let mut senders = Vec::new();
        for v in vehicles {
            let (tx, rx) = operator::channel();
            senders.push((v.clone(), tx));
            commands.push((v.clone(), rx));
        }
        hub = hub.with_operator(token, senders);
    }
    if title.ends_with(".mcl") {
        hub.add_trees(trees_of(&title));
    }
    let hub = Arc::new(hub);
    let m = serve(hub.clone(), addr)?;
    warn_if_exposed(addr, hub.has_operator());
    eprintln!("monitor: {}", m.url());
    Ok(Live { hub, commands })
}

/// After the run: tells the pages it is over and keeps serving its final
/// state for `seconds` (`inf`: until the process is interrupted).
pub fn linger(hub: &Hub, seconds: f64) {
    hub.finish();
    if seconds <= 0.0 || seconds.is_nan() {
        return;
    }
    if seconds.is_infinite() {
        eprintln!("monitor: the run is over; serving its final state until interrupted (Ctrl-C)");
        loop {
            std::thread::park();
        }
    }
    eprintln!("monitor: the run is over; serving its final state for {seconds} s");
    std::thread::sleep(std::time::Duration::from_secs_f64(seconds.min(1e9)));
}

fn serve(hub: Arc<Hub>, addr: &str) -> Result<Monitor, u8> {
    Monitor::start(hub, addr).map_err(|e| {
        eprintln!("error: monitor: {e}");
        2
    })
}

/// A monitor reachable from other machines says so: its page shows the
/// run to anyone, and an operator's token travels in clear over HTTP.
fn warn_if_exposed(addr: &str, operator: bool) {
    let loopback = addr
        .parse::<std::net::SocketAddr>()
        .map(|a| a.ip().is_loopback())
        .unwrap_or_else(|_| addr.starts_with("localhost:"));
    if !loopback {
        eprintln!(
            "warning: monitor: {addr} is not a loopback address: anyone who reaches it sees the run{}",
            if operator { ", and the operator's token travels in clear (plain HTTP)" } else { "" }
        );
    }
}

/// `mcl monitor TRACE... --listen ADDR`: serves the page replaying the
/// traces (several: a fleet, each trace's records without a mission named
/// after its file) until interrupted.
pub fn run(traces: &[PathBuf], listen: &str) -> u8 {
    let records = match load(traces) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let title = traces.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    let hub = Arc::new(Hub::new(Mode::Replay, title));
    for r in &records {
        hub.push(r);
    }
    for f in hub.files().iter().filter(|f| f.ends_with(".mcl")) {
        hub.add_trees(trees_of(f));
    }
    let m = match serve(hub.clone(), listen) {
        Ok(m) => m,
        Err(code) => return code,
    };
    warn_if_exposed(listen, false);
    eprintln!("monitor: {} ({} records; Ctrl-C to stop)", m.url(), records.len());
    loop {
        std::thread::park();
    }
}

/// The records of every trace, in time order (a stable sort: each trace
/// keeps its order at equal times).
fn load(traces: &[PathBuf]) -> Result<Vec<Record>, String> {
    if traces.is_empty() {
        return Err("give at least one trace (mcl run --trace FILE writes one)".into());
    }
    let mut all = Vec::new();
    for p in traces {
        let mut rs = read_trace(p)?;
        if traces.len() > 1 {
            let name = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            for r in &mut rs {
                r.mission.get_or_insert_with(|| name.clone());
            }
        }
        all.extend(rs);
    }
    all.sort_by(|a, b| a.t.total_cmp(&b.t));
    Ok(all)
}

/// The control-structure trees of the missions written in `file` (none
/// when it cannot be read): mcl-compiler's walk of the syntax tree
/// (`structure_tree`, also drawn by `mcl compile --view structure`), with
/// lines for offsets.
pub fn trees_of(file: &str) -> Vec<MissionTree> {
    let Ok(text) = mcl_net::input::read_source(std::path::Path::new(file)) else { return Vec::new() };
    let parsed = mcl_syntax::parse(&text);
    let names = mcl_compiler::scope::mission_names(&parsed.file);
    let line =
        |offset: usize| text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() as u32 + 1;
    parsed
        .file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Mission(m) => Some(m),
            _ => None,
        })
        .zip(names)
        .map(|(m, mission)| MissionTree {
            mission,
            file: file.to_string(),
            root: node(&structure_tree::block(&m.body), &line),
        })
        .collect()
}

/// The monitor's node of a node of the tree.
fn node(n: &StructureNode, line: &dyn Fn(usize) -> u32) -> Node {
    Node {
        kind: n.kind.to_string(),
        text: n.text.clone(),
        line: line(n.offset),
        children: n.children.iter().map(|(p, c)| (p.clone(), node(c, line))).collect(),
    }
}
