//! `mcl run`: play a mission against a mock vehicle (virtual or real time)
//! or a vehicle's AAC over TCP.
//!
//! Exit status: 0 mission ok, 1 mission fail, 2 usage, compile or I/O error,
//! 3 mission stuck, aborted by the operator (`--operator-token`) or time limit passed.
//!
//! With `--mock` or `--sim` and no `--mission`, a file with several missions runs every
//! vehicle at once, coordinated by its constraints ([`run_coordinated`]).

use mcl_compiler::compile::{compile_file, compile_file_unverified, CompileError};
use mcl_compiler::diagnostics::render_human;
use mcl_compiler::{check_file, Database, Db};
use mcl_net::Net;
use mcl_runtime::clock::Clock;
use mcl_runtime::driver::{self, End, Limits, Session, Sink};
use mcl_runtime::journal::{self, Entry, JournalWriter};
use mcl_runtime::mock::MockVehicle;
use mcl_runtime::player::{Output, Player, PlayerOptions};
use mcl_runtime::scenario::{ProgramNames, Scenario};
use mcl_runtime::trace::{live_line, Record, RecordKind, SourceMap, TraceWriter, Tracer};
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Options of `mcl run` (its command-line arguments).
#[derive(Debug, Default, clap::Args)]
pub struct Options {
    /// The mission: an .mcl or .pnml file.
    pub file: PathBuf,
    /// Play against the in-process mock vehicle.
    #[arg(long)]
    pub mock: bool,
    /// Play against a simulated vehicle that moves in a simulated world (docs/simulator.md): with
    /// --virtual-time as fast as it goes, else paced by the wall clock times --speed.
    #[arg(long)]
    pub sim: bool,
    /// With --sim: the world (TOML; default: a flat seabed at 20 m, nothing else).
    #[arg(long, value_name = "FILE")]
    pub world: Option<PathBuf>,
    /// With --sim: how the vehicle's primitives are simulated (TOML; default: examples/sim/vehicle-model.toml);
    /// NAME=FILE for the vehicle of mission NAME only (repeatable).
    #[arg(long, value_name = "[NAME=]FILE")]
    pub vehicle_model: Vec<String>,
    /// With --sim: draw the vehicle's path (plan view and depth profile) as SVG here.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Play against the AAC listening at HOST:PORT.
    #[arg(long, value_name = "HOST:PORT")]
    pub aac: Option<String>,
    /// Play against a ROS 2 vehicle: the player is a ROS 2 node whose topics are mapped to
    /// the vehicle file's primitives by this bridge file (docs/ros2.md; topics for now).
    #[arg(long, value_name = "BRIDGE.toml")]
    pub ros2: Option<PathBuf>,
    /// Shared secret for the AAC.
    #[arg(long)]
    pub token: Option<String>,
    /// Play against the vehicle's AAC over Zenoh: the AAC protocol's messages under
    /// `mcl/<vehicle>/aac/...` (docs/zenoh.md).
    #[arg(long)]
    pub zenoh: bool,
    /// With --zenoh: the vehicle's name in the Zenoh keys (default: the mission's name).
    #[arg(long, value_name = "NAME")]
    pub vehicle_name: Option<String>,
    /// Zenoh: connect to this endpoint (a router or a peer), e.g. tcp/127.0.0.1:7447 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// Zenoh: listen on this endpoint, e.g. tcp/127.0.0.1:7448 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_listen: Vec<String>,
    /// Zenoh: start from this Zenoh configuration file (JSON5; peer mode by default).
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Zenoh: the fleet name in the coordination keys `mcl/<fleet>/...` (default: the file's stem).
    #[arg(long, value_name = "NAME")]
    pub zenoh_fleet: Option<String>,
    /// Zenoh: this process's region (Zenoh's `region_name`), for a router run with
    /// `mcl zenoh-router --region NAME`; without --zenoh-listen the peer then listens nowhere
    /// (docs/zenoh.md).
    #[arg(long, value_name = "NAME")]
    pub region: Option<String>,
    /// How the mock vehicle answers (TOML, see docs/scenarios.md). A scenario written by
    /// `mcl check --counterexample-scenario` (its `[counterexample]` table) also runs a program
    /// whose only errors are verification errors (E06xx, deadlocking constraints), and the run
    /// ends by saying whether it reproduced the counterexample.
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// Seed of the random choices (default: the scenario's seed, else 0).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run in virtual time: deterministic and instantaneous (needs --mock or --sim).
    #[arg(long)]
    pub virtual_time: bool,
    /// Mission time runs FACTOR times faster than real time (with --aac, only for a mock AAC run with the same --speed).
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0)]
    pub speed: f64,
    /// Write the trace here (JSON lines).
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Write an SVG chronogram of the run here.
    #[arg(long, value_name = "FILE")]
    pub chronogram: Option<PathBuf>,
    /// Write the trace's records as an MCAP file here, for Foxglove (docs/mcap.md).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// Journal every firing and received event here, to --resume after a crash.
    #[arg(long, value_name = "FILE")]
    pub journal: Option<PathBuf>,
    /// Resume the run journaled in FILE (and keep journaling there).
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Give a symbolic argument a value, e.g. --set timeout=60 (repeatable).
    #[arg(long, value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Stop (exit status 3) when mission time passes SECONDS (virtual time: 86400 unless given; `inf`: no limit).
    #[arg(long, value_name = "SECONDS")]
    pub time_limit: Option<f64>,
    /// With --aac: give up (exit status 2) when no vehicle has answered within SECONDS
    /// of wall-clock time (`inf`: wait for ever). The mission starts, and its clock runs,
    /// only once the vehicle is connected.
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0)]
    pub connect_timeout: f64,
    /// Run only this mission of a file that defines several (default: all of them
    /// coordinated with --mock, the first with --aac).
    #[arg(long, value_name = "NAME")]
    pub mission: Option<String>,
    /// How coordinated vehicles exchange messages (several missions with --mock).
    #[arg(long, value_enum, default_value = "in-process")]
    pub transport: Transport,
    /// Host the TCP transport's listeners bind to (one free port per vehicle).
    #[arg(long, value_name = "HOST", default_value = "127.0.0.1")]
    pub coord_host: String,
    /// Run only this vehicle (mission) of a coordinated file, in this process, over TCP with
    /// the others (--coord-listen, --coord-peer; real time).
    #[arg(long, value_name = "NAME")]
    pub vehicle: Option<String>,
    /// With --vehicle: the address this vehicle listens on for coordination messages.
    #[arg(long, value_name = "HOST:PORT")]
    pub coord_listen: Option<String>,
    /// With --vehicle: where another vehicle of the file listens (repeatable).
    #[arg(long, value_name = "NAME=HOST:PORT")]
    pub coord_peer: Vec<String>,
    /// With --vehicle: the fleet secret that authenticates every coordination link (the same
    /// for every vehicle; prefer --coord-token-file, which other users cannot read in `ps`).
    #[arg(long, value_name = "SECRET")]
    pub coord_token: Option<String>,
    /// With --vehicle: read the fleet secret from FILE (surrounding whitespace ignored).
    #[arg(long, value_name = "FILE")]
    pub coord_token_file: Option<PathBuf>,
    /// With --vehicle: allow --coord-listen on a non-loopback address without a fleet secret
    /// (anyone who reaches the port can then forge coordination messages).
    #[arg(long)]
    pub coord_insecure: bool,
    /// Coordinated runs in virtual time: carry every coordination message over a modelled
    /// acoustic link, `acoustic:bitrate=BPS,loss=P,delay=S[,range=M]` (losses drawn from
    /// --seed; with --sim, the delay from the distance and frames beyond range lost;
    /// docs/acoustic.md).
    #[arg(long, value_name = "SPEC")]
    pub link: Option<String>,
    /// No live log.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also log every firing and timer.
    #[arg(short, long)]
    pub verbose: bool,
    /// Test hook: abort after N journal syncs, as a crash would.
    #[arg(long, hide = true)]
    pub crash_after: Option<u64>,
    /// Serve a live view of the run in the browser at ADDR (`--monitor` alone: 127.0.0.1 on any
    /// free port); the URL is printed on standard error (docs/monitor.md).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, require_equals = true, default_missing_value = "127.0.0.1:0")]
    pub monitor: Option<String>,
    /// With --monitor: once the run is over, keep serving its final state SECONDS longer (`inf`:
    /// until interrupted).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
    pub monitor_linger: f64,
    /// With --monitor, in real time: take an operator's commands (pause, resume, abort, answer)
    /// from requests that carry this token (`Authorization: Bearer TOKEN`), for every vehicle of
    /// the run. Each mission's net gets an abort hook: resume its journal with the same option.
    #[arg(long, value_name = "TOKEN")]
    pub operator_token: Option<String>,
}

