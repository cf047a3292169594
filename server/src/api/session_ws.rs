//! `GET /ws/sessions/{id}?token=…[&role=observer]`: the session's WebSocket.
//!
//! A reader task parses and applies client messages; a writer task sends `hello`, then the
//! latest frame whenever one is published (a client that is slow to take frames skips the
//! ones it missed: latest state wins), instructor notices and replies. Nothing a client sends
//! can stop the simulation: every bad message gets an `error` reply and the session goes on;
//! a message over [`MAX_CLIENT_MESSAGE_BYTES`] closes the connection with a close frame, code
//! 1009 (message too big). The transport accepts up to [`WS_TRANSPORT_MAX_BYTES`] so that
//! messages a little over the limit are read and refused here, with the close handshake
//! completed; beyond the transport limit the close frame is sent and the connection held
//! open for [`CLOSE_LINGER`] (unread data would make the close a TCP reset) before it drops.
//!
//! Client messages become [`Command`]s here (the WebSocket edge) and take effect through
//! [`command::apply`], like REST actions.

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use axum::extract::ws::{CloseFrame, Message, Utf8Bytes, WebSocket, WebSocketUpgrade, close_code};
use axum::extract::{Path, Query, State};
use axum::response::{IntoResponse, Response};
use futures_util::stream::{SplitSink, SplitStream};
use futures_util::{SinkExt, StreamExt};
use serde::Deserialize;
use tokio::sync::mpsc;

use crate::api::wire::PoseOut;
use crate::app::AppState;
use crate::auth::{Actor, Credentials, TokenFrom};
use crate::error::ApiError;
use crate::metrics::Metrics;
use crate::protocol::{
    ArmModelOut, ClientMessage, Hello, MAX_CLIENT_MESSAGE_BYTES, ObjectModelOut, ScenarioOut,
    SceneOut, ServerMessage,
};
use crate::sessions::admission::TokenBucket;
use crate::sessions::command::{self, Arm, Command};
use crate::sessions::{Live, Session, SessionConfig};

/// Largest message (and frame) the WebSocket transport reads (bytes): 4 × the documented
/// limit, so oversize messages up to here are read whole and refused with a clean close.
pub const WS_TRANSPORT_MAX_BYTES: usize = 4 * MAX_CLIENT_MESSAGE_BYTES;
/// After closing for a message over the transport limit, how long the connection is held
/// (without reading) so the client receives the close frame before the socket drops.
pub const CLOSE_LINGER: Duration = Duration::from_secs(1);
/// After closing for any other reason, how long the peer's close frame is awaited.
pub const CLOSE_HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(2);
/// Close code 1009, "message too big" (RFC 6455 §7.4.1).
pub const CLOSE_TOO_BIG: u16 = close_code::SIZE;

/// Query of the WebSocket URL (the token is read by [`Credentials`]).
#[derive(Debug, Deserialize)]
pub struct WsQuery {
    /// `observer` for read-only.
    pub role: Option<String>,
}

/// Upgrade handler: 404 for an unknown session, 403 for a wrong or missing token.
pub async fn upgrade(
    State(state): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<WsQuery>,
    creds: Credentials,
    ws: WebSocketUpgrade,
) -> Response {
    let Some(session) = state.sessions.get(&id) else {
        return crate::cluster::elsewhere(&state, &id)
            .await
            .unwrap_or_else(|| ApiError::not_found(format!("no live session `{id}`")))
            .into_response();
    };
    let wants_observer = q.role.as_deref() == Some("observer");
    let role = match creds
        .principal(
            &state,
            TokenFrom::Query,
            Some((&session.id, &session.control_token)),
        )
        .and_then(|p| p.on_socket(wants_observer))
    {
        Ok(role) => role,
        Err(e) => return e.into_response(),
    };
    // tungstenite's 128 KiB default read buffer is re-zeroed on reads; client messages are
    // small (≤ 16 KiB), so a small buffer saves that work on every connection.
    ws.max_message_size(WS_TRANSPORT_MAX_BYTES)
        .max_frame_size(WS_TRANSPORT_MAX_BYTES)
        .read_buffer_size(WS_READ_BUFFER_BYTES)
        .on_upgrade(move |socket| serve_socket(socket, state, session, role))
}

/// Read buffer of a WebSocket connection (bytes).
pub const WS_READ_BUFFER_BYTES: usize = 8 * 1024;

