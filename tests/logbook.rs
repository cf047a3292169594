//! The per-trainee logbook over real sockets (issue 30 item 7): a stored class's attempts give
//! the numbers worked out by hand below (attempt counts, best and last scores, the
//! proficiency date = the 12th pass's date with the default CUSUM: p0 0.1, p1 0.3,
//! h = ln 16, twelve passes 12 × ln(0.9/0.7) = 3.0157 ≥ 2.7726, eleven 2.7644 < h — the
//! same arithmetic as tests/progress.rs); an instructor's sign-off round trip; the CSV's
//! header, ISO 8601 dates (instants checked with GNU `date -u -d @…`) and OWASP formula
//! neutralisation of a hostile name; 403/404/400; the trainee's own route with their token.
//! SQLite, and PostgreSQL when `SEAARMS_TEST_DATABASE_URL` is set (as tests/records.rs).

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use common::{TEACHER, create_at, get_as, temp_dir};
use records_common::{Binary, send_json, stored_attempt, stored_session};
use seaarms::db::{Db, Write};
use serde_json::{Value, json};

const GROUP: &str = "ROV-log";
const T0: f64 = 1_700_000_000.0; // 2023-11-14T22:13:20Z
const HOSTILE: &str = "=HYPERLINK(\"http://x.example\",\"y\")";

fn session(id: &str, trainee: &str) -> Write {
    stored_session(id, trainee, GROUP, "reach-targets", T0)
}

/// Ada at reach-targets, hourly from T0: P pass (score 70 + k), F fail (30), A abandoned (no
/// score). Passes at k = 0–4 and 6–12: the 12th pass is k = 12, T0 + 12 h =
/// 2023-11-15T10:13:20Z; then one failure (relapse chart ln 3 = 1.0986 < h: still
/// proficient). 14 attempts, 13 finished, 12 passes, best 82 (k = 12), last 30 (k = 13).
const ADA: &str = "PPPPPAPPPPPPPF";

/// The stored class: Ada as above and two dual-lift attempts (a pass scoring 55 at T0 + 20 h,
/// an abandoned one at T0 + 21 h); Bo one failed reach-targets attempt; the hostile name one
/// pass.
fn class() -> Vec<Write> {
    let mut batch = Vec::new();
    let mut add = |sid: String, name: &str, exercise: &str, k: usize, c: char| {
        batch.push(session(&sid, name));
        let (outcome, score) = match c {
            'P' => ("passed", Some(70.0 + k as f64)),
            'F' => ("failed", Some(30.0)),
            _ => ("abandoned", None),
        };
        let score = if exercise == "dual-lift" && c == 'P' {
            Some(55.0)
        } else {
            score
        };
        batch.extend(stored_attempt(
            &format!("a{sid}"),
            &sid,
            exercise,
            T0 + 3600.0 * k as f64,
            outcome,
            score,
        ));
    };
    for (k, c) in ADA.chars().enumerate() {
        add(format!("00{k:014x}"), "Ada", "reach-targets", k, c);
    }
    add(format!("01{:014x}", 20), "Ada", "dual-lift", 20, 'P');
    add(format!("01{:014x}", 21), "Ada", "dual-lift", 21, 'A');
    add(format!("02{:014x}", 0), "Bo", "reach-targets", 0, 'F');
    add(format!("03{:014x}", 0), HOSTILE, "reach-targets", 0, 'P');
    batch
}

async fn get(url: &str, token: &str) -> (u16, Value) {
    let (status, text) = get_as(url, token).await;
    (status, serde_json::from_str(&text).unwrap_or(Value::Null))
}

fn entry<'a>(book: &'a Value, exercise: &str) -> &'a Value {
    book["exercises"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["exercise"] == exercise)
        .unwrap_or_else(|| panic!("no {exercise} in {book}"))
}

fn q(name: &str) -> String {
    format!("trainee={}&group={GROUP}", url_escape(name))
}

