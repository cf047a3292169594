//! Browser security, applied to every request by one middleware ([`guard`]):
//!
//! * state-changing requests (POST, PUT, PATCH, DELETE) and WebSocket upgrades that carry an
//!   `Origin` must come from the served host itself, the configured public URL or an
//!   allowed origin (403 otherwise) — a cross-site page can neither create sessions nor open
//!   sockets;
//! * a request body must be `application/json` (415 otherwise), so no "simple" cross-site
//!   form or `text/plain` request reaches a handler;
//! * every response carries `Content-Security-Policy`, `X-Content-Type-Options: nosniff`,
//!   `X-Frame-Options: DENY` and `Referrer-Policy: no-referrer`;
//! * every error response has a JSON body (axum's own rejections, 404/405/413 included).
//!
//! Also here: the `Host` syntax check and the public base URL from which `ws_url` is built.

use std::net::IpAddr;

use axum::body::Body;
use axum::extract::{ConnectInfo, Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::app::AppState;
use crate::error::ApiError;

/// Largest error body rewritten into JSON (axum's rejection texts are a few hundred bytes).
const MAX_ERROR_BODY_BYTES: usize = 16 * 1024;

/// `scheme`, lower-case host and port of an origin or URL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Origin {
    /// `http` or `https`.
    pub scheme: String,
    /// Host, lower-case (IPv6 literals keep their brackets).
    pub host: String,
    /// Port (the scheme's default when absent).
    pub port: u16,
}

fn default_port(scheme: &str) -> u16 {
    if scheme == "https" { 443 } else { 80 }
}

impl Origin {
    /// Parses `http[s]://host[:port]` (a trailing `/` is tolerated, nothing else after it).
    pub fn parse(text: &str) -> Option<Origin> {
        let (scheme, rest) = text.split_once("://")?;
        let scheme = scheme.to_ascii_lowercase();
        if scheme != "http" && scheme != "https" {
            return None;
        }
        let authority = rest.strip_suffix('/').unwrap_or(rest);
        let (host, port) = split_host(authority)?;
        Some(Origin {
            port: port.unwrap_or_else(|| default_port(&scheme)),
            scheme,
            host,
        })
    }

    /// `host[:port]`, the port omitted when it is the scheme's default.
    pub fn authority(&self) -> String {
        if self.port == default_port(&self.scheme) {
            self.host.clone()
        } else {
            format!("{}:{}", self.host, self.port)
        }
    }

    /// The WebSocket scheme for this origin's scheme.
    pub fn ws_scheme(&self) -> &'static str {
        if self.scheme == "https" { "wss" } else { "ws" }
    }
}

/// Splits and checks `host[:port]`: a DNS name or IPv4 address (letters, digits, `-`, `.`,
/// `_`; at most 253 characters) or a bracketed IPv6 literal, and an optional port 1–65535.
/// Returns the lower-case host and the port.
pub fn split_host(authority: &str) -> Option<(String, Option<u16>)> {
    let (host, port) = if let Some(rest) = authority.strip_prefix('[') {
        let (v6, after) = rest.split_once(']')?;
        v6.parse::<std::net::Ipv6Addr>().ok()?;
        let port = match after {
            "" => None,
            p => Some(p.strip_prefix(':')?),
        };
        (format!("[{}]", v6.to_ascii_lowercase()), port)
    } else {
        let (host, port) = match authority.split_once(':') {
            Some((h, p)) => (h, Some(p)),
            None => (authority, None),
        };
        let ok = !host.is_empty()
            && host.len() <= 253
            && host
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_'));
        if !ok {
            return None;
        }
        (host.to_ascii_lowercase(), port)
    };
    let port = match port {
        None => None,
        Some(p) if !p.is_empty() && p.len() <= 5 && p.bytes().all(|b| b.is_ascii_digit()) => {
            Some(p.parse::<u16>().ok().filter(|p| *p != 0)?)
        }
        Some(_) => return None,
    };
    Some((host, port))
}

