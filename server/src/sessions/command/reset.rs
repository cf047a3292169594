//! `reset`: back to the initial position (Lim §4.1). Wire: WebSocket and REST
//! `{"type": "reset"}`. Not logged: it ends the attempt and starts a new one.

use serde_json::json;

use crate::sessions::Live;

/// Applies a reset: the simulation at its reset state, inputs cleared, a new attempt.
pub(super) fn apply(live: &mut Live) -> serde_json::Value {
    live.reset();
    json!({})
}
