//! The browser page and its vendored libraries, embedded in the binary (rust-embed; with
//! `debug-embed`, debug builds serve the same bytes as release builds).

use axum::extract::Path;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use rust_embed::RustEmbed;

use crate::error::ApiError;

/// Front-end ES modules and pages (`web/`), served at `/` and `/web/…`.
#[derive(RustEmbed)]
#[folder = "web/"]
pub struct Web;

/// Vendored third-party files (`static/`), served at `/static/…`.
#[derive(RustEmbed)]
#[folder = "static/"]
pub struct Static;

fn serve<E: RustEmbed>(path: &str, cache: &'static str) -> Response {
    match E::get(path) {
        Some(file) => {
            let mime = mime_guess::from_path(path).first_or_octet_stream();
            let mut resp = (StatusCode::OK, file.data.into_owned()).into_response();
            let headers = resp.headers_mut();
            if let Ok(v) = HeaderValue::from_str(mime.as_ref()) {
                headers.insert(header::CONTENT_TYPE, v);
            }
            headers.insert(header::CACHE_CONTROL, HeaderValue::from_static(cache));
            resp
        }
        None => ApiError::not_found(format!("no such file: {path}")).into_response(),
    }
}

/// `GET /`: the trainee page.
pub async fn index() -> Response {
    serve::<Web>("index.html", "no-cache")
}

/// `GET /instructor`: the instructor dashboard.
pub async fn instructor() -> Response {
    serve::<Web>("instructor.html", "no-cache")
}

/// `GET /web/{*path}`: our own modules; revalidated on every load so a new build is seen at once.
pub async fn web(Path(path): Path<String>) -> Response {
    serve::<Web>(&path, "no-cache")
}

/// `GET /static/{*path}`: vendored packages, immutable for a given binary.
pub async fn vendored(Path(path): Path<String>) -> Response {
    serve::<Static>(&path, "public, max-age=86400")
}
