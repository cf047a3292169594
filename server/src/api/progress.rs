//! Learning curves and proficiency (issue 30 item 3): every finished attempt's score in order
//! per trainee and exercise, the CUSUM charts and the state the core judges from them
//! ([`seaarms_core::exercise::proficiency`], with each exercise file's `proficiency`).
//!
//! * `GET /api/progress?exercise=&group=` (instructor): each trainee with finished attempts at
//!   the exercise (in the group, when given), by state then name.
//! * `GET /api/sessions/{id}/progress` (the session's trainee, or the instructor): the trainee
//!   of that live session on every exercise (`not_started` where there is no attempt), for the
//!   start screen's learning curves.
//!
//! A finished attempt is one that passed or failed (abandoned, ended and interrupted ones say
//! nothing of skill). The trainee is the session's name and group, as the records keep them.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, Query, State};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::exercise::proficiency::{AttemptOutcome, ProficiencyState, progress};

use crate::api::attempts::is_instructor;
use crate::api::sessions::{live_actor, live_session};
use crate::app::AppState;
use crate::auth::TokenFrom;
use crate::catalogue::EXERCISES;
use crate::db::{AttemptFilter, AttemptRow, unavailable as db_error};
use crate::error::ApiError;

/// One attempt on a learning curve.
#[derive(Debug, Serialize)]
struct Point {
    id: String,
    started_unix: f64,
    score: f64,
    passed: bool,
}

/// One trainee's curve and state on one exercise.
#[derive(Debug, Serialize)]
struct Curve {
    trainee: String,
    group: String,
    exercise: String,
    state: ProficiencyState,
    /// 1-based attempt at which the trainee last became proficient.
    proficient_at: Option<usize>,
    /// `cusum` or `benchmark`.
    by: Option<&'static str>,
    attempts: Vec<Point>,
    /// The learning (LC-CUSUM) and relapse charts after each attempt, and their limit.
    cusum: Value,
}

/// A curve from one trainee's finished attempts at `spec`, oldest first.
fn curve(trainee: &str, group: &str, spec: &ExerciseSpec, rows: &[&AttemptRow]) -> Curve {
    let attempts: Vec<Point> = rows
        .iter()
        .map(|r| Point {
            id: r.id.clone(),
            started_unix: r.started_unix,
            score: r.score.unwrap_or(0.0),
            passed: r.outcome.as_deref() == Some("passed"),
        })
        .collect();
    let outcomes: Vec<AttemptOutcome> = attempts
        .iter()
        // no reference operators yet: the CUSUM alone judges
        .map(|p| AttemptOutcome::without_benchmark(p.passed))
        .collect();
    let p = &spec.proficiency;
    let pr = progress(&p.cusum, p.consecutive, &outcomes);
    Curve {
        trainee: trainee.to_string(),
        group: group.to_string(),
        exercise: spec.id.clone(),
        state: pr.state,
        proficient_at: pr.proficient_at,
        by: pr.by,
        attempts,
        cusum: json!({
            "learning": pr.cusum.learning,
            "relapse": pr.cusum.relapse,
            "limit": p.cusum.limit,
            "proficient_at": pr.cusum.proficient_at,
            "relapsed_at": pr.cusum.relapsed_at,
            "acceptable_failure": p.cusum.acceptable_failure,
            "unacceptable_failure": p.cusum.unacceptable_failure,
        }),
    }
}

/// Finished (passed or failed) attempts matching `filter`, oldest first.
async fn finished(state: &AppState, filter: AttemptFilter) -> Result<Vec<AttemptRow>, ApiError> {
    let mut rows = state.db.attempts(&filter).await.map_err(db_error)?;
    rows.retain(|r| matches!(r.outcome.as_deref(), Some("passed" | "failed")));
    rows.reverse();
    Ok(rows)
}

/// Query of `GET /api/progress`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassQuery {
    exercise: String,
    group: Option<String>,
}

/// `GET /api/progress?exercise=&group=` (instructor).
pub async fn class(
    State(state): State<AppState>,
    creds: crate::auth::Credentials,
    Query(q): Query<ClassQuery>,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let spec = EXERCISES
        .get(&q.exercise)
        .ok_or_else(|| ApiError::not_found(format!("no exercise `{}`", q.exercise)))?;
    let rows = finished(
        &state,
        AttemptFilter {
            exercise: Some(q.exercise.clone()),
            group: q.group.filter(|g| !g.is_empty()),
            limit: 0,
            ..AttemptFilter::default()
        },
    )
    .await?;
    let mut by: BTreeMap<(String, String), Vec<&AttemptRow>> = BTreeMap::new();
    for r in &rows {
        by.entry((r.trainee.clone(), r.group.clone()))
            .or_default()
            .push(r);
    }
    let mut curves: Vec<Curve> = by
        .iter()
        .map(|((t, g), list)| curve(t, g, &spec, list))
        .collect();
    curves.sort_by_key(|c| (rank(c.state), c.trainee.clone(), c.group.clone()));
    Ok(Json(json!({ "exercise": spec.id, "trainees": curves })))
}

/// The class's order: who needs the instructor first (relapsed, practising), then proficient.
fn rank(s: ProficiencyState) -> u8 {
    match s {
        ProficiencyState::Relapsed => 0,
        ProficiencyState::Practising => 1,
        ProficiencyState::Proficient => 2,
        ProficiencyState::NotStarted => 3,
    }
}

/// `GET /api/sessions/{id}/progress` (the session's trainee or the instructor).
pub async fn of_session(
    State(state): State<AppState>,
    creds: crate::auth::Credentials,
    Path(id): Path<String>,
) -> Result<Json<Value>, ApiError> {
    let session = live_session(&state, &id).await?;
    live_actor(&state, &creds, TokenFrom::Bearer, &session)?;
    // a session without a trainee's name has only its own attempts to show
    let named = !session.label.is_empty();
    let rows = finished(
        &state,
        AttemptFilter {
            trainee: named.then(|| session.label.clone()),
            group: named.then(|| session.group.clone()),
            session: (!named).then(|| session.id.clone()),
            limit: 0,
            ..AttemptFilter::default()
        },
    )
    .await?;
    let curves: Vec<Curve> = EXERCISES
        .all()
        .iter()
        .map(|spec| {
            let list: Vec<&AttemptRow> = rows
                .iter()
                .filter(|r| r.exercise.as_deref() == Some(spec.id.as_str()))
                .collect();
            curve(&session.label, &session.group, spec, &list)
        })
        .collect();
    Ok(Json(
        json!({ "trainee": session.label, "group": session.group, "exercises": curves }),
    ))
}
