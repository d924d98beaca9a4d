//! A vehicle's side of the AAC protocol over Zenoh, in Rust, with nothing
//! of MCL but the protocol (docs/zenoh.md §3, docs/aac-protocol.md): the
//! trivial vehicle of `clients/python/mcl_aac_zenoh.py`, where every
//! `enable` ends ok after a delay (`XyzPrimitive` answers `eventXyzOk`;
//! `--map PRIMITIVE=EVENT` names another event, `--map PRIMITIVE=` none)
//! and a `disable` before then cancels it.
//!
//! ```sh
//! cargo run -p mcl-zenoh --example aac_vehicle -- --vehicle sparus --listen tcp/127.0.0.1:7447
//! mcl run --zenoh examples/survey.mcl --vehicle-name sparus --zenoh-connect tcp/127.0.0.1:7447
//! ```
//!
//! A real vehicle replaces [`Vehicle::execute`]'s timer with its
//! controllers; the rest (sessions, order, re-sends) stays as it is.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

/// Protocol version spoken.
const VERSION: u64 = 1;
/// Unconfirmed events older than this are published again on a `ping`.
const RESEND_AFTER: Duration = Duration::from_secs(1);

/// What the vehicle is told on its command line.
#[derive(Clone, Debug, Default)]
pub struct VehicleOptions {
    /// The vehicle's name in the keys `mcl/<vehicle>/aac/...`.
    pub vehicle: String,
    /// Zenoh endpoints to connect to.
    pub connect: Vec<String>,
    /// Zenoh endpoints to listen on.
    pub listen: Vec<String>,
    /// Seconds before an `enable` ends ok.
    pub delay: Duration,
    /// Primitive → event that ends its `enable` (empty: it never answers).
    pub map: HashMap<String, String>,
}

/// One run of one mission (docs/aac-protocol.md §4).
struct Session {
    run: String,
    id: String,
    last_seq: u64,
    last_event: u64,
    /// Events not confirmed yet: number, message, when last published.
    outbox: Vec<(u64, Value, Instant)>,
    /// Per task: the `seq` of the enable whose answer is pending.
    pending: HashMap<String, u64>,
}

/// The vehicle: its sessions, and where it publishes.
pub struct Vehicle {
    opts: VehicleOptions,
    zenoh: zenoh::Session,
    sessions: Mutex<HashMap<(String, String), Session>>,
    /// Every action executed, in order (`seq`).
    pub executed: Mutex<Vec<u64>>,
}

/// `XyzPrimitive` → `eventXyzOk` (the naming of examples/vehicle.mcl).
fn default_event(primitive: &str) -> String {
    format!("event{}Ok", primitive.strip_suffix("Primitive").unwrap_or(primitive))
}

impl Vehicle {
    async fn publish(&self, msg: &Value) {
        let ty = msg["type"].as_str().unwrap_or("error");
        let key = format!("mcl/{}/aac/vehicle/{ty}", self.opts.vehicle);
        if let Err(e) = self.zenoh.put(key, msg.to_string()).await {
            eprintln!("cannot publish: {e}");
        }
    }

    async fn error(&self, code: &str, message: String, run: Option<&str>, seq: Option<u64>) {
        eprintln!("{code}: {message}");
        let mut m = json!({"type": "error", "code": code, "message": message});
        if let Some(r) = run {
            m["run"] = json!(r);
        }
        if let Some(s) = seq {
            m["seq"] = json!(s);
        }
        self.publish(&m).await;
    }

    /// One message of the player.
    async fn handle(self: &Arc<Self>, payload: &[u8]) {
        let Ok(msg) = serde_json::from_slice::<Value>(payload) else {
            return self.error("malformed", "invalid JSON".into(), None, None).await;
        };
        let run = msg["run"].as_str().map(str::to_string);
        match (msg["type"].as_str(), run) {
            (Some("hello"), Some(run)) => self.hello(&msg, run).await,
            (Some("action" | "ping"), Some(run)) => {
                let known = self.sessions.lock().unwrap().values().any(|s| s.run == run);
                if !known {
                    // This vehicle restarted: the player says hello again.
                    let why = format!("no session for run `{run}`: say hello");
                    return self.error("unexpected", why, Some(&run), msg["seq"].as_u64()).await;
                }
                if msg["type"] == "action" {
                    self.action(&msg, &run).await
                } else {
                    self.ping(&msg, &run).await
                }
            }
            _ => self.error("malformed", "a player message has `type` and `run`".into(), None, None).await,
        }
    }

