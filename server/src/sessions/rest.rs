//! REST endpoints of sessions. Tokens travel as `Authorization: Bearer …` (the CSV download
//! also accepts `?token=` so a plain link works). The instructor token may do everything;
//! a trainee's control token acts on its own session only.

use std::sync::Arc;

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use seaarms_core::analysis::TRANSLATIONAL_ROWS;
use seaarms_core::manipulability::{jlm, measures};
use seaarms_core::sim::{LEFT, RIGHT};
use serde::{Deserialize, Serialize};

use super::record::{RecordMsg, SessionRecord, valid_id};
use super::{CreateError, LIVE_SCENARIOS, Session, token_eq};
use crate::app::AppState;
use crate::error::ApiError;
use crate::json::ApiJson;
use crate::protocol::{ControlMethod, ControlMode, ServerMessage};

fn forbidden(msg: &str) -> ApiError {
    ApiError {
        status: StatusCode::FORBIDDEN,
        error: msg.into(),
        detail: None,
    }
}

fn bearer(headers: &HeaderMap) -> Option<&str> {
    headers
        .get(header::AUTHORIZATION)?
        .to_str()
        .ok()?
        .strip_prefix("Bearer ")
        .map(str::trim)
}

/// Who a request acts as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Caller {
    Instructor,
    Trainee,
}

fn caller(
    state: &AppState,
    token: Option<&str>,
    session: Option<&Session>,
) -> Result<Caller, ApiError> {
    let Some(token) = token else {
        return Err(forbidden("missing token (Authorization: Bearer …)"));
    };
    if token_eq(token, &state.instructor_token) {
        return Ok(Caller::Instructor);
    }
    if let Some(s) = session {
        if token_eq(token, &s.control_token) {
            return Ok(Caller::Trainee);
        }
    }
    Err(forbidden("wrong token"))
}

fn require_instructor(state: &AppState, headers: &HeaderMap) -> Result<(), ApiError> {
    match caller(state, bearer(headers), None)? {
        Caller::Instructor => Ok(()),
        Caller::Trainee => Err(forbidden("instructor token required")),
    }
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
}

/// `POST /api/sessions`: 201, or 503 when the server is full.
pub async fn create(
    State(state): State<AppState>,
    headers: HeaderMap,
    body: axum::body::Bytes,
) -> Result<Response, ApiError> {
    let req: CreateRequest = if body.iter().all(u8::is_ascii_whitespace) {
        CreateRequest::default()
    } else {
        serde_json::from_slice(&body)
            .map_err(|e| ApiError::bad_request(format!("invalid request: {e}")))?
    };
    let sessions = state.sessions.clone();
    let session = tokio::task::spawn_blocking(move || sessions.create(req.scenario, req.control_mode, req.control_method, req.label))
        .await
        .map_err(|e| ApiError { status: StatusCode::INTERNAL_SERVER_ERROR, error: e.to_string(), detail: None })?
        .map_err(|e| match e {
            CreateError::Full(_) | CreateError::Recording(_) => ApiError { status: StatusCode::SERVICE_UNAVAILABLE, error: e.to_string(), detail: None },
            CreateError::UnknownScenario(_) => ApiError::bad_request(e.to_string())
                .with_detail(serde_json::json!({"known": LIVE_SCENARIOS.iter().map(|(n, _)| *n).collect::<Vec<_>>()})),
            CreateError::Sim(_) => ApiError { status: StatusCode::INTERNAL_SERVER_ERROR, error: e.to_string(), detail: None },
        })?;
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("127.0.0.1:8080");
    // Behind a TLS-terminating proxy (classroom deployments) the page must use wss://.
    let scheme = match headers
        .get("x-forwarded-proto")
        .and_then(|h| h.to_str().ok())
    {
        Some(p) if p.eq_ignore_ascii_case("https") => "wss",
        _ => "ws",
    };
    let ws_url = format!(
        "{scheme}://{host}/ws/sessions/{}?token={}",
        session.id, session.control_token
    );
    let body = Created {
        id: session.id.clone(),
        control_token: session.control_token.clone(),
        ws_url,
    };
    Ok((StatusCode::CREATED, Json(body)).into_response())
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
    /// Grasp state (live only).
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
    /// Active faults (live only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faults: Option<Vec<String>>,
    /// `ok`, or `failed` when part of the session's record could not be written.
    pub recording: &'static str,
}