fn url_escape(s: &str) -> String {
    s.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_logbook_holds_the_numbers_worked_out_by_hand_and_the_sign_offs() {
    for url in records_common::database_urls().await {
        eprintln!("database: {}", url.as_deref().unwrap_or("SQLite (default)"));
        logbook_on(url).await;
    }
}

async fn logbook_on(database_url: Option<String>) {
    let dir = temp_dir("logbook");
    let db_url = database_url
        .clone()
        .unwrap_or_else(|| seaarms::db::default_url(&dir));
    let db = Db::open(&db_url).unwrap();
    db.write_batch(&class()).await.unwrap();
    drop(db);
    let extra: Vec<&str> = match &database_url {
        Some(u) => vec!["--database-url", u.as_str()],
        None => vec![],
    };
    let s = Binary::start(&dir, &extra);
    let book_url = format!("{}/api/logbook?{}", s.base, q("Ada"));

    // the numbers, by hand (see ADA)
    let (st, book) = get(&book_url, TEACHER).await;
    assert_eq!(st, 200, "{book}");
    assert_eq!(book["trainee"], "Ada");
    assert_eq!(book["group"], GROUP);
    let reach = entry(&book, "reach-targets");
    assert_eq!(reach["attempts"], 14, "{reach}");
    assert_eq!(reach["finished"], 13);
    assert_eq!(reach["passes"], 12);
    assert_eq!(reach["best_score"], 82.0);
    assert_eq!(reach["last_score"], 30.0);
    assert_eq!(reach["first_unix"], T0);
    assert_eq!(reach["last_unix"], T0 + 13.0 * 3600.0);
    assert_eq!(reach["state"], "proficient");
    assert_eq!(reach["proficient_at"], 12);
    assert_eq!(reach["proficient_unix"], T0 + 12.0 * 3600.0);
    assert_eq!(reach["by"], "cusum");
    assert_eq!(reach["signoff"], Value::Null);
    let dual = entry(&book, "dual-lift");
    assert_eq!(dual["attempts"], 2, "{dual}");
    assert_eq!(dual["finished"], 1);
    assert_eq!(dual["passes"], 1);
    assert_eq!(dual["best_score"], 55.0);
    assert_eq!(dual["last_score"], 55.0);
    assert_eq!(dual["first_unix"], T0 + 20.0 * 3600.0);
    assert_eq!(dual["last_unix"], T0 + 21.0 * 3600.0);
    assert_eq!(dual["state"], "practising");
    assert_eq!(dual["proficient_at"], Value::Null);
    let valve = entry(&book, "valve-turn");
    assert_eq!(valve["attempts"], 0);
    assert_eq!(valve["state"], "not_started");
    assert_eq!(valve["first_unix"], Value::Null);

    // sign-off round trip: the note is normalised as names are (the newline a space)
    let signoffs = format!("{}/api/signoffs", s.base);
    let body = json!({"trainee": "Ada", "group": GROUP, "exercise": "reach-targets",
        "assessor": "  R. Assessor ", "note": "steady\ncontrol"});
    let (st, signed) =
        send_json(reqwest::Method::PUT, &signoffs, TEACHER, Some(body.clone())).await;
    assert_eq!(st, 200, "{signed}");
    assert_eq!(signed["assessor"], "R. Assessor");
    assert_eq!(signed["note"], "steady control");
    let (_, book) = get(&book_url, TEACHER).await;
    let so = &entry(&book, "reach-targets")["signoff"];
    assert_eq!(so["assessor"], "R. Assessor", "{so}");
    assert_eq!(so["note"], "steady control");
    assert_eq!(so["signed_unix"], signed["signed_unix"]);
    assert_eq!(entry(&book, "dual-lift")["signoff"], Value::Null);
    // refused: no instructor token, an unknown exercise, no assessor
    let (st, _) = send_json(reqwest::Method::PUT, &signoffs, "wrong", Some(body.clone())).await;
    assert_eq!(st, 403);
    let mut bad = body.clone();
    bad["exercise"] = json!("nope");
    let (st, _) = send_json(reqwest::Method::PUT, &signoffs, TEACHER, Some(bad)).await;
    assert_eq!(st, 404);
    let mut bad = body.clone();
    bad["assessor"] = json!("   ");
    let (st, _) = send_json(reqwest::Method::PUT, &signoffs, TEACHER, Some(bad)).await;
    assert_eq!(st, 400);

    // the CSV: the header, one row per exercise, ISO 8601 UTC dates, the sign-off
    let (st, text) = get_as(&format!("{}/api/logbook.csv?{}", s.base, q("Ada")), TEACHER).await;
    assert_eq!(st, 200, "{text}");
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        header,
        [
            "trainee",
            "group",
            "exercise",
            "title",
            "first_attempt_utc",
            "last_attempt_utc",
            "attempts",
            "finished",
            "passes",
            "best_score",
            "last_score",
            "state",
            "proficient_at",
            "proficient_utc",
            "proficient_by",
            "signed_off_utc",
            "assessor",
            "note",
        ]
    );
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), book["exercises"].as_array().unwrap().len());
    let col = |row: &csv::StringRecord, name: &str| {
        row[header.iter().position(|h| h == name).unwrap()].to_string()
    };
    let row = rows
        .iter()
        .find(|r| col(r, "exercise") == "reach-targets")
        .unwrap();
    assert_eq!(col(row, "trainee"), "Ada");
    assert_eq!(col(row, "first_attempt_utc"), "2023-11-14T22:13:20Z");
    assert_eq!(col(row, "last_attempt_utc"), "2023-11-15T11:13:20Z");
    assert_eq!(col(row, "proficient_utc"), "2023-11-15T10:13:20Z");
    assert_eq!(col(row, "attempts"), "14");
    assert_eq!(col(row, "finished"), "13");
    assert_eq!(col(row, "passes"), "12");
    assert_eq!(col(row, "best_score"), "82.0");
    assert_eq!(col(row, "last_score"), "30.0");
    assert_eq!(col(row, "state"), "proficient");
    assert_eq!(col(row, "proficient_at"), "12");
    assert_eq!(col(row, "assessor"), "R. Assessor");
    assert!(col(row, "signed_off_utc").ends_with('Z'));

    // revoke: 204, then it is gone (404 a second time)
    let revoke = format!("{signoffs}?{}&exercise=reach-targets", q("Ada"));
    let (st, _) = send_json(reqwest::Method::DELETE, &revoke, TEACHER, None).await;
    assert_eq!(st, 204);
    let (_, book) = get(&book_url, TEACHER).await;
    assert_eq!(entry(&book, "reach-targets")["signoff"], Value::Null);
    let (st, _) = send_json(reqwest::Method::DELETE, &revoke, TEACHER, None).await;
    assert_eq!(st, 404);
    let (st, _) = send_json(reqwest::Method::DELETE, &revoke, "wrong", None).await;
    assert_eq!(st, 403);

    // a hostile name is written with OWASP's leading `'` in the CSV
    let (st, text) = get_as(
        &format!("{}/api/logbook.csv?{}", s.base, q(HOSTILE)),
        TEACHER,
    )
    .await;
    assert_eq!(st, 200, "{text}");
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let first = r.records().next().unwrap().unwrap();
    assert_eq!(&first[0], format!("'{HOSTILE}"));

    // 403 without the instructor token; 400 without a trainee; 404 for a trainee unknown
    let (st, _) = get(&book_url, "wrong").await;
    assert_eq!(st, 403);
    let (st, _) = get_as(&format!("{}/api/logbook.csv?{}", s.base, q("Ada")), "wrong").await;
    assert_eq!(st, 403);
    let (st, _) = get(&format!("{}/api/logbook?group={GROUP}", s.base), TEACHER).await;
    assert_eq!(st, 400);
    let (st, _) = get(
        &format!("{}/api/logbook?trainee=%20&group={GROUP}", s.base),
        TEACHER,
    )
    .await;
    assert_eq!(st, 400);
    let (st, _) = get(&format!("{}/api/logbook?{}", s.base, q("Nobody")), TEACHER).await;
    assert_eq!(st, 404);
    let (st, _) = get(&format!("{}/api/logbook?trainee=Ada", s.base), TEACHER).await;
    assert_eq!(st, 404, "Ada has no attempts outside her group");

    // the trainee's own logbook with their session's token; not with another trainee's
    let (st, ada) = create_at(&s.base, json!({"trainee": "Ada", "group": GROUP})).await;
    assert_eq!(st, 201, "{ada}");
    let (_, bo) = create_at(&s.base, json!({"trainee": "Bo", "group": GROUP})).await;
    let own = format!(
        "{}/api/sessions/{}/logbook",
        s.base,
        ada["id"].as_str().unwrap()
    );
    let (st, mine) = get(&own, ada["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 200, "{mine}");
    let reach = entry(&mine, "reach-targets");
    assert_eq!(reach["attempts"], 14);
    assert_eq!(reach["proficient_unix"], T0 + 12.0 * 3600.0);
    let (st, _) = get(&own, bo["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 403, "another trainee's token");
    let (st, _) = get(&own, TEACHER).await;
    assert_eq!(st, 200, "the instructor's");
    drop(s);
    let _ = std::fs::remove_dir_all(&dir);
}
