//! One module per subcommand.

pub mod analyze;
pub mod check;
pub mod chronogram;
pub mod compile;
pub mod explain;
pub mod fmt;
pub mod interface;
pub mod link_report;
pub mod lsp;
pub mod mock_aac;
pub mod monitor;
pub mod new;
pub mod plan;
pub mod ros2;
pub mod run;
pub mod sim;
pub mod trace_to_mcap;
pub mod zenoh_router;

use std::path::{Path, PathBuf};

/// The input of an `.mcl` file given on the command line, or the error to
/// print (`cannot read `path`: why`): files are read by `mcl_net::input`.
pub fn source_file(db: &mcl_compiler::Database, path: &Path) -> Result<mcl_compiler::SourceFile, String> {
    use mcl_compiler::Db;
    let f = db.file(path);
    match (f.text(db), f.unreadable(db)) {
        (Some(_), _) => Ok(f),
        (None, Some(why)) => Err(format!("cannot read `{}`: {why}", path.display())),
        (None, None) => Err(format!("cannot read `{}`", path.display())),
    }
}

/// Expands folders into the `*.mcl` files they hold (recursively, sorted,
/// skipping hidden folders and build output). Errors name the missing path.
pub fn collect_mcl_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            walk(p, &mut out).map_err(|e| format!("cannot read folder `{}`: {e}", p.display()))?;
        } else if p.exists() {
            // A device, FIFO or socket too: the reader says why it is refused.
            out.push(p.clone());
        } else {
            return Err(format!("no such file or folder: `{}`", p.display()));
        }
    }
    Ok(out)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let path = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if !name.starts_with('.') && name != "target" && name != "node_modules" {
                walk(&path, out)?;
            }
        } else if path.extension().is_some_and(|x| x == "mcl") {
            out.push(path);
        }
    }
    Ok(())
}
