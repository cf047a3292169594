//! Property-based fuzzing (proptest) of every REST request body and every WebSocket client
//! message of the server, against a real server on a real socket (issue 13 item 7).
//!
//! Properties, checked after every generated case:
//! * no 5xx, except the ones `/api/openapi.json` documents for that route (503 of a full
//!   server on `POST /api/sessions`);
//! * every error answer (4xx) is `application/json` with a string `error` field;
//! * the server stays up: `/healthz` answers `ok` after every case;
//! * the browser-security contract of `security.rs`: a foreign or `null` `Origin` on a
//!   state-changing request is 403, a non-JSON body is 415, a body over 64 KiB is 413;
//! * over-limit shapes (huge arrays, huge counts) are refused with a 4xx;
//! * a live session keeps streaming `state` frames with increasing `seq` and finite values
//!   after any REST action or WebSocket message (malformed JSON, wrong types and lengths,
//!   numbers like `1e999`, unknown types, binary frames); a message over 16 KiB closes that
//!   connection with 1009 and the session streams on.
//!
//! Generators are structure-aware (each route's valid shape, then mutated: odd numbers as
//! JSON text, wrong types, wrong-length arrays, missing and extra fields, unicode, deep
//! nesting) and raw (bytes, corrupted valid bodies). Case counts keep the file within a
//! couple of minutes on two cores; every test has its own server.

#![allow(clippy::unwrap_used)]

use std::time::Duration;

use futures_util::SinkExt;
use proptest::collection::vec;
use proptest::option;
use proptest::prelude::*;
use proptest::sample::select;
use proptest::test_runner::TestCaseError;
use tokio_tungstenite::tungstenite::Message;

mod common;
use common::{Reply, SyncServer, TEACHER, Ws, keeps_streaming, send_request};

/// Largest REST body (server/src/json.rs `MAX_BODY_BYTES`).
const MAX_BODY_BYTES: usize = 64 * 1024;
/// Largest WebSocket client message (server/src/protocol.rs `MAX_CLIENT_MESSAGE_BYTES`).
const MAX_WS_MESSAGE_BYTES: usize = 16 * 1024;
/// Largest study (server/core/src/studies.rs `MAX_ROWS`, `MAX_CELLS`).
const MAX_STUDY_ROWS: usize = 100_000;
const MAX_MAP_CELLS: usize = 250_000;

const ROBOTS: &[&str] = &["magnum", "orion", "rx90", "puma560", "pa10", "planar2r"];
const STUDIES: &[&str] = &[
    "single-x",
    "single-z",
    "single-pitch-yaw",
    "dual-x",
    "dual-pitch-yaw",
    "dual-distance",
    "workspace-map",
];
const SCENARIOS: &[&str] = &[
    "case1-single-arm",
    "case2-single-arm-load",
    "case3-dual-open-loop",
    "case4-dual-closed-loop",
];
const LIVE_SCENARIOS: &[&str] = &[
    "training",
    "case1-single-arm",
    "case2-single-arm-load",
    "case3-dual-open-loop",
    "case4-dual-closed-loop",
];

/// `cases` per test, times `SEAARMS_FUZZ_SCALE` when set (a longer local or nightly run:
/// `SEAARMS_FUZZ_SCALE=20 cargo test --test fuzz`).
fn config(cases: u32) -> ProptestConfig {
    let scale = std::env::var("SEAARMS_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse::<u32>().ok())
        .unwrap_or(1)
        .max(1);
    ProptestConfig {
        cases: cases.saturating_mul(scale),
        max_shrink_iters: 64,
        ..ProptestConfig::default()
    }
}

// ---------------------------------------------------------------------------------------
// JSON text with room for invalid tokens, and its mutations
// ---------------------------------------------------------------------------------------

/// JSON as text: `Raw` holds any token (also invalid ones such as `NaN` or `1e999`).
#[derive(Debug, Clone)]
enum J {
    Raw(String),
    Str(String),
    Arr(Vec<J>),
    Obj(Vec<(String, J)>),
}

impl J {
    fn text(&self) -> String {
        let mut s = String::new();
        self.write(&mut s);
        s
    }

    fn write(&self, out: &mut String) {
        match self {
            J::Raw(r) => out.push_str(r),
            J::Str(s) => out.push_str(&serde_json::to_string(s).unwrap()),
            J::Arr(v) => {
                out.push('[');
                for (i, x) in v.iter().enumerate() {
                    if i > 0 {
                        out.push(',');
                    }
                    x.write(out);
                }
                out.push(']');
            }
            J::Obj(kv) => {
                out.push('{');
                for (i, (k, x)) in kv.iter().enumerate() {
                    if i > 0 {
                        out.push(',');
                    }
                    out.push_str(&serde_json::to_string(k).unwrap());
                    out.push(':');
                    x.write(out);
                }
                out.push('}');
            }
        }
    }

    fn count(&self) -> usize {
        1 + match self {
            J::Arr(v) => v.iter().map(J::count).sum(),
            J::Obj(kv) => kv.iter().map(|(_, x)| x.count()).sum(),
            _ => 0,
        }
    }
}

fn num(v: f64) -> J {
    J::Raw(format!("{v:?}"))
}

fn s(text: &str) -> J {
    J::Str(text.to_string())
}

fn nums(v: &[f64]) -> J {
    J::Arr(v.iter().copied().map(num).collect())
}

/// An object from fields, absent ones (`None`) left out.
fn obj(fields: Vec<(&str, Option<J>)>) -> J {
    J::Obj(
        fields
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k.to_string(), v)))
            .collect(),
    )
}

/// Number tokens and values that break parsers and ranges: non-finite spellings, overflow,
/// u64/i64/2⁵³ edges, subnormals, invalid JSON number syntax, wrong types.
const ODD_TOKENS: &[&str] = &[
    "0",
    "-0",
    "1e999",
    "-1e999",
    "1e308",
    "-1.7976931348623157e308",
    "5e-324",
    "1e-400",
    "NaN",
    "-NaN",
    "Infinity",
    "-Infinity",
    "inf",
    "null",
    "true",
    "false",
    "18446744073709551616",
    "18446744073709551615",
    "-9223372036854775809",
    "9007199254740993",
    "4294967297",
    "-1",
    "0.5",
    "1",
    "2",
    "3",
    "6",
    "7",
    "32",
    "33",
    "64",
    "65",
    "100000",
    "1e6",
    "1e9",
    "01",
    "1.",
    "+1",
    ".5",
    "0x10",
    "\"1\"",
    "\"NaN\"",
    "[]",
    "{}",
    "\"\"",
];

/// A replacement value: odd tokens, any float or integer, unicode strings, number arrays,
/// deep nesting (arrays and objects, past serde_json's recursion limit), long strings.
fn weird() -> BoxedStrategy<J> {
    prop_oneof![
        6 => select(ODD_TOKENS).prop_map(|t| J::Raw(t.to_string())),
        2 => any::<f64>().prop_map(|v| if v.is_finite() { num(v) } else { J::Raw("-1e999".into()) }),
        1 => any::<i64>().prop_map(|i| J::Raw(i.to_string())),
        2 => "\\PC{0,24}".prop_map(J::Str),
        1 => ".{0,8}".prop_map(J::Str),
        1 => vec(select(ODD_TOKENS).prop_map(|t| J::Raw(t.to_string())), 0..12).prop_map(J::Arr),
        1 => (1usize..400).prop_map(|d| J::Raw(format!("{}{}", "[".repeat(d), "]".repeat(d)))),
        1 => (1usize..400).prop_map(|d| J::Raw(format!("{}1{}", "{\"a\":".repeat(d), "}".repeat(d)))),
        1 => (1usize..20_000).prop_map(|len| J::Str("é".repeat(len))),
    ]
    .boxed()
}

