//! Learning curves and proficiency over real sockets (issue 30 item 3): a class's stored
//! attempts give each trainee the CUSUM state computed by hand (the core's charts:
//! `seaarms_core::exercise::proficiency`, defaults p0 0.1, p1 0.3, h = ln 16); the trainee of a
//! live session reads their own curves with its token, nobody else's.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use common::{TEACHER, create_at, get_as, temp_dir};
use records_common::{Binary, stored_attempt, stored_session};
use seaarms::db::{Db, Write};
use serde_json::{Value, json};

const GROUP: &str = "ROV-cusum";

/// Each trainee's outcomes at reach-targets, in order (P pass, F fail, A abandoned: not a
/// finished attempt, ignored), and what the charts give by hand: a pass adds
/// ln(0.9/0.7) = 0.25131 to the learning chart, a failure ln(1/3) = −1.09861 (floor 0); after
/// proficiency a failure adds ln 3 to the relapse chart, a pass takes 0.25131 off.
const CLASS: &[(&str, &str, &str, Option<usize>)] = &[
    // 11 passes: 2.7644 < 2.7726; the 12th: 3.0157 — proficient at 12 (the abandoned
    // attempt between them does not count)
    ("Ada", "PPPPPAPPPPPPP", "proficient", Some(12)),
    // the failure at 3 resets the chart (0.50263 − 1.09861 < 0): twelve more, at 15
    ("Bo", "PPFPPPPPPPPPPPP", "proficient", Some(15)),
    // proficient at 12, then three failures: 3 ln 3 = 3.2958 ≥ h — relapsed at 15
    ("Cy", "PPPPPPPPPPPPFFF", "relapsed", Some(12)),
    // 5 passes (1.2566), a failure (0.1580), 5 passes (1.4145): still practising
    ("Di", "PPPPPFPPPPP", "practising", None),
];

fn session(id: &str, trainee: &str) -> Write {
    stored_session(id, trainee, GROUP, "reach-targets", 1_700_000_000.0)
}

/// Scores 90 for a pass, 30 for a failure, none otherwise.
fn attempt(id: &str, session: &str, started: f64, outcome: &str) -> [Write; 2] {
    let score = match outcome {
        "passed" => Some(90.0),
        "failed" => Some(30.0),
        _ => None,
    };
    stored_attempt(id, session, "reach-targets", started, outcome, score)
}

async fn get(url: &str, token: &str) -> (u16, Value) {
    let (status, text) = get_as(url, token).await;
    (status, serde_json::from_str(&text).unwrap_or(Value::Null))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_class_progress_follows_the_cusum_computed_by_hand() {
    let dir = temp_dir("progress");
    let db = Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let mut batch = Vec::new();
    for (i, (name, outcomes, _, _)) in CLASS.iter().enumerate() {
        // each attempt in a session of its own, as a trainee who comes back another day
        for (k, c) in outcomes.chars().enumerate() {
            let sid = format!("{i:02x}{k:014x}");
            batch.push(session(&sid, name));
            let outcome = match c {
                'P' => "passed",
                'F' => "failed",
                _ => "abandoned",
            };
            let started = 1_700_000_000.0 + 3600.0 * k as f64;
            batch.extend(attempt(&format!("a{sid}"), &sid, started, outcome));
        }
    }
    db.write_batch(&batch).await.unwrap();
    drop(db);
    let s = Binary::start(&dir, &[]);

    let (st, class) = get(
        &format!(
            "{}/api/progress?exercise=reach-targets&group={GROUP}",
            s.base
        ),
        TEACHER,
    )
    .await;
    assert_eq!(st, 200, "{class}");
    let list = class["trainees"].as_array().unwrap();
    let names: Vec<&str> = list
        .iter()
        .map(|t| t["trainee"].as_str().unwrap())
        .collect();
    // who needs the instructor first: relapsed, practising, then proficient by name
    assert_eq!(names, ["Cy", "Di", "Ada", "Bo"]);
    for (name, outcomes, state, at) in CLASS {
        let t = list.iter().find(|t| t["trainee"] == *name).unwrap();
        assert_eq!(t["state"], *state, "{name}: {t}");
        assert_eq!(
            t["proficient_at"].as_u64().map(|n| n as usize),
            *at,
            "{name}"
        );
        let finished = outcomes.chars().filter(|&c| c != 'A').count();
        assert_eq!(t["attempts"].as_array().unwrap().len(), finished, "{name}");
        let learning = t["cusum"]["learning"].as_array().unwrap();
        assert_eq!(learning.len(), finished);
        if *name == "Di" {
            let last = learning.last().unwrap().as_f64().unwrap();
            let w = (0.9f64 / 0.7).ln();
            let by_hand = 5.0 * w + (1.0f64 / 3.0).ln() + 5.0 * w;
            assert!(
                (last - by_hand).abs() < 1e-9,
                "Di's chart {last} vs {by_hand}"
            );
        }
    }
    let cy = list.iter().find(|t| t["trainee"] == "Cy").unwrap();
    assert_eq!(cy["cusum"]["relapsed_at"], json!([15]));
    assert!((cy["cusum"]["limit"].as_f64().unwrap() - 16f64.ln()).abs() < 1e-12);

    // bad input: an unknown exercise, a missing one, no instructor token
    let (st, _) = get(&format!("{}/api/progress?exercise=nope", s.base), TEACHER).await;
    assert_eq!(st, 404);
    let (st, _) = get(&format!("{}/api/progress", s.base), TEACHER).await;
    assert_eq!(st, 400);
    let (st, _) = get(
        &format!("{}/api/progress?exercise=reach-targets", s.base),
        "wrong",
    )
    .await;
    assert_eq!(st, 403);

    // Ada, back for another session, reads her own curves with its token: reach-targets
    // proficient at 12, the exercises she never tried not started; Bo's token cannot.
    let (st, ada) = create_at(&s.base, json!({"trainee": "Ada", "group": GROUP})).await;
    assert_eq!(st, 201, "{ada}");
    let (_, bo) = create_at(&s.base, json!({"trainee": "Bo", "group": GROUP})).await;
    let url = format!(
        "{}/api/sessions/{}/progress",
        s.base,
        ada["id"].as_str().unwrap()
    );
    let (st, mine) = get(&url, ada["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 200, "{mine}");
    let ex = mine["exercises"].as_array().unwrap();
    let reach = ex
        .iter()
        .find(|e| e["exercise"] == "reach-targets")
        .unwrap();
    assert_eq!(reach["state"], "proficient");
    assert_eq!(reach["proficient_at"], 12);
    let others: Vec<&Value> = ex
        .iter()
        .filter(|e| e["exercise"] != "reach-targets")
        .collect();
    assert!(!others.is_empty());
    for e in others {
        assert_eq!(e["state"], "not_started", "{e}");
    }
    let (st, _) = get(&url, bo["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 403, "another trainee's token");
    let (st, _) = get(&url, TEACHER).await;
    assert_eq!(st, 200, "the instructor's");
    drop(s);
    let _ = std::fs::remove_dir_all(&dir);
}
