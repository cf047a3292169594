//! The exercise files (`exercises/*.json`, embedded in the binary), their routes, and headless
//! attempts: `seaarms exercise <id> --autopilot | --idle`.
//!
//! A headless attempt builds the same [`Live`] a WebSocket session has and drives it with
//! the same [`Command`]s the WebSocket edge produces (stick input at 50 Hz, settings, the
//! diagnosis answer), stepping it with the same [`Live::advance`]; only the wall clock is
//! missing.

use std::collections::BTreeMap;
use std::sync::{Arc, LazyLock};

use axum::Json;
use axum::extract::Path;
use rust_embed::RustEmbed;
use seaarms_core::exercise::autopilot::PILOT_INTERVAL_S;
use seaarms_core::exercise::{Assessment, Autopilot, ExerciseSpec};
use serde::Serialize;

use crate::error::ApiError;
use crate::sessions::command::{ArmSticks, Command, StickInput};
use crate::sessions::record::RecordMsg;
use crate::sessions::{Live, Scenario};

#[derive(RustEmbed)]
#[folder = "exercises/"]
struct Files;

/// Every exercise, by id, parsed and checked once.
pub struct Exercises {
    by_id: BTreeMap<String, Arc<ExerciseSpec>>,
    /// Files that did not parse or check (a bug in a shipped file; a test keeps this empty).
    pub errors: Vec<String>,
}

/// The exercises shipped in the binary.
pub static EXERCISES: LazyLock<Exercises> = LazyLock::new(Exercises::load);

/// The order the start screen lists them in (first steps first); others follow by id.
const ORDER: &[&str] = &[
    "familiarisation",
    "reach-targets",
    "pick-and-place",
    "dual-lift",
    "valve-turn",
    "hot-stab",
    "fault-diagnosis",
];

impl Exercises {
    fn load() -> Exercises {
        let mut by_id = BTreeMap::new();
        let mut errors = Vec::new();
        for name in Files::iter().filter(|n| n.ends_with(".json")) {
            let Some(file) = Files::get(&name) else {
                continue;
            };
            let parsed = serde_json::from_slice::<ExerciseSpec>(&file.data)
                .map_err(|e| format!("exercises/{name}: {e}"))
                .and_then(|spec| {
                    spec.check().map_err(|e| format!("exercises/{name}: {e}"))?;
                    if format!("{}.json", spec.id) != name {
                        return Err(format!("exercises/{name}: id `{}` ≠ file name", spec.id));
                    }
                    Ok(spec)
                });
            match parsed {
                Ok(spec) => {
                    by_id.insert(spec.id.clone(), Arc::new(spec));
                }
                Err(e) => {
                    tracing::error!("{e}");
                    errors.push(e);
                }
            }
        }
        Exercises { by_id, errors }
    }

    /// An exercise by id.
    pub fn get(&self, id: &str) -> Option<Arc<ExerciseSpec>> {
        self.by_id.get(id).cloned()
    }

    /// Every exercise, in the start screen's order.
    pub fn all(&self) -> Vec<Arc<ExerciseSpec>> {
        let rank = |id: &str| ORDER.iter().position(|o| *o == id).unwrap_or(ORDER.len());
        let mut v: Vec<_> = self.by_id.values().cloned().collect();
        v.sort_by(|a, b| rank(&a.id).cmp(&rank(&b.id)).then(a.id.cmp(&b.id)));
        v
    }
}

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
                live.apply(&Command::settings(mode, method, None)?)?;
            }
            if let Some(answer) = out.answer {
                live.apply(&Command::Diagnose(answer.to_string()))?;
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
    live.end_attempt("abandoned");
    let (mut init, mut inputs) = (None, Vec::new());
    for msg in live.take_records(false) {
        match msg {
            RecordMsg::AttemptStarted(a) => init = Some(serde_json::from_value(a.init)?),
            RecordMsg::AttemptInputs { bytes, .. } => inputs.extend(bytes),
            _ => {}
        }
    }
    Ok(HeadlessRun {
        assessment,
        init: init.ok_or_else(|| anyhow::anyhow!("the attempt recorded no start"))?,
        inputs,
        sim_seconds,
    })
}
