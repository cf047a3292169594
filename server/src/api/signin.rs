//! The instructor's sign-in (issue 29: no token in a page's or link's URL).
//!
//! * `POST /api/signin {"token": …}`: with the instructor token, 204 and the instructor cookie
//!   ([`crate::auth::INSTRUCTOR_COOKIE`], `HttpOnly`, `SameSite=Strict`), which then opens
//!   every instructor route, debrief and download of this browser without a token in the URL;
//!   a wrong token is a 403.
//! * `POST /api/signout`: 204, the cookie removed.
//! * `GET /api/signin`: 200 `{"instructor": bool, "trainee_sessions": n}` — what this
//!   browser's cookies are, so a page opened without a token (a debrief) can tell "nobody
//!   here" without asking for a record it would be refused.

use axum::Json;
use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;

use crate::app::AppState;
use crate::auth::{INSTRUCTOR_COOKIE, WRONG_TOKEN, instructor_cookie_value, set_cookie, token_eq};
use crate::error::ApiError;

/// How long a sign-in lasts (s): a working day and a night.
pub const SIGN_IN_S: u64 = 16 * 3600;

/// Body of `POST /api/signin`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignIn {
    /// The instructor token.
    token: String,
}

/// Whether cookies are sent over https only (`Secure`): the public URL is https.
pub fn secure_cookies(state: &AppState) -> bool {
    state
        .policy
        .public_url
        .as_ref()
        .is_some_and(|u| u.scheme == "https")
}

fn with_cookie(cookie: String) -> Response {
    let mut resp = StatusCode::NO_CONTENT.into_response();
    if let Ok(v) = HeaderValue::from_str(&cookie) {
        resp.headers_mut().insert(header::SET_COOKIE, v);
    }
    resp
}

/// `POST /api/signin`.
pub async fn sign_in(
    State(state): State<AppState>,
    Json(body): Json<SignIn>,
) -> Result<Response, ApiError> {
    if !token_eq(&body.token, &state.instructor_token) {
        return Err(ApiError::forbidden(WRONG_TOKEN));
    }
    let value = instructor_cookie_value(&state.instructor_token);
    Ok(with_cookie(set_cookie(
        INSTRUCTOR_COOKIE,
        &value,
        SIGN_IN_S,
        secure_cookies(&state),
    )))
}

/// `GET /api/signin`.
pub async fn status(State(state): State<AppState>, creds: crate::auth::Credentials) -> Response {
    let (instructor, trainee_sessions) = creds.cookies(&state);
    Json(serde_json::json!({"instructor": instructor, "trainee_sessions": trainee_sessions}))
        .into_response()
}

/// `POST /api/signout`.
pub async fn sign_out(State(state): State<AppState>) -> Response {
    with_cookie(set_cookie(INSTRUCTOR_COOKIE, "", 0, secure_cookies(&state)))
}
