//! The server on a thread of its own, with its own tokio runtime, so that
//! the run it shows keeps its own loop (virtual or real time).

use std::sync::Arc;

use crate::hub::Hub;

/// A running monitor server.
pub struct Monitor {
    hub: Arc<Hub>,
    url: String,
}

impl Monitor {
    /// Binds `addr` (`HOST:PORT`; port 0: any free port) and serves the
    /// page and the API over `hub` until the process ends.
    pub fn start(hub: Arc<Hub>, addr: &str) -> Result<Monitor, String> {
        let listener = std::net::TcpListener::bind(addr).map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        let local = listener.local_addr().map_err(|e| e.to_string())?;
        listener.set_nonblocking(true).map_err(|e| e.to_string())?;
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("mcl-monitor")
            .enable_all()
            .build()
            .map_err(|e| format!("cannot start the monitor: {e}"))?;
        let app = crate::http::router(hub.clone());
        std::thread::Builder::new()
            .name("mcl-monitor".into())
            .spawn(move || {
                rt.block_on(async move {
                    let Ok(listener) = tokio::net::TcpListener::from_std(listener) else { return };
                    let _ = axum::serve(listener, app).await;
                })
            })
            .map_err(|e| format!("cannot start the monitor: {e}"))?;
        let host = match local.ip() {
            ip if ip.is_unspecified() => "127.0.0.1".to_string(),
            std::net::IpAddr::V6(ip) => format!("[{ip}]"),
            ip => ip.to_string(),
        };
        Ok(Monitor { hub, url: format!("http://{host}:{}/", local.port()) })
    }

    /// The page's address.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// The hub it serves.
    pub fn hub(&self) -> &Arc<Hub> {
        &self.hub
    }
}
