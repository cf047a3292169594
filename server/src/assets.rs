//! The browser page and its vendored libraries, embedded in the binary (rust-embed; with
//! `debug-embed`, debug builds serve the same bytes as release builds), and the Content
//! Security Policy that lets exactly them run.

use std::sync::OnceLock;

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
        Some(file) => respond(path, file.data.into_owned(), cache),
        None => ApiError::not_found(format!("no such file: {path}")).into_response(),
    }
}

/// `body` as `path`'s type (by its extension), with the given `Cache-Control`.
fn respond(path: &str, body: Vec<u8>, cache: &'static str) -> Response {
    let mime = mime_guess::from_path(path).first_or_octet_stream();
    let mut resp = (StatusCode::OK, body).into_response();
    let headers = resp.headers_mut();
    if let Ok(v) = HeaderValue::from_str(mime.as_ref()) {
        headers.insert(header::CONTENT_TYPE, v);
    }
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static(cache));
    resp
}

/// The line in a page's `<head>` that stands for the head every page shares
/// (`web/head.html`: charset, viewport, stylesheets, the import map, the modules every page
/// preloads); each page keeps only its title and its own preloads.
const SHARED_HEAD: &str = "<!--#include head.html-->";

/// A page (`web/NAME.html`) as served: its [`SHARED_HEAD`] line replaced by `web/head.html`.
fn page_html(name: &str) -> Option<String> {
    let page = Web::get(name)?;
    let head = Web::get("head.html")?;
    let head = String::from_utf8_lossy(&head.data);
    Some(String::from_utf8_lossy(&page.data).replacen(SHARED_HEAD, head.trim_end(), 1))
}

/// A page with the shared head in place, revalidated on every load.
fn page(name: &str) -> Response {
    match page_html(name) {
        Some(html) => respond(name, html.into_bytes(), "no-cache"),
        None => ApiError::not_found(format!("no such page: {name}")).into_response(),
    }
}

/// `GET /`: the trainee page.
pub async fn index() -> Response {
    page("index.html")
}

/// `GET /instructor`: the instructor dashboard.
pub async fn instructor() -> Response {
    page("instructor.html")
}

/// `GET /replay/{attempt}`: the debrief page (it reads the attempt id from its URL).
pub async fn replay(Path(_attempt): Path<String>) -> Response {
    page("replay.html")
}

/// `GET /logbook?trainee=&group=`: a trainee's printable logbook (it reads the trainee from
/// its URL; the instructor's sign-in cookie opens the data).
pub async fn logbook() -> Response {
    page("logbook.html")
}

/// `GET /web/{*path}`: our own modules; revalidated on every load so a new build is seen at once.
pub async fn web(Path(path): Path<String>) -> Response {
    serve::<Web>(&path, "no-cache")
}

/// `GET /static/{*path}`: vendored packages, immutable for a given binary.
pub async fn vendored(Path(path): Path<String>) -> Response {
    serve::<Static>(&path, "public, max-age=86400")
}

/// The pages' inline import maps (`<script type="importmap">…</script>`): the only inline
/// scripts; a browser cannot load an import map from a file, so the policy allows each by
/// its SHA-256 (CSP Level 3 hash source).
fn inline_importmap_hashes() -> Vec<String> {
    use base64::Engine as _;
    use sha2::{Digest, Sha256};
    const OPEN: &str = "<script type=\"importmap\">";
    let mut hashes: Vec<String> = Vec::new();
    for name in Web::iter().filter(|n| n.ends_with(".html")) {
        let Some(file) = Web::get(&name) else {
            continue;
        };
        let html = String::from_utf8_lossy(&file.data);
        let mut rest: &str = &html;
        while let Some(start) = rest.find(OPEN) {
            let body = &rest[start + OPEN.len()..];
            let Some(end) = body.find("</script>") else {
                break;
            };
            let digest = Sha256::digest(&body.as_bytes()[..end]);
            let h = format!(
                "'sha256-{}'",
                base64::engine::general_purpose::STANDARD.encode(digest)
            );
            if !hashes.contains(&h) {
                hashes.push(h);
            }
            rest = &body[end..];
        }
    }
    hashes
}