fn live_summary(s: &Session, recording: &'static str) -> SessionSummary {
    let live = s.live();
    let arm = |i: usize| {
        let jt = live.sim.jacobian_world(i).fixed_rows::<3>(0).into_owned();
        let j = nalgebra::DMatrix::from_column_slice(3, 6, jt.as_slice());
        let m = measures(&j).ok();
        let _ = TRANSLATIONAL_ROWS;
        ArmSummary {
            yoshikawa: m.as_ref().map_or(0.0, |m| m.yoshikawa),
            isotropy: m.as_ref().map_or(0.0, |m| m.isotropy),
            hong: m.as_ref().map_or(0.0, |m| m.hong),
            jlm: jlm(&s.models[i], &live.sim.arm(i).q),
        }
    };
    SessionSummary {
        id: s.id.clone(),
        status: "live",
        label: s.label.clone(),
        scenario: s.scenario(),
        created_unix: s.created_unix,
        ended_unix: None,
        end_reason: None,
        sim_seconds: live.sim.time_s(),
        grasp: Some(live.sim.grasp_state().as_str()),
        paused: Some(live.paused),
        trainees: Some(s.trainees.load(std::sync::atomic::Ordering::Relaxed)),
        measures: Some([arm(LEFT), arm(RIGHT)]),
        overload_count: s.overloads.load(std::sync::atomic::Ordering::Relaxed),
        faults: Some(live.faults.clone()),
        recording,
    }
}

fn ended_summary(r: SessionRecord) -> SessionSummary {
    SessionSummary {
        id: r.id,
        status: "ended",
        label: r.label,
        scenario: r.scenario,
        created_unix: r.created_unix,
        ended_unix: r.ended_unix,
        end_reason: Some(
            r.end_reason
                .unwrap_or_else(|| "interrupted (server stopped)".into()),
        ),
        sim_seconds: r.sim_seconds.unwrap_or(0.0),
        grasp: None,
        paused: None,
        trainees: None,
        measures: None,
        overload_count: r.overloads.unwrap_or(0),
        faults: None,
        recording: if r.recording_failed { "failed" } else { "ok" },
    }
}

