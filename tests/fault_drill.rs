//! The `fault-diagnosis` exercise end to end, headless, through the trainee's controls only:
//! the autopilot's diagnosis (which reads what the page shows, never the injected fault) names
//! the drawn fault for every seed, covering each fault kind at least twice, and passes; an idle
//! attempt fails. Same seed, same assessment. Over real sockets: a running drill gives the
//! trainee neither its fault nor its time nor its seed; "try again" clears the faults.

#![allow(clippy::unwrap_used)]

mod common;
use common::magnum;

use std::collections::BTreeMap;

use seaarms::catalogue::EXERCISES;
use seaarms::exercises::{Driver, run_headless};
use seaarms_core::exercise::Assessment;
use seaarms_core::hydraulics::FaultKind;

/// Seeds 1..=16: the drill's splitmix64 draw over the file's eight choices (two per kind)
/// gives each fault kind three to five times (checked below, not assumed).
const SEEDS: std::ops::RangeInclusive<u64> = 1..=16;

/// Runs one headless attempt at `fault-diagnosis`.
fn attempt(driver: Driver, seed: u64) -> Assessment {
    let spec = EXERCISES
        .get("fault-diagnosis")
        .expect("fault-diagnosis exercise");
    run_headless(spec, &magnum(), driver, seed).expect("run")
}

