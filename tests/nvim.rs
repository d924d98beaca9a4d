//! End to end with a real editor: headless Neovim (Debian's package) loads
//! the plugin of `editors/nvim`, opens a mission with an error, and we read
//! the diagnostics Neovim received from `mcl lsp`; then it fixes the error in
//! the buffer and the diagnostics must go away.
//!
//! Skipped when `nvim` is not installed, unless `MCL_REQUIRE_NVIM=1` (CI sets
//! it and installs Neovim).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn neovim_receives_the_servers_diagnostics() {
    if !mcl_testutil::have_tool("nvim", mcl_testutil::runs("nvim", &["--version"]), "apt-get install neovim") {
        return;
    }
    let root = root();
    let mcl = PathBuf::from(env!("CARGO_BIN_EXE_mcl"));
    let bin_dir = mcl.parent().unwrap();
    let path = format!("{}:{}", bin_dir.display(), std::env::var("PATH").unwrap_or_default());
    let tmp = std::env::temp_dir().join(format!("mcl-nvim-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let out = tmp.join("diagnostics.json");
    let _ = std::fs::remove_file(&out);

    let file = root.join("tests/nvim/errors.mcl");
    let mut child = Command::new("nvim")
        .args(["--headless", "--clean", "-n", "-i", "NONE", "-u"])
        .arg(root.join("tests/nvim/driver.lua"))
        .arg(&file)
        .env("PATH", path)
        .env("MCL_NVIM_OUT", &out)
        .env("MCL_NVIM_PLUGIN", root.join("editors/nvim"))
        .env("XDG_STATE_HOME", tmp.join("state"))
        .env("XDG_DATA_HOME", tmp.join("data"))
        .env("XDG_CONFIG_HOME", tmp.join("config"))
        .env("XDG_CACHE_HOME", tmp.join("cache"))
        .current_dir(&root)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start nvim");
    // The driver waits at most 60 s for each step; a hung editor is a failure.
    let deadline = Instant::now() + Duration::from_secs(180);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "nvim exited with {status}");
            break;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("nvim did not finish");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let text = std::fs::read_to_string(&out).unwrap_or_else(|e| {
        let mut err = String::new();
        use std::io::Read;
        child.stderr.take().unwrap().read_to_string(&mut err).ok();
        panic!("no output from the driver ({e}); nvim stderr:\n{err}")
    });
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    eprintln!("{v:#}");
    check(&v, &file);
    let _ = std::fs::remove_dir_all(&tmp);
}

fn check(v: &serde_json::Value, file: &Path) {
    assert_eq!(v["filetype"], "mcl", "filetype detection of {}", file.display());
    assert!(v["clients"].as_array().unwrap().iter().any(|c| c == "mcl"), "the mcl server is attached: {v}");
    assert_eq!(v["timed_out"], false, "no diagnostics arrived: {v}");
    let diags = v["diagnostics"].as_array().unwrap();
    assert_eq!(diags.len(), 1, "{v}");
    let d = &diags[0];
    assert_eq!(d["code"], "E0101");
    assert_eq!(d["lnum"], 5, "0-based line of `Surfaec()`");
    assert_eq!(d["col"], 4);
    assert_eq!(d["severity"], 1, "an error");
    assert!(d["message"].as_str().unwrap().contains("Surfaec"), "{d}");
    assert_eq!(v["cleared_after_fix"], true, "fixing the typo in the buffer clears the diagnostic: {v}");
}
