//! The axum application: shared state and the router. `main.rs` only parses the command line
//! and calls [`crate::run`]; tests build the same router on port 0.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};

use crate::api;
use crate::assets;
use crate::compute::{ComputePool, ComputeSettings};
use crate::config::ServeConfig;
use crate::error::ApiError;
use crate::json::MAX_BODY_BYTES;
use crate::metrics::Metrics;
use crate::robots::Robots;
use crate::sessions::record::Recorder;
use crate::sessions::{self, SessionConfig, SessionManager};

/// State shared by every handler.
#[derive(Clone)]
pub struct AppState {
    /// Built-in robot models.
    pub robots: Arc<Robots>,
    /// Live sessions.
    pub sessions: Arc<SessionManager>,
    /// Counters for /metrics.
    pub metrics: Arc<Metrics>,
    /// The instructor token.
    pub instructor_token: Arc<str>,
    /// Recent scenario runs' CSVs, for download.
    pub scenario_runs: Arc<api::scenarios::RunStore>,
    /// The bounded pool of CPU-heavy requests.
    pub compute: Arc<ComputePool>,
}

impl AppState {
    /// Loads the built-in models, opens the data directory and starts the physics workers.
    pub fn new(config: &ServeConfig) -> anyhow::Result<AppState> {
        let robots = Arc::new(Robots::load()?);
        let metrics = Arc::new(Metrics::default());
        let recorder = Recorder::open(&config.data_dir, metrics.clone())?;
        let magnum = robots
            .get("magnum")
            .ok_or_else(|| anyhow::anyhow!("built-in model magnum missing"))?;
        let threads = config.physics_threads.unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(2)
        });
        let sessions = SessionManager::start(
            SessionConfig {
                max_sessions: config.max_sessions,
                idle_timeout: Duration::from_secs(config.idle_timeout_secs),
                frame_hz: config.frame_hz,
                max_messages_per_second: config.max_messages_per_second,
                physics_threads: threads,
            },
            recorder,
            metrics.clone(),
            magnum,
        );
        let instructor_token: Arc<str> = match &config.instructor_token {
            Some(t) if !t.is_empty() => t.as_str().into(),
            _ => sessions::random_hex(16).into(),
        };
        let compute = Arc::new(ComputePool::new(
            &ComputeSettings {
                threads: usize::from(config.compute_threads),
                queue: config.compute_queue,
                deadline: Duration::from_secs(config.compute_deadline_secs),
                priority: config.compute_priority,
            },
            metrics.clone(),
        )?);
        Ok(AppState {
            robots,
            sessions,
            metrics,
            instructor_token,
            scenario_runs: Arc::default(),
            compute,
        })
    }
}

/// Every (method, path) the router serves — documented in `/api/openapi.json`, and checked
/// against it and against the live router by the tests.
pub const ROUTES: &[(&str, &str)] = &[
    ("get", "/"),
    ("get", "/instructor"),
    ("get", "/web/{path}"),
    ("get", "/static/{path}"),
    ("get", "/healthz"),
    ("get", "/metrics"),
    ("get", "/api/openapi.json"),
    ("get", "/api/robots"),
    ("get", "/api/robots/{name}"),
    ("post", "/api/analysis"),
    ("post", "/api/analysis/dual"),
    ("post", "/api/optimal-posture"),
    ("get", "/api/studies"),
    ("post", "/api/studies/{name}"),
    ("get", "/api/scenarios"),
    ("post", "/api/scenarios/{name}/run"),
    ("get", "/api/scenarios/runs/{run}"),
    ("post", "/api/sessions"),
    ("get", "/api/sessions"),
    ("get", "/api/sessions/{id}"),
    ("delete", "/api/sessions/{id}"),
    ("post", "/api/sessions/{id}/actions"),
    ("get", "/api/sessions/{id}/log.csv"),
    ("get", "/ws/sessions/{id}"),
];

async fn count_requests(State(metrics): State<Arc<Metrics>>, req: Request, next: Next) -> Response {
    metrics
        .http_requests
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    next.run(req).await
}

async fn metrics_text(State(state): State<AppState>) -> Response {
    (
        [(
            axum::http::header::CONTENT_TYPE,
            "text/plain; version=0.0.4",
        )],
        state.metrics.render(),
    )
        .into_response()
}

/// Every route of the server.
pub fn app(state: AppState) -> Router {
    Router::new()
        .route("/", get(assets::index))
        .route("/instructor", get(assets::instructor))
        .route("/web/{*path}", get(assets::web))
        .route("/static/{*path}", get(assets::vendored))
        .route("/healthz", get(|| async { "ok" }))
        .route("/metrics", get(metrics_text))
        .route("/api/openapi.json", get(api::openapi::spec))
        .route("/api/robots", get(api::robots::list))
        .route("/api/robots/{name}", get(api::robots::get))
        .route("/api/analysis", post(api::analysis::single))
        .route("/api/analysis/dual", post(api::analysis::dual))
        .route("/api/optimal-posture", post(api::optimize::posture))
        .route("/api/studies", get(api::optimize::studies))
        .route("/api/studies/{name}", post(api::optimize::study))
        .route("/api/scenarios", get(api::scenarios::list))
        .route("/api/scenarios/{name}/run", post(api::scenarios::run))
        .route("/api/scenarios/runs/{run}", get(api::scenarios::download))
        .route(
            "/api/sessions",
            post(sessions::rest::create).get(sessions::rest::list),
        )
        .route(
            "/api/sessions/{id}",
            get(sessions::rest::get_one).delete(sessions::rest::end),
        )
        .route("/api/sessions/{id}/actions", post(sessions::rest::act))
        .route("/api/sessions/{id}/log.csv", get(sessions::rest::log_csv))
        .route("/ws/sessions/{id}", get(sessions::ws::upgrade))
        .fallback(|uri: axum::http::Uri| async move {
            ApiError::not_found(format!("no route for {}", uri.path()))
        })
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(middleware::from_fn_with_state(
            state.metrics.clone(),
            count_requests,
        ))
        .with_state(state)
}
