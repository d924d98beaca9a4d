//! Writes a PNML P/T net as a Promela model for SPIN.
//!
//! ```text
//! cargo run --release -p mcl-net --example to_promela -- NET.pnml > net.pml
//! ```
//!
//! One global variable per place (`byte` when every initial marking and arc
//! weight is below 256, `int` otherwise) and, in one process, one
//! `atomic { guard -> updates }` per transition inside a `do` loop, so that
//! SPIN's state space is the net's reachability graph (one stored state per
//! marking). `byte` variables wrap above 255: use the `int` switch
//! (`--int`) for nets whose places may exceed that.

use std::fmt::Write as _;
use std::process::ExitCode;

use mcl_net::{read_pnml, Net};

/// The Promela text of `net`.
fn promela(net: &Net, wide: bool) -> String {
    let mut out = String::new();
    let ty = if wide { "int" } else { "byte" };
    let _ = writeln!(out, "/* {} : {} places, {} transitions */", net.id(), net.place_count(), net.transition_count());
    for (i, p) in net.places().iter().enumerate() {
        let _ = writeln!(out, "{ty} p{i} = {}; /* {} */", p.initial, p.id.replace("*/", "* /"));
    }
    let _ = writeln!(out, "\nactive proctype net() {{\n  do");
    for t in net.transition_ids() {
        let pre = net.pre(t);
        let guard = if pre.is_empty() {
            "true".to_string()
        } else {
            pre.iter().map(|&(p, w)| format!("p{} >= {w}", p.0)).collect::<Vec<_>>().join(" && ")
        };
        let updates: Vec<String> = net
            .delta(t)
            .iter()
            .map(
                |&(p, d)| {
                    if d > 0 {
                        format!("p{0} = p{0} + {d}", p.0)
                    } else {
                        format!("p{0} = p{0} - {1}", p.0, -d)
                    }
                },
            )
            .collect();
        let body = if updates.is_empty() { "skip".to_string() } else { updates.join("; ") };
        let name = net.transition(t).map_or("", |tr| tr.id.as_str()).replace("*/", "* /");
        let _ = writeln!(out, "  :: atomic {{ ({guard}) -> {body} }} /* {name} */");
    }
    let _ = writeln!(out, "  od\n}}");
    out
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let wide = args.iter().any(|a| a == "--int");
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: to_promela NET.pnml [--int] > NET.pml");
        return ExitCode::from(2);
    };
    let net = match std::fs::read_to_string(path)
        .map_err(|e| e.to_string())
        .and_then(|t| read_pnml(&t).map_err(|e| e.to_string()))
    {
        Ok(n) => n,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let small = net.places().iter().all(|p| p.initial < 256)
        && net.transition_ids().all(|t| net.pre(t).iter().chain(net.post(t)).all(|&(_, w)| w < 256));
    print!("{}", promela(&net, wide || !small));
    ExitCode::SUCCESS
}
