//! `mcl check`: diagnostics for files and everything they import, and the
//! coordination analysis of every file with constraints (`mcl_coord::check`).
//! A file that cannot be read (not UTF-8, not a regular file, over 16 MiB)
//! is reported on standard error and the others are checked (exit status 2).

use crate::{ColorChoice, Format};
use mcl_compiler::diagnostics::{render_human, to_json};
use mcl_compiler::{check_file, program, Database, Db, FileDiagnostic, SourceFile};
use mcl_syntax::Severity;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;

pub fn run(paths: &[PathBuf], format: Format, color: ColorChoice) -> u8 {
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
    let errors = diags.iter().filter(|d| d.diag.severity == Severity::Error).count();
    let warnings = diags.iter().filter(|d| d.diag.severity == Severity::Warning).count();
    let mut stdout = std::io::stdout().lock();
    let written = match format {
        Format::Json => {
            let arr: Vec<_> = diags.iter().map(|d| to_json(&db, d)).collect();
            writeln!(stdout, "{}", serde_json::to_string_pretty(&arr).unwrap_or_else(|_| "[]".into()))
        }
        Format::Human => {
            let use_color = match color {
                ColorChoice::Always => true,
                ColorChoice::Never => false,
                ColorChoice::Auto => std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
            };
            let mut s = render_human(&db, &diags, use_color);
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
    if written.is_err() || unreadable > 0 {
        return 2;
    }
    u8::from(errors > 0)
}
