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
    /// The exercises to be proficient in first (the file's `requires`).
    requires: Vec<String>,
    time_limit_s: f64,
    steps: Vec<StepSummary>,
    control: seaarms_core::exercise::spec::ControlSpec,
}

#[derive(Debug, Serialize)]
struct StepSummary {
    id: String,
    text: String,
}

/// `GET /api/exercises`: every exercise with its goal, steps and requirements, and whether the
/// server locks exercises by them (`progression`, `--progression`; public: which exercises a
/// given trainee may start is theirs, [`crate::api::unlocks`]).
pub async fn list(
    axum::extract::State(state): axum::extract::State<crate::app::AppState>,
) -> Json<serde_json::Value> {
    let list: Vec<ExerciseSummary> = EXERCISES
        .all()
        .iter()
        .map(|s| ExerciseSummary {
            id: s.id.clone(),
            title: s.title.clone(),
            goal: s.goal.clone(),
            skills: s.skills.clone(),
            requires: s.requires.clone(),
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
    Json(serde_json::json!({ "exercises": list, "progression": state.progression }))
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Driver {
    /// The exercise file's autopilot script.
    Autopilot,
    /// A human-paced operator following the autopilot's intent ([`HumanPace`]): decides
    /// every [`HUMAN_DECISION_S`], at most two axes at a time, each at rest, slow (30 %,
    /// Shift) or full — a keyboard user's choices, with a reaction time.
    HumanPaced,
    /// [`Driver::HumanPaced`] with seeded human variation ([`HumanNoise`]): the scripted class
    /// of operators of different skill (issue 30's benchmark tests).
    Noisy(HumanNoise),
    /// Nobody: no input at all.
    Idle,
}

/// Seeded variation of a human-paced operator: each decision comes `reaction` ×
/// [`HUMAN_DECISION_S`] after the last, stretched by up to `jitter` of that (uniform), and each
/// axis's intent is misjudged by a factor drawn uniformly from 1 ± `misjudge` before it is
/// quantised (a person under- or over-estimates how far a jaw has to go). Reaction 1, jitter
/// and misjudge 0 is [`Driver::HumanPaced`]; a slower or less steady operator takes longer,
/// overshoots and corrects more. Human choice reaction times spread by about ±30 % around
/// their mean (Hick's-law studies), hence jitters of that order in the tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HumanNoise {
    /// Mean decision interval as a multiple of [`HUMAN_DECISION_S`] (≥ 0.6).
    pub reaction: f64,
    /// Largest extra share of that interval, drawn per decision (0–1).
    pub jitter: f64,
    /// Largest relative misjudgement of an axis's intent, drawn per decision and axis (0–0.9).
    pub misjudge: f64,
    /// Seed of the draws.
    pub seed: u64,
}

/// SplitMix64 (Steele, Lea & Flood 2014, "Fast splittable pseudorandom number generators"),
/// the draws of [`HumanNoise`]: a uniform number in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// How often the human-paced operator decides (s): 0.25, a choice reaction time (Hick's
/// law puts a two-alternative choice at 0.3–0.4 s; a practised operator tracking a moving
/// target re-decides about every 0.2–0.3 s) — above the issue's ≥ 150 ms between decisions.
pub const HUMAN_DECISION_S: f64 = 0.25;
/// Below this deflection of the autopilot's intent the human leaves the axis at rest (or taps
/// it, below [`HUMAN_TAP`]); below [`HUMAN_FULL`] the slow (30 %) deflection, above it full.
const HUMAN_REST: f64 = 0.08;
const HUMAN_FULL: f64 = 0.6;
/// An intent this small on the strongest arm axis (and above 0.01) is a fine tap (a jog at
/// 0.3 of a full one, Shift) rather than a held key: the last few degrees or millimetres.
const HUMAN_TAP: f64 = 0.25;

/// The human-paced operator's limits on an intent ([`Driver::HumanPaced`]): a fine tap of the
/// strongest arm axis when every arm axis is small (returned: arm, axes; the sticks then rest),
/// else the two strongest of the twelve arm axes (or of the six object axes), each quantized
/// to 0, ±0.3 or ±1; grips to 0 or ±1.
fn human_paced(out: &mut seaarms_core::exercise::PilotOutput) -> Option<(usize, [f64; 6])> {
    let (mut best, mut at) = (0.0_f64, (0, 0));
    for (i, a) in out.axes.iter().enumerate() {
        for (k, v) in a.iter().enumerate() {
            if v.abs() > best.abs() {
                (best, at) = (*v, (i, k));
            }
        }
    }
    let tap = (0.01..HUMAN_TAP).contains(&best.abs()).then(|| {
        let mut axes = [0.0; 6];
        axes[at.1] = 0.3 * best.signum();
        (at.0, axes)
    });
    let q = |v: f64| {
        let a = v.abs();
        if a < HUMAN_REST {
            0.0
        } else if a < HUMAN_FULL {
            0.3 * v.signum()
        } else {
            v.signum()
        }
    };
    let keep_two = |vals: &mut [f64]| {
        let mut idx: Vec<usize> = (0..vals.len()).collect();
        idx.sort_by(|a, b| vals[*b].abs().total_cmp(&vals[*a].abs()));
        for (rank, i) in idx.into_iter().enumerate() {
            vals[i] = if rank < 2 { q(vals[i]) } else { 0.0 };
        }
    };
    let mut arms: Vec<f64> = out.axes.iter().flatten().copied().collect();
    keep_two(&mut arms);
    for (k, v) in arms.into_iter().enumerate() {
        out.axes[k / 6][k % 6] = v;
    }
    keep_two(&mut out.object);
    for g in &mut out.grips {
        *g = if g.abs() < HUMAN_REST {
            0.0
        } else {
            g.signum()
        };
    }
    if tap.is_some() {
        out.axes = [[0.0; 6]; 2];
    }
    tap
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
        None,
    )?;
    let mut pilot = Autopilot::new(spec.autopilot.clone(), spec.control.mode);
    let noise = match driver {
        Driver::HumanPaced => Some(HumanNoise {
            reaction: 1.0,
            jitter: 0.0,
            misjudge: 0.0,
            seed: 0,
        }),
        Driver::Noisy(n) => Some(HumanNoise {
            reaction: n.reaction.clamp(0.6, 8.0),
            jitter: n.jitter.clamp(0.0, 1.0),
            misjudge: n.misjudge.clamp(0.0, 0.9),
            ..n
        }),
        _ => None,
    };
    let mut draws = noise.map_or(0, |n| n.seed);
    if noise.is_some() {
        pilot = pilot.settling();
    }
    let steps_per_tick = (PILOT_INTERVAL_S * 1000.0).round() as u64;
    let max_steps = ((spec.time_limit_s + 1.0) * 1000.0) as u64;
    let mut seq = 0;
    let mut steps = 0;
    let mut next_decision = 0;
    let mut held: Option<seaarms_core::exercise::PilotOutput> = None;
    while steps < max_steps {
        if let Some(noise) = noise {
            let mut out = {
                let run = live
                    .exercise()
                    .ok_or_else(|| anyhow::anyhow!("no exercise"))?;
                pilot.tick(live.sim(), &run.facts())
            };
            // Settings and answers as they come (a click); the sticks only at decisions.
            if let Some((mode, method)) = out.settings.take() {
                live.apply(&Command::settings(mode, method, None, None)?)?;
            }
            if let Some(answer) = out.answer.take() {
                live.apply(&Command::Diagnose {
                    answer: answer.to_string(),
                })?;
            }
            if held.is_none() || steps >= next_decision {
                let mut interval = HUMAN_DECISION_S * noise.reaction;
                if noise.jitter > 0.0 {
                    interval *= 1.0 + noise.jitter * uniform(&mut draws);
                }
                // on the pilot's own tick grid, as its plan is evaluated
                let ticks = (interval / PILOT_INTERVAL_S).round().max(1.0) as u64;
                next_decision = steps + ticks * steps_per_tick;
                if noise.misjudge > 0.0 {
                    for v in out.axes.iter_mut().flatten().chain(out.object.iter_mut()) {
                        *v *= 1.0 + noise.misjudge * (2.0 * uniform(&mut draws) - 1.0);
                    }
                }
                if let Some((arm, axes)) = human_paced(&mut out) {
                    let side = if arm == 0 { "left" } else { "right" };
                    live.apply(&Command::jog(side, &axes, &mut Vec::new())?)?;
                }
                held = Some(out);
            }
            let h = held.as_ref().expect("decided");
            seq += 1;
            live.apply(&Command::Input(StickInput {
                seq,
                arms: [0, 1].map(|i| ArmSticks {
                    axes: h.axes[i],
                    grip: h.grips[i],
                }),
                object: h.object,
            }))?;
        }
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
