//! Learning curves and proficiency (issue 30 item 3): every finished attempt's score in order
//! per trainee and exercise, the CUSUM charts and the state the core judges from them
//! ([`seaarms_core::exercise::proficiency`], with each exercise file's `proficiency`).
//!
//! * `GET /api/progress?exercise=&group=` (instructor): each trainee with finished attempts at
//!   the exercise (in the group, when given), by state then name.
//! * `GET /api/sessions/{id}/progress` (the session's trainee, or the instructor): the trainee
//!   of that live session on every exercise (`not_started` where there is no attempt), for the
//!   start screen's learning curves, and each exercise open or locked for them (`locks`,
//!   [`crate::api::unlocks`]).
//!
//! * `GET /api/reference-operators`, `PUT /api/reference-operators` (instructor): the trainees
//!   whose finished attempts make each exercise's benchmark (issue 30 item 1). Both progress
//!   routes carry each exercise's benchmark (the core's [`ExerciseBenchmark`]), and an attempt
//!   that meets an applying benchmark counts toward "N in a row" proficiency.
//!
//! A finished attempt is one that passed or failed (abandoned, ended and interrupted ones say
//! nothing of skill). The trainee is the session's name and group, as the records keep them.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, Query, State};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::exercise::proficiency::{
    AttemptOutcome, ExerciseBenchmark, ProficiencyState, progress,
};

use crate::api::attempts::is_instructor;
use crate::api::sessions::{live_actor, live_session};
use crate::app::AppState;
use crate::auth::TokenFrom;
use crate::catalogue::EXERCISES;
use crate::db::{AttemptFilter, AttemptRow, unavailable as db_error};
use crate::error::ApiError;

/// One attempt on a learning curve.
#[derive(Debug, Serialize)]
pub(crate) struct Point {
    id: String,
    pub(crate) started_unix: f64,
    pub(crate) score: f64,
    pub(crate) passed: bool,
    /// Met the exercise's benchmark (None while it does not apply).
    met_benchmark: Option<bool>,
}

/// One trainee's curve and state on one exercise.
#[derive(Debug, Serialize)]
pub(crate) struct Curve {
    trainee: String,
    group: String,
    exercise: String,
    pub(crate) state: ProficiencyState,
    /// 1-based attempt at which the trainee last became proficient.
    pub(crate) proficient_at: Option<usize>,
    /// `cusum` or `benchmark`.
    pub(crate) by: Option<&'static str>,
    pub(crate) attempts: Vec<Point>,
    /// The learning (LC-CUSUM) and relapse charts after each attempt, and their limit.
    cusum: Value,
    /// The exercise's benchmark (in a trainee's own progress; the class view gives it once).
    #[serde(skip_serializing_if = "Option::is_none")]
    benchmark: Option<ExerciseBenchmark>,
}

/// An attempt's benchmarked values: its score and its assessment's metrics.
fn values(r: &AttemptRow) -> BTreeMap<String, f64> {
    let mut out: BTreeMap<String, f64> = r
        .assessment
        .as_ref()
        .and_then(Value::as_object)
        .map(|o| {
            o.iter()
                .filter_map(|(k, v)| Some((k.clone(), v.as_f64()?)))
                .collect()
        })
        .unwrap_or_default();
    out.insert("score".into(), r.score.unwrap_or(0.0));
    out
}

/// `spec`'s benchmark from its reference operators' finished attempts.
pub(crate) async fn benchmark(
    state: &AppState,
    spec: &ExerciseSpec,
) -> Result<ExerciseBenchmark, ApiError> {
    let rows = state
        .db
        .reference_attempts(&spec.id)
        .await
        .map_err(db_error)?;
    let refs: Vec<BTreeMap<String, f64>> = rows.iter().map(values).collect();
    Ok(ExerciseBenchmark::of(spec, &refs))
}

/// Reads again, for every exercise whose pass marks are `benchmark`, its benchmark's pass
/// lines into the sessions' board ([`crate::sessions::pass_board`]); an exercise whose read
/// fails keeps its lines (logged).
pub async fn refresh_pass_board(state: &AppState) {
    let board = state.sessions.pass_board();
    for spec in EXERCISES.all() {
        if spec.pass.marks != seaarms_core::exercise::spec::PassMarks::Benchmark {
            continue;
        }
        match benchmark(state, &spec).await {
            Ok(b) => board.set(&spec.id, b.pass_lines()),
            Err(e) => tracing::warn!("benchmark of {}: {}", spec.id, e.error),
        }
    }
}

