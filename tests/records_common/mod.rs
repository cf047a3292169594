//! Helpers of the record tests: the real binary as a server, session creation, WebSocket
//! driving, reading a record CSV.
#![allow(dead_code, clippy::unwrap_used)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::common::TEACHER;

/// The real `seaarms` binary serving on a free port; killed (SIGKILL) when dropped.
pub(crate) struct Binary {
    pub(crate) base: String,
    child: Child,
}

impl Binary {
    pub(crate) fn start(dir: &Path, extra: &[&str]) -> Binary {
        Binary::start_env(dir, extra, &[])
    }

    /// [`Binary::start`] with extra environment variables (settings read from the
    /// environment only, such as credentials).
    pub(crate) fn start_env(dir: &Path, extra: &[&str], env: &[(&str, &str)]) -> Binary {
        let mut child = Command::new(env!("CARGO_BIN_EXE_seaarms"))
            .args([
                "serve",
                "--bind",
                "127.0.0.1:0",
                "--instructor-token",
                TEACHER,
            ])
            .arg("--data-dir")
            .arg(dir)
            .args(extra)
            // tests not about progression start any exercise directly (`--progression on` in
            // `extra`, or the variable in `env`, turns it back on: tests/progression.rs)
            .env("SEAARMS_PROGRESSION", "off")
            .envs(env.iter().copied())
            .env("RUST_LOG", "warn")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Some(url) = line.strip_prefix("seaarms serving on ") {
                    let _ = tx.send(url.trim().to_string());
                }
            }
        });
        let base = match rx.recv_timeout(Duration::from_secs(30)) {
            Ok(b) => b,
            Err(_) => {
                let _ = child.kill();
                panic!("the server did not print its address within 30 s");
            }
        };
        Binary { base, child }
    }

    /// The server's memory from `/proc`: (resident now, peak resident), bytes.
    pub(crate) fn memory(&self) -> (u64, u64) {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let kb = |key: &str| -> u64 {
            let line = status.lines().find(|l| l.starts_with(key)).unwrap();
            line.split_whitespace()
                .nth(1)
                .unwrap()
                .parse::<u64>()
                .unwrap()
                * 1024
        };
        (kb("VmRSS:"), kb("VmHWM:"))
    }

    /// SIGTERM: a graceful stop (every session ends, records are flushed); waits up to 20 s.
    pub(crate) fn stop(mut self) {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-TERM", &pid]).status();
        let end = Instant::now() + Duration::from_secs(20);
        while Instant::now() < end {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("the server did not stop within 20 s of SIGTERM");
    }

    /// Sends `signal` (e.g. `-TERM`) and returns at once.
    pub(crate) fn signal(&self, signal: &str) {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args([signal, &pid]).status();
    }

    /// The exit status once the process has exited, None while it runs.
    pub(crate) fn exited(&mut self) -> Option<std::process::ExitStatus> {
        self.child.try_wait().ok().flatten()
    }

    /// SIGKILL: no shutdown code runs.
    pub(crate) fn kill9(mut self) {
        self.child.kill().unwrap();
        self.child.wait().unwrap();
    }
}

