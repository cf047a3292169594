//! Attempts: their records (from [`crate::db`]) and their replay ([`crate::replay`]).
//!
//! * `GET /api/attempts` (instructor): filtered by trainee, group, exercise or session,
//!   newest first.
//! * `GET /api/attempts/{id}`: the record with its events; `…/inputs`: the decoded input
//!   log; `…/replay?t=`: the state frame at t.
//! * `GET /ws/replay/{id}`: a replay streamed at the frame rate, with play, pause, seek and
//!   speed (0.25–8×).
//!
//! The instructor token sees every attempt; a session's control token sees that session's
//! attempts, also after the session ended (the database keeps the token's SHA-256).
//! Re-simulation runs on blocking threads, one request at a time per connection, and at most
//! [`MAX_REPLAYS`] replay sockets at once; every replay starts its seeks from the server's
//! shared checkpoints ([`crate::replay::checkpoints`], `AppState::replays`), so a seek
//! re-simulates at most one checkpoint interval once an earlier replay has passed there.

use std::sync::{Arc, LazyLock};
use std::time::Duration;

use axum::Json;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use futures_util::{SinkExt, StreamExt};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use tokio::sync::Semaphore;

use crate::api::session_ws::{RateLimit, error_text};
use crate::api::sessions::{admit, create_error, created};
use crate::app::AppState;
use crate::auth::{Credentials, MISSING_TOKEN_OR_QUERY, Principal, TokenFrom, WRONG_TOKEN};
use crate::compute::{Cancel, ComputeError, ComputePool};
use crate::db::{AttemptFilter, AttemptRow, EventRow, unavailable as db_error};
use crate::error::ApiError;
use crate::protocol::{MAX_CLIENT_MESSAGE_BYTES, ReplayClientMessage, ReplayOut, ServerMessage};
use crate::replay::checkpoints::CHECKPOINT_INTERVAL_STEPS;
use crate::replay::{Init, MAX_TAKE_OVERS, Replay, ReplayError, check_version, log, splice};
use crate::security::ws_base;
use crate::sessions::admission::Peer;

/// Most replay WebSockets open at once (each may re-simulate on a blocking thread).
pub const MAX_REPLAYS: usize = 32;
/// Slowest and fastest replay speeds.
pub const SPEED_RANGE: (f64, f64) = (0.25, 8.0);
/// Most attempts one listing returns.
pub const MAX_LIST: usize = 1000;

/// Replay sockets kept for the instructor: a trainee's token never takes the last ones.
pub const INSTRUCTOR_RESERVE: usize = 4;
/// Replay sockets one trainee (one session's token) may hold at once.
pub const REPLAYS_PER_TRAINEE: usize = 2;
/// A replay socket with no message from its client for this long while paused is closed.
pub const REPLAY_IDLE: Duration = Duration::from_secs(600);

static REPLAY_SLOTS: LazyLock<Semaphore> = LazyLock::new(|| Semaphore::new(MAX_REPLAYS));

/// Who holds replay sockets and re-simulations (by principal: `instructor` or the session id
/// of a trainee's token), so one trainee cannot take every slot (issue 29).
static HOLDERS: LazyLock<std::sync::Mutex<std::collections::HashMap<String, usize>>> =
    LazyLock::new(Default::default);

/// One principal's hold on a replay socket or a seek; released when dropped.
pub(crate) struct Held(String);

impl Drop for Held {
    fn drop(&mut self) {
        let mut h = HOLDERS.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(n) = h.get_mut(&self.0) {
            *n -= 1;
            if *n == 0 {
                h.remove(&self.0);
            }
        }
    }
}

/// Takes one of `key`'s at most `max` holds (429 beyond).
pub(crate) fn hold(key: &str, max: usize, what: &str) -> Result<Held, ApiError> {
    let mut h = HOLDERS.lock().unwrap_or_else(|e| e.into_inner());
    let n = h.entry(key.to_string()).or_insert(0);
    if *n >= max {
        return Err(ApiError::new(
            StatusCode::TOO_MANY_REQUESTS,
            format!("at most {max} {what} at once per trainee; close one first"),
        ));
    }
    *n += 1;
    Ok(Held(key.to_string()))
}

