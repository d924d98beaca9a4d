//! `mcl compile`: missions to PNML (and Graphviz).

use mcl_compiler::compile::{compile_file, dot::to_dot, CompileError};
use mcl_compiler::diagnostics::render_human;
use mcl_compiler::{check_file, Database, Db};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Options of `mcl compile`.
pub struct Options<'a> {
    pub file: &'a Path,
    pub output: Option<&'a Path>,
    pub dot: Option<&'a Path>,
    pub out_dir: Option<&'a Path>,
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| format!("cannot create `{}`: {e}", parent.display()))?;
    }
    std::fs::write(path, text).map_err(|e| format!("cannot write `{}`: {e}", path.display()))
}

/// A file name for a mission: its name, with characters outside
/// `[A-Za-z0-9_-]` replaced by `_`.
pub fn file_stem(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

pub fn run(o: Options<'_>) -> u8 {
    if !o.file.is_file() {
        eprintln!("error: no such file: `{}`", o.file.display());
        return 2;
    }
    let db = Database::new();
    let file = db.file(o.file);
    if file.text(&db).is_none() {
        eprintln!("error: cannot read `{}` (is it UTF-8 text?)", o.file.display());
        return 2;
    }
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
    let result = (|| -> Result<(), String> {
        if let Some(dir) = o.out_dir {
            let mut written: Vec<PathBuf> = Vec::new();
            for (i, m) in missions.iter().enumerate() {
                let stem = if m.name == "mission" && missions.len() > 1 {
                    format!("mission{}", i + 1)
                } else {
                    file_stem(&m.name)
                };
                let pnml = mcl_net::write_pnml(&m.net).map_err(|e| e.to_string())?;
                let path = dir.join(format!("{stem}.pnml"));
                write(&path, &pnml)?;
                written.push(path);
                if o.dot.is_some() {
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
        let pnml = mcl_net::write_pnml(&m.net).map_err(|e| e.to_string())?;
        match o.output {
            Some(p) => {
                write(p, &pnml)?;
                eprintln!(
                    "wrote {} ({} places, {} transitions)",
                    p.display(),
                    m.net.place_count(),
                    m.net.transition_count()
                );
            }
            None if o.dot.is_none() => print!("{pnml}"),
            None => {}
        }
        if let Some(d) = o.dot {
            write(d, &to_dot(&m.net))?;
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
