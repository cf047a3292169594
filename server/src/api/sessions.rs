//! REST endpoints of sessions. Tokens travel as `Authorization: Bearer …` (the CSV download
//! and the assessment also accept `?token=` so a plain link works). The instructor token may
//! do everything; a trainee's control token acts on its own session only ([`crate::auth`]).

use std::sync::Arc;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use seaarms_core::exercise::ExerciseRun;
use seaarms_core::sim::{Arm, Simulation};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::app::AppState;
use crate::auth::{Actor, Credentials, MISSING_TOKEN, MISSING_TOKEN_OR_QUERY, TokenFrom, token_eq};
use crate::db::unavailable as db_error;
use crate::error::ApiError;
use crate::json::ApiJson;
use crate::protocol::{Action, ControlMethod, ControlMode, fault_label, grasp_name};
use crate::security::ws_base;
use crate::sessions::admission::{ClientKey, Peer, client_ip};
use crate::sessions::command::{self, Command, CommandError};
use crate::sessions::record::valid_id;
use crate::sessions::{CreateError, Session};

impl From<CommandError> for ApiError {
    fn from(e: CommandError) -> ApiError {
        match e {
            CommandError::Forbidden(m) => ApiError::new(StatusCode::FORBIDDEN, m),
            CommandError::Invalid(m) => ApiError::bad_request(m),
        }
    }
}

/// The 403 message when no token is presented where `from` says to look.
fn missing(from: TokenFrom) -> &'static str {
    match from {
        TokenFrom::Bearer => MISSING_TOKEN,
        _ => MISSING_TOKEN_OR_QUERY,
    }
}

/// Who `creds` (read from `from`) act as on the live session `s`: its trainee or the
/// instructor, else 403.
pub(crate) fn live_actor(
    state: &AppState,
    creds: &Credentials,
    from: TokenFrom,
    s: &Session,
) -> Result<Actor, ApiError> {
    creds
        .principal(state, from, Some((&s.id, &s.control_token)))?
        .actor(missing(from))
}

/// Who `creds` (read from `from`) act as on session `id`, which is not live: the instructor,
/// or the trainee who held its control token (checked against the stored hash).
async fn ended_actor(
    state: &AppState,
    creds: &Credentials,
    from: TokenFrom,
    id: &str,
) -> Result<Actor, ApiError> {
    creds
        .principal_stored(state, from, id)
        .await?
        .actor(missing(from))
}

/// Who `creds` (read from `from`) act as on session `id`, live or ended ([`live_actor`],
/// [`ended_actor`]), with its trainee's name and group (a live session's own: its database row
/// may not be written yet); 421 naming the replica a session is live on, 404 for an unknown
/// session.
pub(crate) async fn session_actor(
    state: &AppState,
    creds: &Credentials,
    from: TokenFrom,
    id: &str,
) -> Result<(Actor, String, String), ApiError> {
    if let Some(s) = state.sessions.get(id) {
        let actor = live_actor(state, creds, from, &s)?;
        return Ok((actor, s.label.clone(), s.group.clone()));
    }
    if let Some(e) = crate::cluster::elsewhere(state, id).await {
        return Err(e);
    }
    let actor = ended_actor(state, creds, from, id).await?;
    let rec = state
        .db
        .session(id)
        .await
        .map_err(db_error)?
        .ok_or_else(|| ApiError::not_found(format!("no session `{id}`")))?;
    Ok((actor, rec.trainee, rec.group))
}

/// Body of `POST /api/sessions` (every field optional).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CreateRequest {
    /// Scenario (see `GET /api/scenarios`); `training` when absent.
    #[serde(default)]
    pub scenario: Option<String>,
    /// `joint` or `cartesian`.
    #[serde(default)]
    pub control_mode: Option<ControlMode>,
    /// `open` or `closed`.
    #[serde(default)]
    pub control_method: Option<ControlMethod>,
    /// Trainee label shown to instructors.
    #[serde(default)]
    pub label: Option<String>,
    /// An exercise id (see `GET /api/exercises`) to start on, instead of a `scenario`.
    #[serde(default)]
    pub exercise: Option<String>,
    /// The trainee's display name (same as `label`).
    #[serde(default)]
    pub trainee: Option<String>,
    /// The trainee's class or group (cleaned like the name: [`crate::names::display_name`]).
    #[serde(default)]
    pub group: Option<String>,
    /// The class join code, when the server requires one (or send `X-Join-Code`).
    #[serde(default)]
    pub join_code: Option<String>,
    /// Each exercise attempt waits for the trainee's `ready` before its clock starts (the
    /// trainee's page asks for it: the goal is read first); absent or false: it starts at
    /// once (scripts, the HTTP API).
    #[serde(default)]
    pub wait_for_ready: bool,
}

