//! Benchmarks from reference operators (issue 30 item 1) in a scripted class, over real
//! sockets: five reference operators and five trainees of different skill work reach-targets
//! headless (the exercise's plan driven by a human-paced operator with seeded variation,
//! `seaarms::exercises::HumanNoise`), their attempts are stored as a live session stores them,
//! the instructor marks the five through `PUT /api/reference-operators`, and the server's
//! benchmark must be the mean and sample SD of the references' values after removing those
//! beyond 1.96 SD (the proficiency-based progression procedure, Gallagher et al. 2005),
//! computed here independently; each trainee's attempts meet it or not as judged here, and a
//! trainee is proficient exactly at their third attempt in a row that meets it.
//!
//! The class (reaction = mean decision interval / 0.25 s; misjudge = largest relative error
//! of an axis's intent; jitter 0.3 for all — human choice reaction times spread by about that):
//! references reaction 1.0, misjudge 0.2, two attempts each; trainees reaction 1.0 / 1.3 /
//! 1.8 / 2.5 / 3.5, misjudge 0.2 / 0.3 / 0.4 / 0.5 / 0.6, twelve attempts for the first (as
//! skilled as the references), five for the others. A reference-like operator meets each
//! required measure's one-SD line (score and time, the default) about 84 % of the time, both
//! about 70 % if they were independent — hence the skilled trainee's twelve attempts.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::collections::BTreeMap;
use std::sync::Arc;

use common::{TEACHER, create_at, get_as, magnum, temp_dir};
use records_common::Binary;
use seaarms::catalogue::EXERCISES;
use seaarms::db::{Db, Write};
use seaarms::exercises::{Driver, HumanNoise, run_headless};
use seaarms::sessions::record::{AttemptEnd, AttemptStart};
use serde_json::{Value, json};

const GROUP: &str = "ROV-bench";
const EXERCISE: &str = "reach-targets";
/// (name, reaction, misjudge, attempts, reference operator)
const CLASS: &[(&str, f64, f64, usize, bool)] = &[
    ("Ref-1", 1.0, 0.2, 2, true),
    ("Ref-2", 1.0, 0.2, 2, true),
    ("Ref-3", 1.0, 0.2, 2, true),
    ("Ref-4", 1.0, 0.2, 2, true),
    ("Ref-5", 1.0, 0.2, 2, true),
    ("Ann", 1.0, 0.2, 12, false),
    ("Ben", 1.3, 0.3, 5, false),
    ("Cat", 1.8, 0.4, 5, false),
    ("Dev", 2.5, 0.5, 5, false),
    ("Eve", 3.5, 0.6, 5, false),
];

/// Mean and sample SD, then once more without the values beyond 1.96 SD (by hand).
fn mean_sd_without_outliers(v: &[f64]) -> (f64, f64, usize) {
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let sd = if v.len() > 1 {
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        (m, sd)
    };
    let (m, sd) = stats(v);
    let kept: Vec<f64> = v
        .iter()
        .copied()
        .filter(|x| sd == 0.0 || (x - m).abs() <= 1.96 * sd)
        .collect();
    let (m, sd) = stats(&kept);
    (m, sd, kept.len())
}

async fn get(url: &str, token: &str) -> (u16, Value) {
    let (status, text) = get_as(url, token).await;
    (status, serde_json::from_str(&text).unwrap_or(Value::Null))
}

