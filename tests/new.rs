//! `mcl new NAME` through the binary: the project it writes is clean for
//! `mcl check` and `mcl fmt --check`, runs ok against the mock vehicle with
//! and without its scenario, and compiles; and the refusals (a folder that
//! is not empty, an invalid name), with exit status 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty folder for one test.
fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mcl-new-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn mcl(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcl")).args(args).current_dir(dir).output().expect("run mcl")
}

fn out(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

#[test]
fn a_new_project_checks_formats_runs_and_compiles() {
    let dir = tmp("project");
    let o = mcl(&dir, &["new", "dive"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    let project = dir.join("dive");
    for f in ["vehicle.mcl", "mission.mcl", "scenario.toml", "README.md"] {
        let text = std::fs::read_to_string(project.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(!text.contains("{{"), "{f}: a placeholder is left: {text}");
    }
    let readme = std::fs::read_to_string(project.join("README.md")).unwrap();
    assert!(readme.starts_with("# dive\n"), "{readme}");
    for command in ["mcl check", "mcl fmt", "--virtual-time", "mcl compile", "--aac", "mcl mock-aac", "mcl_aac.py"] {
        assert!(readme.contains(command), "the README does not mention `{command}`");
    }

    let o = mcl(&project, &["check", "--color", "never", "."]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout), "checked 2 files: 0 errors, 0 warnings\n", "{}", out(&o));

    let o = mcl(&project, &["fmt", "--check", "."]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(o.stdout.is_empty(), "{}", out(&o));

    for extra in [&[][..], &["--scenario", "scenario.toml"][..]] {
        let mut args = vec!["run", "--mock", "mission.mcl", "--virtual-time"];
        args.extend_from_slice(extra);
        let o = mcl(&project, &args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", out(&o));
        let text = out(&o);
        assert!(text.contains("MISSION OK"), "{args:?}: {text}");
        assert!(!text.contains("warning"), "{args:?}: {text}");
    }

    // The scenario's alarm, uncommented, runs the monitor's surfacing.
    let scenario = std::fs::read_to_string(project.join("scenario.toml")).unwrap();
    let alarm =
        scenario.replace("# [[events]]", "[[events]]").replace("# at = ", "at = ").replace("# event = ", "event = ");
    assert_ne!(alarm, scenario, "the scenario has a commented-out alarm");
    std::fs::write(project.join("alarm.toml"), alarm).unwrap();
    let o = mcl(&project, &["run", "--mock", "mission.mcl", "--virtual-time", "--scenario", "alarm.toml"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(out(&o).contains("eventAlarmOk"), "{}", out(&o));

    let o = mcl(&project, &["compile", "mission.mcl", "-o", "mission.pnml", "--dot", "mission.dot"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(std::fs::read_to_string(project.join("mission.pnml")).unwrap().contains("<pnml"));
    assert!(project.join("mission.dot").is_file());
}

#[test]
fn an_empty_folder_is_filled_and_a_path_names_the_project() {
    let dir = tmp("paths");
    std::fs::create_dir_all(dir.join("missions/empty")).unwrap();
    let o = mcl(&dir, &["new", "missions/empty"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    assert!(dir.join("missions/empty/mission.mcl").is_file());
    let o = mcl(&dir, &["new", "deep/er/survey_2"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    let readme = std::fs::read_to_string(dir.join("deep/er/survey_2/README.md")).unwrap();
    assert!(readme.starts_with("# survey_2\n"), "{readme}");
}

#[test]
fn a_folder_that_is_not_empty_is_refused() {
    let dir = tmp("refuse");
    std::fs::create_dir_all(dir.join("taken")).unwrap();
    std::fs::write(dir.join("taken/notes.txt"), "mine").unwrap();
    let o = mcl(&dir, &["new", "taken"]);
    assert_eq!(o.status.code(), Some(2), "{}", out(&o));
    assert!(out(&o).contains("already exists and is not empty"), "{}", out(&o));
    assert!(!dir.join("taken/mission.mcl").exists(), "nothing is written");
    assert_eq!(std::fs::read_to_string(dir.join("taken/notes.txt")).unwrap(), "mine");

    // A file of that name is refused too.
    std::fs::write(dir.join("file"), "x").unwrap();
    let o = mcl(&dir, &["new", "file"]);
    assert_eq!(o.status.code(), Some(2), "{}", out(&o));
    assert_eq!(std::fs::read_to_string(dir.join("file")).unwrap(), "x");
}

#[test]
fn invalid_names_are_refused() {
    let dir = tmp("names");
    for name in ["2fast", "my mission", "-x", "née", "a.b", ".", "..", "/"] {
        let o = mcl(&dir, &["new", name]);
        assert_eq!(o.status.code(), Some(2), "{name:?}: {}", out(&o));
        assert!(out(&o).starts_with("error: "), "{name:?}: {}", out(&o));
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing is created");
    // No name at all is a usage error.
    let o = mcl(&dir, &["new"]);
    assert_eq!(o.status.code(), Some(2), "{}", out(&o));
}

#[test]
fn the_templates_are_formatted_and_clean() {
    // The files `mcl new` writes are the templates of src/cmd/new/ with the
    // project's name in their comments: the templates themselves pass too.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let o = mcl(&root, &["fmt", "--check", "src/cmd/new"]);
    assert_eq!(o.status.code(), Some(0), "{}", out(&o));
    let o = mcl(&root, &["check", "--color", "never", "src/cmd/new"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "checked 2 files: 0 errors, 0 warnings\n", "{}", out(&o));
}
