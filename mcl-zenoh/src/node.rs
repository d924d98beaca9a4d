//! One Zenoh session, in a thread of its own.
//!
//! Zenoh's runtime needs tokio's multi-thread scheduler, and `mcl run`
//! drives its vehicles on a current-thread one: a [`Node`] opens the
//! session on a small runtime of its own, and everything else talks to it
//! through channels ([`Node::put`], [`Node::subscribe`]), so that the
//! coordination ends and the AAC link work from any runtime.

use std::path::PathBuf;
use std::sync::mpsc as std_mpsc;
use std::time::Duration;

use tokio::sync::{mpsc, oneshot};
use zenoh::qos::CongestionControl;

/// How this process joins Zenoh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Talks to peers directly, and to routers (Zenoh's default).
    #[default]
    Peer,
    /// Talks only through one router.
    Client,
    /// A router: routes for the peers and clients that connect to it.
    Router,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Peer => "peer",
            Mode::Client => "client",
            Mode::Router => "router",
        }
    }
}

/// The Zenoh options of `mcl run` (`--zenoh-connect`, `--zenoh-listen`,
/// `--zenoh-config`), see docs/zenoh.md *Connecting*.
#[derive(Clone, Debug, Default)]
pub struct ZenohOptions {
    /// Peer (default), client or router.
    pub mode: Mode,
    /// Endpoints to connect to (`tcp/127.0.0.1:7447`).
    pub connect: Vec<String>,
    /// Endpoints to listen on.
    pub listen: Vec<String>,
    /// A Zenoh configuration file (JSON5) to start from.
    pub config_file: Option<PathBuf>,
    /// A peer's or client's region (`--region NAME`): Zenoh's
    /// `region_name`; a peer given no `listen` endpoint then listens
    /// nowhere (a router of the region's name routes for it).
    pub region: Option<String>,
    /// A router's regions (`mcl zenoh-router --region NAME`, repeatable):
    /// its `gateway.south`, one south region per name, then one more for
    /// every other peer and client ([`gateway_south`]).
    pub gateway_regions: Vec<String>,
}

/// A region name is a non-empty run of ASCII letters, digits, `_`, `-`
/// and `.`, at most 32 characters (Zenoh's `RegionName::MAX_LEN`).
pub fn check_region(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name.len() <= 32
        && name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if ok {
        Ok(())
    } else {
        Err(format!("region `{name}`: expected 1 to 32 ASCII letters, digits, `_`, `-` or `.`"))
    }
}

/// The router's `gateway.south` for `regions` (JSON): one south region per
/// name, the peers and clients whose `region_name` it is, in the order
/// given, then one for every other peer and client. Zenoh routes between
/// south regions, never inside one (docs/zenoh.md, *Regions*). Errors on a
/// bad or repeated name.
pub fn gateway_south(regions: &[String]) -> Result<String, String> {
    let mut entries = Vec::new();
    for (i, r) in regions.iter().enumerate() {
        check_region(r)?;
        if regions[..i].contains(r) {
            return Err(format!("region `{r}` given twice"));
        }
        entries.push(serde_json::json!({ "filters": [ { "region_names": [r] } ] }));
    }
    entries.push(serde_json::json!({ "filters": [ { "modes": ["peer", "client"] } ] }));
    Ok(serde_json::Value::Array(entries).to_string())
}

impl ZenohOptions {
    /// The Zenoh configuration: the file's (or Zenoh's defaults), in the
    /// mode asked for, with the endpoints given. When endpoints are given
    /// and no file, multicast scouting is off: the endpoints say where the
    /// others are.
    pub fn config(&self) -> Result<zenoh::Config, String> {
        let mut c = match &self.config_file {
            Some(p) => zenoh::Config::from_file(p).map_err(|e| format!("--zenoh-config `{}`: {e}", p.display()))?,
            None => zenoh::Config::default(),
        };
        let set = |c: &mut zenoh::Config, key: &str, value: String| {
            c.insert_json5(key, &value).map_err(|e| format!("Zenoh configuration `{key}` = {value}: {e}"))
        };
        if self.config_file.is_none() || self.mode != Mode::Peer {
            set(&mut c, "mode", format!("\"{}\"", self.mode.name()))?;
        }
        let json = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        for e in self.connect.iter().chain(&self.listen) {
            check_endpoint(e)?;
        }
        if !self.connect.is_empty() {
            set(&mut c, "connect/endpoints", json(&self.connect))?;
        }
        if !self.listen.is_empty() {
            set(&mut c, "listen/endpoints", json(&self.listen))?;
        }
        if self.config_file.is_none() && !(self.connect.is_empty() && self.listen.is_empty()) {
            set(&mut c, "scouting/multicast/enabled", "false".into())?;
        }
        if let Some(r) = &self.region {
            if self.mode == Mode::Router {
                return Err("a router names its regions (gateway), not its own region".into());
            }
            check_region(r)?;
            set(&mut c, "region_name", serde_json::Value::from(r.as_str()).to_string())?;
            if self.mode == Mode::Peer && self.listen.is_empty() {
                set(&mut c, "listen/endpoints", "[]".into())?;
            }
        }
        if !self.gateway_regions.is_empty() {
            if self.mode != Mode::Router {
                return Err("only a router is the gateway of regions".into());
            }
            // `gateway` holds `south` alone (Zenoh 1.10).
            set(&mut c, "gateway", format!("{{\"south\":{}}}", gateway_south(&self.gateway_regions)?))?;
        }
        Ok(c)
    }
}

