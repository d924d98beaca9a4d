//! The monitor (docs/monitor.md): `mcl run --monitor` serves a live view of
//! the run ([`start_live`], [`linger`]), and `mcl monitor TRACE...` serves
//! the same page replaying trace files ([`run`]).

use std::path::PathBuf;
use std::sync::Arc;

use mcl_monitor::tree::{MissionTree, Node};
use mcl_monitor::{Hub, Mode, Monitor};
use mcl_runtime::operator;
use mcl_runtime::trace::{read_trace, Record};
use mcl_syntax::ast::{Block, Item, MonitorKind, ParallelOp, Stmt, StmtKind, Value};

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
/// when it cannot be read).
pub fn trees_of(file: &str) -> Vec<MissionTree> {
    let Ok(text) = mcl_net::input::read_source(std::path::Path::new(file)) else { return Vec::new() };
    let parsed = mcl_syntax::parse(&text);
    let names = mcl_compiler::scope::mission_names(&parsed.file);
    let line = |offset: u32| {
        text.as_bytes()[..(offset as usize).min(text.len())].iter().filter(|&&b| b == b'\n').count() as u32 + 1
    };
    parsed
        .file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Mission(m) => Some(m),
            _ => None,
        })
        .zip(names)
        .map(|(m, mission)| MissionTree { mission, file: file.to_string(), root: block(&m.body, &line) })
        .collect()
}

/// A block: its statement, or a sequence of them (the walk of
/// mcl-compiler's `tree_dot.rs`, as data).
fn block(b: &Block, line: &dyn Fn(u32) -> u32) -> Node {
    match b.stmts.as_slice() {
        [one] => stmt(one, line),
        stmts => Node {
            kind: "sequence".into(),
            text: String::new(),
            line: line(b.span.start),
            children: stmts.iter().enumerate().map(|(i, s)| ((i + 1).to_string(), stmt(s, line))).collect(),
        },
    }
}

fn structure(kind: &str, s: &Stmt, parts: &[(String, &Block)], line: &dyn Fn(u32) -> u32) -> Node {
    Node {
        kind: kind.into(),
        text: String::new(),
        line: line(s.span.start),
        children: parts.iter().map(|(p, b)| (p.clone(), block(b, line))).collect(),
    }
}

fn stmt(s: &Stmt, line: &dyn Fn(u32) -> u32) -> Node {
    let part = |p: &str| p.to_string();
    match &s.kind {
        StmtKind::Call(c) => {
            let args: Vec<String> = c.args.iter().map(Value::written).collect();
            let label = c.label.as_ref().map(|l| format!(" : {}", l.text)).unwrap_or_default();
            Node {
                kind: "call".into(),
                text: format!("{}({}){label}", c.name.text, args.join(", ")),
                line: line(c.span.start),
                children: Vec::new(),
            }
        }
        StmtKind::While { cond, body, .. } => {
            structure("while", s, &[(part("condition"), cond), (part("do"), body)], line)
        }
        StmtKind::If { cond, then, otherwise, .. } => match otherwise {
            Some(e) => structure(
                "if-then-else",
                s,
                &[(part("condition"), cond), (part("then"), then), (part("else"), e)],
                line,
            ),
            None => structure("if-then", s, &[(part("condition"), cond), (part("then"), then)], line),
        },
        StmtKind::Parallel { branches, ops, .. } => {
            let kind =
                if ops.first().is_some_and(|(o, _)| *o == ParallelOp::Or) { "parallel-or" } else { "parallel-and" };
            let parts: Vec<(String, &Block)> =
                branches.iter().enumerate().map(|(i, b)| (format!("branch {}", i + 1), b)).collect();
            structure(kind, s, &parts, line)
        }
        StmtKind::Try { body, catch, .. } => {
            structure("try-catch", s, &[(part("try"), body), (part("catch"), catch)], line)
        }
        StmtKind::Not { body, .. } => structure("not", s, &[(String::new(), body)], line),
        StmtKind::Monitor { body, handlers, .. } => {
            let mut parts = vec![(part("watched"), body)];
            for (j, h) in handlers.iter().enumerate() {
                let kw = match h.kind {
                    MonitorKind::Condition => "condition",
                    MonitorKind::WhileCondition => "while_condition",
                };
                parts.push((format!("{kw} {}", j + 1), &h.condition));
                parts.push((format!("do {}", j + 1), &h.action));
            }
            structure("monitor", s, &parts, line)
        }
        StmtKind::Error => {
            Node { kind: "error".into(), text: "(syntax error)".into(), line: line(s.span.start), children: Vec::new() }
        }
    }
}
