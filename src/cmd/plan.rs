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

pub struct Options {
    pub file: Option<PathBuf>,
    pub domain: Option<PathBuf>,
    pub problem: Option<PathBuf>,
    pub operators: Option<PathBuf>,
    pub search: SearchChoice,
    pub heuristic: HeuristicChoice,
    pub format: PlanFormat,
    pub validate: Option<PathBuf>,
    pub max_states: u64,
    pub stats: bool,
}

fn print_errors(errors: &[mcl_plan::Error]) {
    for e in errors {
        eprintln!("error: {e}");
    }
}

/// Type-checks the .mcl program (the file and its imports) with the compiler.
fn check_mcl(path: &Path) -> Result<(), String> {
    let db = Database::new();
    let root = db.file(path);
    if root.text(&db).is_none() {
        return Err(format!("cannot read `{}`", path.display()));
    }
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
    let beside = |name: &str| operators.as_ref().map(|m| m.parent().unwrap_or(Path::new(".")).join(name));
    let Some(domain_path) = o.domain.clone().or_else(|| beside("domain.pddl")) else {
        eprintln!("error: no domain: give --domain D.pddl (or FILE.mcl with domain.pddl beside it)");
        return 2;
    };
    let Some(problem_path) = o.problem.clone().or_else(|| beside("problem.pddl")) else {
        eprintln!("error: no problem: give --problem P.pddl (or FILE.mcl with problem.pddl beside it)");
        return 2;
    };
    let (domain, problem) = match mcl_plan::load(&domain_path, &problem_path) {
        Ok(x) => x,
        Err(e) => {
            print_errors(&e);
            return 2;
        }
    };
    if let Some(ops_path) = &operators {
        if let Err(report) = check_mcl(ops_path) {
            eprint!("{report}");
            eprintln!("error: the mission operators in `{}` have errors", ops_path.display());
            return 2;
        }
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
    }
    if let Some(plan_path) = &o.validate {
        let text = match std::fs::read_to_string(plan_path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: cannot read `{}`: {e}", plan_path.display());
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
    let alg = match (o.search, o.heuristic) {
        (SearchChoice::Bfs, _) => Algorithm::Bfs,
        (SearchChoice::Ucs, _) => Algorithm::Ucs,
        (SearchChoice::Astar, HeuristicChoice::Hadd) => Algorithm::Astar(Heuristic::Add),
        (SearchChoice::Astar, HeuristicChoice::Hmax) => Algorithm::Astar(Heuristic::Max),
        (SearchChoice::Gbfs, HeuristicChoice::Hadd) => Algorithm::Greedy(Heuristic::Add),
        (SearchChoice::Gbfs, HeuristicChoice::Hmax) => Algorithm::Greedy(Heuristic::Max),
    };
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
