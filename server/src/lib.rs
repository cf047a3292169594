//! seaarms server: the thin axum application around [`seaarms_core`].
//!
//! # Layout
//! * [`config`]: command line / environment (one `clap` struct).
//! * [`app`]: shared state and the router.
//! * [`api`]: HTTP handlers and their wire types.
//! * [`robots`]: built-in model registry and `"robot"` field resolution.
//! * [`json`]: the JSON extractor whose rejections are JSON errors.
//! * [`protocol`]: WebSocket wire types (the page contract).
//! * [`error`]: the one HTTP error type.
//! * [`assets`]: the embedded web page and vendored libraries.
//! * [`scenarios`]: the headless runner of Lim's dynamic case studies (CSV + summary).

pub mod api;
pub mod app;
pub mod assets;
pub mod config;
pub mod error;
pub mod json;
pub mod protocol;
pub mod robots;
pub mod scenarios;

use std::future::Future;

use tokio::net::TcpListener;

/// Serves the application on a bound listener until `shutdown` completes (tests bind port 0).
pub async fn run(
    listener: TcpListener,
    state: app::AppState,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    axum::serve(listener, app::app(state))
        .with_graceful_shutdown(shutdown)
        .await
}
