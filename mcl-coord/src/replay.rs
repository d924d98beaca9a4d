//! Counterexamples you can run: the deadlocks that `mcl check` reports —
//! E0406 ([`crate::check`]: a firing sequence of the supervised centralized
//! net) and E0601 of a task that a mission calls (the block verifier:
//! a run of the mission net that gets stuck in that task) — as scenarios
//! for `mcl run --mock --virtual-time` (`mcl_runtime::counterexample`),
//! each checked by a dry run in process before it is given. Used by
//! `mcl check --counterexample-scenario` and the language server's code
//! action (docs/scenarios.md *Counterexamples*, docs/lsp.md).

use std::sync::Arc;

use mcl_compiler::compile::compile_file_unverified;
use mcl_compiler::{codes, Db, FileDiagnostic, SourceFile};
use mcl_net::{explore, Marking, Net, Options, TransitionId};
use mcl_runtime::counterexample::{self as cex, Counterexample, Expected};
use mcl_runtime::scenario::ProgramNames;
use mcl_syntax::Diagnostic;

use crate::model::{Constraint, Mission};
use crate::verify::WitnessKind;

/// Largest state space explored to find where a mission gets stuck in a
/// task (E0601).
pub const MAX_STATES: usize = 200_000;

/// One diagnostic with a counterexample, and its scenario.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The diagnostic (E0406, E0601; an E0601 may be located in an
    /// imported file, where the task is defined).
    pub diagnostic: FileDiagnostic,
    /// The file whose missions the scenario runs.
    pub root: SourceFile,
    /// The mission it runs, when `root` has several and the scenario is for
    /// one of them (E0601: `mcl run --mission NAME`).
    pub mission: Option<String>,
    /// The scenario's TOML text, or why no replay could be built.
    pub scenario: Result<String, String>,
}

/// True for the diagnostics whose counterexamples can be replayed.
pub fn has_counterexample(d: &FileDiagnostic) -> bool {
    d.diag.code == codes::DEADLOCKING_CONSTRAINTS || d.diag.code == codes::BLOCK_PROPERTY
}

/// The scenarios of the diagnostics that `wanted` keeps among those with a
/// counterexample that the missions of `file` run: E0406 of `file`, and
/// E0601 of a task that a mission of `file` calls (the task may be defined
/// in an imported file); in the order of the diagnostics, the compiler's
/// then the coordination analysis'.
pub fn counterexample_scenarios(
    db: &dyn Db,
    file: SourceFile,
    wanted: impl Fn(&FileDiagnostic) -> bool,
) -> Vec<Replay> {
    let mut out = Vec::new();
    let blocks: Vec<FileDiagnostic> = mcl_compiler::program(db, file)
        .files
        .iter()
        .flat_map(|&g| {
            mcl_compiler::check_file(db, g)
                .iter()
                .filter(|d| d.file == g && d.diag.code == codes::BLOCK_PROPERTY && wanted(d))
                .cloned()
                .collect::<Vec<_>>()
        })
        .collect();
    if !blocks.is_empty() {
        let missions = compile_file_unverified(db, file);
        for d in &blocks {
            // A pattern no task uses, or a task no mission of `file` calls:
            // no run of `file` meets it.
            let Some(task) = task_of(&d.diag) else { continue };
            let scenario = match &missions {
                Err(e) => Err(format!("the missions cannot be compiled ({e})")),
                Ok(ms) => {
                    let nets: Vec<(String, &Net)> =
                        ms.iter().filter(|m| calls(&m.net, &task)).map(|m| (m.name.clone(), &m.net)).collect();
                    if nets.is_empty() {
                        continue;
                    }
                    let several = ms.len() > 1;
                    let r = block_scenario(&nets, &task, expected(db, d, "block"));
                    out.push(Replay {
                        diagnostic: d.clone(),
                        root: file,
                        mission: r.as_ref().ok().and_then(|(m, _)| several.then(|| m.clone())),
                        scenario: r.map(|(_, text)| text),
                    });
                    continue;
                }
            };
            out.push(Replay { diagnostic: d.clone(), root: file, mission: None, scenario });
        }
    }
    let deadlocks: Vec<&FileDiagnostic> = crate::coordination_diagnostics(db, file)
        .iter()
        .filter(|d| d.diag.code == codes::DEADLOCKING_CONSTRAINTS)
        .collect();
    if !deadlocks.iter().any(|d| wanted(d)) {
        return out;
    }
    let scenarios = deadlock_scenarios(db, file);
    for (k, d) in deadlocks.into_iter().enumerate().filter(|(_, d)| wanted(d)) {
        let scenario = match &scenarios {
            Err(e) => Err(e.clone()),
            Ok(list) => match list.get(k) {
                Some(build) => build(&expected(db, d, "")),
                None => Err("the analysis no longer finds this deadlock".to_string()),
            },
        };
        out.push(Replay { diagnostic: d.clone(), root: file, mission: None, scenario });
    }
    out
}

