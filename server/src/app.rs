//! The axum application: shared state and the router. `main.rs` only parses the command line
//! and calls [`crate::run`]; tests build the same router on port 0.

use std::sync::Arc;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::routing::{get, post};

use crate::api;
use crate::assets;
use crate::error::ApiError;
use crate::json::MAX_BODY_BYTES;
use crate::robots::Robots;

/// State shared by every handler.
#[derive(Debug, Clone)]
pub struct AppState {
    /// Built-in robot models.
    pub robots: Arc<Robots>,
}

impl AppState {
    /// Loads the built-in models.
    pub fn new() -> anyhow::Result<AppState> {
        Ok(AppState {
            robots: Arc::new(Robots::load()?),
        })
    }
}

/// Every route of the server.
pub fn app(state: AppState) -> Router {
    Router::new()
        .route("/", get(assets::index))
        .route("/web/{*path}", get(assets::web))
        .route("/static/{*path}", get(assets::vendored))
        .route("/healthz", get(|| async { "ok" }))
        .route("/api/robots", get(api::robots::list))
        .route("/api/robots/{name}", get(api::robots::get))
        .route("/api/analysis", post(api::analysis::single))
        .route("/api/analysis/dual", post(api::analysis::dual))
        .fallback(|uri: axum::http::Uri| async move {
            ApiError::not_found(format!("no route for {}", uri.path()))
        })
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .with_state(state)
}
