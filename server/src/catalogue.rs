//! The one catalogue of what can be started, by name:
//!
//! * [`LIVE_SCENARIOS`]: what a live session can start from besides an exercise — free play
//!   and the set-ups of Lim's case studies (the `scenario` of `POST /api/sessions`, the
//!   page's scenario menu in `hello.scenarios`);
//! * [`EXERCISES`]: the exercise files (`exercises/*.json`, embedded in the binary), by id
//!   (`GET /api/exercises`, and a session's `exercise`);
//! * [`SCRIPTED`]: Lim's scripted dynamic case studies, run headless by
//!   `POST /api/scenarios/{name}/run` and `seaarms scenario` ([`crate::scenarios`]).
//!
//! [`Scenario`] is what a live session runs, resolved from a name of the first two; a
//! session stores it once (in its live state, [`crate::sessions::Live::scenario`]).

use std::collections::BTreeMap;
use std::sync::{Arc, LazyLock};

use rust_embed::RustEmbed;
use seaarms_core::Model;
use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::exercise::progression::check_requires;
use seaarms_core::sim::{Medium, SimParams, Simulation};

pub use seaarms_core::sim::scenario::SCENARIOS as SCRIPTED;

/// Scenarios a live session can start from (the initial position of Lim §4.1 for all of
/// them); `training` is free play.
pub const LIVE_SCENARIOS: &[(&str, &str)] = &[
    (
        "training",
        "Free play: both arms at the initial position, the 50 kg box on the seabed, in sea water",
    ),
    (
        "case1-single-arm",
        "Lim case study 1 set-up: move the left arm joint by joint, no object (in air, as the thesis)",
    ),
    (
        "case2-single-arm-load",
        "Lim case study 2 set-up: grab, lift and release the box with the left arm (in air, as the thesis)",
    ),
    (
        "case3-dual-open-loop",
        "Lim case study 3 set-up: both arms grab and carry the box in open loop (in air, as the thesis)",
    ),
    (
        "case4-dual-closed-loop",
        "Lim case study 4 set-up: both arms grab the box, switch to closed loop, carry it (in air, as the thesis)",
    ),
];

/// The medium of a live scenario: free play (`training`) is subsea, like the exercises; the
/// case-study set-ups stay in air, the thesis's setting (Lim §4.2), so their figures compare.
pub fn free_medium(name: &str) -> Medium {
    if name == "training" {
        Medium::Subsea
    } else {
        Medium::Air
    }
}

/// Every name a live session can start from: the live scenarios, then the exercise ids.
pub fn live_names() -> Vec<String> {
    LIVE_SCENARIOS
        .iter()
        .map(|(n, _)| (*n).to_string())
        .chain(EXERCISES.all().iter().map(|e| e.id.clone()))
        .collect()
}

#[derive(RustEmbed)]
#[folder = "exercises/"]
struct Files;

/// Every exercise, by id, parsed and checked once.
pub struct Exercises {
    by_id: BTreeMap<String, Arc<ExerciseSpec>>,
    /// Files that did not parse or check, and a set whose `requires` do not resolve or make
    /// a cycle (a bug in a shipped file; a test keeps this empty).
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
        // the set as a whole: requirements name exercises of it, no cycles
        if let Err(e) = check_requires(by_id.values().map(|s| &**s)) {
            tracing::error!("exercises/: {e}");
            errors.push(format!("exercises/: {e}"));
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

/// What a session runs.
#[derive(Debug, Clone)]
pub enum Scenario {
    /// Free play or a case-study set-up ([`LIVE_SCENARIOS`]), by name.
    Free(String),
    /// An exercise (`exercises/<id>.json`).
    Exercise(Arc<ExerciseSpec>),
}

/// Scenarios are equal when their names are (an exercise id names one file of this build).
impl PartialEq for Scenario {
    fn eq(&self, other: &Scenario) -> bool {
        self.name() == other.name()
    }
}

impl Scenario {
    /// Resolves a name: a live scenario or an exercise id.
    pub fn resolve(name: &str) -> Option<Scenario> {
        if LIVE_SCENARIOS.iter().any(|(n, _)| *n == name) {
            Some(Scenario::Free(name.to_string()))
        } else {
            EXERCISES.get(name).map(Scenario::Exercise)
        }
    }

    /// Its name (an exercise's id).
    pub fn name(&self) -> &str {
        match self {
            Scenario::Free(n) => n,
            Scenario::Exercise(e) => &e.id,
        }
    }

    /// The exercise, if it is one.
    pub fn exercise(&self) -> Option<&Arc<ExerciseSpec>> {
        match self {
            Scenario::Free(_) => None,
            Scenario::Exercise(e) => Some(e),
        }
    }

    /// A fresh simulation for it.
    pub(crate) fn build_sim(
        &self,
        models: &[Arc<Model>; 2],
    ) -> Result<Simulation, seaarms_core::Error> {
        let params = match self {
            Scenario::Free(n) => SimParams::case_study(&models[0], &models[1])?
                .with_environment(free_medium(n).environment()),
            Scenario::Exercise(e) => e.sim_params(&models[0], &models[1])?,
        };
        Simulation::new((*models[0]).clone(), (*models[1]).clone(), params)
    }
}
