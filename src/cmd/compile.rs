//! `mcl compile`: missions to PNML (and Graphviz). With `--out-dir`, a file
//! with several missions and constraints gives one PNML per vehicle: its
//! mission with its part of the supervisors and the firings it sends and
//! receives (`mcl_coord::decentralize`, docs/coordination.md).

use mcl_compiler::compile::{compile_file, dot::to_dot, CompileError};
use mcl_compiler::diagnostics::render_human;
use mcl_compiler::{check_file, Database, SourceFile};
use mcl_coord::{AnalyzeOptions, VehicleNet, Verdict};
use mcl_net::Net;
use mcl_syntax::ast::Item;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Options of `mcl compile`.
pub struct Options<'a> {
    pub file: &'a Path,
    pub output: Option<&'a Path>,
    pub dot: Dot,
    pub out_dir: Option<&'a Path>,
    pub view: View,
}

/// What `--dot OUT.dot` draws.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum View {
    /// The whole net, clustered by structure, call and task.
    Net,
    /// The mission's control-structure tree with its calls.
    Structure,
    /// One task's net.
    Task(String),
}

impl std::str::FromStr for View {
    type Err = String;
    fn from_str(s: &str) -> Result<View, String> {
        match s {
            "net" => Ok(View::Net),
            "structure" => Ok(View::Structure),
            _ => match s.strip_prefix("task:") {
                Some(t) if !t.is_empty() => Ok(View::Task(t.to_string())),
                _ => Err(format!("`{s}`: expected `net`, `structure` or `task:NAME`")),
            },
        }
    }
}

/// The drawing of `--view structure` or `--view task:NAME` (None for the
/// net, drawn from the compiled net itself).
fn view_drawing(db: &Database, file: SourceFile, view: &View, mission: &str) -> Result<Option<String>, String> {
    match view {
        View::Net => Ok(None),
        View::Structure => {
            let parsed = mcl_compiler::parse(db, file);
            let names = mcl_compiler::scope::mission_names(&parsed.file);
            let m = parsed
                .file
                .items
                .iter()
                .filter_map(|i| match i {
                    Item::Mission(m) => Some(m),
                    _ => None,
                })
                .zip(&names)
                .find(|(_, n)| *n == mission)
                .map(|(m, _)| m)
                .ok_or_else(|| format!("no mission `{mission}` in this file"))?;
            let text: &str = file.text(db).as_deref().unwrap_or("");
            let line =
                |offset: usize| text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1;
            Ok(Some(mcl_compiler::compile::tree_dot::structure_dot(m, mission, &line)))
        }
        View::Task(name) => {
            let scope = mcl_compiler::scope::scope(db, file);
            let mut b = mcl_compiler::compile::builder::Builder::new(name);
            match mcl_compiler::compile::add_task_net(db, scope, &mut b, name, "") {
                Ok(Some(_)) => {}
                Ok(None) => return Err(format!("`--view task:{name}`: the program has no task `{name}`")),
                Err(e) => return Err(e.to_string()),
            }
            let net = b.finish().build().map_err(|e| e.to_string())?;
            Ok(Some(to_dot(&net)))
        }
    }
}

/// Which Graphviz drawings `mcl compile` writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Dot {
    /// None.
    No,
    /// `--dot OUT.dot`: the drawing of the file's one mission.
    File(PathBuf),
    /// `--out-dir DIR --dot`: `DIR/<mission>.dot` beside each `<mission>.pnml`.
    PerMission,
}

fn create_parent(path: &Path) -> Result<(), String> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| format!("cannot create `{}`: {e}", parent.display()))?;
    }
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    create_parent(path)?;
    std::fs::write(path, text).map_err(|e| format!("cannot write `{}`: {e}", path.display()))
}

