//! Progression (issue 30 item 4; docs/exercises.md "Progression"): an exercise whose file
//! `requires` others opens to a trainee once they are (or were) proficient in each
//! ([`seaarms_core::exercise::progression`]), or once the instructor unlocks it for them.
//!
//! * The gate: `POST /api/sessions` on a locked exercise is refused ([`check_start`]: 403 with
//!   what is missing). The instructor's token starts anything; `--progression off` opens
//!   everything. A live session changes exercise only by the instructor's `scenario` action,
//!   so that path needs no gate.
//! * `GET /api/unlocks?trainee=&group=` (instructor): each exercise's [`Lock`] for the trainee.
//! * `PUT /api/unlocks` (instructor, body `{trainee, group, exercise}`): unlocks an exercise
//!   for the trainee; `DELETE /api/unlocks?trainee=&group=&exercise=` locks it again. Both
//!   answer the trainee's locks.
//! * The trainee's own locks come with their progress (`GET /api/sessions/{id}/progress`,
//!   [`locks`]), behind the session's token: there is no public lookup by name, which would
//!   show anyone's progress to whoever types the name.
//!
//! The trainee is a name and group as the records keep them (normalised as on entry); an
//! unnamed trainee has no record, so only exercises without requirements are open to them.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Query, State};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::exercise::proficiency::ProficiencyState;
use seaarms_core::exercise::progression::{Missing, missing};

use crate::api::attempts::is_instructor;
use crate::api::progress::{benchmark, curve, finished};
use crate::app::AppState;
use crate::auth::Credentials;
use crate::catalogue::EXERCISES;
use crate::db::{AttemptFilter, AttemptRow, unavailable as db_error};
use crate::error::ApiError;
use crate::names::display_name;

/// One exercise as open or locked for one trainee.
#[derive(Debug, Serialize)]
pub(crate) struct Lock {
    exercise: String,
    /// `open` (no requirement unmet, or `--progression off`), `locked`, or `unlocked` (locked
    /// by its requirements, opened by the instructor).
    status: &'static str,
    /// The exercise file's `requires`.
    requires: Vec<String>,
    /// The requirements not met, with the trainee's state in each (empty when progression is
    /// off).
    missing: Vec<Missing>,
    /// When the instructor unlocked it for the trainee (Unix s), if they did.
    unlocked_unix: Option<f64>,
}

impl Lock {
    /// Whether the trainee may start it.
    fn open(&self) -> bool {
        self.status != "locked"
    }
}

/// The trainee's proficiency state on every exercise they have finished attempts at (the
/// learning curves of [`crate::api::progress`]); absent: not started.
async fn states(
    state: &AppState,
    name: &str,
    group: &str,
) -> Result<BTreeMap<String, ProficiencyState>, ApiError> {
    let mut out = BTreeMap::new();
    if name.is_empty() {
        return Ok(out);
    }
    let rows = finished(
        state,
        AttemptFilter {
            trainee: Some(name.to_string()),
            group: Some(group.to_string()),
            limit: 0,
            ..AttemptFilter::default()
        },
    )
    .await?;
    for spec in EXERCISES.all() {
        let list: Vec<&AttemptRow> = rows
            .iter()
            .filter(|r| r.exercise.as_deref() == Some(spec.id.as_str()))
            .collect();
        if list.is_empty() {
            continue;
        }
        let bench = benchmark(state, &spec).await?;
        let c = curve(name, group, &spec, &bench, &list);
        out.insert(spec.id.clone(), c.state);
    }
    Ok(out)
}

/// Every exercise (in the start screen's order) as open or locked for the trainee `name` of
/// `group` (normalised).
pub(crate) async fn locks(
    state: &AppState,
    name: &str,
    group: &str,
) -> Result<Vec<Lock>, ApiError> {
    let states = states(state, name, group).await?;
    let unlocked: BTreeMap<String, f64> = if name.is_empty() {
        BTreeMap::new()
    } else {
        state
            .db
            .unlocks(name, group)
            .await
            .map_err(db_error)?
            .into_iter()
            .collect()
    };
    let state_of = |id: &str| {
        states
            .get(id)
            .copied()
            .unwrap_or(ProficiencyState::NotStarted)
    };
    Ok(EXERCISES
        .all()
        .iter()
        .map(|spec| {
            let unmet = if state.progression {
                missing(spec, state_of)
            } else {
                Vec::new()
            };
            let unlocked_unix = unlocked.get(&spec.id).copied();
            let status = match (unmet.is_empty(), unlocked_unix) {
                (true, _) => "open",
                (false, Some(_)) => "unlocked",
                (false, None) => "locked",
            };
            Lock {
                exercise: spec.id.clone(),
                status,
                requires: spec.requires.clone(),
                missing: unmet,
                unlocked_unix,
            }
        })
        .collect())
}

