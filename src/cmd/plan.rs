//! `mcl plan`: plans with the MCL planner (mcl-plan) over a PDDL domain and
//! problem, optionally checking the domain's `:mcl` missions against the
//! `mission Name( ... )` / `mcl_plan_op Name( ... )` definitions of an .mcl
//! file. See docs/planning.md.

use clap::ValueEnum;
use mcl_compiler::diagnostics::render_human;
use mcl_compiler::{check_file, program, Database, Db, FileDiagnostic};
use mcl_plan::{Algorithm, Heuristic, Outcome};
use mcl_syntax::Severity;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SearchChoice {
    /// Breadth-first search: fewest actions (seed Extract 7.4).
    Bfs,
    /// Uniform-cost search: cheapest plan.
    Ucs,
    /// A* with --heuristic.
    Astar,
    /// Greedy best-first search with --heuristic: fast, no cost guarantee.
    Gbfs,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum HeuristicChoice {
    /// Additive heuristic (seed 7.3.1.2): informative, not admissible.
    Hadd,
    /// Max heuristic: admissible, A* plans are cheapest.
    Hmax,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PlanFormat {
    /// IPC plan: one `(action arg ...)` per line, then `; cost = N (...)`.
    Ipc,
    /// Each step with its MCL mission instance and expected facts.
    Steps,
    /// The whole plan (Definition 7.2.4) as JSON.
    Json,
}

/// Options of `mcl plan` (its command-line arguments).
#[derive(Debug, clap::Args)]
pub struct Options {
    /// The .mcl file defining the mission operators the domain's `:mcl` calls name.
    pub file: Option<PathBuf>,
    /// PDDL domain file (default: domain.pddl beside FILE.mcl).
    #[arg(long, value_name = "D.pddl")]
    pub domain: Option<PathBuf>,
    /// PDDL problem file (default: problem.pddl beside FILE.mcl).
    #[arg(long, value_name = "P.pddl")]
    pub problem: Option<PathBuf>,
    /// The .mcl file of mission operators (instead of FILE).
    #[arg(long, value_name = "FILE.mcl")]
    pub operators: Option<PathBuf>,
    /// Search algorithm.
    #[arg(long, value_enum, default_value = "astar")]
    pub search: SearchChoice,
    /// Heuristic of A*.
    #[arg(long, value_enum, default_value = "hmax")]
    pub heuristic: HeuristicChoice,
    /// Output format.
    #[arg(long, value_enum, default_value = "ipc")]
    pub format: PlanFormat,
    /// Validate this plan (IPC format) instead of planning.
    #[arg(long, value_name = "PLAN")]
    pub validate: Option<PathBuf>,
    /// Give up after storing this many states.
    #[arg(long, default_value_t = mcl_plan::search::DEFAULT_MAX_STATES)]
    pub max_states: u64,
    /// Print grounding and search statistics on standard error.
    #[arg(long)]
    pub stats: bool,
    /// Execute the plan: run each step's MCL mission on the player, watch the world through
    /// perceptions (world.xml beside FILE.mcl), re-plan when it differs (needs --mock, --sim, --aac or --ros2).
    #[arg(long)]
    pub run: bool,
    /// How to execute it (with `--run`).
    #[command(flatten)]
    pub execute: Execute,
}

/// Options of `mcl plan FILE.mcl --run`.
#[derive(Debug, clap::Args)]
pub struct Execute {
    /// With --run: against the in-process mock vehicle (a dry run).
    #[arg(long, requires = "run")]
    pub mock: bool,
    /// With --run: against the vehicle's AAC listening at HOST:PORT, in real time (e.g.
    /// `mcl mock-aac --plan FILE.mcl`).
    #[arg(long, value_name = "HOST:PORT", requires = "run", conflicts_with = "mock")]
    pub aac: Option<String>,
    /// With --run: against a ROS 2 vehicle whose primitives this bridge file maps to topics,
    /// services and actions, in real time (docs/ros2.md).
    #[arg(long, value_name = "BRIDGE.toml", requires = "run", conflicts_with_all = ["mock", "aac"])]
    pub ros2: Option<PathBuf>,
    /// With --run: against a simulated vehicle in a simulated world, in virtual time
    /// (docs/simulator.md); its perceptions go to the world modeler.
    #[arg(long, requires = "run", conflicts_with_all = ["mock", "aac", "ros2"])]
    pub sim: bool,
    /// With --sim: the simulated world (TOML; --world is the fact-provider scripts).
    #[arg(long, value_name = "W.toml", requires = "sim")]
    pub sim_world: Option<PathBuf>,
    /// With --sim: how the vehicle's primitives are simulated (TOML; default: the bundled model).
    #[arg(long, value_name = "M.toml", requires = "sim")]
    pub vehicle_model: Option<PathBuf>,
    /// With --sim: draw the vehicle's path (plan view and depth profile) as SVG here.
    #[arg(long, value_name = "OUT.svg", requires = "sim")]
    pub trajectory: Option<PathBuf>,
    /// With --aac: shared secret for the AAC.
    #[arg(long, requires = "aac")]
    pub token: Option<String>,
    /// With --run: how the mock vehicle answers and which perceptions it sends (TOML, docs/scenarios.md).
    #[arg(long, value_name = "S.toml", requires = "run")]
    pub scenario: Option<PathBuf>,
    /// With --run: fact-provider scripts (default: world.xml beside FILE.mcl).
    #[arg(long, value_name = "W.xml", requires = "run")]
    pub world: Option<PathBuf>,
    /// With --run: virtual time (instantaneous and deterministic).
    #[arg(long, requires = "run")]
    pub virtual_time: bool,
    /// With --run: mission time runs FACTOR times faster than real time.
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0, requires = "run")]
    pub speed: f64,
    /// With --run: write the trace (JSON lines: player records, plans, re-plans, steps, facts).
    #[arg(long, value_name = "T.jsonl", requires = "run")]
    pub trace: Option<PathBuf>,
    /// With --run: seed of the players and of the mock vehicle (default: the scenario's, else 0).
    #[arg(long, requires = "run")]
    pub seed: Option<u64>,
    /// With --run: mission of FILE.mcl (without parameters) the vehicle runs while re-planning.
    #[arg(long, value_name = "MISSION", requires = "run")]
    pub holding: Option<String>,
    /// With --run: stop (exit status 3) when mission time passes SECONDS.
    #[arg(long, value_name = "SECONDS", requires = "run")]
    pub time_limit: Option<f64>,
    /// With --run: give up after this many plans.
    #[arg(long, value_name = "N", default_value_t = 100, requires = "run")]
    pub max_plans: u32,
    /// With --run: no live log.
    #[arg(short, long)]
    pub quiet: bool,
}

