//! The axum application: shared state and the router. `main.rs` only parses the command line
//! and calls [`crate::run`]; tests build the same router on port 0.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, put};

use crate::api;
use crate::assets;
use crate::compute::{ComputePool, ComputeSettings};
use crate::config::ServeConfig;
use crate::error::ApiError;
use crate::json::MAX_BODY_BYTES;
use crate::metrics::Metrics;
use crate::robots::Robots;
use crate::security::{self, Policy};
use crate::sessions::admission::CreationLimiter;
use crate::sessions::record::Recorder;
use crate::sessions::{SessionConfig, SessionManager};

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
    /// Origins, public URL and trusted proxies.
    pub policy: Arc<Policy>,
    /// Per-client rate limit of session creation.
    pub creation_limiter: Arc<CreationLimiter>,
    /// Class code required to create a session, when configured.
    pub join_code: Option<Arc<str>>,
    /// The bounded pool of CPU-heavy requests.
    pub compute: Arc<ComputePool>,
    /// The training records database.
    pub db: crate::db::Db,
    /// The replays' shared checkpoints (bounded; [`crate::replay::checkpoints`]).
    pub replays: Arc<crate::replay::checkpoints::CheckpointCache>,
    /// The ended attempts' ghost tracks (bounded; [`crate::replay::track`]).
    pub tracks: Arc<crate::replay::track::TrackCache>,
    /// This replica (name, multi-replica mode, drain).
    pub cluster: Arc<crate::cluster::Cluster>,
    /// Where finished attempts' xAPI statements go (`--xapi-endpoint`), when set.
    pub xapi: Option<Arc<crate::xapi::XapiConfig>>,
    /// Exercises' `requires` lock them for trainees (`--progression on`).
    pub progression: bool,
}

/// Checks an operator-supplied secret (instructor token, join code): it must travel intact
/// in a header, so no whitespace or control characters (a trailing space from a pasted
/// value is a start-up error, not a token nobody can type).
fn check_secret(what: &str, value: &str) -> anyhow::Result<()> {
    anyhow::ensure!(
        value
            .chars()
            .all(|c| c.is_ascii_graphic()
                || (!c.is_ascii() && !c.is_whitespace() && !c.is_control())),
        "{what} must not contain spaces or control characters"
    );
    Ok(())
}

impl AppState {
    /// Loads the built-in models, opens the data directory and starts the physics workers.
    pub fn new(config: &ServeConfig) -> anyhow::Result<AppState> {
        let robots = Arc::new(Robots::load()?);
        let metrics = Arc::new(Metrics::default());
        let xapi = config.xapi_config()?.map(Arc::new);
        let db = crate::db::Db::open(&config.database_url())?;
        let cluster = Arc::new(crate::cluster::Cluster::new(
            config.replica_name.as_deref(),
            db.backend(),
            Duration::from_secs(config.drain_seconds),
        )?);
        if cluster.multi {
            // Before the recorder's start-up repair: this replica's previous run is over.
            let (s, a) = db.block_on(db.forget_replica(&cluster.name))?;
            if s + a > 0 {
                tracing::info!(
                    sessions = s,
                    attempts = a,
                    "previous run's sessions marked interrupted"
                );
            }
        }
        let recorder = Recorder::open(
            &config.data_dir,
            db.clone(),
            metrics.clone(),
            config.record_config(),
        )?;
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
                unjoined_grace: Duration::from_secs(config.unjoined_grace_secs),
                abandon_grace: Duration::from_secs(config.abandon_grace_seconds),
                max_sessions_per_client: config.max_sessions_per_client,
            },
            recorder,
            metrics.clone(),
            magnum,
        );
        let instructor_token: Arc<str> = match &config.instructor_token {
            Some(t) if !t.is_empty() => {
                check_secret("the instructor token", t)?;
                t.as_str().into()
            }
            _ => crate::ids::random_hex(16).into(),
        };
        let join_code = match &config.join_code {
            Some(c) if !c.is_empty() => {
                check_secret("the join code", c)?;
                Some(c.as_str().into())
            }
            _ => None,
        };
        let policy = Policy::new(
            config.public_url.as_deref(),
            &config.allowed_origins,
            &config.trusted_proxies,
        )?
        .with_hosts(&config.allowed_hosts, config.bind);
        anyhow::ensure!(
            config.sessions_per_minute.is_finite() && config.sessions_per_minute > 0.0,
            "--sessions-per-minute must be a positive number"
        );
        let compute = Arc::new(ComputePool::new(
            &ComputeSettings {
                threads: usize::from(config.compute_threads),
                queue: config.compute_queue,
                deadline: Duration::from_secs(config.compute_deadline_secs),
                priority: config.compute_priority,
            },
            metrics.clone(),
        )?);
        let replays = sessions.checkpoints().clone();
        Ok(AppState {
            robots,
            sessions,
            metrics,
            instructor_token,
            scenario_runs: Arc::default(),
            policy: Arc::new(policy),
            creation_limiter: Arc::new(CreationLimiter::new(
                config.session_burst,
                config.sessions_per_minute,
            )),
            join_code,
            compute,
            db,
            replays,
            tracks: Arc::default(),
            cluster,
            xapi,
            progression: config.progression == crate::config::Progression::On,
        })
    }
}

