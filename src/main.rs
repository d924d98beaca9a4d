//! `mcl`: the MCL toolchain's command-line interface. It only wires crates
//! together; every capability lives in a library crate.

mod cmd;

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
    /// Exit status: 0 without errors (warnings allowed), 1 with errors, 2 on a usage or I/O error.
    Check {
        /// Files or folders to check.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Output format: human-readable reports or one JSON array.
        #[arg(long, value_enum, default_value = "human")]
        format: Format,
        /// Color the human output.
        #[arg(long, value_enum, default_value = "auto")]
        color: ColorChoice,
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
        /// Also write a Graphviz drawing (with --out-dir: one `<mission>.dot` per mission).
        #[arg(long, num_args = 0..=1, default_missing_value = "")]
        dot: Option<PathBuf>,
        /// Write one `<mission>.pnml` per mission into this folder.
        #[arg(long)]
        out_dir: Option<PathBuf>,
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
        /// Worker threads (0: one per core).
        #[arg(long, default_value_t = 1)]
        threads: usize,
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
        Command::Check { paths, format, color } => cmd::check::run(&paths, format, color),
        Command::Explain { code } => cmd::explain::run(code.as_deref()),
        Command::Analyze { net, format, max_states, semantics, threads } => {
            cmd::analyze::run(&net, format, max_states, semantics, threads)
        }
        Command::Compile { file, output, dot, out_dir } => {
            if dot.as_ref().is_some_and(|d| d.as_os_str().is_empty()) && out_dir.is_none() {
                eprintln!("error: --dot needs a path unless --out-dir is given");
                return ExitCode::from(2);
            }
            cmd::compile::run(cmd::compile::Options {
                file: &file,
                output: output.as_deref(),
                dot: dot.as_deref(),
                out_dir: out_dir.as_deref(),
            })
        }
    };
    ExitCode::from(code)
}