    async fn hello(&self, msg: &Value, run: String) {
        if msg["version"].as_u64() != Some(VERSION) {
            let why = format!("this vehicle speaks protocol version {VERSION}");
            return self.error("version", why, Some(&run), None).await;
        }
        let mission = msg["mission"].as_str().unwrap_or("").to_string();
        let (welcome, again) = {
            let mut sessions = self.sessions.lock().unwrap();
            let s = sessions.entry((mission, run.clone())).or_insert_with(|| Session {
                run: run.clone(),
                id: new_session_id(),
                last_seq: 0,
                last_event: 0,
                outbox: Vec::new(),
                pending: HashMap::new(),
            });
            // What the player has handled in this session; everything when
            // it speaks of another one.
            let handled = if msg["session"].as_str() == Some(s.id.as_str()) {
                msg["last_event"].as_u64().unwrap_or(0)
            } else {
                0
            };
            s.outbox.retain(|(n, _, _)| *n > handled);
            let now = Instant::now();
            let again: Vec<Value> = s.outbox.iter_mut().map(|(_, m, at)| (*at = now, m.clone()).1).collect();
            let welcome = json!({"type": "welcome", "version": VERSION, "last_seq": s.last_seq,
                "last_event": s.last_event, "session": s.id, "aac": "aac_vehicle.rs/1", "run": run});
            (welcome, again)
        };
        self.publish(&welcome).await;
        for m in again {
            self.publish(&m).await;
        }
    }

    async fn action(self: &Arc<Self>, msg: &Value, run: &str) {
        let Some(seq) = msg["seq"].as_u64() else {
            return self.error("malformed", "an action has a `seq`".into(), Some(run), None).await;
        };
        let Some((id, last)) =
            self.sessions.lock().unwrap().values().find(|s| s.run == run).map(|s| (s.id.clone(), s.last_seq))
        else {
            return;
        };
        let ack = json!({"type": "ack", "seq": seq, "run": run, "session": id});
        if seq <= last {
            // Already executed: acknowledged again, not executed.
            return self.publish(&ack).await;
        }
        if seq != last + 1 {
            // After a gap: its re-send comes after the missing one.
            return;
        }
        self.execute(msg, run, seq);
        self.executed.lock().unwrap().push(seq);
        eprintln!("executed seq={seq} {} ({} {})", msg["action"], msg["primitive"], msg["command"]);
        self.publish(&ack).await;
    }

    /// Carries out action `seq`: an enable answers after the delay unless
    /// disabled (or enabled again) meanwhile.
    fn execute(self: &Arc<Self>, msg: &Value, run: &str, seq: u64) {
        let primitive = msg["primitive"].as_str().unwrap_or("");
        let task = msg["task"].as_str().unwrap_or(primitive).to_string();
        let event = self.opts.map.get(primitive).cloned().unwrap_or_else(|| default_event(primitive));
        {
            let mut sessions = self.sessions.lock().unwrap();
            let Some(s) = sessions.values_mut().find(|s| s.run == run) else { return };
            s.last_seq = seq;
            s.pending.remove(&task);
            if msg["command"] != "enable" || event.is_empty() {
                return;
            }
            s.pending.insert(task.clone(), seq);
        }
        let (me, run, delay) = (self.clone(), run.to_string(), self.opts.delay);
        tokio::spawn(async move {
            tokio::time::sleep(delay).await;
            let m = {
                let mut sessions = me.sessions.lock().unwrap();
                let Some(s) = sessions.values_mut().find(|s| s.run == run) else { return };
                if s.pending.get(&task) != Some(&seq) {
                    return; // disabled since: say nothing
                }
                s.pending.remove(&task);
                s.last_event += 1;
                let m = json!({"type": "event", "event": event, "activation": seq, "n": s.last_event,
                    "run": run, "session": s.id});
                s.outbox.push((s.last_event, m.clone(), Instant::now()));
                m
            };
            me.publish(&m).await;
        });
    }