/// The principal key of `creds` for attempt `row` (`instructor`, or `trainee:<session>`).
fn holder_key(state: &AppState, creds: &Credentials, row: &AttemptRow) -> Result<String, ApiError> {
    Ok(if is_instructor(state, creds)? {
        "instructor".to_string()
    } else {
        format!("trainee:{}", row.session)
    })
}

/// The attempts routes read the token from the header, else the query.
pub(crate) const FROM: TokenFrom = TokenFrom::BearerOrQuery;

pub(crate) fn is_instructor(state: &AppState, creds: &Credentials) -> Result<bool, ApiError> {
    Ok(creds.principal(state, FROM, None)?.is_instructor())
}

/// The attempt, if `creds` may see it (the instructor, or the trainee of its session): 403
/// for a wrong token, 404 for an unknown id (after the token check for the instructor, so
/// ids are not probed without one).
pub(crate) async fn authorized(
    state: &AppState,
    creds: &Credentials,
    id: &str,
) -> Result<AttemptRow, ApiError> {
    if !creds.presented(FROM)? {
        return Err(ApiError::forbidden(MISSING_TOKEN_OR_QUERY));
    }
    let not_found = || ApiError::not_found(format!("no attempt `{id}`"));
    if !crate::sessions::record::valid_id(id) {
        return Err(not_found());
    }
    let row = state.db.attempt(id).await.map_err(db_error)?;
    if is_instructor(state, creds)? {
        return row.ok_or_else(not_found);
    }
    let Some(row) = row else {
        return Err(ApiError::forbidden(WRONG_TOKEN));
    };
    match creds.principal_stored(state, FROM, &row.session).await? {
        Principal::Trainee { .. } => Ok(row),
        _ => Err(ApiError::forbidden(WRONG_TOKEN)),
    }
}

/// A trainee opens an attempt's inputs and replay once it has ended (a running drill's
/// silent fault is in them) and while no silent fault of the instructor's acts on its live
/// session (a `persistent` one carries over from an ended attempt); the instructor at any time.
pub(crate) fn check_open(
    state: &AppState,
    creds: &Credentials,
    row: &AttemptRow,
) -> Result<(), ApiError> {
    if is_instructor(state, creds)? {
        return Ok(());
    }
    if row.outcome.is_none() {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "the attempt is still running; its replay opens when it ends",
        ));
    }
    if silent_fault_active(state, &row.session) {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "the session has a fault the instructor keeps hidden; this replay opens when it is cleared",
        ));
    }
    Ok(())
}

/// The live session `session` has a silent fault active.
fn silent_fault_active(state: &AppState, session: &str) -> bool {
    state
        .sessions
        .get(session)
        .is_some_and(|s| s.live().faults().iter().any(|f| f.silent))
}

/// An attempt on the wire: the record (without its initial conditions), whether it can be
/// replayed here, and its links.
#[derive(Debug, Serialize)]
pub struct AttemptOut {
    #[serde(flatten)]
    row: AttemptRow,
    replayable: bool,
    replay_note: Option<String>,
    links: Value,
    #[serde(skip_serializing_if = "Option::is_none")]
    events: Option<Vec<EventRow>>,
}

impl AttemptOut {
    fn new(mut row: AttemptRow, events: Option<Vec<EventRow>>) -> AttemptOut {
        let note = check_version(&row.sim_version).err().map(|e| e.to_string());
        let links = json!({
            "self": format!("/api/attempts/{}", row.id),
            "replay": format!("/replay/{}", row.id),
            "inputs": format!("/api/attempts/{}/inputs", row.id),
            "csv": format!("/api/sessions/{}/log.csv", row.session),
        });
        row.init = Value::Null;
        AttemptOut {
            row,
            replayable: note.is_none(),
            replay_note: note,
            links,
            events,
        }
    }
}

/// Query of `GET /api/attempts`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ListQuery {
    trainee: Option<String>,
    group: Option<String>,
    exercise: Option<String>,
    session: Option<String>,
    limit: Option<usize>,
    /// Read by [`Credentials`]; listed so that it is a known field.
    #[allow(dead_code)]
    token: Option<String>,
}