/// [`refresh_pass_board`] every [`crate::sessions::pass_board::REFRESH_INTERVAL`].
pub async fn pass_board_loop(state: AppState) {
    let mut tick = tokio::time::interval(crate::sessions::pass_board::REFRESH_INTERVAL);
    loop {
        tick.tick().await;
        refresh_pass_board(&state).await;
    }
}

/// A curve from one trainee's finished attempts at `spec`, oldest first, judged against
/// `bench` where it applies (else by the CUSUM alone).
pub(crate) fn curve(
    trainee: &str,
    group: &str,
    spec: &ExerciseSpec,
    bench: &ExerciseBenchmark,
    rows: &[&AttemptRow],
) -> Curve {
    let attempts: Vec<Point> = rows
        .iter()
        .map(|r| Point {
            id: r.id.clone(),
            started_unix: r.started_unix,
            score: r.score.unwrap_or(0.0),
            passed: r.outcome.as_deref() == Some("passed"),
            met_benchmark: bench.met_by(&values(r)),
        })
        .collect();
    let outcomes: Vec<AttemptOutcome> = attempts
        .iter()
        .map(|p| AttemptOutcome {
            passed: p.passed,
            met_benchmark: p.met_benchmark,
        })
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
        benchmark: None,
    }
}

/// Finished (passed or failed) attempts matching `filter`, oldest first; practice attempts
/// ("take over from here") are left out.
pub(crate) async fn finished(
    state: &AppState,
    filter: AttemptFilter,
) -> Result<Vec<AttemptRow>, ApiError> {
    let filter = AttemptFilter {
        without_practice: true,
        ..filter
    };
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
    let bench = benchmark(&state, &spec).await?;
    let mut by: BTreeMap<(String, String), Vec<&AttemptRow>> = BTreeMap::new();
    for r in &rows {
        by.entry((r.trainee.clone(), r.group.clone()))
            .or_default()
            .push(r);
    }
    let mut curves: Vec<Curve> = by
        .iter()
        .map(|((t, g), list)| curve(t, g, &spec, &bench, list))
        .collect();
    curves.sort_by_key(|c| (rank(c.state), c.trainee.clone(), c.group.clone()));
    Ok(Json(
        json!({ "exercise": spec.id, "benchmark": bench, "trainees": curves }),
    ))
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
    let mut curves: Vec<Curve> = Vec::new();
    for spec in EXERCISES.all() {
        let bench = benchmark(&state, &spec).await?;
        let list: Vec<&AttemptRow> = rows
            .iter()
            .filter(|r| r.exercise.as_deref() == Some(spec.id.as_str()))
            .collect();
        let mut c = curve(&session.label, &session.group, &spec, &bench, &list);
        c.benchmark = Some(bench);
        curves.push(c);
    }
    let locks = crate::api::unlocks::locks(&state, &session.label, &session.group).await?;
    Ok(Json(json!({
        "trainee": session.label,
        "group": session.group,
        "exercises": curves,
        "progression": state.progression,
        "locks": locks,
    })))
}

/// A reference operator as listed.
#[derive(Debug, Serialize)]
struct Reference {
    trainee: String,
    group: String,
    marked_unix: f64,
}

/// `GET /api/reference-operators` (instructor).
pub async fn references(
    State(state): State<AppState>,
    creds: crate::auth::Credentials,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    list_references(&state).await
}

async fn list_references(state: &AppState) -> Result<Json<Value>, ApiError> {
    let list: Vec<Reference> = state
        .db
        .reference_operators()
        .await
        .map_err(db_error)?
        .into_iter()
        .map(|(trainee, group, marked_unix)| Reference {
            trainee,
            group,
            marked_unix,
        })
        .collect();
    Ok(Json(json!({ "reference_operators": list })))
}

/// Body of `PUT /api/reference-operators`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkReference {
    trainee: String,
    #[serde(default)]
    group: String,
    reference: bool,
}

/// `PUT /api/reference-operators` (instructor): marks or unmarks a trainee (by name and group,
/// normalised as names are on entry); answers the whole list.
pub async fn mark_reference(
    State(state): State<AppState>,
    creds: crate::auth::Credentials,
    crate::json::ApiJson(body): crate::json::ApiJson<MarkReference>,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let name = crate::names::display_name(&body.trainee);
    if name.is_empty() {
        return Err(ApiError::bad_request("`trainee` must name a trainee"));
    }
    let group = crate::names::display_name(&body.group);
    state
        .db
        .set_reference_operator(&name, &group, body.reference)
        .await
        .map_err(db_error)?;
    refresh_pass_board(&state).await;
    list_references(&state).await
}