fn print_errors(errors: &[mcl_plan::Error]) {
    for e in errors {
        eprintln!("error: {e}");
    }
}

/// Type-checks the .mcl program (the file and its imports) with the compiler.
fn check_mcl(path: &Path) -> Result<(), String> {
    let db = Database::new();
    let root = super::source_file(&db, path)?;
    let std = db.stdlib();
    let mut diags: Vec<FileDiagnostic> = Vec::new();
    for &f in program(&db, root).files.iter() {
        if f != std {
            diags.extend(check_file(&db, f).iter().filter(|d| d.diag.severity == Severity::Error).cloned());
        }
    }
    if diags.is_empty() {
        Ok(())
    } else {
        Err(render_human(&db, &diags, false))
    }
}

pub fn run(o: Options) -> u8 {
    // Which files: FILE.mcl names the operators; domain.pddl and problem.pddl sit beside it.
    let mut operators = o.operators.clone();
    if let Some(f) = &o.file {
        if f.extension().is_some_and(|x| x == "mcl") {
            if operators.is_some() {
                eprintln!("error: give the operators either as FILE.mcl or with --operators, not both");
                return 2;
            }
            operators = Some(f.clone());
        } else {
            eprintln!("error: `{}` is not an .mcl file: give PDDL files with --domain and --problem", f.display());
            return 2;
        }
    }
    // The .mcl program: its compiler diagnostics first, then its planning
    // blocks (`planning { ... }`: the problem is written in MCL) and its
    // mappings of PDDL actions (`pddl_map { ... }`).
    let mut prog = None;
    if let Some(ops_path) = &operators {
        if let Err(report) = check_mcl(ops_path) {
            eprint!("{report}");
            eprintln!("error: the mission operators in `{}` have errors", ops_path.display());
            return 2;
        }
        match mcl_plan::model::McProgram::load(ops_path) {
            Ok(p) => prog = Some(p),
            Err(e) => {
                print_errors(&e);
                return 2;
            }
        }
    }
    // The MCL planning model, unless PDDL files are given explicitly.
    let from_mcl = o.domain.is_none() && o.problem.is_none() && prog.as_ref().is_some_and(|p| p.has_planning());
    let loaded = if from_mcl {
        mcl_plan::model::to_model(prog.as_ref().expect("from_mcl implies a program"))
    } else {
        let beside = |name: &str| operators.as_ref().map(|m| m.parent().unwrap_or(Path::new(".")).join(name));
        let Some(domain_path) = o.domain.clone().or_else(|| beside("domain.pddl")) else {
            eprintln!("error: no domain: give --domain D.pddl (or FILE.mcl with domain.pddl beside it, or a `planning` block in FILE.mcl)");
            return 2;
        };
        let Some(problem_path) = o.problem.clone().or_else(|| beside("problem.pddl")) else {
            eprintln!("error: no problem: give --problem P.pddl (or FILE.mcl with problem.pddl beside it, or a `planning` block in FILE.mcl)");
            return 2;
        };
        mcl_plan::load(&domain_path, &problem_path).and_then(|(mut d, p)| {
            if let Some(prog) = &prog {
                mcl_plan::model::apply_pddl_map(prog, &mut d)?;
            }
            Ok((d, p))
        })
    };
    let mut run_ops: Option<PathBuf> = None;
    let (domain, problem) = match loaded {
        Ok(x) => x,
        Err(e) => {
            print_errors(&e);
            return 2;
        }
    };
    if let Some(ops_path) = &operators {
        let ops = match mcl_plan::mcl::load_operators(ops_path) {
            Ok(ops) => ops,
            Err(errs) => {
                for e in errs {
                    eprintln!("error: {e}");
                }
                return 2;
            }
        };
        let (errors, warnings) = mcl_plan::mcl::check_mapping(&domain, &ops);
        for w in warnings {
            eprintln!("warning: {w}");
        }
        if !errors.is_empty() {
            print_errors(&errors);
            return 2;
        }
        // A run plays the missions of one file: the one that defines the
        // mission operators (FILE.mcl itself, or the file it imports them from).
        let mut files: Vec<&Path> = Vec::new();
        for a in &domain.actions {
            if let Some(f) =
                a.mcl.as_ref().and_then(|m| ops.iter().find(|o| o.name == m.name)).map(|o| o.file.as_path())
            {
                if !files.contains(&f) {
                    files.push(f);
                }
            }
        }
        match files[..] {
            [] => {}
            [f] => run_ops = Some(f.to_path_buf()),
            _ if o.run => {
                let list: Vec<String> = files.iter().map(|f| format!("`{}`", f.display())).collect();
                eprintln!(
                    "error: --run plays the mission operators of one file, but they are defined in {}: move them into one file",
                    list.join(" and ")
                );
                return 2;
            }
            _ => {}
        }
    }
    if let Some(x) = o.run.then_some(o.execute) {
        if o.validate.is_some() {
            eprintln!("error: give either --run or --validate");
            return 2;
        }
        let Some(ops) = operators else {
            eprintln!("error: --run needs the mission operators: give FILE.mcl (or --operators FILE.mcl)");
            return 2;
        };
        let run_ops = run_ops.unwrap_or_else(|| ops.clone());
        return execute(domain, problem, &ops, &run_ops, algorithm(o.search, o.heuristic), o.max_states, x);
    }
    if let Some(plan_path) = &o.validate {
        let text = match mcl_net::input::read_source(plan_path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        };
        return match mcl_plan::validate(&domain, &problem, &text) {
            Ok(cost) => {
                println!("valid plan; cost = {cost} ({})", if problem.metric { "general cost" } else { "unit cost" });
                0
            }
            Err(e) => {
                println!("invalid plan: {e}");
                1
            }
        };
    }
    let alg = algorithm(o.search, o.heuristic);
    let sol = match mcl_plan::solve(&domain, &problem, alg, o.max_states) {
        Ok(s) => s,
        Err(e) => {
            print_errors(&e);
            return 2;
        }
    };
    if o.stats {
        eprintln!(
            "grounded {} actions over {} facts in {:.3} ms; search: {} states, {} expanded, {} generated, {} evaluated, {} dead ends in {:.3} ms",
            sol.actions,
            sol.facts,
            sol.ground_time.as_secs_f64() * 1e3,
            sol.stats.states,
            sol.stats.expanded,
            sol.stats.generated,
            sol.stats.evaluated,
            sol.stats.dead_ends,
            sol.search_time.as_secs_f64() * 1e3
        );
    }
    let mut out = std::io::stdout().lock();
    match sol.outcome {
        Outcome::Plan(plan) => {
            let text = match o.format {
                PlanFormat::Ipc => plan.to_ipc(),
                PlanFormat::Steps => plan.to_steps_text(),
                PlanFormat::Json => {
                    let mut v = serde_json::to_value(&plan).unwrap_or_default();
                    if let Some(steps) = v.get_mut("steps").and_then(|s| s.as_array_mut()) {
                        for (st, p) in steps.iter_mut().zip(&plan.steps) {
                            st["call"] = p
                                .mcl
                                .as_ref()
                                .map(|m| serde_json::Value::String(m.to_string()))
                                .unwrap_or(serde_json::Value::Null);
                        }
                    }
                    v["stats"] = serde_json::to_value(sol.stats).unwrap_or_default();
                    format!("{}\n", serde_json::to_string_pretty(&v).unwrap_or_default())
                }
            };
            if out.write_all(text.as_bytes()).is_err() {
                return 2;
            }
            0
        }
        Outcome::Unsolvable => {
            eprintln!("no plan: the goal cannot be reached from the initial state");
            if o.format == PlanFormat::Ipc {
                let _ = writeln!(out, "; no solution");
            }
            1
        }
        Outcome::LimitReached => {
            eprintln!("no plan found within {} states (--max-states)", o.max_states);
            3
        }
    }
}

