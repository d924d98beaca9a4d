//! Writes a generated fleet (`mcl_coord::gen`) to standard output:
//! `cargo run -p mcl-coord --example fleet -- VEHICLES SEED [deadlock]`.
//! The text imports `vehicle.mcl` (copy `examples/vehicle.mcl` beside it).
//! With `--analyze FILE` instead, analyzes FILE (an .mcl file) and prints
//! the verdict, the sizes and the time (`--full`: without the reduction;
//! `--no-walks`: no random walks first; `--no-structural`: no proof by the
//! state equation first; `--pnml OUT`: also write the centralised supervised
//! net, `Report.net`, to OUT).

use mcl_coord::gen::{fleet, FleetSpec};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "--analyze") {
        let has = |f: &str| args.iter().any(|a| a == f);
        let pnml = args.iter().position(|a| a == "--pnml").and_then(|i| args.get(i + 1)).map(String::as_str);
        analyze(args.get(1).map_or("", String::as_str), has("--full"), has("--no-walks"), has("--no-structural"), pnml);
        return;
    }
    let num = |i: usize, default: u64| args.get(i).and_then(|a| a.parse::<u64>().ok()).unwrap_or(default);
    let spec = FleetSpec {
        vehicles: usize::try_from(num(0, 8)).unwrap_or(8),
        seed: num(1, 1),
        deadlock: args.get(2).is_some_and(|a| a == "deadlock"),
    };
    print!("{}", fleet(&spec).text);
}

fn analyze(path: &str, full: bool, no_walks: bool, no_structural: bool, pnml: Option<&str>) {
    use mcl_compiler::{Database, Db};
    let db = Database::new();
    let (ms, cs) = match mcl_coord::source::load(&db, db.file(std::path::Path::new(path))) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mut opts = mcl_coord::check::options();
    opts.verify.reduction = !full;
    opts.verify.reduction_threshold = 0;
    if no_structural {
        opts.verify.structural_threshold = u64::MAX;
    }
    if no_walks {
        opts.verify.hunt_threshold = u64::MAX;
    }
    let t = std::time::Instant::now();
    match mcl_coord::analyze_with(&ms, &cs, &opts) {
        Ok(r) => {
            println!(
                "{:?} in {:.2} s: classes {:?}, {} product states, {} groups proven by the state equation",
                r.verdict,
                t.elapsed().as_secs_f64(),
                r.stats.vehicle_classes,
                r.stats.product_states,
                r.stats.structural_proofs
            );
            if let Some(out) = pnml {
                let written = mcl_net::write_pnml(&r.net).map_err(|e| e.to_string());
                if let Err(e) = written.and_then(|x| std::fs::write(out, x).map_err(|e| e.to_string())) {
                    eprintln!("error: {out}: {e}");
                }
            }
        }
        Err(e) => eprintln!("error: {e}"),
    }
}
