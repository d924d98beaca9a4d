//! `mcl zenoh-router`: a Zenoh router (the `zenoh` crate in router mode)
//! for vehicles that meet through one instead of connecting to each other
//! (docs/zenoh.md *Through a router*). Any Zenoh router (`zenohd`) does
//! the same; this one needs no other install.

use std::io::Write;
use std::path::PathBuf;

/// Runs a router listening on `listen` (and connecting to `connect`) until
/// killed, the gateway of one south region per name of `regions` (then of
/// every other peer and client). Prints `zenoh router listening on
/// ENDPOINT...` once it is up.
pub fn run(listen: Vec<String>, connect: Vec<String>, config: Option<PathBuf>, regions: Vec<String>) -> u8 {
    crate::interrupt::install();
    let opts = mcl_zenoh::ZenohOptions {
        mode: mcl_zenoh::Mode::Router,
        connect,
        listen: listen.clone(),
        config_file: config,
        gateway_regions: regions,
        ..Default::default()
    };
    let _node = match mcl_zenoh::Node::open(&opts) {
        Ok(n) => n,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let mut out = std::io::stdout().lock();
    let _ = writeln!(
        out,
        "zenoh router listening on {}",
        if listen.is_empty() { "Zenoh's default endpoint".into() } else { listen.join(", ") }
    );
    let _ = out.flush();
    drop(out);
    loop {
        std::thread::park();
    }
}
