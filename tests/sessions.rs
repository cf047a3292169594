//! Live sessions over real sockets: create → connect → stick input moves a joint in the
//! streamed state; observers see the same session read-only; tokens are enforced; bad
//! messages get an error and never hurt the session; a stalled client does not slow another
//! session; records survive a restart; the cap answers 503; OpenAPI lists every route.

#![allow(clippy::unwrap_used)]

use std::time::{Duration, Instant};

use futures_util::SinkExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

mod common;
use common::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stick_input_moves_the_joint_and_observers_see_it_read_only() {
    let s = start_with(temp_dir("sessions"), |c| {
        c.trusted_proxies = vec![std::net::Ipv4Addr::LOCALHOST.into()];
    })
    .await;
    let (st, c) = create(&s, json!({"label": "alice"})).await;
    assert_eq!(st, 201, "{c}");
    let id = c["id"].as_str().unwrap();
    let token = c["control_token"].as_str().unwrap();
    assert!(
        c["ws_url"]
            .as_str()
            .unwrap()
            .contains(&format!("/ws/sessions/{id}?token={token}"))
    );

    assert!(c["ws_url"].as_str().unwrap().starts_with("ws://"));
    // Behind a TLS proxy (X-Forwarded-Proto: https, believed from --trusted-proxies only)
    // the page is told to use wss://.
    let proxied: Value = reqwest::Client::new()
        .post(format!("{}/api/sessions", s.base))
        .header("x-forwarded-proto", "https")
        .json(&json!({"label": "via-proxy"}))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert!(
        proxied["ws_url"].as_str().unwrap().starts_with("wss://"),
        "{proxied}"
    );

    let mut ws = connect(&s, id, &format!("token={token}")).await.unwrap();
    let hello = next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    assert_eq!(hello["role"], "trainee");
    assert_eq!(hello["arms"][0]["model"]["name"], "magnum");
    assert!(
        hello["object"]["mass_kg"].as_f64().unwrap() == 50.0,
        "Lim §4.2.2: 50 kg object"
    );
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let q0 = q(&first, "left", 0);
    for key in ["yoshikawa", "isotropy", "hong", "jlm"] {
        assert!(
            first["arms"]["left"]["measures"][key].is_number(),
            "{key} missing"
        );
    }
    assert_eq!(
        first["arms"]["left"]["joint_frames"]
            .as_array()
            .unwrap()
            .len(),
        6
    );

    // Full stick on the left swing joint for a second (Table 1-1: 20 °/s nominal).
    for seq in 1..=25u64 {
        send(&mut ws, json!({"type": "input", "seq": seq, "arms": {"left": {"axes": [1, 0, 0, 0, 0, 0], "grip": 0}}})).await;
        tokio::time::sleep(Duration::from_millis(40)).await;
    }
    let later = state_after(&mut ws, first["t"].as_f64().unwrap() + 1.0).await;
    let moved = q(&later, "left", 0) - q0;
    assert!(moved > 0.05, "swing moved only {moved} rad");
    assert!(later["input_seq"].as_u64().unwrap() >= 20);
    assert!(later["t"].as_f64().unwrap() > first["t"].as_f64().unwrap());

    // An observer (instructor token) sees the same session and cannot control it.
    let mut obs = connect(&s, id, &format!("token={TEACHER}&role=observer"))
        .await
        .unwrap();
    let h = next_of(&mut obs, "hello", Duration::from_secs(5)).await;
    assert_eq!(h["role"], "observer");
    let seen = next_of(&mut obs, "state", Duration::from_secs(5)).await;
    assert!(
        (q(&seen, "left", 0) - q0).abs() > 0.05,
        "observer sees the moved arm"
    );
    send(
        &mut obs,
        json!({"type": "input", "seq": 1, "arms": {"left": {"axes": [-1, 0, 0, 0, 0, 0]}}}),
    )
    .await;
    let err = next_of(&mut obs, "error", Duration::from_secs(5)).await;
    assert!(
        err["message"]
            .as_str()
            .unwrap()
            .contains("observers cannot control")
    );
    // Ping works for observers too (latency display).
    send(&mut obs, json!({"type": "ping", "t": 12.5})).await;
    assert_eq!(
        next_of(&mut obs, "pong", Duration::from_secs(5)).await["t"],
        12.5
    );

    // Instructor list shows it with live measures.
    let list = get_json(&format!("{}/api/sessions", s.base)).await;
    let entry = list
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["id"] == id)
        .unwrap();
    assert_eq!(entry["status"], "live");
    assert_eq!(entry["label"], "alice");
    assert!(entry["measures"][0]["yoshikawa"].as_f64().unwrap() > 0.0);

    // An instructor message reaches the trainee's page.
    let r = reqwest::Client::new()
        .post(format!("{}/api/sessions/{id}/actions", s.base))
        .bearer_auth(TEACHER)
        .json(&json!({"type": "message", "text": "ease off the shoulder"}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 204);
    let m = next_of(&mut ws, "message", Duration::from_secs(5)).await;
    assert_eq!(m["text"], "ease off the shoulder");
    s.stop().await;
}

