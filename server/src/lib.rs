//! seaarms server: the thin axum application around [`seaarms_core`].
//!
//! # Layout
//! * [`config`]: command line / environment (one `clap` struct).
//! * [`app`]: shared state and the router.
//! * [`api`]: HTTP handlers and their wire types.
//! * [`posture`]: optimal posture requests and answers; [`studies`]: the manipulability
//!   studies and workspace map (parameters, limits, documents).
//! * [`limits`]: the work limits of every computing route; [`compute`]: the bounded pool
//!   those routes compute on.
//! * [`robots`]: built-in model registry and `"robot"` field resolution.
//! * [`json`]: the JSON extractor whose rejections are JSON errors.
//! * [`protocol`]: WebSocket wire types (the page contract).
//! * [`error`]: the one HTTP error type.
//! * [`assets`]: the embedded web page and vendored libraries, and the Content-Security-Policy.
//! * [`security`]: the middleware for origins, content types, security headers, JSON errors.
//! * [`sessions`]: live sessions — physics threads, frames, WebSocket, REST, records.
//! * [`replay`]: attempts' input logs and their exact re-simulation.
//! * [`metrics`]: Prometheus counters; [`load`]: the `seaarms load` client.
//! * [`scenarios`]: the headless runner of Lim's dynamic case studies (CSV + summary).
//! * [`db`]: the training records database (SQLite or PostgreSQL).
//! * [`csv_out`]: the one CSV writer (one number format) for every CSV the server writes.
//! * [`cluster`]: several replicas behind a proxy: replica name, URL prefix, heartbeats,
//!   session directory, drain.
//! * [`xapi`]: finished attempts as xAPI statements to a Learning Record Store (outbox,
//!   sender with back-off).

pub mod api;
pub mod app;
pub mod assets;
pub mod auth;
pub mod catalogue;
pub mod clock;
pub mod cluster;
pub mod compute;
pub mod config;
pub mod csv_out;
pub mod db;
pub mod error;
pub mod exercises;
pub mod ids;
pub mod json;
pub mod limits;
pub mod load;
pub mod metrics;
pub mod names;
pub mod posture;
pub mod protocol;
pub mod replay;
pub mod robots;
pub mod scenarios;
pub mod security;
pub mod sessions;
pub mod studies;
pub mod xapi;

use std::future::Future;

use tokio::net::TcpListener;

/// Serves the application on a bound listener until `shutdown` completes (tests bind port
/// 0). Idle and never-joined sessions are expired every few seconds; on shutdown every session is ended and
/// every record flushed before this returns.
pub async fn run(
    listener: TcpListener,
    state: app::AppState,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let sessions = state.sessions.clone();
    let heartbeat = state.cluster.multi.then(|| {
        tokio::spawn(cluster::heartbeat_loop(
            state.clone(),
            api::sessions::directory_summary,
        ))
    });
    let leaving = state
        .cluster
        .multi
        .then(|| (state.db.clone(), state.cluster.name.clone()));
    let xapi = state.xapi.as_deref().map(|config| {
        let config = match listener.local_addr() {
            Ok(addr) => config.clone().or_listening_on(addr),
            Err(_) => config.clone(),
        };
        tokio::spawn(xapi::send_loop(
            state.db.clone(),
            state.metrics.clone(),
            std::sync::Arc::new(config),
        ))
    });
    let pass_board = tokio::spawn(api::progress::pass_board_loop(state.clone()));
    let expiry = tokio::spawn({
        let sessions = sessions.clone();
        async move {
            let mut tick = tokio::time::interval(sessions.expiry_interval());
            loop {
                tick.tick().await;
                let s = sessions.clone();
                let _ = tokio::task::spawn_blocking(move || s.expire_idle()).await;
            }
        }
    });
    // TCP_NODELAY: frames are small and frequent; Nagle + delayed ACK would hold them back.
    let listener = axum::serve::ListenerExt::tap_io(listener, |tcp: &mut tokio::net::TcpStream| {
        let _ = tcp.set_nodelay(true);
    });
    // Connect info: the peer address keys the per-client admission limits.
    let service = app::app(state).into_make_service_with_connect_info::<std::net::SocketAddr>();
    let result = axum::serve(listener, service)
        .with_graceful_shutdown(shutdown)
        .await;
    expiry.abort();
    pass_board.abort();
    if let Some(h) = xapi {
        h.abort();
    }
    if let Some(h) = heartbeat {
        h.abort();
    }
    let _ = tokio::task::spawn_blocking(move || sessions.shutdown()).await;
    // Every session has ended and is recorded: out of the directory now, not declared lost
    // by the others later.
    if let Some((db, name)) = leaving {
        if let Err(e) = db.leave(&name, clock::unix_now()).await {
            tracing::warn!("leaving the session directory: {e:#}");
        }
    }
    result
}