/// Origin policy and forwarding trust, from the configuration.
#[derive(Debug, Clone, Default)]
pub struct Policy {
    /// Public base URL, when configured.
    pub public_url: Option<Origin>,
    /// Further allowed origins.
    pub allowed_origins: Vec<Origin>,
    /// Proxies whose `X-Forwarded-*` headers are believed.
    pub trusted_proxies: Vec<IpAddr>,
    /// Host names a request's `Host` may name ([`Policy::with_hosts`]); `None`: any.
    pub allowed_hosts: Option<Vec<String>>,
}

impl Policy {
    /// Builds the policy; a malformed public URL or allowed origin is a start-up error.
    pub fn new(
        public_url: Option<&str>,
        allowed_origins: &[String],
        trusted_proxies: &[IpAddr],
    ) -> anyhow::Result<Policy> {
        let public_url = match public_url.filter(|u| !u.is_empty()) {
            Some(u) => Some(Origin::parse(u).ok_or_else(|| {
                anyhow::anyhow!("--public-url `{u}` is not http[s]://host[:port]")
            })?),
            None => None,
        };
        let allowed_origins = allowed_origins
            .iter()
            .filter(|o| !o.is_empty())
            .map(|o| {
                Origin::parse(o).ok_or_else(|| {
                    anyhow::anyhow!("--allowed-origins entry `{o}` is not http[s]://host[:port]")
                })
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(Policy {
            public_url,
            allowed_origins,
            trusted_proxies: trusted_proxies.to_vec(),
            allowed_hosts: None,
        })
    }

    /// The host names requests may name in `Host` (DNS rebinding: a page on `evil.example`,
    /// re-pointed at this machine, sends `Host: evil.example`). `allowed` (`--allowed-hosts`)
    /// when given (`*` allows any); else, for a server bound to one address, that address,
    /// the loopback names when it is a loopback one, and the hosts of the public URL and the
    /// allowed origins; a server bound to every interface (`0.0.0.0`, `::`, a container)
    /// cannot know its names and allows any unless told.
    pub fn with_hosts(mut self, allowed: &[String], bind: std::net::SocketAddr) -> Policy {
        let allowed: Vec<String> = allowed
            .iter()
            .map(|h| h.trim().to_ascii_lowercase())
            .filter(|h| !h.is_empty())
            .collect();
        self.allowed_hosts = if allowed.iter().any(|h| h == "*") {
            None
        } else if !allowed.is_empty() {
            Some(allowed)
        } else if bind.ip().is_unspecified() {
            None
        } else {
            let ip = match bind.ip() {
                IpAddr::V6(v6) => format!("[{v6}]"),
                v4 => v4.to_string(),
            };
            let mut hosts = vec![ip];
            if bind.ip().is_loopback() {
                hosts.extend(["localhost", "127.0.0.1", "[::1]"].map(String::from));
            }
            hosts.extend(self.public_url.iter().map(|o| o.host.clone()));
            hosts.extend(self.allowed_origins.iter().map(|o| o.host.clone()));
            Some(hosts)
        };
        self
    }

    /// Whether a request with `Host: host` is for this server (a request without one cannot
    /// be a rebound page's).
    pub fn host_allowed(&self, host: Option<&str>) -> bool {
        let (Some(hosts), Some(host)) = (&self.allowed_hosts, host) else {
            return true;
        };
        split_host(host).is_some_and(|(h, _)| hosts.contains(&h))
    }

    /// Whether a request with `Origin: origin` to `host` (its Host header) may change state:
    /// the origin names the served host itself (same host and port), the public URL, or an
    /// allowed origin. `null` and malformed origins never may.
    pub fn origin_allowed(&self, origin: &str, host: Option<&str>) -> bool {
        let Some(o) = Origin::parse(origin) else {
            return false;
        };
        if self.public_url.as_ref() == Some(&o) || self.allowed_origins.contains(&o) {
            return true;
        }
        let Some((h, port)) = host.and_then(split_host) else {
            return false;
        };
        h == o.host && port.unwrap_or_else(|| default_port(&o.scheme)) == o.port
    }

    /// Whether the request came through a trusted proxy.
    pub fn via_trusted_proxy(&self, peer: Option<&ConnectInfo<std::net::SocketAddr>>) -> bool {
        peer.is_some_and(|c| self.trusted_proxies.contains(&c.0.ip()))
    }
}

/// The base (`ws[s]://authority`) of WebSocket URLs handed to clients: the public URL when
/// configured, else the request's Host after the syntax check (wss when a trusted proxy says
/// `X-Forwarded-Proto: https`). `None` for a missing or malformed Host.
pub fn ws_base(
    policy: &Policy,
    headers: &HeaderMap,
    peer: Option<&ConnectInfo<std::net::SocketAddr>>,
) -> Option<String> {
    if let Some(u) = &policy.public_url {
        return Some(format!("{}://{}", u.ws_scheme(), u.authority()));
    }
    let host = headers.get(header::HOST)?.to_str().ok()?;
    let (h, port) = split_host(host)?;
    let https = policy.via_trusted_proxy(peer)
        && headers
            .get("x-forwarded-proto")
            .and_then(|v| v.to_str().ok())
            .is_some_and(|p| p.eq_ignore_ascii_case("https"));
    let scheme = if https { "wss" } else { "ws" };
    Some(match port {
        Some(p) => format!("{scheme}://{h}:{p}"),
        None => format!("{scheme}://{h}"),
    })
}

fn forbidden(msg: impl Into<String>) -> Response {
    ApiError {
        status: StatusCode::FORBIDDEN,
        error: msg.into(),
        detail: None,
    }
    .into_response()
}

fn has_body(headers: &HeaderMap) -> bool {
    headers.contains_key(header::TRANSFER_ENCODING)
        || headers
            .get(header::CONTENT_LENGTH)
            .and_then(|v| v.to_str().ok())
            .is_some_and(|v| v.trim() != "0")
}

fn is_json(headers: &HeaderMap) -> bool {
    headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.split(';').next())
        .is_some_and(|essence| essence.trim().eq_ignore_ascii_case("application/json"))
}

fn is_websocket_upgrade(headers: &HeaderMap) -> bool {
    headers
        .get(header::UPGRADE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.eq_ignore_ascii_case("websocket"))
}

/// The response headers every answer carries.
pub(crate) fn add_security_headers(headers: &mut HeaderMap) {
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(crate::assets::content_security_policy()),
    );
    headers.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    headers.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    headers.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
}

