//! `end`: end the session. Wire: `DELETE /api/sessions/{id}` (the instructor, or the
//! session's trainee). Not logged: the attempt's record ends with the session.

use crate::auth::Actor;
use crate::protocol::EndReason;
use crate::sessions::{Session, SessionManager};

/// Ends `session` on behalf of `actor`.
pub(super) fn apply(manager: &SessionManager, session: &Session, actor: Actor) {
    // `Command::permitted` lets only instructors and trainees end a session.
    let reason = match actor {
        Actor::Instructor => EndReason::Instructor,
        Actor::Trainee | Actor::Observer => EndReason::Trainee,
    };
    manager.end(&session.id, reason);
}
