//! Shared by the integration tests: a server on port 0 (the library's `run`, as `main`
//! uses it), session creation, WebSocket connection, sending and reading helpers, the
//! built-in Magnum model, temporary data directories.

#![allow(clippy::unwrap_used, dead_code, unreachable_pub)]

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use tokio_tungstenite::tungstenite::Message;

pub const TEACHER: &str = "teacher-token";

pub struct Server {
    pub base: String,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    done: Option<tokio::task::JoinHandle<()>>,
}

impl Server {
    pub async fn stop(mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(d) = self.done.take() {
            let _ = d.await;
        }
    }
}

/// A fresh path `seaarms-{tag}-{random hex}` in the system's temporary folder (not created).
pub fn temp_dir(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("seaarms-{tag}-{}", seaarms::ids::random_hex(6)))
}

/// The built-in Magnum model (server/core/robots/magnum.json) for both arms, as the server
/// loads it.
pub fn magnum() -> [Arc<seaarms_core::Model>; 2] {
    let robots = seaarms::robots::Robots::load().expect("built-in robots");
    let m = robots.get("magnum").expect("magnum");
    [m.clone(), m]
}

/// Joint `j`'s angle (rad) of `arm` (`left`, `right`) in a state frame.
pub fn q(state: &Value, arm: &str, j: usize) -> f64 {
    state["arms"][arm]["q"][j].as_f64().unwrap()
}

pub async fn start_with(
    dir: PathBuf,
    tweak: impl FnOnce(&mut seaarms::config::ServeConfig),
) -> Server {
    start_with_state(dir, tweak).await.0
}

/// [`start_with`], with the server's state (to look inside it).
pub async fn start_with_state(
    dir: PathBuf,
    tweak: impl FnOnce(&mut seaarms::config::ServeConfig),
) -> (Server, seaarms::app::AppState) {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    // Tests not about progression start any exercise directly: `requires` does not lock
    // (tests/progression.rs turns it on).
    let mut config = seaarms::config::ServeConfig {
        data_dir: dir,
        instructor_token: Some(TEACHER.into()),
        progression: seaarms::config::Progression::Off,
        ..Default::default()
    };
    tweak(&mut config);
    let state = seaarms::app::AppState::new(&config).unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let done = tokio::spawn({
        let state = state.clone();
        async move {
            seaarms::run(listener, state, async {
                let _ = rx.await;
            })
            .await
            .unwrap();
        }
    });
    let server = Server {
        base: format!("http://{addr}"),
        stop: Some(tx),
        done: Some(done),
    };
    (server, state)
}

pub async fn start() -> Server {
    start_with(temp_dir("sessions"), |_| {}).await
}

/// GET with the instructor token; the body as text.
pub async fn get_text(url: &str) -> String {
    reqwest::Client::new()
        .get(url)
        .bearer_auth(TEACHER)
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap()
}

/// GET `url` with `token` as a bearer; the status and the body text.
pub async fn get_as(url: &str, token: &str) -> (u16, String) {
    let r = reqwest::Client::new()
        .get(url)
        .bearer_auth(token)
        .send()
        .await
        .unwrap();
    (r.status().as_u16(), r.text().await.unwrap())
}

/// GET with the instructor token; the body as JSON.
pub async fn get_json(url: &str) -> Value {
    let text = get_text(url).await;
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{url}: {e}: {text}"))
}

/// Creates a session on `s`; the status and the body.
pub async fn create(s: &Server, body: Value) -> (u16, Value) {
    create_at(&s.base, body).await
}

/// Creates a session on the server at `base`; the status and the body.
pub async fn create_at(base: &str, body: Value) -> (u16, Value) {
    let r = reqwest::Client::new()
        .post(format!("{base}/api/sessions"))
        .json(&body)
        .send()
        .await
        .unwrap();
    let st = r.status().as_u16();
    (st, r.json().await.unwrap())
}

/// `POST /api/sessions/{id}/actions` with `token`; the status and the body text.
pub async fn act(s: &Server, id: &str, token: &str, body: Value) -> (u16, String) {
    let r = reqwest::Client::new()
        .post(format!("{}/api/sessions/{id}/actions", s.base))
        .bearer_auth(token)
        .json(&body)
        .send()
        .await
        .unwrap();
    (r.status().as_u16(), r.text().await.unwrap())
}

/// Creates a default session; its id and control token.
pub async fn new_session(s: &Server) -> (String, String) {
    let (st, c) = create(s, serde_json::json!({})).await;
    assert_eq!(st, 201, "{c}");
    (
        c["id"].as_str().unwrap().to_string(),
        c["control_token"].as_str().unwrap().to_string(),
    )
}

