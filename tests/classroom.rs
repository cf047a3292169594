//! Classroom behaviours over real sockets: a silent fault acts on the arm but appears in no
//! frame or notice the trainee receives (only in the instructor's summary); an instructor's
//! pause cannot be lifted by the trainee; a session whose trainee left ends as abandoned
//! after the grace period unless the trainee comes back; the live summary carries the
//! roster fields (who paused, the exercise's step, progress and score, the frame's
//! warnings, the running attempt).

#![allow(clippy::unwrap_used)]

use std::time::{Duration, Instant};

use futures_util::StreamExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

mod common;
use common::*;

/// GET `url` with `token`, as JSON.
async fn get_as(url: String, token: &str) -> Value {
    reqwest::Client::new()
        .get(url)
        .bearer_auth(token)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap()
}

/// `GET /api/sessions/{id}` with `token`, as JSON.
async fn summary(s: &Server, id: &str, token: &str) -> Value {
    get_as(format!("{}/api/sessions/{id}", s.base), token).await
}

/// The next text message (within 5 s), raw and parsed.
async fn next_text(ws: &mut Ws) -> (String, Value) {
    loop {
        let msg = tokio::time::timeout(Duration::from_secs(5), ws.next())
            .await
            .expect("no message within 5 s");
        match msg {
            Some(Ok(Message::Text(t))) => {
                let v = serde_json::from_str(&t).unwrap();
                return (t.to_string(), v);
            }
            Some(Ok(Message::Ping(_) | Message::Pong(_))) => {}
            other => panic!("socket ended or sent {other:?}"),
        }
    }
}

/// A silent stuck valve (left swing, spool 0.8) moves the joint with zero stick input, as an
/// unfaulted session's does not; yet no message the trainee receives names it, while a
/// visible fault injected at the same time is in every frame. The instructor's summary lists
/// the silent fault with `"silent": true`; the trainee's own summary does not list it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_silent_fault_acts_but_is_shown_to_the_instructor_only() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    let (plain_id, plain_token) = new_session(&s).await;
    let mut ws = trainee(&s, &id, &token).await;
    let mut plain = trainee(&s, &plain_id, &plain_token).await;

    let silent = json!({"type": "fault", "fault": "stuck_valve", "arm": "left", "joint": 0,
        "value": 0.8, "silent": true});
    assert_eq!(act(&s, &id, TEACHER, silent).await.0, 204);
    let visible = json!({"type": "fault", "fault": "air", "arm": "right", "value": 0.5});
    assert_eq!(act(&s, &id, TEACHER, visible).await.0, 204);
    let (silent_label, visible_label) = ("stuck_valve:left:0:0.8", "air:right:0.5");

    // Frames published after the injection: skip until the visible fault is listed.
    let first = loop {
        let (text, v) = next_text(&mut ws).await;
        if v["type"] == "state" && text.contains(visible_label) {
            break v;
        }
    };
    let plain_first = state_after(&mut plain, 0.0).await;
    let t0 = first["t"].as_f64().unwrap();
    let mut frames = 0;
    let mut last = first.clone();
    while frames < 20 || last["t"].as_f64().unwrap() < t0 + 1.0 {
        let (text, v) = next_text(&mut ws).await;
        assert_eq!(v["type"], "state", "no notice announces the fault: {text}");
        assert!(
            !text.contains("stuck_valve"),
            "silent fault in a frame: {text}"
        );
        assert_eq!(v["faults"], json!([visible_label]));
        last = v;
        frames += 1;
    }
    let plain_last = state_after(&mut plain, plain_first["t"].as_f64().unwrap() + 1.0).await;
    // The stuck spool drives the swing actuator (Lim Table 1-1: 20 °/s at full flow), the
    // unfaulted arm with the same zero input stays where it is.
    let moved = (q(&last, "left", 0) - q(&first, "left", 0)).abs();
    let still = (q(&plain_last, "left", 0) - q(&plain_first, "left", 0)).abs();
    assert!(
        moved > 0.05,
        "silently stuck valve moved the swing only {moved} rad"
    );
    assert!(still < 0.005, "unfaulted swing moved {still} rad");

    let mine = summary(&s, &id, TEACHER).await;
    assert_eq!(
        mine["faults"],
        json!([{"label": silent_label, "silent": true}, {"label": visible_label, "silent": false}]),
        "{mine}"
    );
    let theirs = summary(&s, &id, &token).await;
    assert_eq!(
        theirs["faults"],
        json!([{"label": visible_label, "silent": false}]),
        "the trainee's own summary: {theirs}"
    );
    let listed = get_json(&format!("{}/api/sessions", s.base)).await;
    let entry = listed
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["id"] == id.as_str())
        .unwrap();
    assert_eq!(entry["faults"][0]["silent"], true, "{entry}");

    // A trainee cannot inject faults, silent or not.
    let again =
        json!({"type": "fault", "fault": "air", "arm": "left", "value": 0.5, "silent": true});
    assert_eq!(act(&s, &id, &token, again).await.0, 403);
    // Clearing removes silent faults too.
    assert_eq!(
        act(&s, &id, TEACHER, json!({"type": "clear_faults"}))
            .await
            .0,
        204
    );
    assert_eq!(summary(&s, &id, TEACHER).await["faults"], json!([]));
    drop(plain);

    // In an exercise, a silent fault is no intervention (the trainee's assessment would
    // show the count); a visible one is.
    let (st, c) = create(&s, json!({"exercise": "pick-and-place"})).await;
    assert_eq!(st, 201, "{c}");
    let (id, token) = (
        c["id"].as_str().unwrap(),
        c["control_token"].as_str().unwrap(),
    );
    let interventions = || async {
        let a = get_as(format!("{}/api/sessions/{id}/assessment", s.base), token).await;
        a["interventions"].as_f64().unwrap()
    };
    let leak = json!({"type": "fault", "fault": "leak", "arm": "left", "joint": 1,
        "value": 5e-10, "silent": true});
    assert_eq!(act(&s, id, TEACHER, leak).await.0, 204);
    assert_eq!(interventions().await, 0.0);
    let leak = json!({"type": "fault", "fault": "leak", "arm": "left", "joint": 1, "value": 5e-10});
    assert_eq!(act(&s, id, TEACHER, leak).await.0, 204);
    assert_eq!(interventions().await, 1.0);
    s.stop().await;
}

