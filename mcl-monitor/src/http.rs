//! The HTTP API and the page (docs/monitor.md lists every endpoint and the
//! messages of the event stream).

use std::convert::Infallible;
use std::sync::Arc;

use axum::extract::{Query, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::Stream;
use mcl_runtime::operator::Command;
use serde::Deserialize;
use serde_json::json;

use crate::hub::{Hub, Refused};

const INDEX: &str = include_str!("../assets/index.html");
const APP: &str = include_str!("../assets/app.js");
const STYLE: &str = include_str!("../assets/style.css");

/// Records sent in one message of the event stream at most.
const BATCH: usize = 2000;

/// The routes of the monitor over `hub`.
pub fn router(hub: Arc<Hub>) -> Router {
    Router::new()
        .route("/", get(|| async { ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], INDEX) }))
        .route("/app.js", get(|| async { ([(header::CONTENT_TYPE, "text/javascript; charset=utf-8")], APP) }))
        .route("/style.css", get(|| async { ([(header::CONTENT_TYPE, "text/css; charset=utf-8")], STYLE) }))
        .route("/api/info", get(info))
        .route("/api/state", get(state))
        .route("/api/records", get(records))
        .route("/api/events", get(events))
        .route("/api/source", get(source))
        .route("/api/tree", get(|State(hub): State<Arc<Hub>>| async move { Json(hub.trees()) }))
        .route("/api/operator", post(operator))
        .with_state(hub)
}

async fn info(State(hub): State<Arc<Hub>>) -> Json<serde_json::Value> {
    Json(json!({
        "mode": hub.mode(),
        "title": hub.title(),
        "operator": hub.has_operator(),
        "vehicles": hub.vehicles(),
    }))
}

async fn state(State(hub): State<Arc<Hub>>) -> Response {
    let (s, finished) = hub.state();
    let mut v = serde_json::to_value(s).unwrap_or_default();
    v["finished"] = json!(finished);
    v["mode"] = json!(hub.mode());
    Json(v).into_response()
}

/// `?from=N`: records from the N-th (0-based).
#[derive(Deserialize)]
struct From {
    #[serde(default)]
    from: usize,
}

/// `{"from": N, "pushed_ms": ms, "records": [...]}` around JSON texts.
fn batch(from: usize, lines: &[Arc<str>], pushed: Option<f64>) -> String {
    let mut out =
        format!("{{\"from\":{from},\"pushed_ms\":{},\"records\":[", pushed.map_or("null".into(), |p| p.to_string()));
    for (i, l) in lines.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(l);
    }
    out.push_str("]}");
    out
}

async fn records(State(hub): State<Arc<Hub>>, Query(q): Query<From>) -> Response {
    let (lines, pushed) = hub.records(q.from, usize::MAX);
    ([(header::CONTENT_TYPE, "application/json")], batch(q.from, &lines, pushed)).into_response()
}

/// Server-sent events: `records` messages (every record from `from` on,
/// then each new one as it is pushed) and a `status` message when the run
/// ends.
async fn events(
    State(hub): State<Arc<Hub>>,
    Query(q): Query<From>,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let rx = hub.subscribe();
    let stream = futures_util::stream::unfold((hub, rx, q.from, false), |(hub, mut rx, from, told)| async move {
        loop {
            let (n, finished) = *rx.borrow_and_update();
            if n > from {
                let (lines, pushed) = hub.records(from, BATCH);
                let next = from + lines.len();
                let ev = Event::default().event("records").data(batch(from, &lines, pushed));
                return Some((Ok(ev), (hub, rx, next, told)));
            }
            if finished && !told {
                let ev = Event::default().event("status").data(json!({ "finished": true }).to_string());
                return Some((Ok(ev), (hub, rx, from, true)));
            }
            rx.changed().await.ok()?;
        }
    });
    Sse::new(stream).keep_alive(KeepAlive::default())
}

#[derive(Deserialize)]
struct File {
    file: String,
}

async fn source(State(hub): State<Arc<Hub>>, Query(q): Query<File>) -> Response {
    match hub.source(&q.file) {
        Some(text) => ([(header::CONTENT_TYPE, "text/plain; charset=utf-8")], text.to_string()).into_response(),
        None => (StatusCode::NOT_FOUND, "no call of this run is written in that file, or it cannot be read\n")
            .into_response(),
    }
}

/// `Authorization: Bearer TOKEN`.
fn bearer(h: &HeaderMap) -> Option<&str> {
    h.get(header::AUTHORIZATION)?.to_str().ok()?.strip_prefix("Bearer ").map(str::trim)
}

/// The vehicle an operator's request names (`"vehicle"`, next to the command).
#[derive(Deserialize)]
struct Vehicle {
    #[serde(default)]
    vehicle: Option<String>,
}

async fn operator(State(hub): State<Arc<Hub>>, headers: HeaderMap, body: String) -> Response {
    let parsed = serde_json::from_str::<Command>(&body).and_then(|c| Ok((c, serde_json::from_str::<Vehicle>(&body)?)));
    let (c, to) = match parsed {
        Ok(c) => c,
        Err(e) => return error(StatusCode::BAD_REQUEST, &format!("not an operator command: {e}")),
    };
    match hub.command(bearer(&headers), to.vehicle.as_deref(), c) {
        Ok(()) => (StatusCode::ACCEPTED, Json(json!({ "accepted": true }))).into_response(),
        Err(Refused::Off) => {
            error(StatusCode::FORBIDDEN, "operator control is off: start the run with --operator-token TOKEN")
        }
        Err(Refused::Token) => {
            let mut r = error(StatusCode::UNAUTHORIZED, "missing or wrong token (Authorization: Bearer TOKEN)");
            r.headers_mut().insert(header::WWW_AUTHENTICATE, header::HeaderValue::from_static("Bearer"));
            r
        }
        Err(Refused::Finished) => error(StatusCode::CONFLICT, "the run is over"),
        Err(Refused::Vehicle(why)) => error(StatusCode::BAD_REQUEST, &why),
    }
}

fn error(code: StatusCode, message: &str) -> Response {
    (code, Json(json!({ "error": message }))).into_response()
}