#[test]
fn autopilot_names_every_fault_and_passes() {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    for seed in SEEDS {
        let a = attempt(Driver::Autopilot, seed);
        let d = a.diagnosis.clone().expect("a drill has a diagnosis");
        println!(
            "seed {seed:2}: {:11} at {:5.2} s → answer {:11} passed {} score {:.1} time {:.1} s {:?}",
            d.fault,
            d.injected_at_s,
            d.answer,
            a.passed,
            a.score,
            a.metrics.time_s,
            a.failed_because
        );
        *seen.entry(d.fault.clone()).or_default() += 1;
        if !(a.passed && d.correct) {
            failures.push((seed, d.fault, d.answer, a.failed_because.clone()));
        }
        let json = serde_json::to_value(&a).expect("json");
        for (k, v) in json.as_object().expect("object") {
            if let Some(x) = v.as_f64() {
                assert!(x.is_finite(), "seed {seed}: {k} = {x}");
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    for kind in FaultKind::NAMES {
        assert!(
            seen.get(kind).copied().unwrap_or(0) >= 2,
            "{kind} drawn < 2 times: {seen:?}"
        );
    }
}

/// An idle attempt fails (no answer). Its first step, the jaw to marker A, is not reached
/// and ends at the fault window's end all the same (version 4: a fault that came first can
/// make A unreachable), and the stop step follows after its hold; each at its time whatever
/// the fault's moment.
#[test]
fn idle_attempt_fails_and_runs_are_deterministic() {
    let idle = attempt(Driver::Idle, 3);
    assert!(idle.done && !idle.passed, "{idle:?}");
    assert!(!idle.completed);
    assert_eq!(idle.diagnosis.as_ref().map(|d| d.answer.as_str()), Some(""));
    let spec = EXERCISES.get("fault-diagnosis").expect("exercise");
    let window_end = spec.fault_drill.as_ref().expect("drill").window_s[1];
    let hold = spec.steps[1].hold_s;
    assert_eq!(idle.step_times_s.len(), 2, "{:?}", idle.step_times_s);
    assert!(
        (idle.step_times_s[0] - window_end).abs() <= 0.05,
        "the reach step ended at {:.2} s, not at the window's end {window_end} s",
        idle.step_times_s[0]
    );
    assert!(
        (idle.step_times_s[1] - hold).abs() <= 0.05,
        "{:?}",
        idle.step_times_s
    );
    let a = attempt(Driver::Autopilot, 6);
    let b = attempt(Driver::Autopilot, 6);
    assert_eq!(a, b);
}

/// The stop step cannot time the hidden fault (issue 29, the residual hint): with the reach
/// step taken out and the arm left still, the step ticks at the window's end plus its hold,
/// the same for a fault drawn at 5.x s as for one at 14.x s (when it ticked 3 s after the
/// injection, a trainee who sat still read the fault's moment off the task panel).
#[test]
fn the_stop_step_ticks_at_the_same_time_whenever_the_fault_came() {
    let mut spec = (*EXERCISES.get("fault-diagnosis").expect("exercise")).clone();
    spec.steps.remove(0);
    let window_end = spec.fault_drill.as_ref().expect("drill").window_s[1];
    let hold = spec.steps[0].hold_s;
    let spec = Arc::new(spec);
    let mut ticks = Vec::new();
    for seed in SEEDS {
        let a = run_headless(spec.clone(), &magnum(), Driver::Idle, seed).expect("run");
        let at = a.diagnosis.as_ref().expect("diagnosis").injected_at_s;
        let tick = a
            .step_times_s
            .first()
            .copied()
            .expect("the stop step ticked");
        println!("seed {seed:2}: fault at {at:5.2} s, stop step at {tick:5.2} s");
        ticks.push((at, tick));
    }
    let (early, late) = (
        ticks.iter().map(|t| t.0).fold(f64::MAX, f64::min),
        ticks.iter().map(|t| t.0).fold(0.0, f64::max),
    );
    assert!(
        early < 8.0 && late > 12.0,
        "the seeds' draws span the window: {early:.2}–{late:.2} s"
    );
    for (at, tick) in ticks {
        assert!(
            (tick - (window_end + hold)).abs() <= 0.05,
            "fault at {at:.2} s: the stop step ticked at {tick:.2} s, not at {:.2} s",
            window_end + hold
        );
    }
}

// ---------------------------------------------------------------------------------------
// The drill cannot be read off the server (issue 29 item 1), over real sockets.
// ---------------------------------------------------------------------------------------

use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::{TEACHER, act, create, get_as, get_json, start};
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

/// What gives the running drill away: the attempt's seed (it draws the fault and its time),
/// the injection time as the server writes it, the fault as a named field or a label.
fn secrets(instructor_assessment: &Value) -> Vec<String> {
    let d = &instructor_assessment["diagnosis"];
    let kind = d["fault"].as_str().unwrap();
    vec![
        instructor_assessment["seed"].to_string(),
        serde_json::to_string(&d["injected_at_s"]).unwrap(),
        format!("\"fault\":\"{kind}\""),
        format!("{kind}:left"),
    ]
}

/// Issue 29: "During a running `fault-diagnosis` attempt, no response or message available
/// to the trainee's token contains the fault's name, its injection time or the seed (checked
/// over every route and both sockets)". The trainee's socket (hello, every frame, replies and
/// errors) and every route its token opens are read before and after the injection; the same
/// patterns are found in the instructor's assessment (so the search can fail).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_running_drill_gives_the_trainee_neither_its_fault_nor_its_time_nor_its_seed() {
    let s = start().await;
    let (st, c) = create(&s, json!({"exercise": "fault-diagnosis"})).await;
    assert_eq!(st, 201, "{c}");
    let id = c["id"].as_str().unwrap().to_string();
    let token = c["control_token"].as_str().unwrap().to_string();
    let ws_url = format!(
        "{}/ws/sessions/{id}?token={token}",
        s.base.replace("http://", "ws://")
    );
    let (ws, _) = tokio_tungstenite::connect_async(&ws_url).await.unwrap();
    let (mut tx, mut rx) = ws.split();
    let seen: Arc<Mutex<Vec<String>>> = Arc::default();
    let sink = seen.clone();
    let reader = tokio::spawn(async move {
        while let Some(Ok(m)) = rx.next().await {
            if let Message::Text(t) = m {
                sink.lock().unwrap().push(t.to_string());
            }
        }
    });
    let base = s.base.clone();
    let instructor = get_json(&format!("{base}/api/sessions/{id}/assessment")).await;
    let hidden = secrets(&instructor);
    let instructor_text = instructor.to_string();
    for p in &hidden[..3] {
        assert!(
            instructor_text.contains(p.as_str()),
            "{p} not in {instructor_text}"
        );
    }
    let injected_at = instructor["diagnosis"]["injected_at_s"].as_f64().unwrap();
    let attempt = get_json(&format!("{base}/api/sessions/{id}")).await["attempt"]
        .as_str()
        .unwrap()
        .to_string();
    let routes = [
        format!("{base}/api/sessions/{id}"),
        format!("{base}/api/sessions/{id}/assessment"),
        format!("{base}/api/sessions/{id}/log.csv"),
        format!("{base}/api/sessions"),
        format!("{base}/api/attempts"),
        format!("{base}/api/attempts/{attempt}"),
        format!("{base}/api/attempts/{attempt}/inputs"),
        format!("{base}/api/attempts/{attempt}/replay?t=1"),
        format!("{base}/api/results.csv"),
        format!("{base}/api/exercises/fault-diagnosis"),
        format!("{base}/metrics"),
    ];
    let mut rest: Vec<(String, u16, String)> = Vec::new();
    let mut seq = 1;
    loop {
        for r in &routes {
            let (code, body) = get_as(r, &token).await;
            rest.push((r.clone(), code, body));
        }
        // a reply, an error and a refused command on the socket
        for m in [
            json!({"type": "input", "seq": seq, "arms": {"left": {"axes": [0, 0, 0, 0, 0, 0]}}}),
            json!({"type": "diagnose", "answer": "no-such-fault"}),
            json!({"type": "fault", "fault": "air"}),
        ] {
            tx.send(Message::Text(m.to_string().into())).await.unwrap();
        }
        tx.send(Message::Text("{not json".into())).await.unwrap();
        seq += 1;
        let t = get_json(&format!("{base}/api/sessions/{id}")).await["sim_seconds"]
            .as_f64()
            .unwrap();
        if t > injected_at + 1.5 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(700)).await;
    }
    // The replay socket is refused while the attempt runs.
    let replay_ws = format!(
        "{}/ws/replay/{attempt}?token={token}",
        s.base.replace("http://", "ws://")
    );
    match tokio_tungstenite::connect_async(&replay_ws).await {
        Ok((mut ws, _)) => {
            while let Some(Ok(m)) = ws.next().await {
                if let Message::Text(t) = m {
                    rest.push((replay_ws.clone(), 101, t.to_string()));
                }
            }
        }
        Err(e) => rest.push((replay_ws.clone(), 0, e.to_string())),
    }
    let still_running = get_json(&format!("{base}/api/sessions/{id}/assessment")).await;
    assert_eq!(
        still_running["done"], false,
        "the drill ended during the check"
    );
    reader.abort();
    let frames = seen.lock().unwrap().clone();
    assert!(
        frames.iter().any(|f| f.contains("\"hello\"")) && frames.len() > 20,
        "{} messages",
        frames.len()
    );
    let states: Vec<f64> = frames
        .iter()
        .filter_map(|f| serde_json::from_str::<Value>(f).ok())
        .filter(|v| v["type"] == "state")
        .filter_map(|v| v["t"].as_f64())
        .collect();
    assert!(
        states.iter().any(|&t| t > injected_at + 1.0),
        "no frame after the injection at {injected_at} s"
    );
    for p in &hidden {
        for f in &frames {
            assert!(!f.contains(p.as_str()), "the socket gave away {p}: {f}");
        }
        for (route, code, body) in &rest {
            assert!(
                !body.contains(p.as_str()),
                "{route} ({code}) gave away {p}: {body}"
            );
        }
    }
    // The record's routes stay shut while the attempt runs.
    for (route, code, _) in &rest {
        if route.contains("/inputs") || route.contains("/replay?") {
            assert_eq!(*code, 409, "{route}");
        }
    }
    s.stop().await;
}

/// The instructor's assessment of session `id`'s running attempt.
async fn assessment(base: &str, id: &str) -> Value {
    get_json(&format!("{base}/api/sessions/{id}/assessment")).await
}

/// The instructor's summary of session `id`.
async fn summary(base: &str, id: &str) -> Value {
    get_json(&format!("{base}/api/sessions/{id}")).await
}

/// Polls until attempt `attempt` is recorded as ended (the recorder writes asynchronously).
async fn ended(base: &str, attempt: &str) {
    for _ in 0..100 {
        let a = get_json(&format!("{base}/api/attempts/{attempt}")).await;
        if !a["outcome"].is_null() {
            return;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("attempt {attempt} never ended");
}

/// Issue 29 item 1: "a reset clears instructor faults unless the instructor marks them
/// persistent; a silent fault is shown to the trainee only in the debrief after the
/// attempt", and the seeds are unpredictable. Before: a silent `stuck_valve` stayed active in
/// the new attempt (and the drill's own fault with it) while the old attempt's record named
/// it to the trainee; the next seed was this one plus 1.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn try_again_clears_the_faults_and_draws_a_fresh_seed() {
    let s = start().await;
    let base = s.base.clone();
    let (_, c) = create(&s, json!({"exercise": "fault-diagnosis"})).await;
    let id = c["id"].as_str().unwrap().to_string();
    let token = c["control_token"].as_str().unwrap().to_string();
    let first = assessment(&base, &id).await;
    let a1 = summary(&base, &id).await["attempt"]
        .as_str()
        .unwrap()
        .to_string();
    // past the drill's injection, with a silent fault of the instructor's on top
    let due = first["diagnosis"]["injected_at_s"].as_f64().unwrap() + 0.5;
    while summary(&base, &id).await["sim_seconds"].as_f64().unwrap() < due {
        tokio::time::sleep(Duration::from_millis(250)).await;
    }
    let stuck = json!({"type": "fault", "fault": "stuck_valve", "arm": "right", "joint": 2,
        "value": 0.7, "silent": true});
    assert_eq!(act(&s, &id, TEACHER, stuck.clone()).await.0 / 100, 2);
    assert_eq!(
        summary(&base, &id).await["faults"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
    assert_eq!(
        act(&s, &id, &token, json!({"type": "reset"})).await.0 / 100,
        2
    );

    let second = assessment(&base, &id).await;
    let a2 = summary(&base, &id).await["attempt"]
        .as_str()
        .unwrap()
        .to_string();
    assert_ne!(a1, a2);
    let (s1, s2) = (
        first["seed"].as_u64().unwrap(),
        second["seed"].as_u64().unwrap(),
    );
    assert!(s2 != s1 && s2 != s1.wrapping_add(1), "seeds {s1} then {s2}");
    assert_eq!(
        summary(&base, &id).await["faults"],
        json!([]),
        "the reset kept a fault"
    );
    // The new attempt starts with no fault acting, as the first one did (neither the
    // instructor's stuck valve nor the drill's fault of the attempt before).
    let init = |a: &str| {
        let url = format!("{base}/api/attempts/{a}/inputs");
        async move { get_json(&url).await["init"].clone() }
    };
    let (i1, i2) = (init(&a1).await, init(&a2).await);
    assert_eq!(i2["faults"], json!([]));
    assert_eq!(i2["sim_faults"], i1["sim_faults"], "a fault carried over");
    // The ended attempt is the trainee's to read: its debrief names the silent fault.
    ended(&base, &a1).await;
    let (code, body) = get_as(&format!("{base}/api/attempts/{a1}"), &token).await;
    assert_eq!(code, 200, "{body}");
    assert!(body.contains("stuck_valve:right:2"), "{body}");

    // A persistent silent fault outlives the reset, and stays hidden from the trainee in
    // the attempt that injected it while it acts.
    let mut persistent = stuck;
    persistent["persistent"] = json!(true);
    assert_eq!(act(&s, &id, TEACHER, persistent).await.0 / 100, 2);
    assert_eq!(
        act(&s, &id, &token, json!({"type": "reset"})).await.0 / 100,
        2
    );
    let faults = summary(&base, &id).await["faults"].clone();
    assert_eq!(
        faults,
        json!([{"label": "stuck_valve:right:2:0.7", "silent": true}])
    );
    ended(&base, &a2).await;
    let (code, body) = get_as(&format!("{base}/api/attempts/{a2}"), &token).await;
    assert_eq!(code, 200, "{body}");
    assert!(!body.contains("stuck_valve:right"), "{body}");
    let inputs = format!("{base}/api/attempts/{a2}/inputs");
    assert_eq!(get_as(&inputs, &token).await.0, 409);
    assert_eq!(
        get_as(&inputs, TEACHER).await.0,
        200,
        "the instructor reads it"
    );
    assert_eq!(
        act(&s, &id, TEACHER, json!({"type": "clear_faults"}))
            .await
            .0
            / 100,
        2
    );
    let (code, body) = get_as(&inputs, &token).await;
    assert_eq!(code, 200, "cleared, the debrief opens: {body}");
    // the log form of the instructor's fault (the drill's own is on the left arm, arm 0)
    assert!(
        body.contains(r#"{"arm":1,"joint":2,"kind":"stuck_valve""#),
        "{body}"
    );
    s.stop().await;
}
