//! `ready`: the trainee has read the exercise's goal; the attempt's clock starts (a session
//! created with `wait_for_ready`, as the trainee's page creates them; otherwise nothing).
//! Wire: the WebSocket's `{"type": "ready"}`. Not logged: while an attempt waits no steps
//! pass, so the log's step stamps already account for it.

use serde_json::json;

use crate::sessions::Live;

/// Applies `ready`: says whether the attempt was waiting.
pub(super) fn apply(live: &mut Live) -> serde_json::Value {
    let waited = live.awaiting_ready();
    live.ready();
    json!({"started": waited})
}