fn key() -> BoxedStrategy<String> {
    prop_oneof![
        select(
            &[
                "type",
                "robot",
                "q",
                "rows",
                "polytope",
                "arms",
                "base",
                "seq",
                "axes",
                "grip",
                "object",
                "value",
                "joint",
                "x",
                "",
                "__proto__",
            ][..]
        )
        .prop_map(str::to_string),
        "\\PC{0,12}",
    ]
    .boxed()
}

/// One structural change at a node chosen by index (pre-order, modulo the node count).
#[derive(Debug, Clone)]
enum Mutation {
    Replace(usize, J),
    Remove(usize, usize),
    Add(usize, String, J),
    Nest(usize, usize),
    Resize(usize, usize),
}

fn mutation() -> BoxedStrategy<Mutation> {
    prop_oneof![
        4 => (any::<usize>(), weird()).prop_map(|(at, j)| Mutation::Replace(at, j)),
        2 => (any::<usize>(), any::<usize>()).prop_map(|(at, k)| Mutation::Remove(at, k)),
        2 => (any::<usize>(), key(), weird()).prop_map(|(at, k, j)| Mutation::Add(at, k, j)),
        1 => (any::<usize>(), 1usize..200).prop_map(|(at, d)| Mutation::Nest(at, d)),
        2 => (any::<usize>(), prop_oneof![0usize..10, 10usize..3000])
            .prop_map(|(at, n)| Mutation::Resize(at, n)),
    ]
    .boxed()
}

fn visit(node: &mut J, target: usize, i: &mut usize, f: &mut dyn FnMut(&mut J)) -> bool {
    if *i == target {
        f(node);
        return true;
    }
    *i += 1;
    match node {
        J::Arr(v) => v.iter_mut().any(|c| visit(c, target, i, f)),
        J::Obj(kv) => kv.iter_mut().any(|(_, c)| visit(c, target, i, f)),
        _ => false,
    }
}

fn mutate(root: &mut J, m: &Mutation) {
    let at = match m {
        Mutation::Replace(a, _)
        | Mutation::Remove(a, _)
        | Mutation::Add(a, _, _)
        | Mutation::Nest(a, _)
        | Mutation::Resize(a, _) => *a,
    } % root.count();
    visit(root, at, &mut 0, &mut |node| match m {
        Mutation::Replace(_, j) => *node = j.clone(),
        Mutation::Remove(_, k) => match node {
            J::Arr(v) if !v.is_empty() => {
                let k = k % v.len();
                v.remove(k);
            }
            J::Obj(kv) if !kv.is_empty() => {
                let k = k % kv.len();
                kv.remove(k);
            }
            _ => *node = J::Raw("null".into()),
        },
        Mutation::Add(_, k, j) => match node {
            J::Arr(v) => v.push(j.clone()),
            J::Obj(kv) => kv.push((k.clone(), j.clone())),
            other => *other = J::Arr(vec![other.clone(), j.clone()]),
        },
        Mutation::Nest(_, d) => {
            for _ in 0..*d {
                *node = J::Arr(vec![node.clone()]);
            }
        }
        Mutation::Resize(_, n) => match node {
            J::Arr(v) => {
                let fill = v.last().cloned().unwrap_or_else(|| num(0.25));
                v.resize(*n, fill);
            }
            other => *other = J::Arr(vec![other.clone(); (*n).min(64)]),
        },
    });
}

/// Largest body sent: 3 × the limit. A larger one would still be refused with 413, but the
/// server closes the connection without reading the rest, so the client may fail writing
/// it before it reads the answer (a transport matter, not a property of the server).
const MAX_SENT_BODY_BYTES: usize = 3 * MAX_BODY_BYTES;

/// Request bodies from a route's valid shape: mutated (most), byte-corrupted or truncated,
/// raw bytes, a bare odd value, or padded past 64 KiB (each cut at [`MAX_SENT_BODY_BYTES`]).
fn bodies(valid: BoxedStrategy<J>) -> BoxedStrategy<Vec<u8>> {
    let any_body = prop_oneof![
        4 => valid.clone().prop_map(|j| j.text().into_bytes()),
        6 => (valid.clone(), vec(mutation(), 1..4)).prop_map(|(mut j, ms)| {
            for m in &ms {
                mutate(&mut j, m);
            }
            j.text().into_bytes()
        }),
        1 => (valid.clone(), vec((any::<usize>(), any::<u8>()), 1..4), any::<Option<usize>>())
            .prop_map(|(j, flips, cut)| {
                let mut b = j.text().into_bytes();
                for (at, byte) in flips {
                    if !b.is_empty() {
                        let at = at % b.len();
                        b[at] = byte;
                    }
                }
                if let (Some(c), false) = (cut, b.is_empty()) {
                    b.truncate(c % b.len());
                }
                b
            }),
        1 => vec(any::<u8>(), 0..512),
        1 => weird().prop_map(|j| j.text().into_bytes()),
        1 => (valid, (MAX_BODY_BYTES + 1)..MAX_SENT_BODY_BYTES).prop_map(|(j, len)| {
            let mut b = j.text().into_bytes();
            b.resize(len.max(b.len()), b' ');
            b
        }),
    ];
    any_body
        .prop_map(|mut b| {
            b.truncate(MAX_SENT_BODY_BYTES);
            b
        })
        .boxed()
}

// ---------------------------------------------------------------------------------------
// Headers and the checks every answer must pass
// ---------------------------------------------------------------------------------------

/// `Content-Type` values: JSON spellings (accepted) and others (415 with a body).
const JSON_TYPES: &[&str] = &[
    "application/json",
    "application/json",
    "application/json; charset=utf-8",
    "Application/JSON",
    " application/json ;foo=bar",
];
const OTHER_TYPES: &[&str] = &[
    "text/plain",
    "application/x-www-form-urlencoded",
    "multipart/form-data; boundary=x",
    "application/jsonp",
    "application/json-patch+json",
    "json",
    "",
    "*/*",
];

fn content_type() -> BoxedStrategy<Option<&'static str>> {
    prop_oneof![
        12 => select(JSON_TYPES).prop_map(Some),
        2 => select(OTHER_TYPES).prop_map(Some),
        1 => Just(None),
    ]
    .boxed()
}

