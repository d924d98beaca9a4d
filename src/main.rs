//! `mcl`: the MCL toolchain's command-line interface. It only wires crates
//! together; every capability lives in a library crate.

mod cmd;
mod interrupt;

use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "mcl", version, about = "Mission Control Language toolchain: check, compile and run AUV missions")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// How diagnostics are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Human,
    Json,
}

/// When to color output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorChoice {
    Auto,
    Always,
    Never,
}

#[derive(Subcommand)]
enum Command {
    /// Check MCL files for errors (files, or folders searched for *.mcl).
    ///
    /// Exit status: 0 without errors (warnings allowed), 1 with errors, 2 on a usage or I/O error
    /// (a file that cannot be read is reported and the others are still checked).
    Check {
        /// Files or folders to check (default: the current folder).
        #[arg(default_value = ".")]
        paths: Vec<PathBuf>,
        /// Output format: human-readable reports or one JSON array.
        #[arg(long, value_enum, default_value = "human")]
        format: Format,
        /// Color the human output.
        #[arg(long, value_enum, default_value = "auto")]
        color: ColorChoice,
        /// For each deadlock that a verifier reports (E0406, and E0601 of a task a mission calls),
        /// write a scenario under which `mcl run --mock --virtual-time FILE --scenario OUT.toml`
        /// replays it and ends stuck there (exit status 3). Each is checked by a dry run first.
        /// One counterexample is written to OUT.toml; several to OUT-1.toml, OUT-2.toml, ...
        /// in the order of the diagnostics (docs/scenarios.md, "Counterexamples").
        #[arg(long, value_name = "OUT.toml")]
        counterexample_scenario: Option<PathBuf>,
        /// Also check this ROS 2 bridge file (docs/ros2.md) against the vehicle the checked
        /// files describe and the message types it uses; its errors have file and line.
        #[arg(long, value_name = "BRIDGE.toml")]
        ros2: Option<PathBuf>,
    },
    /// Compile the missions of a file to Petri nets (PNML 2009), and optionally Graphviz.
    ///
    /// Exit status: 0 on success, 1 when the program has errors, 2 on a usage or I/O error.
    Compile {
        /// The MCL file whose missions to compile.
        file: PathBuf,
        /// Write the PNML here (default: standard output).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Also write a Graphviz drawing to OUT.dot; with --out-dir, give no
        /// path: one `<mission>.dot` per mission is written into the folder.
        #[arg(long, num_args = 0..=1, value_name = "OUT.dot")]
        dot: Option<Option<PathBuf>>,
        /// Write one `<mission>.pnml` per mission into this folder.
        #[arg(long)]
        out_dir: Option<PathBuf>,
        /// What `--dot OUT.dot` draws: `net` (the whole net, clustered), `structure` (the
        /// mission's control structures and calls), or `task:NAME` (one task's net).
        #[arg(long, default_value = "net", value_name = "net|structure|task:NAME")]
        view: cmd::compile::View,
        /// Instead of the nets: per constraint and per mission, the most coordination messages
        /// a run sends and the bytes each takes, compact and as JSON (docs/acoustic.md).
        #[arg(long, conflicts_with_all = ["output", "dot", "out_dir"])]
        link_report: bool,
        /// With --link-report: its format.
        #[arg(long, value_enum, default_value = "human", requires = "link_report")]
        format: Format,
        /// With --link-report: a message that does not fit a frame of N bytes is an error
        /// (E0410) at its constraint.
        #[arg(long, value_name = "N", requires = "link_report")]
        frame_bytes: Option<u64>,
    },
    /// Explore the state space of a PNML net (ours or any other tool's).
    ///
    /// Reports reachable and dead markings, place bounds and 1-safeness.
    Analyze {
        /// A PNML 2009 P/T net.
        net: PathBuf,
        #[arg(long, value_enum, default_value = "human")]
        format: Format,
        /// Stop after this many states and report the net as larger.
        #[arg(long, default_value_t = mcl_net::explore::DEFAULT_MAX_STATES)]
        max_states: usize,
        /// Firing rule.
        #[arg(long, value_enum, default_value = "auto")]
        semantics: cmd::analyze::SemanticsChoice,
        /// Worker threads (0: one per core). Above 1 the workers explore
        /// without levels: the same counts and verdicts, dead markings with
        /// real but not always shortest paths.
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// With --threads: explore level by level instead, so that dead
        /// markings come with shortest paths (slower on many cores).
        #[arg(long)]
        shortest_paths: bool,
        /// Exploration method: every marking, stubborn sets (deadlocks
        /// only), or decision diagrams (exact counts; --max-states then
        /// limits the diagram nodes).
        #[arg(long, value_enum, default_value = "explicit")]
        method: cmd::analyze::Method,
        /// With --method symbolic: the places' order in the diagram.
        #[arg(long, value_enum, default_value = "force")]
        order: cmd::analyze::OrderChoice,
    },
    /// Run a mission: against the in-process mock vehicle (--mock) or a vehicle's AAC over TCP (--aac) or Zenoh (--zenoh).
    ///
    /// FILE is an .mcl file (compiled in memory) or a compiled .pnml. With --mock and no --mission,
    /// a file with several missions runs every vehicle at once, coordinated by its constraints.
    /// Exit status: 0 mission ok (every mission), 1 mission fail, 2 usage, compile or I/O error,
    /// 3 mission stuck, aborted by the operator or time limit passed, 130 after SIGINT and 143
    /// after SIGTERM (the trace flushed first).
    Run(Box<cmd::run::Options>),
    /// Replay trace files in the browser: the monitor's page (docs/monitor.md) with a time slider,
    /// play/pause, and jumps to the next event, failure or coordination message.
    ///
    /// Several traces show a fleet (records without a mission are named after their file). Prints
    /// the page's URL on standard error, then serves until interrupted.
    Monitor {
        /// JSONL traces written by `mcl run --trace`.
        #[arg(required = true)]
        traces: Vec<PathBuf>,
        /// Address to listen on (port 0: any free port).
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:0")]
        listen: String,
    },
    /// Run a Zenoh router for vehicles that meet through one (docs/zenoh.md). Runs until killed.
    ZenohRouter {
        /// Listen on this endpoint, e.g. tcp/127.0.0.1:7447 (repeatable).
        #[arg(long, value_name = "ENDPOINT")]
        listen: Vec<String>,
        /// Connect to this endpoint, e.g. another router (repeatable).
        #[arg(long, value_name = "ENDPOINT")]
        connect: Vec<String>,
        /// Start from this Zenoh configuration file (JSON5).
        #[arg(long, value_name = "FILE")]
        config: Option<PathBuf>,
        /// Be the gateway of this region (repeatable): one south region per name, for the peers
        /// run with `--region NAME`, then one for every other peer and client (docs/zenoh.md).
        #[arg(long, value_name = "NAME")]
        region: Vec<String>,
    },
    /// Draw an SVG chronogram (one row per primitive) of a trace written by `mcl run --trace`.
    Chronogram {
        /// A JSONL trace.
        trace: PathBuf,
        /// The SVG to write.
        #[arg(short, long)]
        output: PathBuf,
        /// Only this mission's records (a trace of several missions).
        #[arg(long)]
        mission: Option<String>,
    },
    /// Convert a trace written by `mcl run --trace` to an MCAP file for Foxglove (docs/mcap.md).
    ///
    /// One channel per kind of record (actions, events, firings, poses, outcomes, coordination
    /// messages...), JSON messages with JSON schemas, logged at their mission time. Exit status: 0
    /// when written, 2 when the trace cannot be read or the file cannot be written.
    TraceToMcap {
        /// A JSONL trace.
        trace: PathBuf,
        /// The MCAP file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Run the mock vehicle as an AAC server speaking the TCP protocol (docs/aac-protocol.md).
    ///
    /// Prints `listening on ADDR` on standard output, then logs every message on standard error.
    /// Runs until killed.
    MockAac {
        /// The missions: an .mcl or .pnml file (the player's hello names the mission).
        #[arg(long, value_name = "FILE", required_unless_present = "plan", conflicts_with = "plan")]
        net: Option<PathBuf>,
        /// Serve the vehicle of a planned mission (`mcl plan FILE.mcl --run --aac`): one mock for the
        /// actions of every mission of the operators file FILE.mcl.
        #[arg(long, value_name = "FILE.mcl")]
        plan: Option<PathBuf>,
        /// How the mock vehicle answers (TOML, see docs/scenarios.md).
        #[arg(long, value_name = "FILE")]
        scenario: Option<PathBuf>,
        /// Address to listen on (port 0: any free port).
        #[arg(long, value_name = "HOST:PORT", default_value = mcl_runtime::protocol::DEFAULT_ADDR)]
        listen: String,
        /// Shared secret: refuse players whose hello lacks it.
        #[arg(long)]
        token: Option<String>,
        /// Mission time runs FACTOR times faster than real time.
        #[arg(long, value_name = "FACTOR", default_value_t = 1.0)]
        speed: f64,
        /// Save executed actions here and restore them at start (survives a restart).
        #[arg(long, value_name = "FILE")]
        state: Option<PathBuf>,
        /// Seed of the mock's random draws (default: the scenario's seed, else 0).
        #[arg(long)]
        seed: Option<u64>,
        /// Seconds of silence after which a player is considered gone.
        #[arg(long, value_name = "SECONDS", default_value_t = 5.0)]
        timeout: f64,
        /// Log connections and executed actions only, not every message.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Plan with the on-board planner: PDDL domain and problem, MCL mission operators (docs/planning.md).
    ///
    /// FILE.mcl names the mission operators, with domain.pddl and problem.pddl beside it unless
    /// --domain/--problem say otherwise. Prints the plan in the IPC format. Exit status: 0 with a
    /// plan (or a valid plan with --validate), 1 when the problem has no solution (or the plan is
    /// invalid), 2 on bad input, 3 when --max-states is reached. With --run --mock, executes the
    /// plan as a dry run against the mock vehicle, with --run --aac HOST:PORT against a vehicle's
    /// AAC in real time, and re-plans when the world differs (exit status 0 goal reached, 1 no
    /// plan, gave up or the AAC link lost, 2 bad input, 3 --time-limit, 130/143 after
    /// SIGINT/SIGTERM with the trace flushed).
    Plan(Box<cmd::plan::Options>),
    /// Run the language server (LSP over standard input and output), for editors.
    Lsp {
        /// Accepted for editors that pass it; standard input and output are the only transport.
        #[arg(long, hide = true)]
        stdio: bool,
    },
    /// Format MCL files in place in the canonical style (files, or folders searched for *.mcl).
    ///
    /// `mcl fmt -` formats standard input to standard output. Exit status: 0 when every file is
    /// formatted, 1 with --check when some file would change (they are listed), 2 on a usage or
    /// I/O error or a file with syntax errors (left alone).
    Fmt {
        /// Files or folders to format, or `-` for standard input.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Change nothing: list the files that are not formatted and exit with status 1 if any.
        #[arg(long)]
        check: bool,
    },
    /// Start a new project in a new folder NAME: a vehicle, a mission, a mock scenario and a README.
    ///
    /// NAME may be a path; its last part is the project's name (a letter, then letters, digits,
    /// `-` and `_`). Exit status: 0 when the project is written, 2 when NAME is not valid, the
    /// folder exists and is not empty, or a file cannot be written.
    New {
        /// The folder to create (it may exist if it is empty).
        name: PathBuf,
    },
    /// The vehicle file as a contract for its AAC: per primitive, the commands the player sends
    /// (parameters in order) and the events the vehicle sends, with their roles (ends the task
    /// ok, ends it in fail, neither) and whether a mission watches it as a monitor's condition.
    ///
    /// Exit status: 0 with the interface on standard output, 1 when the program has errors,
    /// 2 when the file cannot be read.
    Interface {
        /// An .mcl file (a vehicle file, or a mission that imports one).
        file: PathBuf,
        #[arg(long, value_enum, default_value = "markdown")]
        format: cmd::interface::InterfaceFormat,
    },
    /// Explain a diagnostic code, with an example of the error and its fix.
    Explain {
        /// A code such as E0101; without one, lists every code.
        code: Option<String>,
    },
}

fn main() -> ExitCode {
    // Behave like other command-line tools when the reader of our output goes
    // away (`mcl analyze net.pnml | head`): end quietly instead of panicking.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    let code = match cli.command {
        Command::Check { paths, format, color, counterexample_scenario, ros2 } => {
            cmd::check::run(&paths, format, color, counterexample_scenario.as_deref(), ros2.as_deref())
        }
        Command::Explain { code } => cmd::explain::run(code.as_deref()),
        Command::Interface { file, format } => cmd::interface::run(&file, format),
        Command::Fmt { paths, check } => cmd::fmt::run(&paths, check),
        Command::New { name } => cmd::new::run(&name),
        Command::Lsp { stdio: _ } => cmd::lsp::run(),
        Command::Plan(o) => cmd::plan::run(*o),
        Command::Run(o) => cmd::run::run(*o),
        Command::MockAac { net, plan, scenario, listen, token, speed, state, seed, timeout, quiet } => {
            cmd::mock_aac::run(cmd::mock_aac::Options {
                net,
                plan,
                scenario,
                listen,
                token,
                speed,
                state,
                seed,
                timeout,
                quiet,
            })
        }
        Command::Monitor { traces, listen } => cmd::monitor::run(&traces, &listen),
        Command::ZenohRouter { listen, connect, config, region } => {
            cmd::zenoh_router::run(listen, connect, config, region)
        }
        Command::Chronogram { trace, output, mission } => cmd::chronogram::run(&trace, &output, mission.as_deref()),
        Command::TraceToMcap { trace, output } => cmd::trace_to_mcap::run(&trace, &output),
        Command::Analyze { net, format, max_states, semantics, threads, shortest_paths, method, order } => {
            cmd::analyze::run(&net, format, max_states, semantics, threads, shortest_paths, method, order)
        }
        Command::Compile { file, link_report: true, format, frame_bytes, .. } => {
            cmd::link_report::run(&file, format, frame_bytes)
        }
        Command::Compile { file, output, dot, out_dir, view, .. } => {
            let dot = match (dot, &out_dir) {
                (Some(None), None) => {
                    eprintln!("error: --dot needs a path (--dot OUT.dot) unless --out-dir is given");
                    return ExitCode::from(2);
                }
                (Some(Some(p)), Some(_)) => {
                    eprintln!(
                        "error: with --out-dir, --dot takes no path: it writes one `<mission>.dot` per mission into the folder (got `{}`)",
                        p.display()
                    );
                    return ExitCode::from(2);
                }
                (Some(Some(p)), None) => cmd::compile::Dot::File(p),
                (Some(None), Some(_)) => cmd::compile::Dot::PerMission,
                (None, _) => cmd::compile::Dot::No,
            };
            if view != cmd::compile::View::Net && !matches!(dot, cmd::compile::Dot::File(_)) {
                eprintln!("error: --view structure and --view task:NAME draw one picture: give --dot OUT.dot (without --out-dir)");
                return ExitCode::from(2);
            }
            cmd::compile::run(cmd::compile::Options {
                file: &file,
                output: output.as_deref(),
                dot,
                out_dir: out_dir.as_deref(),
                view,
            })
        }
    };
    ExitCode::from(code)
}
