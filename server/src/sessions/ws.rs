//! `GET /ws/sessions/{id}?token=…[&role=observer]`: the session's WebSocket.
//!
//! A reader task parses and applies client messages; a writer task sends `hello`, then the
//! latest frame whenever one is published (a client that is slow to take frames skips the
//! ones it missed: latest state wins), instructor notices and replies. Nothing a client sends
//! can stop the simulation: every bad message gets an `error` reply and the session goes on;
//! a message over 16 KiB closes the connection with 1008 (policy violation).

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

use axum::extract::ws::{CloseFrame, Message, Utf8Bytes, WebSocket, WebSocketUpgrade, close_code};
use axum::extract::{Path, Query, State};
use axum::response::{IntoResponse, Response};
use futures_util::{SinkExt, StreamExt};
use seaarms_core::sim::{LEFT, RIGHT};
use serde::Deserialize;
use tokio::sync::mpsc;

use super::record::RecordMsg;
use super::snapshot::{CARTESIAN_MAX_ANGULAR_RAD_S, CARTESIAN_MAX_LINEAR_M_S};
use super::{Live, Session};
use crate::api::wire::PoseOut;
use crate::app::AppState;
use crate::error::ApiError;
use crate::protocol::{
    ArmAxes, ArmModelOut, ClientMessage, ControlMode, Hello, MAX_CLIENT_MESSAGE_BYTES,
    ObjectModelOut, ServerMessage,
};

/// Query of the WebSocket URL.
#[derive(Debug, Deserialize)]
pub struct WsQuery {
    /// Trainee control token or instructor token.
    pub token: Option<String>,
    /// `observer` for read-only.
    pub role: Option<String>,
}

/// Who is connected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// May control the session.
    Trainee,
    /// Read-only.
    Observer,
}

/// Upgrade handler: 404 for an unknown session, 403 for a wrong or missing token.
pub async fn upgrade(
    State(state): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<WsQuery>,
    ws: WebSocketUpgrade,
) -> Response {
    let Some(session) = state.sessions.get(&id) else {
        return ApiError::not_found(format!("no live session `{id}`")).into_response();
    };
    let token = q.token.unwrap_or_default();
    let wants_observer = q.role.as_deref() == Some("observer");
    let role = if super::token_eq(&token, &session.control_token) {
        if wants_observer {
            Role::Observer
        } else {
            Role::Trainee
        }
    } else if super::token_eq(&token, &state.instructor_token) {
        Role::Observer
    } else {
        return ApiError {
            status: axum::http::StatusCode::FORBIDDEN,
            error: "wrong or missing token".into(),
            detail: None,
        }
        .into_response();
    };
    // tungstenite's 128 KiB default read buffer is re-zeroed on reads; client messages are
    // small (≤ 16 KiB), so a small buffer saves that work on every connection.
    ws.max_message_size(4 * MAX_CLIENT_MESSAGE_BYTES)
        .read_buffer_size(WS_READ_BUFFER_BYTES)
        .on_upgrade(move |socket| serve_socket(socket, state, session, role))
}

/// Read buffer of a WebSocket connection (bytes).
pub const WS_READ_BUFFER_BYTES: usize = 8 * 1024;

fn error_text(message: impl Into<String>) -> Utf8Bytes {
    let msg = ServerMessage::Error {
        message: message.into(),
    };
    serde_json::to_string(&msg).unwrap_or_default().into()
}

fn hello(session: &Session, state: &AppState, role: Role) -> Utf8Bytes {
    let live = session.live();
    let params = live.sim.params();
    let arm = |i: usize| ArmModelOut {
        model: session.models[i].spec.clone(),
        base: PoseOut::from(&params.arms[i].base),
    };
    let size = params.object.size_m;
    let msg = ServerMessage::Hello(Box::new(Hello {
        session: session.id.clone(),
        role: match role {
            Role::Trainee => "trainee",
            Role::Observer => "observer",
        },
        arms: [arm(LEFT), arm(RIGHT)],
        object: ObjectModelOut {
            size_m: [size.x, size.y, size.z],
            mass_kg: params.object.mass_kg,
        },
        seabed_z_m: params.object.seabed_z_m,
        settings: live.settings,
        scenario: session.scenario(),
        frame_hz: state.sessions.config.frame_hz,
    }));
    serde_json::to_string(&msg).unwrap_or_default().into()
}