/// Connects as the session's trainee and reads the `hello`.
pub async fn trainee(s: &Server, id: &str, token: &str) -> Ws {
    let mut ws = connect(s, id, &format!("token={token}")).await.unwrap();
    next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    ws
}

/// Opens a WebSocket with extra request headers (e.g. `Origin`); `Err(status)` when refused.
pub async fn connect_with(
    s: &Server,
    id: &str,
    query: &str,
    headers: &[(&str, &str)],
) -> Result<Ws, u16> {
    use tokio_tungstenite::tungstenite::client::IntoClientRequest;
    let url = format!(
        "{}/ws/sessions/{id}?{query}",
        s.base.replace("http://", "ws://")
    );
    let mut req = url.into_client_request().unwrap();
    for (k, v) in headers {
        req.headers_mut().insert(
            tokio_tungstenite::tungstenite::http::HeaderName::from_bytes(k.as_bytes()).unwrap(),
            v.parse().unwrap(),
        );
    }
    match tokio_tungstenite::connect_async(req).await {
        Ok((ws, _)) => Ok(ws),
        Err(tokio_tungstenite::tungstenite::Error::Http(resp)) => Err(resp.status().as_u16()),
        Err(e) => panic!("connect: {e}"),
    }
}

/// Reads until the server's close frame (within 5 s); its code.
pub async fn close_code(ws: &mut Ws) -> u16 {
    loop {
        match tokio::time::timeout(Duration::from_secs(5), ws.next())
            .await
            .expect("no close frame within 5 s")
        {
            Some(Ok(Message::Close(Some(f)))) => return u16::from(f.code),
            Some(Ok(_)) => continue,
            other => panic!("expected a close frame, got {other:?}"),
        }
    }
}

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

pub async fn connect(s: &Server, id: &str, query: &str) -> Result<Ws, u16> {
    let url = format!(
        "{}/ws/sessions/{id}?{query}",
        s.base.replace("http://", "ws://")
    );
    match tokio_tungstenite::connect_async(&url).await {
        Ok((ws, _)) => Ok(ws),
        Err(tokio_tungstenite::tungstenite::Error::Http(resp)) => Err(resp.status().as_u16()),
        Err(e) => panic!("connect: {e}"),
    }
}

/// Next message of the given type within `timeout`.
pub async fn next_of(ws: &mut Ws, kind: &str, timeout: Duration) -> Value {
    let deadline = Instant::now() + timeout;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let msg = tokio::time::timeout(left, ws.next())
            .await
            .unwrap_or_else(|_| panic!("no `{kind}` message in time"));
        match msg {
            Some(Ok(Message::Text(t))) => {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["type"] == kind {
                    return v;
                }
            }
            Some(Ok(Message::Close(f))) => panic!("closed while waiting for {kind}: {f:?}"),
            Some(Ok(_)) => {}
            other => panic!("socket ended while waiting for {kind}: {other:?}"),
        }
    }
}

/// Sends `v` as one text message.
pub async fn send(ws: &mut Ws, v: Value) {
    ws.send(Message::Text(v.to_string().into())).await.unwrap();
}