/// Whether a Content-Type is JSON as security.rs defines it (its essence, any case).
fn is_json_type(ct: Option<&str>) -> bool {
    ct.and_then(|c| c.split(';').next())
        .is_some_and(|e| e.trim().eq_ignore_ascii_case("application/json"))
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum OriginKind {
    None,
    Same,
    Foreign,
    Null,
}

fn origin_kind() -> BoxedStrategy<OriginKind> {
    prop_oneof![
        16 => Just(OriginKind::None),
        2 => Just(OriginKind::Same),
        1 => Just(OriginKind::Foreign),
        1 => Just(OriginKind::Null),
    ]
    .boxed()
}

#[derive(Debug, Clone)]
enum Auth {
    None,
    Teacher,
    Control,
    Raw(Vec<u8>),
}

fn auth() -> BoxedStrategy<Auth> {
    prop_oneof![
        2 => Just(Auth::None),
        2 => Just(Auth::Teacher),
        2 => Just(Auth::Control),
        1 => "[!-~]{0,40}".prop_map(|t| Auth::Raw(format!("Bearer {t}").into_bytes())),
        1 => vec(any::<u8>(), 0..40).prop_map(Auth::Raw),
        1 => Just(Auth::Raw(format!("bearer {TEACHER}").into_bytes())),
        1 => Just(Auth::Raw(format!("Bearer {TEACHER} ").into_bytes())),
        1 => Just(Auth::Raw(format!("Basic {TEACHER}").into_bytes())),
    ]
    .boxed()
}

/// Headers of one generated request.
#[derive(Debug, Clone)]
struct Hdrs {
    content_type: Option<&'static str>,
    origin: OriginKind,
    auth: Auth,
}

fn hdrs() -> BoxedStrategy<Hdrs> {
    hdrs_with(auth())
}

fn hdrs_with(auth: BoxedStrategy<Auth>) -> BoxedStrategy<Hdrs> {
    (content_type(), origin_kind(), auth)
        .prop_map(|(content_type, origin, auth)| Hdrs {
            content_type,
            origin,
            auth,
        })
        .boxed()
}

impl Hdrs {
    fn list(&self, base: &str, control_token: &str) -> Vec<(String, Vec<u8>)> {
        let mut h = Vec::new();
        if let Some(ct) = self.content_type {
            h.push(("content-type".to_string(), ct.as_bytes().to_vec()));
        }
        let origin = match self.origin {
            OriginKind::None => None,
            OriginKind::Same => Some(base.to_string()),
            OriginKind::Foreign => Some("https://evil.example".to_string()),
            OriginKind::Null => Some("null".to_string()),
        };
        if let Some(o) = origin {
            h.push(("origin".to_string(), o.into_bytes()));
        }
        let auth = match &self.auth {
            Auth::None => None,
            Auth::Teacher => Some(format!("Bearer {TEACHER}").into_bytes()),
            Auth::Control => Some(format!("Bearer {control_token}").into_bytes()),
            Auth::Raw(b) => Some(b.clone()),
        };
        if let Some(a) = auth {
            h.push(("authorization".to_string(), a));
        }
        h
    }

    /// The status security.rs must answer before any handler runs, if any: 403 for a
    /// foreign or `null` Origin on a state change, then 415 for a non-JSON body.
    fn expected_guard_status(&self, method: &str, body: &[u8]) -> Option<u16> {
        let changes_state = matches!(method, "POST" | "PUT" | "PATCH" | "DELETE");
        if !changes_state {
            return None;
        }
        if matches!(self.origin, OriginKind::Foreign | OriginKind::Null) {
            return Some(403);
        }
        if !body.is_empty() && !is_json_type(self.content_type) {
            return Some(415);
        }
        None
    }
}

/// The properties every answer must have (module docs); `reads_body`: the handler reads the
/// body (so a body over 64 KiB must be refused with 413).
fn check_answer(
    srv: &SyncServer,
    method: &str,
    path: &str,
    h: &Hdrs,
    body: &[u8],
    reply: &Result<Reply, String>,
    reads_body: bool,
) -> Result<Reply, TestCaseError> {
    let r = reply
        .as_ref()
        .map_err(|e| TestCaseError::fail(format!("{method} {path}: no answer: {e}")))?;
    let what = format!("{method} {path} ({h:?}, {} body bytes)", body.len());
    if r.status >= 500 {
        let documented = srv.documented_5xx(method, path);
        prop_assert!(
            documented.contains(&r.status),
            "{what}: undocumented {}",
            r.describe()
        );
    }
    r.check_error_body()
        .map_err(|e| TestCaseError::fail(format!("{what}: {e}")))?;
    if let Some(expected) = h.expected_guard_status(method, body) {
        prop_assert_eq!(r.status, expected, "{}: {}", what, r.describe());
    } else if reads_body && body.len() > MAX_BODY_BYTES {
        // Refused; by the body limit unless the query string was refused first or the path
        // (a `..` segment, say) matched no route at all (the fallback reads no body).
        // No route, or a route without this method: an id of `.` or `%2E` is a dot segment
        // the client's URL parser removes (WHATWG URL), so `/api/sessions/%2E/actions` arrives
        // as `/api/sessions/actions` (GET/DELETE only), refused before its body is read.
        let unrouted = r.json().is_some_and(|v| {
            v["error"].as_str().is_some_and(|e| {
                (r.status == 404 && e.starts_with("no route for"))
                    || (r.status == 405 && e.contains(" is not allowed on "))
            })
        });
        let expected: &[u16] = if path.contains('?') {
            &[400, 413]
        } else {
            &[413]
        };
        prop_assert!(
            unrouted || expected.contains(&r.status),
            "{}: {}",
            what,
            r.describe()
        );
    }
    srv.healthy()
        .map_err(|e| TestCaseError::fail(format!("after {what}: {e}")))?;
    Ok(r.clone())
}

/// Sends a request and checks it.
fn request(
    srv: &SyncServer,
    method: &str,
    path: &str,
    h: &Hdrs,
    control_token: &str,
    body: Vec<u8>,
    reads_body: bool,
) -> Result<Reply, TestCaseError> {
    let url = format!("{}{path}", srv.server.base);
    let headers = h.list(&srv.server.base, control_token);
    let http = reqwest::Client::new();
    let b = (!body.is_empty()).then(|| body.clone());
    let reply = srv.block_on(send_request(&http, method, &url, &headers, b));
    check_answer(srv, method, path, h, &body, &reply, reads_body)
}

fn server() -> SyncServer {
    SyncServer::start(|c| {
        c.frame_hz = 120;
        c.unjoined_grace_secs = 3600;
        c.session_burst = 1000;
        c.sessions_per_minute = 1.0e4;
        c.max_sessions = 8;
        c.max_sessions_per_client = 8;
        c.physics_threads = Some(1);
    })
}

/// A live session with a trainee and an observer connection on it.
struct LiveSession {
    id: String,
    token: String,
    trainee: Ws,
    observer: Ws,
}

fn live_session(srv: &SyncServer) -> LiveSession {
    srv.block_on(async {
        let (id, token) = common::new_session(&srv.server).await;
        let mut sockets = Vec::new();
        for query in [
            format!("token={token}"),
            format!("token={token}&role=observer"),
        ] {
            sockets.push(common::connect(&srv.server, &id, &query).await.unwrap());
        }
        let observer = sockets.pop().unwrap();
        let trainee = sockets.pop().unwrap();
        LiveSession {
            id,
            token,
            trainee,
            observer,
        }
    })
}

/// A server with a live session whose trainee socket is read after every case.
struct Watched {
    srv: SyncServer,
    id: String,
    token: String,
    ws: std::cell::RefCell<Ws>,
    seq: std::cell::Cell<u64>,
}

impl Watched {
    fn start() -> Watched {
        let srv = server();
        let LiveSession {
            id, token, trainee, ..
        } = live_session(&srv);
        Watched {
            srv,
            id,
            token,
            ws: std::cell::RefCell::new(trainee),
            seq: std::cell::Cell::new(0),
        }
    }

    /// The session streams on: `frames` new finite state frames with increasing `seq`.
    fn streams_on(&self, frames: usize, after: &str) -> Result<(), TestCaseError> {
        let mut seq = self.seq.get();
        let r = self
            .srv
            .block_on(keeps_streaming(&mut self.ws.borrow_mut(), &mut seq, frames));
        self.seq.set(seq);
        r.map_err(|e| TestCaseError::fail(format!("session after {after}: {e}")))
    }
}

// ---------------------------------------------------------------------------------------
// Shapes of the REST bodies
// ---------------------------------------------------------------------------------------

fn small() -> BoxedStrategy<f64> {
    prop_oneof![-2.0..2.0f64, Just(0.0), Just(-0.0)].boxed()
}

fn inline_model(joints: std::ops::Range<usize>) -> BoxedStrategy<J> {
    let joint = (
        select(&["revolute", "revolute", "prismatic"][..]),
        small(),
        select(
            &[
                0.0,
                std::f64::consts::FRAC_PI_2,
                -std::f64::consts::FRAC_PI_2,
                1.0,
            ][..],
        ),
        small(),
        small(),
        option::of((-3.0..0.0f64, 0.01..3.0f64)),
        option::of(0.01..5.0f64),
        prop_oneof![4 => Just(None), 2 => Just(Some("x")), 1 => Just(Some("y"))],
    )
        .prop_map(|(t, a, alpha, d, theta, limits, vmax, twist)| {
            obj(vec![
                ("type", Some(s(t))),
                ("a", Some(num(a))),
                ("alpha", Some(num(alpha))),
                ("d", Some(num(d))),
                ("theta", Some(num(theta))),
                ("limits", limits.map(|(lo, hi)| nums(&[lo, hi]))),
                ("max_velocity", vmax.map(num)),
                ("twist_axis", twist.map(s)),
            ])
        });
    (
        "\\PC{0,12}",
        select(&["standard", "modified"][..]),
        vec(joint, joints),
        option::of(vec(small(), 3)),
    )
        .prop_map(|(name, dh, joints, tool)| {
            obj(vec![
                ("name", Some(J::Str(name))),
                ("dh", Some(s(dh))),
                ("joints", Some(J::Arr(joints))),
                ("tool", tool.map(|t| nums(&t))),
            ])
        })
        .boxed()
}

/// Degrees of freedom of the built-in robots (server/core/robots/*.json).
const ROBOT_DOF: &[(&str, usize)] = &[
    ("magnum", 6),
    ("orion", 6),
    ("rx90", 6),
    ("puma560", 6),
    ("pa10", 7),
    ("planar2r", 2),
];

fn robot() -> BoxedStrategy<J> {
    robot_and_q().prop_map(|(r, _)| r).boxed()
}

/// A robot (built-in, inline or an unknown name) and joint values, mostly one per joint.
fn robot_and_q() -> BoxedStrategy<(J, J)> {
    let robot = prop_oneof![
        6 => select(ROBOT_DOF).prop_map(|(name, dof)| (s(name), dof)),
        2 => (1usize..8).prop_flat_map(|n| inline_model(n..n + 1).prop_map(move |m| (m, n))),
        1 => "\\PC{0,16}".prop_map(|name| (J::Str(name), 6)),
    ];
    (robot, 0usize..8)
        .prop_flat_map(|((robot, dof), odd_len)| {
            let q = prop_oneof![
                6 => vec(-3.2..3.2f64, dof),
                1 => vec(-3.2..3.2f64, odd_len),
                1 => vec(-2.0e4..2.0e4f64, dof),
            ];
            (Just(robot), q.prop_map(|v| nums(&v)))
        })
        .boxed()
}

fn task_rows() -> BoxedStrategy<J> {
    prop_oneof![
        4 => proptest::sample::subsequence((0usize..6).collect::<Vec<_>>(), 1..=6),
        1 => vec(0usize..8, 0..8),
    ]
    .prop_map(|r| J::Arr(r.into_iter().map(|i| J::Raw(i.to_string())).collect()))
    .boxed()
}

fn analysis_body() -> BoxedStrategy<J> {
    (
        robot_and_q(),
        option::of(task_rows()),
        option::of(any::<bool>()),
    )
        .prop_map(|((robot, q), rows, polytope)| {
            obj(vec![
                ("robot", Some(robot)),
                ("q", Some(q)),
                ("rows", rows),
                ("polytope", polytope.map(|b| J::Raw(b.to_string()))),
            ])
        })
        .boxed()
}

fn rotation() -> BoxedStrategy<J> {
    prop_oneof![
        // A proper rotation about z.
        (-3.2..3.2f64).prop_map(|a| {
            let (sn, c) = a.sin_cos();
            J::Arr(vec![
                nums(&[c, -sn, 0.0]),
                nums(&[sn, c, 0.0]),
                nums(&[0.0, 0.0, 1.0]),
            ])
        }),
        // A reflection, a scaled matrix, anything.
        Just(J::Arr(vec![
            nums(&[-1.0, 0.0, 0.0]),
            nums(&[0.0, 1.0, 0.0]),
            nums(&[0.0, 0.0, 1.0])
        ])),
        vec(vec(small(), 3), 3).prop_map(|m| J::Arr(m.iter().map(|r| nums(r)).collect())),
    ]
    .boxed()
}

fn dual_body() -> BoxedStrategy<J> {
    let arm = (
        robot_and_q(),
        option::of((vec(-2.0..2.0f64, 3), option::of(rotation()))),
    )
        .prop_map(|((robot, q), base)| {
            obj(vec![
                ("robot", Some(robot)),
                ("q", Some(q)),
                (
                    "base",
                    base.map(|(p, r)| obj(vec![("position", Some(nums(&p))), ("rotation", r)])),
                ),
            ])
        });
    (
        prop_oneof![4 => vec(arm.clone(), 2), 1 => vec(arm, 0..4)],
        option::of(any::<bool>()),
    )
        .prop_map(|(arms, polytope)| {
            obj(vec![
                ("arms", Some(J::Arr(arms))),
                ("polytope", polytope.map(|b| J::Raw(b.to_string()))),
            ])
        })
        .boxed()
}

fn posture_body() -> BoxedStrategy<J> {
    (
        robot(),
        vec(-1.0..1.0f64, 3),
        prop_oneof![4 => 0.0..=1.0f64, 1 => -1.0..2.0f64],
        option::of(task_rows()),
        option::of(0usize..6),
    )
        .prop_map(|(robot, target, alpha, rows, starts)| {
            obj(vec![
                ("robot", Some(robot)),
                ("target_position", Some(nums(&target))),
                ("alpha", Some(num(alpha))),
                ("rows", rows),
                ("starts", starts.map(|n| J::Raw(n.to_string()))),
            ])
        })
        .boxed()
}

fn levels(lo: f64, hi: f64) -> BoxedStrategy<J> {
    vec(lo..hi, 0..3).prop_map(|v| nums(&v)).boxed()
}

fn opt_num(lo: f64, hi: f64) -> BoxedStrategy<Option<J>> {
    option::of((lo..hi).prop_map(num)).boxed()
}

/// Study parameters made of one list of levels (key, range) and optional numbers (key,
/// range each).
type LevelShape = (
    &'static str,
    (f64, f64),
    &'static [(&'static str, f64, f64)],
);