/// The `error` message with `message`.
pub(crate) fn error_text(message: impl Into<String>) -> Utf8Bytes {
    let msg = ServerMessage::Error {
        message: message.into(),
    };
    serde_json::to_string(&msg).unwrap_or_default().into()
}

fn hello(session: &Session, state: &AppState, role: Actor) -> Utf8Bytes {
    let mut hello = hello_for(
        &session.id,
        role.as_str(),
        &session.live(),
        &state.sessions.config,
    );
    hello.replica = Some(state.cluster.name.clone());
    serde_json::to_string(&ServerMessage::Hello(Box::new(hello)))
        .unwrap_or_default()
        .into()
}

/// The `hello` of session `id` in state `live` (a live session's, or a replay's).
pub fn hello_for(id: &str, role: &'static str, live: &Live, config: &SessionConfig) -> Hello {
    let params = live.sim().params();
    let models = live.models();
    let arm = |arm: Arm| ArmModelOut {
        model: models[arm.index()].spec.clone(),
        base: PoseOut::from(&params.arms[arm.index()].base),
    };
    let size = params.object.size_m;
    Hello {
        session: id.to_string(),
        role,
        arms: Arm::BOTH.map(arm),
        object: ObjectModelOut {
            size_m: [size.x, size.y, size.z],
            mass_kg: params.object.mass_kg,
        },
        seabed_z_m: params.object.seabed_z_m,
        settings: live.settings(),
        scenario: live.scenario().name().to_string(),
        frame_hz: config.frame_hz,
        max_messages_per_second: config.max_messages_per_second,
        scenarios: crate::catalogue::LIVE_SCENARIOS
            .iter()
            .map(|&(name, description)| ScenarioOut { name, description })
            .collect(),
        exercise: live.scenario().exercise().cloned(),
        scene: SceneOut::new(params, live.scenario().exercise().map(|e| &**e)),
        replica: None,
        replay: None,
    }
}

/// The `ended` message, once the session has ended (sent right before the close frame).
fn ended_text(session: &Session) -> Option<Utf8Bytes> {
    let reason = *session.end_reason.get()?;
    serde_json::to_string(&ServerMessage::ended(reason))
        .ok()
        .map(Utf8Bytes::from)
}

/// What the reader asks the writer to send.
enum Outgoing {
    Text(Utf8Bytes),
    Close(u16, String),
}

/// How a connection's reading ended, after the server sent a close frame or not.
enum Ending {
    /// The peer closed or went away; nothing more to do.
    Plain,
    /// We closed after reading a whole message: the peer's close frame is awaited.
    AwaitPeerClose,
    /// The transport refused a message and nothing more may be read: the connection is held
    /// for [`CLOSE_LINGER`] so the close frame arrives before the socket drops.
    Linger,
}

/// Whether a read error is the transport's size limit (tungstenite's `Capacity` error).
fn is_capacity_error(e: &axum::Error) -> bool {
    std::error::Error::source(e)
        .and_then(|inner| inner.downcast_ref::<tokio_tungstenite::tungstenite::Error>())
        .is_some_and(|e| matches!(e, tokio_tungstenite::tungstenite::Error::Capacity(_)))
}

/// Reads (and drops) what the peer still sends until its close frame arrives, the stream
/// ends or [`CLOSE_HANDSHAKE_TIMEOUT`] passes (the transport limit bounds each message).
async fn await_peer_close(stream: &mut SplitStream<WebSocket>) {
    let _ = tokio::time::timeout(CLOSE_HANDSHAKE_TIMEOUT, async {
        while let Some(Ok(msg)) = stream.next().await {
            if matches!(msg, Message::Close(_)) {
                break;
            }
        }
    })
    .await;
}

/// One WebSocket connection: a writer task sends the hello, frames, notices and replies; this
/// task reads the client's messages until it stops, then closes the connection cleanly.
async fn serve_socket(socket: WebSocket, state: AppState, session: Arc<Session>, role: Actor) {
    let metrics = state.metrics.clone();
    connected(&metrics, &session, role);
    let (sink, mut stream) = socket.split();
    let (reply_tx, reply_rx) = mpsc::channel::<Outgoing>(64);
    let hello = hello(&session, &state, role);
    let writer = tokio::spawn(write_loop(
        sink,
        session.clone(),
        metrics.clone(),
        hello,
        reply_rx,
    ));
    let ending = read_loop(&mut stream, &state, &session, role, &reply_tx).await;
    drop(reply_tx);
    let _ = writer.await;
    match ending {
        Ending::Linger => tokio::time::sleep(CLOSE_LINGER).await,
        Ending::AwaitPeerClose => await_peer_close(&mut stream).await,
        Ending::Plain => {}
    }
    disconnected(&metrics, &session, role);
}

