//! `mcl compile --link-report FILE`: per constraint and per mission, the
//! most coordination messages a run sends and the bytes each takes, in the
//! compact encoding and as JSON (`mcl_coord::link_report`,
//! docs/acoustic.md); `--frame-bytes N` makes a message that does not fit
//! an N-byte frame an error (E0410) at each constraint.

use std::io::IsTerminal;
use std::path::Path;

use mcl_compiler::diagnostics::{render_human, to_json};
use mcl_compiler::{Database, FileDiagnostic};

use crate::Format;

/// Prints the link report of `path`; exit status 0, 1 when a message does
/// not fit `frame_bytes` or the program has errors, 2 on a usage error.
pub fn run(path: &Path, format: Format, frame_bytes: Option<u64>) -> u8 {
    let db = Database::new();
    let file = match super::source_file(&db, path) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let (missions, constraints) = match mcl_coord::source::load(&db, file) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let vehicles = match super::compile::vehicle_nets(&db, file, 1, false) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let report = mcl_coord::link_report::link_report(&missions, &constraints, &vehicles);
    let diags: Vec<FileDiagnostic> = frame_bytes
        .map(|n| report.frame_diagnostics(n))
        .unwrap_or_default()
        .into_iter()
        .map(|diag| FileDiagnostic { file, diag })
        .collect();
    match format {
        Format::Human => {
            print!("{}", report.to_text());
            if !diags.is_empty() {
                eprint!("{}", render_human(&db, &diags, std::io::stderr().is_terminal()));
            }
        }
        Format::Json => {
            let mut v = serde_json::to_value(&report).unwrap_or_default();
            v["diagnostics"] = diags.iter().map(|d| to_json(&db, d)).collect();
            println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
        }
    }
    u8::from(!diags.is_empty())
}
