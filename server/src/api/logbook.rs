//! The per-trainee logbook (issue 30 item 7; docs/operations.md "The logbook"): per exercise,
//! the dates of the first and last attempts, the attempts (finished and all), passes, best and
//! last scores, the proficiency state and the date of the attempt at which the trainee became
//! proficient (the learning curve of [`crate::api::progress`], not re-derived here), and the
//! instructor's sign-off — the record an assessor keeps for a competence scheme such as
//! IMCA C 005.
//!
//! * `GET /api/logbook?trainee=&group=` (instructor): JSON; `GET /api/logbook.csv?…` the same
//!   as CSV ([`crate::csv_out`], dates ISO 8601 UTC).
//! * `GET /api/sessions/{id}/logbook` (the session's trainee, or the instructor): the logbook
//!   of that live session's trainee.
//! * `PUT /api/signoffs` (instructor): signs a trainee off on an exercise (again: replaces the
//!   sign-off); `DELETE /api/signoffs?trainee=&group=&exercise=` revokes it.
//!
//! Names, groups, assessors and notes are normalised as names are on entry
//! ([`crate::names`]); the trainee is the session's name and group, as the records keep them.

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::exercise::proficiency::ProficiencyState;

use crate::api::attempts::is_instructor;
use crate::api::progress::{benchmark, curve};
use crate::api::results::{file_safe, rfc3339};
use crate::api::sessions::{live_actor, live_session};
use crate::app::AppState;
use crate::auth::{Credentials, TokenFrom};
use crate::catalogue::EXERCISES;
use crate::csv_out::{Field, table};
use crate::db::{AttemptFilter, AttemptRow, Signoff, unavailable as db_error};
use crate::error::ApiError;
use crate::names::{NOTE_WIDTH, display_name, display_text};

/// One exercise of a logbook.
#[derive(Debug, Serialize)]
struct Entry {
    exercise: String,
    title: String,
    /// Start of the first and of the last attempt (any outcome), Unix s.
    first_unix: Option<f64>,
    last_unix: Option<f64>,
    /// Every attempt at the exercise, and the finished ones (passed or failed).
    attempts: usize,
    finished: usize,
    passes: usize,
    /// Best and last score of the finished attempts.
    best_score: Option<f64>,
    last_score: Option<f64>,
    state: ProficiencyState,
    /// 1-based finished attempt at which the trainee last became proficient, its start and
    /// how (`cusum` or `benchmark`).
    proficient_at: Option<usize>,
    proficient_unix: Option<f64>,
    by: Option<&'static str>,
    signoff: Option<Signoff>,
}

/// The logbook of `trainee` of `group` from their attempts (newest first, any outcome) and
/// sign-offs: every exercise of the catalogue, in its order.
async fn entries(
    state: &AppState,
    trainee: &str,
    group: &str,
    rows: &[AttemptRow],
    signoffs: &[Signoff],
) -> Result<Vec<Entry>, ApiError> {
    let mut out = Vec::new();
    for spec in EXERCISES.all() {
        let mut all: Vec<&AttemptRow> = rows
            .iter()
            .filter(|r| r.exercise.as_deref() == Some(spec.id.as_str()))
            .collect();
        all.reverse(); // oldest first
        let finished: Vec<&AttemptRow> = all
            .iter()
            .copied()
            .filter(|r| matches!(r.outcome.as_deref(), Some("passed" | "failed")))
            .collect();
        let bench = benchmark(state, &spec).await?;
        let c = curve(trainee, group, &spec, &bench, &finished);
        let proficient_unix = c
            .proficient_at
            .and_then(|n| c.attempts.get(n.checked_sub(1)?))
            .map(|p| p.started_unix);
        out.push(Entry {
            exercise: spec.id.clone(),
            title: spec.title.clone(),
            first_unix: all.first().map(|r| r.started_unix),
            last_unix: all.last().map(|r| r.started_unix),
            attempts: all.len(),
            finished: c.attempts.len(),
            passes: c.attempts.iter().filter(|p| p.passed).count(),
            best_score: c.attempts.iter().map(|p| p.score).reduce(f64::max),
            last_score: c.attempts.last().map(|p| p.score),
            state: c.state,
            proficient_at: c.proficient_at,
            proficient_unix,
            by: c.by,
            signoff: signoffs.iter().find(|s| s.exercise == spec.id).cloned(),
        });
    }
    Ok(out)
}

