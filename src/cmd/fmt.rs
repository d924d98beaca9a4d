//! `mcl fmt`: rewrites MCL files in the canonical style
//! (`mcl_syntax::format`), or with `--check` lists those that are not in it.
//! `mcl fmt -` formats standard input to standard output (for editors).

use mcl_compiler::diagnostics::{display_path, render_human, FileDiagnostic};
use mcl_compiler::Database;
use mcl_syntax::format::{format, FormatError};
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};

/// Exit status: 0 when every file is (now) formatted; 1 with `--check` when
/// some file would change; 2 on a usage or I/O error or a file with syntax
/// errors (its errors are printed and the file is left alone).
pub fn run(paths: &[PathBuf], check: bool) -> u8 {
    if paths.iter().any(|p| p.as_os_str() == "-") {
        if paths.len() != 1 {
            eprintln!("error: `-` (standard input) cannot be combined with other paths");
            return 2;
        }
        return stdin(check);
    }
    let files = match super::collect_mcl_files(paths) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let mut failed = false;
    let mut changed: Vec<&Path> = Vec::new();
    for path in &files {
        let text = match read(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {e}");
                failed = true;
                continue;
            }
        };
        match format(&text) {
            Ok(out) if out == text => {}
            Ok(out) => {
                changed.push(path);
                if !check {
                    if let Err(e) = std::fs::write(path, out) {
                        eprintln!("error: cannot write `{}`: {e}", path.display());
                        failed = true;
                    }
                }
            }
            Err(e) => {
                report(path, &text, &e);
                failed = true;
            }
        }
    }
    let n = files.len();
    let plural = |k: usize| if k == 1 { "" } else { "s" };
    if check {
        let mut out = std::io::stdout().lock();
        for p in &changed {
            let _ = writeln!(out, "{}", display_path(p));
        }
        if !changed.is_empty() {
            eprintln!("{} of {n} file{} would be reformatted (run `mcl fmt` on them)", changed.len(), plural(n));
        }
    } else if !changed.is_empty() {
        eprintln!("reformatted {} of {n} file{}", changed.len(), plural(n));
    }
    if failed {
        2
    } else {
        u8::from(check && !changed.is_empty())
    }
}

fn read(path: &Path) -> Result<String, mcl_net::input::ReadError> {
    mcl_net::input::read_source(path)
}

fn stdin(check: bool) -> u8 {
    let limit = mcl_net::input::MAX_SOURCE_BYTES;
    let mut text = String::new();
    if let Err(e) = std::io::stdin().take(limit + 1).read_to_string(&mut text) {
        eprintln!("error: cannot read standard input: {e}");
        return 2;
    }
    if text.len() as u64 > limit {
        eprintln!("error: cannot read standard input: {}", mcl_net::input::Reason::TooLarge { limit });
        return 2;
    }
    match format(&text) {
        Ok(out) if check => {
            if out == text {
                0
            } else {
                println!("<stdin>");
                1
            }
        }
        Ok(out) => match std::io::stdout().lock().write_all(out.as_bytes()) {
            Ok(()) => 0,
            Err(_) => 2,
        },
        Err(e) => {
            report(Path::new("<stdin>"), &text, &e);
            2
        }
    }
}

/// Prints why `path` was not formatted, with the same reports as `mcl check`.
fn report(path: &Path, text: &str, e: &FormatError) {
    match e {
        FormatError::Syntax(errors) => {
            let mut db = Database::new();
            let file = db.set_text(path, text);
            let diags: Vec<FileDiagnostic> = errors.iter().map(|d| FileDiagnostic { file, diag: d.clone() }).collect();
            let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
            let mut s = render_human(&db, &diags, color);
            let k = errors.len();
            s.push_str(&format!(
                "error: `{}` not formatted: {k} syntax error{}\n",
                display_path(file.path(&db)),
                if k == 1 { "" } else { "s" }
            ));
            let _ = std::io::stderr().lock().write_all(s.as_bytes());
        }
        FormatError::Internal(msg) => {
            eprintln!("error: `{}` not formatted: {msg} (please report this bug)", path.display());
        }
    }
}
