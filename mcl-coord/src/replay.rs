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
    let analysis = || analyze_replayable(&missions, &constraints, &crate::check::options());
    let report = crate::interrupt::interruptible(|| db.unwind_if_revision_cancelled(), analysis);
    replays_of(&missions, report.map_err(|e| e.to_string())?)
}

/// E0406: one builder per reported problem ([`crate::check::reported`]),
/// in the order of the diagnostics. Each replays the problem's firing
/// sequence on the supervised net (with the take-back of withdrawn sync
/// arrivals as nodes), and checks it on the vehicle nets that `mcl run`
/// plays (built although the constraints deadlock).
pub fn deadlock_replays(missions: &[Mission], constraints: &[Constraint]) -> Result<Vec<Build>, String> {
    let report = analyze_replayable(missions, constraints, &crate::check::options()).map_err(|e| e.to_string())?;
    replays_of(missions, report)
}

/// The analysis behind E0406 ([`crate::analyze_with`]), with each reported
/// problem ([`crate::check::reported`]) whose firing sequence no dry run
/// follows replaced by the run of the exact product to a stuck state
/// (`verify::flight::stuck_run`: the players with their messages in
/// flight): its firing sequence, its marking, its waiting calls and its
/// message, so that the diagnostic, the scenario and the dry run name the
/// same marking. The analysis' sequence may hold steps that no player
/// takes; the exact product's never does. Each reported problem costs a
/// dry run (more when its sequence does not replay).
pub fn analyze_replayable(
    missions: &[Mission],
    constraints: &[Constraint],
    opts: &crate::AnalyzeOptions,
) -> Result<crate::Report, crate::CoordError> {
    let mut report = crate::analyze_with(missions, constraints, opts)?;
    if report.problems.is_empty() {
        return Ok(report);
    }
    let Ok(r) = Replayer::new(missions, &report) else { return Ok(report) };
    let (Ok(plant), mut seen) = (crate::centralize(missions), Vec::new()) else { return Ok(report) };
    let mut runs: [Option<Option<ExactRun>>; 2] = [None, None];
    let probe = Expected { code: "E0406".into(), ..Expected::default() };
    for i in 0..report.problems.len() {
        let p = &report.problems[i];
        // Only the reported ones (the first of each set of constraints).
        if seen.contains(&p.constraints) {
            continue;
        }
        seen.push(p.constraints.clone());
        if r.build(&Case::of(&r.net, p), &probe).is_ok() {
            continue;
        }
        let quiet = p.kind == WitnessKind::Stuck;
        let run = runs[usize::from(quiet)]
            .get_or_insert_with(|| exact_run(&r.net, &report, missions, &r.vnets, quiet))
            .as_ref();
        let Some(run) = run else { continue };
        let w = crate::verify::Witness {
            kind: p.kind,
            path: run
                .path
                .iter()
                .filter_map(|&t| report.net.transition_by_id(&r.net.transitions()[t.index()].id))
                .collect(),
            marking: run.supervised.clone(),
            held: run.held.clone(),
        };
        let p = p.clone();
        report.problems[i] = crate::analysis::problem(
            &plant,
            &report.net,
            &report.supervisors,
            &w,
            (p.siphon, p.refusal),
            &p.constraints,
            constraints,
        );
        // The set of constraints stays the reported one's.
        report.problems[i].constraints = p.constraints;
    }
    Ok(report)
}

/// A run of the exact product to a stuck state, on the supervised
/// centralized net: the firings of the missions' own transitions, in the
/// order the players took them, the marking at its end and the calls held.
struct ExactRun {
    /// On the net with take-back nodes ([`Replayer::net`]).
    path: Vec<TransitionId>,
    /// The marking of the supervised net ([`crate::Report::net`]): the
    /// missions' places, and the supervisor places as the sequence leaves
    /// them there (none when it does not fire there).
    supervised: Marking,
    /// The calls held in the stuck state: the start transitions (of the
    /// supervised net) of the vehicles that have not ended, enabled in
    /// their vehicle net but for supervisor copies, with the indices of
    /// those supervisors.
    held: Vec<(TransitionId, Vec<usize>)>,
}