const SWEEP_X: LevelShape = (
    "z_levels",
    (-0.5, 1.0),
    &[
        ("x_start", 0.3, 0.8),
        ("x_step", 0.05, 0.3),
        ("x_end", 0.8, 2.0),
        ("left_base_y_m", -1.0, 2.0),
    ],
);
const SWEEP_Z: LevelShape = (
    "x_levels",
    (0.5, 1.6),
    &[
        ("z_start", -0.5, 0.2),
        ("z_step", 0.05, 0.3),
        ("z_end", 0.2, 1.0),
    ],
);
const DISTANCE: LevelShape = (
    "x_levels",
    (0.5, 1.6),
    &[
        ("z", -0.5, 0.8),
        ("swing_max_deg", 0.0, 30.0),
        ("step_deg", 2.0, 10.0),
        ("left_base_y_m", -1.0, 2.0),
    ],
);

fn level_params((levels_key, range, fields): LevelShape) -> BoxedStrategy<J> {
    let numbers: Vec<_> = fields.iter().map(|(_, lo, hi)| opt_num(*lo, *hi)).collect();
    (levels(range.0, range.1), numbers)
        .prop_map(move |(lv, values)| {
            let mut kv = vec![(levels_key, Some(lv))];
            kv.extend(fields.iter().map(|f| f.0).zip(values));
            obj(kv)
        })
        .boxed()
}

