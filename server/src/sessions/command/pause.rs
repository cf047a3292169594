//! `pause` and `resume`: stop and restart the session's clock. Wire: WebSocket and REST
//! `{"type": "pause"}`, `{"type": "resume"}`. Not logged: a paused session takes no steps,
//! so the log's step stamps already account for pauses.

use serde_json::json;

use super::CommandError;
use crate::auth::Actor;
use crate::sessions::Live;

/// What a trainee's `resume` gets while the instructor has paused the session.
pub const PAUSED_BY_INSTRUCTOR: &str = "paused by the instructor; only the instructor can resume";

/// Pauses (`pause`) or resumes the clock on behalf of `by`. An instructor's pause is
/// lifted only by the instructor: the trainee's `resume` is refused
/// ([`PAUSED_BY_INSTRUCTOR`]) and the trainee's `pause` leaves it the instructor's. The
/// instructor's pause takes over a trainee's; the instructor's resume lifts any pause.
/// Returns the record's detail (who holds the pause now).
pub fn apply(live: &mut Live, by: Actor, pause: bool) -> Result<serde_json::Value, CommandError> {
    let instructors = live.paused_by() == Some(Actor::Instructor);
    match (pause, by) {
        (false, Actor::Trainee) if instructors => {
            return Err(CommandError::Forbidden(PAUSED_BY_INSTRUCTOR.to_string()));
        }
        (true, Actor::Trainee) if instructors => {}
        (true, _) => live.set_paused(Some(by)),
        (false, _) => live.set_paused(None),
    }
    Ok(json!({"paused_by": live.paused_by()}))
}
