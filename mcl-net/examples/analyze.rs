//! Explores a PNML net and prints the analysis report as JSON.
//!
//! ```text
//! cargo run --release -p mcl-net --example analyze -- NET.pnml [--plain] [--max-states N]
//!     [--dead-examples N] [--threads N] [--unordered]
//! ```
//!
//! `--unordered` explores on several threads without levels
//! ([`mcl_net::Options::exact_order`] false).
//!
//! Besides the report, the JSON has `seconds` (wall time of the exploration)
//! and `states_per_second`.

use std::process::ExitCode;
use std::time::Instant;

use mcl_net::{analyze, read_pnml, Options, Semantics};

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let mut path = None;
    let mut opts = Options::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--plain" => opts.semantics = Semantics::Plain,
            "--mcl" => opts.semantics = Semantics::Mcl,
            "--unordered" => opts.exact_order = false,
            "--max-states" | "--dead-examples" | "--threads" => {
                let Some(n) = args.next().and_then(|v| v.parse::<usize>().ok()) else {
                    eprintln!("{a} needs a number");
                    return ExitCode::from(2);
                };
                match a.as_str() {
                    "--max-states" => opts.max_states = n,
                    "--threads" => opts.threads = n,
                    _ => opts.max_dead_examples = n,
                }
            }
            _ if path.is_none() => path = Some(a),
            _ => {
                eprintln!("unexpected argument `{a}`");
                return ExitCode::from(2);
            }
        }
    }
    let Some(path) = path else {
        eprintln!(
            "usage: analyze NET.pnml [--plain|--mcl] [--max-states N] [--dead-examples N] [--threads N] [--unordered]"
        );
        return ExitCode::from(2);
    };
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let net = match read_pnml(&text) {
        Ok(n) => n,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let start = Instant::now();
    let report = analyze(&net, &opts);
    let seconds = start.elapsed().as_secs_f64();
    let mut json = match serde_json::to_value(&report) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("cannot serialize report: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(obj) = json.as_object_mut() {
        obj.insert("seconds".into(), seconds.into());
        obj.insert("states_per_second".into(), (report.states as f64 / seconds).into());
    }
    println!("{}", serde_json::to_string_pretty(&json).unwrap_or_default());
    ExitCode::SUCCESS
}