fn sweep_x_params() -> BoxedStrategy<J> {
    level_params(SWEEP_X)
}

fn sweep_z_params() -> BoxedStrategy<J> {
    level_params(SWEEP_Z)
}

fn distance_params() -> BoxedStrategy<J> {
    level_params(DISTANCE)
}

fn pitch_yaw_params() -> BoxedStrategy<J> {
    let f = opt_num;
    (
        vec(("\\PC{0,6}", vec(-1.5..1.5f64, 3)), 0..3),
        option::of((0.0..90.0f64, 90.0..180.0f64)),
        option::of((0.0..90.0f64, 90.0..180.0f64)),
        f(10.0, 45.0),
        f(-1.0, 2.0),
    )
        .prop_map(|(points, pitch, yaw, step, y)| {
            let points = points
                .into_iter()
                .map(|(n, p)| {
                    obj(vec![
                        ("name", Some(J::Str(n))),
                        ("position", Some(nums(&p))),
                    ])
                })
                .collect();
            obj(vec![
                ("points", Some(J::Arr(points))),
                ("pitch_deg", pitch.map(|(a, b)| nums(&[a, b]))),
                ("yaw_deg", yaw.map(|(a, b)| nums(&[a, b]))),
                ("step_deg", step),
                ("left_base_y_m", y),
            ])
        })
        .boxed()
}

fn map_params() -> BoxedStrategy<J> {
    (
        option::of(select(ROBOTS).prop_map(s)),
        option::of((0.0..1.0f64, 1.0..2.0f64)),
        option::of((-0.5..0.5f64, 0.5..1.0f64)),
        option::of(1usize..10),
        option::of(1usize..10),
        opt_num(-0.5, 0.5),
        option::of(select(&["nominal", "free", "fixed"][..]).prop_map(s)),
    )
        .prop_map(|(robot, xr, zr, nx, nz, y, orientation)| {
            obj(vec![
                ("robot", robot),
                ("x_range", xr.map(|(a, b)| nums(&[a, b]))),
                ("z_range", zr.map(|(a, b)| nums(&[a, b]))),
                ("nx", nx.map(|n| J::Raw(n.to_string()))),
                ("nz", nz.map(|n| J::Raw(n.to_string()))),
                ("y", y),
                ("orientation", orientation),
            ])
        })
        .boxed()
}

/// A study name and parameters of modest size: mostly the study's own shape, sometimes
/// another study's, no parameters, or an unknown name.
fn study_case() -> BoxedStrategy<(String, BoxedStrategy<J>)> {
    let own = |name: &'static str, p: fn() -> BoxedStrategy<J>| (name.to_string(), p());
    prop_oneof![
        Just(own("single-x", sweep_x_params)),
        Just(own("dual-x", sweep_x_params)),
        Just(own("single-z", sweep_z_params)),
        Just(own("single-pitch-yaw", pitch_yaw_params)),
        Just(own("dual-pitch-yaw", pitch_yaw_params)),
        Just(own("dual-distance", distance_params)),
        Just(own("workspace-map", map_params)),
        (
            study_name(),
            select(
                &[
                    sweep_x_params,
                    sweep_z_params,
                    pitch_yaw_params,
                    distance_params,
                    map_params
                ][..]
            )
        )
            .prop_map(|(name, p)| (name, p())),
        study_name().prop_map(|name| (name, Just(J::Raw("null".into())).boxed())),
    ]
    .boxed()
}

fn session_body() -> BoxedStrategy<J> {
    let name = |known: &'static [&'static str]| prop_oneof![4 => select(known).prop_map(s), 1 => "\\PC{0,12}".prop_map(J::Str)];
    (
        option::of(name(LIVE_SCENARIOS)),
        option::of(name(&["joint", "cartesian"])),
        option::of(name(&["open", "closed"])),
        option::of("\\PC{0,80}".prop_map(J::Str)),
        option::of("\\PC{0,12}".prop_map(J::Str)),
    )
        .prop_map(|(scenario, mode, method, label, code)| {
            obj(vec![
                ("scenario", scenario),
                ("control_mode", mode),
                ("control_method", method),
                ("label", label),
                ("join_code", code),
            ])
        })
        .boxed()
}

fn action_body() -> BoxedStrategy<J> {
    let ty = |t: &str| Some(s(t));
    prop_oneof![
        select(
            &[
                "reset",
                "pause",
                "resume",
                "release",
                "clear_faults",
                "end",
                "input"
            ][..]
        )
        .prop_map(move |t| obj(vec![("type", ty(t))])),
        prop_oneof![
            select(LIVE_SCENARIOS).prop_map(s),
            "\\PC{0,12}".prop_map(J::Str)
        ]
        .prop_map(move |sc| obj(vec![("type", ty("scenario")), ("scenario", Some(sc))])),
        (
            select(&["supply_drop", "stuck_valve", "leak", "air", "fire"][..]),
            select(&["left", "right", "both"][..]),
            option::of(0usize..8),
            prop_oneof![
                0.0..6.89e6f64,
                -1.0..=1.0f64,
                0.0..1.0e-9f64,
                0.01..=1.0f64,
                -1.0e7..1.0e7f64,
            ],
            option::of(any::<bool>()),
        )
            .prop_map(move |(fault, arm, joint, value, silent)| obj(vec![
                ("type", ty("fault")),
                ("fault", Some(s(fault))),
                ("arm", Some(s(arm))),
                ("joint", joint.map(|j| J::Raw(j.to_string()))),
                ("value", Some(num(value))),
                ("silent", silent.map(|b| J::Raw(b.to_string()))),
            ])),
        (
            prop_oneof![-1.0..3.0f64, -1.0e6..1.0e6f64],
            prop_oneof![-400.0..400.0f64, -1.0e9..1.0e9f64],
        )
            .prop_map(move |(speed, heading)| obj(vec![
                ("type", ty("set_current")),
                ("speed_m_s", Some(num(speed))),
                ("heading_deg", Some(num(heading))),
            ])),
        "\\PC{0,600}"
            .prop_map(move |t| obj(vec![("type", ty("message")), ("text", Some(J::Str(t)))])),
    ]
    .boxed()
}

// ---------------------------------------------------------------------------------------
// REST: the POST routes
// ---------------------------------------------------------------------------------------

