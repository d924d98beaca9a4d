//! Explores PNML nets with decision diagrams and prints one line per net:
//! states, edges, dead markings, diagram size and the wall time.
//!
//! ```text
//! cargo run --release -p mcl-net --example symbolic -- [--order force|pnml] [--no-group] [--runs N] NET.pnml...
//! ```
//!
//! With `--runs N` each net is explored N times and the best time is kept;
//! `--no-group` puts every place on its own level.

use std::process::ExitCode;
use std::time::Instant;

use mcl_net::explore::symbolic::VariableOrder;
use mcl_net::explore::{explore_symbolic, SymbolicOptions};
use mcl_net::read_pnml;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let mut opts = SymbolicOptions::default();
    let mut runs = 1usize;
    let mut paths = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--order" => match args.next().as_deref() {
                Some("force") => opts.order = VariableOrder::Force,
                Some("pnml") => opts.order = VariableOrder::Pnml,
                _ => {
                    eprintln!("--order needs force or pnml");
                    return ExitCode::from(2);
                }
            },
            "--no-group" => opts.group = false,
            "--runs" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) => runs = n,
                None => {
                    eprintln!("--runs needs a number");
                    return ExitCode::from(2);
                }
            },
            _ => paths.push(a),
        }
    }
    if paths.is_empty() {
        eprintln!("usage: symbolic [--order force|pnml] [--no-group] [--runs N] NET.pnml...");
        return ExitCode::from(2);
    }
    println!(
        "{:<28} {:>12} {:>12} {:>6} {:>6} {:>9} {:>9} {:>10}",
        "net", "states", "edges", "dead", "levels", "mdd", "created", "seconds"
    );
    for path in paths {
        let net = match std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|t| read_pnml(&t).map_err(|e| e.to_string()))
        {
            Ok(n) => n,
            Err(e) => {
                eprintln!("{path}: {e}");
                return ExitCode::FAILURE;
            }
        };
        let mut best = f64::INFINITY;
        let mut report = None;
        for _ in 0..runs.max(1) {
            let start = Instant::now();
            let r = explore_symbolic(&net, &opts);
            best = best.min(start.elapsed().as_secs_f64());
            report = Some(r);
        }
        let Some(r) = report else { continue };
        let show = |c: Option<u128>| c.map_or("-".into(), |c| c.to_string());
        let name = std::path::Path::new(&path).file_stem().map_or(path.clone(), |s| s.to_string_lossy().into_owned());
        if let Some(stop) = &r.stop {
            println!("{name:<28} incomplete: {stop:?} ({} levels)", r.levels);
            continue;
        }
        println!(
            "{name:<28} {:>12} {:>12} {:>6} {:>6} {:>9} {:>9} {:>10.4}",
            show(r.states),
            show(r.edges),
            show(r.dead_markings),
            r.levels,
            r.mdd_nodes,
            r.nodes_created,
            best
        );
    }
    ExitCode::SUCCESS
}
