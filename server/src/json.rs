//! A JSON body extractor whose every rejection is an [`ApiError`] with a JSON body:
//! malformed JSON (with line and column), wrong types, bodies over the limit (413).

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, Request};
use serde::de::DeserializeOwned;

use crate::error::ApiError;

/// Largest REST request body accepted (bytes).
pub const MAX_BODY_BYTES: usize = 64 * 1024;

/// The message of every 413 (bodies over [`MAX_BODY_BYTES`]).
pub fn body_too_large_message() -> String {
    format!("request body is larger than {MAX_BODY_BYTES} bytes")
}

/// The API error of a body that could not be read (413 over [`MAX_BODY_BYTES`]).
pub fn body_rejection(rejection: BytesRejection) -> ApiError {
    ApiError {
        status: rejection.status(),
        error: match rejection.status().as_u16() {
            413 => body_too_large_message(),
            _ => rejection.body_text(),
        },
        detail: None,
    }
}

/// `Json<T>` with API errors.
#[derive(Debug, Clone)]
pub struct ApiJson<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> FromRequest<S> for ApiJson<T> {
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        let bytes = Bytes::from_request(req, state)
            .await
            .map_err(body_rejection)?;
        parse(&bytes).map(ApiJson)
    }
}

/// Parses a JSON body into `T`; errors name the line and column (malformed JSON) or the field.
pub fn parse<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, ApiError> {
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let value = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let msg = if inner.is_syntax() || inner.is_eof() {
            format!("malformed JSON: {inner}")
        } else if path == "." {
            format!("invalid request: {inner}")
        } else {
            format!("invalid field `{path}`: {inner}")
        };
        ApiError::bad_request(msg)
    })?;
    de.end()
        .map_err(|e| ApiError::bad_request(format!("malformed JSON: {e}")))?;
    Ok(value)
}
