//! Several replicas behind a standard proxy (issue 18; docs/api.md "Replicas",
//! docs/operations.md "Several replicas"). No cluster manager of our own: each replica
//! only names itself, lists its live sessions and heartbeats in the shared database
//! ([`crate::db`]'s `replicas` and `session_directory`), answers 503 while it is full or
//! draining (the proxy retries another), and accepts the path prefix `/r/<its name>/` that
//! the proxy (HAProxy, a Kubernetes Ingress with `pathType: Prefix`) routes on.
//!
//! Multi-replica mode is on when the database is PostgreSQL (the only shared one); with the
//! default SQLite file nothing here runs and every URL is as before (the prefix of its own
//! name is still accepted).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use axum::extract::{Request, State};
use axum::http::{StatusCode, Uri};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::app::AppState;
use crate::clock::unix_now;
use crate::db::{Backend, ReplicaBeat};
use crate::error::ApiError;

/// How often a replica writes its heartbeat and its sessions' directory rows.
pub const HEARTBEAT: Duration = Duration::from_secs(1);

/// A replica whose heartbeat is older than this is declared lost by the others: five
/// heartbeats, so a replica is not declared lost over one slow database round trip or a
/// stalled second (the measured heartbeat transaction with 30 sessions takes a few ms).
pub const HEARTBEAT_TIMEOUT: Duration = Duration::from_secs(5);

/// The first path segment of a replica prefix: `/r/<replica>/…`.
pub const PREFIX_SEGMENT: &str = "r";

/// This replica: its name, mode and drain state.
#[derive(Debug)]
pub struct Cluster {
    /// The replica's name (a DNS label).
    pub name: String,
    /// Whether replicas share the database (PostgreSQL): session URLs carry the prefix, the
    /// heartbeat and the directory run.
    pub multi: bool,
    /// When this process started (Unix seconds).
    pub started_unix: f64,
    /// Longest drain on SIGTERM.
    pub drain: Duration,
    draining: AtomicBool,
}

/// Whether `name` is a DNS label (RFC 1123: 1–63 of `a-z`, `0-9`, `-`, not starting or
/// ending with `-`), so it is one path segment with nothing to escape and a valid
/// Kubernetes pod and Service name.
pub fn valid_name(name: &str) -> bool {
    (1..=63).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
        && !name.starts_with('-')
        && !name.ends_with('-')
}

/// The host name as a replica name (lowercased; characters a DNS label does not allow
/// become `-`); `seaarms` when there is none.
pub fn default_name() -> String {
    let raw = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_default();
    let cleaned: String = raw
        .trim()
        .to_ascii_lowercase()
        .chars()
        .map(|c| {
            if c.is_ascii_lowercase() || c.is_ascii_digit() {
                c
            } else {
                '-'
            }
        })
        .take(63)
        .collect();
    let cleaned = cleaned.trim_matches('-').to_string();
    if valid_name(&cleaned) {
        cleaned
    } else {
        "seaarms".to_string()
    }
}

impl Cluster {
    /// This replica from the settings: `name` (default [`default_name`]) and the database
    /// back end (multi-replica mode with PostgreSQL).
    pub fn new(name: Option<&str>, backend: Backend, drain: Duration) -> anyhow::Result<Cluster> {
        let name = match name {
            Some(n) if !n.is_empty() => n.to_string(),
            _ => default_name(),
        };
        anyhow::ensure!(
            valid_name(&name),
            "--replica-name `{name}` must be a DNS label: 1–63 of a-z, 0-9 and -, not starting or ending with -"
        );
        Ok(Cluster {
            name,
            multi: backend == Backend::Postgres,
            started_unix: unix_now(),
            drain,
            draining: AtomicBool::new(false),
        })
    }

    /// The path prefix of this replica's session URLs: `/r/<name>` in multi-replica mode,
    /// empty otherwise.
    pub fn base(&self) -> String {
        if self.multi {
            base_of(&self.name)
        } else {
            String::new()
        }
    }

    /// Whether this replica is draining (no new sessions, `/healthz` 503).
    pub fn draining(&self) -> bool {
        self.draining.load(Ordering::Relaxed)
    }

    /// Starts draining.
    pub fn start_draining(&self) {
        self.draining.store(true, Ordering::Relaxed);
    }
}

/// The path prefix of replica `name`.
pub fn base_of(name: &str) -> String {
    format!("/{PREFIX_SEGMENT}/{name}")
}

/// Middleware run before routing: `/r/<this replica>/rest` is served as `/rest`; a prefix
/// naming another replica answers 421 naming it (the proxy sent it to the wrong place).
pub async fn route_prefix(
    State(cluster): State<Arc<Cluster>>,
    mut req: Request,
    next: Next,
) -> Response {
    let Some(rest) = req
        .uri()
        .path()
        .strip_prefix('/')
        .and_then(|p| p.strip_prefix(PREFIX_SEGMENT))
        .and_then(|p| p.strip_prefix('/'))
    else {
        return next.run(req).await;
    };
    let (name, tail) = rest.split_once('/').unwrap_or((rest, ""));
    // Answered before the routes' guard: its headers are added here (issue 29 item 14).
    let refused = |e: ApiError| {
        let mut resp = e.into_response();
        crate::security::add_security_headers(resp.headers_mut());
        resp
    };
    if name != cluster.name {
        return refused(misdirected(name, &cluster.name));
    }
    let path_and_query = match req.uri().query() {
        Some(q) => format!("/{tail}?{q}"),
        None => format!("/{tail}"),
    };
    match path_and_query.parse::<Uri>() {
        Ok(uri) => *req.uri_mut() = uri,
        Err(_) => return refused(ApiError::bad_request("malformed path")),
    }
    next.run(req).await
}