/// `POST /api/analysis`, `/api/analysis/dual`, `/api/optimal-posture`: one server for all
/// three (each call builds its own, so the three run in parallel).
fn post_route(cases: u32, path: &'static str, shape: fn() -> BoxedStrategy<J>) {
    let srv = server();
    proptest!(config(cases), |(h in hdrs(), body in bodies(shape()))| {
        let r = request(&srv, "POST", path, &h, "none", body, true)?;
        if r.status == 200 {
            prop_assert!(r.json().is_some(), "{path}: 200 without JSON: {}", r.describe());
        }
    });
}

#[test]
fn analysis_bodies() {
    post_route(400, "/api/analysis", analysis_body);
}

#[test]
fn dual_analysis_bodies() {
    post_route(300, "/api/analysis/dual", dual_body);
}

#[test]
fn optimal_posture_bodies() {
    post_route(160, "/api/optimal-posture", posture_body);
}

fn study_name() -> BoxedStrategy<String> {
    prop_oneof![
        6 => select(STUDIES).prop_map(str::to_string),
        1 => odd_segment(),
    ]
    .boxed()
}

fn study_query() -> BoxedStrategy<String> {
    prop_oneof![
        3 => Just(String::new()),
        1 => Just("?format=json".to_string()),
        1 => Just("?format=csv".to_string()),
        1 => Just("?format=csv&format=json".to_string()),
        1 => "[a-z%0-9]{0,8}".prop_map(|f| format!("?format={f}")),
    ]
    .boxed()
}

#[test]
fn study_bodies() {
    let srv = server();
    let case = study_case().prop_flat_map(|(name, params)| (Just(name), bodies(params)));
    proptest!(config(200), |(
        h in hdrs(),
        (name, body) in case,
        query in study_query(),
    )| {
        let path = format!("/api/studies/{}{query}", pct(&name));
        request(&srv, "POST", &path, &h, "none", body, true)?;
    });
}

/// Over-limit study shapes: one series over `MAX_ROWS`, several series each within it but
/// together over it, map grids over `MAX_CELLS`, sweeps whose row count overflows. All
/// unreachable (so no sweep stops early at the workspace boundary): refused with a 4xx.
fn over_limit_study() -> BoxedStrategy<(&'static str, J)> {
    // `k` series of `n` rows each: start 0, step 1, end n − 1 (studies.rs `check_step`).
    let total = (20_000usize..=MAX_STUDY_ROWS)
        .prop_flat_map(|n| {
            let min_k = MAX_STUDY_ROWS / n + 1;
            (Just(n), min_k..min_k + 3)
        })
        .boxed();
    prop_oneof![
        (MAX_STUDY_ROWS + 1..50 * MAX_STUDY_ROWS).prop_map(|n| {
            (
                "single-x",
                obj(vec![
                    ("x_start", Some(num(0.0))),
                    ("x_step", Some(num(1.0))),
                    ("x_end", Some(num(n as f64 - 1.0))),
                ]),
            )
        }),
        Just((
            "single-z",
            obj(vec![
                ("z_start", Some(num(0.0))),
                ("z_step", Some(num(1.0e-300))),
                ("z_end", Some(num(1.0e300))),
            ])
        )),
        (total.clone(), select(&["single-x", "dual-x"][..])).prop_map(|((n, k), study)| {
            (
                study,
                obj(vec![
                    ("z_levels", Some(nums(&vec![50.0; k]))),
                    ("x_start", Some(num(0.0))),
                    ("x_step", Some(num(1.0))),
                    ("x_end", Some(num(n as f64 - 1.0))),
                ]),
            )
        }),
        total.clone().prop_map(|(n, k)| {
            (
                "single-z",
                obj(vec![
                    ("x_levels", Some(nums(&vec![50.0; k]))),
                    ("z_start", Some(num(0.0))),
                    ("z_step", Some(num(1.0))),
                    ("z_end", Some(num(n as f64 - 1.0))),
                ]),
            )
        }),
        (
            total.clone(),
            select(&["single-pitch-yaw", "dual-pitch-yaw"][..])
        )
            .prop_map(|((n, k), study)| {
                let point = obj(vec![
                    ("name", Some(s("far"))),
                    ("position", Some(nums(&[50.0, 0.0, 0.0]))),
                ]);
                // Pitch and yaw series of n/2 rows each per point.
                let half = (n / 2) as f64;
                (
                    study,
                    obj(vec![
                        ("points", Some(J::Arr(vec![point; k]))),
                        ("pitch_deg", Some(nums(&[0.0, half - 1.0]))),
                        ("yaw_deg", Some(nums(&[0.0, half - 1.0]))),
                        ("step_deg", Some(num(1.0))),
                    ]),
                )
            }),
        total.prop_map(|(n, k)| {
            // Swing −m..m in steps of 1: 2m + 1 rows per level.
            let m = ((n - 1) / 2) as f64;
            (
                "dual-distance",
                obj(vec![
                    ("x_levels", Some(nums(&vec![50.0; k]))),
                    ("swing_max_deg", Some(num(m))),
                    ("step_deg", Some(num(1.0))),
                ]),
            )
        }),
        (1usize..=MAX_MAP_CELLS).prop_map(|nx| {
            let nz = MAX_MAP_CELLS / nx + 1;
            (
                "workspace-map",
                obj(vec![
                    ("nx", Some(J::Raw(nx.to_string()))),
                    ("nz", Some(J::Raw(nz.to_string()))),
                ]),
            )
        }),
    ]
    .boxed()
}

#[test]
fn over_limit_studies_are_refused() {
    let srv = server();
    let h = Hdrs {
        content_type: Some("application/json"),
        origin: OriginKind::None,
        auth: Auth::None,
    };
    let mut cfg = config(16);
    cfg.max_shrink_iters = 4;
    proptest!(cfg, |((study, params) in over_limit_study())| {
        let path = format!("/api/studies/{study}");
        let r = request(&srv, "POST", &path, &h, "none", params.text().into_bytes(), true)?;
        prop_assert!(
            (400..500).contains(&r.status),
            "{} {}: over the limit but answered {}",
            study,
            params.text().chars().take(200).collect::<String>(),
            r.describe()
        );
    });
}

/// A path segment: mutated known names, unicode, dots, slashes, percent signs, long.
fn odd_segment() -> BoxedStrategy<String> {
    let known: Vec<&str> = ROBOTS
        .iter()
        .chain(STUDIES)
        .chain(LIVE_SCENARIOS)
        .copied()
        .collect();
    prop_oneof![
        3 => (select(known), "\\PC{0,3}", any::<bool>()).prop_map(|(k, extra, upper)| {
            let k = if upper { k.to_uppercase() } else { k.to_string() };
            format!("{k}{extra}")
        }),
        2 => "\\PC{0,24}",
        1 => select(&["..", ".", "%", "%00", "%2e%2e", "..%2f..%2fetc%2fpasswd", "a/b", "\\", "~", "index.html", "run", "runs"][..]).prop_map(str::to_string),
        1 => "[0-9a-f]{16}",
        1 => (1usize..3000).prop_map(|n| "a".repeat(n)),
    ]
    .boxed()
}

/// Percent-encodes a segment (RFC 3986 unreserved characters kept), except an existing
/// `%XX` form which is passed through (so encoded odd bytes reach the router).
fn pct(seg: &str) -> String {
    // A bare "." or ".." segment would be removed by the client's URL normalization (RFC 3986
    // §5.2.4) and the request would hit another route; sent encoded, it reaches the server.
    if seg == "." || seg == ".." {
        return seg.replace('.', "%2E");
    }
    let mut out = String::new();
    for b in seg.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~' | b'%') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    if out.is_empty() { "%20".into() } else { out }
}

