//! Progression over the real binary (issue 30 item 4): an exercise whose file `requires`
//! another opens to a trainee once the CUSUM makes them proficient in it (stored attempts,
//! the arithmetic of tests/progress.rs: default p0 0.1, p1 0.3, h = ln 16; a pass adds
//! ln(0.9/0.7) = 0.25131, so eleven passes give 2.7644 < 2.7726 and the twelfth 3.0157 ≥ h),
//! stays open after a relapse, and is opened for one trainee by the instructor's unlock (stored:
//! it survives a restart) and closed again by deleting it; the instructor's token starts
//! anything; `--progression off` opens everything. The chain is the shipped files'
//! (`familiarisation` → `reach-targets` → `pick-and-place`, docs/exercises.md "Progression").
//! SQLite, and PostgreSQL when `SEAARMS_TEST_DATABASE_URL` is set (as tests/logbook.rs).

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use common::{TEACHER, create_at, get_as, temp_dir};
use records_common::{Binary, send_json, stored_attempt, stored_session};
use seaarms::db::{Db, Write};
use serde_json::{Value, json};

const GROUP: &str = "ROV-prog";
const T0: f64 = 1_700_000_000.0;

/// `outcomes` (P pass, F fail) of `trainee` at `exercise`, each in a session of its own,
/// numbered from `first` (so a later batch adds attempts after the earlier ones).
fn attempts(tag: u8, trainee: &str, exercise: &str, outcomes: &str, first: usize) -> Vec<Write> {
    let mut out = Vec::new();
    for (k, c) in outcomes.chars().enumerate() {
        let k = first + k;
        let sid = format!("{tag:02x}{k:014x}");
        let started = T0 + 3600.0 * k as f64;
        let (outcome, score) = if c == 'P' {
            ("passed", 90.0)
        } else {
            ("failed", 30.0)
        };
        out.push(stored_session(&sid, trainee, GROUP, exercise, started));
        out.extend(stored_attempt(
            &format!("a{sid}"),
            &sid,
            exercise,
            started,
            outcome,
            Some(score),
        ));
    }
    out
}

/// Starts `exercise` as `trainee` of GROUP (no token, as the start screen does): status and
/// answer.
async fn start(base: &str, trainee: &str, group: &str, exercise: &str) -> (u16, Value) {
    create_at(
        base,
        json!({"trainee": trainee, "group": group, "exercise": exercise}),
    )
    .await
}

