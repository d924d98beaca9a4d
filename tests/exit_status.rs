//! The one exit-status convention of the README (*Exit statuses, one
//! convention*) across `check`, `interface`, `compile`, `run`, `plan` and
//! `trace-to-mcap`: 0 yes, 1 the answer is no, 2 could not do what was
//! asked, 3 stopped at a limit.

use std::path::PathBuf;
use std::process::Command;

fn code(args: &[&str]) -> Option<i32> {
    Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run mcl")
        .status
        .code()
}

const ERRORS: &str = "tests/ui/e0101_did_you_mean.mcl";
const MISSING: &str = "no/such/file.mcl";

#[test]
fn one_convention_across_commands() {
    let out = std::env::temp_dir().join(format!("mcl-exit-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let pnml = out.join("x.pnml");
    let pnml = pnml.to_str().unwrap();
    // 0: done, and the answer is yes.
    assert_eq!(code(&["check", "examples/survey.mcl"]), Some(0));
    assert_eq!(code(&["compile", "examples/survey.mcl", "-o", pnml]), Some(0));
    assert_eq!(code(&["run", "--mock", "--virtual-time", "-q", "examples/survey.mcl"]), Some(0));
    // 1: the answer is no (the program has errors, the mission failed).
    assert_eq!(code(&["check", ERRORS]), Some(1));
    assert_eq!(code(&["interface", ERRORS]), Some(1));
    assert_eq!(code(&["compile", ERRORS, "-o", pnml]), Some(1));
    let scenario = out.join("fail.toml");
    std::fs::write(&scenario, "[tasks.StopVehicle]\noutcome = \"fail\"\n").unwrap();
    let failing =
        ["run", "--mock", "--virtual-time", "-q", "examples/survey.mcl", "--scenario", scenario.to_str().unwrap()];
    assert_eq!(code(&failing), Some(1), "{failing:?} ends in fail");
    // 2: it could not do what was asked; for run and plan, a program that
    // does not compile is input they cannot use.
    for args in [
        vec!["check", MISSING],
        vec!["interface", MISSING],
        vec!["compile", MISSING, "-o", pnml],
        vec!["run", "--mock", "--virtual-time", "-q", MISSING],
        vec!["run", "--mock", "--virtual-time", "-q", ERRORS],
        vec!["plan", ERRORS],
        vec!["trace-to-mcap", MISSING, "-o", pnml],
        vec!["run", "--mock", "--no-such-option", "examples/survey.mcl"],
    ] {
        assert_eq!(code(&args), Some(2), "{args:?}");
    }
    // 3: stopped at a limit it was given.
    assert_eq!(code(&["run", "--mock", "--virtual-time", "-q", "--time-limit", "12", "examples/survey.mcl"]), Some(3));
    let _ = std::fs::remove_dir_all(PathBuf::from(&out));
}