/// The first state frame (within 5 s) for which `pred` holds.
async fn frame_where(ws: &mut Ws, what: &str, pred: impl Fn(&Value) -> bool) -> Value {
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        assert!(Instant::now() < deadline, "no frame with {what} within 5 s");
        let v = next_of(ws, "state", Duration::from_secs(5)).await;
        if pred(&v) {
            return v;
        }
    }
}

/// The contract's refusal of a trainee's resume while the instructor paused.
const PAUSED_BY_INSTRUCTOR: &str = "paused by the instructor; only the instructor can resume";

/// Frames say who paused. The trainee pauses and resumes its own pause; an instructor's pause
/// takes over a trainee's, is not lifted by the trainee's `resume` (WS error message, REST
/// 403) nor taken back by the trainee's `pause`, and the clock stands still meanwhile; the
/// instructor's resume lifts it and the clock runs again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_trainee_cannot_lift_the_instructors_pause() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    let mut ws = trainee(&s, &id, &token).await;
    let running = frame_where(&mut ws, "a running clock", |v| v["paused"] == false).await;
    assert_eq!(running["paused_by"], Value::Null);

    send(&mut ws, json!({"type": "pause"})).await;
    frame_where(&mut ws, "paused_by trainee", |v| {
        v["paused"] == true && v["paused_by"] == "trainee"
    })
    .await;
    assert_eq!(summary(&s, &id, TEACHER).await["paused_by"], "trainee");
    send(&mut ws, json!({"type": "resume"})).await;
    frame_where(&mut ws, "the trainee's resume", |v| {
        v["paused"] == false && v["paused_by"].is_null()
    })
    .await;

    // The trainee pauses, then the instructor: the pause becomes the instructor's.
    send(&mut ws, json!({"type": "pause"})).await;
    frame_where(&mut ws, "paused_by trainee", |v| {
        v["paused_by"] == "trainee"
    })
    .await;
    assert_eq!(act(&s, &id, TEACHER, json!({"type": "pause"})).await.0, 204);
    let held = frame_where(&mut ws, "paused_by instructor", |v| {
        v["paused"] == true && v["paused_by"] == "instructor"
    })
    .await;
    assert_eq!(summary(&s, &id, TEACHER).await["paused_by"], "instructor");

    // The trainee's resume is refused over both edges; its pause changes nothing.
    send(&mut ws, json!({"type": "resume"})).await;
    let err = next_of(&mut ws, "error", Duration::from_secs(5)).await;
    assert_eq!(err["message"], PAUSED_BY_INSTRUCTOR);
    let (status, body) = act(&s, &id, &token, json!({"type": "resume"})).await;
    assert_eq!(status, 403, "{body}");
    let body: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(body["error"], PAUSED_BY_INSTRUCTOR);
    send(&mut ws, json!({"type": "pause"})).await;
    assert_eq!(act(&s, &id, &token, json!({"type": "pause"})).await.0, 204);
    tokio::time::sleep(Duration::from_millis(500)).await;
    let still = state_after(&mut ws, 0.0).await;
    let still = frame_where(&mut ws, "a frame after the trainee's pause", |v| {
        v["seq"].as_u64() > still["seq"].as_u64()
    })
    .await;
    assert_eq!(still["paused_by"], "instructor", "{}", still["paused_by"]);
    assert_eq!(still["t"], held["t"], "the clock stood still while paused");
    assert_eq!(summary(&s, &id, &token).await["paused_by"], "instructor");

    // The instructor's resume lifts it.
    assert_eq!(
        act(&s, &id, TEACHER, json!({"type": "resume"})).await.0,
        204
    );
    let resumed = frame_where(&mut ws, "the instructor's resume", |v| {
        v["paused"] == false && v["paused_by"].is_null()
    })
    .await;
    state_after(&mut ws, resumed["t"].as_f64().unwrap() + 0.2).await;
    s.stop().await;
}

