//! Issue 30 item 5, "take over from here": a live attempt started from an attempt's replayed
//! state at t begins exactly there — its first frame's joint angles, velocities, pressures and
//! box pose equal the REST replay's frame at t bit for bit (the reference is the replay route
//! of the source, a different path from the take-over's own seek and session) —, is itself
//! replayed bit for bit (its replay at its end equals the last live frame), a take-over of a
//! take-over replays too, the route refuses what it should (400, 403, 404, 409, and 429 past a
//! client's cap of live sessions, as `POST /api/sessions`), and practice attempts are left out
//! of the learning curves and the logbook's counts.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::time::{Duration, Instant};

use common::*;
use records_common::Binary;
use seaarms::db::{Db, Write};
use seaarms::sessions::record::{AttemptEnd, AttemptStart};
use serde_json::{Value, json};

/// POST /api/attempts/{id}/take-over with `body` and `token`: status, body, whether a cookie
/// was set.
async fn take_over(base: &str, id: &str, token: &str, body: Value) -> (u16, Value, bool) {
    let r = reqwest::Client::new()
        .post(format!("{base}/api/attempts/{id}/take-over"))
        .bearer_auth(token)
        .json(&body)
        .send()
        .await
        .unwrap();
    let st = r.status().as_u16();
    let cookie = r.headers().get("set-cookie").is_some();
    let text = r.text().await.unwrap();
    (
        st,
        serde_json::from_str(&text).unwrap_or(Value::String(text)),
        cookie,
    )
}

/// Every number of a frame that the state is made of, as bits: both arms' q, q̇, line
/// pressures, the box pose and velocity, and the time.
fn state_bits(frame: &Value) -> Vec<u64> {
    let mut v = Vec::new();
    for arm in ["left", "right"] {
        for k in ["q", "qd", "p_in", "p_out"] {
            for x in frame["arms"][arm][k].as_array().unwrap() {
                v.push(x.as_f64().unwrap().to_bits());
            }
        }
    }
    let o = &frame["object"];
    let rows = o["pose"]["rotation"].as_array().unwrap();
    for x in o["pose"]["position"]
        .as_array()
        .unwrap()
        .iter()
        .chain(rows.iter().flat_map(|r| r.as_array().unwrap()))
        .chain(o["velocity"].as_array().unwrap())
    {
        v.push(x.as_f64().unwrap().to_bits());
    }
    v.push(frame["t"].as_f64().unwrap().to_bits());
    v
}

/// The frame at `t` of attempt `id` by the REST replay route.
async fn replay_at(base: &str, id: &str, token: &str, t: f64) -> Value {
    let (st, text) = get_as(&format!("{base}/api/attempts/{id}/replay?t={t}"), token).await;
    assert_eq!(st, 200, "{text}");
    serde_json::from_str(&text).unwrap()
}