fn algorithm(search: SearchChoice, heuristic: HeuristicChoice) -> Algorithm {
    match (search, heuristic) {
        (SearchChoice::Bfs, _) => Algorithm::Bfs,
        (SearchChoice::Ucs, _) => Algorithm::Ucs,
        (SearchChoice::Astar, HeuristicChoice::Hadd) => Algorithm::Astar(Heuristic::Add),
        (SearchChoice::Astar, HeuristicChoice::Hmax) => Algorithm::Astar(Heuristic::Max),
        (SearchChoice::Gbfs, HeuristicChoice::Hadd) => Algorithm::Greedy(Heuristic::Add),
        (SearchChoice::Gbfs, HeuristicChoice::Hmax) => Algorithm::Greedy(Heuristic::Max),
    }
}

/// Trace file and live log of `--run`.
struct RunSink {
    trace: Option<mcl_runtime::trace::TraceWriter>,
    live: bool,
    error: Option<String>,
    /// Feeds the ROS 2 node's status topic (`--ros2`).
    ros2_status: Option<mcl_ros2::status::Feed>,
}

impl mcl_plan::run::RecordSink for RunSink {
    fn record(&mut self, record: serde_json::Value, live: Option<String>) {
        if let Some(w) = &mut self.trace {
            if let Err(e) = w.write_json(&record) {
                self.error.get_or_insert(format!("cannot write the trace: {e}"));
            }
        }
        if let (true, Some(line)) = (self.live, live) {
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }
    }