/// `GET /api/attempts` (instructor).
pub async fn list(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<ListQuery>,
) -> Result<Json<Value>, ApiError> {
    if !is_instructor(&state, &creds)? {
        return Err(ApiError::forbidden("instructor token required"));
    }
    let filter = AttemptFilter {
        trainee: q.trainee,
        group: q.group,
        exercise: q.exercise,
        session: q.session,
        limit: q.limit.unwrap_or(MAX_LIST).clamp(1, MAX_LIST),
        without_practice: false,
    };
    let rows = state.db.attempts(&filter).await.map_err(db_error)?;
    let out: Vec<AttemptOut> = rows.into_iter().map(|r| AttemptOut::new(r, None)).collect();
    Ok(Json(json!({ "attempts": out })))
}

/// `GET /api/attempts/{id}`: the record, its assessment and its events.
pub async fn get(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Json<AttemptOut>, ApiError> {
    let row = authorized(&state, &creds, &id).await?;
    let mut events = state.db.attempt_events(&id).await.map_err(db_error)?;
    // A silent fault stays hidden from the trainee while the attempt runs (a drill), and while
    // one acts on the session (a persistent one outlives the attempt that injected it).
    if (row.outcome.is_none() || silent_fault_active(&state, &row.session))
        && !is_instructor(&state, &creds)?
    {
        events.retain(|e| e.detail.get("silent") != Some(&Value::Bool(true)));
    }
    Ok(Json(AttemptOut::new(row, Some(events))))
}

/// `GET /api/attempts/{id}/inputs`: the initial conditions and the decoded input log.
pub async fn inputs(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
) -> Result<Json<Value>, ApiError> {
    let row = authorized(&state, &creds, &id).await?;
    check_open(&state, &creds, &row)?;
    let bytes = state.db.attempt_inputs(&id).await.map_err(db_error)?;
    let entries = log::decode(&bytes).map_err(|e| {
        ApiError::new(
            StatusCode::CONFLICT,
            format!("the input log is damaged: {e}"),
        )
    })?;
    Ok(Json(json!({
        "format": log::FORMAT,
        "sim_version": row.sim_version,
        "init": row.init,
        "input_quantum": log::INPUT_QUANTUM,
        "bytes": bytes.len(),
        "entries": entries,
    })))
}

/// 409: the attempt cannot be replayed here, and why.
fn conflict(e: ReplayError) -> ApiError {
    ApiError::new(StatusCode::CONFLICT, e.to_string())
}

/// Builds the replay of an attempt (409 when it cannot be replayed here).
pub(crate) async fn load(state: &AppState, row: &AttemptRow) -> Result<Replay, ApiError> {
    Ok(load_chain(state, row).await?.0)
}

/// [`load`], with the number of take-overs between the attempt and the first of its chain.
async fn load_chain(state: &AppState, row: &AttemptRow) -> Result<(Replay, usize), ApiError> {
    // A running attempt: what the recorder has written so far (whole seconds).
    let duration_s = if row.ended_unix.is_some() {
        row.sim_seconds
    } else {
        let sessions = state.sessions.clone();
        tokio::task::spawn_blocking(move || sessions.recorder.flush())
            .await
            .ok();
        state.sessions.get(&row.session).map_or(0.0, |s| {
            let live = s.live();
            if live.attempt_id() == row.id {
                live.sim().time_s().floor()
            } else {
                0.0
            }
        })
    };
    let (init, entries, links) = record(state, row).await?;
    let models = [state.sessions.magnum(), state.sessions.magnum()];
    let replay = Replay::shared(
        &models,
        init,
        entries,
        duration_s,
        state.replays.clone(),
        &row.id,
    )
    .map_err(conflict)?;
    Ok((replay, links))
}

/// What replays `row` (409 when it cannot be replayed here): its initial conditions and log,
/// or for a practice attempt its source's, followed to the first attempt of the chain
/// ([`crate::replay::splice`]; at most [`MAX_TAKE_OVERS`] take-overs).
/// Also the number of take-overs followed.
async fn record(
    state: &AppState,
    row: &AttemptRow,
) -> Result<(Init, Vec<log::Entry>, usize), ApiError> {
    check_version(&row.sim_version).map_err(conflict)?;
    let mut init = parse_init(row)?;
    let mut entries = inputs_of(state, &row.id).await?;
    let mut links = 0;
    while let Some(from) = init.from.take() {
        links += 1;
        if links > MAX_TAKE_OVERS {
            return Err(conflict(ReplayError::Record(format!(
                "it is more than {MAX_TAKE_OVERS} take-overs from an attempt started afresh"
            ))));
        }
        let source = state
            .db
            .attempt(&from.attempt)
            .await
            .map_err(db_error)?
            .ok_or_else(|| {
                conflict(ReplayError::Record(format!(
                    "it was taken over from attempt `{}`, whose record is gone",
                    from.attempt
                )))
            })?;
        check_version(&source.sim_version).map_err(conflict)?;
        init = parse_init(&source)?;
        entries = splice(inputs_of(state, &source.id).await?, from.step, entries);
    }
    Ok((init, entries, links))
}

/// An attempt's initial conditions (409 when unreadable or of another log format).
fn parse_init(row: &AttemptRow) -> Result<Init, ApiError> {
    let init: Init = serde_json::from_value(row.init.clone())
        .map_err(|e| conflict(ReplayError::Record(format!("initial conditions: {e}"))))?;
    if init.format != log::FORMAT {
        return Err(conflict(ReplayError::Record(format!(
            "log format {} (this server reads {})",
            init.format,
            log::FORMAT
        ))));
    }
    Ok(init)
}

/// An attempt's decoded input log (409 when damaged).
async fn inputs_of(state: &AppState, id: &str) -> Result<Vec<log::Entry>, ApiError> {
    let bytes = state.db.attempt_inputs(id).await.map_err(db_error)?;
    log::decode(&bytes).map_err(|e| conflict(ReplayError::Record(e.to_string())))
}

/// Query of `GET /api/attempts/{id}/replay`.
#[derive(Debug, Default, Deserialize)]
pub struct ReplayQuery {
    t: Option<f64>,
}

/// `GET /api/attempts/{id}/replay?t=`: the state frame at t (s since the attempt's start,
/// clamped to its length), re-simulated from the record.
pub async fn replay_at(
    State(state): State<AppState>,
    creds: Credentials,
    Path(id): Path<String>,
    Query(q): Query<ReplayQuery>,
) -> Result<Response, ApiError> {
    let t = q.t.unwrap_or(0.0);
    if !t.is_finite() {
        return Err(ApiError::bad_request(
            "`t` must be a finite number of seconds",
        ));
    }
    let row = authorized(&state, &creds, &id).await?;
    check_open(&state, &creds, &row)?;
    let key = holder_key(&state, &creds, &row)?;
    // One re-simulation at a time per trainee; the instructor's are not limited here.
    let _held = if key == "instructor" {
        None
    } else {
        Some(hold(&format!("{key}:seek"), 1, "replay seeks")?)
    };
    let mut replay = load(&state, &row).await?;
    // On the compute pool: its low priority keeps the live sessions' frames on time, its
    // queue bounds the load (503), its deadline the time (504), and a client that goes away
    // cancels the seek within a simulated second.
    let json = state
        .compute
        .run(move |cancel| {
            replay
                .seek_checked(t, &|| cancel.check().is_ok())
                .map_err(|e| pool_error(e, cancel))?;
            Ok(state_text(&mut replay))
        })
        .await
        .map_err(|e| e.api_error())?;
    Ok((
        [(header::CONTENT_TYPE, "application/json")],
        json.to_string(),
    )
        .into_response())
}

/// Body of `POST /api/attempts/{id}/take-over`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TakeOverRequest {
    /// Seconds since the attempt's start (0 to its length; the nearest step).
    t: f64,
}