/// Query of the instructor's logbook routes.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogbookQuery {
    trainee: String,
    #[serde(default)]
    group: String,
}

/// The trainee and group of a query, normalised; 400 without a name.
fn who(trainee: &str, group: &str) -> Result<(String, String), ApiError> {
    let name = display_name(trainee);
    if name.is_empty() {
        return Err(ApiError::bad_request("`trainee` must name a trainee"));
    }
    Ok((name, display_name(group)))
}

/// The instructor's logbook of the trainee a query names: 403 without the instructor token,
/// 400 without a name, 404 for a trainee with neither attempts nor sign-offs.
async fn of_query(
    state: &AppState,
    creds: &Credentials,
    q: &LogbookQuery,
) -> Result<(String, String, Vec<Entry>), ApiError> {
    if !is_instructor(state, creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let (name, group) = who(&q.trainee, &q.group)?;
    let rows = state
        .db
        .attempts(&AttemptFilter {
            trainee: Some(name.clone()),
            group: Some(group.clone()),
            limit: 0,
            without_practice: true,
            ..AttemptFilter::default()
        })
        .await
        .map_err(db_error)?;
    let signoffs = state.db.signoffs(&name, &group).await.map_err(db_error)?;
    if rows.is_empty() && signoffs.is_empty() {
        return Err(ApiError::not_found(format!(
            "no attempts of `{name}` in group `{group}`"
        )));
    }
    let list = entries(state, &name, &group, &rows, &signoffs).await?;
    Ok((name, group, list))
}

fn body(trainee: &str, group: &str, list: &[Entry]) -> Json<Value> {
    Json(json!({
        "trainee": trainee,
        "group": group,
        "generated_unix": crate::clock::unix_now(),
        "exercises": list,
    }))
}

/// `GET /api/logbook?trainee=&group=` (instructor).
pub async fn get(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<LogbookQuery>,
) -> Result<Json<Value>, ApiError> {
    let (name, group, list) = of_query(&state, &creds, &q).await?;
    Ok(body(&name, &group, &list))
}

/// The columns of `GET /api/logbook.csv`.
pub const COLUMNS: [&str; 18] = [
    "trainee",
    "group",
    "exercise",
    "title",
    "first_attempt_utc",
    "last_attempt_utc",
    "attempts",
    "finished",
    "passes",
    "best_score",
    "last_score",
    "state",
    "proficient_at",
    "proficient_utc",
    "proficient_by",
    "signed_off_utc",
    "assessor",
    "note",
];

/// `GET /api/logbook.csv?trainee=&group=` (instructor): the logbook as CSV, one row per
/// exercise, dates ISO 8601 UTC, cells neutralised against formulas ([`crate::csv_out`]).
pub async fn csv(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<LogbookQuery>,
) -> Result<Response, ApiError> {
    let (name, group, list) = of_query(&state, &creds, &q).await?;
    let date = |t: Option<f64>| t.map(rfc3339).unwrap_or_default();
    let text: Vec<[String; 6]> = list
        .iter()
        .map(|e| {
            [
                date(e.first_unix),
                date(e.last_unix),
                date(e.proficient_unix),
                date(e.signoff.as_ref().map(|s| s.signed_unix)),
                state_name(e.state).to_string(),
                e.by.unwrap_or_default().to_string(),
            ]
        })
        .collect();
    let rows = list.iter().zip(&text).map(|(e, t)| {
        let count = |n: usize| Field::Int(n as u64);
        let s = e.signoff.as_ref();
        [
            Field::Text(&name),
            Field::Text(&group),
            Field::Text(&e.exercise),
            Field::Text(&e.title),
            Field::Text(&t[0]),
            Field::Text(&t[1]),
            count(e.attempts),
            count(e.finished),
            count(e.passes),
            e.best_score.into(),
            e.last_score.into(),
            Field::Text(&t[4]),
            e.proficient_at.map_or(Field::Empty, count),
            Field::Text(&t[2]),
            Field::Text(&t[5]),
            Field::Text(&t[3]),
            s.map_or(Field::Empty, |s| Field::Text(&s.assessor)),
            s.map_or(Field::Empty, |s| Field::Text(&s.note)),
        ]
    });
    let csv = table(&COLUMNS, rows);
    Ok((
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!(
                    "attachment; filename=\"seaarms-logbook-{}.csv\"",
                    file_safe(&name)
                ),
            ),
        ],
        csv,
    )
        .into_response())
}