    fn record_typed(&mut self, record: &mcl_runtime::trace::Record, live: Option<String>) {
        if let Some(f) = &self.ros2_status {
            f.record(record);
        }
        if let Some(w) = &mut self.trace {
            if let Err(e) = w.write(record) {
                self.error.get_or_insert(format!("cannot write the trace: {e}"));
            }
        }
        if let (true, Some(line)) = (self.live, live) {
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }
    }
}

/// The run's side of the TCP link to a vehicle's AAC ([`mcl_runtime::tcp`]),
/// driven from the run's thread on a current-thread runtime.
struct TcpAac {
    rt: tokio::runtime::Runtime,
    link: Option<mcl_runtime::link::Link>,
    handle: Option<tokio::task::JoinHandle<Result<mcl_runtime::tcp::LinkStats, mcl_runtime::tcp::LinkError>>>,
    addr: String,
}

impl TcpAac {
    /// Why the link closed: the link task's error, if it said.
    fn closed(&mut self) -> String {
        let why = match self.handle.take() {
            Some(h) => match self.rt.block_on(h) {
                Ok(Err(e)) => e.to_string(),
                Ok(Ok(_)) => "the link closed".into(),
                Err(e) => format!("the link task failed: {e}"),
            },
            None => "the link closed".into(),
        };
        format!("AAC at `{}`: {why}", self.addr)
    }