/// `POST /api/attempts/{id}/take-over` `{"t": s}` ("take over from here", issue 30 item 5):
/// a new session for the attempt's trainee (name and group) whose first attempt is a
/// practice attempt starting from the attempt's replayed state at `t`, waiting for `ready`;
/// answered like `POST /api/sessions` (201, the trainee's cookie). Who may: whoever may
/// replay the attempt (the instructor, or its session's trainee once it ended). 400 for a
/// `t` that is not in [0, length]; 409 for an attempt that cannot be replayed here, or that
/// is not an exercise (free play has no `ready` to wait for, so its first frame would not be
/// the state at `t`, and no assessment to practise); the admission limits of
/// `POST /api/sessions` (429, 503); the seek's of `GET …/replay` (503 busy, 504 too long).
pub async fn take_over(
    State(state): State<AppState>,
    Peer(peer): Peer,
    creds: Credentials,
    headers: HeaderMap,
    Path(id): Path<String>,
    body: axum::body::Bytes,
) -> Result<Response, ApiError> {
    let req: TakeOverRequest = crate::json::parse(&body)?;
    if !req.t.is_finite() || req.t < 0.0 {
        return Err(ApiError::bad_request(
            "`t` must be a finite, non-negative number of seconds",
        ));
    }
    let row = authorized(&state, &creds, &id).await?;
    check_open(&state, &creds, &row)?;
    if row.exercise.is_none() {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "only an exercise attempt can be taken over (free play has no exercise to practise)",
        ));
    }
    let source_init = parse_init(&row)?;
    let (mut replay, links) = load_chain(&state, &row).await?;
    if links >= MAX_TAKE_OVERS {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            format!(
                "this practice attempt is already {links} take-overs from an attempt started \
                 afresh, the most that replay follows; take over from an earlier one"
            ),
        ));
    }
    if Replay::step_at(req.t) > Replay::step_at(replay.duration_s()) {
        return Err(ApiError::bad_request(format!(
            "`t` = {} s is beyond the attempt's length, {} s",
            req.t,
            replay.duration_s()
        )));
    }
    let step = Replay::step_at(req.t);
    let base = ws_base(&state.policy, &headers, peer.as_ref())
        .ok_or_else(|| ApiError::bad_request("missing or malformed Host header"))?;
    let instructor = is_instructor(&state, &creds)?;
    let client = match admit(&state, peer.as_ref(), &headers, instructor) {
        Ok(client) => client,
        Err(resp) => return Ok(*resp),
    };
    let key = holder_key(&state, &creds, &row)?;
    let _held = if instructor {
        None
    } else {
        Some(hold(&format!("{key}:seek"), 1, "replay seeks")?)
    };
    // The seek runs on the compute pool, as `GET …/replay` does (its checkpoints shared).
    let start = state
        .compute
        .run(move |cancel| {
            replay
                .seek_step_checked(step, &|| cancel.check().is_ok())
                .map_err(|e| pool_error(e, cancel))?;
            Ok(replay.live().checkpoint())
        })
        .await
        .map_err(|e| e.api_error())?;
    let init = Init {
        from: Some(log::Source {
            attempt: row.id.clone(),
            step,
        }),
        ..source_init
    };
    let sessions = state.sessions.clone();
    let (label, group) = (row.trainee.clone(), row.group.clone());
    let session = tokio::task::spawn_blocking(move || {
        sessions.create_taking_over(client, start, &init, &label, &group)
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
    .map_err(create_error)?;
    created(&state, &session, &base).await
}

/// A seek's error on the compute pool: a cancelled seek is the pool's (deadline, or the
/// request went away), any other the record's (409).
pub(crate) fn pool_error(e: ReplayError, cancel: &Cancel) -> ComputeError {
    match e {
        ReplayError::Cancelled => cancel.check().err().unwrap_or(ComputeError::Failed),
        e => conflict(e).into(),
    }
}

fn state_text(replay: &mut Replay) -> Utf8Bytes {
    let frame = replay.frame();
    serde_json::to_string(&ServerMessage::State(Box::new(frame)))
        .unwrap_or_default()
        .into()
}

/// `GET /ws/replay/{id}?token=`: the replay WebSocket (see the module doc and docs/api.md).
pub async fn replay_ws(
    State(state): State<AppState>,
    Path(id): Path<String>,
    creds: Credentials,
    ws: WebSocketUpgrade,
) -> Result<Response, ApiError> {
    let row = authorized(&state, &creds, &id).await?;
    check_open(&state, &creds, &row)?;
    let key = holder_key(&state, &creds, &row)?;
    let instructor = key == "instructor";
    // A trainee's token leaves the last INSTRUCTOR_RESERVE sockets to the instructor.
    if !instructor && REPLAY_SLOTS.available_permits() <= INSTRUCTOR_RESERVE {
        return Err(ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            format!(
                "{} replays are open; try again shortly",
                MAX_REPLAYS - INSTRUCTOR_RESERVE
            ),
        ));
    }
    let held = if instructor {
        None
    } else {
        Some(hold(&key, REPLAYS_PER_TRAINEE, "replays")?)
    };
    let permit = REPLAY_SLOTS.try_acquire().map_err(|_| {
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            format!("{MAX_REPLAYS} replays are open; try again shortly"),
        )
    })?;
    let mut replay = load(&state, &row).await?;
    let hello = replay_hello(&state, &row, &mut replay);
    let frame_hz = state.sessions.config.frame_hz.clamp(10, 120);
    let per_second = state.sessions.config.max_messages_per_second;
    let compute = state.compute.clone();
    Ok(ws
        .max_message_size(MAX_CLIENT_MESSAGE_BYTES)
        .on_upgrade(move |socket| async move {
            let _permit = permit;
            let _held = held;
            serve_replay(socket, replay, compute, hello, frame_hz, per_second).await;
        }))
}

