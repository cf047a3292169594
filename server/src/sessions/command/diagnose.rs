//! `diagnose`: name the fault of a diagnosis drill (one of the drill's answers). Wire: the
//! WebSocket's `{"type": "diagnose", "answer"}`. Logged as `{"c": "diagnose", "answer"}`
//! (it counts in the score).

use serde_json::json;

use super::CommandError;
use crate::sessions::Live;

/// Applies an answer to the running exercise's drill.
pub(super) fn apply(live: &mut Live, answer: &str) -> Result<serde_json::Value, CommandError> {
    live.diagnose(answer).map_err(CommandError::Invalid)?;
    Ok(json!({"answer": answer}))
}