/// A state's name as the JSON gives it.
fn state_name(s: ProficiencyState) -> &'static str {
    match s {
        ProficiencyState::NotStarted => "not_started",
        ProficiencyState::Practising => "practising",
        ProficiencyState::Proficient => "proficient",
        ProficiencyState::Relapsed => "relapsed",
    }
}

/// `GET /api/sessions/{id}/logbook` (the session's trainee or the instructor): the logbook
/// of the live session's trainee (a session without a name: its own attempts, no sign-offs).
pub async fn of_session(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Json<Value>, ApiError> {
    let session = live_session(&state, &id).await?;
    live_actor(&state, &creds, TokenFrom::Bearer, &session)?;
    let named = !session.label.is_empty();
    let rows = state
        .db
        .attempts(&AttemptFilter {
            trainee: named.then(|| session.label.clone()),
            group: named.then(|| session.group.clone()),
            session: (!named).then(|| session.id.clone()),
            limit: 0,
            without_practice: true,
            ..AttemptFilter::default()
        })
        .await
        .map_err(db_error)?;
    let signoffs = if named {
        state
            .db
            .signoffs(&session.label, &session.group)
            .await
            .map_err(db_error)?
    } else {
        Vec::new()
    };
    let list = entries(&state, &session.label, &session.group, &rows, &signoffs).await?;
    Ok(body(&session.label, &session.group, &list))
}

/// Body of `PUT /api/signoffs`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignOff {
    trainee: String,
    #[serde(default)]
    group: String,
    exercise: String,
    assessor: String,
    #[serde(default)]
    note: Option<String>,
}

/// `PUT /api/signoffs` (instructor): signs the trainee off on the exercise (replacing an
/// earlier sign-off of it); answers the sign-off as stored. 400 without a trainee or an
/// assessor, 404 for an exercise not in the catalogue.
pub async fn sign(
    State(state): State<AppState>,
    creds: Credentials,
    crate::json::ApiJson(b): crate::json::ApiJson<SignOff>,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let (name, group) = who(&b.trainee, &b.group)?;
    let spec = EXERCISES
        .get(&b.exercise)
        .ok_or_else(|| ApiError::not_found(format!("no exercise `{}`", b.exercise)))?;
    let assessor = display_name(&b.assessor);
    if assessor.is_empty() {
        return Err(ApiError::bad_request("`assessor` must name the assessor"));
    }
    let s = Signoff {
        exercise: spec.id.clone(),
        signed_unix: crate::clock::unix_now(),
        assessor,
        note: display_text(b.note.as_deref().unwrap_or_default(), NOTE_WIDTH),
    };
    state
        .db
        .set_signoff(&name, &group, &s)
        .await
        .map_err(db_error)?;
    Ok(Json(json!({
        "trainee": name,
        "group": group,
        "exercise": s.exercise,
        "signed_unix": s.signed_unix,
        "assessor": s.assessor,
        "note": s.note,
    })))
}

/// Query of `DELETE /api/signoffs`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Revoke {
    trainee: String,
    #[serde(default)]
    group: String,
    exercise: String,
}

/// `DELETE /api/signoffs?trainee=&group=&exercise=` (instructor): revokes a sign-off; 204, or
/// 404 when there was none.
pub async fn revoke(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<Revoke>,
) -> Result<StatusCode, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let (name, group) = who(&q.trainee, &q.group)?;
    let gone = state
        .db
        .revoke_signoff(&name, &group, &q.exercise)
        .await
        .map_err(db_error)?;
    if gone {
        Ok(StatusCode::NO_CONTENT)
    } else {
        Err(ApiError::not_found(format!(
            "no sign-off of `{name}` on `{}`",
            q.exercise
        )))
    }
}