/// How the vehicles of a coordinated run exchange messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Transport {
    /// Channels inside the process.
    #[default]
    InProcess,
    /// JSON lines over TCP (one listener per vehicle).
    Tcp,
    /// Zenoh publications (docs/zenoh.md; --zenoh-connect, --zenoh-listen, --zenoh-config).
    Zenoh,
}

/// A loaded mission.
pub struct LoadedMission {
    pub name: String,
    pub net: Net,
    /// The names its calls pass as arguments (`Altitude( altitude, ... )`),
    /// which `--set` gives values to; empty for a PNML file.
    pub symbols: Vec<String>,
}

/// The symbolic arguments of each mission of `file`, by mission name
/// (`scope::mission_names`): identifiers in call arguments, lists
/// included, that are not the mission's own parameters.
fn mission_symbols(file: &mcl_syntax::ast::SourceFile) -> BTreeMap<String, Vec<String>> {
    use mcl_syntax::ast::{Item, StmtKind, Value as V, ValueKind};
    fn idents(v: &V, params: &[String], out: &mut Vec<String>) {
        match &v.kind {
            ValueKind::Ident(n) if !params.contains(&n.text) && !out.contains(&n.text) => out.push(n.text.clone()),
            ValueKind::List { items, .. } => items.iter().for_each(|i| idents(i, params, out)),
            _ => {}
        }
    }
    let names = mcl_compiler::scope::mission_names(file);
    let missions = file.items.iter().filter_map(|i| match i {
        Item::Mission(m) => Some(m),
        _ => None,
    });
    let mut out = BTreeMap::new();
    for (name, m) in names.into_iter().zip(missions) {
        let params: Vec<String> = m.params.iter().map(|p| p.text.clone()).collect();
        let mut syms = Vec::new();
        mcl_syntax::visit::walk_block(&m.body, &mut |s| {
            if let StmtKind::Call(c) = &s.kind {
                c.args.iter().for_each(|a| idents(a, &params, &mut syms));
            }
        });
        out.insert(name, syms);
    }
    out
}

/// Loads the missions of an `.mcl` file (compiled in memory) or a `.pnml`
/// file. On error, prints it (diagnostics like `mcl check`) and returns the
/// exit status. With `unverified` (a run of a counterexample scenario), a
/// program whose only errors are verification errors (E06xx) is compiled
/// all the same.
pub fn load_missions(file: &Path, unverified: bool) -> Result<Vec<LoadedMission>, u8> {
    if file.extension().is_some_and(|e| e.eq_ignore_ascii_case("pnml") || e.eq_ignore_ascii_case("xml")) {
        let text = mcl_net::input::read_source(file).map_err(|e| {
            eprintln!("error: {e}");
            2u8
        })?;
        let nets = mcl_net::read_pnml_nets(&text).map_err(|e| {
            eprintln!("error: `{}`: {e}", file.display());
            2u8
        })?;
        return Ok(nets
            .into_iter()
            .map(|net| LoadedMission { name: net.name().to_string(), net, symbols: Vec::new() })
            .collect());
    }
    let db = Database::new();
    let f = super::source_file(&db, file).map_err(|e| {
        eprintln!("error: {e}");
        2u8
    })?;
    let compiled = if unverified { compile_file_unverified(&db, f) } else { compile_file(&db, f) };
    match compiled {
        Ok(ms) => {
            if unverified && check_file(&db, f).iter().any(|d| d.diag.is_error()) {
                eprintln!(
                    "note: `{}` breaks block properties (E06xx); it is run all the same to replay the counterexample",
                    file.display()
                );
            }
            let mut symbols = mission_symbols(&mcl_compiler::queries::parse(&db, f).file);
            Ok(ms
                .into_iter()
                .map(|m| LoadedMission {
                    symbols: symbols.remove(&m.name).unwrap_or_default(),
                    name: m.name,
                    net: m.net,
                })
                .collect())
        }
        Err(CompileError::HasErrors) => {
            let diags: Vec<_> = check_file(&db, f).iter().filter(|d| d.diag.is_error()).cloned().collect();
            eprint!("{}", render_human(&db, &diags, std::io::stderr().is_terminal()));
            eprintln!("error: `{}` has errors; nothing was run", file.display());
            Err(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            Err(2)
        }
    }
}

/// Parses `NAME=VALUE`; VALUE is JSON when it parses as JSON, a string otherwise.
pub fn parse_set(s: &str) -> Result<(String, Value), String> {
    let (k, v) = s.split_once('=').ok_or_else(|| format!("--set `{s}`: expected NAME=VALUE"))?;
    let k = k.trim();
    if k.is_empty() {
        return Err(format!("--set `{s}`: the name is empty"));
    }
    let v = serde_json::from_str(v.trim()).unwrap_or_else(|_| Value::String(v.to_string()));
    Ok((k.to_string(), v))
}

/// Trace file, live log and the records kept for the chronogram.
struct RunSink {
    /// Publishes each vehicle's mission state over Zenoh (`mcl/<vehicle>/status`).
    status: Option<mcl_zenoh::StatusPublisher>,
    /// Feeds the ROS 2 node's status topic (`--ros2`, docs/ros2.md).
    ros2_status: Option<mcl_ros2::status::Feed>,
    trace: Option<TraceWriter>,
    live: bool,
    verbose: bool,
    quiet_replay: bool,
    records: Vec<Record>,
    error: Option<String>,
    /// The last notice of the link to the AAC: `-q` prints none, but says
    /// the last one when the run fails.
    last_link: Option<String>,
    /// `--mcap FILE`: the same records as MCAP messages.
    mcap: Option<McapOut>,
    /// The live monitor (`--monitor`).
    monitor: Option<Arc<mcl_monitor::Hub>>,
}

type McapOut = mcl_mcap::McapTrace<std::io::BufWriter<std::fs::File>>;

/// The MCAP writer of `--mcap FILE`.
fn open_mcap(path: &Option<PathBuf>) -> Result<Option<McapOut>, u8> {
    let Some(p) = path else { return Ok(None) };
    let file = super::trace_to_mcap::create(p)?;
    mcl_mcap::McapTrace::new(file).map(Some).map_err(|e| usage(&format!("`{}`: {e}", p.display())))
}

impl RunSink {
    /// After a run: flushes the trace, reports a failed run, writes the
    /// chronogram. `Err` holds the exit status.
    fn finish<T, E: std::fmt::Display>(&mut self, result: Result<T, E>, chronogram: Option<&Path>) -> Result<T, u8> {
        if let Some(w) = &mut self.trace {
            if let Err(e) = w.flush() {
                self.error.get_or_insert(format!("cannot write the trace: {e}"));
            }
        }
        if let Some(m) = self.mcap.take() {
            if let Err(e) = m.finish() {
                self.error.get_or_insert(e.to_string());
            }
        }
        let end = result.map_err(|e| {
            eprintln!("error: {e}");
            if let Some(l) = self.last_link.as_ref().filter(|_| !self.live) {
                eprintln!("  the link's last notice: {l}");
            }
            2u8
        })?;
        if let Some(p) = chronogram {
            let svg = mcl_runtime::chronogram::render(&self.records, &mcl_runtime::chronogram::Options::default());
            if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                let _ = std::fs::create_dir_all(dir);
            }
            if let Err(e) = std::fs::write(p, svg) {
                eprintln!("error: cannot write `{}`: {e}", p.display());
                return Err(2);
            }
        }
        Ok(end)
    }
}

