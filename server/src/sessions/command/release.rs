//! `release`: open both jaws, whatever the sticks say, for [`RELEASE_DURATION_S`]. Wire:
//! WebSocket and REST `{"type": "release"}`. Logged as `{"c": "release"}`.

use serde_json::json;

use crate::sessions::Live;

/// How long `release` drives both jaws open (s): 7.5 cm at 10.2 cm/s takes 0.74 s (Lim
/// Table 1-1), so 1 s opens them fully whatever grip the sticks send meanwhile.
pub const RELEASE_DURATION_S: f64 = 1.0;

/// Applies a release.
pub(super) fn apply(live: &mut Live) -> serde_json::Value {
    live.release(RELEASE_DURATION_S);
    json!({})
}