/// `GET /api/sessions` (instructor): live sessions with live summaries, then finished ones
/// from the on-disk index (newest last).
pub async fn list(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Vec<SessionSummary>>, ApiError> {
    require_instructor(&state, &headers)?;
    let live: Vec<Arc<Session>> = state.sessions.all();
    let live_ids: Vec<String> = live.iter().map(|s| s.id.clone()).collect();
    let recorder_index = {
        let sessions = state.sessions.clone();
        tokio::task::spawn_blocking(move || sessions.recorder.index())
            .await
            .unwrap_or_default()
    };
    let recorder = &state.sessions.recorder;
    let mut out: Vec<SessionSummary> = live
        .iter()
        .map(|s| live_summary(s, recorder.recording(&s.id)))
        .collect();
    out.extend(
        recorder_index
            .into_iter()
            .filter(|r| !live_ids.contains(&r.id))
            .map(ended_summary),
    );
    Ok(Json(out))
}

/// `GET /api/sessions/{id}`: one session's summary (instructor, or its own trainee).
pub async fn get_one(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<Json<SessionSummary>, ApiError> {
    if let Some(s) = state.sessions.get(&id) {
        caller(&state, bearer(&headers), Some(&s))?;
        return Ok(Json(live_summary(
            &s,
            state.sessions.recorder.recording(&s.id),
        )));
    }
    require_instructor(&state, &headers)?;
    let index = state.sessions.recorder.index();
    index
        .into_iter()
        .find(|r| r.id == id)
        .map(|r| Json(ended_summary(r)))
        .ok_or_else(|| ApiError::not_found(format!("no session `{id}`")))
}

/// `DELETE /api/sessions/{id}`: end a session (instructor, or its own trainee).
pub async fn end(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    let s = state
        .sessions
        .get(&id)
        .ok_or_else(|| ApiError::not_found(format!("no live session `{id}`")))?;
    let who = caller(&state, bearer(&headers), Some(&s))?;
    let sessions = state.sessions.clone();
    let reason = if who == Caller::Instructor {
        "ended by instructor"
    } else {
        "ended by trainee"
    };
    tokio::task::spawn_blocking(move || sessions.end(&id, reason))
        .await
        .ok();
    Ok(StatusCode::NO_CONTENT)
}

/// Instructor (and, for the first four, trainee) actions on a session.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Back to the initial position.
    Reset,
    /// Pause the clock.
    Pause,
    /// Resume it.
    Resume,
    /// Open both jaws.
    Release,
    /// Change scenario (resets the session).
    Scenario {
        /// Scenario name.
        scenario: String,
    },
    /// Inject a fault.
    Fault {
        /// `supply_drop` (value: Pa, 0..6.89e6), `stuck_valve` (joint 0..5, value: spool in
        /// [−1, 1]), `leak` (joint, value: m³/(s·Pa) in [0, 1e-9]), `air` (value: bulk-modulus
        /// scale in [0.01, 1]).
        fault: String,
        /// `left` or `right`.
        arm: String,
        /// Joint index 0..5 (stuck_valve, leak).
        #[serde(default)]
        joint: Option<usize>,
        /// Size of the fault (see `fault`).
        value: f64,
    },
    /// Remove every fault.
    ClearFaults,
    /// Show a message on the trainee's page.
    Message {
        /// Up to 500 characters.
        text: String,
    },
}

/// `POST /api/sessions/{id}/actions`.
pub async fn act(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    ApiJson(action): ApiJson<Action>,
) -> Result<StatusCode, ApiError> {
    let s = state
        .sessions
        .get(&id)
        .ok_or_else(|| ApiError::not_found(format!("no live session `{id}`")))?;
    let who = caller(&state, bearer(&headers), Some(&s))?;
    let trainee_allowed = matches!(
        action,
        Action::Reset | Action::Pause | Action::Resume | Action::Release
    );
    if who == Caller::Trainee && !trainee_allowed {
        return Err(forbidden("instructor token required for this action"));
    }
    let by = if who == Caller::Instructor {
        "instructor"
    } else {
        "trainee"
    };
    let mut event = serde_json::json!({"event": "action", "by": by});
    {
        let mut live = s.live();
        let t = live.sim.time_s();
        event["t"] = serde_json::json!(t);
        match &action {
            Action::Reset => super::ws::reset(&mut live),
            Action::Pause => live.paused = true,
            Action::Resume => live.paused = false,
            Action::Release => live.release_until_s = t + 1.0,
            Action::Scenario { scenario } => {
                if !LIVE_SCENARIOS.iter().any(|(n, _)| n == scenario) {
                    return Err(ApiError::bad_request(format!(
                        "unknown scenario `{scenario}`"
                    )));
                }
                *s.scenario.lock().unwrap_or_else(|e| e.into_inner()) = scenario.clone();
                super::ws::reset(&mut live);
            }
            Action::Fault {
                fault,
                arm,
                joint,
                value,
            } => {
                let a = match arm.as_str() {
                    "left" => LEFT,
                    "right" => RIGHT,
                    _ => {
                        return Err(ApiError::bad_request(format!(
                            "arm must be `left` or `right`, got `{arm}`"
                        )));
                    }
                };
                let joint_index = || -> Result<usize, ApiError> {
                    match joint {
                        Some(j) if *j < 6 => Ok(*j),
                        _ => Err(ApiError::bad_request("this fault needs `joint` in 0..=5")),
                    }
                };
                let in_range = |lo: f64, hi: f64| -> Result<f64, ApiError> {
                    if value.is_finite() && *value >= lo && *value <= hi {
                        Ok(*value)
                    } else {
                        Err(ApiError::bad_request(format!(
                            "`value` for {fault} must be in [{lo}, {hi}], got {value}"
                        )))
                    }
                };
                let label = match fault.as_str() {
                    "supply_drop" => {
                        let v = in_range(0.0, 6.89e6)?;
                        live.sim.faults_mut(a).supply_drop_pa = v;
                        format!("supply_drop:{arm}:{v:.0}Pa")
                    }
                    "stuck_valve" => {
                        let (j, v) = (joint_index()?, in_range(-1.0, 1.0)?);
                        live.sim.faults_mut(a).stuck_valve[j] = Some(v);
                        format!("stuck_valve:{arm}:{j}:{v}")
                    }
                    "leak" => {
                        let (j, v) = (joint_index()?, in_range(0.0, 1e-9)?);
                        live.sim.faults_mut(a).leak_m3_s_pa[j] = v;
                        format!("leak:{arm}:{j}:{v:e}")
                    }
                    "air" => {
                        let v = in_range(0.01, 1.0)?;
                        live.sim.faults_mut(a).bulk_modulus_scale = v;
                        format!("air:{arm}:{v}")
                    }
                    other => {
                        return Err(ApiError::bad_request(format!(
                            "unknown fault `{other}` (supply_drop, stuck_valve, leak, air)"
                        )));
                    }
                };
                live.faults.push(label);
            }
            Action::ClearFaults => {
                for a in [LEFT, RIGHT] {
                    *live.sim.faults_mut(a) = Default::default();
                }
                live.faults.clear();
            }
            Action::Message { text } => {
                if text.chars().count() > 500 {
                    return Err(ApiError::bad_request(
                        "message text is limited to 500 characters",
                    ));
                }
                let msg = ServerMessage::Message {
                    from: "instructor".into(),
                    text: text.clone(),
                };
                let _ = s
                    .notices
                    .send(serde_json::to_string(&msg).unwrap_or_default().into());
            }
        }
    }
    event["action"] = serde_json::to_value(format!("{action:?}")).unwrap_or_default();
    state.sessions.recorder.send(RecordMsg::Event {
        id: s.id.clone(),
        json: event.to_string(),
    });
    Ok(StatusCode::NO_CONTENT)
}

/// Query of the CSV download.
#[derive(Debug, Deserialize)]
pub struct TokenQuery {
    /// Token, for plain download links.
    pub token: Option<String>,
}

/// `GET /api/sessions/{id}/log.csv`: the session's record (flushed first).
pub async fn log_csv(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    Query(q): Query<TokenQuery>,
) -> Result<Response, ApiError> {
    if !valid_id(&id) {
        return Err(ApiError::not_found(format!("no session `{id}`")));
    }
    let token = bearer(&headers).or(q.token.as_deref());
    let live = state.sessions.get(&id);
    caller(&state, token, live.as_deref())?;
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