#[test]
fn scenario_run_requests() {
    let srv = server();
    proptest!(config(128), |(
        h in hdrs(),
        name in prop_oneof![1 => select(SCENARIOS).prop_map(str::to_string), 3 => odd_segment()],
        body in prop_oneof![Just(Vec::new()), bodies(weird())],
    )| {
        // A known scenario runs for seconds of CPU: only requests the guard refuses (403,
        // 415) are sent to one; every other name is unknown.
        let name = if SCENARIOS.contains(&name.as_str())
            && h.expected_guard_status("POST", &body).is_none()
        {
            format!("{name}-x")
        } else {
            name
        };
        let path = format!("/api/scenarios/{}/run", pct(&name));
        let r = request(&srv, "POST", &path, &h, "none", body, false)?;
        // An unknown scenario is 404 (`runs` routes to the GET-only CSV download: 405).
        if h.expected_guard_status("POST", &[]).is_none() && r.status < 500 {
            let expected: &[u16] = if name == "runs" { &[405, 415] } else { &[404, 415] };
            prop_assert!(expected.contains(&r.status), "{name}: {}", r.describe());
        }
    });
}

#[test]
fn session_creation_bodies() {
    let srv = server();
    proptest!(config(160), |(h in hdrs(), body in prop_oneof![Just(Vec::new()), bodies(session_body())])| {
        let r = request(&srv, "POST", "/api/sessions", &h, "none", body, true)?;
        if r.status == 201 {
            let v = r.json().unwrap_or_default();
            let (Some(id), Some(token), Some(url)) =
                (v["id"].as_str(), v["control_token"].as_str(), v["ws_url"].as_str())
            else {
                return Err(TestCaseError::fail(format!("201 without id/token/url: {}", r.describe())));
            };
            prop_assert!(url.contains(id) && url.contains(token), "{}", r.describe());
            // Free the server for the next case (each session is a 1 kHz simulation).
            let end = Hdrs { content_type: None, origin: OriginKind::None, auth: Auth::Teacher };
            let gone = request(&srv, "DELETE", &format!("/api/sessions/{id}"), &end, "none", Vec::new(), false)?;
            prop_assert_eq!(gone.status, 204, "{}", gone.describe());
        }
    });
}

#[test]
fn session_action_bodies() {
    let w = Watched::start();
    let (srv, id, token) = (&w.srv, &w.id, &w.token);
    let valid_token = prop_oneof![
        6 => Just(Auth::Teacher),
        3 => Just(Auth::Control),
        2 => auth(),
    ]
    .boxed();
    proptest!(config(300), |(
        h in hdrs_with(valid_token.clone()),
        which in prop_oneof![6 => Just(None), 1 => odd_segment().prop_map(Some)],
        body in bodies(action_body()),
    )| {
        let target = which.unwrap_or_else(|| id.clone());
        let path = format!("/api/sessions/{}/actions", pct(&target));
        request(srv, "POST", &path, &h, token, body, true)?;
        // The session streams on, finite, whatever the action (faults of any allowed size).
        w.streams_on(2, &path)?;
    });
}

// ---------------------------------------------------------------------------------------
// REST: paths and queries of the other routes
// ---------------------------------------------------------------------------------------

/// (method, path template with `{}` for the fuzzed segment) of every route with a path
/// parameter, and some without (where the segment is appended).
const PATH_ROUTES: &[(&str, &str)] = &[
    ("GET", "/api/robots/{}"),
    ("GET", "/api/sessions/{}"),
    ("DELETE", "/api/sessions/{}"),
    ("GET", "/api/sessions/{}/log.csv"),
    ("GET", "/api/scenarios/runs/{}"),
    ("GET", "/web/{}"),
    ("GET", "/static/{}"),
    ("GET", "/ws/sessions/{}"),
    ("GET", "/api/attempts/{}"),
    ("GET", "/api/attempts/{}/replay"),
    ("GET", "/api/attempts/{}/inputs"),
    ("GET", "/ws/replay/{}"),
    ("GET", "/replay/{}"),
    ("GET", "/api/sessions"),
    ("GET", "/api/studies/{}"),
    ("PUT", "/api/sessions/{}"),
    ("PATCH", "/api/analysis"),
    ("OPTIONS", "/api/robots"),
    ("DELETE", "/api/robots/{}"),
    ("GET", "/api/{}"),
    ("GET", "/{}"),
];

fn query() -> BoxedStrategy<String> {
    prop_oneof![
        2 => Just(String::new()),
        2 => "\\PC{0,20}".prop_map(|t| format!("?token={}", pct(&t))),
        1 => Just(format!("?token={TEACHER}")),
        1 => Just(format!("?token={TEACHER}&token=x")),
        1 => "\\PC{0,8}".prop_map(|r| format!("?role={}&format={}", pct(&r), pct(&r))),
        1 => vec(any::<u8>(), 0..20).prop_map(|b| {
            format!("?{}", b.iter().map(|x| format!("%{x:02X}")).collect::<String>())
        }),
    ]
    .boxed()
}

#[test]
fn paths_and_queries() {
    let w = Watched::start();
    let (srv, id, token) = (&w.srv, &w.id, &w.token);
    let teacher = Hdrs {
        content_type: None,
        origin: OriginKind::None,
        auth: Auth::Teacher,
    };
    proptest!(config(300), |(
        route in select(PATH_ROUTES),
        seg in prop_oneof![4 => odd_segment(), 1 => Just(String::new())],
        own in any::<bool>(),
        q in query(),
        mut h in hdrs(),
    )| {
        let (method, template) = route;
        // A DELETE of the live session with a valid token would end it: those get a
        // wrong token, so the property "a refused DELETE leaves the session live" is tested.
        let seg = if own && !seg.is_empty() { id.clone() } else { pct(&seg) };
        if method == "DELETE" && seg == *id {
            h.auth = Auth::Raw(format!("Bearer {TEACHER}x").into_bytes());
        }
        let path = format!("{}{q}", template.replace("{}", &seg));
        let r = request(srv, method, &path, &h, token, Vec::new(), false)?;
        if method == "GET" && template == "/api/robots/{}" && r.status == 200 {
            prop_assert!(ROBOTS.contains(&seg.as_str()), "{}", r.describe());
        }
        // The session is live and streaming after every request.
        let live = request(srv, "GET", &format!("/api/sessions/{id}"), &teacher, "none", Vec::new(), false)?;
        prop_assert_eq!(live.status, 200, "{}", live.describe());
        let summary = live.json().unwrap_or_default();
        prop_assert_eq!(summary["status"].as_str(), Some("live"), "{}", live.describe());
        w.streams_on(1, &format!("{method} {path}"))?;
    });
}

// ---------------------------------------------------------------------------------------
// WebSocket client messages
// ---------------------------------------------------------------------------------------

fn axes() -> BoxedStrategy<J> {
    (
        prop_oneof![4 => vec(-1.5..1.5f64, 6), 1 => vec(-1.5..1.5f64, 0..9)],
        option::of(-1.5..1.5f64),
    )
        .prop_map(|(a, grip)| obj(vec![("axes", Some(nums(&a))), ("grip", grip.map(num))]))
        .boxed()
}