/// The attempt `id` once it has ended (the recorder writes within about a second).
async fn ended(base: &str, id: &str) -> Value {
    for _ in 0..100 {
        let a = get_json(&format!("{base}/api/attempts/{id}")).await;
        if a["outcome"].is_string() {
            return a;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("attempt {id} did not end");
}

/// The session `id`'s attempts, newest first, once `n` are listed and ended.
async fn attempts_of(base: &str, session: &str, n: usize) -> Vec<Value> {
    for _ in 0..100 {
        let list = get_json(&format!("{base}/api/attempts?session={session}")).await;
        let a = list["attempts"].as_array().unwrap().clone();
        if a.len() == n && a.iter().all(|a| a["outcome"].is_string()) {
            return a;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("session {session}: not {n} ended attempts");
}

/// Pauses the session and returns its first paused frame: the state its attempt ends in.
async fn pause_and_read(ws: &mut Ws) -> Value {
    send(ws, json!({"type": "pause"})).await;
    loop {
        let f = next_of(ws, "state", Duration::from_secs(5)).await;
        if f["paused"] == true {
            return f;
        }
    }
}

/// Ends session `id` with `token`.
async fn end(base: &str, id: &str, token: &str) {
    let r = reqwest::Client::new()
        .delete(format!("{base}/api/sessions/{id}"))
        .bearer_auth(token)
        .send()
        .await
        .unwrap();
    assert!(r.status().is_success(), "{}", r.status());
}

/// Drives the session `created` (as `POST /api/sessions` answered) for `messages` × 20 ms over
/// its trainee socket, ends it, and returns its one attempt once it has ended.
async fn drive_and_end(s: &Server, created: &Value, messages: u64) -> Value {
    let id = created["id"].as_str().unwrap();
    let token = created["control_token"].as_str().unwrap();
    let mut ws = trainee(s, id, token).await;
    drive(&mut ws, &mut 0, messages, 0.0).await;
    end(&s.base, id, token).await;
    attempts_of(&s.base, id, 1).await.remove(0)
}

/// Ada's reach-targets session driven for `messages` × 20 ms and ended: its control token and
/// its one (ended) attempt, the source the tests take over from.
async fn ada_source(s: &Server, messages: u64) -> (String, Value) {
    let (st, c) = create(
        s,
        json!({"trainee": "Ada", "group": "T", "exercise": "reach-targets"}),
    )
    .await;
    assert_eq!(st, 201, "{c}");
    let token = c["control_token"].as_str().unwrap().to_string();
    (token, drive_and_end(s, &c, messages).await)
}

/// A new session's first state frame, from its trainee socket.
async fn first_frame(s: &Server, created: &Value) -> (Ws, Value) {
    let id = created["id"].as_str().unwrap();
    let token = created["control_token"].as_str().unwrap();
    let mut ws = trainee(s, id, token).await;
    let f = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    (ws, f)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_take_over_starts_at_the_replayed_frame_and_replays_bit_for_bit() {
    let dir = temp_dir("takeover");
    let s = start_with(dir.clone(), |_| {}).await;
    let base = s.base.clone();

    // The source: an exercise attempt driven over the socket, abandoned by ending the session.
    let (token, source) = ada_source(&s, 80).await;
    let src = source["id"].as_str().unwrap().to_string();
    assert_eq!(source["practice"], false);
    let length = source["sim_seconds"].as_f64().unwrap();
    assert!(length > 1.2, "{source}");

    // (a) The take-over at t: the new session's first frame is the replay's frame at t.
    let t = 1.2345;
    let at_t = replay_at(&base, &src, &token, t).await;
    // the simulation's clock sums 1 ms steps: the nearest step, 1235, within rounding
    assert!(
        (at_t["t"].as_f64().unwrap() - 1.235).abs() < 1e-9,
        "the nearest step"
    );
    // (not the start's state: the arms moved by then)
    let at_0 = replay_at(&base, &src, &token, 0.0).await;
    assert!(state_bits(&at_0)[..12] != state_bits(&at_t)[..12]);
    let (st, created, cookie) = take_over(&base, &src, &token, json!({"t": t})).await;
    assert_eq!(st, 201, "{created}");
    assert!(
        cookie,
        "the trainee's cookie is set, as POST /api/sessions sets it"
    );
    for k in ["id", "control_token", "ws_url", "replica", "base"] {
        assert!(created.get(k).is_some(), "{k} in {created}");
    }
    let (mut ws2, first) = first_frame(&s, &created).await;
    assert_eq!(first["awaiting_ready"], true, "it waits for ready");
    assert_eq!(first["practice"]["attempt"], src.as_str());
    assert!(
        state_bits(&first) == state_bits(&at_t),
        "the first frame differs from the replay at t:\n{first}\n{at_t}"
    );
    // Waiting for ready, it does not step: a later frame is the same state.
    tokio::time::sleep(Duration::from_millis(300)).await;
    let later = next_of(&mut ws2, "state", Duration::from_secs(5)).await;
    assert!(state_bits(&later) == state_bits(&at_t));

    // (b) Drive the practice attempt, end it: its replay at its end is its last live frame.
    send(&mut ws2, json!({"type": "ready"})).await;
    let mut seq2 = 0;
    drive(&mut ws2, &mut seq2, 60, 1.0).await;
    let last = pause_and_read(&mut ws2).await;
    let id2 = created["id"].as_str().unwrap();
    let token2 = created["control_token"].as_str().unwrap();
    end(&base, id2, token2).await;
    let practice = attempts_of(&base, id2, 1).await.remove(0);
    let p = practice["id"].as_str().unwrap().to_string();
    assert_eq!(practice["practice"], true, "{practice}");
    assert_eq!(practice["taken_over_from"]["attempt"], src.as_str());
    assert_eq!(practice["taken_over_from"]["t"], 1.235);
    assert_eq!(practice["trainee"], "Ada");
    assert_eq!(practice["group"], "T");
    assert_eq!(practice["exercise"], "reach-targets");
    let end_t = practice["sim_seconds"].as_f64().unwrap();
    assert_eq!(
        end_t,
        last["t"].as_f64().unwrap(),
        "it ended where it paused"
    );
    assert!(end_t > t + 0.5, "it ran after the take-over: {end_t}");
    let replayed = replay_at(&base, &p, token2, end_t).await;
    assert!(
        state_bits(&replayed) == state_bits(&last),
        "the practice attempt's replay at its end differs from its last frame:\n{replayed}\n{last}"
    );
    // Its replay before t is the source's (the timeline starts at the source's start).
    let early = replay_at(&base, &p, token2, 0.5).await;
    assert!(state_bits(&early) == state_bits(&replay_at(&base, &src, &token, 0.5).await));

    // (c) A take-over of the take-over (by the instructor) starts at its replayed frame, and
    // replays there too.
    let t3 = (t + end_t) / 2.0;
    let at_t3 = replay_at(&base, &p, TEACHER, t3).await;
    let (st, c3, _) = take_over(&base, &p, TEACHER, json!({"t": t3})).await;
    assert_eq!(st, 201, "{c3}");
    let (_ws3, first3) = first_frame(&s, &c3).await;
    assert!(state_bits(&first3) == state_bits(&at_t3));
    let id3 = c3["id"].as_str().unwrap();
    end(&base, id3, c3["control_token"].as_str().unwrap()).await;
    let a3 = attempts_of(&base, id3, 1).await.remove(0);
    let a3id = a3["id"].as_str().unwrap();
    assert_eq!(a3["taken_over_from"]["attempt"], p.as_str());
    let again = replay_at(&base, a3id, TEACHER, a3["sim_seconds"].as_f64().unwrap()).await;
    assert!(
        state_bits(&again) == state_bits(&first3),
        "the take-over of a take-over replays to its (unstepped) end"
    );
    let inputs = get_json(&format!("{base}/api/attempts/{a3id}/inputs")).await;
    assert_eq!(inputs["init"]["from"]["attempt"], p.as_str());

    // (d) What the route refuses. A chain of take-overs stops at MAX_TAKE_OVERS (8) links from
    // the attempt started afresh: `a3` is two links deep (src → p → a3); six more take-overs
    // reach eight, and taking over the eighth is refused with 409, its chain still replayable.
    let mut last = a3id.to_string();
    for depth in 3..=seaarms::replay::MAX_TAKE_OVERS {
        let length = ended(&base, &last).await["sim_seconds"].as_f64().unwrap();
        let (st, c, _) = take_over(&base, &last, TEACHER, json!({"t": length})).await;
        assert_eq!(st, 201, "take-over {depth}: {c}");
        let id = c["id"].as_str().unwrap();
        end(&base, id, c["control_token"].as_str().unwrap()).await;
        last = attempts_of(&base, id, 1).await.remove(0)["id"]
            .as_str()
            .unwrap()
            .to_string();
    }
    let (st, b, _) = take_over(&base, &last, TEACHER, json!({"t": 0.1})).await;
    assert_eq!(st, 409, "a ninth link: {b}");
    assert!(b["error"].as_str().unwrap().contains("take-overs"), "{b}");
    let deepest = replay_at(&base, &last, TEACHER, 0.5).await;
    assert!(
        state_bits(&deepest) == state_bits(&replay_at(&base, &src, TEACHER, 0.5).await),
        "the eighth link replays from the first attempt's start"
    );
    let url_src = src.as_str();
    for (body, why) in [
        (json!({"t": -1}), "negative"),
        (json!({"t": length + 1.0}), "beyond the length"),
        (json!({}), "missing"),
        (json!({"t": "soon"}), "not a number"),
        (json!({"t": 1, "x": 2}), "unknown field"),
    ] {
        let (st, b, _) = take_over(&base, url_src, &token, body).await;
        assert_eq!(st, 400, "{why}: {b}");
        assert!(b["error"].is_string(), "{b}");
    }
    let (st, _, _) = take_over(&base, url_src, "not-a-token", json!({"t": 1})).await;
    assert_eq!(st, 403, "a wrong token");
    let (st, other) = create(&s, json!({"trainee": "Bo", "group": "T"})).await;
    assert_eq!(st, 201);
    let (st, _, _) = take_over(
        &base,
        url_src,
        other["control_token"].as_str().unwrap(),
        json!({"t": 1}),
    )
    .await;
    assert_eq!(st, 403, "another trainee's token");
    let (st, _, _) = take_over(&base, "0123456789abcdef", TEACHER, json!({"t": 1})).await;
    assert_eq!(st, 404, "an unknown attempt");
    // free play is not taken over (409)
    let otoken = other["control_token"].as_str().unwrap();
    let free = drive_and_end(&s, &other, 10).await;
    let (st, b, _) = take_over(
        &base,
        free["id"].as_str().unwrap(),
        otoken,
        json!({"t": 0.1}),
    )
    .await;
    assert_eq!(st, 409, "free play: {b}");
    let _ = ended(&base, &src).await;
    s.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}

/// A take-over creates a session, so it is admitted as `POST /api/sessions` is
/// (`api::sessions::admit`): past a client's cap of live sessions (here 2) it gets 429 naming
/// the cap; the instructor's token is not capped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn take_overs_count_against_a_clients_live_sessions() {
    let dir = temp_dir("takeover-cap");
    let s = start_with(dir.clone(), |c| c.max_sessions_per_client = 2).await;
    let base = s.base.clone();
    let (token, source) = ada_source(&s, 40).await;
    let src = source["id"].as_str().unwrap().to_string();
    for k in 1..=2 {
        let (st, b, _) = take_over(&base, &src, &token, json!({"t": 0.5})).await;
        assert_eq!(st, 201, "take-over {k}: {b}");
    }
    let r = reqwest::Client::new()
        .post(format!("{base}/api/attempts/{src}/take-over"))
        .bearer_auth(&token)
        .json(&json!({"t": 0.5}))
        .send()
        .await
        .unwrap();
    assert_eq!(
        r.status().as_u16(),
        429,
        "a third live session for this client"
    );
    let b: Value = r.json().await.unwrap();
    assert!(
        b["error"].as_str().unwrap().contains("live sessions"),
        "{b}"
    );
    let (st, b, _) = take_over(&base, &src, TEACHER, json!({"t": 0.5})).await;
    assert_eq!(st, 201, "the instructor: {b}");
    s.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}

const GROUP: &str = "ROV-practice";

fn attempt(id: &str, session: &str, started: f64, outcome: &str, from: Option<&str>) -> [Write; 2] {
    let mut init = json!({});
    if let Some(f) = from {
        init = json!({"from": {"attempt": f, "step": 1500}});
    }
    [
        Write::AttemptStart(Box::new(AttemptStart {
            id: id.into(),
            session: session.into(),
            scenario: "reach-targets".into(),
            exercise: Some("reach-targets".into()),
            exercise_version: Some("1".into()),
            sim_version: "sim-1".into(),
            started_unix: started,
            init,
        })),
        Write::AttemptEnd(Box::new(AttemptEnd {
            id: id.into(),
            ended_unix: started + 30.0,
            sim_seconds: 30.0,
            outcome: outcome.into(),
            score: Some(if outcome == "passed" { 90.0 } else { 30.0 }),
            assessment: None,
        })),
    ]
}

/// (e) Practice attempts count nowhere: 12 passes make a trainee proficient at 12 (the
/// CUSUM by hand: tests/progress.rs), and failed practice attempts between them change
/// neither the curve nor the logbook's count; the attempts list still shows them, marked.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn practice_attempts_are_left_out_of_progress_and_the_logbook() {
    let dir = temp_dir("takeover-progress");
    let db = Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let mut batch = Vec::new();
    for k in 0..12 {
        let sid = format!("{k:016x}");
        batch.push(Write::Session {
            id: sid.clone(),
            trainee: "Pia".into(),
            group: GROUP.into(),
            scenario: "reach-targets".into(),
            created_unix: 1_700_000_000.0,
            token_sha256: "ab".repeat(32),
        });
        let started = 1_700_000_000.0 + 3600.0 * k as f64;
        let id = format!("a{sid}");
        batch.extend(attempt(&id, &sid, started, "passed", None));
        // a failed practice attempt taken over from it
        batch.extend(attempt(
            &format!("p{sid}"),
            &sid,
            started + 60.0,
            "failed",
            Some(&id),
        ));
    }
    db.write_batch(&batch).await.unwrap();
    drop(db);
    let s = Binary::start(&dir, &[]);
    let (st, text) = get_as(
        &format!(
            "{}/api/progress?exercise=reach-targets&group={GROUP}",
            s.base
        ),
        TEACHER,
    )
    .await;
    assert_eq!(st, 200, "{text}");
    let class: Value = serde_json::from_str(&text).unwrap();
    let pia = &class["trainees"][0];
    assert_eq!(pia["trainee"], "Pia");
    assert_eq!(pia["attempts"].as_array().unwrap().len(), 12, "{pia}");
    assert_eq!(pia["state"], "proficient", "{pia}");
    assert_eq!(pia["proficient_at"], 12);

    let (st, text) = get_as(
        &format!("{}/api/logbook?trainee=Pia&group={GROUP}", s.base),
        TEACHER,
    )
    .await;
    assert_eq!(st, 200, "{text}");
    let book: Value = serde_json::from_str(&text).unwrap();
    let e = book["exercises"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["exercise"] == "reach-targets")
        .unwrap_or_else(|| panic!("{book}"))
        .clone();
    assert_eq!(e["attempts"], 12, "{e}");
    assert_eq!(e["finished"], 12, "{e}");
    assert_eq!(e["passes"], 12, "{e}");

    let (_, text) = get_as(
        &format!("{}/api/attempts?trainee=Pia&group={GROUP}", s.base),
        TEACHER,
    )
    .await;
    let list: Value = serde_json::from_str(&text).unwrap();
    let all = list["attempts"].as_array().unwrap();
    assert_eq!(all.len(), 24, "the list shows every attempt");
    let practice: Vec<&Value> = all.iter().filter(|a| a["practice"] == true).collect();
    assert_eq!(practice.len(), 12);
    assert!(practice.iter().all(|a| a["taken_over_from"]["t"] == 1.5));
    drop(s);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Take-over latency for a `seconds`-long exercise attempt recorded through the server's
/// recorder (cold: no replay has been there; warm: a second take-over at the same t).
/// Prints the numbers; run with `cargo test --release --test takeover -- --ignored`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "a measurement: run in release"]
async fn take_over_latency_60_and_300_s() {
    use seaarms::catalogue::Scenario;
    use seaarms::sessions::command::{ArmSticks, Command, StickInput};
    use seaarms::sessions::record::RecordMsg;
    use seaarms::sessions::{AttemptStop, Live};
    let dir = temp_dir("takeover-latency");
    let config = seaarms::config::ServeConfig {
        data_dir: dir.clone(),
        instructor_token: Some(TEACHER.into()),
        ..Default::default()
    };
    let state = seaarms::app::AppState::new(&config).unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let server = tokio::spawn(seaarms::run(listener, state.clone(), async {
        let _ = rx.await;
    }));
    let (st, c) = create_at(
        &base,
        json!({"trainee": "Lat", "exercise": "reach-targets"}),
    )
    .await;
    assert_eq!(st, 201);
    let session = c["id"].as_str().unwrap().to_string();
    for seconds in [60u64, 300] {
        let (st2, session) = (state.clone(), session.clone());
        let id = tokio::task::spawn_blocking(move || {
            let models = [st2.sessions.magnum(), st2.sessions.magnum()];
            let scenario = Scenario::resolve("reach-targets").unwrap();
            let mut live = Live::new(&session, &models, &scenario, None, None, 3, None).unwrap();
            let mut records = Vec::new();
            // the synthetic pattern of `replay::synthetic`: one axis at a time, every 0.25 s
            for i in 0..seconds * 4 {
                let mut axes = [0.0; 6];
                axes[((i / 8) % 6) as usize] = if (i / 3) % 2 == 0 { 0.8 } else { -0.6 };
                let input = StickInput {
                    seq: i + 1,
                    arms: [ArmSticks { axes, grip: 0.0 }; 2],
                    ..StickInput::default()
                };
                live.apply(&Command::Input(input)).unwrap();
                for _ in 0..250 {
                    live.advance();
                }
                if i % 4 == 3 {
                    records.extend(live.take_records(true));
                }
            }
            live.end_attempt(AttemptStop::Left);
            records.extend(live.take_records(false));
            let mut id = None;
            for msg in records {
                if let RecordMsg::AttemptStarted(a) = &msg {
                    id = Some(a.id.clone());
                }
                st2.sessions.recorder.send(msg);
            }
            st2.sessions.recorder.flush();
            id.unwrap()
        })
        .await
        .unwrap();
        let t = seconds as f64 - 0.5;
        for run in ["cold", "warm"] {
            let t0 = Instant::now();
            let (st, c, _) = take_over(&base, &id, TEACHER, json!({"t": t})).await;
            let ms = t0.elapsed().as_secs_f64() * 1000.0;
            assert_eq!(st, 201, "{c}");
            eprintln!("take-over of a {seconds} s attempt at {t} s, {run}: {ms:.0} ms");
            end(&base, c["id"].as_str().unwrap(), TEACHER).await;
        }
    }
    let _ = tx.send(());
    let _ = server.await;
    let _ = std::fs::remove_dir_all(&dir);
}