/// Polls the instructor's summary of `id` (every 100 ms, up to `within`) until `pred` holds.
async fn summary_until(
    s: &Server,
    id: &str,
    within: Duration,
    pred: impl Fn(&Value) -> bool,
) -> Value {
    let deadline = Instant::now() + within;
    loop {
        let v = summary(s, id, TEACHER).await;
        if pred(&v) {
            return v;
        }
        assert!(
            Instant::now() < deadline,
            "not reached within {within:?}: {v}"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Closes a client socket and waits until the server counts no trainee on `id`.
async fn leave(s: &Server, id: &str, mut ws: Ws) {
    ws.close(None).await.unwrap();
    drop(ws);
    summary_until(s, id, Duration::from_secs(10), |v| v["trainees"] == 0).await;
}

/// With a 1 s abandon grace: a session whose trainee left ends `abandoned` (the observer
/// gets the `ended` message, the record says why); one whose trainee comes back within the
/// grace stays live past it, and ends the same way once the trainee leaves for good.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_the_trainee_left_ends_after_the_grace() {
    let s = start_with(temp_dir("classroom"), |c| c.abandon_grace_seconds = 1).await;
    let (id, token) = new_session(&s).await;
    let ws = trainee(&s, &id, &token).await;
    let mut obs = connect(&s, &id, &format!("token={TEACHER}&role=observer"))
        .await
        .unwrap();
    next_of(&mut obs, "hello", Duration::from_secs(5)).await;
    leave(&s, &id, ws).await;
    let ended = next_of(&mut obs, "ended", Duration::from_secs(10)).await;
    assert_eq!(ended["reason"], "abandoned", "{ended}");
    let text = "the trainee left: no connection for 1 s";
    assert_eq!(ended["text"], text);
    let record = summary_until(&s, &id, Duration::from_secs(10), |v| v["status"] == "ended").await;
    assert_eq!(record["end_reason"], text, "{record}");

    // Back within the grace: still live well after it.
    let (id, token) = new_session(&s).await;
    let ws = trainee(&s, &id, &token).await;
    leave(&s, &id, ws).await;
    let back = trainee(&s, &id, &token).await;
    tokio::time::sleep(Duration::from_millis(2500)).await;
    let v = summary(&s, &id, TEACHER).await;
    assert_eq!(v["status"], "live", "{v}");
    assert_eq!(v["trainees"], 1, "{v}");
    leave(&s, &id, back).await;
    let record = summary_until(&s, &id, Duration::from_secs(10), |v| v["status"] == "ended").await;
    assert_eq!(record["end_reason"], text, "{record}");
    s.stop().await;
}

/// The idle timeout (1 s here) ends a session whose connected trainee sends nothing; one
/// whose trainee keeps sending input stays live past it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_connected_but_inactive_trainee_times_out() {
    let s = start_with(temp_dir("classroom"), |c| c.idle_timeout_secs = 1).await;
    let (quiet_id, quiet_token) = new_session(&s).await;
    let (busy_id, busy_token) = new_session(&s).await;
    let mut quiet = trainee(&s, &quiet_id, &quiet_token).await;
    let mut busy = trainee(&s, &busy_id, &busy_token).await;
    // The busy trainee sends input every 200 ms for 3 s (three idle timeouts).
    let sender = tokio::spawn(async move {
        let started = Instant::now();
        let mut seq = 0;
        while started.elapsed() < Duration::from_secs(3) {
            seq += 1;
            send(&mut busy, json!({"type": "input", "seq": seq})).await;
            tokio::time::sleep(Duration::from_millis(200)).await;
        }
        busy
    });
    let ended = next_of(&mut quiet, "ended", Duration::from_secs(10)).await;
    assert_eq!(ended["reason"], "idle_timeout", "{ended}");
    let mut busy = sender.await.unwrap();
    assert_eq!(summary(&s, &busy_id, TEACHER).await["status"], "live");
    state_after(&mut busy, 0.0).await;
    s.stop().await;
}

/// The roster fields of a live summary against the trainee's own frames of the same state:
/// the trainee drives the left swing through the first familiarisation step to its limit,
/// the instructor pauses, and the summary then gives the paused frame's warnings (the
/// near-limit one included), its exercise step, step count, progress and score, the
/// exercise's title, `paused_by`, and the running attempt (a new one after a reset). A
/// free-play session has no exercise.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_roster_fields_match_the_frames() {
    let s = start().await;
    let (st, c) = create(&s, json!({"exercise": "familiarisation", "trainee": "ada"})).await;
    assert_eq!(st, 201, "{c}");
    let (id, token) = (
        c["id"].as_str().unwrap().to_string(),
        c["control_token"].as_str().unwrap().to_string(),
    );
    let mut ws = trainee(&s, &id, &token).await;
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let v = summary(&s, &id, TEACHER).await;
    assert_eq!(v["exercise"]["status"], "running", "{v}");
    assert_eq!(v["exercise"]["step"], 0, "{v}");
    let attempt = v["attempt"].as_str().unwrap().to_string();
    assert!(!attempt.is_empty(), "{v}");
    assert_eq!(v["paused_by"], Value::Null);

    // Full stick on the left swing (20 °/s, Lim Table 1-1) for 2 s: through +15° (step 1)
    // to the +25° limit (magnum.json), where the frames warn.
    let t0 = first["t"].as_f64().unwrap();
    hold_sticks(
        &mut ws,
        1,
        50,
        json!({"left": {"axes": [1, 0, 0, 0, 0, 0]}}),
    )
    .await;
    send(&mut ws, json!({"type": "input", "seq": 51})).await;
    state_after(&mut ws, t0 + 2.0).await;
    assert_eq!(act(&s, &id, TEACHER, json!({"type": "pause"})).await.0, 204);
    let frame = frame_where(&mut ws, "the instructor's pause", |v| {
        v["paused_by"] == "instructor"
    })
    .await;
    let v = summary(&s, &id, TEACHER).await;
    assert_eq!(v["paused_by"], "instructor");
    assert!(
        frame["warnings"]
            .as_array()
            .unwrap()
            .contains(&json!("near_joint_limit:left:0")),
        "{}",
        frame["warnings"]
    );
    assert_eq!(v["warnings"], frame["warnings"]);
    let (ex, fx) = (&v["exercise"], &frame["exercise"]);
    assert_eq!(ex["id"], "familiarisation");
    let spec = get_json(&format!("{}/api/exercises/familiarisation", s.base)).await;
    assert_eq!(ex["title"], spec["title"]);
    assert_eq!(ex["steps_total"], fx["steps"]);
    assert_eq!(ex["steps_total"], spec["steps"].as_array().unwrap().len());
    assert_eq!(ex["step"], fx["step"]);
    assert!(
        ex["step"].as_u64().unwrap() >= 1,
        "step 1 (swing to +15°) done: {ex}"
    );
    assert_eq!(ex["progress"], fx["progress"]);
    assert_eq!(ex["score"], fx["score"]);
    assert_eq!(ex["status"], "running");
    assert_eq!(v["attempt"], attempt.as_str());

    // A reset starts a new attempt.
    send(&mut ws, json!({"type": "reset"})).await;
    let v = summary_until(&s, &id, Duration::from_secs(5), |v| {
        v["attempt"] != attempt.as_str()
    })
    .await;
    assert_eq!(v["exercise"]["step"], 0, "{v}");

    let (free, _) = new_session(&s).await;
    let v = summary(&s, &free, TEACHER).await;
    assert_eq!(v["exercise"], Value::Null, "{v}");
    assert!(v["warnings"].is_array() && v["attempt"].is_string(), "{v}");
    s.stop().await;
}