/// True when some call of `net` is a call of `task`.
fn calls(net: &Net, task: &str) -> bool {
    net.transitions().iter().any(|t| t.binding.as_ref().is_some_and(|b| b.task == task))
}

/// The task named by an E0601 diagnostic's label (`... of task `T``).
fn task_of(d: &Diagnostic) -> Option<String> {
    d.labels.iter().find_map(|l| {
        let rest = &l.message[l.message.find("of task `")? + "of task `".len()..];
        Some(rest[..rest.find('`')?].to_string())
    })
}

/// The `[counterexample]` table of a diagnostic, its marking left empty.
fn expected(db: &dyn Db, d: &FileDiagnostic, kind: &str) -> Expected {
    let text = d.file.text(db).as_deref().unwrap_or("").to_string();
    let line = text.get(..d.diag.span.start as usize).map_or(1, |b| b.matches('\n').count() + 1);
    Expected {
        code: d.diag.code.to_string(),
        at: format!("{}:{line}", shown(d.file.path(db))),
        message: d.diag.message.clone(),
        kind: kind.to_string(),
        ..Expected::default()
    }
}

/// A path as the user gave it: relative to the current folder when inside it.
pub fn shown(path: &std::path::Path) -> String {
    let rel = std::env::current_dir().ok().and_then(|d| path.strip_prefix(d).ok().map(|p| p.to_path_buf()));
    rel.as_deref().unwrap_or(path).display().to_string()
}

/// E0601: the shortest run of a mission of `missions` (those that call
/// `task`) to a dead marking in which the mission has not ended and `task`
/// holds a token, replayed; with the mission's name.
fn block_scenario(missions: &[(String, &Net)], task: &str, mut want: Expected) -> Result<(String, String), String> {
    let prefix = format!("task.{task}.");
    let mut why = format!("no mission calls task `{task}`");
    for (name, net) in missions {
        let ss = explore(net, &Options { max_states: MAX_STATES, ..Options::default() });
        let ended = |m: &Marking| {
            net.places().iter().enumerate().any(|(i, p)| {
                (p.id.as_str() == mcl_runtime::player::MISSION_OK || p.id.as_str() == mcl_runtime::player::MISSION_FAIL)
                    && m.0[i] > 0
            })
        };
        let stuck = ss.dead_states().find(|&s| {
            let m = ss.marking(s);
            !ended(&m) && m.support().any(|(p, _)| net.place(p).is_some_and(|x| x.id.starts_with(&prefix)))
        });
        let Some(s) = stuck else {
            why = format!(
                "no run of mission `{name}` gets stuck in task `{task}`{}: the violation does not stop the mission",
                if ss.complete() { "" } else { " within the states explored" }
            );
            continue;
        };
        let path = ss.path_to(s);
        let cx = Counterexample { net, path: &path, centralized: false, mission: name, waiting: &[] };
        want.marking = cx.marking(&ss.marking(s));
        let tasks = ProgramNames::of([*net]).tasks;
        let shared = Arc::new((*net).clone());
        return cex::build(&cx, &tasks, &want, false, |t| cex::check_single(&shared, name, t))
            .map(|t| (name.clone(), t));
    }
    Err(why)
}

/// A builder of the scenario of one reported deadlock, given its
/// `[counterexample]` table (its marking, kind and waiting calls are filled
/// in from the problem).
pub type Build = Box<dyn Fn(&Expected) -> Result<String, String>>;

/// [`deadlock_replays`] of the missions of `file`; an edit in the editor
/// stops the analysis part-way (as it does the diagnostics').
fn deadlock_scenarios(db: &dyn Db, file: SourceFile) -> Result<Vec<Build>, String> {
    let (missions, constraints) = crate::source::load(db, file).map_err(|e| e.to_string())?;
    let analysis = || crate::analyze_with(&missions, &constraints, &crate::check::options());
    let report = crate::interrupt::interruptible(|| db.unwind_if_revision_cancelled(), analysis);
    replays_of(&missions, report.map_err(|e| e.to_string())?)
}

/// E0406: one builder per reported problem ([`crate::check::reported`]),
/// in the order of the diagnostics. Each replays the problem's firing
/// sequence on the supervised net (with the take-back of withdrawn sync
/// arrivals as nodes), and checks it on the vehicle nets that `mcl run`
/// plays (built although the constraints deadlock).
pub fn deadlock_replays(missions: &[Mission], constraints: &[Constraint]) -> Result<Vec<Build>, String> {
    let report = crate::analyze_with(missions, constraints, &crate::check::options()).map_err(|e| e.to_string())?;
    replays_of(missions, report)
}

/// A run of the exact product to a stuck state, on the supervised
/// centralized net: the firings of the missions' own transitions, in the
/// order the players took them, and the missions' marking at its end.
struct ExactRun {
    path: Vec<TransitionId>,
    marking: Marking,
}