impl Sink for RunSink {
    fn record(&mut self, r: &Record) {
        if let Some(s) = &mut self.status {
            s.record(r);
        }
        if let Some(f) = &self.ros2_status {
            f.record(r);
        }
        if let Some(w) = &mut self.trace {
            if let Err(e) = w.write(r) {
                self.error.get_or_insert(format!("cannot write the trace: {e}"));
            }
        }
        if let Some(m) = &mut self.mcap {
            if let Err(e) = m.record(r) {
                self.error.get_or_insert(e.to_string());
            }
        }
        if self.live && !self.quiet_replay {
            if let Some(line) = live_line(r, self.verbose) {
                let mut out = std::io::stdout().lock();
                let _ = writeln!(out, "{line}");
                let _ = out.flush();
            }
        } else if !self.live {
            match &r.kind {
                // A quiet run prints no link lines; it keeps the last one
                // for the error of a run that fails (`finish`).
                RecordKind::Link { message } if !self.quiet_replay => self.last_link = Some(message.clone()),
                // It says when it refuses a coordination message.
                RecordKind::CoordReject { message } => eprintln!("warning: coordination: refused {message}"),
                _ => {}
            }
        }
        if let Some(h) = &self.monitor {
            h.push(r);
        }
        self.records.push(r.clone());
    }

    fn replaying(&mut self, on: bool) {
        self.quiet_replay = on;
    }
}

/// The trace writer of `--trace FILE`, flushed on SIGINT and SIGTERM too.
pub(crate) fn open_trace(path: &Option<PathBuf>) -> Result<Option<TraceWriter>, u8> {
    let Some(p) = path else { return Ok(None) };
    match TraceWriter::create(p) {
        Ok(w) => {
            let flusher = w.flusher();
            crate::interrupt::on_signal(move || flusher.flush());
            Ok(Some(w))
        }
        Err(e) => Err(usage(&format!("cannot write trace `{}`: {e}", p.display()))),
    }
}

fn usage(msg: &str) -> u8 {
    eprintln!("error: {msg}");
    2
}

