//! Issue 16: attempts recorded by a live server over real sockets, listed, protected by
//! token, and replayed: the state the replay gives at a recorded time equals the recorded
//! CSV row exactly (the CSV's numbers are shortest round-trip decimals, so they parse back
//! to the very bits the simulation had), for an attempt that began after a reset; and the
//! replay WebSocket plays, seeks and changes speed. Runs on SQLite and, when
//! `SEAARMS_TEST_DATABASE_URL` is set (tests/run.sh), on PostgreSQL.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};

async fn get_with(url: &str, token: &str) -> (u16, Value) {
    let (st, text) = get_as(url, token).await;
    (
        st,
        serde_json::from_str(&text).unwrap_or(Value::String(text)),
    )
}

/// Columns of the CSV header.
fn columns(header: &str) -> Vec<String> {
    header.split(',').map(str::to_string).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn attempts_are_recorded_listed_and_replay_the_recorded_rows_exactly() {
    for url in records_common::database_urls().await {
        eprintln!("database: {}", url.as_deref().unwrap_or("SQLite (default)"));
        recorded_listed_replayed(url).await;
    }
}

async fn recorded_listed_replayed(database_url: Option<String>) {
    let s = start_with(temp_dir("attempts"), |c| c.database_url = database_url).await;
    let (st, c) = create(
        &s,
        json!({"trainee": "Ada Lovelace", "group": "Class A", "scenario": "training"}),
    )
    .await;
    assert_eq!(st, 201, "{c}");
    let id = c["id"].as_str().unwrap().to_string();
    let token = c["control_token"].as_str().unwrap().to_string();
    let mut ws = trainee(&s, &id, &token).await;
    let mut seq = 0;
    drive(&mut ws, &mut seq, 60, 0.0).await;
    send(&mut ws, json!({"type": "reset"})).await;
    drive(&mut ws, &mut seq, 40, 1.0).await;
    send(
        &mut ws,
        json!({"type": "settings", "control_method": "closed"}),
    )
    .await;
    drive(&mut ws, &mut seq, 40, 2.0).await;
    // The session ends: its running attempt ends with it.
    let r = reqwest::Client::new()
        .delete(format!("{}/api/sessions/{id}", s.base))
        .bearer_auth(&token)
        .send()
        .await
        .unwrap();
    assert!(r.status().is_success(), "{}", r.status());

    // Both attempts are listed for the session, newest first, ended.
    let mut attempts = Vec::new();
    for _ in 0..50 {
        let list = get_json(&format!("{}/api/attempts?session={id}", s.base)).await;
        attempts = list["attempts"].as_array().unwrap().clone();
        if attempts.len() == 2 && attempts.iter().all(|a| a["outcome"].is_string()) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    assert_eq!(attempts.len(), 2, "{attempts:?}");
    let (second, first) = (&attempts[0], &attempts[1]);
    assert!(second["started_unix"].as_f64() >= first["started_unix"].as_f64());
    for a in &attempts {
        assert_eq!(a["trainee"], "Ada Lovelace");
        assert_eq!(a["group"], "Class A");
        assert_eq!(a["session"], id.as_str());
        assert_eq!(
            a["outcome"], "ended",
            "free play ends, it is not passed or failed"
        );
        assert_eq!(a["replayable"], true, "{a}");
        assert!(
            a["links"]["replay"]
                .as_str()
                .unwrap()
                .starts_with("/replay/")
        );
    }
    let a2 = second["id"].as_str().unwrap();

    // Who may read it: the trainee's token (after the session ended), the instructor; not
    // another token; an unknown id is 404 for the instructor.
    let (st, rec) = get_with(&format!("{}/api/attempts/{a2}", s.base), &token).await;
    assert_eq!(st, 200, "{rec}");
    assert!(
        rec["events"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "settings" && e["actor"] == "trainee"),
        "the settings change is a typed event: {}",
        rec["events"]
    );
    let (st, _) = get_with(&format!("{}/api/attempts/{a2}", s.base), "not-a-token").await;
    assert_eq!(st, 403);
    let (st, _) = get_with(
        &format!("{}/api/attempts/0123456789abcdef", s.base),
        TEACHER,
    )
    .await;
    assert_eq!(st, 404);
    let (st, _) = get_with(&format!("{}/api/attempts", s.base), &token).await;
    assert_eq!(st, 403, "listing is the instructor's");

    // The input log: small, and its inputs are the quantized sticks.
    let (st, inputs) = get_with(&format!("{}/api/attempts/{a2}/inputs", s.base), &token).await;
    assert_eq!(st, 200, "{inputs}");
    let entries = inputs["entries"].as_array().unwrap();
    assert!(entries.iter().any(|e| e["c"] == "settings"), "{inputs}");
    assert!(entries.iter().filter(|e| e["c"] == "input").count() >= 30);
    assert!(
        inputs["bytes"].as_u64().unwrap() < 8_000,
        "{}",
        inputs["bytes"]
    );

    // The CSV's rows of the second attempt (its `attempt` column; t restarts at the reset).
    let csv = get_text(&format!("{}/api/sessions/{id}/log.csv", s.base)).await;
    let mut lines = csv.lines();
    let cols = columns(lines.next().unwrap());
    let col = |name: &str| cols.iter().position(|c| c == name).unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let second_rows: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("attempt")] == a2).collect();
    assert!(second_rows.len() > 100, "{} rows", second_rows.len());
    assert!(
        second_rows[0][0].parse::<f64>().unwrap() < 0.02,
        "t restarts at the attempt"
    );
    assert!(
        rows.iter()
            .any(|r| r[col("attempt")] == first["id"].as_str().unwrap())
    );
    for row in second_rows.iter().step_by(second_rows.len() / 8).take(8) {
        let t: f64 = row[0].parse().unwrap();
        let (st, frame) = get_with(
            &format!("{}/api/attempts/{a2}/replay?t={t}", s.base),
            &token,
        )
        .await;
        assert_eq!(st, 200, "{frame}");
        assert_eq!(frame["t"].as_f64().unwrap(), t);
        for arm in ["left", "right"] {
            for (key, name) in [
                ("q", "q"),
                ("qd", "qd"),
                ("p_in", "p_in"),
                ("p_out", "p_out"),
            ] {
                for j in 0..6 {
                    let recorded: f64 =
                        row[col(&format!("{arm}_{name}{}", j + 1))].parse().unwrap();
                    let replayed = frame["arms"][arm][key][j].as_f64().unwrap();
                    assert_eq!(
                        replayed.to_bits(),
                        recorded.to_bits(),
                        "{arm} {key}[{j}] at t = {t}: replay {replayed} vs record {recorded}"
                    );
                }
            }
        }
        let pos = frame["object"]["pose"]["position"].as_array().unwrap();
        for (i, c) in ["object_x", "object_y", "object_z"].iter().enumerate() {
            let recorded: f64 = row[col(c)].parse().unwrap();
            assert_eq!(
                pos[i].as_f64().unwrap().to_bits(),
                recorded.to_bits(),
                "{c} at {t}"
            );
        }
    }

    // The replay socket: hello with the attempt's length, paused at 0; seek; play at 4×.
    let url = format!(
        "{}/ws/replay/{a2}?token={token}",
        s.base.replace("http://", "ws://")
    );
    let (mut rs, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = next_of(&mut rs, "hello", Duration::from_secs(10)).await;
    let duration = hello["replay"]["duration_s"].as_f64().unwrap();
    assert!(duration > 1.5, "{duration}");
    let st = next_of(&mut rs, "replay", Duration::from_secs(10)).await;
    assert_eq!(st["playing"], false);
    assert_eq!(st["t"], 0.0);
    send(&mut rs, json!({"type": "seek", "t": 0.5})).await;
    let f = next_of(&mut rs, "state", Duration::from_secs(10)).await;
    assert!((f["t"].as_f64().unwrap() - 0.5).abs() < 1e-9, "{}", f["t"]);
    send(&mut rs, json!({"type": "speed", "value": 9})).await;
    let e = next_of(&mut rs, "error", Duration::from_secs(10)).await;
    assert!(e["message"].as_str().unwrap().contains("speed"), "{e}");
    send(&mut rs, json!({"type": "speed", "value": 4})).await;
    send(&mut rs, json!({"type": "play"})).await;
    let wall = std::time::Instant::now();
    let mut last = next_of(&mut rs, "replay", Duration::from_secs(10)).await;
    while last["playing"] != true {
        last = next_of(&mut rs, "replay", Duration::from_secs(10)).await;
    }
    // Until 1 s of the attempt has played (it is longer than 1.5 s).
    while last["t"].as_f64().unwrap() < 1.5 {
        last = next_of(&mut rs, "replay", Duration::from_secs(10)).await;
    }
    let advanced = last["t"].as_f64().unwrap() - 0.5;
    let rate = advanced / wall.elapsed().as_secs_f64();
    eprintln!(
        "4x playback: {advanced:.3} s in {:.3} s wall = {rate:.2}x",
        wall.elapsed().as_secs_f64()
    );
    // Playback follows the wall clock; loose, since a loaded machine may lag.
    assert!(rate > 2.0, "4× playback advanced at {rate:.2}× real time");
    send(&mut rs, json!({"type": "bogus"})).await;
    next_of(&mut rs, "error", Duration::from_secs(10)).await;
    s.stop().await;
}

/// An attempt recorded by another build is listed with its assessment but not re-simulated:
/// `replayable` is false, `replay_note` names both versions, and the replay answers 409.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_attempt_of_another_simulator_version_says_it_cannot_be_replayed() {
    use seaarms::db::{Db, Write};
    use seaarms::sessions::record::{AttemptEnd, AttemptStart};
    let dir = temp_dir("attempts");
    let db = Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let (session, attempt) = ("00000000000000aa", "00000000000000bb");
    let old = "0.0.1+0123456789abcdef";
    db.block_on(db.write_batch(&[
        Write::Session {
            id: session.into(),
            trainee: "Grace".into(),
            group: "B".into(),
            scenario: "training".into(),
            created_unix: 1.0,
            token_sha256: seaarms::auth::sha256_hex("old-token"),
        },
        Write::AttemptStart(Box::new(AttemptStart {
            id: attempt.into(),
            session: session.into(),
            scenario: "training".into(),
            exercise: None,
            exercise_version: None,
            sim_version: old.into(),
            started_unix: 1.0,
            init: json!({}),
        })),
        Write::AttemptEnd(Box::new(AttemptEnd {
            id: attempt.into(),
            ended_unix: 2.0,
            sim_seconds: 1.0,
            outcome: "ended".into(),
            score: None,
            assessment: None,
        })),
    ]))
    .unwrap();
    drop(db);
    let s = start_with(dir, |_| {}).await;
    let (st, a) = get_with(&format!("{}/api/attempts/{attempt}", s.base), "old-token").await;
    assert_eq!(st, 200, "{a}");
    assert_eq!(a["replayable"], false);
    let note = a["replay_note"].as_str().unwrap();
    assert!(
        note.contains(old) && note.contains(seaarms::replay::SIM_VERSION),
        "{note}"
    );
    let (st, e) = get_with(
        &format!("{}/api/attempts/{attempt}/replay?t=0.5", s.base),
        "old-token",
    )
    .await;
    assert_eq!(st, 409, "{e}");
    assert!(e.to_string().contains(old), "{e}");
    s.stop().await;
}