fn replay_hello(state: &AppState, row: &AttemptRow, replay: &mut Replay) -> Utf8Bytes {
    let mut hello = crate::api::session_ws::hello_for(
        &row.session,
        "observer",
        replay.live(),
        &state.sessions.config,
    );
    hello.replay = Some(ReplayOut {
        attempt: row.id.clone(),
        duration_s: replay.duration_s(),
    });
    serde_json::to_string(&ServerMessage::Hello(Box::new(hello)))
        .unwrap_or_default()
        .into()
}

/// Playback state of one replay socket.
struct Playback {
    replay: Replay,
    /// Where seeks longer than a checkpoint interval run ([`Playback::seek`]).
    compute: Arc<ComputePool>,
    playing: bool,
    speed: f64,
    /// Wall clock and replay time when playing last started or changed: playback follows
    /// the wall clock (a slow tick does not slow it down).
    anchor: Option<(std::time::Instant, f64)>,
}

impl Playback {
    fn status(&self) -> Utf8Bytes {
        let msg = ServerMessage::Replay {
            t: self.replay.time_s(),
            playing: self.playing,
            speed: self.speed,
            duration_s: self.replay.duration_s(),
        };
        serde_json::to_string(&msg).unwrap_or_default().into()
    }

    /// Moves to `t` on a blocking thread; returns the frame there (None if the thread
    /// failed: the socket closes). A seek that would re-simulate more than one checkpoint
    /// interval (no replay has been there yet) first runs on a scout replay on the compute
    /// pool, as the REST seek does (low priority, queue, deadline), which leaves checkpoints
    /// up to `t`; the socket's own seek then re-simulates at most one interval. A busy pool
    /// answers an error and the replay stays where it was.
    async fn seek(mut self, t: f64) -> Option<(Playback, Result<Utf8Bytes, String>)> {
        if self.replay.seek_cost(Replay::step_at(t)) > CHECKPOINT_INTERVAL_STEPS {
            let scouted = match self.replay.scout() {
                Ok(mut scout) => self
                    .compute
                    .run(move |cancel| {
                        scout
                            .seek_checked(t, &|| cancel.check().is_ok())
                            .map_err(|e| pool_error(e, cancel))
                    })
                    .await
                    .map_err(|e| e.api_error().error),
                Err(e) => Err(e.to_string()),
            };
            if let Err(e) = scouted {
                return Some((self, Err(e)));
            }
        }
        tokio::task::spawn_blocking(move || {
            let r = self.replay.seek(t).map(|()| state_text(&mut self.replay));
            (self, r.map_err(|e| e.to_string()))
        })
        .await
        .ok()
    }
}