pub fn run(o: Options) -> u8 {
    // Before any thread starts: SIGINT and SIGTERM flush the trace and exit
    // with 130 or 143.
    crate::interrupt::install();
    // Usage checks.
    if o.operator_token.is_some() && (o.monitor.is_none() || o.virtual_time) {
        return usage("--operator-token takes commands through the monitor of a real-time run: give --monitor, with --mock, --sim or --aac, without --virtual-time");
    }
    if o.operator_token.as_deref().is_some_and(str::is_empty) {
        return usage("--operator-token is empty");
    }
    if [o.mock, o.sim, o.aac.is_some(), o.ros2.is_some(), o.zenoh].iter().filter(|b| **b).count() != 1 {
        return usage(
            "give exactly one of --mock (in-process mock vehicle), --sim (simulated vehicle), --aac HOST:PORT, --ros2 BRIDGE.toml and --zenoh",
        );
    }
    let zenoh_flags =
        !o.zenoh_connect.is_empty() || !o.zenoh_listen.is_empty() || o.zenoh_config.is_some() || o.region.is_some();
    if (zenoh_flags || o.zenoh_fleet.is_some()) && !o.zenoh && o.transport != Transport::Zenoh {
        return usage(
            "--zenoh-connect, --zenoh-listen, --zenoh-config, --zenoh-fleet and --region go with --zenoh or --transport zenoh",
        );
    }
    if o.vehicle_name.is_some() && !o.zenoh {
        return usage("--vehicle-name goes with --zenoh");
    }
    // The ROS 2 bridge, checked against the file's vehicle before anything runs.
    let mut ros2_engine = match &o.ros2 {
        Some(b) => match super::ros2::engine_for(b, &[o.file.as_path()]) {
            Ok(e) => Some(e),
            Err(code) => return code,
        },
        None => None,
    };
    if !o.sim && (o.world.is_some() || !o.vehicle_model.is_empty() || o.trajectory.is_some()) {
        return usage("--world, --vehicle-model and --trajectory go with --sim");
    }
    if o.virtual_time && o.transport == Transport::Zenoh {
        return usage("--transport zenoh runs in real time (virtual time needs no transport)");
    }
    if o.virtual_time && !o.mock && !o.sim {
        return usage("--virtual-time needs --mock or --sim (a real AAC runs in real time)");
    }
    if o.scenario.is_some() && !o.mock && !o.sim {
        return usage(
            "--scenario configures the in-process mock; use it with --mock (give it to `mcl mock-aac` otherwise)",
        );
    }
    if !(o.speed.is_finite() && o.speed > 0.0) {
        return usage("--speed must be a positive number");
    }
    if o.journal.is_some() && o.resume.is_some() {
        return usage("--resume FILE continues the journal FILE; do not give --journal as well");
    }
    if o.connect_timeout.is_nan() || o.connect_timeout < 0.0 {
        return usage("--connect-timeout takes a number of seconds >= 0, or `inf`");
    }
    if o.time_limit.is_some_and(|t| t.is_nan() || t < 0.0) {
        return usage("--time-limit must be a number of seconds ≥ 0 (or `inf`: no limit)");
    }
    let mut symbols: BTreeMap<String, Value> = BTreeMap::new();
    let mut sets = Vec::new();
    for s in &o.set {
        match parse_set(s) {
            Ok(kv) => sets.push(kv),
            Err(e) => return usage(&e),
        }
    }

    // The mission; a counterexample scenario runs it even if it deadlocks.
    let counterexample = counterexample_of(&o);
    let missions = match load_missions(&o.file, counterexample.is_some()) {
        Ok(m) => m,
        Err(code) => return code,
    };
    if missions.is_empty() {
        eprintln!("error: `{}` defines no mission", o.file.display());
        return 2;
    }
    let several = missions.len() > 1;
    let names: Vec<String> = missions.iter().map(|m| m.name.clone()).collect();
    let is_mcl = !o.file.extension().is_some_and(|e| e.eq_ignore_ascii_case("pnml") || e.eq_ignore_ascii_case("xml"));
    let coord_flags = o.coord_listen.is_some()
        || !o.coord_peer.is_empty()
        || o.coord_token.is_some()
        || o.coord_token_file.is_some()
        || o.coord_insecure;
    if o.vehicle.is_some() || coord_flags {
        if o.vehicle.is_none() {
            return usage(
                "--coord-listen, --coord-peer, --coord-token, --coord-token-file and --coord-insecure go with --vehicle NAME",
            );
        }
        if !(several && o.mission.is_none() && o.mock && is_mcl) {
            return usage(
                "--vehicle runs one vehicle of an .mcl file with several missions, with --mock and without --mission",
            );
        }
        if o.virtual_time {
            return usage("--vehicle runs in real time (virtual time needs every vehicle in one process)");
        }
    }
    if several && o.mission.is_none() && (o.mock || o.sim) && is_mcl {
        return run_coordinated(&o, sets);
    }
    if o.link.is_some() {
        return usage(
            "--link models the coordination link of several missions run together (--mock or --sim, without --mission)",
        );
    }
    let chosen = match &o.mission {
        Some(n) => match missions.into_iter().find(|m| &m.name == n) {
            Some(m) => m,
            None => {
                return usage(&format!("`{}` has no mission `{n}` (missions: {})", o.file.display(), names.join(", ")))
            }
        },
        None => {
            if several {
                eprintln!(
                    "note: `{}` defines {} missions ({}); running the first, `{}` (pick one with --mission NAME)",
                    o.file.display(),
                    names.len(),
                    names.join(", "),
                    names[0]
                );
            }
            missions.into_iter().next().expect("not empty")
        }
    };
    if chosen.net.properties().iter().any(|(k, _)| k == "mission_param") {
        eprintln!(
            "warning: mission `{}` has parameters (a planner operator); its parameters are sent unresolved",
            chosen.name
        );
    }
    // The operator's abort marks `mission.abort` through a hook in the net.
    let net = match &o.operator_token {
        Some(_) => match mcl_runtime::operator::with_abort_hook(&chosen.net) {
            Ok(n) => Arc::new(n),
            Err(e) => return usage(&e),
        },
        None => Arc::new(chosen.net),
    };
    let mission_label = if several || chosen.name != "mission" { Some(chosen.name.clone()) } else { None };

    // Journal to resume.
    let resume_entries = match &o.resume {
        Some(p) => match journal::read_journal(p) {
            Ok(e) => Some(e),
            Err(e) => return usage(&e),
        },
        None => None,
    };
    let fingerprint = journal::fingerprint(&net);
    // The run id given to a TCP AAC: the journal's when resuming.
    let run_id: Option<String> = match &resume_entries {
        Some(entries) => match &entries[0] {
            Entry::Header { run, .. } => run.clone(),
            _ => None,
        },
        None => (o.aac.is_some() || o.zenoh).then(mcl_runtime::tcp::new_id),
    };

    // Scenario, seeds and symbols.
    let (scenario_text, scenario) = match (&resume_entries, &o.scenario) {
        (Some(entries), given) => {
            let Entry::Header { scenario, .. } = &entries[0] else { unreachable!("read_journal checks the header") };
            if let (Some(p), Some(text)) = (given, scenario) {
                if mcl_net::input::read_source(p).ok().as_deref() != Some(text.as_str()) {
                    return usage("--scenario differs from the scenario recorded in the journal");
                }
            }
            match scenario {
                Some(text) => match Scenario::from_toml(text, "scenario recorded in the journal") {
                    Ok(s) => (Some(text.clone()), s),
                    Err(e) => return usage(&e),
                },
                None => (None, Scenario::default()),
            }
        }
        (None, Some(p)) => {
            let text = match mcl_net::input::read_source(p) {
                Ok(t) => t,
                Err(e) => return usage(&format!("scenario: {e}")),
            };
            match Scenario::from_toml(&text, &p.display().to_string()) {
                Ok(s) => (Some(text), s),
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            }
        }
        (None, None) => (None, Scenario::default()),
    };
    let mut seed = o.seed.or(scenario.seed).unwrap_or(0);
    let mut mock_seed = scenario.seed.unwrap_or(seed);
    // The simulated vehicle's model and world, and the symbols they give.
    let sim_setup = match o.sim.then(|| super::sim::load(&o, &names)).transpose() {
        Ok(s) => s,
        Err(code) => return code,
    };
    if let Some(s) = &sim_setup {
        symbols.extend(s.symbols_of(&chosen.name));
    }
    symbols.extend(scenario.symbols.clone());
    symbols.extend(sets);
    // A real vehicle would receive a symbol's name as its value
    // (docs/aac-protocol.md §11): say so before the run starts.
    let unset: Vec<&str> = chosen.symbols.iter().filter(|s| !symbols.contains_key(*s)).map(String::as_str).collect();
    if o.aac.is_some() && resume_entries.is_none() && !unset.is_empty() {
        eprintln!(
            "warning: symbolic argument{} without a value, sent to the vehicle as {} own name{}: {} (give {} with --set {}=VALUE)",
            if unset.len() == 1 { "" } else { "s" },
            if unset.len() == 1 { "its" } else { "their" },
            if unset.len() == 1 { "" } else { "s" },
            unset.join(", "),
            if unset.len() == 1 { "it a value" } else { "each a value" },
            unset[0]
        );
    }
    if let Some(entries) = &resume_entries {
        let Entry::Header { mission, seed: s, fingerprint: f, symbols: syms, mock_seed: ms, .. } = &entries[0] else {
            unreachable!("read_journal checks the header")
        };
        if *f != fingerprint || *mission != chosen.name {
            return usage(&format!(
                "the journal was written by another mission or another version of it (journal: `{mission}` {f}; now: `{}` {fingerprint})",
                chosen.name
            ));
        }
        if o.seed.is_some_and(|x| x != *s) {
            return usage(&format!("--seed {} differs from the journal's seed {s}", o.seed.unwrap_or_default()));
        }
        if !o.set.is_empty() && symbols != *syms {
            return usage("--set differs from the symbols recorded in the journal");
        }
        seed = *s;
        mock_seed = ms.unwrap_or(seed);
        symbols = syms.clone();
    }

    let player = Player::new(net.clone(), PlayerOptions { seed, symbols: symbols.clone(), ..Default::default() });
    let mut sources = SourceMap::new();
    let tracer = Tracer::new(&net, mission_label, &mut sources);
    let trace = match open_trace(&o.trace) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let mcap = match open_mcap(&o.mcap) {
        Ok(m) => m,
        Err(code) => return code,
    };
    let mut live_monitor = match &o.monitor {
        Some(addr) => match super::monitor::start_live(
            addr,
            o.file.display().to_string(),
            o.operator_token.clone(),
            std::slice::from_ref(&chosen.name),
        ) {
            Ok(m) => Some(m),
            Err(code) => return code,
        },
        None => None,
    };
    let mut sink = RunSink {
        status: None,
        ros2_status: None,
        trace,
        live: !o.quiet,
        verbose: o.verbose,
        quiet_replay: false,
        records: Vec::new(),
        error: None,
        last_link: None,
        mcap,
        monitor: live_monitor.as_ref().map(|m| m.hub.clone()),
    };
    // The AAC over Zenoh: the vehicle's name in the keys, the session, the status.
    let zenoh_vehicle = o.vehicle_name.clone().unwrap_or_else(|| chosen.name.clone());
    let zenoh_node = match o.zenoh.then(|| open_zenoh(&o)).transpose() {
        Ok(n) => n,
        Err(code) => return code,
    };
    if let Some(n) = &zenoh_node {
        if let Err(e) = mcl_zenoh::keys::check_chunk("--vehicle-name", &zenoh_vehicle) {
            return usage(&e);
        }
        sink.status = Some(mcl_zenoh::StatusPublisher::new(n.clone(), Some((&zenoh_vehicle, &chosen.name))));
    }
    // The ROS 2 node's status topic hears the run's records.
    let ros2_status = ros2_engine.as_ref().map(|_| {
        let (feed, listener) = mcl_ros2::status::channel(&chosen.name);
        sink.ros2_status = Some(feed);
        listener
    });
    if o.mock || o.sim {
        let errors = scenario.check_against(&ProgramNames::of([net.as_ref()]));
        for e in &errors {
            eprintln!("error: scenario: {e}");
        }
        if !errors.is_empty() {
            return 2;
        }
    }
    let mut sim_vehicle = sim_setup.map(|s| s.single(&chosen.name, &net, scenario.clone(), mock_seed));
    if let Some(v) = &mut sim_vehicle {
        mcl_runtime::vehicle::VirtualVehicle::initial(v);
    }
    let mut mock = MockVehicle::from_net(&net, scenario, mock_seed);
    mock.initial();
    let kept_net = net.clone();

    // Replay the journal.
    let mut player = player;
    let mut resend = Vec::new();
    let mut offset = 0.0;
    let mut journal_writer = None;
    // Where the run stands with its AAC (from a journal of version 2).
    let mut resume_point = None;
    if let (Some(entries), Some(path)) = (&resume_entries, &o.resume) {
        sink.quiet_replay = true;
        // A simulated vehicle is re-derived: the loop replayed against it (docs/simulator.md).
        let mut sim_error = None;
        let aborted = mcl_runtime::operator::journal_aborted(entries);
        let replayed = journal::replay(&mut player, entries, |input, outs| {
            if let Some(v) = &mut sim_vehicle {
                super::sim::replay_input(v, input, outs, &tracer, &mut sink, &mut sim_error);
                return;
            }
            if let Some(m) = input.message() {
                mock.take_delivered(&m);
            }
            for out in outs {
                let mut r = tracer.record(out);
                if aborted {
                    mcl_runtime::operator::mark_aborted(&mut r);
                }
                sink.record(&r);
                if let Output::Send { t, action } = out {
                    mock.on_action(*t, action);
                }
            }
        });
        sink.quiet_replay = false;
        let replayed = match replayed.and_then(|r| sim_error.map_or(Ok(r), Err)) {
            Ok(r) => r,
            Err(e) => return usage(&format!("cannot resume from `{}`: {e}", path.display())),
        };
        let _ = mock.take_warnings();
        offset = replayed.last_time;
        resend = replayed.unacknowledged();
        resume_point = replayed.resume_point.clone();
        if !o.quiet {
            println!(
                "[{offset:>10.3}] resumed from {}: {} inputs replayed, {} transitions fired, {} actions sent{}",
                path.display(),
                replayed.inputs,
                player.fired_count(),
                replayed.actions.len(),
                if o.virtual_time || resend.is_empty() {
                    String::new()
                } else {
                    format!(" ({} not acknowledged: sent again)", resend.len())
                }
            );
        }
        match JournalWriter::append_to(path) {
            Ok(w) => journal_writer = Some(w),
            Err(e) => return usage(&e),
        }
    } else if let Some(path) = &o.journal {
        let header = Entry::Header {
            version: journal::VERSION,
            mission: chosen.name.clone(),
            seed,
            fingerprint: fingerprint.clone(),
            symbols: symbols.clone(),
            scenario: if o.mock || o.sim { scenario_text.clone().or(Some(String::new())) } else { None },
            mock_seed: (o.mock || o.sim).then_some(mock_seed),
            run: run_id.clone(),
            unix_start: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs_f64())
                .unwrap_or(0.0),
        };
        match JournalWriter::create(path, &header) {
            Ok(w) => journal_writer = Some(w),
            Err(e) => return usage(&e),
        }
    }

    let mut limits = if o.virtual_time { Limits::virtual_time(o.time_limit) } else { Limits::real_time(o.time_limit) };
    limits.connect_timeout = Some(o.connect_timeout).filter(|t| t.is_finite());
    let mut session = Session::new(player, tracer, &mut sink);
    session.journal = journal_writer;
    session.crash_after = o.crash_after;
    session.operator = live_monitor.as_mut().and_then(|m| m.commands_for(&chosen.name));
    // Until the AAC welcomes the player, actions are queued.
    session.link_down = o.aac.is_some() || o.zenoh;
    // The events the run handled in its AAC session: told to the AAC once
    // journaled, and, when resuming, where the AAC takes up again.
    let delivered = match &resume_point {
        Some((id, n)) => mcl_runtime::link::Delivered::new(id.clone(), *n),
        None => mcl_runtime::link::Delivered::default(),
    };
    session.delivered = delivered.clone();
    let result: Result<End, String> = if let (Some(v), true) = (&mut sim_vehicle, o.virtual_time) {
        driver::run_virtual(&mut session, v, limits)
    } else if let Some(v) = &mut sim_vehicle {
        match tokio::runtime::Builder::new_current_thread().enable_all().build() {
            Ok(rt) => rt.block_on(driver::run_paced(&mut session, v, limits, Clock::new(o.speed, offset))),
            Err(e) => return usage(&format!("cannot start the runtime: {e}")),
        }
    } else if o.virtual_time {
        driver::run_virtual(&mut session, &mut mock, limits)
    } else {
        let rt = match tokio::runtime::Builder::new_current_thread().enable_all().build() {
            Ok(rt) => rt,
            Err(e) => return usage(&format!("cannot start the runtime: {e}")),
        };
        let speed = o.speed;
        let aac = o.aac.clone();
        let token = o.token.clone();
        let mission_name = chosen.name.clone();
        rt.block_on(async {
            let clock = Clock::new(speed, offset);
            if let Some(node) = zenoh_node.clone() {
                let opts = mcl_zenoh::AacOptions {
                    mission: mission_name.clone(),
                    run: run_id.clone().unwrap_or_else(mcl_runtime::tcp::new_id),
                    token: token.clone(),
                    delivered: delivered.clone(),
                    events: mcl_runtime::protocol::EventEnd::of_net(session.player.net()),
                    linger: std::time::Duration::from_secs(10),
                };
                let (mut link, handle) = mcl_zenoh::connect(node, &zenoh_vehicle, opts).await?;
                let r = driver::run_real_time(&mut session, &mut link, clock, limits, resend).await;
                // Let the last actions reach the vehicle before leaving.
                let mcl_runtime::link::Link { actions, inbound } = link;
                drop(actions);
                let _ = handle.await;
                drop(inbound);
                return r;
            }
            match aac {
                None if ros2_engine.is_some() => {
                    let (mut link, end) = mcl_runtime::link::pair();
                    let node = super::ros2::spawn_node(ros2_engine.take(), end, ros2_status);
                    let r = driver::run_real_time(&mut session, &mut link, clock, limits, resend).await;
                    // Closing the link ends the node.
                    drop(link);
                    super::ros2::join_node(node);
                    r
                }
                None => {
                    let (mut link, end) = mcl_runtime::link::pair();
                    let server = tokio::spawn(driver::serve_mock(mock, end, clock, |w| eprintln!("warning: {w}")));
                    let r = driver::run_real_time(&mut session, &mut link, clock, limits, resend).await;
                    drop(link);
                    let _ = server.await;
                    r
                }
                Some(addr) => {
                    let opts = mcl_runtime::tcp::ConnectOptions {
                        token,
                        mission: mission_name,
                        run: run_id,
                        // A version 1 journal has no event numbers: its run
                        // resumes without a resume point.
                        delivered: (o.resume.is_none() || resume_point.is_some()).then_some(delivered),
                        reestablish: true,
                        events: mcl_runtime::protocol::EventEnd::of_net(session.player.net()),
                        ..Default::default()
                    };
                    let (mut link, handle) = mcl_runtime::tcp::connect_with_handle(addr, opts);
                    let r = driver::run_real_time(&mut session, &mut link, clock, limits, resend).await;
                    // Let the last actions reach the vehicle before leaving.
                    let mcl_runtime::link::Link { actions, inbound } = link;
                    drop(actions);
                    match handle.await {
                        Ok(Err(e)) => eprintln!("warning: {e}"),
                        Err(e) => eprintln!("warning: the link task failed: {e}"),
                        Ok(Ok(_)) => {}
                    }
                    drop(inbound);
                    r
                }
            }
        })
    };
    let player_time = session.player.now();
    let fired = session.player.fired_count();
    drop(session);

    let end = match sink.finish(result, o.chronogram.as_deref()) {
        Ok(end) => end,
        Err(code) => return code,
    };
    let end_time = end.driver_time().unwrap_or(player_time);
    if let (Some(v), Some(p)) = (&sim_vehicle, &o.trajectory) {
        let title = format!(
            "{} — mission `{}`, {} at t={end_time:.1} s",
            o.file.display(),
            chosen.name,
            end.result().to_uppercase()
        );
        if let Err(code) = super::sim::write_trajectory(v, p, &title) {
            return code;
        }
    }
    if let Some(e) = sink.error {
        eprintln!("error: {e}");
        return 2;
    }
    let counts = Counts::of(sink.records.iter());
    // How it got there, when it left its nominal path (a catch, a monitor's condition).
    let via = sink.records.iter().rev().find_map(|r| match &r.kind {
        RecordKind::Outcome { via, .. } => Some(via.clone()),
        _ => None,
    });
    // An operator's abort ends a mission that the player sees stuck.
    let aborted =
        sink.records.iter().rev().any(|r| matches!(&r.kind, RecordKind::Outcome { result, .. } if result == "aborted"));
    eprintln!(
        "mission `{}`: {}{} at t={end_time:.3} s ({} actions, {} events, {} unexpected events, {fired} firings)",
        chosen.name,
        if aborted { "ABORTED".to_string() } else { end.result().to_uppercase() },
        via.flatten().map(|v| format!(" through {v}")).unwrap_or_default(),
        counts.actions,
        counts.events,
        counts.unexpected,
    );
    if let Some(expected) = &counterexample {
        let stuck: Vec<String> =
            mcl_runtime::counterexample::is_stuck(&end).then(|| chosen.name.clone()).into_iter().collect();
        say_reproduced(expected, &[(chosen.name.clone(), kept_net.as_ref())], &sink.records, &stuck);
    }
    if let Some(m) = &live_monitor {
        super::monitor::linger(&m.hub, o.monitor_linger);
    }
    end.exit_code()
}

