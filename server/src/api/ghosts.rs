//! Ghosts (issue 30 item 5): an earlier attempt drawn see-through beside a live attempt or a
//! debrief, time-aligned, and the attempts a trainee may compare with.
//!
//! * `GET /api/sessions/{id}/ghosts?exercise=` (the session's trainee — its control token or
//!   cookie, also after it ended — or the instructor): which attempts may be the ghost on that
//!   exercise. `best`: the trainee's own highest-scoring finished attempt (the earliest of
//!   equal scores); `reference`: the reference operators' highest-scoring finished attempt
//!   (the best, not the median: the ghost shows what the best operator did); `attempts`: the
//!   trainee's finished attempts there, newest first. "The trainee's own" is what the learning
//!   curves count ([`crate::api::progress`]): every session with the same name and group, or
//!   only this session when it has no name. Only replayable attempts (this simulator's
//!   version) are named. A reference attempt carries no name: only its score and assessment.
//! * `GET /api/attempts/{id}/track?session=` : the attempt's poses at 10 Hz
//!   ([`crate::replay::track`]). Read as the attempt's replay is (the instructor; the trainee of
//!   its session, once it ended), and also by the trainee of session `session` (its token or
//!   cookie) when the attempt is finished and is that trainee's own (same name and group) or a
//!   reference operator's: poses only, the names stay out. Re-simulated on the compute pool
//!   (its queue, deadline and cancellation, as `GET /api/attempts/{id}/replay`), one at a time
//!   per trainee, depositing the shared checkpoints on the way; an ended attempt's track is
//!   cached (`AppState::tracks`, bounded).

use std::sync::Arc;

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::api::attempts::{FROM, authorized, check_open, hold, load, pool_error};
use crate::api::progress::finished;
use crate::api::sessions::session_actor;
use crate::app::AppState;
use crate::auth::{Actor, Credentials, WRONG_TOKEN};
use crate::catalogue::EXERCISES;
use crate::db::{AttemptFilter, AttemptRow, unavailable as db_error};
use crate::error::ApiError;
use crate::replay::{check_version, track};

/// Query of `GET /api/attempts/{id}/track`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackQuery {
    /// The asking trainee's session (for another session's attempt).
    session: Option<String>,
    /// Read by [`Credentials`]; listed so that it is a known field.
    #[allow(dead_code)]
    token: Option<String>,
}

/// The attempt `id` if `creds` may read its track (see the module docs), with the key its
/// re-simulations are held under (`instructor`, or the asking trainee's session).
async fn readable(
    state: &AppState,
    creds: &Credentials,
    id: &str,
    session: Option<&str>,
) -> Result<(AttemptRow, String), ApiError> {
    let instructor = creds.principal(state, FROM, None)?.is_instructor();
    match authorized(state, creds, id).await {
        Ok(row) => {
            check_open(state, creds, &row)?;
            let key = if instructor {
                "instructor".to_string()
            } else {
                format!("trainee:{}", row.session)
            };
            return Ok((row, key));
        }
        Err(e) if e.status == StatusCode::FORBIDDEN && session.is_some() => {}
        Err(e) => return Err(e),
    }
    let session = session.unwrap_or_default();
    let (asker, name, group) = session_actor(state, creds, FROM, session).await?;
    if asker != Actor::Trainee {
        return Err(ApiError::forbidden(WRONG_TOKEN));
    }
    let row = state
        .db
        .attempt(id)
        .await
        .map_err(db_error)?
        .ok_or_else(|| ApiError::not_found(format!("no attempt `{id}`")))?;
    let own = !name.is_empty() && name == row.trainee && group == row.group;
    let allowed = own
        || state
            .db
            .reference_operators()
            .await
            .map_err(db_error)?
            .iter()
            .any(|(name, group, _)| *name == row.trainee && *group == row.group);
    if !allowed || !matches!(row.outcome.as_deref(), Some("passed" | "failed")) {
        return Err(ApiError::forbidden(
            "a trainee reads the tracks of its own attempts and of the reference operators' finished attempts",
        ));
    }
    check_open(state, creds, &row)?;
    Ok((row, format!("trainee:{session}")))
}