    async fn ping(&self, msg: &Value, run: &str) {
        let (pong, again) = {
            let mut sessions = self.sessions.lock().unwrap();
            let Some(s) = sessions.values_mut().find(|s| s.run == run) else { return };
            if let Some(last) = msg["last_event"].as_u64() {
                s.outbox.retain(|(n, _, _)| *n > last);
            }
            let now = Instant::now();
            let again: Vec<Value> = s
                .outbox
                .iter_mut()
                .filter(|(_, _, at)| now.duration_since(*at) >= RESEND_AFTER)
                .map(|(_, m, at)| (*at = now, m.clone()).1)
                .collect();
            (json!({"type": "pong", "run": run, "session": s.id}), again)
        };
        self.publish(&pong).await;
        for m in again {
            self.publish(&m).await;
        }
    }
}

/// A session id: new at each start of this vehicle (the player then knows
/// it restarted).
fn new_session_id() -> String {
    let t = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    format!("{t:x}-{:x}", std::process::id())
}

/// Opens the Zenoh session and serves the player's messages until the
/// session ends. Returns the vehicle once it subscribes (the serving goes
/// on in a task of the current runtime).
pub async fn start(opts: VehicleOptions) -> Result<Arc<Vehicle>, String> {
    let mut config = zenoh::Config::default();
    let mut set = |key: &str, value: String| config.insert_json5(key, &value).map_err(|e| format!("{key}: {e}"));
    set("mode", "\"peer\"".into())?;
    if !opts.connect.is_empty() {
        set("connect/endpoints", json!(opts.connect).to_string())?;
    }
    if !opts.listen.is_empty() {
        set("listen/endpoints", json!(opts.listen).to_string())?;
    }
    if !(opts.connect.is_empty() && opts.listen.is_empty()) {
        set("scouting/multicast/enabled", "false".into())?;
    }
    let zenoh = zenoh::open(config).await.map_err(|e| format!("cannot open Zenoh: {e}"))?;
    let sub = zenoh
        .declare_subscriber(format!("mcl/{}/aac/player/*", opts.vehicle))
        .await
        .map_err(|e| format!("cannot subscribe: {e}"))?;
    let vehicle =
        Arc::new(Vehicle { opts, zenoh, sessions: Mutex::new(HashMap::new()), executed: Mutex::new(Vec::new()) });
    let v = vehicle.clone();
    tokio::spawn(async move {
        // One player message at a time, in the order they come.
        while let Ok(sample) = sub.recv_async().await {
            v.handle(&sample.payload().to_bytes()).await;
        }
    });
    Ok(vehicle)
}

/// `--vehicle NAME [--connect E]... [--listen E]... [--delay SECONDS] [--map P=EVENT]...`
#[allow(dead_code)]
fn options(args: &[String]) -> Result<VehicleOptions, String> {
    let mut o = VehicleOptions { delay: Duration::from_millis(100), ..Default::default() };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().cloned().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--vehicle" => o.vehicle = value()?,
            "--connect" => o.connect.push(value()?),
            "--listen" => o.listen.push(value()?),
            "--delay" => {
                let s: f64 = value()?.parse().map_err(|e| format!("--delay: {e}"))?;
                o.delay = Duration::try_from_secs_f64(s).map_err(|e| format!("--delay: {e}"))?;
            }
            "--map" => {
                let m = value()?;
                let (p, e) = m.split_once('=').ok_or(format!("--map `{m}`: expected PRIMITIVE=EVENT"))?;
                o.map.insert(p.to_string(), e.to_string());
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if o.vehicle.is_empty() || o.vehicle.contains(['/', '*', '$', '?', '#']) {
        return Err("--vehicle NAME (a chunk of a Zenoh key) is required".into());
    }
    Ok(o)
}

#[allow(dead_code)]
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opts = match options(&args) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().expect("a tokio runtime");
    rt.block_on(async {
        let where_ = [opts.listen.clone(), opts.connect.clone()].concat().join(", ");
        if let Err(e) = start(opts).await {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
        println!("listening on {}", if where_.is_empty() { "zenoh".into() } else { where_ });
        std::future::pending::<()>().await
    })
}
