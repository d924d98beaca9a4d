//! `mcl check`: diagnostics for files and everything they import, and the
//! coordination analysis of every file with constraints (`mcl_coord::check`).
//! A file that cannot be read (not UTF-8, not a regular file, over 16 MiB)
//! is reported on standard error and the others are checked (exit status 2).
//! With `--counterexample-scenario OUT.toml`, the counterexamples of the
//! deadlocks reported are written as scenarios for `mcl run`
//! (`mcl_coord::replay`; messages on standard error). With `--ros2
//! BRIDGE.toml`, the ROS 2 bridge file is checked against the vehicle of the
//! checked files (`src/cmd/ros2.rs`).

use crate::{ColorChoice, Format};
use mcl_compiler::diagnostics::{render_human, to_json};
use mcl_compiler::{check_file, program, Database, Db, FileDiagnostic, SourceFile};
use mcl_syntax::Severity;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

pub fn run(
    paths: &[PathBuf],
    format: Format,
    color: ColorChoice,
    scenario_out: Option<&Path>,
    ros2: Option<&Path>,
) -> u8 {
    let files = match super::collect_mcl_files(paths) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let db = Database::new();
    let mut roots: Vec<SourceFile> = Vec::new();
    // A file that cannot be read is reported and the others are checked.
    let mut unreadable = 0;
    for path in &files {
        match super::source_file(&db, path) {
            Ok(f) => roots.push(f),
            Err(e) => {
                eprintln!("error: {e}");
                unreadable += 1;
            }
        }
    }
    // Imported files are checked too, each once.
    let mut to_check: Vec<SourceFile> = Vec::new();
    let std = db.stdlib();
    for &r in &roots {
        for &f in program(&db, r).files.iter().rev() {
            if f != std && !to_check.contains(&f) {
                to_check.push(f);
            }
        }
    }
    let mut diags: Vec<FileDiagnostic> = Vec::new();
    for &f in &to_check {
        diags.extend(check_file(&db, f).iter().cloned());
        // Deadlock analysis of the file's missions under its constraints
        // (E0406, W0407); nothing while the program has errors.
        diags.extend(mcl_coord::coordination_diagnostics(&db, f).iter().cloned());
    }
    // The ROS 2 bridge file, against the vehicle of the checked programs
    // (only once they have no errors: their interface is then complete).
    let program_errors = diags.iter().any(|d| d.diag.severity == Severity::Error);
    let bridge_errors = match ros2 {
        Some(b) if !program_errors => super::ros2::check_bridge(b, &super::ros2::vehicle_of(&db, &roots)),
        Some(b) => {
            eprintln!("note: `{}` is checked once the program has no errors", b.display());
            Vec::new()
        }
        None => Vec::new(),
    };
    let errors = diags.iter().filter(|d| d.diag.severity == Severity::Error).count() + bridge_errors.len();
    let warnings = diags.iter().filter(|d| d.diag.severity == Severity::Warning).count();
    let mut stdout = std::io::stdout().lock();
    let written = match format {
        Format::Json => {
            let mut arr: Vec<_> = diags.iter().map(|d| to_json(&db, d)).collect();
            arr.extend(bridge_errors.iter().map(super::ros2::to_json));
            writeln!(stdout, "{}", serde_json::to_string_pretty(&arr).unwrap_or_else(|_| "[]".into()))
        }
        Format::Human => {
            let use_color = match color {
                ColorChoice::Always => true,
                ColorChoice::Never => false,
                ColorChoice::Auto => std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
            };
            let mut s = render_human(&db, &diags, use_color);
            for e in &bridge_errors {
                s.push_str(&format!("{e}\n"));
            }
            let n = to_check.len();
            s.push_str(&format!(
                "checked {n} file{}: {errors} error{}, {warnings} warning{}{}\n",
                if n == 1 { "" } else { "s" },
                if errors == 1 { "" } else { "s" },
                if warnings == 1 { "" } else { "s" },
                match unreadable {
                    0 => String::new(),
                    1 => "; 1 file could not be read".to_string(),
                    k => format!("; {k} files could not be read"),
                }
            ));
            stdout.write_all(s.as_bytes())
        }
    };
    drop(stdout);
    let scenarios_failed = match scenario_out {
        Some(out) => write_scenarios(&db, &to_check, out).is_err(),
        None => false,
    };
    if written.is_err() || unreadable > 0 || scenarios_failed {
        return 2;
    }
    u8::from(errors > 0)
}

/// Writes the scenario of every counterexample of `files` (`OUT.toml` for
/// one, `OUT-1.toml`, `OUT-2.toml`, ... for several) and says on standard
/// error what was written, and which counterexample has no replay and why.
/// `Err` when a file cannot be written.
fn write_scenarios(db: &Database, files: &[SourceFile], out: &Path) -> Result<(), ()> {
    let replays: Vec<mcl_coord::replay::Replay> = files
        .iter()
        .flat_map(|&f| mcl_coord::replay::counterexample_scenarios(db, f, mcl_coord::replay::has_counterexample))
        .collect();
    if replays.is_empty() {
        eprintln!("note: no deadlock counterexample to write (E0406, or E0601 of a task a mission calls)");
        return Ok(());
    }
    let mut result = Ok(());
    let n = replays.len();
    for (i, r) in replays.into_iter().enumerate() {
        let d = &r.diagnostic;
        let text = d.file.text(db).as_deref().unwrap_or("").to_string();
        let line = text.get(..d.diag.span.start as usize).map_or(1, |b| b.matches('\n').count() + 1);
        let source = mcl_coord::replay::shown(d.file.path(db));
        let what = format!("{} at {source}:{line}", d.diag.code);
        let root = mcl_coord::replay::shown(r.root.path(db));
        let mission = r.mission.as_ref().map(|m| format!(" --mission {m}")).unwrap_or_default();
        match r.scenario {
            Ok(scenario) => {
                let path = if n == 1 { out.to_path_buf() } else { numbered(out, i + 1) };
                match std::fs::write(&path, scenario) {
                    Ok(()) => eprintln!(
                        "counterexample of {what} written to {0} (replay: mcl run --mock --virtual-time {root}{mission} --scenario {0})",
                        path.display()
                    ),
                    Err(e) => {
                        eprintln!("error: cannot write `{}`: {e}", path.display());
                        result = Err(());
                    }
                }
            }
            Err(why) => eprintln!("warning: no scenario replays the counterexample of {what}: {why}"),
        }
    }
    result
}

/// `OUT-k.toml` for `OUT.toml` (`OUT-k` for a path without extension).
fn numbered(out: &Path, k: usize) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
    let name = match out.extension() {
        Some(e) => format!("{stem}-{k}.{}", e.to_string_lossy()),
        None => format!("{stem}-{k}"),
    };
    out.with_file_name(name)
}
