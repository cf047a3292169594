//! The typed records of attempts and events: what the live state tells the recorder
//! ([`crate::sessions::record`]) and the database stores.
//!
//! An *attempt* is one stretch of a session from a start (session creation, reset, scenario
//! switch) to the next start or the session's end, for every scenario (an exercise's
//! attempt carries its assessment). It is recorded as its initial conditions
//! ([`AttemptStart::init`]) and the compressed stream of applied inputs
//! ([`crate::sessions::command::log`]), from which [`crate::replay`] re-simulates it exactly.

use serde::Serialize;

/// An attempt started.
#[derive(Debug, Clone, Serialize)]
pub struct AttemptStart {
    /// Attempt id (16 hex digits).
    pub id: String,
    /// Session id.
    pub session: String,
    /// Scenario name (an exercise's id for an exercise).
    pub scenario: String,
    /// Exercise id, when the scenario is an exercise.
    pub exercise: Option<String>,
    /// Version stamp of the exercise file (its `version` and content hash).
    pub exercise_version: Option<String>,
    /// Version stamp of the simulator that recorded it ([`crate::replay::SIM_VERSION`]).
    pub sim_version: String,
    /// Unix seconds.
    pub started_unix: f64,
    /// Initial conditions for replay ([`crate::replay::Init`] as JSON).
    pub init: serde_json::Value,
}

impl AttemptStart {
    /// A practice attempt's source ("take over from here"), from its initial conditions'
    /// `from` (`{"attempt": id, "step": k}`); None for every other attempt.
    pub fn taken_over_from(&self) -> Option<TakenOver> {
        let from = self.init.get("from")?;
        Some(TakenOver {
            attempt: from.get("attempt")?.as_str()?.to_string(),
            t: from.get("step")?.as_u64()? as f64 / 1000.0,
        })
    }
}

/// The attempt and time a practice attempt was taken over from (`migrations/0006`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TakenOver {
    /// The source attempt's id.
    pub attempt: String,
    /// Seconds since the source's start.
    pub t: f64,
}

/// An attempt ended (a new start, or its session ended).
#[derive(Debug, Clone, Serialize)]
pub struct AttemptEnd {
    /// Attempt id.
    pub id: String,
    /// Unix seconds.
    pub ended_unix: f64,
    /// Simulated seconds the attempt ran.
    pub sim_seconds: f64,
    /// `passed`, `failed` (exercise), `abandoned` (reset or switch before the end),
    /// `ended` (free play), or `interrupted` (server stopped).
    pub outcome: String,
    /// Score 0–100 (exercises).
    pub score: Option<f64>,
    /// The exercise's assessment (the `GET /api/sessions/{id}/assessment` JSON).
    pub assessment: Option<serde_json::Value>,
}

/// One typed event of a session (grasp change, strike, overload, relief, fault, instructor
/// action, reset, …).
#[derive(Debug, Clone, Serialize)]
pub struct EventRecord {
    /// Session id.
    pub session: String,
    /// Attempt it happened in.
    pub attempt: Option<String>,
    /// Simulated seconds since the attempt started.
    pub t: f64,
    /// Kind: `grasp`, `relief`, `exercise` (strike, overload, drop, step, …), or a command
    /// name (`reset`, `pause`, `fault`, `settings`, …).
    pub kind: String,
    /// Who gave it, for commands (`trainee`, `instructor`).
    pub actor: Option<&'static str>,
    /// Details (JSON object).
    pub detail: serde_json::Value,
}
