//! `mcl chronogram`: an SVG timeline of a trace written by `mcl run --trace`.

use std::path::Path;

pub fn run(trace: &Path, output: &Path, mission: Option<&str>) -> u8 {
    let records = match mcl_runtime::trace::read_trace(trace) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let records: Vec<_> = match mission {
        Some(m) => records.into_iter().filter(|r| r.mission.as_deref() == Some(m)).collect(),
        None => records,
    };
    if records.is_empty() {
        eprintln!(
            "error: `{}` holds no record{}",
            trace.display(),
            mission.map(|m| format!(" of mission `{m}`")).unwrap_or_default()
        );
        return 2;
    }
    let svg = mcl_runtime::chronogram::render(&records, &mcl_runtime::chronogram::Options::default());
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        let _ = std::fs::create_dir_all(dir);
    }
    match std::fs::write(output, svg) {
        Ok(()) => {
            eprintln!("wrote {}", output.display());
            0
        }
        Err(e) => {
            eprintln!("error: cannot write `{}`: {e}", output.display());
            2
        }
    }
}
