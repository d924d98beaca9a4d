//! `mcl trace-to-mcap`: a trace written by `mcl run --trace` (or `mcl plan
//! --run --trace`) as an MCAP file for Foxglove (`mcl_mcap`, docs/mcap.md).

use std::path::Path;

/// Exit status: 0 when the file is written, 2 when the trace cannot be read
/// (or has a bad line) or the file cannot be written.
pub fn run(trace: &Path, output: &Path) -> u8 {
    let text = match mcl_net::input::read_text(trace, mcl_net::input::MAX_RECORDS_BYTES) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let file = match create(output) {
        Ok(f) => f,
        Err(code) => return code,
    };
    match mcl_mcap::convert(&text, file) {
        Ok(counts) => {
            let n: u64 = counts.values().sum();
            eprintln!("wrote {} ({n} messages)", output.display());
            0
        }
        Err(mcl_mcap::Error::BadLine { line, message }) => {
            eprintln!("error: {}:{line}: {message}", trace.display());
            let _ = std::fs::remove_file(output);
            2
        }
        Err(e) => {
            eprintln!("error: `{}`: {e}", output.display());
            2
        }
    }
}

/// Creates `path` (and its folder) for an MCAP writer; exit status 2 if it cannot.
pub fn create(path: &Path) -> Result<std::io::BufWriter<std::fs::File>, u8> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        let _ = std::fs::create_dir_all(dir);
    }
    std::fs::File::create(path).map(std::io::BufWriter::new).map_err(|e| {
        eprintln!("error: cannot write `{}`: {e}", path.display());
        2
    })
}