/// Issue 26: the replay socket takes client messages at the session socket's rate
/// (`--max-messages-per-second`, bursts of two seconds' worth, the same limiter): a burst of
/// 40 messages at 5 per second gets the session socket's "too many messages" notice (its
/// text is the one tests/sessions.rs reads on the session socket), and the
/// socket goes on answering once the rate allows.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_replay_socket_has_the_session_sockets_message_rate_limit() {
    let s = start_with(temp_dir("replay-rate"), |c| c.max_messages_per_second = 5).await;
    let (attempt, token) = ended_attempt(&s).await;
    let url = format!(
        "{}/ws/replay/{attempt}?token={token}",
        s.base.replace("http://", "ws://")
    );
    let (mut rs, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    next_of(&mut rs, "hello", Duration::from_secs(10)).await;
    next_of(&mut rs, "replay", Duration::from_secs(10)).await;
    for _ in 0..40 {
        send(&mut rs, json!({"type": "pause"})).await;
    }
    let e = next_of(&mut rs, "error", Duration::from_secs(10)).await;
    let message = e["message"].as_str().unwrap();
    assert!(
        message.contains("too many messages: at most 5 per second"),
        "{message}"
    );
    // The bucket refills at 5 a second: after 1.5 s a seek is answered.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    send(&mut rs, json!({"type": "seek", "t": 0.05})).await;
    let f = next_of(&mut rs, "state", Duration::from_secs(10)).await;
    assert!((f["t"].as_f64().unwrap() - 0.05).abs() < 1e-9, "{}", f["t"]);
    s.stop().await;
}