/// Answer of `POST /api/sessions`.
#[derive(Debug, Serialize)]
pub struct Created {
    /// Session id.
    pub id: String,
    /// Token that controls this session (keep it secret).
    pub control_token: String,
    /// WebSocket URL (token included).
    pub ws_url: String,
    /// The replica that holds it (docs/api.md "Replicas").
    pub replica: String,
    /// Path prefix of its URLs (`/r/<replica>` with several replicas, else empty): the REST
    /// routes of this session are `{base}/api/sessions/{id}/…`.
    pub base: String,
}

/// `POST /api/sessions`: 201; 403 without the class join code (when one is configured), or
/// on an exercise still locked for the trainee ([`crate::api::unlocks::check_start`]);
/// 429 (with `Retry-After`) when this client creates sessions too fast or holds too many;
/// 503 when the server is full. The instructor token (as a bearer) is exempt from the join
/// code and the per-client limits.
pub async fn create(
    State(state): State<AppState>,
    Peer(peer): Peer,
    creds: Credentials,
    headers: HeaderMap,
    body: axum::body::Bytes,
) -> Result<Response, ApiError> {
    let req: CreateRequest = if body.iter().all(u8::is_ascii_whitespace) {
        CreateRequest::default()
    } else {
        crate::json::parse(&body)?
    };
    let instructor = creds
        .principal(&state, TokenFrom::Bearer, None)?
        .is_instructor();
    let client = match admit(&state, peer.as_ref(), &headers, instructor) {
        Ok(client) => client,
        Err(resp) => return Ok(*resp),
    };
    if let (Some(code), false) = (&state.join_code, instructor) {
        let presented = req
            .join_code
            .as_deref()
            .or_else(|| headers.get("x-join-code").and_then(|v| v.to_str().ok()));
        if !presented.is_some_and(|p| token_eq(p, code)) {
            return Err(ApiError::forbidden(
                "this server needs the class join code (`join_code` field or X-Join-Code header)",
            ));
        }
    }
    if req.exercise.is_some() && req.scenario.is_some() {
        return Err(ApiError::bad_request(
            "give `exercise` or `scenario`, not both",
        ));
    }
    if req.trainee.is_some() && req.label.is_some() {
        return Err(ApiError::bad_request("give `trainee` or `label`, not both"));
    }
    let scenario = req.exercise.or(req.scenario);
    let label = req.trainee.or(req.label);
    crate::api::unlocks::check_start(
        &state,
        instructor,
        scenario.as_deref(),
        &crate::names::display_name(label.as_deref().unwrap_or_default()),
        &crate::names::display_name(req.group.as_deref().unwrap_or_default()),
    )
    .await?;
    let base = ws_base(&state.policy, &headers, peer.as_ref())
        .ok_or_else(|| ApiError::bad_request("missing or malformed Host header"))?;
    let sessions = state.sessions.clone();
    let session = tokio::task::spawn_blocking(move || {
        sessions.create(
            client,
            crate::sessions::NewSession {
                scenario,
                mode: req.control_mode,
                method: req.control_method,
                label,
                group: req.group,
                wait_for_ready: req.wait_for_ready,
            },
        )
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
    .map_err(create_error)?;
    created(&state, &session, &base).await
}

/// Who creates a session, by the same admission rules for every way of creating one
/// (`POST /api/sessions`, a take-over): the instructor is exempt, anyone else is a client by
/// address, limited by the creation limiter (429); a draining replica creates none (503).
pub(crate) fn admit(
    state: &AppState,
    peer: Option<&axum::extract::ConnectInfo<std::net::SocketAddr>>,
    headers: &HeaderMap,
    instructor: bool,
) -> Result<ClientKey, Box<Response>> {
    let client = if instructor {
        ClientKey::Exempt
    } else {
        let ip = client_ip(peer, headers, &state.policy.trusted_proxies)
            .unwrap_or(std::net::Ipv4Addr::UNSPECIFIED.into());
        ClientKey::from_ip(ip)
    };
    if let Err(wait) = state.creation_limiter.check(client) {
        return Err(Box::new(too_many(
            format!(
                "too many new sessions from this client: at most {} at once, then {} per minute",
                state.creation_limiter.burst(),
                state.creation_limiter.per_minute()
            ),
            wait,
        )));
    }
    if state.cluster.draining() {
        return Err(Box::new(
            ApiError::new(
                StatusCode::SERVICE_UNAVAILABLE,
                format!(
                    "replica `{}` is draining (shutting down); try again",
                    state.cluster.name
                ),
            )
            .into_response(),
        ));
    }
    Ok(client)
}

/// The answer to a refused creation.
pub(crate) fn create_error(e: CreateError) -> ApiError {
    match e {
        CreateError::Full(_) | CreateError::Recording(_) => {
            ApiError::new(StatusCode::SERVICE_UNAVAILABLE, e.to_string())
        }
        CreateError::ClientFull(_) => ApiError::new(StatusCode::TOO_MANY_REQUESTS, e.to_string()),
        CreateError::UnknownScenario(_) => {
            ApiError::bad_request(e.to_string()).with_detail(serde_json::json!({
                "known": crate::catalogue::live_names()
            }))
        }
        CreateError::Sim(_) => ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}

/// 201 with [`Created`] and the trainee's cookie for a new `session` (`base`: the
/// WebSocket URL's scheme and host); with several replicas, the session directory learns
/// where it lives first.
pub(crate) async fn created(
    state: &AppState,
    session: &Session,
    base: &str,
) -> Result<Response, ApiError> {
    let prefix = state.cluster.base();
    let ws_url = format!(
        "{base}{prefix}/ws/sessions/{}?token={}",
        session.id, session.control_token
    );
    if state.cluster.multi {
        // Other replicas learn where it lives now, not at the next heartbeat.
        let summary = directory_summary(state, session).to_string();
        let put = state.db.directory_put(
            session.id.clone(),
            state.cluster.name.clone(),
            crate::clock::unix_now(),
            summary,
        );
        if let Err(e) = put.await {
            tracing::warn!(id = %session.id, "session directory: {e:#}");
        }
    }
    // The page's debrief links need no token in their URL: this browser keeps it.
    let cookie = crate::auth::set_cookie(
        &crate::auth::trainee_cookie_name(&session.id),
        &session.control_token,
        TRAINEE_COOKIE_S,
        crate::api::signin::secure_cookies(state),
    );
    let body = Created {
        id: session.id.clone(),
        control_token: session.control_token.clone(),
        ws_url,
        replica: state.cluster.name.clone(),
        base: prefix,
    };
    let mut resp = (StatusCode::CREATED, Json(body)).into_response();
    if let Ok(v) = HeaderValue::from_str(&cookie) {
        resp.headers_mut().insert(header::SET_COOKIE, v);
    }
    Ok(resp)
}

/// How long a trainee's session cookie lasts (s): a week, for the debriefs afterwards.
const TRAINEE_COOKIE_S: u64 = 7 * 24 * 3600;

/// 429 with `Retry-After` (whole seconds, at least 1) in the header and the body.
fn too_many(message: String, wait: std::time::Duration) -> Response {
    let secs = wait.as_secs_f64().ceil().max(1.0) as u64;
    let mut resp = ApiError::new(StatusCode::TOO_MANY_REQUESTS, message)
        .with_detail(serde_json::json!({"retry_after_s": secs}))
        .into_response();
    resp.headers_mut()
        .insert(header::RETRY_AFTER, HeaderValue::from(secs));
    resp
}

/// Translational measures of one arm in a summary.
#[derive(Debug, Serialize)]
pub struct ArmSummary {
    /// √det(JJᵀ).
    pub yoshikawa: f64,
    /// σmin/σmax.
    pub isotropy: f64,
    /// Hong's index.
    pub hong: f64,
    /// JLM.
    pub jlm: f64,
}

/// One session in `GET /api/sessions`.
#[derive(Debug, Serialize)]
pub struct SessionSummary {
    /// Id.
    pub id: String,
    /// `live` or `ended`.
    pub status: &'static str,
    /// Trainee label.
    pub label: String,
    /// Trainee display name (the same as `label`).
    pub trainee: String,
    /// The trainee's class or group ("" when none).
    pub group: String,
    /// Ids of the session's recorded attempts, newest first.
    pub attempts: Vec<String>,
    /// Scenario.
    pub scenario: String,
    /// Unix seconds.
    pub created_unix: f64,
    /// Unix seconds, ended sessions only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ended_unix: Option<f64>,
    /// Why it ended.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_reason: Option<String>,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Grasp state (live only; wire names of [`crate::protocol::grasp_name`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grasp: Option<&'static str>,
    /// Paused (live only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paused: Option<bool>,
    /// Trainee connections (live only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trainees: Option<u64>,
    /// Per-arm translational measures (live only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measures: Option<[ArmSummary; 2]>,
    /// Relief-valve events (overloads).
    pub overload_count: u64,
    /// Active faults (live only). The session's own trainee is not shown silent ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faults: Option<Vec<FaultSummary>>,
    /// `ok`, or `failed` when part of the session's record could not be written.
    pub recording: &'static str,
    /// What the instructor's roster shows of a live session (absent for ended ones).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub roster: Option<Roster>,
    /// The replica holding it (live only; docs/api.md "Replicas").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replica: Option<String>,
    /// Path prefix of its URLs (live only; `/r/<replica>` with several replicas, else empty).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base: Option<String>,
}

/// The roster fields of a live session's summary.
#[derive(Debug, Serialize)]
pub struct Roster {
    /// Who paused the clock (`instructor`, `trainee`), `null` while it runs.
    pub paused_by: Option<Actor>,
    /// The running exercise attempt, `null` in free play.
    pub exercise: Option<ExerciseSummary>,
    /// The warnings of the session's current state frame.
    pub warnings: Vec<String>,
    /// The running attempt's id.
    pub attempt: String,
    /// The exercise waits for the trainee's "Ready" (its clock has not started).
    pub awaiting_ready: bool,
}

/// A running exercise attempt in the roster.
#[derive(Debug, Serialize)]
pub struct ExerciseSummary {
    /// Exercise id.
    pub id: String,
    /// Its title.
    pub title: String,
    /// Steps done (the current step's 0-based index; `steps_total` once all are done).
    pub step: usize,
    /// Number of steps.
    pub steps_total: usize,
    /// Overall progress in [0, 1].
    pub progress: f64,
    /// Score so far, 0–100 (final once done).
    pub score: f64,
    /// `running`, `passed` or `failed`.
    pub status: &'static str,
}

impl ExerciseSummary {
    /// The summary of the attempt `run` on `sim`.
    fn new(run: &ExerciseRun, sim: &Simulation) -> ExerciseSummary {
        let st = run.status(sim);
        ExerciseSummary {
            id: st.id,
            title: run.spec().title.clone(),
            step: st.step,
            steps_total: st.steps,
            progress: st.progress,
            score: st.score,
            status: match (st.done, st.passed) {
                (false, _) => "running",
                (true, true) => "passed",
                (true, false) => "failed",
            },
        }
    }
}

/// An active fault in a session summary.
#[derive(Debug, Serialize)]
pub struct FaultSummary {
    /// Its label ([`crate::protocol::fault_label`], as state frames list faults).
    pub label: String,
    /// Injected without telling the trainee (absent from the state frames).
    pub silent: bool,
}

/// The live summary of `s` as `viewer` may see it (the session's trainee is not shown
/// silent faults).
fn live_summary(
    s: &Session,
    recording: &'static str,
    attempts: Vec<String>,
    viewer: Actor,
) -> SessionSummary {
    let live = s.live();
    let sim = live.sim();
    // The measures of the last published frame.
    let arm = |arm: Arm| {
        let m = &live.measures().arms[arm.index()];
        ArmSummary {
            yoshikawa: m.translational.yoshikawa,
            isotropy: m.translational.isotropy,
            hong: m.translational.hong,
            jlm: m.jlm,
        }
    };
    SessionSummary {
        id: s.id.clone(),
        status: "live",
        label: s.label.clone(),
        trainee: s.label.clone(),
        group: s.group.clone(),
        attempts,
        scenario: live.scenario().name().to_string(),
        created_unix: s.created_unix,
        ended_unix: None,
        end_reason: None,
        sim_seconds: sim.time_s(),
        grasp: Some(grasp_name(sim.grasp_state())),
        paused: Some(live.paused()),
        trainees: Some(s.trainees.load(std::sync::atomic::Ordering::Relaxed)),
        measures: Some(Arm::BOTH.map(arm)),
        overload_count: s.overloads.load(std::sync::atomic::Ordering::Relaxed),
        faults: Some(
            live.faults()
                .iter()
                .filter(|f| viewer == Actor::Instructor || !f.silent)
                .map(|f| FaultSummary {
                    label: fault_label(f),
                    silent: f.silent,
                })
                .collect(),
        ),
        recording,
        roster: Some(Roster {
            paused_by: live.paused_by(),
            exercise: live.exercise().map(|run| ExerciseSummary::new(run, sim)),
            warnings: crate::sessions::snapshot::warnings(&live),
            attempt: live.attempt_id().to_string(),
            awaiting_ready: live.awaiting_ready(),
        }),
        replica: None,
        base: None,
    }
}

/// `summary` placed on this replica (its `replica` and `base`).
fn placed(state: &AppState, mut summary: SessionSummary) -> SessionSummary {
    summary.replica = Some(state.cluster.name.clone());
    summary.base = Some(state.cluster.base());
    summary
}

/// A live session's summary as the instructor sees it, for the session directory (other
/// replicas list it from there; attempts are read from the records there).
pub(crate) fn directory_summary(state: &AppState, s: &Session) -> serde_json::Value {
    let recording = state.sessions.recorder.recording(&s.id);
    serde_json::to_value(placed(
        state,
        live_summary(s, recording, Vec::new(), Actor::Instructor),
    ))
    .unwrap_or_default()
}

fn ended_summary(
    mut r: crate::db::SessionRecord,
    failed_now: bool,
    attempts: Vec<String>,
    unstored_end: Option<crate::sessions::record::UnstoredEnd>,
) -> SessionSummary {
    // ended while its end could not be stored (a full disk): the end the recorder holds,
    // not "interrupted" with the last stored progress
    if let (None, Some(end)) = (&r.end_reason, unstored_end) {
        r.ended_unix = Some(end.ended_unix);
        r.end_reason = Some(end.reason);
        r.sim_seconds = end.sim_seconds;
    }
    SessionSummary {
        id: r.id,
        status: "ended",
        label: r.trainee.clone(),
        trainee: r.trainee,
        group: r.group,
        attempts,
        scenario: r.scenario,
        created_unix: r.created_unix,
        ended_unix: r.ended_unix,
        end_reason: Some(
            r.end_reason
                .unwrap_or_else(|| crate::db::INTERRUPTED.into()),
        ),
        sim_seconds: r.sim_seconds,
        grasp: None,
        paused: None,
        trainees: None,
        measures: None,
        overload_count: r.overloads,
        faults: None,
        recording: if r.recording_failed || failed_now {
            "failed"
        } else {
            "ok"
        },
        roster: None,
        replica: None,
        base: None,
    }
}

/// Waits until the recorder has stored everything queued so far (sessions just ended).
async fn flush_records(state: &AppState) {
    let sessions = state.sessions.clone();
    let _ = tokio::task::spawn_blocking(move || sessions.recorder.flush()).await;
}

/// `GET /api/sessions` (instructor): live sessions with live summaries, then finished ones
/// from the records database (oldest first).
pub async fn list(
    State(state): State<AppState>,
    creds: Credentials,
    axum::extract::Query(page): axum::extract::Query<ListPage>,
) -> Result<Response, ApiError> {
    creds.require_instructor(&state)?;
    if let Some(b) = page.before.as_deref().filter(|b| !valid_id(b)) {
        return Err(ApiError::bad_request(format!(
            "`before` is not a session id: `{b}`"
        )));
    }
    let limit = page.ended.unwrap_or(DEFAULT_ENDED).min(MAX_ENDED);
    flush_records(&state).await;
    let live: Vec<Arc<Session>> = state.sessions.all();
    // The live sessions are listed even when the database cannot be read (their summaries
    // are in memory, and say `recording: failed`); then the stored ones are left out.
    let mut stored = state
        .db
        .sessions_page(page.before.as_deref(), limit)
        .await
        .unwrap_or_else(|e| {
            tracing::warn!("session list without the stored sessions: {e:#}");
            Vec::new()
        });
    // the page was full: the next one starts after its last session
    let next = (limit > 0 && stored.len() == limit)
        .then(|| stored.last().map(|r| r.id.clone()))
        .flatten();
    // Sessions that ended while their end could not be stored (a full disk): not yet among
    // the stored ended ones, and the newest — first on the first page.
    if page.before.is_none() {
        for id in state.sessions.recorder.unstored_end_ids() {
            if stored.iter().any(|r| r.id == id) || state.sessions.get(&id).is_some() {
                continue;
            }
            if let Ok(Some(r)) = state.db.session(&id).await {
                stored.insert(0, r);
            }
        }
    }
    let mut ids: Vec<String> = live.iter().map(|s| s.id.clone()).collect();
    ids.extend(stored.iter().map(|r| r.id.clone()));
    let mut attempts: std::collections::HashMap<String, Vec<String>> =
        std::collections::HashMap::new();
    let listed = state.db.attempt_ids_of(&ids).await.unwrap_or_else(|e| {
        tracing::warn!("session list without attempt ids: {e:#}");
        Vec::new()
    });
    for (session, attempt) in listed {
        attempts.entry(session).or_default().push(attempt);
    }
    let recorder = &state.sessions.recorder;
    let value = |s: SessionSummary| serde_json::to_value(s).unwrap_or_default();
    let mut out: Vec<serde_json::Value> = live
        .iter()
        .map(|s| {
            let a = attempts.remove(&s.id).unwrap_or_default();
            value(placed(
                &state,
                live_summary(s, recorder.recording(&s.id), a, Actor::Instructor),
            ))
        })
        .collect();
    let mut live_ids: std::collections::HashSet<String> =
        live.iter().map(|s| s.id.clone()).collect();
    // Other replicas' live sessions, as their last heartbeat summarised them.
    if state.cluster.multi {
        let others = state
            .db
            .directory_others(&state.cluster.name)
            .await
            .map_err(db_error)?;
        for (id, _, summary) in others {
            let Ok(mut v) = serde_json::from_str::<serde_json::Value>(&summary) else {
                continue;
            };
            v["attempts"] = serde_json::json!(attempts.remove(&id).unwrap_or_default());
            live_ids.insert(id);
            out.push(v);
        }
    }
    out.extend(
        stored
            .into_iter()
            .filter(|r| !live_ids.contains(&r.id))
            .map(|r| {
                let failed = recorder.recording(&r.id) == "failed";
                let a = attempts.remove(&r.id).unwrap_or_default();
                let end = recorder.unstored_end(&r.id);
                value(ended_summary(r, failed, a, end))
            }),
    );
    let mut resp = Json(out).into_response();
    if let Some(v) = next.and_then(|n| HeaderValue::from_str(&n).ok()) {
        resp.headers_mut().insert(NEXT_PAGE_HEADER, v);
    }
    Ok(resp)
}

/// Ended sessions a list gives by default, and at most.
const DEFAULT_ENDED: usize = 50;
const MAX_ENDED: usize = 500;
/// The header naming the `before` of the next page of ended sessions (absent on the last).
const NEXT_PAGE_HEADER: &str = "x-next-before";

/// Query of `GET /api/sessions`: every live session, then a page of the stored ones, newest
/// first.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ListPage {
    /// How many stored sessions (default [`DEFAULT_ENDED`], at most [`MAX_ENDED`]).
    ended: Option<usize>,
    /// Only those older than this session (the previous page's `X-Next-Before`).
    before: Option<String>,
}

/// `GET /api/sessions/{id}`: one session's summary (instructor, or its own trainee — also
/// after it ended).
pub async fn get_one(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Json<SessionSummary>, ApiError> {
    let ids = |v: Vec<(String, String)>| v.into_iter().map(|(_, a)| a).collect::<Vec<_>>();
    if let Some(s) = state.sessions.get(&id) {
        let viewer = live_actor(&state, &creds, TokenFrom::Bearer, &s)?;
        flush_records(&state).await;
        // A live session's summary is in memory: a database that cannot be read (the
        // instructor needs to see `recording: failed` then) leaves only its attempt list out.
        let attempts = ids(state.db.attempt_ids(Some(&id)).await.unwrap_or_else(|e| {
            tracing::warn!(%id, "session summary without its attempts: {e:#}");
            Vec::new()
        }));
        return Ok(Json(placed(
            &state,
            live_summary(
                &s,
                state.sessions.recorder.recording(&s.id),
                attempts,
                viewer,
            ),
        )));
    }
    if let Some(e) = crate::cluster::elsewhere(&state, &id).await {
        return Err(e);
    }
    ended_actor(&state, &creds, TokenFrom::Bearer, &id).await?;
    flush_records(&state).await;
    let record = state
        .db
        .session(&id)
        .await
        .map_err(db_error)?
        .ok_or_else(|| ApiError::not_found(format!("no session `{id}`")))?;
    let attempts = ids(state.db.attempt_ids(Some(&id)).await.map_err(db_error)?);
    let failed = state.sessions.recorder.recording(&id) == "failed";
    let end = state.sessions.recorder.unstored_end(&id);
    Ok(Json(ended_summary(record, failed, attempts, end)))
}

/// `DELETE /api/sessions/{id}`: end a live session (the instructor any, a trainee its own);
/// 404 when no such session is live.
pub async fn end(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    let s = live_session(&state, &id).await?;
    let actor = live_actor(&state, &creds, TokenFrom::Bearer, &s)?;
    let sessions = state.sessions.clone();
    tokio::task::spawn_blocking(move || command::apply(&sessions, &s, actor, Command::End))
        .await
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))??;
    Ok(StatusCode::NO_CONTENT)
}

pub(crate) async fn live_session(state: &AppState, id: &str) -> Result<Arc<Session>, ApiError> {
    if let Some(s) = state.sessions.get(id) {
        return Ok(s);
    }
    Err(crate::cluster::elsewhere(state, id)
        .await
        .unwrap_or_else(|| ApiError::not_found(format!("no live session `{id}`"))))
}

/// `POST /api/sessions/{id}/actions`.
pub async fn act(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
    ApiJson(action): ApiJson<Action>,
) -> Result<StatusCode, ApiError> {
    let s = live_session(&state, &id).await?;
    let actor = live_actor(&state, &creds, TokenFrom::Bearer, &s)?;
    let command = Command::try_from(action)?;
    command::apply(&state.sessions, &s, actor, command)?;
    Ok(StatusCode::NO_CONTENT)
}

/// `GET /api/sessions/{id}/assessment` (the session's trainee or the instructor): the
/// assessment of the live session's current exercise attempt (final once it is done);
/// 404 for an unknown or ended session, 409 when it runs no exercise.
pub async fn assessment(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Json<Value>, ApiError> {
    let session = live_session(&state, &id).await?;
    let actor = live_actor(&state, &creds, TokenFrom::BearerOrQuery, &session)?;
    let live = session.live();
    live.exercise()
        .map(|r| Json(assessment_for(r.assessment(), actor)))
        .ok_or_else(|| {
            ApiError::new(
                StatusCode::CONFLICT,
                format!(
                    "session `{id}` runs `{}`, not an exercise",
                    live.scenario().name()
                ),
            )
        })
}

/// The assessment as `actor` may read it: until the attempt is done, the trainee is not told
/// its seed (it draws a drill's fault and time) nor the drill's fault and injection time
/// (issue 29: the drill could be read off this route).
fn assessment_for(a: seaarms_core::exercise::Assessment, actor: Actor) -> Value {
    let done = a.done;
    let mut v = serde_json::to_value(a).unwrap_or(Value::Null);
    if actor != Actor::Instructor && !done {
        if let Some(o) = v.as_object_mut() {
            o.remove("seed");
            o.remove("diagnosis");
        }
    }
    v
}

/// `GET /api/sessions/{id}/log.csv`: the session's record (flushed first); the instructor or
/// the session's trainee (also after it ended).
pub async fn log_csv(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    if !valid_id(&id) {
        return Err(ApiError::not_found(format!("no session `{id}`")));
    }
    // live on another replica: 421 naming it (docs/api.md), as its other routes
    session_actor(&state, &creds, TokenFrom::BearerOrQuery, &id).await?;
    let path = state
        .sessions
        .recorder
        .log_path(&id)
        .ok_or_else(|| ApiError::not_found(format!("no session `{id}`")))?;
    let sessions = state.sessions.clone();
    tokio::task::spawn_blocking(move || sessions.recorder.flush())
        .await
        .ok();
    let mut bytes = tokio::fs::read(&path)
        .await
        .map_err(|_| ApiError::not_found(format!("no record for session `{id}`")))?;
    // Only whole rows, even if a write is under way or a crash cut the last one.
    bytes.truncate(crate::csv_out::complete_lines(&bytes).len());
    Ok((
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"seaarms-{id}.csv\""),
            ),
        ],
        bytes,
    )
        .into_response())
}
