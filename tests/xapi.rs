//! Issue 30 item 6: a finished attempt's xAPI statements arrive at a real Learning Record
//! Store with the right verbs and score; with the LRS down, the session runs on and the
//! statements arrive after it returns.
//!
//! The LRS is Ralph (PyPI `ralph-malph`, France Université Numérique's LRS; `tests/run.sh`
//! installs it), started here on its file-system back end with HTTP Basic credentials made by
//! its own `ralph auth`. The server is the real binary, its credentials in the environment
//! (`SEAARMS_XAPI_USERNAME`, `SEAARMS_XAPI_PASSWORD`). An attempt is the familiarisation
//! exercise driven to its end over the trainee's WebSocket by a proportional controller on the
//! joint sticks. Ralph must be installed when `SEAARMS_TEST_RALPH` is set (tests/run.sh sets
//! it); otherwise the test says it is skipped.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{TEACHER, Ws, next_of, send, temp_dir};
use records_common::{Binary, metric};
use serde_json::{Value, json};

const LRS_USER: &str = "seaarms";
const LRS_PASSWORD: &str = "xapi-test-password";
const PUBLIC: &str = "http://seaarms.test";

/// Whether Ralph's LRS can be started here.
fn ralph_installed() -> bool {
    Command::new("python3")
        .args(["-c", "import ralph.api, uvicorn"])
        .env("RALPH_RUNSERVER_BACKEND", "fs")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Ralph's LRS on `port` (its file-system back end in `dir`), killed when dropped. Started
/// through uvicorn directly: `ralph runserver` runs it under uvicorn's reloader, whose child
/// a kill would leave behind.
struct Ralph {
    child: Child,
    port: u16,
}

fn ralph_env(dir: &Path) -> Vec<(&'static str, PathBuf)> {
    vec![
        ("RALPH_AUTH_FILE", dir.join("auth.json")),
        ("RALPH_APP_DIR", dir.join("app")),
        (
            "RALPH_BACKENDS__LRS__FS__DEFAULT_DIRECTORY_PATH",
            dir.join("statements"),
        ),
    ]
}

impl Ralph {
    /// Writes the LRS's credentials file with `ralph auth` (bcrypt-hashed password; the
    /// agent it names is the LRS's authority for our statements).
    fn make_user(dir: &Path) {
        std::fs::create_dir_all(dir.join("statements")).unwrap();
        let out = Command::new("ralph")
            .args(["auth", "-u", LRS_USER, "-p", LRS_PASSWORD, "-s", "all"])
            .args(["-A", LRS_USER, PUBLIC, "-w"])
            .envs(ralph_env(dir))
            .env("RALPH_RUNSERVER_BACKEND", "fs")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "ralph auth: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }

    /// Starts the LRS; it stores statements in `dir/statements/<file>`. Ralph 5.1's
    /// file-system back end writes each file once (a second POST to a running LRS answers
    /// 500, "overwrite is not allowed"), so each start takes a fresh file and each instance
    /// here receives one attempt's statements in one request.
    async fn start(dir: &Path, port: u16, file: &str) -> Ralph {
        let log = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(dir.join("ralph.log"))
            .unwrap();
        let child = Command::new("python3")
            .args(["-m", "uvicorn", "ralph.api:app", "--host", "127.0.0.1"])
            .args(["--port", &port.to_string()])
            .envs(ralph_env(dir))
            .env("RALPH_RUNSERVER_BACKEND", "fs")
            .env("RALPH_BACKENDS__LRS__FS__DEFAULT_LRS_FILE", file)
            .current_dir(dir)
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .unwrap();
        let r = Ralph { child, port };
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let up = reqwest::get(format!("{}/__heartbeat__", r.base()))
                .await
                .is_ok_and(|a| a.status().is_success());
            if up {
                return r;
            }
            assert!(Instant::now() < deadline, "Ralph did not start within 60 s");
            tokio::time::sleep(Duration::from_millis(200)).await;
        }
    }

    fn base(&self) -> String {
        format!("http://127.0.0.1:{}", self.port)
    }

    /// The statements about `agent` (an xAPI agent object), by Ralph's
    /// `GET /xAPI/statements?agent=…` (xAPI 1.0.3 part 3 §2.1.3).
    async fn statements_of(&self, agent: &Value) -> Vec<Value> {
        let r = reqwest::Client::new()
            .get(format!("{}/xAPI/statements", self.base()))
            .query(&[("agent", agent.to_string())])
            .basic_auth(LRS_USER, Some(LRS_PASSWORD))
            .header("X-Experience-API-Version", "1.0.3")
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 200);
        let v: Value = r.json().await.unwrap();
        v["statements"].as_array().cloned().unwrap_or_default()
    }

    /// Every statement the LRS holds (an empty list while it does not answer). Not
    /// `?activity=…`: Ralph 5.1's file-system back end finds nothing by activity.
    async fn all_statements(&self) -> Vec<Value> {
        let r = reqwest::Client::new()
            .get(format!("{}/xAPI/statements", self.base()))
            .basic_auth(LRS_USER, Some(LRS_PASSWORD))
            .header("X-Experience-API-Version", "1.0.3")
            .send()
            .await;
        match r {
            Ok(r) if r.status().is_success() => {
                let v: Value = r.json().await.unwrap();
                v["statements"].as_array().cloned().unwrap_or_default()
            }
            _ => Vec::new(),
        }
    }

    fn stop(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Ralph {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().port()
}

/// The familiarisation exercise's ghost posture (its targets), from the server.
async fn ghost_rad(base: &str) -> Vec<f64> {
    let spec: Value = reqwest::get(format!("{base}/api/exercises/familiarisation"))
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    spec["scene"]["ghosts"][0]["q_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_f64().unwrap().to_radians())
        .collect()
}

/// Drives the left arm to `target` (rad per joint) with stick = 3·error (clamped to ±1,
/// nothing within 0.3°) until the running exercise reports done; returns how many state
/// frames came meanwhile. Panics after `limit`.
async fn drive_to_done(ws: &mut Ws, seq: &mut u64, target: &[f64], limit: Duration) -> usize {
    let deadline = Instant::now() + limit;
    let mut frames = 0;
    // Frames sent before a reset took effect still show the previous attempt done.
    let mut running = false;
    loop {
        assert!(
            Instant::now() < deadline,
            "the exercise did not finish in {limit:?}"
        );
        let s = next_of(ws, "state", Duration::from_secs(5)).await;
        frames += 1;
        running |= s["exercise"]["done"] == false;
        if running && s["exercise"]["done"] == true {
            send(ws, json!({"type": "input", "seq": *seq + 1, "arms": {}})).await;
            *seq += 1;
            return frames;
        }
        let axes: Vec<f64> = (0..6)
            .map(|j| {
                let e = target[j] - common::q(&s, "left", j);
                if e.abs() < 0.3f64.to_radians() {
                    0.0
                } else {
                    (3.0 * e).clamp(-1.0, 1.0)
                }
            })
            .collect();
        *seq += 1;
        send(
            ws,
            json!({"type": "input", "seq": *seq, "arms": {"left": {"axes": axes, "grip": 0}}}),
        )
        .await;
    }
}

/// The stored attempt `id` once it has an outcome (the recorder writes within a second).
async fn stored_attempt(base: &str, id: &str) -> Value {
    let deadline = Instant::now() + Duration::from_secs(15);
    loop {
        let (_, text) = common::get_as(&format!("{base}/api/attempts/{id}"), TEACHER).await;
        let a: Value = serde_json::from_str(&text).unwrap_or(Value::Null);
        if a["outcome"].is_string() {
            return a;
        }
        assert!(Instant::now() < deadline, "attempt {id} not stored: {text}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

/// The statements of attempt `id` among `all` (by our context extension), by verb.
fn of_attempt(all: &[Value], id: &str) -> Vec<(String, Value)> {
    let key = format!("{PUBLIC}/xapi/extensions/attempt");
    let mut v: Vec<(String, Value)> = all
        .iter()
        .filter(|s| s["context"]["extensions"][&key]["attempt"] == id)
        .map(|s| {
            let verb = s["verb"]["id"].as_str().unwrap();
            (verb.rsplit('/').next().unwrap().to_string(), s.clone())
        })
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// Waits (up to `limit`) for attempt `id`'s statements at the LRS: at least `n`.
async fn wait_for_statements(
    ralph: &Ralph,
    id: &str,
    n: usize,
    limit: Duration,
) -> Vec<(String, Value)> {
    let deadline = Instant::now() + limit;
    loop {
        let got = of_attempt(&ralph.all_statements().await, id);
        if got.len() >= n {
            return got;
        }
        assert!(
            Instant::now() < deadline,
            "attempt {id}: {} of {n} statements at the LRS after {limit:?}",
            got.len()
        );
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
}

/// Checks the statements of a stored attempt against it: verbs, score, success, completion.
fn check(statements: &[(String, Value)], a: &Value) {
    let verbs: Vec<&str> = statements.iter().map(|(v, _)| v.as_str()).collect();
    let outcome = a["outcome"].as_str().unwrap();
    let completed = a["assessment"]["completed"] == true;
    let mut want = vec!["attempted", outcome, "scored"];
    if completed {
        want.push("completed");
    }
    want.sort_unstable();
    assert_eq!(
        verbs, want,
        "verbs for a {outcome} attempt (completed {completed})"
    );
    let score = a["score"].as_f64().unwrap();
    for (verb, s) in statements {
        assert_eq!(s["actor"]["name"], "Ada Lovelace");
        assert_eq!(s["actor"]["account"]["homePage"], PUBLIC);
        assert_eq!(
            s["object"]["id"],
            format!("{PUBLIC}/exercises/familiarisation")
        );
        if verb == "scored" || verb == outcome {
            let sc = &s["result"]["score"];
            assert!((sc["raw"].as_f64().unwrap() - score).abs() < 1e-9, "{s}");
            assert!((sc["scaled"].as_f64().unwrap() - score / 100.0).abs() < 1e-9);
            assert_eq!(sc["min"], 0);
            assert_eq!(sc["max"], 100);
        }
        if verb == outcome {
            assert_eq!(s["result"]["success"], outcome == "passed");
            assert_eq!(s["result"]["completion"], completed);
            let metrics = &s["result"]["extensions"][format!("{PUBLIC}/xapi/extensions/metrics")];
            assert_eq!(
                metrics["time_s"], a["assessment"]["time_s"],
                "the attempt's metrics ride along"
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn statements_reach_a_real_lrs_and_wait_out_its_downtime() {
    if !ralph_installed() {
        assert!(
            std::env::var_os("SEAARMS_TEST_RALPH").is_none(),
            "SEAARMS_TEST_RALPH is set but Ralph's LRS (PyPI ralph-malph[cli,lrs]) is not \
             installed"
        );
        eprintln!("SKIPPED: Ralph's LRS is not installed (pip install 'ralph-malph[cli,lrs]')");
        return;
    }
    let lrs_dir = temp_dir("ralph");
    Ralph::make_user(&lrs_dir);
    let port = free_port();
    let ralph = Ralph::start(&lrs_dir, port, "before.jsonl").await;

    let data = temp_dir("xapi");
    let endpoint = format!("http://127.0.0.1:{port}/xAPI/");
    let server = Binary::start_env(
        &data,
        &["--xapi-endpoint", &endpoint, "--public-url", PUBLIC],
        &[
            ("SEAARMS_XAPI_USERNAME", LRS_USER),
            ("SEAARMS_XAPI_PASSWORD", LRS_PASSWORD),
        ],
    );
    let base = server.base.clone();
    let target = ghost_rad(&base).await;
    let c: Value = reqwest::Client::new()
        .post(format!("{base}/api/sessions"))
        .json(
            &json!({"trainee": "Ada Lovelace", "group": "Class X", "scenario": "familiarisation"}),
        )
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let session = c["id"].as_str().unwrap().to_string();
    // Not `ws_url`: that is built from the public URL, a name nothing resolves here.
    let ws_url = format!(
        "{}/ws/sessions/{session}?token={}",
        base.replace("http://", "ws://"),
        c["control_token"].as_str().unwrap()
    );
    let (mut ws, _) = tokio_tungstenite::connect_async(ws_url).await.unwrap();
    next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    let mut seq = 0;

    // 1. An attempt to its end: its statements arrive with the stored verbs and score.
    drive_to_done(&mut ws, &mut seq, &target, Duration::from_secs(120)).await;
    let first = attempts_of(&base, &session, 1).await[0].clone();
    let a1 = stored_attempt(&base, &first).await;
    let n1 = 3 + usize::from(a1["assessment"]["completed"] == true);
    let got = wait_for_statements(&ralph, &first, n1, Duration::from_secs(30)).await;
    check(&got, &a1);
    let agent = json!({"objectType": "Agent", "account": got[0].1["actor"]["account"]});
    assert_eq!(
        ralph.statements_of(&agent).await.len(),
        n1,
        "read back by agent: this trainee's statements only"
    );
    println!(
        "attempt 1: {} score {:.1}, {} statements at the LRS",
        a1["outcome"], a1["score"], n1
    );

    // 2. The LRS goes down; the trainee tries again and finishes, the frames flowing all the
    // while; the attempt waits in the outbox.
    ralph.stop();
    send(&mut ws, json!({"type": "reset"})).await;
    let frames = drive_to_done(&mut ws, &mut seq, &target, Duration::from_secs(120)).await;
    let mut last = 0;
    common::keeps_streaming(&mut ws, &mut last, 60)
        .await
        .expect("the session streams on while the LRS is down");
    let attempts = attempts_of(&base, &session, 2).await;
    let second = attempts
        .iter()
        .find(|a| **a != first)
        .cloned()
        .expect("a second attempt");
    let a2 = stored_attempt(&base, &second).await;
    let t_down = Instant::now();
    let failures = loop {
        let f = metric(&base, "seaarms_xapi_send_failures_total").await;
        if f > 0 {
            break f;
        }
        assert!(
            t_down.elapsed() < Duration::from_secs(20),
            "no failed try counted"
        );
        tokio::time::sleep(Duration::from_millis(300)).await;
    };
    // The gauge is refreshed at the end of the sender's look, just after the failed try.
    while metric(&base, "seaarms_xapi_pending").await != 1 {
        assert!(
            t_down.elapsed() < Duration::from_secs(20),
            "one attempt pending"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    println!("LRS down: {frames} frames during the second attempt; {failures} failed tries");

    // 3. The LRS returns: the statements arrive (within the back-off's cap and a poll).
    let ralph = Ralph::start(&lrs_dir, port, "after.jsonl").await;
    let back = Instant::now();
    let n2 = 3 + usize::from(a2["assessment"]["completed"] == true);
    let got = wait_for_statements(&ralph, &second, n2, Duration::from_secs(90)).await;
    check(&got, &a2);
    println!(
        "attempt 2: {} score {:.1}; its {n2} statements arrived {:.1} s after the LRS returned",
        a2["outcome"],
        a2["score"],
        back.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    while metric(&base, "seaarms_xapi_pending").await != 0 {
        assert!(t.elapsed() < Duration::from_secs(5), "the outbox empties");
        tokio::time::sleep(Duration::from_millis(300)).await;
    }
    assert_eq!(
        metric(&base, "seaarms_xapi_statements_sent_total").await,
        (n1 + n2) as u64
    );
    assert_eq!(metric(&base, "seaarms_xapi_refused_total").await, 0);
    // This instance holds what came after its start (its own file): the second attempt's
    // statements, each once.
    assert_eq!(ralph.statements_of(&agent).await.len(), n2);
    server.stop();
    let _ = std::fs::remove_dir_all(&data);
    drop(ralph);
    let _ = std::fs::remove_dir_all(&lrs_dir);
}

/// The session's attempt ids, newest first, once at least `n` are stored.
async fn attempts_of(base: &str, session: &str, n: usize) -> Vec<String> {
    let deadline = Instant::now() + Duration::from_secs(15);
    loop {
        let url = format!("{base}/api/attempts?session={session}");
        let (_, text) = common::get_as(&url, TEACHER).await;
        let v: Value = serde_json::from_str(&text).unwrap();
        let ids: Vec<String> = v["attempts"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|a| a["id"].as_str().map(str::to_string))
            .collect();
        if ids.len() >= n {
            return ids;
        }
        assert!(Instant::now() < deadline, "{n} attempts not stored: {text}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

/// The outbox's SQL on both databases (SQLite, and PostgreSQL when
/// `SEAARMS_TEST_DATABASE_URL` is set): the queue write adds only a finished exercise
/// attempt of a named trainee, once; a claimed row is not claimed again within its lease; a
/// failed try makes it due later; a refusal keeps it out of the pending count; done removes
/// it; deleting the session (retention) takes its row too.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_outbox_queues_only_stored_finished_attempts() {
    use seaarms::db::attempt::{AttemptEnd, AttemptStart};
    use seaarms::db::{Db, Write};
    for url in records_common::database_urls().await {
        let dir = temp_dir("outbox");
        let url = url.unwrap_or_else(|| seaarms::db::default_url(&dir));
        let db = Db::open(&url).unwrap();
        let session = |id: &str, trainee: &str| Write::Session {
            id: id.into(),
            trainee: trainee.into(),
            group: "G".into(),
            scenario: "familiarisation".into(),
            created_unix: 1e9,
            token_sha256: "00".into(),
        };
        let start = |id: &str, session: &str, exercise: Option<&str>| {
            Write::AttemptStart(Box::new(AttemptStart {
                id: id.into(),
                session: session.into(),
                scenario: "familiarisation".into(),
                exercise: exercise.map(str::to_string),
                exercise_version: None,
                sim_version: "v".into(),
                started_unix: 1e9,
                init: json!({}),
            }))
        };
        let end = |id: &str, outcome: &str| {
            Write::AttemptEnd(Box::new(AttemptEnd {
                id: id.into(),
                ended_unix: 1e9 + 60.0,
                sim_seconds: 60.0,
                outcome: outcome.into(),
                score: Some(72.5),
                assessment: Some(json!({"completed": true, "time_s": 60.0})),
            }))
        };
        let queue = |id: &str| Write::XapiQueue {
            attempt: id.into(),
            queued_unix: 1e9 + 61.0,
        };
        db.write_batch(&[
            session("s1", "Ada"),
            session("s2", ""),
            start("a-passed", "s1", Some("familiarisation")),
            end("a-passed", "passed"),
            queue("a-passed"),
            start("a-failed", "s1", Some("familiarisation")),
            end("a-failed", "failed"),
            queue("a-failed"),
            start("a-abandoned", "s1", Some("familiarisation")),
            end("a-abandoned", "abandoned"),
            queue("a-abandoned"),
            start("a-free", "s1", None),
            end("a-free", "ended"),
            queue("a-free"),
            start("a-anonymous", "s2", Some("familiarisation")),
            end("a-anonymous", "passed"),
            queue("a-anonymous"),
            // Queued twice (a batch retried): one row.
            queue("a-passed"),
        ])
        .await
        .unwrap();
        assert_eq!(db.xapi_pending().await.unwrap(), 2, "{url}");
        let now = 1e9 + 100.0;
        let claimed = db.xapi_claim(now, 60.0, 10).await.unwrap();
        let ids: Vec<&str> = claimed.iter().map(|(a, _)| a.as_str()).collect();
        assert_eq!(ids, ["a-failed", "a-passed"], "oldest first, then by id");
        assert!(claimed.iter().all(|(_, tries)| *tries == 0));
        assert!(
            db.xapi_claim(now + 1.0, 60.0, 10).await.unwrap().is_empty(),
            "leased"
        );
        let src = db.xapi_source("a-passed").await.unwrap().unwrap();
        assert_eq!(src.attempt.score, Some(72.5));
        assert_eq!(src.trainee_id.len(), 16, "the trainees table's hex id");
        db.xapi_retry("a-passed", now + 5.0, "connection refused")
            .await
            .unwrap();
        db.xapi_reject("a-failed", "409 Conflict").await.unwrap();
        assert_eq!(db.xapi_pending().await.unwrap(), 1);
        assert!(db.xapi_claim(now + 4.0, 60.0, 10).await.unwrap().is_empty());
        let again = db.xapi_claim(now + 5.0, 60.0, 10).await.unwrap();
        assert_eq!(
            again,
            [("a-passed".to_string(), 1)],
            "due again, one try so far"
        );
        db.xapi_done("a-passed").await.unwrap();
        assert_eq!(db.xapi_pending().await.unwrap(), 0);
        // Retention deletes the session's rows, the refused outbox row with them.
        db.write_batch(&[
            start("a-later", "s1", Some("familiarisation")),
            end("a-later", "passed"),
            queue("a-later"),
        ])
        .await
        .unwrap();
        assert_eq!(db.xapi_pending().await.unwrap(), 1);
        db.delete_sessions(&["s1".to_string()]).await.unwrap();
        assert_eq!(db.xapi_pending().await.unwrap(), 0);
        assert!(db.xapi_source("a-later").await.unwrap().is_none());
        drop(db);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