/// Issue 29 item 2: "one trainee can take every replay slot" (32 sockets on their own
/// attempt, never read: the instructor's 33rd got 503). A trainee's token holds at most
/// `REPLAYS_PER_TRAINEE` replay sockets (then 429) and never the instructor's reserve; the
/// instructor still opens one; a closed socket gives its slot back.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_trainee_cannot_take_every_replay_slot() {
    use seaarms::api::attempts::REPLAYS_PER_TRAINEE;
    let s = start_with(temp_dir("replay-caps"), |_| {}).await;
    let (attempt, token) = ended_attempt(&s).await;
    let ws = |tok: &str| {
        format!(
            "{}/ws/replay/{attempt}?token={tok}",
            s.base.replace("http://", "ws://")
        )
    };
    let open = |url: String| async move {
        match tokio_tungstenite::connect_async(&url).await {
            Ok((mut rs, _)) => {
                next_of(&mut rs, "hello", Duration::from_secs(10)).await;
                Ok(rs)
            }
            Err(tokio_tungstenite::tungstenite::Error::Http(r)) => Err(r.status().as_u16()),
            Err(e) => panic!("{e}"),
        }
    };
    let mut mine = Vec::new();
    for _ in 0..REPLAYS_PER_TRAINEE {
        mine.push(open(ws(&token)).await.expect("within the trainee's share"));
    }
    assert_eq!(
        open(ws(&token)).await.err(),
        Some(429),
        "one more than the share"
    );
    let instructor = open(ws(TEACHER)).await;
    assert!(instructor.is_ok(), "the instructor opens a replay");
    drop(mine.pop());
    let mut again = None;
    for _ in 0..50 {
        if let Ok(rs) = open(ws(&token)).await {
            again = Some(rs);
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(again.is_some(), "a closed socket gives its slot back");
    // The REST seek: one at a time per trainee, on the compute pool.
    let url = format!("{}/api/attempts/{attempt}/replay?t=0.5", s.base);
    let (st, v) = get_with(&url, &token).await;
    assert_eq!(st, 200, "{v}");
    s.stop().await;
}

/// A finished attempt of a new session (driven briefly, then ended by its trainee); its id
/// and the session's control token.
async fn ended_attempt(s: &common::Server) -> (String, String) {
    let (id, token) = new_session(s).await;
    let mut ws = trainee(s, &id, &token).await;
    let mut seq = 0;
    drive(&mut ws, &mut seq, 5, 0.0).await;
    let r = reqwest::Client::new()
        .delete(format!("{}/api/sessions/{id}", s.base))
        .bearer_auth(&token)
        .send()
        .await
        .unwrap();
    assert!(r.status().is_success(), "{}", r.status());
    let mut attempt = None;
    for _ in 0..50 {
        let list = get_json(&format!("{}/api/attempts?session={id}", s.base)).await;
        if let Some(a) = list["attempts"]
            .as_array()
            .and_then(|a| a.first())
            .filter(|a| a["outcome"].is_string())
        {
            attempt = a["id"].as_str().map(str::to_string);
            break;
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    let attempt = attempt.expect("the attempt is recorded");
    (attempt, token)
}
