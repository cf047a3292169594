//! Who is asking: the one place tokens are read and compared, for every route and socket.
//!
//! * [`Credentials`], an extractor: the token of `Authorization: Bearer …` and of `?token=`,
//!   as sent. Each route says where it accepts the token ([`TokenFrom`]): the REST routes of
//!   sessions read the header (the CSV download and the assessment also the query, so a plain
//!   link works), the attempts routes both, the WebSockets the query (browsers cannot set
//!   headers on them). Without a token, the pages' cookies stand in for it (issue 29: no
//!   token in a page's or link's URL): the instructor's, set by `POST /api/signin`
//!   ([`INSTRUCTOR_COOKIE`], a digest of the token, not the token), and a trainee's per
//!   session, set when the session is created ([`trainee_cookie_name`]); both `HttpOnly`,
//!   `SameSite=Strict`.
//! * [`Principal`]: what the token opens — the instructor (every session), the trainee of
//!   session X (its control token; once the session has ended, the SHA-256 the records keep),
//!   or nobody (no token, or a token that opens nothing).
//! * [`Actor`]: who acts on a session — the one "who" type: commands are checked against
//!   it, events store its name (`actor`: `instructor`, `trainee`, `observer`), and a paused
//!   clock remembers it (`paused_by`).
//!
//! Every refusal is a 403 with the messages the API documents (docs/api.md), defined here.

use axum::extract::{FromRequestParts, Query};
use axum::http::request::Parts;
use axum::http::{HeaderMap, header};
use serde::{Deserialize, Serialize};

use crate::app::AppState;
use crate::db::unavailable as db_error;
use crate::error::ApiError;

/// Compares two tokens exactly (no trimming, case-sensitive) in time independent of their
/// contents and lengths: the SHA-256 digests of both are compared with an XOR fold, so neither
/// the position of the first difference nor a length mismatch shows in the timing.
pub fn token_eq(a: &str, b: &str) -> bool {
    use sha2::{Digest, Sha256};
    let (da, db) = (Sha256::digest(a.as_bytes()), Sha256::digest(b.as_bytes()));
    let diff = da
        .iter()
        .zip(db.iter())
        .fold(0u8, |acc, (x, y)| acc | (x ^ y));
    std::hint::black_box(diff) == 0
}

/// The SHA-256 of `text`, as lowercase hex (the records keep a control token this way).
pub fn sha256_hex(text: &str) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The token of `Authorization: Bearer <token>`, exactly as sent (no trimming).
pub fn bearer(headers: &HeaderMap) -> Option<&str> {
    let (scheme, token) = headers
        .get(header::AUTHORIZATION)?
        .to_str()
        .ok()?
        .split_once(' ')?;
    scheme.eq_ignore_ascii_case("bearer").then_some(token)
}

/// Who acts on a session: the one "who" type of the server. Its name is what events store
/// (`actor`) and what state frames and summaries show as `paused_by`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Actor {
    /// The instructor token: every command (on a WebSocket, an observer).
    Instructor,
    /// The session's own control token: driving, settings, reset/pause/resume/release,
    /// diagnosis, end.
    Trainee,
    /// A read-only connection: nothing.
    Observer,
}

impl Actor {
    /// Name in records and messages (the serialized name).
    pub fn as_str(self) -> &'static str {
        match self {
            Actor::Instructor => "instructor",
            Actor::Trainee => "trainee",
            Actor::Observer => "observer",
        }
    }
}

/// Where a route accepts the token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TokenFrom {
    /// `Authorization: Bearer …` only.
    Bearer,
    /// The header, else `?token=`.
    BearerOrQuery,
    /// `?token=` only (WebSockets).
    Query,
}

/// The 403 message of the session routes when no token is presented.
pub const MISSING_TOKEN: &str = "missing token (Authorization: Bearer …)";
/// The 403 message of the attempts routes when no token is presented.
pub const MISSING_TOKEN_OR_QUERY: &str = "missing token (Authorization: Bearer … or ?token=)";
/// The 403 message of a wrong token.
pub const WRONG_TOKEN: &str = "wrong token";
/// The 403 message of a session WebSocket without a token that opens it.
pub const WRONG_OR_MISSING_TOKEN: &str = "wrong or missing token";

/// The instructor's sign-in cookie (`POST /api/signin`).
pub const INSTRUCTOR_COOKIE: &str = "seaarms_instructor";
/// Prefix of a trainee's session cookie (`seaarms_t_<session id>` = its control token).
const TRAINEE_COOKIE_PREFIX: &str = "seaarms_t_";

/// The instructor cookie's value for `instructor_token`: a SHA-256 digest of it (the same on
/// every replica that shares the token; changing the token signs every page out).
pub fn instructor_cookie_value(instructor_token: &str) -> String {
    sha256_hex(&format!("seaarms instructor sign-in\0{instructor_token}"))
}