    /// Lets the last actions be acknowledged (up to the link's linger time), then closes.
    fn close(mut self) {
        if let Some(mcl_runtime::link::Link { actions, inbound }) = self.link.take() {
            drop(actions);
            if let Some(h) = self.handle.take() {
                match self.rt.block_on(h) {
                    Ok(Err(e)) => eprintln!("warning: AAC at `{}`: {e}", self.addr),
                    Err(e) => eprintln!("warning: the link task failed: {e}"),
                    Ok(Ok(_)) => {}
                }
            }
            drop(inbound);
        }
    }
}

impl mcl_plan::run::AacLink for TcpAac {
    fn send(&mut self, action: mcl_runtime::link::Action) -> Result<(), String> {
        let sent = self.link.as_ref().is_some_and(|l| l.actions.send(action).is_ok());
        if sent {
            Ok(())
        } else {
            Err(self.closed())
        }
    }

    fn recv(&mut self, timeout: Option<std::time::Duration>) -> Result<Option<mcl_runtime::link::Inbound>, String> {
        let Some(link) = self.link.as_mut() else { return Err(self.closed()) };
        match recv_on(&self.rt, link, timeout) {
            Some(got) => Ok(got),
            None => Err(self.closed()),
        }
    }
}

/// The next message from the vehicle's end of `link`, waited for on `rt` at
/// most `timeout` (none: as long as it takes): `Some(None)` when the time
/// passed, `None` when that end has closed.
pub(crate) fn recv_on(
    rt: &tokio::runtime::Runtime,
    link: &mut mcl_runtime::link::Link,
    timeout: Option<std::time::Duration>,
) -> Option<Option<mcl_runtime::link::Inbound>> {
    let got = rt.block_on(async {
        match timeout {
            Some(d) => tokio::time::timeout(d, link.inbound.recv()).await.ok(),
            None => Some(link.inbound.recv().await),
        }
    });
    match got {
        None => Some(None),
        Some(Some(m)) => Some(Some(m)),
        Some(None) => None,
    }
}