/// Every (method, path) the router serves — documented in `/api/openapi.json`, and checked
/// against it and against the live router by the tests.
pub const ROUTES: &[(&str, &str)] = &[
    ("get", "/"),
    ("get", "/instructor"),
    ("get", "/replay/{attempt}"),
    ("get", "/logbook"),
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
    ("get", "/api/sessions/{id}/assessment"),
    ("get", "/api/sessions/{id}/progress"),
    ("get", "/api/sessions/{id}/ghosts"),
    ("get", "/api/progress"),
    ("get", "/api/reference-operators"),
    ("put", "/api/reference-operators"),
    ("get", "/api/sessions/{id}/logbook"),
    ("get", "/api/logbook"),
    ("get", "/api/logbook.csv"),
    ("put", "/api/signoffs"),
    ("delete", "/api/signoffs"),
    ("get", "/api/unlocks"),
    ("put", "/api/unlocks"),
    ("delete", "/api/unlocks"),
    ("get", "/api/results.csv"),
    ("post", "/api/signin"),
    ("get", "/api/signin"),
    ("post", "/api/signout"),
    ("get", "/api/exercises"),
    ("get", "/api/exercises/{id}"),
    ("get", "/ws/sessions/{id}"),
    ("get", "/api/attempts"),
    ("get", "/api/attempts/{id}"),
    ("get", "/api/attempts/{id}/inputs"),
    ("get", "/api/attempts/{id}/replay"),
    ("get", "/api/attempts/{id}/track"),
    ("post", "/api/attempts/{id}/take-over"),
    ("get", "/ws/replay/{id}"),
];

async fn count_requests(State(metrics): State<Arc<Metrics>>, req: Request, next: Next) -> Response {
    metrics
        .http_requests
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    next.run(req).await
}

async fn metrics_text(State(state): State<AppState>) -> Response {
    let text = state.metrics.render(&state.cluster.name);
    (
        [(
            axum::http::header::CONTENT_TYPE,
            "text/plain; version=0.0.4",
        )],
        text,
    )
        .into_response()
}

/// `GET /healthz`: `ok`; while draining 503 (readiness: the proxy and Kubernetes send no new
/// sessions), except `?probe=live` (liveness: the process still serves its live sessions).
async fn healthz(
    State(state): State<AppState>,
    axum::extract::RawQuery(query): axum::extract::RawQuery,
) -> Response {
    let liveness = query.as_deref() == Some("probe=live");
    if state.cluster.draining() && !liveness {
        return (axum::http::StatusCode::SERVICE_UNAVAILABLE, "draining").into_response();
    }
    "ok".into_response()
}

/// Every route of the server, behind the replica prefix (`/r/<this replica>/…` is served
/// as `/…`; [`crate::cluster::route_prefix`] rewrites the path before routing).
pub fn app(state: AppState) -> Router {
    let cluster = state.cluster.clone();
    Router::new()
        .fallback_service(routes(state))
        .layer(middleware::from_fn_with_state(
            cluster,
            crate::cluster::route_prefix,
        ))
}

fn routes(state: AppState) -> Router {
    Router::new()
        .route("/", get(assets::index))
        .route("/instructor", get(assets::instructor))
        .route("/replay/{attempt}", get(assets::replay))
        .route("/logbook", get(assets::logbook))
        .route("/web/{*path}", get(assets::web))
        .route("/static/{*path}", get(assets::vendored))
        .route("/healthz", get(healthz))
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
            post(api::sessions::create).get(api::sessions::list),
        )
        .route(
            "/api/sessions/{id}",
            get(api::sessions::get_one).delete(api::sessions::end),
        )
        .route("/api/sessions/{id}/actions", post(api::sessions::act))
        .route("/api/sessions/{id}/log.csv", get(api::sessions::log_csv))
        .route(
            "/api/sessions/{id}/assessment",
            get(api::sessions::assessment),
        )
        .route(
            "/api/sessions/{id}/progress",
            get(api::progress::of_session),
        )
        .route("/api/sessions/{id}/ghosts", get(api::ghosts::of_session))
        .route("/api/progress", get(api::progress::class))
        .route(
            "/api/reference-operators",
            get(api::progress::references).put(api::progress::mark_reference),
        )
        .route("/api/sessions/{id}/logbook", get(api::logbook::of_session))
        .route("/api/logbook", get(api::logbook::get))
        .route("/api/logbook.csv", get(api::logbook::csv))
        .route(
            "/api/signoffs",
            put(api::logbook::sign).delete(api::logbook::revoke),
        )
        .route(
            "/api/unlocks",
            get(api::unlocks::get)
                .put(api::unlocks::unlock)
                .delete(api::unlocks::lock),
        )
        .route("/api/results.csv", get(api::results::export))
        .route(
            "/api/signin",
            post(api::signin::sign_in).get(api::signin::status),
        )
        .route("/api/signout", post(api::signin::sign_out))
        .route("/api/exercises", get(crate::exercises::list))
        .route("/api/exercises/{id}", get(crate::exercises::get))
        .route("/ws/sessions/{id}", get(api::session_ws::upgrade))
        .route("/api/attempts", get(api::attempts::list))
        .route("/api/attempts/{id}", get(api::attempts::get))
        .route("/api/attempts/{id}/inputs", get(api::attempts::inputs))
        .route("/api/attempts/{id}/replay", get(api::attempts::replay_at))
        .route("/api/attempts/{id}/track", get(api::ghosts::track))
        .route(
            "/api/attempts/{id}/take-over",
            post(api::attempts::take_over),
        )
        .route("/ws/replay/{id}", get(api::attempts::replay_ws))
        .fallback(|uri: axum::http::Uri| async move {
            ApiError::not_found(format!("no route for {}", uri.path()))
        })
        .method_not_allowed_fallback(
            |method: axum::http::Method, uri: axum::http::Uri| async move {
                ApiError::new(
                    axum::http::StatusCode::METHOD_NOT_ALLOWED,
                    format!("{method} is not allowed on {}", uri.path()),
                )
            },
        )
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(middleware::from_fn_with_state(
            state.clone(),
            security::guard,
        ))
        .layer(middleware::from_fn_with_state(
            state.metrics.clone(),
            count_requests,
        ))
        .with_state(state)
}