/// The name of session `id`'s trainee cookie.
pub fn trainee_cookie_name(id: &str) -> String {
    format!("{TRAINEE_COOKIE_PREFIX}{id}")
}

/// A `Set-Cookie` value: `HttpOnly`, `SameSite=Strict`, path `/`, for `max_age_s` (0 removes
/// it); `Secure` when the server is served over https.
pub fn set_cookie(name: &str, value: &str, max_age_s: u64, secure: bool) -> String {
    let secure = if secure { "; Secure" } else { "" };
    format!("{name}={value}; Max-Age={max_age_s}; Path=/; HttpOnly; SameSite=Strict{secure}")
}

/// A request's credentials: the bearer token and the `token` query parameter, as sent, and
/// the sign-in cookies. A malformed query (`?token=a&token=b`) is a 400 for the routes that
/// read the query, as their own query extractor's rejection would be, and no concern of the
/// others.
#[derive(Debug, Clone)]
pub struct Credentials {
    bearer: Option<String>,
    query: Result<Option<String>, ApiError>,
    /// The instructor cookie's value, as sent.
    instructor_cookie: Option<String>,
    /// (session id, control token) of each trainee cookie sent.
    trainee_cookies: Vec<(String, String)>,
}

#[derive(Deserialize)]
struct TokenParam {
    token: Option<String>,
}

impl<S: Send + Sync> FromRequestParts<S> for Credentials {
    type Rejection = std::convert::Infallible;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, Self::Rejection> {
        let query = Query::<TokenParam>::try_from_uri(&parts.uri)
            .map(|Query(p)| p.token)
            .map_err(|e| ApiError::new(e.status(), e.body_text()));
        let mut instructor_cookie = None;
        let mut trainee_cookies = Vec::new();
        let pairs = parts
            .headers
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(';'))
            .filter_map(|kv| kv.trim().split_once('='));
        for (k, v) in pairs {
            if k == INSTRUCTOR_COOKIE {
                instructor_cookie = Some(v.to_string());
            } else if let Some(id) = k.strip_prefix(TRAINEE_COOKIE_PREFIX) {
                trainee_cookies.push((id.to_string(), v.to_string()));
            }
        }
        Ok(Credentials {
            bearer: bearer(&parts.headers).map(str::to_string),
            query,
            instructor_cookie,
            trainee_cookies,
        })
    }
}

/// What a token opens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Principal {
    /// The instructor token.
    Instructor,
    /// The control token of session `session`.
    Trainee {
        /// The session's id.
        session: String,
    },
    /// No token (`token_given` false), or one that opens nothing here.
    Anonymous {
        /// Whether a token was presented.
        token_given: bool,
    },
}

impl Credentials {
    /// The token presented where `from` says (400 for a malformed query when `from` reads
    /// it).
    pub fn token(&self, from: TokenFrom) -> Result<Option<&str>, ApiError> {
        let query = || {
            self.query
                .as_ref()
                .map(Option::as_deref)
                .map_err(Clone::clone)
        };
        Ok(match from {
            TokenFrom::Bearer => self.bearer.as_deref(),
            TokenFrom::BearerOrQuery => {
                let query = query()?;
                self.bearer.as_deref().or(query)
            }
            TokenFrom::Query => query()?,
        })
    }

    /// What this browser's cookies are (`GET /api/signin`): signed in as the instructor, and
    /// how many trainee session cookies it sent (not checked against their sessions).
    pub fn cookies(&self, state: &AppState) -> (bool, usize) {
        let expected = instructor_cookie_value(&state.instructor_token);
        let instructor = self
            .instructor_cookie
            .as_deref()
            .is_some_and(|c| token_eq(c, &expected));
        (instructor, self.trainee_cookies.len())
    }

    /// Whether any credential came: a token where `from` says, or a sign-in cookie.
    pub fn presented(&self, from: TokenFrom) -> Result<bool, ApiError> {
        Ok(self.token(from)?.is_some()
            || self.instructor_cookie.is_some()
            || !self.trainee_cookies.is_empty())
    }

    /// Who the token (read from `from`) is, for session `session` (its id and live control
    /// token) or for no session.
    pub fn principal(
        &self,
        state: &AppState,
        from: TokenFrom,
        session: Option<(&str, &str)>,
    ) -> Result<Principal, ApiError> {
        let Some(token) = self.token(from)? else {
            return Ok(self.of_cookies(state, session));
        };
        if token_eq(token, &state.instructor_token) {
            return Ok(Principal::Instructor);
        }
        Ok(match session {
            Some((id, control)) if token_eq(token, control) => Principal::Trainee {
                session: id.to_string(),
            },
            _ => Principal::Anonymous { token_given: true },
        })
    }