/// The gate of `POST /api/sessions`: Ok when `scenario` is no exercise, or progression is off,
/// or the creator is the instructor, or the exercise is open to the trainee `name` of `group`
/// (normalised); else 403 naming what is missing.
pub(crate) async fn check_start(
    state: &AppState,
    instructor: bool,
    scenario: Option<&str>,
    name: &str,
    group: &str,
) -> Result<(), ApiError> {
    let Some(spec) = scenario.and_then(|s| EXERCISES.get(s)) else {
        return Ok(());
    };
    if !state.progression || instructor || spec.requires.is_empty() {
        return Ok(());
    }
    let all = locks(state, name, group).await?;
    let Some(lock) = all.iter().find(|l| l.exercise == spec.id) else {
        return Ok(());
    };
    if lock.open() {
        return Ok(());
    }
    let needs: Vec<String> = lock
        .missing
        .iter()
        .map(|m| {
            let title = EXERCISES
                .get(&m.exercise)
                .map_or_else(|| m.exercise.clone(), |e| e.title.clone());
            format!("`{}` ({title}; now {})", m.exercise, state_text(m.state))
        })
        .collect();
    Err(ApiError::forbidden(format!(
        "exercise `{}` is locked: it needs proficiency in {}; practise that first, or ask \
         the instructor to unlock it",
        spec.id,
        needs.join(" and ")
    ))
    .with_detail(json!({ "exercise": spec.id, "missing": lock.missing })))
}

/// A state as the error message says it.
fn state_text(s: ProficiencyState) -> &'static str {
    match s {
        ProficiencyState::NotStarted => "not started",
        ProficiencyState::Practising => "practising",
        ProficiencyState::Proficient => "proficient",
        ProficiencyState::Relapsed => "relapsed",
    }
}

/// A trainee named by a query or body: the name (required) and group, normalised.
fn who(trainee: &str, group: &str) -> Result<(String, String), ApiError> {
    let name = display_name(trainee);
    if name.is_empty() {
        return Err(ApiError::bad_request("`trainee` must name a trainee"));
    }
    Ok((name, display_name(group)))
}

/// The answer of the three routes.
async fn answer(state: &AppState, name: &str, group: &str) -> Result<Json<Value>, ApiError> {
    let list = locks(state, name, group).await?;
    Ok(Json(json!({
        "trainee": name,
        "group": group,
        "progression": state.progression,
        "exercises": list,
    })))
}

/// Query of `GET /api/unlocks`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraineeQuery {
    trainee: String,
    #[serde(default)]
    group: String,
}

/// `GET /api/unlocks?trainee=&group=` (instructor).
pub async fn get(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<TraineeQuery>,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let (name, group) = who(&q.trainee, &q.group)?;
    answer(&state, &name, &group).await
}

/// Body of `PUT /api/unlocks`; query of `DELETE /api/unlocks`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unlock {
    trainee: String,
    #[serde(default)]
    group: String,
    exercise: String,
}

/// The instructor's change: who, and a known exercise (404 otherwise).
async fn change(
    state: &AppState,
    creds: &Credentials,
    u: &Unlock,
    on: bool,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(state, creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let (name, group) = who(&u.trainee, &u.group)?;
    if EXERCISES.get(&u.exercise).is_none() {
        return Err(ApiError::not_found(format!("no exercise `{}`", u.exercise)));
    }
    state
        .db
        .set_unlock(&name, &group, &u.exercise, on)
        .await
        .map_err(db_error)?;
    answer(state, &name, &group).await
}

/// `PUT /api/unlocks` (instructor): opens an exercise for a trainee.
pub async fn unlock(
    State(state): State<AppState>,
    creds: Credentials,
    crate::json::ApiJson(body): crate::json::ApiJson<Unlock>,
) -> Result<Json<Value>, ApiError> {
    change(&state, &creds, &body, true).await
}

/// `DELETE /api/unlocks?trainee=&group=&exercise=` (instructor): locks it again (its
/// requirements decide once more).
pub async fn lock(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<Unlock>,
) -> Result<Json<Value>, ApiError> {
    change(&state, &creds, &q, false).await
}