/// What the reader asks the writer to send.
enum Outgoing {
    Text(Utf8Bytes),
    Close(u16, &'static str),
}

async fn serve_socket(socket: WebSocket, state: AppState, session: Arc<Session>, role: Role) {
    let metrics = state.metrics.clone();
    metrics.ws_clients.fetch_add(1, Ordering::Relaxed);
    if role == Role::Trainee {
        session.trainees.fetch_add(1, Ordering::Relaxed);
        session.touch();
    }
    let (mut sink, mut stream) = socket.split();
    let (reply_tx, mut reply_rx) = mpsc::channel::<Outgoing>(64);

    let writer = {
        let session = session.clone();
        let metrics = metrics.clone();
        let hello = hello(&session, &state, role);
        tokio::spawn(async move {
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
                            Outgoing::Close(close_code::NORMAL, "session ended")
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
                        Err(_) => Outgoing::Close(close_code::NORMAL, "session ended"),
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
        })
    };

    let mut limiter = RateLimiter::new(state.sessions.config.max_messages_per_second);
    let mut last_rate_notice: Option<Instant> = None;
    while let Some(Ok(msg)) = stream.next().await {
        let text = match msg {
            Message::Text(t) => t,
            Message::Binary(b) => {
                if b.len() > MAX_CLIENT_MESSAGE_BYTES {
                    let _ = reply_tx
                        .send(Outgoing::Close(close_code::POLICY, "message over 16 KiB"))
                        .await;
                    break;
                }
                metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
                let _ = reply_tx.try_send(Outgoing::Text(error_text(
                    "binary messages are not supported; send JSON text",
                )));
                continue;
            }
            Message::Close(_) => break,
            Message::Ping(_) | Message::Pong(_) => continue,
        };
        if text.len() > MAX_CLIENT_MESSAGE_BYTES {
            metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
            let _ = reply_tx
                .send(Outgoing::Close(close_code::POLICY, "message over 16 KiB"))
                .await;
            break;
        }
        if !limiter.allow() {
            metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
            if last_rate_notice.is_none_or(|t| t.elapsed().as_secs_f64() >= 1.0) {
                last_rate_notice = Some(Instant::now());
                let _ = reply_tx.try_send(Outgoing::Text(error_text(format!(
                    "too many messages: at most {} per second; extra messages are dropped",
                    state.sessions.config.max_messages_per_second
                ))));
            }
            continue;
        }
        let replies = match serde_json::from_str::<ClientMessage>(&text) {
            Ok(m) => handle(&session, &state, role, m),
            Err(e) => vec![ServerMessage::Error {
                message: format!("invalid message: {e}"),
            }],
        };
        for r in replies {
            if matches!(r, ServerMessage::Error { .. }) {
                metrics.ws_messages_rejected.fetch_add(1, Ordering::Relaxed);
            }
            let text: Utf8Bytes = serde_json::to_string(&r).unwrap_or_default().into();
            let _ = reply_tx.try_send(Outgoing::Text(text));
        }
    }
    drop(reply_tx);
    let _ = writer.await;
    metrics.ws_clients.fetch_sub(1, Ordering::Relaxed);
    if role == Role::Trainee {
        session.trainees.fetch_sub(1, Ordering::Relaxed);
        session.touch();
    }
}

/// Token bucket: `rate` messages per second, bursts of up to 2·`rate`.
struct RateLimiter {
    rate: f64,
    tokens: f64,
    last: Instant,
}

impl RateLimiter {
    fn new(rate: u32) -> RateLimiter {
        let rate = f64::from(rate.max(1));
        RateLimiter {
            rate,
            tokens: 2.0 * rate,
            last: Instant::now(),
        }
    }
    fn allow(&mut self) -> bool {
        let now = Instant::now();
        self.tokens = (self.tokens + now.duration_since(self.last).as_secs_f64() * self.rate)
            .min(2.0 * self.rate);
        self.last = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

/// Validates one arm's axes: six values (an empty list means all zero), each clamped to
/// [−1, 1]; clamping is reported.
fn arm_axes(name: &str, a: &ArmAxes, notes: &mut Vec<String>) -> Result<([f64; 6], f64), String> {
    let mut out = [0.0; 6];
    if !a.axes.is_empty() && a.axes.len() != 6 {
        return Err(format!(
            "arms.{name}.axes must have 6 values, got {}",
            a.axes.len()
        ));
    }
    for (i, v) in a.axes.iter().enumerate() {
        out[i] = clamp_unit(*v, &format!("arms.{name}.axes[{i}]"), notes);
    }
    let grip = clamp_unit(a.grip, &format!("arms.{name}.grip"), notes);
    Ok((out, grip))
}

fn clamp_unit(v: f64, what: &str, notes: &mut Vec<String>) -> f64 {
    if !v.is_finite() {
        notes.push(format!("{what} is not finite; used 0"));
        return 0.0;
    }
    if v.abs() > 1.0 {
        notes.push(format!("{what} = {v} clamped to {}", v.signum()));
        return v.signum();
    }
    v
}

fn record_event(state: &AppState, session: &Session, t: f64, event: serde_json::Value) {
    let mut e = event;
    e["t"] = serde_json::json!(t);
    state.sessions.recorder.send(RecordMsg::Event {
        id: session.id.clone(),
        json: e.to_string(),
    });
}

/// Applies one client message; returns the replies.
fn handle(
    session: &Session,
    state: &AppState,
    role: Role,
    msg: ClientMessage,
) -> Vec<ServerMessage> {
    if let ClientMessage::Ping { t } = msg {
        return vec![ServerMessage::Pong { t }];
    }
    if role == Role::Observer {
        return vec![ServerMessage::Error {
            message: "observers cannot control this session".into(),
        }];
    }
    session.touch();
    let mut notes = Vec::new();
    let mut guard = session.live();
    let live: &mut Live = &mut guard;
    let t = live.sim.time_s();
    match msg {
        ClientMessage::Input { seq, arms, object } => {
            let mut parsed = [([0.0; 6], 0.0); 2];
            for (i, (name, a)) in [("left", &arms.left), ("right", &arms.right)]
                .into_iter()
                .enumerate()
            {
                if let Some(a) = a {
                    match arm_axes(name, a, &mut notes) {
                        Ok(v) => parsed[i] = v,
                        Err(e) => return vec![ServerMessage::Error { message: e }],
                    }
                }
            }
            let mut twist = [0.0; 6];
            if let Some(o) = &object {
                if o.len() != 6 {
                    return vec![ServerMessage::Error {
                        message: format!("object must have 6 values, got {}", o.len()),
                    }];
                }
                for (i, v) in o.iter().enumerate() {
                    let f = clamp_unit(*v, &format!("object[{i}]"), &mut notes);
                    twist[i] = f * if i < 3 {
                        CARTESIAN_MAX_LINEAR_M_S
                    } else {
                        CARTESIAN_MAX_ANGULAR_RAD_S
                    };
                }
            }
            for (arm, (axes, grip)) in parsed.into_iter().enumerate() {
                match live.settings.control_mode {
                    ControlMode::Joint => {
                        live.input.arms[arm].valves = axes;
                        live.cartesian[arm] = [0.0; 6];
                    }
                    ControlMode::Cartesian => {
                        live.input.arms[arm].valves = [0.0; 6];
                        live.cartesian[arm] = axes;
                    }
                }
                live.input.arms[arm].jaw = grip;
            }
            live.input.object_velocity = twist;
            live.input_seq = live.input_seq.max(seq);
        }
        ClientMessage::Settings {
            control_mode,
            control_method,
            arm_speed,
        } => {
            if let Some(s) = arm_speed {
                if !(s.is_finite() && s > 0.0 && s <= 1.0) {
                    return vec![ServerMessage::Error {
                        message: format!("arm_speed must be in (0, 1], got {s}"),
                    }];
                }
                live.settings.arm_speed = s;
            }
            if let Some(m) = control_mode {
                live.settings.control_mode = m;
                live.cartesian = [[0.0; 6]; 2];
                for a in &mut live.input.arms {
                    a.valves = [0.0; 6];
                }
            }
            if let Some(m) = control_method {
                live.settings.control_method = m;
            }
            record_event(
                state,
                session,
                t,
                serde_json::json!({"event": "settings", "settings": live.settings}),
            );
        }
        ClientMessage::Reset => {
            reset(live);
            record_event(
                state,
                session,
                t,
                serde_json::json!({"event": "reset", "by": "trainee"}),
            );
        }
        ClientMessage::Pause => {
            live.paused = true;
            record_event(
                state,
                session,
                t,
                serde_json::json!({"event": "pause", "by": "trainee"}),
            );
        }
        ClientMessage::Resume => {
            live.paused = false;
            record_event(
                state,
                session,
                t,
                serde_json::json!({"event": "resume", "by": "trainee"}),
            );
        }
        ClientMessage::Release => {
            // Open both jaws for 1 s (7.5 cm at 10.2 cm/s takes 0.74 s, Lim Table 1-1),
            // whatever grip the sticks send meanwhile.
            live.release_until_s = t + 1.0;
            record_event(state, session, t, serde_json::json!({"event": "release"}));
        }
        ClientMessage::Ping { .. } => {}
    }
    notes
        .into_iter()
        .map(|n| ServerMessage::Error {
            message: format!("adjusted: {n}"),
        })
        .collect()
}

/// Back to the initial position (Lim §4.1): simulation reset, inputs cleared.
pub fn reset(live: &mut Live) {
    live.sim.reset();
    live.input.arms = Default::default();
    live.input.object_velocity = [0.0; 6];
    live.cartesian = [[0.0; 6]; 2];
    live.relief_recorded = 0;
}