/// The Content-Security-Policy of every response: everything from this server only, no
/// inline script but the hashed import maps, no inline `<style>` or `style=""` attributes,
/// WebSockets to any host (the page's socket goes to the server it came from; `'self'` does
/// not cover `ws:` in every browser), no framing, no plugins.
pub fn content_security_policy() -> &'static str {
    static CSP: OnceLock<String> = OnceLock::new();
    CSP.get_or_init(|| {
        let mut script_src = String::from("'self'");
        for h in inline_importmap_hashes() {
            script_src.push(' ');
            script_src.push_str(&h);
        }
        format!(
            "default-src 'self'; script-src {script_src}; style-src 'self'; \
             img-src 'self' data: blob:; connect-src 'self' ws: wss:; object-src 'none'; \
             base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The policy hashes the import map the pages really carry: recomputed here from the
    /// page text with an independent SHA-256 (FIPS 180-4 test vector first, so the hash
    /// itself is right).
    #[test]
    fn the_policy_allows_the_pages_import_map_and_nothing_else_inline() {
        use base64::Engine as _;
        use sha2::{Digest, Sha256};
        // FIPS 180-4 / NIST example: SHA-256("abc").
        let hex: String = Sha256::digest(b"abc")
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(
            hex,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        let csp = content_security_policy();
        let index = page_html("index.html").unwrap();
        let map = index
            .split("<script type=\"importmap\">")
            .nth(1)
            .unwrap()
            .split("</script>")
            .next()
            .unwrap();
        let want = base64::engine::general_purpose::STANDARD.encode(Sha256::digest(map));
        assert!(csp.contains(&format!("'sha256-{want}'")), "{csp}");
        assert!(!csp.contains("unsafe-inline") && !csp.contains("unsafe-eval"));
        assert!(csp.contains("frame-ancestors 'none'"));
        // No page has another inline script or an inline style element.
        for name in Web::iter().filter(|n| n.ends_with(".html")) {
            let html = String::from_utf8(Web::get(&name).unwrap().data.into_owned()).unwrap();
            let scripts = html.matches("<script").count();
            let external = html.matches("<script type=\"module\" src=").count();
            let maps = html.matches("<script type=\"importmap\">").count();
            assert_eq!(scripts, external + maps, "{name} has an inline script");
            assert!(!html.contains("<style"), "{name} has an inline <style>");
            assert!(!html.contains("style=\""), "{name} has a style attribute");
        }
    }

    /// The head every page shares is written once (`web/head.html`) and served inside each
    /// page: no page file carries its own import map or charset, each served page has exactly
    /// one of each (the charset within the first 1024 bytes, where the HTML standard's encoding
    /// sniffing looks), the whole shared head, and its own title.
    #[test]
    fn every_page_is_served_with_the_one_shared_head() {
        let head = String::from_utf8(Web::get("head.html").unwrap().data.into_owned()).unwrap();
        for (name, title) in [
            ("index.html", "trainee"),
            ("instructor.html", "instructor"),
            ("replay.html", "debrief"),
            ("logbook.html", "logbook"),
        ] {
            let raw = String::from_utf8(Web::get(name).unwrap().data.into_owned()).unwrap();
            assert!(
                !raw.contains("<script type=\"importmap\">"),
                "{name} has its own import map"
            );
            assert!(!raw.contains("<meta charset"), "{name} has its own charset");
            assert_eq!(raw.matches(SHARED_HEAD).count(), 1, "{name}");
            let served = page_html(name).unwrap();
            assert!(!served.contains(SHARED_HEAD), "{name}");
            assert!(
                served.contains(head.trim_end()),
                "{name} lacks the shared head"
            );
            assert_eq!(
                served.matches("<script type=\"importmap\">").count(),
                1,
                "{name}"
            );
            assert_eq!(served.matches("<meta charset=").count(), 1, "{name}");
            assert!(
                served.find("<meta charset=\"utf-8\">").unwrap() < 1024,
                "{name}"
            );
            assert!(
                served.contains(&format!("<title>seaarms — {title}</title>")),
                "{name}"
            );
        }
    }
}
