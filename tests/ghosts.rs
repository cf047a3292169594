//! Ghosts over the real binary (issue 30 item 5): an attempt's track sampled at 10 Hz equals
//! the REST replay's state frame (`GET /api/attempts/{id}/replay?t=`, the debrief's seek) at
//! every sampled time within the track's rounding; `GET /api/sessions/{id}/ghosts` names the
//! trainee's highest-scoring attempt (picked here from the stored scores) and the reference
//! operator's; a trainee reads its own and the reference operators' tracks and gets 403 on
//! another trainee's; unknown attempts are 404. The attempts are headless reach-targets runs of
//! a human-paced operator with seeded variation (`seaarms::exercises::HumanNoise`), recorded
//! as a live session records them; a 120 s free-play attempt (`replay::synthetic`) gives the
//! track's size and build time, printed.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::time::Instant;

use common::{TEACHER, get_as, magnum, temp_dir};
use records_common::Binary;
use seaarms::auth::sha256_hex;
use seaarms::catalogue::EXERCISES;
use seaarms::db::{Db, Write};
use seaarms::exercises::{Driver, HumanNoise, run_recorded};
use seaarms::replay::SIM_VERSION;
use seaarms::replay::track::{POSITION_QUANTUM_M, VALUE_QUANTUM};
use seaarms::sessions::record::{AttemptEnd, AttemptStart};
use serde_json::{Value, json};

const EXERCISE: &str = "reach-targets";
const GROUP: &str = "ROV-ghost";

/// A session of `trainee` whose control token is `token`.
fn session(id: &str, trainee: &str, token: &str) -> Write {
    Write::Session {
        id: id.into(),
        trainee: trainee.into(),
        group: GROUP.into(),
        scenario: EXERCISE.into(),
        created_unix: 1_700_000_000.0,
        token_sha256: sha256_hex(token),
    }
}

/// The records of one attempt as the recorder writes them.
#[allow(clippy::too_many_arguments)]
fn attempt(
    id: &str,
    session: &str,
    scenario: &str,
    init: Value,
    inputs: Vec<u8>,
    sim_seconds: f64,
    started: f64,
    assessment: Option<Value>,
) -> Vec<Write> {
    let (outcome, score) = match &assessment {
        Some(a) if a["passed"] == true => ("passed", a["score"].as_f64()),
        Some(a) => ("failed", a["score"].as_f64()),
        None => ("ended", None),
    };
    vec![
        Write::AttemptStart(Box::new(AttemptStart {
            id: id.into(),
            session: session.into(),
            scenario: scenario.into(),
            exercise: assessment.as_ref().map(|_| EXERCISE.into()),
            exercise_version: None,
            sim_version: SIM_VERSION.into(),
            started_unix: started,
            init,
        })),
        Write::AttemptInputs {
            id: id.into(),
            seq: 0,
            data: inputs,
            sim_seconds,
        },
        Write::AttemptEnd(Box::new(AttemptEnd {
            id: id.into(),
            ended_unix: started + sim_seconds,
            sim_seconds,
            outcome: outcome.into(),
            score,
            assessment,
        })),
    ]
}

async fn get(url: &str, token: &str) -> (u16, Value) {
    let (status, text) = get_as(url, token).await;
    (status, serde_json::from_str(&text).unwrap_or(Value::Null))
}