/// One replay socket: hello, the first frame and the status, then the client's commands
/// (rate-limited like the session socket's messages) and, while playing, frames at the
/// frame rate.
async fn serve_replay(
    socket: WebSocket,
    replay: Replay,
    compute: Arc<ComputePool>,
    hello: Utf8Bytes,
    frame_hz: u32,
    per_second: u32,
) {
    let (mut tx, mut rx) = socket.split();
    let mut pb = Playback {
        replay,
        compute,
        playing: false,
        speed: 1.0,
        anchor: None,
    };
    let first = state_text(&mut pb.replay);
    for text in [hello, first, pb.status()] {
        if tx.send(Message::Text(text)).await.is_err() {
            return;
        }
    }
    let interval = Duration::from_secs_f64(1.0 / f64::from(frame_hz));
    let mut rate = RateLimit::new(per_second);
    let mut tick = tokio::time::interval(interval);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let idle = tokio::time::sleep(REPLAY_IDLE);
    tokio::pin!(idle);
    loop {
        let mut out: Vec<Utf8Bytes> = Vec::new();
        tokio::select! {
            // Paused and silent for REPLAY_IDLE: the slot goes back (a forgotten tab).
            () = &mut idle, if !pb.playing => {
                let _ = tx.send(Message::Text(error_text(format!(
                    "closed after {} min without a message while paused",
                    REPLAY_IDLE.as_secs() / 60
                )))).await;
                let _ = tx.send(Message::Close(None)).await;
                return;
            }
            msg = rx.next() => {
                idle.as_mut().reset(tokio::time::Instant::now() + REPLAY_IDLE);
                let text = match msg {
                    Some(Ok(Message::Text(t))) => t,
                    Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                    Some(Ok(_)) => continue,
                };
                match rate.admit() {
                    // Over the rate: dropped, with at most one notice a second.
                    Err(notice) => out.extend(notice),
                    Ok(()) => {
                        match serde_json::from_str::<ReplayClientMessage>(&text) {
                            Ok(ReplayClientMessage::Play) => {
                                if pb.replay.at_end() {
                                    let Some((p, frame)) = pb.seek(0.0).await else { return };
                                    pb = p;
                                    out.extend(frame.ok());
                                }
                                pb.playing = true;
                            }
                            Ok(ReplayClientMessage::Pause) => pb.playing = false,
                            Ok(ReplayClientMessage::Seek { t }) if t.is_finite() => {
                                let Some((p, frame)) = pb.seek(t).await else { return };
                                pb = p;
                                match frame {
                                    Ok(f) => out.push(f),
                                    Err(e) => out.push(error_text(e)),
                                }
                            }
                            Ok(ReplayClientMessage::Seek { .. }) => {
                                out.push(error_text("`t` must be a finite number of seconds"));
                            }
                            Ok(ReplayClientMessage::Speed { value })
                                if (SPEED_RANGE.0..=SPEED_RANGE.1).contains(&value) =>
                            {
                                pb.speed = value;
                            }
                            Ok(ReplayClientMessage::Speed { value }) => out.push(error_text(format!(
                                "speed must be in [{}, {}], got {value}",
                                SPEED_RANGE.0, SPEED_RANGE.1
                            ))),
                            Err(e) => out.push(error_text(format!(
                                "expected {{\"type\": \"play\"|\"pause\"|\"seek\"|\"speed\", …}}: {e}"
                            ))),
                        }
                        pb.anchor = None;
                        out.push(pb.status());
                    }
                }
            }
            _ = tick.tick(), if pb.playing => {
                // playing counts as use: the idle time runs from when it stops
                idle.as_mut().reset(tokio::time::Instant::now() + REPLAY_IDLE);
                let (wall, t0) = *pb
                    .anchor
                    .get_or_insert((std::time::Instant::now(), pb.replay.time_s()));
                let t = (t0 + pb.speed * wall.elapsed().as_secs_f64())
                    .min(pb.replay.duration_s());
                let Some((p, frame)) = pb.seek(t).await else { return };
                pb = p;
                match frame {
                    Ok(f) => out.push(f),
                    Err(e) => {
                        pb.playing = false;
                        out.push(error_text(e));
                    }
                }
                if pb.replay.at_end() {
                    pb.playing = false;
                }
                out.push(pb.status());
            }
        }
        for text in out {
            if tx.send(Message::Text(text)).await.is_err() {
                return;
            }
        }
    }
}