/// Connects to the AAC at `addr` and waits for its `welcome` (up to `wait`).
fn connect_aac(
    addr: &str,
    token: Option<String>,
    mission: String,
    wait: std::time::Duration,
) -> Result<TcpAac, String> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the runtime: {e}"))?;
    let opts = mcl_runtime::tcp::ConnectOptions { token, mission, ..Default::default() };
    let (link, handle) = rt.block_on(async { mcl_runtime::tcp::connect_with_handle(addr, opts) });
    let mut aac = TcpAac { rt, link: Some(link), handle: Some(handle), addr: addr.to_string() };
    let deadline = std::time::Instant::now() + wait;
    loop {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        match mcl_plan::run::AacLink::recv(&mut aac, Some(left))? {
            Some(mcl_runtime::link::Inbound::Connected) => return Ok(aac),
            Some(_) => {}
            None => {
                return Err(format!(
                    "cannot reach the AAC at `{addr}` within {} s (is it running? e.g. `mcl mock-aac --plan FILE.mcl --listen {addr}`)",
                    wait.as_secs_f64()
                ))
            }
        }
    }
}

/// How long `--run --aac` waits for the AAC's `welcome` before giving up.
const AAC_CONNECT_WAIT: std::time::Duration = std::time::Duration::from_secs(10);

/// `mcl plan FILE.mcl --run --mock|--sim|--aac|--ros2`: plans, executes each
/// step's MCL mission on the player against the mock vehicle, a simulated
/// one, a vehicle's AAC or a ROS 2 vehicle through the bridge, and
/// re-plans on divergence.
fn execute(
    domain: mcl_plan::Domain,
    problem: mcl_plan::Problem,
    file: &Path,
    ops: &Path,
    alg: Algorithm,
    max_states: u64,
    x: Execute,
) -> u8 {
    use mcl_plan::executor::Executor;
    use mcl_runtime::scenario::Scenario;
    crate::interrupt::install();
    if [x.mock, x.sim, x.aac.is_some(), x.ros2.is_some()].iter().filter(|b| **b).count() != 1 {
        eprintln!("error: --run needs --mock (the in-process mock vehicle), --sim (a simulated vehicle), --aac HOST:PORT (a vehicle's AAC) or --ros2 BRIDGE.toml (a ROS 2 vehicle)");
        return 2;
    }
    if x.ros2.is_some() && (x.virtual_time || x.scenario.is_some()) {
        eprintln!(
            "error: --ros2 runs in real time against the ROS 2 vehicle: --virtual-time and --scenario go with --mock"
        );
        return 2;
    }
    // The ROS 2 bridge, checked against the operators' vehicle before anything runs.
    let ros2_engine = match x.ros2.as_deref().map(|b| super::ros2::engine_for(b, &[file])).transpose() {
        Ok(e) => e,
        Err(code) => return code,
    };
    if x.sim && !x.virtual_time {
        eprintln!("error: --sim runs in virtual time only for now: add --virtual-time");
        return 2;
    }
    if x.aac.is_some() && x.virtual_time {
        eprintln!("error: --virtual-time needs --mock (a vehicle's AAC runs in real time)");
        return 2;
    }
    if x.aac.is_some() && x.scenario.is_some() {
        eprintln!("error: --scenario configures the in-process mock; use it with --mock (give it to `mcl mock-aac --plan` otherwise)");
        return 2;
    }
    if !(x.speed.is_finite() && x.speed > 0.0) {
        eprintln!("error: --speed must be a positive number");
        return 2;
    }
    if x.time_limit.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
        eprintln!("error: --time-limit must be a number of seconds ≥ 0");
        return 2;
    }
    let world_path = x.world.clone().unwrap_or_else(|| file.parent().unwrap_or(Path::new(".")).join("world.xml"));
    let xml = match mcl_net::input::read_source(&world_path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: the fact-provider scripts: {e} (give --world W.xml)");
            return 2;
        }
    };
    let scripts = match mcl_plan::world::parse_scripts(&world_path.display().to_string(), &xml) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let world = match mcl_plan::world::WorldModeler::new(scripts, &domain, &problem) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {}: {e}", world_path.display());
            return 2;
        }
    };
    let scenario = match &x.scenario {
        Some(p) => match Scenario::load(p) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        },
        None => Scenario::default(),
    };
    let seed = x.seed.or(scenario.seed).unwrap_or(0);
    let sim =
        match x.sim.then(|| super::sim::load_files(x.vehicle_model.as_deref(), x.sim_world.as_deref())).transpose() {
            Ok(s) => s,
            Err(code) => return code,
        };
    let mut ex = match Executor::new(domain, problem, alg) {
        Ok(ex) => ex,
        Err(e) => {
            eprintln!("no plan: {e}");
            return 1;
        }
    };
    ex.max_states = max_states;
    // The same traces as `mcl run`: whole lines, flushed on SIGINT/SIGTERM.
    let trace = match super::run::open_trace(&x.trace) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let mut sink = RunSink { trace, live: !x.quiet, error: None, ros2_status: None };
    let opts = mcl_plan::run::RunOptions {
        seed,
        virtual_time: x.virtual_time,
        speed: x.speed,
        time_limit: x.time_limit,
        holding: x.holding.clone(),
        max_plans: x.max_plans.max(1),
    };
    let stem = file.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
    let report = match &x.aac {
        None if ros2_engine.is_some() => {
            let (feed, listener) = mcl_ros2::status::channel(&format!("plan:{stem}"));
            sink.ros2_status = Some(feed);
            let mut node = match super::ros2::NodeLink::start(ros2_engine, listener) {
                Ok(n) => n,
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            };
            let r = mcl_plan::run::run_planned_aac(ex, world, ops, &mut node, opts, &mut sink);
            node.close();
            r
        }
        None => match &sim {
            Some(s) => run_sim(s, ex, world, ops, scenario, opts, &mut sink, x.trajectory.as_deref(), file),
            None => mcl_plan::run::run_planned(ex, world, ops, scenario, opts, &mut sink),
        },
        Some(addr) => {
            let mut aac = match connect_aac(addr, x.token.clone(), format!("plan:{stem}"), AAC_CONNECT_WAIT) {
                Ok(a) => a,
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            };
            let r = mcl_plan::run::run_planned_aac(ex, world, ops, &mut aac, opts, &mut sink);
            aac.close();
            r
        }
    };
    if let Some(w) = &mut sink.trace {
        if let Err(e) = w.flush() {
            sink.error.get_or_insert(format!("cannot write the trace: {e}"));
        }
    }
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    if let Some(e) = sink.error {
        eprintln!("error: {e}");
        return 2;
    }
    eprintln!(
        "planned mission: {} at t={:.3} s ({} plan(s), {} step(s)){}",
        report.result.to_uppercase(),
        report.t,
        report.plans,
        report.steps,
        report.reason.as_ref().map(|r| format!(": {r}")).unwrap_or_default()
    );
    report.exit_code()
}

