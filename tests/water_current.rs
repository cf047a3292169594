//! The instructor's water current over real sockets (issue 17 item 7): free play runs in
//! still sea water and its frames say so; the instructor sets the current with
//! `POST /api/sessions/{id}/actions {"type": "set_current", …}` and the trainee's frames
//! carry it (and the free box is carried along); the trainee's token gets 403; bad values
//! and a session in air get 400 with a JSON error; nothing reaches the simulation then.

#![allow(clippy::unwrap_used)]

use std::time::Duration;

use serde_json::{Value, json};

mod common;
use common::*;

/// [`act`] with the body parsed as JSON (null for an empty body).
async fn act_json(s: &Server, id: &str, token: &str, body: Value) -> (u16, Value) {
    let (st, text) = act(s, id, token, body).await;
    (st, serde_json::from_str(&text).unwrap_or(Value::Null))
}

/// The same with a raw body (for numbers JSON values cannot carry).
async fn act_raw(s: &Server, id: &str, body: &str) -> (u16, Value) {
    let r = reqwest::Client::new()
        .post(format!("{}/api/sessions/{id}/actions", s.base))
        .bearer_auth(TEACHER)
        .header("content-type", "application/json")
        .body(body.to_string())
        .send()
        .await
        .unwrap();
    let st = r.status().as_u16();
    (st, r.json().await.unwrap_or(Value::Null))
}

fn current(frame: &Value) -> (f64, f64) {
    let c = &frame["current"];
    (
        c["speed_m_s"].as_f64().unwrap(),
        c["heading_deg"].as_f64().unwrap(),
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_instructor_sets_the_current_and_the_trainee_sees_it() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    let mut ws = trainee(&s, &id, &token).await;
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    assert_eq!(current(&first), (0.0, 0.0), "free play: still sea water");

    // The trainee may not.
    let (st, body) = act_json(
        &s,
        &id,
        &token,
        json!({"type": "set_current", "speed_m_s": 0.5, "heading_deg": 30}),
    )
    .await;
    assert_eq!(st, 403, "{body}");
    assert!(
        body["error"].as_str().unwrap().contains("set_current"),
        "{body}"
    );

    // Bad values: a clear JSON error each, and no change.
    for (bad, says) in [
        (
            json!({"type": "set_current", "speed_m_s": -0.1, "heading_deg": 0}),
            "speed_m_s",
        ),
        (
            json!({"type": "set_current", "speed_m_s": 2.6, "heading_deg": 0}),
            "speed_m_s",
        ),
        (
            json!({"type": "set_current", "speed_m_s": 1e300, "heading_deg": 0}),
            "speed_m_s",
        ),
        (
            json!({"type": "set_current", "speed_m_s": 0.5, "heading_deg": 400}),
            "heading_deg",
        ),
        (
            json!({"type": "set_current", "speed_m_s": "fast", "heading_deg": 0}),
            "",
        ),
        (
            json!({"type": "set_current", "speed_m_s": null, "heading_deg": 0}),
            "",
        ),
        (
            json!({"type": "set_current", "heading_deg": 0}),
            "speed_m_s",
        ),
    ] {
        let (st, body) = act_json(&s, &id, TEACHER, bad.clone()).await;
        assert_eq!(st, 400, "{bad} → {body}");
        let msg = body["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{bad}: JSON error, got {body}"));
        assert!(msg.contains(says), "{bad}: {msg}");
    }
    // A number beyond f64 (JSON has no NaN): refused by the parser, still JSON.
    let (st, body) = act_raw(
        &s,
        &id,
        r#"{"type": "set_current", "speed_m_s": 1e999, "heading_deg": 0}"#,
    )
    .await;
    assert_eq!(st, 400, "{body}");
    assert!(body["error"].is_string(), "{body}");
    let still = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    assert_eq!(
        current(&still),
        (0.0, 0.0),
        "refused changes change nothing"
    );

    // The instructor sets 0.5 m/s towards −90° (stored as 270°: flowing to −y).
    let (st, body) = act_json(
        &s,
        &id,
        TEACHER,
        json!({"type": "set_current", "speed_m_s": 0.5, "heading_deg": -90}),
    )
    .await;
    assert_eq!(st, 204, "{body}");
    let mut frame = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    for _ in 0..50 {
        if current(&frame).0 > 0.0 {
            break;
        }
        frame = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    }
    assert_eq!(current(&frame), (0.5, 270.0));

    // Switching to a live case-study set-up puts the session in air: no current to set.
    let (st, _) = act_json(
        &s,
        &id,
        TEACHER,
        json!({"type": "scenario", "scenario": "case1-single-arm"}),
    )
    .await;
    assert_eq!(st, 204);
    let (st, body) = act_json(
        &s,
        &id,
        TEACHER,
        json!({"type": "set_current", "speed_m_s": 0.5, "heading_deg": 0}),
    )
    .await;
    assert_eq!(st, 400, "{body}");
    assert!(body["error"].as_str().unwrap().contains("air"), "{body}");
    let mut frame = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    for _ in 0..50 {
        if frame["scenario"] == "case1-single-arm" {
            break;
        }
        frame = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    }
    assert!(frame["current"].is_null(), "in air: {}", frame["current"]);
    s.stop().await;
}

/// The instructor's visibility (issue 28 item 1: "distance fog/turbidity the instructor can
/// set"): frames carry `visibility_m` once set (null before: each page's own); the trainee's
/// token gets 403; outside [0.5, 50] m or not a number, 400 with a JSON error and no change.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_instructor_sets_the_visibility_and_every_page_gets_it() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    let mut ws = trainee(&s, &id, &token).await;
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    assert!(first["visibility_m"].is_null(), "{}", first["visibility_m"]);
    let (st, body) = act_json(
        &s,
        &id,
        &token,
        json!({"type": "set_visibility", "visibility_m": 3}),
    )
    .await;
    assert_eq!(st, 403, "{body}");
    for bad in [
        json!(0.1),
        json!(51),
        json!(-3),
        json!("murky"),
        json!(null),
    ] {
        let (st, body) = act_json(
            &s,
            &id,
            TEACHER,
            json!({"type": "set_visibility", "visibility_m": bad}),
        )
        .await;
        assert_eq!(st, 400, "{bad} → {body}");
        assert!(body["error"].is_string(), "{bad}: {body}");
    }
    let f = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    assert!(f["visibility_m"].is_null());
    let (st, body) = act_json(
        &s,
        &id,
        TEACHER,
        json!({"type": "set_visibility", "visibility_m": 3}),
    )
    .await;
    assert_eq!(st, 204, "{body}");
    let t = f["t"].as_f64().unwrap();
    let f = state_after(&mut ws, t + 0.1).await;
    assert_eq!(f["visibility_m"], 3.0);
    s.stop().await;
}