async fn put(url: &str, token: &str, body: &str) -> (u16, Value) {
    let r = reqwest::Client::new()
        .put(url)
        .bearer_auth(token)
        .header("content-type", "application/json")
        .body(body.to_string())
        .send()
        .await
        .unwrap();
    let st = r.status().as_u16();
    (st, r.json().await.unwrap_or(Value::Null))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_scripted_class_gets_the_benchmark_of_its_reference_operators() {
    let spec = EXERCISES.get(EXERCISE).unwrap();
    let models = magnum();
    // every attempt, headless: (name, assessment JSON), in order per trainee
    let jobs: Vec<(usize, usize)> = CLASS
        .iter()
        .enumerate()
        .flat_map(|(i, c)| (0..c.3).map(move |k| (i, k)))
        .collect();
    let runs: Vec<(usize, usize, Value)> = std::thread::scope(|s| {
        let chunks: Vec<Vec<(usize, usize)>> = jobs
            .chunks(jobs.len().div_ceil(2))
            .map(<[_]>::to_vec)
            .collect();
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|chunk| {
                let (spec, models) = (Arc::clone(&spec), models.clone());
                s.spawn(move || {
                    chunk
                        .into_iter()
                        .map(|(i, k)| {
                            let (_, reaction, misjudge, _, _) = CLASS[i];
                            let seed = 1000 + 100 * i as u64 + k as u64;
                            let noise = HumanNoise {
                                reaction,
                                jitter: 0.3,
                                misjudge,
                                seed,
                            };
                            let a = run_headless(spec.clone(), &models, Driver::Noisy(noise), seed)
                                .unwrap();
                            (i, k, serde_json::to_value(&a).unwrap())
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });

    let dir = temp_dir("benchmarks");
    let db = Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let mut batch = Vec::new();
    for (i, k, a) in &runs {
        let sid = format!("{i:02x}{k:014x}");
        batch.push(Write::Session {
            id: sid.clone(),
            trainee: CLASS[*i].0.into(),
            group: GROUP.into(),
            scenario: EXERCISE.into(),
            created_unix: 1_700_000_000.0,
            token_sha256: "ab".repeat(32),
        });
        let started = 1_700_000_000.0 + 3600.0 * *k as f64 + *i as f64;
        batch.push(Write::AttemptStart(Box::new(AttemptStart {
            id: format!("a{sid}"),
            session: sid.clone(),
            scenario: EXERCISE.into(),
            exercise: Some(EXERCISE.into()),
            exercise_version: Some(spec.version.to_string()),
            sim_version: "sim-1".into(),
            started_unix: started,
            init: json!({}),
        })));
        batch.push(Write::AttemptEnd(Box::new(AttemptEnd {
            id: format!("a{sid}"),
            ended_unix: started + 60.0,
            sim_seconds: a["time_s"].as_f64().unwrap(),
            outcome: if a["passed"] == true {
                "passed"
            } else {
                "failed"
            }
            .into(),
            score: a["score"].as_f64(),
            assessment: Some(a.clone()),
        })));
    }
    db.write_batch(&batch).await.unwrap();
    drop(db);
    let s = Binary::start(&dir, &[]);
    let progress = format!("{}/api/progress?exercise={EXERCISE}&group={GROUP}", s.base);
    let refs_url = format!("{}/api/reference-operators", s.base);

    // no reference operators yet: no benchmark applies, every attempt's met_benchmark is null
    let (st, before) = get(&progress, TEACHER).await;
    assert_eq!(st, 200, "{before}");
    assert_eq!(before["benchmark"]["applies"], false);
    assert_eq!(before["benchmark"]["reference_attempts"], 0);
    assert!(before["trainees"].as_array().unwrap().iter().all(|t| {
        t["attempts"]
            .as_array()
            .unwrap()
            .iter()
            .all(|a| a["met_benchmark"].is_null())
    }));

    // bad input loses nothing: no instructor token, malformed JSON, an empty name, an unknown field
    for (token, body, want) in [
        (
            "wrong",
            r#"{"trainee":"Ref-1","group":"ROV-bench","reference":true}"#,
            403,
        ),
        (TEACHER, r#"{"trainee":"Ref-1","#, 400),
        (
            TEACHER,
            r#"{"trainee":"  ","group":"ROV-bench","reference":true}"#,
            400,
        ),
        (
            TEACHER,
            r#"{"trainee":"Ref-1","reference":true,"k":2}"#,
            400,
        ),
    ] {
        let (st, body) = put(&refs_url, token, body).await;
        assert_eq!(st, want, "{body}");
        assert!(body["error"].is_string(), "{body}");
    }
    // the instructor marks the five (and one by mistake, then unmarks it)
    for (name, _, _, _, reference) in CLASS {
        if *reference {
            let b = json!({"trainee": name, "group": GROUP, "reference": true}).to_string();
            assert_eq!(put(&refs_url, TEACHER, &b).await.0, 200);
        }
    }
    let b = json!({"trainee": "Eve", "group": GROUP, "reference": true}).to_string();
    assert_eq!(put(&refs_url, TEACHER, &b).await.0, 200);
    let b = json!({"trainee": "Eve", "group": GROUP, "reference": false}).to_string();
    let (st, list) = put(&refs_url, TEACHER, &b).await;
    assert_eq!(st, 200);
    let names: Vec<&str> = list["reference_operators"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["trainee"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["Ref-1", "Ref-2", "Ref-3", "Ref-4", "Ref-5"]);
    assert_eq!(get(&refs_url, "wrong").await.0, 403);

    let (st, class) = get(&progress, TEACHER).await;
    assert_eq!(st, 200, "{class}");
    let bench = &class["benchmark"];
    assert_eq!(bench["reference_attempts"], 10, "{bench}");
    assert_eq!(bench["applies"], true, "{bench}");
    let k = bench["k"].as_f64().unwrap();
    assert_eq!(k, spec.proficiency.benchmark_sd);
    // the measures: the score (higher better) and each scoring term's metric, better toward
    // its `good` value (the exercise file)
    let measures = bench["measures"].as_array().unwrap();
    assert_eq!(measures[0]["metric"], "score");
    for t in &spec.scoring {
        let m = measures
            .iter()
            .find(|m| m["metric"] == t.metric.as_str())
            .unwrap();
        assert_eq!(m["higher_is_better"], t.good > t.bad, "{m}");
    }
    let value = |a: &Value, metric: &str| a[metric].as_f64().unwrap();
    let mut lines: BTreeMap<String, (f64, bool)> = BTreeMap::new();
    let required: Vec<&str> = spec
        .proficiency
        .benchmark_on
        .iter()
        .map(String::as_str)
        .collect();
    for m in measures {
        let metric = m["metric"].as_str().unwrap();
        let reference: Vec<f64> = runs
            .iter()
            .filter(|(i, _, _)| CLASS[*i].4)
            .map(|(_, _, a)| value(a, metric))
            .collect();
        let (mean, sd, n) = mean_sd_without_outliers(&reference);
        let b = &m["benchmark"];
        let close = |x: &Value, y: f64| (x.as_f64().unwrap() - y).abs() <= 1e-9 * (1.0 + y.abs());
        assert!(
            close(&b["mean"], mean) && close(&b["sd"], sd),
            "{metric}: {b} vs {mean} ± {sd}"
        );
        assert_eq!(b["n"], n, "{metric}");
        assert_eq!(b["outliers"], 10 - n, "{metric}");
        let up = m["higher_is_better"].as_bool().unwrap();
        let line = if up { mean - k * sd } else { mean + k * sd };
        assert!(close(&m["line"], line), "{metric}: {} vs {line}", m["line"]);
        assert_eq!(m["required"], required.contains(&metric), "{metric}");
        if required.contains(&metric) {
            lines.insert(metric.to_string(), (line, up));
        }
    }

    // each trainee's attempts against the lines, judged here; proficient at the third in a row
    let mut states = Vec::new();
    for (i, (name, _, _, _, reference)) in CLASS.iter().enumerate() {
        if *reference {
            continue;
        }
        let t = class["trainees"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["trainee"] == *name)
            .unwrap();
        let mine: Vec<&Value> = {
            let mut v: Vec<(usize, &Value)> = runs
                .iter()
                .filter(|r| r.0 == i)
                .map(|r| (r.1, &r.2))
                .collect();
            v.sort_by_key(|r| r.0);
            v.into_iter().map(|r| r.1).collect()
        };
        let met: Vec<bool> = mine
            .iter()
            .map(|a| {
                lines.iter().all(|(metric, (line, up))| {
                    let v = value(a, metric);
                    if *up { v >= *line } else { v <= *line }
                })
            })
            .collect();
        if std::env::var("BENCH_DEBUG").is_ok() {
            for (metric, (line, up)) in &lines {
                let v: Vec<String> = mine
                    .iter()
                    .map(|a| format!("{:.3}", value(a, metric)))
                    .collect();
                println!("{name} {metric} line {line:.3} up {up}: {v:?}");
            }
        }
        let api: Vec<bool> = t["attempts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a["met_benchmark"].as_bool().unwrap())
            .collect();
        assert_eq!(api, met, "{name}: met_benchmark per attempt");
        let third = (0..met.len())
            .find(|&n| n >= 2 && met[n - 2..=n].iter().all(|&m| m))
            .map(|n| n + 1);
        if let Some(at) = third {
            assert_eq!(t["state"], "proficient", "{name}: {met:?}");
            assert_eq!(t["proficient_at"], at, "{name}");
            assert_eq!(t["by"], "benchmark", "{name}");
        } else {
            // the CUSUM alone needs twelve passes in a row at the defaults: only the first
            // trainee has that many attempts, and the benchmark comes first for her
            assert_eq!(t["state"], "practising", "{name}: {met:?}");
        }
        states.push((*name, met, t["state"].clone()));
    }
    let names: Vec<&str> = measures
        .iter()
        .map(|m| m["metric"].as_str().unwrap())
        .collect();
    println!("measures {names:?}; class against the benchmark: {states:?}");
    // the class spreads: the steady operator reaches the benchmark, the slowest does not
    let state_of = |n: &str| states.iter().find(|s| s.0 == n).unwrap().2.clone();
    assert_eq!(state_of("Ann"), "proficient", "{states:?}");
    assert_eq!(state_of("Eve"), "practising", "{states:?}");

    // a trainee back for a new session sees the benchmark with their own curve
    let (st, ann) = create_at(&s.base, json!({"trainee": "Ann", "group": GROUP})).await;
    assert_eq!(st, 201, "{ann}");
    let url = format!(
        "{}/api/sessions/{}/progress",
        s.base,
        ann["id"].as_str().unwrap()
    );
    let (st, mine) = get(&url, ann["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 200, "{mine}");
    let reach = mine["exercises"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["exercise"] == EXERCISE)
        .unwrap();
    assert_eq!(reach["benchmark"]["applies"], true);
    assert_eq!(reach["benchmark"]["measures"], bench["measures"]);

    // the exercise's pass marks are `benchmark`: an attempt started now is judged by these
    // lines (score and time, as computed above), recorded with it
    let (st, run) = create_at(
        &s.base,
        json!({"exercise": EXERCISE, "trainee": "Ann", "group": GROUP}),
    )
    .await;
    assert_eq!(st, 201, "{run}");
    let url = format!(
        "{}/api/sessions/{}/assessment",
        s.base,
        run["id"].as_str().unwrap()
    );
    let (st, a) = get(&url, run["control_token"].as_str().unwrap()).await;
    assert_eq!(st, 200, "{a}");
    let marks = &a["pass_marks"];
    assert_eq!(marks["kind"], "benchmark", "{marks}");
    assert_eq!(marks["benchmark"]["reference_attempts"], 10, "{marks}");
    let given: BTreeMap<String, (f64, bool)> = marks["benchmark"]["lines"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            (
                l["metric"].as_str().unwrap().to_string(),
                (
                    l["line"].as_f64().unwrap(),
                    l["higher_is_better"].as_bool().unwrap(),
                ),
            )
        })
        .collect();
    assert_eq!(given.len(), lines.len(), "{marks}");
    for (metric, (line, up)) in &lines {
        let (g, gup) = given[metric];
        assert!(
            (g - line).abs() <= 1e-9 * (1.0 + line.abs()) && gup == *up,
            "{metric}: {g} vs {line}"
        );
    }
    drop(s);
    let _ = std::fs::remove_dir_all(&dir);
}