/// `--run --sim`: the plan's steps played against a simulated vehicle of
/// `setup` (`mcl_plan::run::run_planned_on`), whose perceptions (cable in
/// sight, position, navigation quality...) go to the world modeler; the
/// path drawn to `trajectory` at the end.
#[allow(clippy::too_many_arguments)]
fn run_sim(
    setup: &super::sim::Setup,
    ex: mcl_plan::executor::Executor,
    world: mcl_plan::world::WorldModeler,
    ops: &Path,
    scenario: mcl_runtime::scenario::Scenario,
    opts: mcl_plan::run::RunOptions,
    sink: &mut RunSink,
    trajectory: Option<&Path>,
    file: &Path,
) -> Result<mcl_plan::run::Report, String> {
    let missions = mcl_plan::run::Missions::load(ops)?;
    let vehicle = mcl_sim::SharedSim::new(setup.vehicle(scenario));
    let report = mcl_plan::run::run_planned_on(ex, world, missions, Box::new(vehicle.clone()), opts, sink)?;
    if let Some(p) = trajectory {
        let title =
            format!("{} — planned mission, {} at t={:.1} s", file.display(), report.result.to_uppercase(), report.t);
        let v = vehicle.lock();
        let svg = mcl_sim::trajectory::svg(v.track(), v.world(), &title);
        std::fs::write(p, svg).map_err(|e| format!("cannot write `{}`: {e}", p.display()))?;
    }
    Ok(report)
}