/// The `[counterexample]` table of the scenario of a run with the mock
/// (not resumed), if it has one.
fn counterexample_of(o: &Options) -> Option<mcl_runtime::counterexample::Expected> {
    if !o.mock || o.resume.is_some() {
        return None;
    }
    let text = mcl_net::input::read_source(o.scenario.as_ref()?).ok()?;
    mcl_runtime::counterexample::expected_of(&text)
}

/// Says whether the run reproduced the counterexample its scenario replays.
fn say_reproduced(
    expected: &mcl_runtime::counterexample::Expected,
    nets: &[(String, &Net)],
    records: &[Record],
    stuck: &[String],
) {
    let what = format!("{} at {}", expected.code, expected.at);
    match mcl_runtime::counterexample::reproduced(expected, nets, records, stuck) {
        Ok(()) => {
            let ms: Vec<String> = expected
                .marking
                .keys()
                .map(|m| format!("`{m}` {}", if stuck.contains(m) { "stuck" } else { "ended" }))
                .collect();
            eprintln!("counterexample of {what}: reproduced ({}, in the marking it names)", ms.join(", "))
        }
        Err(why) => eprintln!("counterexample of {what}: NOT reproduced: {why}"),
    }
}

/// The link model of `--link` (virtual time, several vehicles in this
/// process), with the simulated vehicles' positions.
fn acoustic_link(
    o: &Options,
    simulated: &[(String, mcl_sim::SharedSim)],
) -> Result<Option<mcl_runtime::acoustic::AcousticLink>, u8> {
    let Some(text) = &o.link else { return Ok(None) };
    if !o.virtual_time || o.vehicle.is_some() {
        return Err(usage(
            "--link models the coordination link of a run in virtual time: give --virtual-time, without --vehicle",
        ));
    }
    let spec = mcl_runtime::acoustic::LinkSpec::parse(text).map_err(|e| usage(&format!("--link: {e}")))?;
    let positions: Option<mcl_runtime::acoustic::Positions> = (!simulated.is_empty()).then(|| {
        let sims: Vec<(String, mcl_sim::SharedSim)> = simulated.to_vec();
        std::sync::Arc::new(move |name: &str| {
            sims.iter().find(|(n, _)| n == name).map(|(_, v)| {
                let p = v.lock().pose();
                [p.x, p.y, p.z]
            })
        }) as mcl_runtime::acoustic::Positions
    });
    Ok(Some(mcl_runtime::acoustic::AcousticLink { spec, seed: o.seed.unwrap_or(0), positions }))
}