    /// Who the cookies are, when no token was presented: the signed-in instructor, else the
    /// trainee of `session` whose cookie carries its control token.
    fn of_cookies(&self, state: &AppState, session: Option<(&str, &str)>) -> Principal {
        if self.cookies(state).0 {
            return Principal::Instructor;
        }
        match (session, self.trainee_cookie(session.map(|s| s.0))) {
            (Some((id, control)), Some(t)) if token_eq(t, control) => Principal::Trainee {
                session: id.to_string(),
            },
            _ => Principal::Anonymous { token_given: false },
        }
    }

    /// The control token a trainee cookie carries for session `id`.
    fn trainee_cookie(&self, id: Option<&str>) -> Option<&str> {
        let id = id?;
        self.trainee_cookies
            .iter()
            .find(|(s, _)| s == id)
            .map(|(_, t)| t.as_str())
    }

    /// Who the token is for a session that may have ended: the instructor, or the trainee who
    /// held session `id`'s control token (checked against the SHA-256 the records keep).
    pub async fn principal_stored(
        &self,
        state: &AppState,
        from: TokenFrom,
        id: &str,
    ) -> Result<Principal, ApiError> {
        let p = self.principal(state, from, None)?;
        let token = match (&p, self.token(from)?) {
            (Principal::Anonymous { token_given: true }, Some(token)) => token,
            // no token: the trainee's cookie for this session, if any
            (Principal::Anonymous { token_given: false }, None) => {
                match self.trainee_cookie(Some(id)) {
                    Some(t) => t,
                    None => return Ok(p),
                }
            }
            _ => return Ok(p),
        };
        let stored = state.db.session_token_sha256(id).await.map_err(db_error)?;
        Ok(match stored {
            Some(hash) if token_eq(&sha256_hex(token), &hash) => Principal::Trainee {
                session: id.to_string(),
            },
            _ => p,
        })
    }

    /// 403 unless the bearer token is the instructor's ([`MISSING_TOKEN`], [`WRONG_TOKEN`]).
    pub fn require_instructor(&self, state: &AppState) -> Result<(), ApiError> {
        self.principal(state, TokenFrom::Bearer, None)?
            .actor(MISSING_TOKEN)
            .map(|_| ())
    }
}

impl Principal {
    /// The actor this principal acts as on a REST route, or the 403: `missing` without a
    /// token, [`WRONG_TOKEN`] with one that opens nothing.
    pub fn actor(&self, missing: &'static str) -> Result<Actor, ApiError> {
        match self {
            Principal::Instructor => Ok(Actor::Instructor),
            Principal::Trainee { .. } => Ok(Actor::Trainee),
            Principal::Anonymous { token_given: false } => Err(ApiError::forbidden(missing)),
            Principal::Anonymous { token_given: true } => Err(ApiError::forbidden(WRONG_TOKEN)),
        }
    }

    /// The actor of a session WebSocket: the instructor watches (observer), the trainee
    /// drives unless it asks to watch (`wants_observer`); anyone else gets the 403.
    pub fn on_socket(&self, wants_observer: bool) -> Result<Actor, ApiError> {
        match self {
            Principal::Instructor => Ok(Actor::Observer),
            Principal::Trainee { .. } if wants_observer => Ok(Actor::Observer),
            Principal::Trainee { .. } => Ok(Actor::Trainee),
            Principal::Anonymous { .. } => Err(ApiError::forbidden(WRONG_OR_MISSING_TOKEN)),
        }
    }

    /// Whether this is the instructor.
    pub fn is_instructor(&self) -> bool {
        *self == Principal::Instructor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn actor_names_are_the_stored_strings() {
        for a in [Actor::Instructor, Actor::Trainee, Actor::Observer] {
            assert_eq!(serde_json::to_value(a).unwrap(), a.as_str());
        }
        assert_eq!(Actor::Instructor.as_str(), "instructor");
    }

    #[test]
    fn refusals_keep_the_documented_messages() {
        let none = Principal::Anonymous { token_given: false };
        let wrong = Principal::Anonymous { token_given: true };
        let msg = |r: Result<Actor, ApiError>| r.unwrap_err().error;
        assert_eq!(
            msg(none.actor(MISSING_TOKEN)),
            "missing token (Authorization: Bearer …)"
        );
        assert_eq!(msg(wrong.actor(MISSING_TOKEN)), "wrong token");
        assert_eq!(msg(wrong.on_socket(false)), "wrong or missing token");
        assert_eq!(
            Principal::Instructor.on_socket(false).unwrap(),
            Actor::Observer
        );
    }
}
