//! `set_current`: the instructor sets the water's current (a subsea session). Wire: the REST
//! action `{"type": "set_current", "speed_m_s", "heading_deg"}`. Logged as
//! `{"c": "current", "speed_m_s", "heading_deg"}` (heading reduced to [0, 360)).

use serde_json::json;

use super::{Command, CommandError};
use crate::sessions::Live;
use seaarms_core::sim::water::Current;

pub use seaarms_core::sim::water::MAX_CURRENT_M_S;

impl Command {
    /// Parses a current, checking speed ∈ [0, [`MAX_CURRENT_M_S`]] m/s and a finite heading
    /// within ±360° ([`Current::new`]).
    pub fn current(speed_m_s: f64, heading_deg: f64) -> Result<Command, CommandError> {
        Current::new(speed_m_s, heading_deg)
            .map(Command::SetCurrent)
            .map_err(|e| CommandError::Invalid(e.to_string()))
    }
}

/// Applies a current (refused in air).
pub(super) fn apply(live: &mut Live, current: &Current) -> Result<serde_json::Value, CommandError> {
    live.set_current(*current)
        .map_err(|e| CommandError::Invalid(e.to_string()))?;
    Ok(json!({"current": current}))
}