/// Writes the PNML of `net` to `path` as it is made, through a buffer: the
/// document (gigabytes for a million calls) is never in memory whole. On
/// error, a partly written regular file is removed.
fn write_pnml_file(path: &Path, net: &Net) -> Result<(), String> {
    create_parent(path)?;
    let file = std::fs::File::create(path).map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    let result = mcl_net::write_pnml_to(net, std::io::BufWriter::with_capacity(1 << 16, file));
    result.map_err(|e| {
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(path);
        }
        e.to_string()
    })
}

/// A file name for a mission: its name, with characters outside
/// `[A-Za-z0-9_-]` replaced by `_`.
pub fn file_stem(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// True when `file` has a non-empty `constraints { ... }` block.
pub fn has_constraints(db: &Database, file: SourceFile) -> bool {
    mcl_compiler::parse(db, file)
        .file
        .items
        .iter()
        .any(|i| matches!(i, Item::Constraints(b) if !b.constraints.is_empty()))
}

/// The per-vehicle nets of the missions of `file` (without errors) under
/// its constraints: the supervisors (`mcl_coord::analyze`) split with the
/// least communication (`mcl_coord::decentralize`). Constraints that
/// deadlock are refused with the diagnostics of `mcl check` (E0406); an
/// inconclusive analysis is a warning. With `deadlocks_allowed` (a run of
/// a counterexample scenario, `mcl run` with `[counterexample]`), nets of
/// constraints that deadlock are built all the same, with a note. On
/// error, prints it and returns the exit status `code`.
pub fn vehicle_nets(db: &Database, file: SourceFile, code: u8, deadlocks_allowed: bool) -> Result<Vec<VehicleNet>, u8> {
    let fail = |msg: String| {
        eprintln!("error: {msg}");
        code
    };
    let (missions, constraints) = mcl_coord::source::load(db, file).map_err(|e| fail(e.to_string()))?;
    let supervisors = if constraints.is_empty() {
        Vec::new()
    } else {
        let opts = AnalyzeOptions { structure: false, ..AnalyzeOptions::default() };
        let report = mcl_coord::analyze_with(&missions, &constraints, &opts).map_err(|e| fail(e.to_string()))?;
        match &report.verdict {
            Verdict::Free => {}
            Verdict::Deadlock if deadlocks_allowed => eprintln!(
                "note: `{}`: the constraints deadlock (E0406); the vehicle nets are built all the same to replay the counterexample",
                file.path(db).display()
            ),
            Verdict::Deadlock => {
                let diags = mcl_coord::coordination_diagnostics(db, file);
                eprint!("{}", render_human(db, diags, std::io::stderr().is_terminal()));
                let first = report.problems.first().map(|p| p.message.clone()).unwrap_or_default();
                return Err(fail(format!(
                    "`{}`: the constraints deadlock ({first}); no vehicle net was made",
                    file.path(db).display()
                )));
            }
            Verdict::Unknown { reason } => {
                eprintln!("warning: the deadlock analysis was inconclusive ({reason}); the nets are not proven free of deadlock")
            }
        }
        report.supervisors
    };
    mcl_coord::decentralize(&missions, &supervisors).map_err(|e| fail(e.to_string()))
}

/// Where a vehicle's net sends and what it receives, for humans:
/// `2 supervisor places, sends 3 firings to asc, receives 2 from asc`.
pub fn coordination_summary(v: &VehicleNet) -> String {
    let sups = mcl_coord::decentral::supervisor_places(&v.net).len();
    let mut parts = vec![format!("{sups} supervisor place{}", if sups == 1 { "" } else { "s" })];
    let mut peers: Vec<&String> = v.send.iter().map(|(_, to)| to).chain(v.receive.iter().map(|(_, f)| f)).collect();
    peers.sort();
    peers.dedup();
    for p in peers {
        let sent = v.send.iter().filter(|(_, to)| to == p).count();
        let got = v.receive.iter().filter(|(_, f)| f == p).count();
        parts.push(format!("sends {sent} firing{} to {p}, receives {got} from {p}", if sent == 1 { "" } else { "s" }));
    }
    parts.join(", ")
}

pub fn run(o: Options<'_>) -> u8 {
    let db = Database::new();
    let file = match super::source_file(&db, o.file) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let missions = match compile_file(&db, file) {
        Ok(m) => m,
        Err(CompileError::HasErrors) => {
            let diags: Vec<_> = check_file(&db, file).iter().filter(|d| d.diag.is_error()).cloned().collect();
            eprint!("{}", render_human(&db, &diags, std::io::stderr().is_terminal()));
            eprintln!("error: `{}` has errors; nothing was compiled", o.file.display());
            return 1;
        }
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    if missions.is_empty() {
        eprintln!("error: `{}` defines no mission", o.file.display());
        return 1;
    }
    if let (Some(dir), true) = (o.out_dir, missions.len() > 1 && has_constraints(&db, file)) {
        let vehicles = match vehicle_nets(&db, file, 1, false) {
            Ok(v) => v,
            Err(code) => return code,
        };
        let result = (|| -> Result<(), String> {
            for v in &vehicles {
                let stem = file_stem(&v.mission);
                let path = dir.join(format!("{stem}.pnml"));
                write_pnml_file(&path, &v.net)?;
                eprintln!(
                    "wrote {} ({} places, {} transitions; {})",
                    path.display(),
                    v.net.place_count(),
                    v.net.transition_count(),
                    coordination_summary(v)
                );
                if o.dot == Dot::PerMission {
                    let path = dir.join(format!("{stem}.dot"));
                    write(&path, &to_dot(&v.net))?;
                    eprintln!("wrote {}", path.display());
                }
            }
            Ok(())
        })();
        return match result {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                2
            }
        };
    }
    // A drawing of the program rather than of the net is made while the
    // database is there.
    let view_dot = match (&o.dot, missions.first()) {
        (Dot::File(_), Some(m)) => match view_drawing(&db, file, &o.view, &m.name) {
            Ok(d) => d,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        },
        _ => None,
    };
    // The nets are all that is left to write: the database (syntax trees,
    // check results) goes before the PNML is written.
    drop(db);
    let result = (|| -> Result<(), String> {
        if let Some(dir) = o.out_dir {
            let mut written: Vec<PathBuf> = Vec::new();
            for m in &missions {
                // Names are unique per file (`mcl_compiler::scope::mission_names`).
                let stem = file_stem(&m.name);
                let path = dir.join(format!("{stem}.pnml"));
                write_pnml_file(&path, &m.net)?;
                written.push(path);
                if o.dot == Dot::PerMission {
                    let path = dir.join(format!("{stem}.dot"));
                    write(&path, &to_dot(&m.net))?;
                    written.push(path);
                }
            }
            for p in written {
                eprintln!("wrote {}", p.display());
            }
            return Ok(());
        }
        if missions.len() > 1 {
            let names: Vec<&str> = missions.iter().map(|m| m.name.as_str()).collect();
            return Err(format!(
                "`{}` defines {} missions ({}); use --out-dir DIR to write one PNML per mission",
                o.file.display(),
                names.len(),
                names.join(", ")
            ));
        }
        let m = &missions[0];
        match o.output {
            Some(p) => {
                write_pnml_file(p, &m.net)?;
                eprintln!(
                    "wrote {} ({} places, {} transitions)",
                    p.display(),
                    m.net.place_count(),
                    m.net.transition_count()
                );
            }
            None if o.dot == Dot::No => {
                let out = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
                mcl_net::write_pnml_to(&m.net, out).map_err(|e| e.to_string())?
            }
            None => {}
        }
        if let Dot::File(d) = &o.dot {
            match &view_dot {
                Some(text) => write(d, text)?,
                None => write(d, &to_dot(&m.net))?,
            }
            eprintln!("wrote {}", d.display());
        }
        Ok(())
    })();
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}
