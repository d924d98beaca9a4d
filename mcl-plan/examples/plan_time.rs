//! Times planning in-process (parse + ground + search, no process start-up)
//! for the benchmark script: prints one JSON line.
//!
//! `cargo run --release -p mcl-plan --example plan_time -- DOMAIN PROBLEM bfs|ucs|astar-hadd|astar-hmax|gbfs-hadd [REPEAT]`

use mcl_plan::{Algorithm, Heuristic, Outcome};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() < 3 {
        eprintln!("usage: plan_time DOMAIN PROBLEM bfs|ucs|astar-hadd|astar-hmax|gbfs-hadd [REPEAT]");
        std::process::exit(2);
    }
    let alg = match a[2].as_str() {
        "bfs" => Algorithm::Bfs,
        "ucs" => Algorithm::Ucs,
        "astar-hadd" => Algorithm::Astar(Heuristic::Add),
        "astar-hmax" => Algorithm::Astar(Heuristic::Max),
        "gbfs-hadd" => Algorithm::Greedy(Heuristic::Add),
        other => {
            eprintln!("unknown search {other}");
            std::process::exit(2);
        }
    };
    let repeat: usize = a.get(3).and_then(|r| r.parse().ok()).unwrap_or(1).max(1);
    let mut best = f64::INFINITY;
    let mut line = String::new();
    for _ in 0..repeat {
        let t = Instant::now();
        let dt = std::fs::read_to_string(&a[0]).expect("domain");
        let pt = std::fs::read_to_string(&a[1]).expect("problem");
        let d = mcl_plan::parse_domain(&a[0], &dt).expect("domain parses");
        let p = mcl_plan::parse_problem(&a[1], &pt).expect("problem parses");
        let s = mcl_plan::solve(&d, &p, alg, mcl_plan::search::DEFAULT_MAX_STATES).expect("grounds");
        let secs = t.elapsed().as_secs_f64();
        let cost = match &s.outcome {
            Outcome::Plan(p) => p.cost as i64,
            _ => -1,
        };
        if secs < best {
            best = secs;
            line = format!(
                "{{\"seconds\": {secs:.6}, \"cost\": {cost}, \"expanded\": {}, \"states\": {}, \"actions\": {}, \"facts\": {}, \"ground_s\": {:.6}, \"search_s\": {:.6}}}",
                s.stats.expanded,
                s.stats.states,
                s.actions,
                s.facts,
                s.ground_time.as_secs_f64(),
                s.search_time.as_secs_f64()
            );
        }
    }
    println!("{line}");
}