/// The [`ExactRun`] of `missions` (their vehicle nets `vnets`) on `net`
/// (the supervised net of `report` with take-back nodes).
fn exact_run(
    net: &Net,
    report: &crate::Report,
    missions: &[Mission],
    vnets: &[crate::VehicleNet],
    quiet: bool,
) -> Option<ExactRun> {
    let run = crate::verify::flight::stuck_run(missions, vnets, quiet, MAX_STATES)?;
    let central = |vn: &crate::VehicleNet, id: &str| format!("{}{}{id}", vn.mission, crate::central::SEP);
    let mut path = Vec::new();
    for (v, fired) in &run.steps {
        let vn = vnets.get(*v)?;
        for &t in fired {
            let id = &vn.net.transitions().get(t.index())?.id;
            // The vehicle net's own coordination nodes have no counterpart.
            if let Some(c) = net.transition_by_id(&central(vn, id)) {
                path.push(c);
            }
        }
    }
    let snet = &report.net;
    let mut supervised = Marking(vec![0; snet.place_count()]);
    let mut held = Vec::new();
    for (vn, m) in vnets.iter().zip(&run.markings) {
        for (p, &k) in vn.net.places().iter().zip(m) {
            if k > 0 && !p.id.starts_with("coord.") {
                if let Some(c) = snet.place_by_id(&central(vn, &p.id)) {
                    supervised.0[c.index()] = k;
                }
            }
        }
        let ended = vn.net.places().iter().zip(m).any(|(p, &k)| {
            k > 0
                && (p.id.as_str() == mcl_runtime::player::MISSION_OK
                    || p.id.as_str() == mcl_runtime::player::MISSION_FAIL)
        });
        if ended {
            continue;
        }
        let coord = |p: mcl_net::PlaceId| vn.net.place(p).is_some_and(|x| x.id.starts_with("coord."));
        for t in vn.net.transition_ids() {
            let Some(c) = vn.net.transition(t).and_then(|x| snet.transition_by_id(&central(vn, &x.id))) else {
                continue;
            };
            let plant_ok =
                mcl_net::semantics::is_enabled_with(&vn.net, t, |p| if coord(p) { u32::MAX } else { m[p.index()] });
            let missing: Vec<usize> = vn
                .net
                .pre(t)
                .iter()
                .filter(|&&(p, w)| coord(p) && m[p.index()] < w)
                .filter_map(|&(p, _)| {
                    let id = &vn.net.place(p)?.id;
                    report.supervisors.iter().position(|s| s.id == id.as_str())
                })
                .collect();
            if plant_ok && !missing.is_empty() {
                held.push((c, missing));
            }
        }
    }
    // The supervisor places, as the centralized net counts them.
    let np = snet.place_count() - report.supervisors.len();
    let mut m = snet.initial_marking();
    let fired = path.iter().all(|&t| {
        let id = &net.transitions()[t.index()].id;
        snet.transition_by_id(id).is_some_and(|t| mcl_net::semantics::fire(snet, &mut m, t).is_ok())
    });
    if fired {
        supervised.0[np..].copy_from_slice(&m.0[np..]);
    }
    Some(ExactRun { path, supervised, held })
}

/// What the scenario of one reported problem is built from.
struct Case {
    /// Its firing sequence on [`Replayer::net`] (`None`: it names a
    /// transition that the net does not have).
    path: Option<Vec<TransitionId>>,
    /// Its marking on that net.
    marking: Marking,
    kind: &'static str,
    waiting: Vec<String>,
    /// The missions of the held calls.
    held: Vec<String>,
}

impl Case {
    fn of(net: &Net, p: &crate::Problem) -> Case {
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
        let held = p
            .held_by
            .iter()
            .filter_map(|(t, _)| t.split_once(crate::central::SEP))
            .map(|(m, _)| m.to_string())
            .collect();
        Case { path, marking: m, kind, waiting: p.waiting.clone(), held }
    }
}

/// What the scenarios of a report's problems are built and checked with.
struct Replayer {
    /// The supervised net with the take-back nodes.
    net: Arc<Net>,
    vnets: Vec<crate::VehicleNet>,
    /// The vehicle nets that `mcl run` plays, by mission.
    vehicles: Vec<(String, Arc<Net>)>,
    tasks: Vec<String>,
}

impl Replayer {
    fn new(missions: &[Mission], report: &crate::Report) -> Result<Replayer, String> {
        let net =
            Arc::new(crate::supervisor::with_take_backs(&report.net, &report.supervisors).map_err(|e| e.to_string())?);
        let vnets = crate::decentralize(missions, &report.supervisors)
            .map_err(|e| format!("the vehicle nets cannot be built ({e})"))?;
        let vehicles: Vec<(String, Arc<Net>)> =
            vnets.iter().map(|v| (v.mission.clone(), Arc::new(v.net.clone()))).collect();
        let tasks = ProgramNames::of(vehicles.iter().map(|(_, n)| n.as_ref())).tasks;
        Ok(Replayer { net, vnets, vehicles, tasks })
    }

    /// The scenario of `case`, checked by a dry run, with the
    /// `[counterexample]` table `e` (its marking, kind and waiting calls
    /// filled in from the case).
    fn build(&self, case: &Case, e: &Expected) -> Result<String, String> {
        let path = case.path.as_ref().ok_or("the counterexample names a transition the net does not have")?;
        let cx = Counterexample { net: &self.net, path, centralized: true, mission: "", waiting: &case.held };
        let want = Expected {
            kind: case.kind.to_string(),
            waiting: case.waiting.clone(),
            marking: cx.marking(&case.marking),
            ..e.clone()
        };
        cex::build(&cx, &self.tasks, &want, true, |t| cex::check_vehicles(&self.vehicles, t))
    }
}

fn replays_of(missions: &[Mission], report: crate::Report) -> Result<Vec<Build>, String> {
    let r = Arc::new(Replayer::new(missions, &report)?);
    let mut out: Vec<Build> = Vec::new();
    for p in crate::check::reported(&report.problems) {
        let case = Case::of(&r.net, p);
        let r = r.clone();
        out.push(Box::new(move |e: &Expected| r.build(&case, e)));
    }
    Ok(out)
}
