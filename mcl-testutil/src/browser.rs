//! A real browser for tests of web pages and pictures: headless Chromium.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The browser: `MCL_CHROMIUM`, else Debian's `/usr/bin/chromium`.
pub fn chromium() -> PathBuf {
    std::env::var_os("MCL_CHROMIUM").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"))
}

/// Whether a test that needs Chromium goes on ([`crate::have_tool`] with
/// the tool `chromium`; CI sets `MCL_REQUIRE_CHROMIUM=1`).
#[track_caller]
pub fn have_chromium() -> bool {
    let install = format!("apt-get install chromium, or set MCL_CHROMIUM; {} is absent", chromium().display());
    crate::have_tool("chromium", chromium().exists(), &install)
}

/// Renders `page` (an SVG or HTML file) in headless Chromium at `width` ×
/// `height` and writes a PNG screenshot to `png`, with a fresh profile in
/// `profile`. False when the browser failed.
pub fn screenshot(page: &Path, png: &Path, profile: &Path, (width, height): (u32, u32)) -> bool {
    let status = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--screenshot={}", png.display()),
            &format!("--window-size={width},{height}"),
            &format!("file://{}", page.display()),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    status.is_ok_and(|s| s.success())
}

/// Width, height and file size of a PNG file (None: not a PNG).
pub fn png_size(path: &Path) -> Option<(u32, u32, u64)> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() < 24 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let w = u32::from_be_bytes(bytes[16..20].try_into().ok()?);
    let h = u32::from_be_bytes(bytes[20..24].try_into().ok()?);
    Some((w, h, bytes.len() as u64))
}

/// Size in bytes of the screenshot of a blank white page of that size
/// (written under `dir`), to tell a drawn page from an empty one: a
/// drawing compresses worse.
pub fn blank_png_size(dir: &Path, (width, height): (u32, u32)) -> Option<u64> {
    std::fs::create_dir_all(dir).ok()?;
    let svg = dir.join("blank.svg");
    let svg_text = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}"><rect width="{width}" height="{height}" fill="#fff"/></svg>"##
    );
    std::fs::write(&svg, svg_text).ok()?;
    let png = dir.join("blank.png");
    if !screenshot(&svg, &png, &dir.join("chromium-blank"), (width, height)) {
        return None;
    }
    png_size(&png).map(|(_, _, s)| s)
}
