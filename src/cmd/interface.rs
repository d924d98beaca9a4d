//! `mcl interface`: the vehicle file as a contract — per primitive, the
//! commands the player sends (parameters in order) and the events the
//! vehicle sends with their roles (`mcl_compiler::interface`), as Markdown
//! for people or JSON for tools.

use mcl_compiler::diagnostics::render_human;
use mcl_compiler::interface::{to_markdown, vehicle_interface};
use mcl_compiler::{check_file, Database};
use std::io::IsTerminal;
use std::path::Path;

/// Output formats of `mcl interface`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InterfaceFormat {
    Markdown,
    Json,
}

/// Exit status: 0 with the interface on standard output, 1 when the program
/// has errors (they are printed), 2 when the file cannot be read.
pub fn run(path: &Path, format: InterfaceFormat) -> u8 {
    let db = Database::new();
    let file = match super::source_file(&db, path) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let errors: Vec<_> = check_file(&db, file).iter().filter(|d| d.diag.is_error()).cloned().collect();
    if !errors.is_empty() {
        eprint!("{}", render_human(&db, &errors, std::io::stderr().is_terminal()));
        eprintln!("error: `{}` has errors; fix them first", path.display());
        return 1;
    }
    let i = vehicle_interface(&db, file);
    match format {
        InterfaceFormat::Markdown => print!("{}", to_markdown(&i)),
        InterfaceFormat::Json => match serde_json::to_string_pretty(&i) {
            Ok(s) => println!("{s}"),
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        },
    }
    0
}