/// The [`ExactRun`] of `missions` (their vehicle nets `vnets`) on `net`.
fn exact_run(net: &Net, missions: &[Mission], vnets: &[crate::VehicleNet], quiet: bool) -> Option<ExactRun> {
    let run = crate::verify::flight::stuck_run(missions, vnets, quiet, MAX_STATES)?;
    let mut path = Vec::new();
    for (v, fired) in &run.steps {
        let vn = vnets.get(*v)?;
        for &t in fired {
            let id = &vn.net.transitions().get(t.index())?.id;
            // The vehicle net's own coordination nodes have no counterpart.
            if let Some(c) = net.transition_by_id(&format!("{}{}{id}", vn.mission, crate::central::SEP)) {
                path.push(c);
            }
        }
    }
    let mut marking = Marking(vec![0; net.place_count()]);
    for (vn, m) in vnets.iter().zip(&run.markings) {
        for (p, &k) in vn.net.places().iter().zip(m) {
            if k > 0 && !p.id.starts_with("coord.") {
                if let Some(c) = net.place_by_id(&format!("{}{}{}", vn.mission, crate::central::SEP, p.id)) {
                    marking.0[c.index()] = k;
                }
            }
        }
    }
    Some(ExactRun { path, marking })
}

fn replays_of(missions: &[Mission], report: crate::Report) -> Result<Vec<Build>, String> {
    let net =
        Arc::new(crate::supervisor::with_take_backs(&report.net, &report.supervisors).map_err(|e| e.to_string())?);
    let vnets = crate::decentralize(missions, &report.supervisors)
        .map_err(|e| format!("the vehicle nets cannot be built ({e})"))?;
    let vehicles: Vec<(String, Arc<Net>)> =
        vnets.iter().map(|v| (v.mission.clone(), Arc::new(v.net.clone()))).collect();
    // The runs of the exact product to a stuck state (`verify::flight`),
    // found on first use: all runs, and nominal ones.
    let runs: Arc<[std::sync::OnceLock<Option<ExactRun>>; 2]> = Arc::new(Default::default());
    let (missions_all, vnets) = (Arc::new(missions.to_vec()), Arc::new(vnets));
    let vehicles = Arc::new(vehicles);
    let tasks = ProgramNames::of(vehicles.iter().map(|(_, n)| n.as_ref())).tasks;
    let mut out: Vec<Build> = Vec::new();
    for p in crate::check::reported(&report.problems) {
        let path: Option<Vec<TransitionId>> = p.counterexample.iter().map(|id| net.transition_by_id(id)).collect();
        let mut m = Marking(vec![0; net.place_count()]);
        for s in &p.marking {
            let (id, k) = match s.rsplit_once('*') {
                Some((id, k)) if k.parse::<u32>().is_ok() => (id, k.parse().unwrap_or(1)),
                _ => (s.as_str(), 1),
            };
            if let Some(pl) = net.place_by_id(id) {
                m.0[pl.index()] = k;
            }
        }
        let kind = match p.kind {
            WitnessKind::Dead => "dead",
            WitnessKind::Blocked => "blocked",
            WitnessKind::Stuck => "stuck",
        };
        let waiting = p.waiting.clone();
        let held: Vec<String> = p
            .held_by
            .iter()
            .filter_map(|(t, _)| t.split_once(crate::central::SEP))
            .map(|(m, _)| m.to_string())
            .collect();
        let (net, vehicles, tasks) = (net.clone(), vehicles.clone(), tasks.clone());
        let (runs, missions_all, vnets) = (runs.clone(), missions_all.clone(), vnets.clone());
        let quiet = p.kind == WitnessKind::Stuck;
        out.push(Box::new(move |e: &Expected| {
            let path = path.as_ref().ok_or("the counterexample names a transition the net does not have")?;
            let cx = Counterexample { net: &net, path, centralized: true, mission: "", waiting: &held };
            let want =
                Expected { kind: kind.to_string(), waiting: waiting.clone(), marking: cx.marking(&m), ..e.clone() };
            let why = match cex::build(&cx, &tasks, &want, true, |t| cex::check_vehicles(&vehicles, t)) {
                Ok(text) => return Ok(text),
                Err(why) => why,
            };
            // The analysis' path may hold steps that no player takes: the
            // exact product's own run to a stuck state (the players with
            // their messages in flight) is tried instead.
            let run = runs[usize::from(quiet)].get_or_init(|| exact_run(&net, &missions_all, &vnets, quiet));
            let Some(run) = run else { return Err(why) };
            let cx = Counterexample { path: &run.path, ..cx };
            let want = Expected { marking: cx.marking(&run.marking), ..want };
            cex::build(&cx, &tasks, &want, true, |t| cex::check_vehicles(&vehicles, t))
                .map_err(|e| format!("{why}; along the run of the players with messages in flight: {e}"))
        }));
    }
    Ok(out)
}
