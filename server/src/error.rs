//! The HTTP error type: every failure becomes a status and a JSON body
//! `{"error": "...", "detail": ...}`.

use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::json;

/// An API error with its status.
#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    /// HTTP status.
    pub status: StatusCode,
    /// Human-readable message.
    pub error: String,
    /// Optional machine-readable detail.
    pub detail: Option<serde_json::Value>,
}

impl ApiError {
    /// Any status with a message.
    pub fn new(status: StatusCode, error: impl Into<String>) -> ApiError {
        ApiError {
            status,
            error: error.into(),
            detail: None,
        }
    }
    /// 403 with a message (a missing or wrong token).
    pub fn forbidden(error: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::FORBIDDEN, error)
    }
    /// 400 with a message.
    pub fn bad_request(error: impl Into<String>) -> ApiError {
        ApiError {
            status: StatusCode::BAD_REQUEST,
            error: error.into(),
            detail: None,
        }
    }
    /// 404 with a message.
    pub fn not_found(error: impl Into<String>) -> ApiError {
        ApiError {
            status: StatusCode::NOT_FOUND,
            error: error.into(),
            detail: None,
        }
    }
    /// 422 with a message.
    pub fn unprocessable(error: impl Into<String>) -> ApiError {
        ApiError {
            status: StatusCode::UNPROCESSABLE_ENTITY,
            error: error.into(),
            detail: None,
        }
    }
    /// Adds a detail value.
    pub fn with_detail(mut self, detail: serde_json::Value) -> ApiError {
        self.detail = Some(detail);
        self
    }
}

impl From<seaarms_core::Error> for ApiError {
    fn from(e: seaarms_core::Error) -> ApiError {
        use seaarms_core::Error as E;
        let status = match &e {
            E::NotConverged { .. } | E::Unreachable { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            _ => StatusCode::BAD_REQUEST,
        };
        ApiError {
            status,
            error: e.to_string(),
            detail: None,
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = match self.detail {
            Some(d) => json!({ "error": self.error, "detail": d }),
            None => json!({ "error": self.error }),
        };
        (self.status, Json(body)).into_response()
    }
}
