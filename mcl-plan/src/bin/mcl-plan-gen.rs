//! `mcl-plan-gen`: writes `domain.pddl` and `problem.pddl` of a classic
//! STRIPS benchmark problem into a folder. Deterministic.
//!
//! ```text
//! mcl-plan-gen OUTDIR gripper BALLS
//! mcl-plan-gen OUTDIR blocksworld BLOCKS SEED
//! mcl-plan-gen OUTDIR logistics CITIES SIZE AIRPLANES PACKAGES SEED
//! mcl-plan-gen OUTDIR logistics-costs CITIES SIZE AIRPLANES PACKAGES SEED
//! mcl-plan-gen OUTDIR miconic FLOORS PASSENGERS SEED
//! ```

use mcl_plan::gen;
use std::process::ExitCode;

const USAGE: &str = "usage: mcl-plan-gen OUTDIR (gripper BALLS | blocksworld BLOCKS SEED | logistics CITIES SIZE AIRPLANES PACKAGES SEED | logistics-costs CITIES SIZE AIRPLANES PACKAGES SEED | miconic FLOORS PASSENGERS SEED)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    }
    let nums: Result<Vec<u64>, _> = args[2..].iter().map(|a| a.parse::<u64>()).collect();
    let Ok(n) = nums else {
        eprintln!("error: the sizes must be non-negative integers\n{USAGE}");
        return ExitCode::from(2);
    };
    let u = |i: usize| n[i] as usize;
    let inst = match (args[1].as_str(), n.len()) {
        ("gripper", 1) => gen::gripper(u(0)),
        ("blocksworld", 2) => gen::blocksworld(u(0), n[1]),
        ("logistics", 5) => gen::logistics(u(0), u(1), u(2), u(3), n[4]),
        ("logistics-costs", 5) => gen::logistics_with_costs(u(0), u(1), u(2), u(3), n[4]),
        ("miconic", 3) => gen::miconic(u(0), u(1), n[2]),
        _ => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    match gen::write(&inst, std::path::Path::new(&args[0])) {
        Ok((d, p)) => {
            println!("{} {}", d.display(), p.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: cannot write into `{}`: {e}", args[0]);
            ExitCode::from(2)
        }
    }
}
