//! # mcl-testutil
//!
//! Helpers shared by the workspace's tests (a dev-dependency only).
//!
//! A test that needs an outside tool (python3 and its packages, Neovim,
//! Chromium, ...) asks [`have_tool`] first. Where the tool is missing the
//! test is skipped, saying so, unless `MCL_REQUIRE_<TOOL>=1` is set: then a
//! missing tool is a failure. CI installs its tools and sets those
//! variables (`.ci/run`), so that no test passes there without running.
//!
//! ```no_run
//! use mcl_testutil::{have_tool, runs};
//! if !have_tool("nvim", runs("nvim", &["--version"]), "apt-get install neovim") {
//!     return; // skipped: nvim not found (set MCL_REQUIRE_NVIM=1 to fail instead)
//! }
//! ```

pub mod browser;

use std::ffi::OsStr;
use std::process::{Command, Stdio};

/// The variable that makes `tool` required: `MCL_REQUIRE_` and the tool's
/// name in capitals, other characters than letters and digits as `_`
/// (`python3` gives `MCL_REQUIRE_PYTHON3`).
pub fn require_var(tool: &str) -> String {
    let name: String =
        tool.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_uppercase() } else { '_' }).collect();
    format!("MCL_REQUIRE_{name}")
}

/// Whether `tool` is required: its [`require_var`] is `1`. Unset, empty or
/// `0`, it is not; any other value is a mistake and fails the test (a
/// misspelt `true` must not skip quietly where the tool was meant to be
/// required).
#[track_caller]
pub fn required(tool: &str) -> bool {
    let var = require_var(tool);
    match std::env::var(&var) {
        Ok(v) if v == "1" => true,
        Ok(v) if v.is_empty() || v == "0" => false,
        Ok(v) => panic!("{var}={v:?}: set it to 1 (a missing {tool} fails the test) or 0"),
        Err(_) => false,
    }
}

/// Whether a test that needs `tool` goes on: `true` when the tool was
/// `found`. When it was not, fails the test if the tool is [`required`];
/// otherwise says on stderr that the test is skipped and how to install the
/// tool (`install`), and returns `false`: the test then returns at once.
#[track_caller]
pub fn have_tool(tool: &str, found: bool, install: &str) -> bool {
    if found {
        return true;
    }
    let var = require_var(tool);
    assert!(!required(tool), "{tool} not found but {var}=1 requires it ({install})");
    eprintln!("skipped: {tool} not found (set {var}=1 to fail instead; {install})");
    false
}

/// Whether `program args...` can be run and exits with success (its output
/// is discarded): the usual probe for [`have_tool`], e.g.
/// `runs("python3", &["-c", "import pm4py"])`.
pub fn runs(program: impl AsRef<OsStr>, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_variable_is_named_after_the_tool() {
        assert_eq!(require_var("nvim"), "MCL_REQUIRE_NVIM");
        assert_eq!(require_var("python3"), "MCL_REQUIRE_PYTHON3");
        assert_eq!(require_var("tree-sitter"), "MCL_REQUIRE_TREE_SITTER");
    }

    #[test]
    fn a_found_tool_goes_on_and_a_missing_one_skips_unless_required() {
        // A tool name no other test uses, so that its variable is ours.
        let tool = "mcl-testutil-probe";
        assert!(have_tool(tool, true, "nothing to install"));
        assert!(!runs("/nonexistent/mcl-testutil-probe", &[]));
        std::env::remove_var(require_var(tool));
        assert!(!have_tool(tool, false, "nothing to install"));
        std::env::set_var(require_var(tool), "1");
        let failed = std::panic::catch_unwind(|| have_tool(tool, false, "nothing to install"));
        std::env::set_var(require_var(tool), "yes");
        let misspelt = std::panic::catch_unwind(|| required(tool));
        std::env::remove_var(require_var(tool));
        assert!(failed.is_err(), "a required tool that is missing fails the test");
        assert!(misspelt.is_err(), "a value other than 0 or 1 fails the test");
    }
}