/// Counts a new connection (and a trainee joining its session).
fn connected(metrics: &Metrics, session: &Session, role: Actor) {
    metrics.ws_clients.fetch_add(1, Ordering::Relaxed);
    if role == Actor::Trainee {
        session.trainees.fetch_add(1, Ordering::Relaxed);
        session.joined.store(true, Ordering::Relaxed);
        session.touch();
    }
}

/// Counts a connection gone (and a trainee leaving its session).
fn disconnected(metrics: &Metrics, session: &Session, role: Actor) {
    metrics.ws_clients.fetch_sub(1, Ordering::Relaxed);
    if role == Actor::Trainee {
        // The last one out starts the abandon grace (SessionManager::expire_idle).
        if session.trainees.fetch_sub(1, Ordering::Relaxed) == 1 {
            session.trainee_left();
        }
        session.touch();
    }
}

/// The writer: sends `hello`, then the latest frame whenever it changes (a slow client skips
/// frames, counted in `frames_skipped`), notices and the reader's replies, until the session
/// ends (then the `ended` message and the close frame), the reader is done or the client is gone.
async fn write_loop(
    mut sink: SplitSink<WebSocket, Message>,
    session: Arc<Session>,
    metrics: Arc<Metrics>,
    hello: Utf8Bytes,
    mut reply_rx: mpsc::Receiver<Outgoing>,
) {
    if sink.send(Message::Text(hello)).await.is_err() {
        return;
    }
    let mut frames = session.frames.subscribe();
    let mut notices = session.notices.subscribe();
    let mut last_seq: Option<u64> = None;
    // A late joiner gets the current snapshot at once.
    frames.mark_changed();
    loop {
        let out = tokio::select! {
            changed = frames.changed() => {
                if changed.is_err() || session.ended.load(Ordering::Relaxed) {
                    Outgoing::Close(close_code::NORMAL, "session ended".into())
                } else {
                    let frame = frames.borrow_and_update().clone();
                    let Some(frame) = frame else { continue };
                    if let Some(prev) = last_seq {
                        if frame.seq > prev + 1 {
                            metrics.frames_skipped.fetch_add(frame.seq - prev - 1, Ordering::Relaxed);
                        }
                    }
                    last_seq = Some(frame.seq);
                    metrics.frames_sent.fetch_add(1, Ordering::Relaxed);
                    Outgoing::Text(frame.json)
                }
            }
            notice = notices.recv() => match notice {
                Ok(text) => Outgoing::Text(text),
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => continue,
                Err(_) => Outgoing::Close(close_code::NORMAL, "session ended".into()),
            },
            reply = reply_rx.recv() => match reply {
                Some(r) => r,
                None => break,
            },
        };
        match out {
            Outgoing::Text(t) => {
                if sink.send(Message::Text(t)).await.is_err() {
                    break;
                }
            }
            Outgoing::Close(code, reason) => {
                if let Some(text) = ended_text(&session) {
                    let _ = sink.send(Message::Text(text)).await;
                }
                let _ = sink
                    .send(Message::Close(Some(CloseFrame {
                        code,
                        reason: reason.into(),
                    })))
                    .await;
                break;
            }
        }
    }
}

/// A connection's message rate limit: a token bucket allowing bursts of up to two seconds'
/// worth of messages, and at most one notice a second about dropped ones. The session and
/// replay sockets both use it.
pub(crate) struct RateLimit {
    bucket: TokenBucket,
    per_second: u32,
    last_notice: Option<Instant>,
}

impl RateLimit {
    pub(crate) fn new(per_second: u32) -> RateLimit {
        let rate = f64::from(per_second.max(1));
        RateLimit {
            bucket: TokenBucket::new(2.0 * rate, rate, Instant::now()),
            per_second,
            last_notice: None,
        }
    }

