//! The exercises' routes (`GET /api/exercises`, the files themselves are in
//! [`crate::catalogue`]) and headless attempts: `seaarms exercise <id> --autopilot | --idle`.
//!
//! A headless attempt builds the same [`Live`] a WebSocket session has and drives it with
//! the same [`Command`]s the WebSocket edge produces (stick input at 50 Hz, settings, the
//! diagnosis answer), stepping it with the same [`Live::advance`]; only the wall clock is
//! missing.

use std::sync::Arc;

use axum::Json;
use axum::extract::Path;
use seaarms_core::exercise::autopilot::PILOT_INTERVAL_S;
use seaarms_core::exercise::{Assessment, Autopilot, ExerciseSpec};
use serde::Serialize;

use crate::catalogue::{EXERCISES, Scenario};
use crate::error::ApiError;
use crate::sessions::Live;
use crate::sessions::command::{ArmSticks, Command, StickInput};
use crate::sessions::record::RecordMsg;

/// One exercise in `GET /api/exercises`.
#[derive(Debug, Serialize)]
pub struct ExerciseSummary {
    id: String,
    title: String,
    goal: String,
    skills: Vec<String>,
    time_limit_s: f64,
    steps: Vec<StepSummary>,
    control: seaarms_core::exercise::spec::ControlSpec,
}

#[derive(Debug, Serialize)]
struct StepSummary {
    id: String,
    text: String,
}

/// `GET /api/exercises`: every exercise with its goal and steps.
pub async fn list() -> Json<serde_json::Value> {
    let list: Vec<ExerciseSummary> = EXERCISES
        .all()
        .iter()
        .map(|s| ExerciseSummary {
            id: s.id.clone(),
            title: s.title.clone(),
            goal: s.goal.clone(),
            skills: s.skills.clone(),
            time_limit_s: s.time_limit_s,
            steps: s
                .steps
                .iter()
                .map(|st| StepSummary {
                    id: st.id.clone(),
                    text: st.text.clone(),
                })
                .collect(),
            control: s.control,
        })
        .collect();
    Json(serde_json::json!({ "exercises": list }))
}

/// `GET /api/exercises/{id}`: the whole exercise file; 404 for an unknown id.
pub async fn get(Path(id): Path<String>) -> Result<Json<Arc<ExerciseSpec>>, ApiError> {
    EXERCISES.get(&id).map(Json).ok_or_else(|| {
        ApiError::not_found(format!("unknown exercise `{id}`")).with_detail(serde_json::json!({
            "known": EXERCISES.all().iter().map(|s| s.id.clone()).collect::<Vec<_>>()
        }))
    })
}

/// Who drives a headless attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Driver {
    /// The exercise file's autopilot script.
    Autopilot,
    /// Nobody: no input at all.
    Idle,
}

/// Runs one attempt at `spec` headless until it is done (at most its time limit plus a
/// second) and returns the assessment.
pub fn run_headless(
    spec: Arc<ExerciseSpec>,
    models: &[Arc<seaarms_core::Model>; 2],
    driver: Driver,
    seed: u64,
) -> anyhow::Result<Assessment> {
    run_recorded(spec, models, driver, seed, &mut |_| {}).map(|r| r.assessment)
}

/// A headless attempt with its record, as a live session records it.
pub struct HeadlessRun {
    /// The assessment.
    pub assessment: Assessment,
    /// Its initial conditions ([`crate::replay::Init`]).
    pub init: crate::replay::Init,
    /// Its input log (every piece, concatenated).
    pub inputs: Vec<u8>,
    /// Simulated seconds it ran.
    pub sim_seconds: f64,
    /// The events it recorded (physics events, exercise events, commands), in order.
    pub events: Vec<crate::db::attempt::EventRecord>,
}

/// [`run_headless`], calling `observe` after every step, and keeping the attempt's record.
pub fn run_recorded(
    spec: Arc<ExerciseSpec>,
    models: &[Arc<seaarms_core::Model>; 2],
    driver: Driver,
    seed: u64,
    observe: &mut dyn FnMut(&Live),
) -> anyhow::Result<HeadlessRun> {
    let mut live = Live::new(
        "headless",
        models,
        &Scenario::Exercise(spec.clone()),
        None,
        None,
        seed,
    )?;
    let mut pilot = Autopilot::new(spec.autopilot.clone(), spec.control.mode);
    let steps_per_tick = (PILOT_INTERVAL_S * 1000.0).round() as u64;
    let max_steps = ((spec.time_limit_s + 1.0) * 1000.0) as u64;
    let mut seq = 0;
    let mut steps = 0;
    while steps < max_steps {
        if driver == Driver::Autopilot {
            let out = {
                let run = live
                    .exercise()
                    .ok_or_else(|| anyhow::anyhow!("no exercise"))?;
                pilot.tick(live.sim(), &run.facts())
            };
            if let Some((mode, method)) = out.settings {
                live.apply(&Command::settings(mode, method, None, None)?)?;
            }
            if let Some(answer) = out.answer {
                live.apply(&Command::Diagnose {
                    answer: answer.to_string(),
                })?;
            }
            seq += 1;
            let input = StickInput {
                seq,
                arms: [0, 1].map(|i| ArmSticks {
                    axes: out.axes[i],
                    grip: out.grips[i],
                }),
                object: out.object,
            };
            live.apply(&Command::Input(input))?;
        }
        for _ in 0..steps_per_tick {
            live.advance();
            observe(&live);
        }
        steps += steps_per_tick;
        if live.exercise().is_some_and(|r| r.done()) {
            break;
        }
    }
    let assessment = live
        .exercise()
        .map(|r| r.assessment())
        .ok_or_else(|| anyhow::anyhow!("no exercise"))?;
    let sim_seconds = live.sim().time_s();
    live.end_attempt(crate::sessions::AttemptStop::Left);
    let (mut init, mut inputs, mut events) = (None, Vec::new(), Vec::new());
    for msg in live.take_records(false) {
        match msg {
            RecordMsg::AttemptStarted(a) => init = Some(serde_json::from_value(a.init)?),
            RecordMsg::AttemptInputs { bytes, .. } => inputs.extend(bytes),
            RecordMsg::Event(e) => events.push(*e),
            _ => {}
        }
    }
    Ok(HeadlessRun {
        assessment,
        init: init.ok_or_else(|| anyhow::anyhow!("the attempt recorded no start"))?,
        inputs,
        sim_seconds,
        events,
    })
}