/// One exercise's lock in an answer's `exercises` (the unlocks routes) or `locks` (progress).
fn lock<'a>(list: &'a Value, exercise: &str) -> &'a Value {
    list.as_array()
        .unwrap()
        .iter()
        .find(|l| l["exercise"] == exercise)
        .unwrap_or_else(|| panic!("no {exercise} in {list}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn exercises_open_by_proficiency_or_the_instructor() {
    for url in records_common::database_urls().await {
        eprintln!("database: {}", url.as_deref().unwrap_or("SQLite (default)"));
        progression_on(url).await;
    }
}

async fn progression_on(database_url: Option<String>) {
    let dir = temp_dir("progression");
    let db_url = database_url
        .clone()
        .unwrap_or_else(|| seaarms::db::default_url(&dir));
    let db = Db::open(&db_url).unwrap();
    let mut class = attempts(1, "Eve", "familiarisation", &"P".repeat(11), 0);
    // proficient at 12, then three failures (3 ln 3 = 3.2958 ≥ h): relapsed at 15
    class.extend(attempts(2, "Cy", "familiarisation", "PPPPPPPPPPPPFFF", 0));
    db.write_batch(&class).await.unwrap();
    drop(db);
    // one loopback client creates many sessions here: lift the per-client creation limits
    let mut extra: Vec<&str> = vec![
        "--progression",
        "on",
        "--session-burst",
        "1000",
        "--sessions-per-minute",
        "1000",
    ];
    if let Some(u) = &database_url {
        extra.extend(["--database-url", u.as_str()]);
    }
    let s = Binary::start(&dir, &extra);

    // a new trainee: familiarisation (no requirement) opens, reach-targets does not, and the
    // error names what is missing and the trainee's state in it
    let (st, ok) = start(&s.base, "Neo", GROUP, "familiarisation").await;
    assert_eq!(st, 201, "{ok}");
    let (st, err) = start(&s.base, "Neo", GROUP, "reach-targets").await;
    assert_eq!(st, 403, "{err}");
    let msg = err["error"].as_str().unwrap();
    assert!(
        msg.contains("`reach-targets` is locked") && msg.contains("`familiarisation`"),
        "{msg}"
    );
    assert!(msg.contains("not started"), "{msg}");
    assert_eq!(
        err["detail"],
        json!({"exercise": "reach-targets",
               "missing": [{"exercise": "familiarisation", "state": "not_started"}]})
    );
    // free play is never locked
    let (st, _) = create_at(&s.base, json!({"trainee": "Neo", "scenario": "training"})).await;
    assert_eq!(st, 201);

    // eleven passes: practising (2.7644 < ln 16), still locked
    let (st, err) = start(&s.base, "Eve", GROUP, "reach-targets").await;
    assert_eq!(st, 403, "{err}");
    assert_eq!(err["detail"]["missing"][0]["state"], "practising");
    // relapsed after proficiency: stays open; the next one in the chain is locked
    let (st, ok) = start(&s.base, "Cy", GROUP, "reach-targets").await;
    assert_eq!(st, 201, "{ok}");
    let (st, err) = start(&s.base, "Cy", GROUP, "pick-and-place").await;
    assert_eq!(st, 403, "{err}");
    assert_eq!(
        err["detail"]["missing"],
        json!([{"exercise": "reach-targets", "state": "not_started"}])
    );

    // Neo's own view of it, with the session's token (the start screen's source)
    let (_, neo) = start(&s.base, "Neo", GROUP, "familiarisation").await;
    let (st, text) = get_as(
        &format!(
            "{}/api/sessions/{}/progress",
            s.base,
            neo["id"].as_str().unwrap()
        ),
        neo["control_token"].as_str().unwrap(),
    )
    .await;
    assert_eq!(st, 200, "{text}");
    let mine: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(mine["progression"], true);
    assert_eq!(lock(&mine["locks"], "familiarisation")["status"], "open");
    let reach = lock(&mine["locks"], "reach-targets");
    assert_eq!(reach["status"], "locked", "{reach}");
    assert_eq!(reach["requires"], json!(["familiarisation"]));

    // the instructor's token starts anything, for anyone
    let (st, ok) = send_json(
        reqwest::Method::POST,
        &format!("{}/api/sessions", s.base),
        TEACHER,
        Some(json!({"trainee": "Neo", "group": GROUP, "exercise": "hot-stab"})),
    )
    .await;
    assert_eq!(st, 201, "{ok}");

    // the instructor unlocks reach-targets for Neo of GROUP: Neo only
    let unlocks = format!("{}/api/unlocks", s.base);
    let body = json!({"trainee": "Neo", "group": GROUP, "exercise": "reach-targets"});
    let (st, _) = send_json(reqwest::Method::PUT, &unlocks, "wrong", Some(body.clone())).await;
    assert_eq!(st, 403, "a trainee cannot unlock");
    let (st, _) = send_json(
        reqwest::Method::PUT,
        &unlocks,
        TEACHER,
        Some(json!({"trainee": "Neo", "group": GROUP, "exercise": "nope"})),
    )
    .await;
    assert_eq!(st, 404);
    let (st, list) = send_json(reqwest::Method::PUT, &unlocks, TEACHER, Some(body)).await;
    assert_eq!(st, 200, "{list}");
    let reach = lock(&list["exercises"], "reach-targets");
    assert_eq!(reach["status"], "unlocked", "{reach}");
    assert!(reach["unlocked_unix"].as_f64().unwrap() > T0);
    let (st, ok) = start(&s.base, "Neo", GROUP, "reach-targets").await;
    assert_eq!(st, 201, "{ok}");
    let (st, _) = start(&s.base, "Eve", GROUP, "reach-targets").await;
    assert_eq!(st, 403, "another trainee");
    let (st, _) = start(&s.base, "Neo", "other-group", "reach-targets").await;
    assert_eq!(st, 403, "the same name in another group");
    // and locks it again
    let (st, list) = send_json(
        reqwest::Method::DELETE,
        &format!("{unlocks}?trainee=Neo&group={GROUP}&exercise=reach-targets"),
        TEACHER,
        None,
    )
    .await;
    assert_eq!(st, 200, "{list}");
    assert_eq!(
        lock(&list["exercises"], "reach-targets")["status"],
        "locked"
    );
    let (st, _) = start(&s.base, "Neo", GROUP, "reach-targets").await;
    assert_eq!(st, 403, "locked again");
    // an unlock to keep across the restart
    let (st, _) = send_json(
        reqwest::Method::PUT,
        &unlocks,
        TEACHER,
        Some(json!({"trainee": "Neo", "group": GROUP, "exercise": "dual-lift"})),
    )
    .await;
    assert_eq!(st, 200);
    s.stop();

    // Eve's twelfth pass: 3.0157 ≥ ln 16, proficient — reach-targets opens
    let db = Db::open(&db_url).unwrap();
    db.write_batch(&attempts(1, "Eve", "familiarisation", "P", 11))
        .await
        .unwrap();
    drop(db);
    let s = Binary::start(&dir, &extra);
    let (st, ok) = start(&s.base, "Eve", GROUP, "reach-targets").await;
    assert_eq!(st, 201, "{ok}");
    let (st, list) = send_json(
        reqwest::Method::GET,
        &format!("{}/api/unlocks?trainee=Neo&group={GROUP}", s.base),
        TEACHER,
        None,
    )
    .await;
    assert_eq!(st, 200, "{list}");
    assert_eq!(lock(&list["exercises"], "dual-lift")["status"], "unlocked");
    let (st, ok) = start(&s.base, "Neo", GROUP, "dual-lift").await;
    assert_eq!(st, 201, "stored unlock: {ok}");
    let (st, _) = get_as(&format!("{}/api/unlocks?trainee=Neo", s.base), "wrong").await;
    assert_eq!(st, 403);
    s.stop();

    // --progression off: everything open to everyone
    let s = Binary::start(&dir, &["--progression", "off"]);
    let (st, ok) = start(&s.base, "Nobody-yet", GROUP, "hot-stab").await;
    assert_eq!(st, 201, "{ok}");
    s.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