    /// Takes a token for one message: `Ok` if within the limit, else `Err` with the notice to
    /// send the client, if one is due.
    pub(crate) fn admit(&mut self) -> Result<(), Option<Utf8Bytes>> {
        if self.bucket.try_take(Instant::now()) {
            return Ok(());
        }
        if self
            .last_notice
            .is_some_and(|t| t.elapsed().as_secs_f64() < 1.0)
        {
            return Err(None);
        }
        self.last_notice = Some(Instant::now());
        Err(Some(error_text(format!(
            "too many messages: at most {} per second; extra messages are dropped",
            self.per_second
        ))))
    }
}

/// Whether a message is over [`MAX_CLIENT_MESSAGE_BYTES`] (read whole: under the transport
/// limit).
fn is_oversize(item: &Result<Message, axum::Error>) -> bool {
    match item {
        Ok(Message::Text(t)) => t.len() > MAX_CLIENT_MESSAGE_BYTES,
        Ok(Message::Binary(b)) => b.len() > MAX_CLIENT_MESSAGE_BYTES,
        Ok(_) | Err(_) => false,
    }
}

/// The reader: takes the client's messages until it closes, goes away or sends one too big,
/// handing replies to the writer; returns how the reading ended.
async fn read_loop(
    stream: &mut SplitStream<WebSocket>,
    state: &AppState,
    session: &Session,
    role: Actor,
    reply_tx: &mpsc::Sender<Outgoing>,
) -> Ending {
    let metrics = &state.metrics;
    let mut rate = RateLimit::new(state.sessions.config.max_messages_per_second);
    while let Some(item) = stream.next().await {
        // Over the documented limit: read whole (under the transport limit) and the close
        // handshake completed, or refused by the transport (nothing more can be read).
        let oversize = is_oversize(&item);
        if oversize || item.as_ref().err().is_some_and(is_capacity_error) {
            metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
            let too_big = format!("message over {} KiB", MAX_CLIENT_MESSAGE_BYTES / 1024);
            let _ = reply_tx.send(Outgoing::Close(CLOSE_TOO_BIG, too_big)).await;
            return if oversize {
                Ending::AwaitPeerClose
            } else {
                Ending::Linger
            };
        }
        let text = match item {
            Ok(Message::Text(t)) => t,
            Ok(Message::Binary(_)) => {
                metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
                let _ = reply_tx.try_send(Outgoing::Text(error_text(
                    "binary messages are not supported; send JSON text",
                )));
                continue;
            }
            Ok(Message::Ping(_) | Message::Pong(_)) => continue,
            Ok(Message::Close(_)) | Err(_) => break,
        };
        if let Err(notice) = rate.admit() {
            metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
            if let Some(notice) = notice {
                let _ = reply_tx.try_send(Outgoing::Text(notice));
            }
            continue;
        }
        reply(&text, state, session, role, reply_tx);
    }
    Ending::Plain
}

/// Parses and handles one client message, handing the replies to the writer (errors counted
/// as rejected messages).
fn reply(
    text: &str,
    state: &AppState,
    session: &Session,
    role: Actor,
    reply_tx: &mpsc::Sender<Outgoing>,
) {
    let replies = match serde_json::from_str::<ClientMessage>(text) {
        Ok(m) => handle(session, state, role, m),
        Err(e) => vec![ServerMessage::Error {
            message: format!("invalid message: {e}"),
        }],
    };
    for r in replies {
        if matches!(r, ServerMessage::Error { .. }) {
            state
                .metrics
                .ws_messages_rejected
                .fetch_add(1, Ordering::Relaxed);
        }
        let text: Utf8Bytes = serde_json::to_string(&r).unwrap_or_default().into();
        let _ = reply_tx.try_send(Outgoing::Text(text));
    }
}

/// Handles one client message; returns the replies.
fn handle(
    session: &Session,
    state: &AppState,
    role: Actor,
    msg: ClientMessage,
) -> Vec<ServerMessage> {
    if let ClientMessage::Ping { t } = msg {
        return vec![ServerMessage::Pong { t }];
    }
    let mut notes = Vec::new();
    let result = Command::from_client(msg, &mut notes)
        .and_then(|c| command::apply(&state.sessions, session, role, c).map_err(|e| e.to_string()));
    match result {
        Ok(()) => notes
            .into_iter()
            .map(|n| ServerMessage::Error {
                message: format!("adjusted: {n}"),
            })
            .collect(),
        Err(message) => vec![ServerMessage::Error { message }],
    }
}
