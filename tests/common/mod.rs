//! Shared by the integration tests: a server on port 0 (the library's `run`, as `main`
//! uses it), session creation, WebSocket connection and reading helpers.

#![allow(clippy::unwrap_used, dead_code, unreachable_pub)]

use std::path::PathBuf;
use std::time::{Duration, Instant};

use futures_util::StreamExt;
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

pub fn temp_dir() -> PathBuf {
    std::env::temp_dir().join(format!(
        "seaarms-sessions-{}",
        seaarms::sessions::random_hex(6)
    ))
}

pub async fn start_with(
    dir: PathBuf,
    tweak: impl FnOnce(&mut seaarms::config::ServeConfig),
) -> Server {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let mut config = seaarms::config::ServeConfig {
        data_dir: dir,
        instructor_token: Some(TEACHER.into()),
        ..Default::default()
    };
    tweak(&mut config);
    let state = seaarms::app::AppState::new(&config).unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let done = tokio::spawn(async move {
        seaarms::run(listener, state, async {
            let _ = rx.await;
        })
        .await
        .unwrap();
    });
    Server {
        base: format!("http://{addr}"),
        stop: Some(tx),
        done: Some(done),
    }
}

pub async fn start() -> Server {
    start_with(temp_dir(), |_| {}).await
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
