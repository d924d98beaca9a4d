//! `mcl new NAME`: a small project to start from, in a new folder: a vehicle
//! file, a mission that imports it, a scenario for the mock vehicle and a
//! README saying how to check, format, run, compile and connect a vehicle.
//! The templates are the files of `src/cmd/new/`; `{{name}}` in them becomes
//! the project's name.

use std::path::Path;

/// The files of a new project: (file name, template).
const FILES: &[(&str, &str)] = &[
    ("vehicle.mcl", include_str!("new/vehicle.mcl")),
    ("mission.mcl", include_str!("new/mission.mcl")),
    ("scenario.toml", include_str!("new/scenario.toml")),
    ("README.md", include_str!("new/README.md")),
];

/// Exit status: 0 when the project is written; 2 when the name is not valid,
/// the folder exists and is not empty, or a file cannot be written.
pub fn run(path: &Path) -> u8 {
    let name = match project_name(path) {
        Ok(n) => n,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    match std::fs::read_dir(path) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                eprintln!("error: `{}` already exists and is not empty; choose another name", path.display());
                return 2;
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => {
            let what = if path.exists() { "is not a folder that can be read" } else { "cannot be read" };
            eprintln!("error: `{}` {what}: {e}", path.display());
            return 2;
        }
    }
    if let Err(e) = std::fs::create_dir_all(path) {
        eprintln!("error: cannot create the folder `{}`: {e}", path.display());
        return 2;
    }
    for (file, template) in FILES {
        let target = path.join(file);
        if let Err(e) = std::fs::write(&target, template.replace("{{name}}", name)) {
            eprintln!("error: cannot write `{}`: {e}", target.display());
            return 2;
        }
    }
    let dir = path.display();
    println!(
        "created the MCL project `{name}` in `{dir}`: {}",
        FILES.iter().map(|f| f.0).collect::<Vec<_>>().join(", ")
    );
    println!();
    println!("    cd {dir}");
    println!("    mcl check .");
    println!("    mcl run --mock mission.mcl --virtual-time --scenario scenario.toml");
    println!();
    println!("README.md says how to format, compile to PNML and connect a vehicle.");
    0
}

/// The project's name: the last part of `path`, which must start with an
/// ASCII letter and hold only ASCII letters, digits, `-` and `_` (it names a
/// folder and appears in the files' comments).
fn project_name(path: &Path) -> Result<&str, String> {
    let Some(name) = path.file_name() else {
        return Err(format!("`{}` does not end with a project name", path.display()));
    };
    let Some(name) = name.to_str() else {
        return Err(format!("the project name `{}` is not valid UTF-8", name.to_string_lossy()));
    };
    let valid = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !valid {
        return Err(format!(
            "`{name}` is not a valid project name: start with a letter, then use letters, digits, `-` and `_`"
        ));
    }
    Ok(name)
}
