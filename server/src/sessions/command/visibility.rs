//! `set_visibility`: the instructor sets how far one sees in the water, for every page of the
//! session (the pilot cameras' fog, web/water.js). Wire: the REST action `{"type":
//! "set_visibility", "visibility_m"}`; frames carry it as `visibility_m`. Not logged: it
//! changes what is drawn, not the simulation (the record keeps it as an event).

use serde_json::json;

use super::{Command, CommandError};
use crate::sessions::Live;

/// Visibility range an instructor may set (m): from very murky water (0.5 m, a silted
/// harbour) to clear ocean water (50 m); The ROV Manual's simulator chapter treats
/// turbidity as a training variable in this range.
pub const VISIBILITY_RANGE_M: [f64; 2] = [0.5, 50.0];

impl Command {
    /// Parses a visibility, checking it is finite and within [`VISIBILITY_RANGE_M`].
    pub fn visibility(visibility_m: f64) -> Result<Command, CommandError> {
        let [lo, hi] = VISIBILITY_RANGE_M;
        if !(visibility_m.is_finite() && (lo..=hi).contains(&visibility_m)) {
            return Err(CommandError::Invalid(format!(
                "visibility_m must be in [{lo}, {hi}] m, got {visibility_m}"
            )));
        }
        Ok(Command::SetVisibility(visibility_m))
    }
}

/// Applies a visibility (any session: in air it is kept for when the pages draw water).
pub(super) fn apply(live: &mut Live, visibility_m: f64) -> serde_json::Value {
    live.set_visibility(visibility_m);
    json!({"visibility_m": visibility_m})
}