/// Rewrites a non-JSON error response (axum's extractor rejections, body-limit 413s, …)
/// into the API's JSON error, keeping its status and message.
async fn json_error(resp: Response) -> Response {
    let status = resp.status();
    let (parts, body) = resp.into_parts();
    let text = axum::body::to_bytes(body, MAX_ERROR_BODY_BYTES)
        .await
        .map(|b| String::from_utf8_lossy(&b).trim().to_string())
        .unwrap_or_default();
    let error = if status == StatusCode::PAYLOAD_TOO_LARGE {
        crate::json::body_too_large_message()
    } else if text.is_empty() {
        status
            .canonical_reason()
            .unwrap_or("request failed")
            .to_lowercase()
    } else {
        text
    };
    let mut out = ApiError {
        status,
        error,
        detail: None,
    }
    .into_response();
    // Keep headers such as `Allow` (405) and `Retry-After`; the body's own headers go.
    for (name, value) in &parts.headers {
        if name != header::CONTENT_TYPE && name != header::CONTENT_LENGTH {
            out.headers_mut().insert(name.clone(), value.clone());
        }
    }
    out
}

/// The security middleware (see the module docs).
pub async fn guard(State(state): State<AppState>, req: Request<Body>, next: Next) -> Response {
    let headers = req.headers();
    let host = headers.get(header::HOST).map(|h| h.to_str().unwrap_or(""));
    if !state.policy.host_allowed(host) {
        // The name only once it has passed the syntax check: a Host is never echoed raw.
        let mut resp = match host.and_then(split_host) {
            Some((h, _)) => ApiError::new(
                StatusCode::MISDIRECTED_REQUEST,
                format!("this server does not answer for Host `{h}` (--allowed-hosts)"),
            ),
            None => ApiError::new(StatusCode::BAD_REQUEST, "malformed Host header"),
        }
        .into_response();
        add_security_headers(resp.headers_mut());
        return resp;
    }
    let changes_state = matches!(
        *req.method(),
        Method::POST | Method::PUT | Method::PATCH | Method::DELETE
    );
    let mut resp = if let Some(origin) = headers
        .get(header::ORIGIN)
        .filter(|_| changes_state || is_websocket_upgrade(headers))
    {
        let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
        match origin.to_str() {
            Ok(o) if state.policy.origin_allowed(o, host) => None,
            Ok(o) => Some(forbidden(format!(
                "origin `{o}` may not use this server (allowed: the served host itself, or --allowed-origins)"
            ))),
            Err(_) => Some(forbidden("malformed Origin header")),
        }
    } else {
        None
    };
    if resp.is_none() && changes_state && has_body(headers) && !is_json(headers) {
        resp = Some(
            ApiError {
                status: StatusCode::UNSUPPORTED_MEDIA_TYPE,
                error: "request bodies must be JSON (Content-Type: application/json)".into(),
                detail: None,
            }
            .into_response(),
        );
    }
    let mut resp = match resp {
        Some(r) => r,
        None => next.run(req).await,
    };
    let is_json_body = resp
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    if (resp.status().is_client_error() || resp.status().is_server_error()) && !is_json_body {
        resp = json_error(resp).await;
    }
    add_security_headers(resp.headers_mut());
    resp
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn host_syntax() {
        assert_eq!(
            split_host("Example.org:8080"),
            Some(("example.org".into(), Some(8080)))
        );
        assert_eq!(split_host("127.0.0.1"), Some(("127.0.0.1".into(), None)));
        assert_eq!(split_host("[::1]:9"), Some(("[::1]".into(), Some(9))));
        for bad in [
            "",
            "evil.com/x",
            "a b",
            "host:",
            "host:99999",
            "host:0",
            "host:8080:1",
            "[::1",
            "[nope]:80",
            "user@host",
            "host\"><script>",
        ] {
            assert_eq!(split_host(bad), None, "{bad}");
        }
    }

    #[test]
    fn origins_match_the_served_host_or_the_allow_list() {
        let p = Policy::new(None, &["https://proxy.example.org".into()], &[]).unwrap();
        assert!(p.origin_allowed("http://127.0.0.1:8080", Some("127.0.0.1:8080")));
        assert!(p.origin_allowed("http://LOCALHOST", Some("localhost:80")));
        assert!(p.origin_allowed("https://sim.example.org", Some("sim.example.org")));
        assert!(!p.origin_allowed("http://127.0.0.1:8081", Some("127.0.0.1:8080")));
        assert!(!p.origin_allowed("https://evil.example", Some("127.0.0.1:8080")));
        assert!(!p.origin_allowed("null", Some("127.0.0.1:8080")));
        assert!(!p.origin_allowed("http://127.0.0.1:8080", None));
        assert!(p.origin_allowed("https://proxy.example.org", Some("10.0.0.5:8080")));
        assert!(p.origin_allowed("https://proxy.example.org:443/", Some("x")));
        assert!(!p.origin_allowed("http://proxy.example.org", Some("x")));
        assert!(Policy::new(Some("ftp://x"), &[], &[]).is_err());
        assert!(Policy::new(None, &["not an origin".into()], &[]).is_err());
    }

    #[test]
    fn ws_base_never_echoes_a_malformed_host() {
        let p = Policy::default();
        let mut h = HeaderMap::new();
        h.insert(header::HOST, "evil.com/x?".parse().unwrap());
        assert_eq!(ws_base(&p, &h, None), None);
        h.insert(header::HOST, "Sim.Example.org:8443".parse().unwrap());
        h.insert("x-forwarded-proto", "https".parse().unwrap());
        // X-Forwarded-Proto from an untrusted peer is ignored.
        assert_eq!(
            ws_base(&p, &h, None).as_deref(),
            Some("ws://sim.example.org:8443")
        );
        let p = Policy::new(Some("https://sim.example.org/"), &[], &[]).unwrap();
        assert_eq!(
            ws_base(&p, &h, None).as_deref(),
            Some("wss://sim.example.org")
        );
    }
}