/// An endpoint is `PROTOCOL/ADDRESS` (this build has `tcp` only).
fn check_endpoint(e: &str) -> Result<(), String> {
    match e.split_once('/') {
        Some(("tcp", addr)) if !addr.is_empty() => Ok(()),
        Some((proto, _)) if !proto.is_empty() && proto != "tcp" => {
            Err(format!("Zenoh endpoint `{e}`: this build of mcl speaks `tcp/HOST:PORT` only"))
        }
        _ => Err(format!("Zenoh endpoint `{e}`: expected `tcp/HOST:PORT`")),
    }
}

/// A sample received on a subscription: its key and its payload.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Received {
    /// The key it was published on.
    pub key: String,
    /// Its payload.
    pub payload: Vec<u8>,
}

type SubscribeRequest = (String, oneshot::Sender<Result<mpsc::UnboundedReceiver<Received>, String>>);

/// An open Zenoh session (see the [module documentation](self)). Closed,
/// after what was put is sent, when dropped.
pub struct Node {
    handle: tokio::runtime::Handle,
    puts: Option<mpsc::UnboundedSender<(String, Vec<u8>)>>,
    subscribe: mpsc::UnboundedSender<SubscribeRequest>,
    done: std::sync::Mutex<std_mpsc::Receiver<()>>,
}

impl std::fmt::Debug for Node {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Node")
    }
}

impl Node {
    /// Opens a session with `opts` (waits until it is open: listeners
    /// bound; connections to peers and routers go on in the background,
    /// retried while they fail).
    pub fn open(opts: &ZenohOptions) -> Result<Node, String> {
        let config = opts.config()?;
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("zenoh-node")
            .enable_all()
            .build()
            .map_err(|e| format!("cannot start the Zenoh runtime: {e}"))?;
        let handle = rt.handle().clone();
        let (opened_tx, opened_rx) = std_mpsc::channel::<Result<(), String>>();
        let (done_tx, done) = std_mpsc::channel();
        let (puts, mut put_rx) = mpsc::unbounded_channel::<(String, Vec<u8>)>();
        let (subscribe, mut sub_rx) = mpsc::unbounded_channel::<SubscribeRequest>();
        std::thread::Builder::new()
            .name("zenoh-node".into())
            .spawn(move || {
                rt.block_on(async move {
                    let session = match zenoh::open(config).await {
                        Ok(s) => s,
                        Err(e) => {
                            let _ = opened_tx.send(Err(format!("cannot open the Zenoh session: {e}")));
                            return;
                        }
                    };
                    let _ = opened_tx.send(Ok(()));
                    let s = session.clone();
                    tokio::spawn(async move {
                        while let Some((key, reply)) = sub_rx.recv().await {
                            let _ = reply.send(subscribe_on(&s, &key).await);
                        }
                    });
                    // Puts in order, one at a time, until the node is dropped.
                    while let Some((key, payload)) = put_rx.recv().await {
                        // A put that fails (a malformed key) is dropped: the
                        // senders re-send what matters.
                        let _ = session.put(key.as_str(), payload).congestion_control(CongestionControl::Block).await;
                    }
                    let _ = session.close().await;
                });
                rt.shutdown_timeout(Duration::from_millis(200));
                let _ = done_tx.send(());
            })
            .map_err(|e| format!("cannot start the Zenoh thread: {e}"))?;
        match opened_rx.recv() {
            Ok(Ok(())) => Ok(Node { handle, puts: Some(puts), subscribe, done: std::sync::Mutex::new(done) }),
            Ok(Err(e)) => Err(e),
            Err(_) => Err("the Zenoh thread ended before the session opened".into()),
        }
    }

    /// Publishes `payload` on `key` (in order with the other puts of this
    /// node; never blocks).
    pub fn put(&self, key: String, payload: Vec<u8>) {
        if let Some(p) = &self.puts {
            let _ = p.send((key, payload));
        }
    }

    /// Subscribes to `key_expr` (a key expression: `*` one chunk, `**` any):
    /// every sample published on a matching key from now on.
    pub async fn subscribe(&self, key_expr: &str) -> Result<mpsc::UnboundedReceiver<Received>, String> {
        let (tx, rx) = oneshot::channel();
        self.subscribe.send((key_expr.to_string(), tx)).map_err(|_| "the Zenoh session is closed".to_string())?;
        rx.await.map_err(|_| "the Zenoh session is closed".to_string())?
    }