/// 421 Misdirected Request: what was asked of `me` lives on replica `other`.
fn misdirected(other: &str, me: &str) -> ApiError {
    ApiError::new(
        StatusCode::MISDIRECTED_REQUEST,
        format!(
            "this is replica `{me}`; the request is for replica `{other}` (ask through the proxy, under {})",
            base_of(other)
        ),
    )
    .with_detail(serde_json::json!({"replica": other, "base": base_of(other), "this_replica": me}))
}

/// For a session id not live here: 421 naming the replica that holds it, when the directory
/// lists it on another one (None otherwise, also when the database cannot be asked).
pub async fn elsewhere(state: &AppState, id: &str) -> Option<ApiError> {
    if !state.cluster.multi {
        return None;
    }
    match state.db.directory_replica(id).await {
        Ok(Some(r)) if r != state.cluster.name => Some(misdirected(&r, &state.cluster.name)),
        Ok(_) => None,
        Err(e) => {
            tracing::warn!("session directory: {e:#}");
            None
        }
    }
}

/// How a live session is summarised in the directory (the instructor's REST summary,
/// `crate::api::sessions::directory_summary`, given by [`crate::run`]: the cluster does not
/// know the summary's shape).
pub type Summarize = fn(&AppState, &crate::sessions::Session) -> serde_json::Value;

/// Writes one heartbeat (this replica's row and its sessions' directory rows, each summarised
/// by `summarize`) and declares lost the replicas whose heartbeat is older than
/// [`HEARTBEAT_TIMEOUT`].
pub async fn beat(
    state: &AppState,
    summarize: Summarize,
) -> anyhow::Result<Vec<crate::db::LostReplica>> {
    let since = unix_now();
    let st = state.clone();
    let summaries = tokio::task::spawn_blocking(move || {
        st.sessions
            .all()
            .iter()
            .map(|s| {
                let v = summarize(&st, s);
                (s.id.clone(), v.to_string())
            })
            .collect::<Vec<_>>()
    })
    .await?;
    let now = unix_now();
    let c = &state.cluster;
    let beat = ReplicaBeat {
        name: c.name.clone(),
        started_unix: c.started_unix,
        now_unix: now,
        live_sessions: i64::try_from(summaries.len()).unwrap_or(i64::MAX),
        max_sessions: i64::try_from(state.sessions.config.max_sessions).unwrap_or(i64::MAX),
        draining: c.draining(),
    };
    state.db.heartbeat(beat, summaries, since).await?;
    let lost = state
        .db
        .reap_lost(&c.name, now - HEARTBEAT_TIMEOUT.as_secs_f64(), now)
        .await?;
    for l in &lost {
        tracing::warn!(
            replica = %l.name,
            sessions = l.sessions,
            attempts = l.attempts,
            silent_s = now - l.last_heartbeat_unix,
            "replica lost: its sessions marked interrupted"
        );
    }
    Ok(lost)
}

/// The heartbeat loop (multi-replica mode): [`beat`] every [`HEARTBEAT`] until aborted.
pub async fn heartbeat_loop(state: AppState, summarize: Summarize) {
    let mut tick = tokio::time::interval(HEARTBEAT);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tick.tick().await;
        if let Err(e) = beat(&state, summarize).await {
            tracing::warn!("heartbeat: {e:#}");
        }
    }
}

/// Graceful drain (SIGTERM): stop taking sessions (creation 503, `/healthz` 503), then wait
/// until no session is live or the drain deadline passes; the caller then stops the server,
/// which ends what is left as interrupted (`server_shutdown`).
pub async fn drain(state: &AppState) {
    let c = &state.cluster;
    if c.drain.is_zero() {
        return;
    }
    c.start_draining();
    state.metrics.draining.store(1, Ordering::Relaxed);
    let live = state.sessions.all().len();
    tracing::info!(live, deadline_s = c.drain.as_secs(), "draining");
    let deadline = Instant::now() + c.drain;
    while Instant::now() < deadline && !state.sessions.all().is_empty() {
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    tracing::info!(
        left = state.sessions.all().len(),
        "drain over; ending what is left as interrupted"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 1123 labels: what Kubernetes accepts as a pod name segment.
    #[test]
    fn replica_names_are_dns_labels() {
        for ok in ["seaarms-0", "a", "x1", &"a".repeat(63)] {
            assert!(valid_name(ok), "{ok}");
        }
        for bad in ["", "-a", "a-", "A", "a_b", "a/b", "a.b", &"a".repeat(64)] {
            assert!(!valid_name(bad), "{bad}");
        }
        assert!(valid_name(&default_name()));
    }
}