fn json_response(json: Arc<str>) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        json.to_string(),
    )
        .into_response()
}

/// `GET /api/attempts/{id}/track?session=`: the attempt's ghost track (see the module docs).
pub async fn track(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
    Query(q): Query<TrackQuery>,
) -> Result<Response, ApiError> {
    let (row, key) = readable(&state, &creds, &id, q.session.as_deref()).await?;
    let ended = row.ended_unix.is_some();
    if ended && let Some(json) = state.tracks.get(&id) {
        return Ok(json_response(json));
    }
    // One re-simulation at a time per trainee; the instructor's are not limited here.
    let _held = if key == "instructor" {
        None
    } else {
        Some(hold(&format!("{key}:seek"), 1, "replay seeks")?)
    };
    let mut replay = load(&state, &row).await?;
    let attempt = id.clone();
    let json: Arc<str> = state
        .compute
        .run(move |cancel| {
            let t = track::build(&mut replay, &attempt, &|| cancel.check().is_ok())
                .map_err(|e| pool_error(e, cancel))?;
            Ok(Arc::from(serde_json::to_string(&t).unwrap_or_default()))
        })
        .await
        .map_err(|e| e.api_error())?;
    if ended {
        state.tracks.insert(&id, json.clone());
    }
    Ok(json_response(json))
}

/// Query of `GET /api/sessions/{id}/ghosts`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GhostsQuery {
    exercise: String,
    /// Read by [`Credentials`]; listed so that it is a known field.
    #[allow(dead_code)]
    token: Option<String>,
}

/// One attempt that can be a ghost.
#[derive(Debug, Serialize)]
struct Candidate {
    attempt: String,
    score: f64,
    outcome: Option<String>,
    started_unix: f64,
    sim_seconds: f64,
    assessment: Option<Value>,
}

impl Candidate {
    fn of(r: &AttemptRow) -> Candidate {
        Candidate {
            attempt: r.id.clone(),
            score: r.score.unwrap_or(0.0),
            outcome: r.outcome.clone(),
            started_unix: r.started_unix,
            sim_seconds: r.sim_seconds,
            assessment: r.assessment.clone(),
        }
    }
}

/// The highest-scoring of `rows` (oldest first), the earliest of equal scores.
fn best(rows: &[AttemptRow]) -> Option<&AttemptRow> {
    rows.iter()
        .fold(None, |best: Option<&AttemptRow>, r| match best {
            Some(b) if b.score.unwrap_or(0.0) >= r.score.unwrap_or(0.0) => Some(b),
            _ => Some(r),
        })
}

/// `GET /api/sessions/{id}/ghosts?exercise=` (see the module docs).
pub async fn of_session(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
    Query(q): Query<GhostsQuery>,
) -> Result<Json<Value>, ApiError> {
    let (_, name, group) = session_actor(&state, &creds, FROM, &id).await?;
    let spec = EXERCISES
        .get(&q.exercise)
        .ok_or_else(|| ApiError::not_found(format!("no exercise `{}`", q.exercise)))?;
    let named = !name.is_empty();
    let replayable = |r: &AttemptRow| check_version(&r.sim_version).is_ok();
    let mut own = finished(
        &state,
        AttemptFilter {
            trainee: named.then(|| name.clone()),
            group: named.then(|| group.clone()),
            session: (!named).then(|| id.clone()),
            exercise: Some(spec.id.clone()),
            limit: 0,
            without_practice: true,
        },
    )
    .await?;
    own.retain(replayable);
    let mut references = state
        .db
        .reference_attempts(&spec.id)
        .await
        .map_err(db_error)?;
    references.retain(replayable);
    Ok(Json(json!({
        "exercise": spec.id,
        "best": best(&own).map(Candidate::of),
        "reference": best(&references).map(Candidate::of),
        "attempts": own.iter().rev().map(Candidate::of).collect::<Vec<_>>(),
    })))
}