/// The fleet secret of `--vehicle`'s coordination links (`--coord-token`,
/// `--coord-token-file`), none otherwise. Refuses (exit status 2) a listener
/// on a non-loopback address without a secret unless `--coord-insecure`.
fn coord_auth(o: &Options) -> Result<mcl_runtime::coord::Auth, u8> {
    let secret = match (&o.coord_token, &o.coord_token_file) {
        (Some(_), Some(_)) => return Err(usage("give one of --coord-token and --coord-token-file")),
        (Some(t), None) => Some(t.clone()),
        (None, Some(p)) => match mcl_net::input::read_source(p) {
            Ok(t) => Some(t.trim().to_string()),
            Err(e) => return Err(usage(&format!("--coord-token-file: {e}"))),
        },
        (None, None) => None,
    };
    if secret.as_deref().is_some_and(str::is_empty) {
        return Err(usage("the fleet secret (--coord-token, --coord-token-file) is empty"));
    }
    if let (None, Some(listen)) = (&secret, &o.coord_listen) {
        use std::net::ToSocketAddrs;
        let addrs: Vec<std::net::SocketAddr> = listen.to_socket_addrs().map(|a| a.collect()).unwrap_or_default();
        let loopback = !addrs.is_empty() && addrs.iter().all(|a| a.ip().is_loopback());
        if !loopback && !o.coord_insecure {
            return Err(usage(&format!(
                "--coord-listen {listen} is not a loopback address: anyone who reaches it could forge coordination messages; give the fleet secret with --coord-token-file FILE (or --coord-token), or --coord-insecure to accept the risk"
            )));
        }
    }
    Ok(match secret {
        Some(s) => mcl_runtime::coord::Auth::secret(s.as_bytes()),
        None => mcl_runtime::coord::Auth::none(),
    })
}

/// The Zenoh session of `--zenoh` or `--transport zenoh` (peer mode unless
/// the configuration file says otherwise).
fn open_zenoh(o: &Options) -> Result<Arc<mcl_zenoh::Node>, u8> {
    let opts = mcl_zenoh::ZenohOptions {
        mode: mcl_zenoh::Mode::Peer,
        connect: o.zenoh_connect.clone(),
        listen: o.zenoh_listen.clone(),
        config_file: o.zenoh_config.clone(),
        region: o.region.clone(),
        ..Default::default()
    };
    mcl_zenoh::Node::open(&opts).map(Arc::new).map_err(|e| usage(&e))
}

/// What the header of a vehicle's journal records.
struct Recorded {
    scenario: Option<String>,
    seed: u64,
    mock_seed: u64,
    symbols: BTreeMap<String, Value>,
    /// The run of the vehicle's coordination messages.
    run: String,
}

/// The journal of `--vehicle NAME` (`--journal` creates it, `--resume`
/// continues it), and, when resuming, the seed, mock seed and symbols it
/// recorded (checked against the options given).
#[allow(clippy::type_complexity)]
fn vehicle_journal(
    o: &Options,
    resume: &Option<Vec<Entry>>,
    mission: &str,
    net: &Net,
    rec: Recorded,
) -> Result<(Option<JournalWriter>, Option<(u64, u64, BTreeMap<String, Value>)>), u8> {
    let fingerprint = journal::fingerprint(net);
    if let (Some(entries), Some(path)) = (resume, &o.resume) {
        let Entry::Header { mission: m, seed: s, fingerprint: f, symbols: syms, mock_seed: ms, .. } = &entries[0]
        else {
            unreachable!("read_journal checks the header")
        };
        if *f != fingerprint || m != mission {
            return Err(usage(&format!(
                "the journal was written by another vehicle or another version of it (journal: `{m}` {f}; now: `{mission}` {fingerprint})"
            )));
        }
        if o.seed.is_some_and(|x| x != *s) {
            return Err(usage(&format!("--seed {} differs from the journal's seed {s}", o.seed.unwrap_or_default())));
        }
        let w = JournalWriter::append_to(path).map_err(|e| usage(&e))?;
        return Ok((Some(w), Some((*s, ms.unwrap_or(*s), syms.clone()))));
    }
    let Some(path) = &o.journal else { return Ok((None, None)) };
    let header = Entry::Header {
        version: journal::VERSION,
        mission: mission.to_string(),
        seed: rec.seed,
        fingerprint,
        symbols: rec.symbols,
        scenario: Some(rec.scenario.unwrap_or_default()),
        mock_seed: Some(rec.mock_seed),
        run: Some(rec.run),
        unix_start: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0),
    };
    let w = JournalWriter::create(path, &header).map_err(|e| usage(&e))?;
    Ok((Some(w), None))
}

/// What the summary line of a run counts among its records.
#[derive(Debug, Default)]
struct Counts {
    actions: usize,
    events: usize,
    unexpected: usize,
    sent: usize,
    received: usize,
}

impl Counts {
    fn of<'a>(records: impl Iterator<Item = &'a Record>) -> Counts {
        let mut c = Counts::default();
        for r in records {
            match r.kind {
                RecordKind::Action { .. } => c.actions += 1,
                RecordKind::Event { .. } => c.events += 1,
                RecordKind::UnexpectedEvent { .. } => c.unexpected += 1,
                RecordKind::CoordSend { .. } => c.sent += 1,
                RecordKind::CoordReceive { .. } => c.received += 1,
                _ => {}
            }
        }
        c
    }
}

