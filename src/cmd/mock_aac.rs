//! `mcl mock-aac`: the mock vehicle as its own process, behind the real AAC
//! protocol over TCP (`docs/aac-protocol.md`), for `mcl run --aac`.
//!
//! Each session (one run of one mission, named in the player's `hello`) gets
//! a fresh [`MockVehicle`] for that mission's net, answering by the
//! scenario, in real time. With `--state FILE`, every executed action is
//! saved before it is acknowledged and the sessions are restored at start:
//! a killed and restarted mock-aac neither forgets nor repeats an action.
//!
//! With `--plan FILE.mcl` it serves the vehicle of a planned mission
//! (`mcl plan FILE.mcl --run --aac`): every session gets one mock whose
//! tables are those of all the missions of the operators file, with the call
//! sites numbered as the planner's run numbers them
//! ([`mcl_plan::run::Missions::mock_tables`]).

use std::collections::HashMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use mcl_runtime::mock::{CallInfo, MockVehicle, TaskEvents};
use mcl_runtime::scenario::Scenario;
use mcl_runtime::tcp::{serve_vehicle, LogLevel, ServeOptions, SessionKey, Vehicle, VehicleOptions};

use super::run::load_missions;

/// Options of `mcl mock-aac`.
#[derive(Debug)]
pub struct Options {
    /// The missions (exactly one of `net` and `plan`).
    pub net: Option<PathBuf>,
    /// The mission operators of a planned mission.
    pub plan: Option<PathBuf>,
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
    let served = match (&o.net, &o.plan) {
        (Some(net), None) => match load_missions(net, false) {
            Ok(m) if m.is_empty() => {
                eprintln!("error: `{}` defines no mission", net.display());
                return 2;
            }
            Ok(m) => Served::Nets(m.into_iter().map(|m| (m.name, m.net)).collect()),
            Err(code) => return code,
        },
        (None, Some(ops)) => match mcl_plan::run::Missions::load(ops) {
            Ok(m) => {
                let (tasks, calls) = m.mock_tables();
                Served::Plan(tasks, calls)
            }
            Err(e) => {
                // Rendered diagnostics (if any), then the summary line.
                match e.trim_end().rsplit_once('\n') {
                    Some((diags, last)) => eprintln!("{diags}\nerror: {last}"),
                    None => eprintln!("error: {e}"),
                }
                return 2;
            }
        },
        _ => {
            eprintln!("error: give exactly one of --net FILE and --plan FILE.mcl");
            return 2;
        }
    };
    let file = o.net.as_ref().or(o.plan.as_ref()).map(|p| p.display().to_string()).unwrap_or_default();
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
    let names = match &served {
        Served::Nets(nets) => nets.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>().join(", "),
        Served::Plan(..) => "the operators of a planned mission".to_string(),
    };
    let nets: Arc<Vec<(String, mcl_net::Net)>> = Arc::new(match served {
        Served::Nets(nets) => nets,
        Served::Plan(tasks, calls) => {
            let make = move |_: &SessionKey| -> Option<Box<dyn Vehicle>> {
                Some(Box::new(MockVehicle::new(tasks.clone(), calls.clone(), scenario.clone(), seed)))
            };
            return serve(o, &file, &names, make);
        }
    });
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
    serve(o, &file, &names, make)
}

/// What the mock serves: missions by name, or the tables of a plan's operators.
enum Served {
    Nets(Vec<(String, mcl_net::Net)>),
    Plan(HashMap<String, TaskEvents>, HashMap<u32, CallInfo>),
}

/// Listens and serves the vehicles `make` builds.
fn serve<F>(o: Options, file: &str, names: &str, make: F) -> u8
where
    F: FnMut(&SessionKey) -> Option<Box<dyn Vehicle>> + Send + 'static,
{
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
            "mock-aac: serving {file} ({names}) on {addr}, speed {}, {}{}",
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