/// Every client message type of protocol.rs in its valid shape (values partly out of
/// range), and unknown types.
fn client_message() -> BoxedStrategy<J> {
    let ty = |t: &str| Some(s(t));
    prop_oneof![
        4 => (
            prop_oneof![0u64..1_000_000, Just((1u64 << 53) - 1), Just(1u64 << 53), Just(u64::MAX)],
            option::of(axes()),
            option::of(axes()),
            option::of(prop_oneof![4 => vec(-1.5..1.5f64, 6), 1 => vec(-1.5..1.5f64, 0..9)]),
        )
            .prop_map(move |(seq, left, right, object)| obj(vec![
                ("type", ty("input")),
                ("seq", Some(J::Raw(seq.to_string()))),
                ("arms", Some(obj(vec![("left", left), ("right", right)]))),
                ("object", object.map(|o| nums(&o))),
            ])),
        2 => (
            option::of(select(&["joint", "cartesian", "polar"][..])),
            option::of(select(&["open", "closed", "ajar"][..])),
            option::of(prop_oneof![0.0..=1.0f64, -2.0..2.0f64]),
        )
            .prop_map(move |(mode, method, speed)| obj(vec![
                ("type", ty("settings")),
                ("control_mode", mode.map(s)),
                ("control_method", method.map(s)),
                ("arm_speed", speed.map(num)),
            ])),
        2 => select(&["reset", "pause", "resume", "release", "end", "fault", "hello", "state", "Input", ""][..])
            .prop_map(move |t| obj(vec![("type", ty(t))])),
        1 => any::<f64>()
            .prop_map(move |t| obj(vec![("type", ty("ping")), ("t", Some(if t.is_finite() { num(t) } else { J::Raw("1e999".into()) }))])),
    ]
    .boxed()
}

/// One WebSocket frame a client may send (all under the 16 KiB limit).
#[derive(Debug, Clone)]
enum Frame {
    Text(String),
    Binary(Vec<u8>),
    Ping(Vec<u8>),
}

fn ws_frame() -> BoxedStrategy<Frame> {
    prop_oneof![
        8 => bodies(client_message())
            .prop_filter("under the message limit", |b| b.len() <= MAX_WS_MESSAGE_BYTES)
            .prop_map(|b| Frame::Text(String::from_utf8_lossy(&b).into_owned())),
        1 => "\\PC{0,64}".prop_map(Frame::Text),
        1 => vec(any::<u8>(), 0..256).prop_map(Frame::Binary),
        1 => client_message().prop_map(|j| Frame::Binary(j.text().into_bytes())),
        1 => vec(any::<u8>(), 0..100).prop_map(Frame::Ping),
    ]
    .boxed()
}

async fn send_frame(ws: &mut Ws, f: &Frame) -> Result<(), String> {
    let msg = match f {
        Frame::Text(t) => Message::text(t.clone()),
        Frame::Binary(b) => Message::binary(b.clone()),
        Frame::Ping(b) => Message::Ping(b.clone().into()),
    };
    ws.send(msg).await.map_err(|e| format!("send: {e}"))
}

#[test]
fn ws_client_messages() {
    let srv = server();
    let LiveSession {
        trainee, observer, ..
    } = live_session(&srv);
    let socks = std::cell::RefCell::new([(trainee, 0u64), (observer, 0u64)]);
    proptest!(config(600), |(frames in vec((ws_frame(), 0usize..2), 1..4))| {
        let mut socks = socks.borrow_mut();
        srv.block_on(async {
            for (f, who) in &frames {
                send_frame(&mut socks[*who].0, f).await?;
            }
            // Both connections stream on, finite, with increasing seq.
            for (ws, seq) in socks.iter_mut() {
                keeps_streaming(ws, seq, 2).await?;
            }
            Ok::<(), String>(())
        })
        .map_err(|e| TestCaseError::fail(format!("after {frames:?}: {e}")))?;
        srv.healthy().map_err(TestCaseError::fail)?;
    });
}

/// Reads until a close frame (5 s); its code, or `None` when the socket ended without one.
async fn close_code_of(ws: &mut Ws) -> Result<Option<u16>, String> {
    use futures_util::StreamExt;
    loop {
        match tokio::time::timeout(Duration::from_secs(5), ws.next()).await {
            Err(_) => return Err("no close within 5 s".into()),
            Ok(Some(Ok(Message::Close(f)))) => return Ok(f.map(|f| u16::from(f.code))),
            Ok(Some(Ok(_))) => {}
            Ok(other) => return Err(format!("socket ended without a close frame: {other:?}")),
        }
    }
}

#[test]
fn ws_oversize_messages_close_1009_and_the_session_streams_on() {
    let srv = server();
    let LiveSession {
        id,
        token,
        trainee,
        observer,
    } = live_session(&srv);
    let state = std::cell::RefCell::new((Some(trainee), observer, 0u64));
    proptest!(config(16), |(
        len in prop_oneof![
            (MAX_WS_MESSAGE_BYTES + 1)..(4 * MAX_WS_MESSAGE_BYTES),
            (4 * MAX_WS_MESSAGE_BYTES + 1)..(12 * MAX_WS_MESSAGE_BYTES),
        ],
        binary in any::<bool>(),
        fill in client_message(),
    )| {
        let mut st = state.borrow_mut();
        let (trainee, observer, obs_seq) = &mut *st;
        let result = srv.block_on(async {
            let mut ws = match trainee.take() {
                Some(ws) => ws,
                None => common::connect(&srv.server, &id, &format!("token={token}"))
                    .await
                    .map_err(|s| format!("reconnect refused: {s}"))?,
            };
            // A valid message padded with spaces to `len` bytes.
            let mut text = fill.text();
            text.push_str(&" ".repeat(len.saturating_sub(text.len())));
            let msg = if binary { Message::binary(text.into_bytes()) } else { Message::text(text) };
            // The server may close before reading all of a message over its transport limit.
            let _ = ws.send(msg).await;
            let code = close_code_of(&mut ws).await?;
            if code != Some(1009) {
                return Err(format!("{len} bytes: closed with {code:?}, not 1009"));
            }
            // The session streams on: to the observer, and to a new trainee connection.
            keeps_streaming(observer, obs_seq, 2).await?;
            let mut again = common::connect(&srv.server, &id, &format!("token={token}"))
                .await
                .map_err(|s| format!("reconnect refused: {s}"))?;
            let mut seq = 0;
            keeps_streaming(&mut again, &mut seq, 2).await?;
            *trainee = Some(again);
            Ok::<(), String>(())
        });
        result.map_err(TestCaseError::fail)?;
        srv.healthy().map_err(TestCaseError::fail)?;
    });
}

/// The finiteness oracle itself: a NaN (written by serde_json as `null`) in a state frame's
/// arm is caught; the documented nullable fields are not.
#[test]
fn the_finiteness_check_sees_non_finite_values() {
    let ok = serde_json::json!({"type": "state", "seq": 1, "dual": null,
        "arms": {"left": {"q": [0.0, 1.0], "measures": {"condition_number": null}}}});
    assert!(common::check_state_finite(&ok).is_ok());
    let mut bad = ok.clone();
    bad["arms"]["left"]["q"][1] = serde_json::to_value(f64::NAN).unwrap();
    let err = common::check_state_finite(&bad).unwrap_err();
    assert!(err.contains(".arms.left.q[1]"), "{err}");
    let mut bad = ok;
    bad["t"] = serde_json::Value::Null;
    assert!(common::check_state_finite(&bad).is_err());
}