/// `mcl run --mock FILE` on a file with several missions: every vehicle at
/// once, each with its own mock vehicle, exchanging the coordination
/// messages of its vehicle net over `o.transport`
/// (`mcl_runtime::multi`). The scenario applies to every vehicle, its
/// `[missions.NAME]` tables to one. With `--sim` each vehicle is simulated
/// in one shared world instead (`super::sim`, docs/simulator.md).
pub fn run_coordinated(o: &Options, sets: Vec<(String, Value)>) -> u8 {
    if (o.journal.is_some() || o.resume.is_some()) && o.vehicle.is_none() {
        return usage(
            "--journal and --resume record one vehicle: run each with --vehicle NAME (its own process), or pick one mission with --mission NAME",
        );
    }
    let auth = match coord_auth(o) {
        Ok(a) => a,
        Err(code) => return code,
    };
    let zenoh = o.transport == Transport::Zenoh;
    if zenoh && (o.coord_listen.is_some() || !o.coord_peer.is_empty()) {
        return usage(
            "--coord-listen and --coord-peer are TCP addresses; over Zenoh give --zenoh-listen and --zenoh-connect",
        );
    }
    let fleet = o.zenoh_fleet.clone().unwrap_or_else(|| {
        o.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "fleet".into())
    });
    let zenoh_node = match zenoh.then(|| open_zenoh(o)).transpose() {
        Ok(n) => n,
        Err(code) => return code,
    };
    if zenoh {
        if let Err(e) = mcl_zenoh::keys::check_chunk("fleet", &fleet) {
            return usage(&format!("{e}: give another with --zenoh-fleet NAME"));
        }
    }
    let resume_entries = match &o.resume {
        Some(p) => match journal::read_journal(p) {
            Ok(e) => Some(e),
            Err(e) => return usage(&e),
        },
        None => None,
    };
    // The run of this vehicle's messages: its journal's when resuming.
    let run_id = match resume_entries.as_deref().map(|e| &e[0]) {
        Some(Entry::Header { run: Some(r), .. }) => r.clone(),
        _ => mcl_runtime::tcp::new_id(),
    };
    let db = Database::new();
    let file = db.file(&o.file);
    let counterexample = counterexample_of(o);
    let vehicles = match super::compile::vehicle_nets(&db, file, 2, counterexample.is_some()) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let mut names: Vec<String> = vehicles.iter().map(|v| v.mission.clone()).collect();
    let file_missions = names.clone();
    if let Some(dup) = names.iter().enumerate().find(|(i, n)| names[..*i].contains(n)).map(|(_, n)| n) {
        return usage(&format!(
            "`{}` has two missions named `{dup}`: name every mission (`mission : name {{ ... }}`) to run them together",
            o.file.display()
        ));
    }
    let all_names: Vec<String> = names.iter().filter(|n| o.vehicle.as_ref() != Some(*n)).cloned().collect();
    // The names of every vehicle of the file: one scenario serves them all
    // (also when this process runs only one of them).
    let known = ProgramNames::of(vehicles.iter().map(|v| &v.net));
    // One vehicle in this process, the others elsewhere.
    let mut peers: Vec<(String, std::net::SocketAddr)> = Vec::new();
    let mut vehicles = vehicles;
    if let Some(me) = &o.vehicle {
        let Some(k) = names.iter().position(|n| n == me) else {
            return usage(&format!("`{}` has no mission `{me}` (missions: {})", o.file.display(), names.join(", ")));
        };
        for p in &o.coord_peer {
            let Some((name, addr)) = p.split_once('=') else {
                return usage(&format!("--coord-peer `{p}`: expected NAME=HOST:PORT"));
            };
            if !names.iter().any(|n| n == name) || name == me {
                return usage(&format!(
                    "--coord-peer `{p}`: `{name}` is not another mission of `{}` (missions: {})",
                    o.file.display(),
                    names.join(", ")
                ));
            }
            use std::net::ToSocketAddrs;
            match addr.to_socket_addrs().ok().and_then(|mut a| a.next()) {
                Some(a) => peers.push((name.to_string(), a)),
                None => return usage(&format!("--coord-peer `{p}`: cannot resolve `{addr}`")),
            }
        }
        let v = vehicles.swap_remove(k);
        let missing: Vec<&String> =
            v.send.iter().map(|(_, to)| to).filter(|to| !peers.iter().any(|(n, _)| n == *to)).collect();
        if let (Some(to), false) = (missing.first(), zenoh) {
            return usage(&format!(
                "`{me}` sends coordination messages to `{to}`: give its address with --coord-peer {to}=HOST:PORT"
            ));
        }
        vehicles = vec![v];
        names = vec![me.clone()];
    }
    // Scenarios (a resumed vehicle's is in its journal).
    let text = match (&resume_entries, &o.scenario) {
        (Some(entries), _) => match &entries[0] {
            Entry::Header { scenario: Some(t), .. } if !t.is_empty() => {
                Some((t.clone(), "scenario recorded in the journal".to_string()))
            }
            _ => None,
        },
        (None, Some(p)) => match mcl_net::input::read_source(p) {
            Ok(t) => Some((t, p.display().to_string())),
            Err(e) => return usage(&format!("scenario: {e}")),
        },
        (None, None) => None,
    };
    let mut scenarios = Vec::new();
    for n in &names {
        match &text {
            Some((t, origin)) => match mcl_runtime::multi::scenario_for(t, origin, n) {
                Ok(s) => scenarios.push(s),
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            },
            None => scenarios.push(Scenario::default()),
        }
    }
    if let Some((t, _)) = &text {
        for m in mcl_runtime::multi::scenario_missions(t) {
            if !names.contains(&m) {
                eprintln!("warning: scenario: there is no mission `{m}` (missions: {})", names.join(", "));
            }
        }
    }
    let mut errors = std::collections::BTreeSet::new();
    for s in &scenarios {
        errors.extend(s.check_against(&known));
    }
    for e in &errors {
        eprintln!("error: scenario: {e}");
    }
    if !errors.is_empty() {
        return 2;
    }

    let sim_setup = match o.sim.then(|| super::sim::load(o, &file_missions)).transpose() {
        Ok(s) => s,
        Err(code) => return code,
    };
    let mut simulated: Vec<(String, mcl_sim::SharedSim)> = Vec::new();
    let trace = match open_trace(&o.trace) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let mcap = match open_mcap(&o.mcap) {
        Ok(m) => m,
        Err(code) => return code,
    };
    let mut live_monitor = match &o.monitor {
        Some(addr) => {
            match super::monitor::start_live(addr, o.file.display().to_string(), o.operator_token.clone(), &names) {
                Ok(m) => Some(m),
                Err(code) => return code,
            }
        }
        None => None,
    };
    let sink = Arc::new(std::sync::Mutex::new(RunSink {
        status: None,
        ros2_status: None,
        trace,
        live: !o.quiet,
        verbose: o.verbose,
        quiet_replay: false,
        records: Vec::new(),
        error: None,
        last_link: None,
        mcap,
        monitor: live_monitor.as_ref().map(|m| m.hub.clone()),
    }));
    let mut sources = SourceMap::new();
    let mut parts = Vec::new();
    let mut journal_writer = None;
    let mut kept_nets: Vec<(String, Arc<Net>)> = Vec::new();
    for (v, scenario) in vehicles.into_iter().zip(scenarios) {
        let mut seed = o.seed.or(scenario.seed).unwrap_or(0);
        let mut mock_seed = scenario.seed.unwrap_or(seed);
        let mut symbols: BTreeMap<String, Value> =
            sim_setup.as_ref().map(|s| s.symbols_of(&v.mission)).unwrap_or_default();
        symbols.extend(scenario.symbols.clone());
        symbols.extend(sets.iter().cloned());
        // The operator's abort marks each vehicle's `mission.abort` through a hook in its net.
        let net = match &o.operator_token {
            Some(_) => match mcl_runtime::operator::with_abort_hook(&v.net) {
                Ok(n) => Arc::new(n),
                Err(e) => return usage(&e),
            },
            None => Arc::new(v.net),
        };
        if o.vehicle.is_some() {
            let recorded = Recorded {
                scenario: text.as_ref().map(|t| t.0.clone()),
                seed,
                mock_seed,
                symbols: symbols.clone(),
                run: run_id.clone(),
            };
            match vehicle_journal(o, &resume_entries, &v.mission, &net, recorded) {
                Ok((w, restored)) => {
                    journal_writer = w;
                    if let Some((s, ms, syms)) = restored {
                        (seed, mock_seed, symbols) = (s, ms, syms);
                    }
                }
                Err(code) => return code,
            }
        }
        let opts = PlayerOptions { seed, symbols, ..Default::default() };
        let tracer = Tracer::new(&net, Some(v.mission.clone()), &mut sources);
        let mock = fleet_vehicle(&sim_setup, &v.mission, &net, scenario.clone(), mock_seed, &mut simulated);
        kept_nets.push((v.mission.clone(), net.clone()));
        parts.push((v.mission, net, opts, tracer, mock));
    }
    let rt = match tokio::runtime::Builder::new_current_thread().enable_all().build() {
        Ok(rt) => rt,
        Err(e) => return usage(&format!("cannot start the runtime: {e}")),
    };
    let limits = if o.virtual_time { Limits::virtual_time(o.time_limit) } else { Limits::real_time(o.time_limit) };
    let link = match acoustic_link(o, &simulated) {
        Ok(l) => l,
        Err(code) => return code,
    };
    if let (Some(n), Ok(mut s)) = (&zenoh_node, sink.lock()) {
        s.status = Some(mcl_zenoh::StatusPublisher::new(n.clone(), None));
    }
    let shared: mcl_runtime::multi::SharedSink = sink.clone();
    let result: Result<mcl_runtime::multi::MultiEnd, String> = rt.block_on(async {
        let transports: Vec<Box<dyn mcl_runtime::coord::CoordTransport>> = if let (Some(me), Some(node)) =
            (&o.vehicle, &zenoh_node)
        {
            let received: std::collections::HashMap<String, u64> =
                resume_entries.as_deref().map(journal::received_seqs).unwrap_or_default().into_iter().collect();
            let mut end = mcl_zenoh::ZenohEnd::open(node.clone(), &fleet, me, auth.clone(), &received).await?;
            end.accept_from(&all_names);
            end.set_run(&run_id);
            for n in &all_names {
                end.add_peer(n)?;
            }
            eprintln!("coordination: `{me}` on Zenoh, fleet `{fleet}` (keys mcl/{fleet}/{me}/coord/...)");
            vec![Box::new(end)]
        } else if let Some(me) = &o.vehicle {
            let listen = o.coord_listen.clone().unwrap_or_else(|| format!("{}:0", o.coord_host));
            let received: std::collections::HashMap<String, u64> =
                resume_entries.as_deref().map(journal::received_seqs).unwrap_or_default().into_iter().collect();
            let mut end = mcl_runtime::coord::TcpEnd::bind_with(me, &listen, auth.clone(), &received)
                .await
                .map_err(|e| format!("cannot listen on `{listen}` for the coordination of `{me}`: {e}"))?;
            end.accept_from(&all_names);
            end.set_run(&run_id);
            eprintln!("coordination: `{me}` listens on {}", end.local_addr());
            for (n, a) in &peers {
                end.add_peer(n, *a);
            }
            vec![Box::new(end)]
        } else {
            match o.transport {
                Transport::InProcess => mcl_runtime::coord::in_process(&names)
                    .into_iter()
                    .map(|e| Box::new(e) as Box<dyn mcl_runtime::coord::CoordTransport>)
                    .collect(),
                Transport::Tcp => match mcl_runtime::coord::tcp_mesh(&names, &o.coord_host).await {
                    Ok(ends) => {
                        if o.verbose {
                            for e in &ends {
                                eprintln!("coordination: `{}` listens on {}", e.mission_name(), e.local_addr());
                            }
                        }
                        ends.into_iter().map(|e| Box::new(e) as Box<dyn mcl_runtime::coord::CoordTransport>).collect()
                    }
                    Err(e) => return Err(format!("cannot listen on `{}` for the TCP transport: {e}", o.coord_host)),
                },
                Transport::Zenoh => {
                    let node = zenoh_node.clone().ok_or("no Zenoh session")?;
                    mcl_zenoh::zenoh_mesh(node, &fleet, &names)
                        .await?
                        .into_iter()
                        .map(|e| Box::new(e) as Box<dyn mcl_runtime::coord::CoordTransport>)
                        .collect()
                }
            }
        };
        let mut vs = Vec::new();
        for ((name, net, opts, tracer, mock), tr) in parts.into_iter().zip(transports) {
            let mut v = mcl_runtime::multi::Vehicle::new(&name, net, opts, tracer, mock, tr)?;
            // A counterexample may start a vehicle late (`[counterexample.start]`).
            if let Some(t) = counterexample.as_ref().and_then(|e| e.start.get(&name)).filter(|_| o.virtual_time) {
                v = v.starting_at(*t);
            }
            // ... and deliver given messages late (`[[counterexample.delay]]`).
            let delays = counterexample.as_ref().filter(|_| o.virtual_time).map(|e| e.delay.as_slice()).unwrap_or(&[]);
            for d in delays.iter().filter(|d| d.from == name) {
                v = v.delaying(&d.to, d.seq, d.at);
            }
            if let Some(c) = live_monitor.as_mut().and_then(|m| m.commands_for(&name)) {
                v = v.with_operator(c);
            }
            vs.push(match journal_writer.take() {
                Some(w) => v.with_journal(w, resume_entries.clone(), o.crash_after),
                None => v,
            });
        }
        if o.virtual_time {
            mcl_runtime::multi::run_virtual_with_link(vs, shared, limits, link, None).await
        } else if o.sim {
            // Simulated vehicles: the virtual-time run, paced by the clock.
            mcl_runtime::multi::run_virtual_with_link(vs, shared, limits, link, Some(Clock::new(o.speed, 0.0))).await
        } else {
            let peers: Vec<String> = if zenoh && o.vehicle.is_some() {
                all_names.clone()
            } else {
                peers.iter().map(|(n, _)| n.clone()).collect()
            };
            // A resumed vehicle's clock goes on from its last journaled input.
            let offset = resume_entries.as_deref().map(journal::last_time).unwrap_or(0.0);
            mcl_runtime::multi::run_real_time_with_peers(vs, shared, Clock::new(o.speed, offset), limits, &peers).await
        }
    });
    let mut sink = match sink.lock() {
        Ok(s) => s,
        Err(_) => {
            eprintln!("error: the run failed");
            return 2;
        }
    };
    let end = match sink.finish(result, o.chronogram.as_deref()) {
        Ok(end) => end,
        Err(code) => return code,
    };
    if let Some(p) = &o.trajectory {
        let title = format!("{} — {} vehicles, {}", o.file.display(), simulated.len(), end.result().to_uppercase());
        if let Err(code) = super::sim::write_fleet_trajectory(&simulated, p, &title) {
            return code;
        }
    }
    if let Some(e) = sink.error.take() {
        eprintln!("error: {e}");
        return 2;
    }
    for ((name, e, t), fired) in end.ends.iter().zip(&end.fired) {
        let c = Counts::of(sink.records.iter().filter(|r| r.mission.as_deref() == Some(name.as_str())));
        // An operator's abort ends a mission that the player sees stuck.
        let aborted = sink.records.iter().any(|r| {
            r.mission.as_deref() == Some(name.as_str())
                && matches!(&r.kind, RecordKind::Outcome { result, .. } if result == "aborted")
        });
        eprintln!(
            "mission `{name}`: {} at t={t:.3} s ({} actions, {} events, {} unexpected events, {fired} firings, {} messages sent, {} received)",
            if aborted { "ABORTED".to_string() } else { e.result().to_uppercase() },
            c.actions,
            c.events,
            c.unexpected,
            c.sent,
            c.received,
        );
    }
    let mutex = if end.mutex.total() > 0 {
        format!(
            "; mutex protocol: {} requests, {} grants, {} returns",
            end.mutex.requests, end.mutex.grants, end.mutex.returns
        )
    } else {
        String::new()
    };
    eprintln!(
        "coordination: {} missions, {} messages sent ({} transport{mutex})",
        end.ends.len(),
        end.messages,
        match o.transport {
            Transport::Zenoh => "Zenoh",
            _ if o.vehicle.is_some() => "TCP",
            _ if o.link.is_some() => "acoustic link model over the in-process",
            Transport::InProcess => "in-process",
            Transport::Tcp => "TCP",
        }
    );
    if let Some(expected) = &counterexample {
        let stuck: Vec<String> = end
            .ends
            .iter()
            .filter(|(_, e, _)| mcl_runtime::counterexample::is_stuck(e))
            .map(|(n, _, _)| n.clone())
            .collect();
        let nets: Vec<(String, &Net)> = kept_nets.iter().map(|(n, net)| (n.clone(), net.as_ref())).collect();
        say_reproduced(expected, &nets, &sink.records, &stuck);
    }
    if let Some(m) = &live_monitor {
        super::monitor::linger(&m.hub, o.monitor_linger);
    }
    end.exit_code()
}

/// The vehicle of `mission` in a coordinated run: simulated in the world of
/// `sim` (kept in `simulated` for the trajectory), else the mock of `net`.
fn fleet_vehicle(
    sim: &Option<super::sim::Setup>,
    mission: &str,
    net: &Net,
    scenario: Scenario,
    mock_seed: u64,
    simulated: &mut Vec<(String, mcl_sim::SharedSim)>,
) -> super::sim::FleetVehicle {
    match sim {
        Some(s) => {
            let v = s.vehicle_of(mission, net, scenario, mock_seed);
            simulated.push((mission.to_string(), v.clone()));
            super::sim::FleetVehicle::Sim(v)
        }
        None => super::sim::FleetVehicle::Mock(Box::new(MockVehicle::from_net(net, scenario, mock_seed))),
    }
}