/// A frame's pose `{position, rotation}` as the track's 12 numbers.
fn flat(p: &Value) -> Vec<f64> {
    let mut v: Vec<f64> = (0..3).map(|i| p["position"][i].as_f64().unwrap()).collect();
    for i in 0..3 {
        for j in 0..3 {
            v.push(p["rotation"][i][j].as_f64().unwrap());
        }
    }
    v
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// `sample` is `frame` rounded: positions to 0.1 mm, angles and rotations to 1e-4 (half a
/// quantum, and the float's last bits).
fn check_sample(sample: &Value, frame: &Value, what: &str) {
    let close = |a: &[f64], b: &[f64], quantum: f64, name: &str| {
        assert_eq!(a.len(), b.len(), "{what} {name}");
        for (x, y) in a.iter().zip(b) {
            assert!(
                (x - y).abs() <= quantum / 2.0 + 1e-12,
                "{what} {name}: track {x} vs replay {y}"
            );
        }
    };
    let pose = |track: &Value, replay: &Value, name: &str| {
        let (t, r) = (nums(track), flat(replay));
        close(&t[..3], &r[..3], POSITION_QUANTUM_M, name);
        close(&t[3..], &r[3..], VALUE_QUANTUM, name);
    };
    close(
        &[sample["t"].as_f64().unwrap()],
        &[frame["t"].as_f64().unwrap()],
        1e-3,
        "t",
    );
    for (i, side) in ["left", "right"].iter().enumerate() {
        let (s, f) = (&sample["arms"][i], &frame["arms"][side]);
        close(&nums(&s["q"]), &nums(&f["q"]), VALUE_QUANTUM, "q");
        close(
            &[s["jaw_opening_m"].as_f64().unwrap()],
            &[f["jaw_opening_m"].as_f64().unwrap()],
            POSITION_QUANTUM_M,
            "jaw",
        );
        let frames = f["joint_frames"].as_array().unwrap();
        assert_eq!(s["joint_frames"].as_array().unwrap().len(), frames.len());
        for (k, jf) in frames.iter().enumerate() {
            pose(
                &s["joint_frames"][k],
                jf,
                &format!("{side} joint frame {k}"),
            );
        }
        pose(&s["pose"], &f["pose"], &format!("{side} tool pose"));
    }
    pose(&sample["object"], &frame["object"]["pose"], "object");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tracks_follow_the_replay_and_ghosts_name_the_best_attempts() {
    let spec = EXERCISES.get(EXERCISE).unwrap();
    let models = magnum();
    // Ada's two attempts (sessions a1, a2: two days), Ben's (a reference operator) and Cy's
    let runs: Vec<_> = [
        (1.0, 0.2, 11),
        (1.5, 0.4, 12),
        (1.0, 0.2, 13),
        (2.0, 0.5, 14),
    ]
    .into_iter()
    .map(|(reaction, misjudge, seed)| {
        let noise = HumanNoise {
            reaction,
            jitter: 0.3,
            misjudge,
            seed,
        };
        run_recorded(
            spec.clone(),
            &models,
            Driver::Noisy(noise),
            seed,
            &mut |_| {},
        )
        .unwrap()
    })
    .collect();
    let long = seaarms::replay::synthetic::free_play(&models, "s-free", 120, &mut |_| {}).unwrap();

    let dir = temp_dir("ghosts");
    let db = Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let sessions = [
        ("00000000000000a1", "Ada", "tok-ada-1"),
        ("00000000000000a2", "Ada", "tok-ada-2"),
        ("00000000000000b1", "Ben", "tok-ben"),
        ("00000000000000c1", "Cy", "tok-cy"),
    ];
    let mut batch: Vec<Write> = sessions
        .iter()
        .map(|(id, name, tok)| session(id, name, tok))
        .collect();
    let ids = ["ada1", "ada2", "bbb1", "ccc1"].map(|a| format!("{a}000000000000"));
    let mut scores = Vec::new();
    for (k, run) in runs.iter().enumerate() {
        let a = serde_json::to_value(&run.assessment).unwrap();
        scores.push(a["score"].as_f64().unwrap());
        batch.extend(attempt(
            &ids[k],
            sessions[k].0,
            EXERCISE,
            serde_json::to_value(&run.init).unwrap(),
            run.inputs.clone(),
            run.sim_seconds,
            1_700_000_000.0 + 86_400.0 * k as f64,
            Some(a),
        ));
    }
    let free = "fee0000000000000".to_string();
    batch.extend(attempt(
        &free,
        sessions[0].0,
        "training",
        serde_json::to_value(&long.init).unwrap(),
        long.inputs.clone(),
        long.sim_seconds,
        1_700_100_000.0,
        None,
    ));
    db.write_batch(&batch).await.unwrap();
    drop(db);
    let s = Binary::start(&dir, &[]);
    let base = &s.base;
    let (st, body) = get(&format!("{base}/api/reference-operators"), TEACHER).await;
    assert_eq!(st, 200, "{body}");
    let r = reqwest::Client::new()
        .put(format!("{base}/api/reference-operators"))
        .bearer_auth(TEACHER)
        .json(&json!({"trainee": "Ben", "group": GROUP, "reference": true}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);

    // The ghosts of Ada's second session: her best by the stored scores (the earlier of equal
    // ones), Ben's as the reference; nothing of Cy's.
    let best = if scores[1] > scores[0] {
        &ids[1]
    } else {
        &ids[0]
    };
    let url = format!(
        "{base}/api/sessions/{}/ghosts?exercise={EXERCISE}",
        sessions[1].0
    );
    let (st, g) = get(&url, "tok-ada-2").await;
    assert_eq!(st, 200, "{g}");
    println!(
        "scores {scores:?}; best {} reference {}",
        g["best"]["attempt"], g["reference"]["attempt"]
    );
    assert_eq!(g["best"]["attempt"], json!(best), "{g}");
    assert_eq!(g["best"]["score"], json!(scores[0].max(scores[1])));
    assert_eq!(g["reference"]["attempt"], json!(ids[2]), "{g}");
    assert_eq!(g["reference"]["score"], json!(scores[2]));
    let listed: Vec<&str> = g["attempts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["attempt"].as_str().unwrap())
        .collect();
    assert_eq!(listed, [ids[1].as_str(), ids[0].as_str()], "newest first");
    assert!(
        !g.to_string().contains("Ben"),
        "no reference operator's name"
    );
    // another session's token: 403; no token: 403; an unknown exercise: 404
    assert_eq!(get(&url, "tok-cy").await.0, 403);
    assert_eq!(get_as(&url, "").await.0, 403);
    let (st, _) = get(
        &format!("{base}/api/sessions/{}/ghosts?exercise=nope", sessions[1].0),
        "tok-ada-2",
    )
    .await;
    assert_eq!(st, 404);

    // Ada reads her first session's attempt from her second session: the track equals the
    // REST replay frame at every tenth sample and the last.
    let track_url =
        |id: &str, session: &str| format!("{base}/api/attempts/{id}/track?session={session}");
    let (st, track) = get(&track_url(&ids[0], sessions[1].0), "tok-ada-2").await;
    assert_eq!(st, 200, "{track}");
    let samples = track["samples"].as_array().unwrap();
    let duration = track["duration_s"].as_f64().unwrap();
    assert!((duration - runs[0].sim_seconds).abs() < 1e-9);
    assert_eq!(samples.len(), (duration * 10.0).ceil() as usize + 1);
    let mut picks: Vec<usize> = (0..samples.len()).step_by(10).collect();
    picks.push(samples.len() - 1);
    for i in picks {
        let t = samples[i]["t"].as_f64().unwrap();
        let (st, frame) = get(
            &format!("{base}/api/attempts/{}/replay?t={t}", ids[0]),
            TEACHER,
        )
        .await;
        assert_eq!(st, 200, "{frame}");
        check_sample(&samples[i], &frame, &format!("sample {i} (t = {t})"));
    }
    // and the two samples 1 s apart differ (the arm moves)
    assert_ne!(samples[10]["arms"], samples[20]["arms"]);

    // The reference's track: any trainee; Cy's (not a reference): 403 for Ada; her own
    // session's token without `session`: 403; unknown: 404.
    assert_eq!(
        get(&track_url(&ids[2], sessions[1].0), "tok-ada-2").await.0,
        200
    );
    assert_eq!(
        get(&track_url(&ids[3], sessions[1].0), "tok-ada-2").await.0,
        403
    );
    assert_eq!(
        get(&track_url(&ids[3], sessions[3].0), "tok-ada-2").await.0,
        403
    );
    let no_session = format!("{base}/api/attempts/{}/track", ids[0]);
    assert_eq!(get(&no_session, "tok-ada-2").await.0, 403);
    assert_eq!(
        get(&no_session, "tok-ada-1").await.0,
        200,
        "its own session"
    );
    let unknown = "0123456789abcdef";
    assert_eq!(
        get(&track_url(unknown, sessions[1].0), "tok-ada-2").await.0,
        404
    );
    assert_eq!(
        get(&format!("{base}/api/attempts/{unknown}/track"), TEACHER)
            .await
            .0,
        404
    );

    // A 120 s attempt's track: size, cold and warm build time.
    let t0 = Instant::now();
    let (st, text) = get_as(&format!("{base}/api/attempts/{free}/track"), TEACHER).await;
    let cold = t0.elapsed();
    assert_eq!(st, 200);
    let t1 = Instant::now();
    let (st, again) = get_as(&format!("{base}/api/attempts/{free}/track"), TEACHER).await;
    let warm = t1.elapsed();
    assert_eq!(st, 200);
    assert_eq!(text, again, "the cached track is the same");
    let v: Value = serde_json::from_str(&text).unwrap();
    let n = v["samples"].as_array().unwrap().len();
    assert_eq!(n, 1201, "120 s at 10 Hz and both ends");
    println!(
        "120 s track: {} bytes ({} samples, {:.0} B each); cold {:.2} s, warm {:.1} ms",
        text.len(),
        n,
        text.len() as f64 / n as f64,
        cold.as_secs_f64(),
        warm.as_secs_f64() * 1000.0
    );
    s.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