impl Drop for Binary {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The value of a metric in `/metrics`.
pub(crate) async fn metric(base: &str, name: &str) -> u64 {
    let text = reqwest::get(format!("{base}/metrics"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{name} ")))
        .unwrap_or_else(|| panic!("no {name} in {text}"))
        .trim()
        .parse()
        .unwrap()
}

/// Drives session `c` (the creation answer) over its WebSocket for `seconds`: full stick on
/// `joint` of both arms, 25 messages a second.
pub(crate) async fn drive(c: &Value, joint: usize, seconds: f64) {
    let url = c["ws_url"].as_str().unwrap();
    let (mut ws, _) = tokio_tungstenite::connect_async(url).await.unwrap();
    let mut axes = [0.0; 6];
    axes[joint] = 1.0;
    let n = (seconds * 25.0) as u64;
    for seq in 1..=n {
        let msg = json!({"type": "input", "seq": seq,
            "arms": {"left": {"axes": axes, "grip": 0}, "right": {"axes": axes, "grip": 0}}});
        crate::common::send(&mut ws, msg).await;
        tokio::time::sleep(Duration::from_millis(40)).await;
    }
    let _ = ws.close(None).await;
}

/// A record CSV as read from disk: the header, the whole rows, and the bytes after the last
/// newline (a row cut by a crash; 0 when the file ends with a whole row).
pub(crate) struct Csv {
    pub(crate) header: Vec<String>,
    pub(crate) rows: Vec<Vec<String>>,
    pub(crate) cut_tail: usize,
}

impl Csv {
    pub(crate) fn read(path: &Path) -> Csv {
        let bytes = std::fs::read(path).unwrap();
        let whole = seaarms::csv_out::complete_lines(&bytes);
        let cut_tail = bytes.len() - whole.len();
        let mut r = csv::Reader::from_reader(whole);
        let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        let rows = r
            .records()
            .map(|rec| {
                let rec = rec.unwrap_or_else(|e| panic!("{}: bad row: {e}", path.display()));
                assert_eq!(rec.len(), header.len(), "{}: short row", path.display());
                rec.iter().map(String::from).collect()
            })
            .collect();
        Csv {
            header,
            rows,
            cut_tail,
        }
    }

    /// Column `name` of the last row, as f64.
    pub(crate) fn last(&self, name: &str) -> f64 {
        let i = self.header.iter().position(|h| h == name).unwrap();
        self.rows.last().unwrap()[i].parse().unwrap()
    }
}

/// Polls `f` every 100 ms until it gives Some, for at most `limit`.
pub(crate) async fn eventually<T, F, Fut>(limit: Duration, mut f: F) -> Option<T>
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Option<T>>,
{
    let end = Instant::now() + limit;
    while Instant::now() < end {
        if let Some(v) = f().await {
            return Some(v);
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    None
}

/// The databases every records test runs against: the default SQLite file in the data
/// folder (`None`), and a fresh database on the PostgreSQL server of
/// `SEAARMS_TEST_DATABASE_URL` when it is set (`tests/run.sh` starts one); without it a
/// notice says the PostgreSQL half is skipped.
pub(crate) async fn database_urls() -> Vec<Option<String>> {
    let mut urls = vec![None];
    match std::env::var("SEAARMS_TEST_DATABASE_URL") {
        Ok(base) if !base.is_empty() => urls.push(Some(fresh_postgres_database(&base).await)),
        _ => eprintln!(
            "NOTICE: SEAARMS_TEST_DATABASE_URL is not set: PostgreSQL skipped, SQLite only \
             (tests/run.sh starts a throwaway PostgreSQL server and sets it)"
        ),
    }
    urls
}

/// Creates an empty database beside the one `base` names (so tests running at once do not
/// see each other's records, e.g. under retention) and returns its URL.
pub(crate) async fn fresh_postgres_database(base: &str) -> String {
    use sqlx::{Connection, Executor};
    sqlx::any::install_default_drivers();
    let name = format!("seaarms_{}", seaarms::ids::random_hex(6));
    let mut c = sqlx::AnyConnection::connect(base)
        .await
        .unwrap_or_else(|e| panic!("SEAARMS_TEST_DATABASE_URL {base}: {e}"));
    c.execute(format!("CREATE DATABASE {name}").as_str())
        .await
        .unwrap();
    c.close().await.unwrap();
    let (server, _) = base
        .rsplit_once('/')
        .unwrap_or_else(|| panic!("{base}: no database name"));
    format!("{server}/{name}")
}

/// A stored session of `trainee` in `group` on `scenario`, created at `created_unix` (a class
/// written straight to the database, as the recorder writes it).
pub(crate) fn stored_session(
    id: &str,
    trainee: &str,
    group: &str,
    scenario: &str,
    created_unix: f64,
) -> seaarms::db::Write {
    seaarms::db::Write::Session {
        id: id.into(),
        trainee: trainee.into(),
        group: group.into(),
        scenario: scenario.into(),
        created_unix,
        token_sha256: "ab".repeat(32),
    }
}

/// A stored attempt at `exercise` (version 1) in `session`, started at `started` and ended
/// 30 s later (30 s simulated) with `outcome` and `score`, no assessment: its start and end.
pub(crate) fn stored_attempt(
    id: &str,
    session: &str,
    exercise: &str,
    started: f64,
    outcome: &str,
    score: Option<f64>,
) -> [seaarms::db::Write; 2] {
    use seaarms::sessions::record::{AttemptEnd, AttemptStart};
    [
        seaarms::db::Write::AttemptStart(Box::new(AttemptStart {
            id: id.into(),
            session: session.into(),
            scenario: exercise.into(),
            exercise: Some(exercise.into()),
            exercise_version: Some("1".into()),
            sim_version: "sim-1".into(),
            started_unix: started,
            init: json!({}),
        })),
        seaarms::db::Write::AttemptEnd(Box::new(AttemptEnd {
            id: id.into(),
            ended_unix: started + 30.0,
            sim_seconds: 30.0,
            outcome: outcome.into(),
            score,
            assessment: None,
        })),
    ]
}

/// `method` on `url` with bearer `token` and an optional JSON body: the status and the body as
/// JSON (Null when it is not JSON).
pub(crate) async fn send_json(
    method: reqwest::Method,
    url: &str,
    token: &str,
    body: Option<Value>,
) -> (u16, Value) {
    let mut r = reqwest::Client::new()
        .request(method, url)
        .bearer_auth(token);
    if let Some(b) = body {
        r = r.json(&b);
    }
    let r = r.send().await.unwrap();
    let st = r.status().as_u16();
    (
        st,
        serde_json::from_str(&r.text().await.unwrap()).unwrap_or(Value::Null),
    )
}