/// Cartesian mode (redundancy resolution, Jun eq. 21): an "up" stick raises the left
/// end-effector while its x and y barely move.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cartesian_mode_moves_the_end_effector_along_the_stick() {
    let s = start().await;
    let (_, c) = create(&s, json!({"control_mode": "cartesian"})).await;
    let (id, tok) = (
        c["id"].as_str().unwrap(),
        c["control_token"].as_str().unwrap(),
    );
    let mut ws = connect(&s, id, &format!("token={tok}")).await.unwrap();
    let hello = next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    assert_eq!(hello["settings"]["control_mode"], "cartesian");
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let p0: Vec<f64> = first["arms"]["left"]["pose"]["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for seq in 1..=30u64 {
        send(
            &mut ws,
            json!({"type": "input", "seq": seq, "arms": {"left": {"axes": [0, 0, 0.5, 0, 0, 0]}}}),
        )
        .await;
        tokio::time::sleep(Duration::from_millis(40)).await;
    }
    let later = state_after(&mut ws, first["t"].as_f64().unwrap() + 1.2).await;
    let p1: Vec<f64> = later["arms"]["left"]["pose"]["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let dz = p1[2] - p0[2];
    let dxy = ((p1[0] - p0[0]).powi(2) + (p1[1] - p0[1]).powi(2)).sqrt();
    assert!(dz > 0.04, "end-effector rose only {dz} m");
    assert!(
        dxy < 0.5 * dz,
        "sideways drift {dxy} m for a vertical command (rise {dz} m)"
    );
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tokens_are_enforced() {
    let s = start().await;
    let (_, a) = create(&s, json!({})).await;
    let (_, b) = create(&s, json!({})).await;
    let (ida, ta) = (
        a["id"].as_str().unwrap(),
        a["control_token"].as_str().unwrap(),
    );
    let idb = b["id"].as_str().unwrap();
    assert_eq!(connect(&s, ida, "token=wrong").await.err(), Some(403));
    assert_eq!(connect(&s, ida, "").await.err(), Some(403));
    assert_eq!(
        connect(&s, idb, &format!("token={ta}")).await.err(),
        Some(403),
        "A's token does not open B"
    );
    assert_eq!(
        connect(&s, "0000000000000000", &format!("token={ta}"))
            .await
            .err(),
        Some(404)
    );
    let http = reqwest::Client::new();
    let st = |r: reqwest::Response| r.status().as_u16();
    assert_eq!(
        st(http
            .get(format!("{}/api/sessions", s.base))
            .send()
            .await
            .unwrap()),
        403
    );
    assert_eq!(
        st(http
            .get(format!("{}/api/sessions", s.base))
            .bearer_auth(ta)
            .send()
            .await
            .unwrap()),
        403
    );
    let act = |id: &str, tok: &str, body: Value| {
        http.post(format!("{}/api/sessions/{id}/actions", s.base))
            .bearer_auth(tok.to_string())
            .json(&body)
            .send()
    };
    assert_eq!(
        st(act(ida, ta, json!({"type": "pause"})).await.unwrap()),
        204,
        "own session"
    );
    assert_eq!(
        st(act(idb, ta, json!({"type": "pause"})).await.unwrap()),
        403,
        "other session"
    );
    assert_eq!(
        st(act(ida, ta, json!({"type": "message", "text": "hi"}))
            .await
            .unwrap()),
        403,
        "instructor-only"
    );
    assert_eq!(
        st(act(
            ida,
            TEACHER,
            json!({"type": "fault", "fault": "supply_drop", "arm": "left", "value": 2.0e6})
        )
        .await
        .unwrap()),
        204
    );
    let bad = act(
        ida,
        TEACHER,
        json!({"type": "fault", "fault": "stuck_valve", "arm": "left", "value": 0.5}),
    )
    .await
    .unwrap();
    assert_eq!(bad.status().as_u16(), 400);
    assert!(bad.text().await.unwrap().contains("joint"));
    assert_eq!(
        st(act(ida, TEACHER, json!({"type": "explode"})).await.unwrap()),
        400
    );
    assert_eq!(
        st(act("0000000000000000", TEACHER, json!({"type": "reset"}))
            .await
            .unwrap()),
        404
    );
    // The CSV download needs a token too.
    assert_eq!(
        st(http
            .get(format!("{}/api/sessions/{ida}/log.csv", s.base))
            .send()
            .await
            .unwrap()),
        403
    );
    let csv = http
        .get(format!("{}/api/sessions/{ida}/log.csv?token={ta}", s.base))
        .send()
        .await
        .unwrap();
    assert_eq!(csv.status().as_u16(), 200);
    assert!(csv.text().await.unwrap().starts_with("t,left_q1"));
    // Unknown scenario on create.
    let (code, body) = create(&s, json!({"scenario": "nope"})).await;
    assert_eq!(code, 400);
    assert!(body["error"].as_str().unwrap().contains("unknown scenario"));
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_messages_get_errors_and_the_session_keeps_running() {
    let s = start_with(temp_dir("sessions"), |c| c.max_messages_per_second = 50).await;
    let (_, c) = create(&s, json!({})).await;
    let (id, tok) = (
        c["id"].as_str().unwrap(),
        c["control_token"].as_str().unwrap(),
    );
    let mut ws = trainee(&s, id, tok).await;
    let cases: Vec<(String, &str)> = vec![
        ("{not json".into(), "invalid message"),
        (
            json!({"type": "launch_missiles"}).to_string(),
            "invalid message",
        ),
        (
            json!({"type": "input", "seq": "one"}).to_string(),
            "invalid message",
        ),
        (
            json!({"type": "input", "seq": 1, "arms": {"left": {"axes": [0, 0, 0]}}}).to_string(),
            "6 values",
        ),
        (
            json!({"type": "input", "seq": 2, "arms": {"left": {"axes": [5, 0, 0, 0, 0, 0]}}})
                .to_string(),
            "clamped",
        ),
        (
            json!({"type": "input", "seq": 3, "arms": {"left": {"axes": [1e300, 0, 0, 0, 0, 0]}}})
                .to_string(),
            "clamped",
        ),
        (
            r#"{"type": "input", "seq": 4, "arms": {"left": {"axes": [NaN, 0, 0, 0, 0, 0]}}}"#
                .into(),
            "invalid message",
        ),
        (
            json!({"type": "settings", "arm_speed": 7}).to_string(),
            "arm_speed",
        ),
        (
            json!({"type": "settings", "control_mode": "telepathic"}).to_string(),
            "invalid message",
        ),
    ];
    for (text, needle) in cases {
        ws.send(Message::Text(text.clone().into())).await.unwrap();
        let e = next_of(&mut ws, "error", Duration::from_secs(5)).await;
        assert!(
            e["message"].as_str().unwrap().contains(needle),
            "{text} → {e}"
        );
    }
    let before = next_of(&mut ws, "state", Duration::from_secs(5)).await["t"]
        .as_f64()
        .unwrap();
    // The simulation kept running: a frame 0.3 s of simulated time later arrives promptly.
    let after = state_after(&mut ws, before + 0.3).await;
    for arm in ["left", "right"] {
        for v in after["arms"][arm]["q"].as_array().unwrap() {
            assert!(v.as_f64().unwrap().is_finite());
        }
    }
    // Over the rate: a burst of 500 messages → one rate error, session alive.
    for i in 0..500u64 {
        send(&mut ws, json!({"type": "input", "seq": 100 + i})).await;
    }
    let e = next_of(&mut ws, "error", Duration::from_secs(5)).await;
    assert!(
        e["message"].as_str().unwrap().contains("too many messages"),
        "{e}"
    );
    next_of(&mut ws, "state", Duration::from_secs(5)).await;
    // Oversize messages: admission_and_security.rs, oversize_messages_close_with_1009.
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stalled_client_does_not_slow_another_session() {
    let s = start().await;
    let (_, a) = create(&s, json!({})).await;
    let (_, b) = create(&s, json!({})).await;
    // A connects and never reads.
    let _stalled = connect(
        &s,
        a["id"].as_str().unwrap(),
        &format!("token={}", a["control_token"].as_str().unwrap()),
    )
    .await
    .unwrap();
    let mut ws = connect(
        &s,
        b["id"].as_str().unwrap(),
        &format!("token={}", b["control_token"].as_str().unwrap()),
    )
    .await
    .unwrap();
    next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let wall = Instant::now();
    let mut frames = 0;
    let mut last = first.clone();
    while wall.elapsed() < Duration::from_secs(3) {
        last = next_of(&mut ws, "state", Duration::from_secs(5)).await;
        frames += 1;
    }
    let sim = last["t"].as_f64().unwrap() - first["t"].as_f64().unwrap();
    let real = wall.elapsed().as_secs_f64();
    assert!(
        sim > 0.85 * real,
        "B's simulation ran {sim:.2} s in {real:.2} s of wall time"
    );
    assert!(
        frames as f64 > 30.0 * real,
        "B received {frames} frames in {real:.2} s (60 Hz configured)"
    );
    // A's simulation also kept real time although its client reads nothing.
    let a_summary = get_json(&format!(
        "{}/api/sessions/{}",
        s.base,
        a["id"].as_str().unwrap()
    ))
    .await;
    assert!(a_summary["sim_seconds"].as_f64().unwrap() > 1.5);
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn records_survive_a_restart() {
    let dir = temp_dir("sessions");
    let s = start_with(dir.clone(), |_| {}).await;
    let (_, c) = create(
        &s,
        json!({"label": "bob", "scenario": "case3-dual-open-loop"}),
    )
    .await;
    let id = c["id"].as_str().unwrap().to_string();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    s.stop().await;
    // Same data directory, new server.
    let s2 = start_with(dir.clone(), |_| {}).await;
    let list = get_json(&format!("{}/api/sessions", s2.base)).await;
    let entry = list
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["id"] == id.as_str())
        .unwrap_or_else(|| panic!("{list}"));
    assert_eq!(entry["status"], "ended");
    assert_eq!(entry["label"], "bob");
    assert_eq!(entry["scenario"], "case3-dual-open-loop");
    assert_eq!(entry["end_reason"], "server shutdown");
    assert!(entry["sim_seconds"].as_f64().unwrap() > 1.0);
    let csv = get_text(&format!("{}/api/sessions/{id}/log.csv", s2.base)).await;
    let rows = csv.lines().count() - 1;
    assert!(rows >= 100, "100 Hz record of > 1 s has {rows} rows");
    s2.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_cap_answers_503_and_operations_routes_work() {
    let s = start_with(temp_dir("sessions"), |c| c.max_sessions = 1).await;
    let (st, _) = create(&s, json!({})).await;
    assert_eq!(st, 201);
    let (st, body) = create(&s, json!({})).await;
    assert_eq!(st, 503);
    assert!(body["error"].as_str().unwrap().contains("full"));
    let http = reqwest::Client::new();
    let metrics = http
        .get(format!("{}/metrics", s.base))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    for name in [
        "seaarms_sessions 1",
        "seaarms_step_overruns_total",
        "seaarms_websocket_clients",
        "seaarms_frames_skipped_total",
        "seaarms_http_requests_total",
    ] {
        assert!(metrics.contains(name), "{name} missing from\n{metrics}");
    }
    assert_eq!(
        http.get(format!("{}/healthz", s.base))
            .send()
            .await
            .unwrap()
            .status()
            .as_u16(),
        200
    );
    s.stop().await;
}

/// Every route the router serves is in /api/openapi.json and vice versa, and each one is
/// really routed (answers something other than the fallback's "no route").
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn openapi_lists_every_route() {
    let s = start().await;
    let http = reqwest::Client::new();
    let doc: Value = http
        .get(format!("{}/api/openapi.json", s.base))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let paths = doc["paths"].as_object().unwrap();
    let mut documented: Vec<(String, String)> = Vec::new();
    for (p, ops) in paths {
        for m in ops.as_object().unwrap().keys() {
            documented.push((m.clone(), p.clone()));
        }
    }
    let mut routes: Vec<(String, String)> = seaarms::app::ROUTES
        .iter()
        .map(|(m, p)| (m.to_string(), p.to_string()))
        .collect();
    documented.sort();
    routes.sort();
    assert_eq!(documented, routes);
    for (method, path) in &routes {
        let concrete = path
            .replace("{path}", "index.html")
            .replace("{name}", "magnum")
            .replace("{id}", "0000000000000000")
            .replace("{run}", "none.csv");
        let url = format!("{}{concrete}", s.base);
        let resp = match method.as_str() {
            "get" => http.get(&url).send().await.unwrap(),
            "post" => http
                .post(&url)
                .header("content-type", "application/json")
                .body("{}")
                .send()
                .await
                .unwrap(),
            "put" => http
                .put(&url)
                .header("content-type", "application/json")
                .body("{}")
                .send()
                .await
                .unwrap(),
            "delete" => http.delete(&url).send().await.unwrap(),
            m => panic!("method {m}"),
        };
        let status = resp.status().as_u16();
        let text = resp.text().await.unwrap_or_default();
        assert!(
            !text.contains("no route for"),
            "{method} {path} is not routed ({status}: {text})"
        );
    }
    s.stop().await;
}

/// Issue 28 item 6: "the exercise clock starts when the trainee presses Ready after reading
/// the goal". A session created with `wait_for_ready` on an exercise streams frames with
/// `awaiting_ready` and the attempt's clock at 0 (no steps pass) until the trainee's
/// `ready`; then it runs. A reset ("try again") waits again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_exercise_waits_for_ready_before_its_clock_starts() {
    let s = start().await;
    let (st, c) = create(
        &s,
        json!({"exercise": "reach-targets", "wait_for_ready": true}),
    )
    .await;
    assert_eq!(st, 201, "{c}");
    let (id, token) = (
        c["id"].as_str().unwrap(),
        c["control_token"].as_str().unwrap(),
    );
    let mut ws = trainee(&s, id, token).await;
    tokio::time::sleep(Duration::from_millis(600)).await;
    let f = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let f = state_after(&mut ws, f["t"].as_f64().unwrap()).await;
    assert_eq!(f["awaiting_ready"], true, "{}", f["awaiting_ready"]);
    assert_eq!(f["t"], 0.0);
    assert_eq!(f["exercise"]["elapsed_s"], 0.0);
    // The instructor's roster says so, rather than "live, t 0.0".
    let summary = format!("{}/api/sessions/{id}", s.base);
    assert_eq!(get_json(&summary).await["awaiting_ready"], true);
    send(&mut ws, json!({"type": "ready"})).await;
    let f = state_after(&mut ws, 0.3).await;
    assert_eq!(f["awaiting_ready"], false);
    assert_eq!(get_json(&summary).await["awaiting_ready"], false);
    assert!(f["exercise"]["elapsed_s"].as_f64().unwrap() >= 0.3);
    send(&mut ws, json!({"type": "reset"})).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let mut f = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    while f["awaiting_ready"] != true {
        f = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    }
    assert_eq!(
        f["exercise"]["elapsed_s"], 0.0,
        "try again waits for ready again"
    );
    // Without `wait_for_ready` (scripts, the HTTP API) the attempt starts at once.
    let (_, c) = create(&s, json!({"exercise": "reach-targets"})).await;
    let mut ws = trainee(
        &s,
        c["id"].as_str().unwrap(),
        c["control_token"].as_str().unwrap(),
    )
    .await;
    let f = state_after(&mut ws, 0.2).await;
    assert_eq!(f["awaiting_ready"], false);
    s.stop().await;
}