/// Drives the left arm and the right jaw with changing sticks for `messages` × 20 ms (`seq`
/// numbers the inputs on; `phase` shifts the sine they follow).
pub async fn drive(ws: &mut Ws, seq: &mut u64, messages: u64, phase: f64) {
    for i in 0..messages {
        *seq += 1;
        let a = (phase + i as f64 * 0.07).sin();
        send(
            ws,
            serde_json::json!({"type": "input", "seq": *seq, "arms": {
                "left": {"axes": [0.8 * a, 0.6, -0.4 * a, 0.3, 0.0, 0.2], "grip": 0},
                "right": {"axes": [0, 0, 0.5, 0, 0, 0], "grip": -a}}}),
        )
        .await;
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// Holds the sticks: sends `count` input messages 40 ms apart (seq `first_seq`, …) with the
/// `arms` given (e.g. `{"left": {"axes": [1, 0, 0, 0, 0, 0]}}`).
pub async fn hold_sticks(ws: &mut Ws, first_seq: u64, count: u64, arms: Value) {
    for seq in first_seq..first_seq + count {
        send(
            ws,
            serde_json::json!({"type": "input", "seq": seq, "arms": arms}),
        )
        .await;
        tokio::time::sleep(Duration::from_millis(40)).await;
    }
}

/// The first state frame with simulated time ≥ `t_min` (frames buffered in the socket while
/// the test was busy are read and dropped on the way).
pub async fn state_after(ws: &mut Ws, t_min: f64) -> Value {
    loop {
        let s = next_of(ws, "state", Duration::from_secs(5)).await;
        if s["t"].as_f64().unwrap() >= t_min {
            return s;
        }
    }
}

// ---------------------------------------------------------------------------------------
// Synchronous harness for the property tests (tests/fuzz_rest.rs, tests/fuzz_ws.rs):
// proptest runs its cases on the test thread, so the server lives on a runtime built once
// and the async client calls run through `block_on`.
// ---------------------------------------------------------------------------------------

/// A server on its own multi-threaded runtime, for synchronous tests.
pub struct SyncServer {
    /// The runtime the server (and every client call) runs on.
    pub rt: tokio::runtime::Runtime,
    /// The server.
    pub server: Server,
    /// `/api/openapi.json` as the server serves it.
    pub openapi: Value,
}

impl SyncServer {
    /// Starts a server on port 0 with `tweak` applied to the configuration.
    pub fn start(tweak: impl FnOnce(&mut seaarms::config::ServeConfig)) -> SyncServer {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let server = rt.block_on(start_with(temp_dir("sync"), tweak));
        let openapi = rt.block_on(async {
            reqwest::get(format!("{}/api/openapi.json", server.base))
                .await
                .unwrap()
                .json::<Value>()
                .await
                .unwrap()
        });
        SyncServer {
            rt,
            server,
            openapi,
        }
    }

    /// Runs a future to completion on the server's runtime.
    pub fn block_on<F: std::future::Future>(&self, f: F) -> F::Output {
        self.rt.block_on(f)
    }

    /// The 5xx statuses `/api/openapi.json` documents for `method` on `path` (a concrete
    /// path, matched against the spec's `{param}` templates; `{path}` matches the rest).
    pub fn documented_5xx(&self, method: &str, path: &str) -> Vec<u16> {
        let path = path.split('?').next().unwrap_or(path);
        let Some(paths) = self.openapi["paths"].as_object() else {
            return Vec::new();
        };
        for (template, ops) in paths {
            if !template_matches(template, path) {
                continue;
            }
            let Some(responses) = ops[method.to_ascii_lowercase()]["responses"].as_object() else {
                continue;
            };
            return responses
                .keys()
                .filter_map(|k| k.parse::<u16>().ok())
                .filter(|s| *s >= 500)
                .collect();
        }
        Vec::new()
    }

    /// `GET /healthz` answers 200 `ok` (the server did not die or wedge).
    pub fn healthy(&self) -> Result<(), String> {
        self.block_on(async {
            let r = reqwest::Client::new()
                .get(format!("{}/healthz", self.server.base))
                .timeout(Duration::from_secs(10))
                .send()
                .await
                .map_err(|e| format!("/healthz: {e}"))?;
            let status = r.status().as_u16();
            let text = r.text().await.map_err(|e| format!("/healthz body: {e}"))?;
            if status == 200 && text == "ok" {
                Ok(())
            } else {
                Err(format!("/healthz answered {status}: {text}"))
            }
        })
    }
}

fn template_matches(template: &str, path: &str) -> bool {
    let t: Vec<&str> = template.split('/').collect();
    let p: Vec<&str> = path.split('/').collect();
    for (i, seg) in t.iter().enumerate() {
        if *seg == "{path}" {
            return p.len() > i;
        }
        match p.get(i) {
            Some(ps) if seg.starts_with('{') || seg == ps => {}
            _ => return false,
        }
    }
    t.len() == p.len()
}

/// An HTTP answer, read whole.
#[derive(Debug, Clone)]
pub struct Reply {
    /// Status code.
    pub status: u16,
    /// `Content-Type`, when sent.
    pub content_type: Option<String>,
    /// Body bytes.
    pub body: Vec<u8>,
}

impl Reply {
    /// The body as JSON, when it is.
    pub fn json(&self) -> Option<Value> {
        serde_json::from_slice(&self.body).ok()
    }

    /// A short description for failure messages.
    pub fn describe(&self) -> String {
        let text = String::from_utf8_lossy(&self.body);
        let cut: String = text.chars().take(400).collect();
        format!("{} ({:?}): {cut}", self.status, self.content_type)
    }

    /// An error answer (4xx/5xx) is `application/json` with a string `error` field.
    pub fn check_error_body(&self) -> Result<(), String> {
        if self.status < 400 {
            return Ok(());
        }
        let json_type = self
            .content_type
            .as_deref()
            .is_some_and(|c| c.starts_with("application/json"));
        let ok = json_type && self.json().is_some_and(|v| v["error"].is_string());
        if ok {
            Ok(())
        } else {
            Err(format!(
                "error without a JSON `error` body: {}",
                self.describe()
            ))
        }
    }
}

/// Sends one request (raw body bytes, headers as given; values that are not valid header
/// bytes are skipped) and reads the answer; `Err` when the connection fails or the
/// answer takes more than 60 s (a hang guard, not a speed check).
pub async fn send_request(
    http: &reqwest::Client,
    method: &str,
    url: &str,
    headers: &[(String, Vec<u8>)],
    body: Option<Vec<u8>>,
) -> Result<Reply, String> {
    let method = reqwest::Method::from_bytes(method.as_bytes()).map_err(|e| e.to_string())?;
    let mut req = http.request(method, url).timeout(Duration::from_secs(60));
    for (k, v) in headers {
        if let (Ok(name), Ok(value)) = (
            reqwest::header::HeaderName::from_bytes(k.as_bytes()),
            reqwest::header::HeaderValue::from_bytes(v),
        ) {
            req = req.header(name, value);
        }
    }
    if let Some(b) = body {
        req = req.body(b);
    }
    let resp = req.send().await.map_err(|e| format!("{url}: {e:?}"))?;
    let status = resp.status().as_u16();
    let content_type = resp
        .headers()
        .get(reqwest::header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .map(str::to_string);
    let body = resp
        .bytes()
        .await
        .map_err(|e| format!("{url} body: {e}"))?
        .to_vec();
    Ok(Reply {
        status,
        content_type,
        body,
    })
}

/// JSON paths (object keys) whose value may be `null` in a state frame: no dual ellipsoid
/// unless both jaws hold, no condition number at a singularity, no capture cue, exercise,
/// event or panel when there is none, no `paused_by` while the clock runs, no water `current`
/// in air (protocol.rs).
const NULLABLE_STATE_KEYS: &[&str] = &[
    "dual",
    "paused_by",
    "condition_number",
    "capture",
    "exercise",
    "last_event",
    "panel",
    "current",
    "touch",
    "visibility_m",
];

/// Checks a state frame: every number finite (serde_json writes NaN and ±∞ as `null`, so a
/// `null` outside [`NULLABLE_STATE_KEYS`] is a non-finite value).
pub fn check_state_finite(frame: &Value) -> Result<(), String> {
    fn walk(v: &Value, key: &str, path: &mut String) -> Result<(), String> {
        match v {
            Value::Null if !NULLABLE_STATE_KEYS.contains(&key) => {
                Err(format!("state frame has null (non-finite) at {path}"))
            }
            Value::Number(n) if n.as_f64().is_none_or(|f| !f.is_finite()) => {
                Err(format!("state frame has non-finite number at {path}"))
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    let len = path.len();
                    path.push_str(&format!("[{i}]"));
                    walk(x, key, path)?;
                    path.truncate(len);
                }
                Ok(())
            }
            Value::Object(o) => {
                for (k, x) in o {
                    let len = path.len();
                    path.push('.');
                    path.push_str(k);
                    walk(x, k, path)?;
                    path.truncate(len);
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
    walk(frame, "", &mut String::new())
}

/// Reads the socket until `frames` new state frames have arrived (within 5 s each): every
/// text message is JSON with a known `type`, state frames have strictly increasing `seq`
/// (above `last_seq`, which is updated) and are finite. `Err` describes what broke.
pub async fn keeps_streaming(ws: &mut Ws, last_seq: &mut u64, frames: usize) -> Result<(), String> {
    let mut seen = 0;
    while seen < frames {
        let msg = tokio::time::timeout(Duration::from_secs(5), ws.next())
            .await
            .map_err(|_| format!("no message for 5 s after seq {last_seq}"))?;
        let text = match msg {
            Some(Ok(Message::Text(t))) => t,
            Some(Ok(Message::Ping(_) | Message::Pong(_))) => continue,
            other => return Err(format!("socket ended or sent {other:?}")),
        };
        let v: Value =
            serde_json::from_str(&text).map_err(|e| format!("non-JSON message ({e}): {text}"))?;
        match v["type"].as_str() {
            Some("state") => {
                let seq = v["seq"]
                    .as_u64()
                    .ok_or_else(|| format!("state frame without seq: {text}"))?;
                if seq <= *last_seq {
                    return Err(format!("state seq {seq} after {last_seq}"));
                }
                check_state_finite(&v)?;
                *last_seq = seq;
                seen += 1;
            }
            Some("error") if v["message"].is_string() => {}
            Some("pong" | "message" | "hello" | "scenario") => {}
            _ => return Err(format!("unexpected message: {text}")),
        }
    }
    Ok(())
}
