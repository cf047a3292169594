//! `GET /api/openapi.json`: the hand-kept OpenAPI description of every route
//! (`openapi.json` beside this file; `tests/operations.rs` checks it against the router).

use axum::http::header;
use axum::response::IntoResponse;

/// The document's text.
pub const OPENAPI_JSON: &str = include_str!("openapi.json");

/// Handler.
pub async fn spec() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "application/json")], OPENAPI_JSON)
}
