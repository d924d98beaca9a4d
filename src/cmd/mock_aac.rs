//! `mcl mock-aac`: the mock vehicle as its own process, behind the real AAC
//! protocol over TCP (`docs/aac-protocol.md`), for `mcl run --aac`.
//!
//! Each session (one run of one mission, named in the player's `hello`) gets
//! a fresh [`MockVehicle`] for that mission's net, answering by the
//! scenario, in real time. With `--state FILE`, every executed action is
//! saved before it is acknowledged and the sessions are restored at start:
//! a killed and restarted mock-aac neither forgets nor repeats an action.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use mcl_runtime::mock::MockVehicle;
use mcl_runtime::scenario::Scenario;
use mcl_runtime::tcp::{serve_vehicle, LogLevel, ServeOptions, SessionKey, Vehicle, VehicleOptions};

use super::run::load_missions;

/// Options of `mcl mock-aac`.
#[derive(Debug)]
pub struct Options {
    pub net: PathBuf,
    pub scenario: Option<PathBuf>,
    pub listen: String,
    pub token: Option<String>,
    pub speed: f64,
    pub state: Option<PathBuf>,
    pub seed: Option<u64>,
    pub timeout: f64,
    pub quiet: bool,
}

fn is_loopback(addr: &str) -> bool {
    let host = addr.rsplit_once(':').map_or(addr, |(h, _)| h).trim_start_matches('[').trim_end_matches(']');
    host == "localhost" || host.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

pub fn run(o: Options) -> u8 {
    if !(o.speed.is_finite() && o.speed > 0.0) {
        eprintln!("error: --speed must be a positive number");
        return 2;
    }
    if !(o.timeout.is_finite() && o.timeout > 0.0) {
        eprintln!("error: --timeout must be a positive number of seconds");
        return 2;
    }
    let missions = match load_missions(&o.net) {
        Ok(m) if m.is_empty() => {
            eprintln!("error: `{}` defines no mission", o.net.display());
            return 2;
        }
        Ok(m) => m,
        Err(code) => return code,
    };
    let scenario = match &o.scenario {
        Some(p) => match Scenario::load(p) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
            }
        },
        None => Scenario::default(),
    };
    let seed = o.seed.or(scenario.seed).unwrap_or(0);
    if !is_loopback(&o.listen) && o.token.is_none() {
        eprintln!("warning: listening on `{}`, not a loopback address, without --token: anyone who reaches it can command the vehicle", o.listen);
    }
    let names: Vec<String> = missions.iter().map(|m| m.name.clone()).collect();
    let nets: Arc<Vec<(String, mcl_net::Net)>> = Arc::new(missions.into_iter().map(|m| (m.name, m.net)).collect());
    let make = move |key: &SessionKey| -> Option<Box<dyn Vehicle>> {
        let net = match nets.iter().find(|(n, _)| *n == key.mission) {
            Some((_, net)) => net,
            None if nets.len() == 1 => {
                eprintln!(
                    "mock-aac: the player asks for mission `{}`; serving `{}`, the only mission of the file",
                    key.mission, nets[0].0
                );
                &nets[0].1
            }
            None => {
                eprintln!("mock-aac: no mission `{}` in the file; its actions will be refused", key.mission);
                return None;
            }
        };
        Some(Box::new(MockVehicle::from_net(net, scenario.clone(), seed)))
    };
    let level = if o.quiet { LogLevel::Info } else { LogLevel::Messages };
    let serve = ServeOptions {
        token: o.token.clone(),
        timeout: std::time::Duration::from_secs_f64(o.timeout),
        log: level,
        name: concat!("mcl-mock-aac/", env!("CARGO_PKG_VERSION")).into(),
        ..ServeOptions::default()
    };
    let vehicle = VehicleOptions { speed: o.speed, state: o.state.clone(), log: level, ..VehicleOptions::default() };
    let rt = match tokio::runtime::Builder::new_current_thread().enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the runtime: {e}");
            return 2;
        }
    };
    rt.block_on(async move {
        let listener = match tokio::net::TcpListener::bind(&o.listen).await {
            Ok(l) => l,
            Err(e) => {
                eprintln!("error: cannot listen on `{}`: {e}", o.listen);
                return 2;
            }
        };
        let addr = listener.local_addr().map(|a| a.to_string()).unwrap_or_else(|_| o.listen.clone());
        // The first line of standard output is for scripts (and tests) that
        // listen on port 0.
        println!("listening on {addr}");
        let _ = std::io::stdout().flush();
        eprintln!(
            "mock-aac: serving {} ({}) on {addr}, speed {}, {}{}",
            o.net.display(),
            names.join(", "),
            o.speed,
            if o.token.is_some() { "token required" } else { "no token" },
            o.state.as_ref().map(|p| format!(", state in {}", p.display())).unwrap_or_default()
        );
        match serve_vehicle(listener, serve, vehicle, make).await {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                2
            }
        }
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn loopback() {
        assert!(super::is_loopback("127.0.0.1:7010"));
        assert!(super::is_loopback("[::1]:7010"));
        assert!(super::is_loopback("localhost:1"));
        assert!(!super::is_loopback("0.0.0.0:7010"));
        assert!(!super::is_loopback("192.168.1.2:7010"));
    }
}