    /// Spawns `fut` on the node's runtime (it ends with the node).
    pub fn spawn<F>(&self, fut: F) -> tokio::task::JoinHandle<F::Output>
    where
        F: std::future::Future + Send + 'static,
        F::Output: Send + 'static,
    {
        self.handle.spawn(fut)
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        // Closing the put channel lets the session send what was put, then
        // close; wait a little for it.
        self.puts = None;
        if let Ok(done) = self.done.lock() {
            let _ = done.recv_timeout(Duration::from_secs(3));
        }
    }
}

async fn subscribe_on(s: &zenoh::Session, key: &str) -> Result<mpsc::UnboundedReceiver<Received>, String> {
    let (tx, rx) = mpsc::unbounded_channel();
    // The subscription lives as long as the session (background).
    s.declare_subscriber(key)
        .callback(move |sample| {
            let _ = tx.send(Received {
                key: sample.key_expr().as_str().to_string(),
                payload: sample.payload().to_bytes().into_owned(),
            });
        })
        .background()
        .await
        .map_err(|e| format!("cannot subscribe to `{key}`: {e}"))?;
    Ok(rx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_are_checked_and_set() {
        let o = ZenohOptions {
            connect: vec!["tcp/127.0.0.1:7447".into()],
            listen: vec!["tcp/127.0.0.1:0".into()],
            ..Default::default()
        };
        let c = o.config().unwrap();
        assert_eq!(c.get_json("connect/endpoints").unwrap(), r#"["tcp/127.0.0.1:7447"]"#);
        assert_eq!(c.get_json("scouting/multicast/enabled").unwrap(), "false");
        assert_eq!(c.get_json("mode").unwrap(), r#""peer""#);
        let bad = ZenohOptions { connect: vec!["udp/1.2.3.4:5".into()], ..Default::default() };
        assert!(bad.config().unwrap_err().contains("`tcp/HOST:PORT` only"));
        let bad = ZenohOptions { listen: vec!["127.0.0.1:5".into()], ..Default::default() };
        assert!(bad.config().unwrap_err().contains("expected `tcp/HOST:PORT`"));
        let missing = ZenohOptions { config_file: Some("/nonexistent/z.json5".into()), ..Default::default() };
        assert!(missing.config().unwrap_err().contains("--zenoh-config"));
    }

    #[test]
    fn regions_set_the_region_name_and_the_gateway() {
        let peer = ZenohOptions {
            connect: vec!["tcp/127.0.0.1:7447".into()],
            region: Some("auv".into()),
            ..Default::default()
        };
        let c = peer.config().unwrap();
        assert_eq!(c.get_json("region_name").unwrap(), r#""auv""#);
        assert_eq!(
            c.get_json("listen/endpoints").unwrap(),
            "[]",
            "a peer with a region and no endpoint listens nowhere"
        );
        let listening = ZenohOptions { listen: vec!["tcp/127.0.0.1:0".into()], ..peer.clone() };
        assert_eq!(listening.config().unwrap().get_json("listen/endpoints").unwrap(), r#"["tcp/127.0.0.1:0"]"#);
        let router = ZenohOptions {
            mode: Mode::Router,
            listen: vec!["tcp/127.0.0.1:7447".into()],
            gateway_regions: vec!["auv".into(), "asc".into()],
            ..Default::default()
        };
        let gateway = router.config().unwrap().get_json("gateway").unwrap();
        assert!(gateway.contains("auv") && gateway.contains("asc"), "{gateway}");
        let south: serde_json::Value = serde_json::from_str(&gateway_south(&router.gateway_regions).unwrap()).unwrap();
        assert_eq!(
            south,
            serde_json::json!([
                { "filters": [ { "region_names": ["auv"] } ] },
                { "filters": [ { "region_names": ["asc"] } ] },
                { "filters": [ { "modes": ["peer", "client"] } ] }
            ])
        );
        // Bad input is an error, never a panic.
        for (bad, why) in [
            (ZenohOptions { region: Some(String::new()), ..Default::default() }, "region ``"),
            (ZenohOptions { region: Some("a b".into()), ..Default::default() }, "region `a b`"),
            (ZenohOptions { region: Some("x\"}".into()), ..Default::default() }, "expected 1 to 32"),
            (ZenohOptions { region: Some("a".repeat(33)), ..Default::default() }, "expected 1 to 32"),
            (ZenohOptions { gateway_regions: vec!["auv".into()], ..Default::default() }, "only a router"),
            (ZenohOptions { mode: Mode::Router, region: Some("auv".into()), ..Default::default() }, "a router names"),
            (
                ZenohOptions {
                    mode: Mode::Router,
                    gateway_regions: vec!["a".into(), "a".into()],
                    ..Default::default()
                },
                "given twice",
            ),
        ] {
            let e = bad.config().unwrap_err();
            assert!(e.contains(why), "{e}");
        }
    }
}
