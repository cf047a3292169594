//! Several replicas behind a real proxy (issue 18; docs/api.md "Replicas"):
//!
//! * `three_replicas_behind_haproxy`: three release `seaarms` processes on one real
//!   PostgreSQL (a fresh database on `SEAARMS_TEST_DATABASE_URL`) behind a real HAProxy whose
//!   configuration is built from `deploy/kubernetes/ingress.yaml` (the same path prefixes to
//!   the same replicas as the Ingress). 60 sessions created through the proxy spread over the
//!   replicas; each WebSocket reaches its own replica (the `replica` of its hello); every
//!   replica lists all 60; one replica killed with SIGKILL has its sessions and attempts
//!   marked interrupted within the heartbeat timeout, the others' sessions keep their frame
//!   interval p99 ≤ 25 ms (measured by `seaarms load`'s own code, `load::measure`), and new
//!   sessions go to the survivors — a full one answers 503 and the proxy retries the other.
//!   It needs `--release` (tests/run.sh runs it so) and skips in a debug build; without
//!   haproxy or the database it skips, except under CI=true, where it fails.
//! * `sigterm_drains_then_interrupts`: a replica sent SIGTERM with a live session refuses new
//!   sessions and fails readiness, keeps stepping the live one, and after `--drain-seconds`
//!   ends it as interrupted and exits.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{TEACHER, next_of, temp_dir};
use futures_util::StreamExt;
use records_common::{Binary, fresh_postgres_database, metric};
use seaarms::cluster::{HEARTBEAT, HEARTBEAT_TIMEOUT};
use serde_json::{Value, json};

/// Replicas started, and sessions created through the proxy (the figures).
const REPLICAS: usize = 3;
const SESSIONS: usize = 60;
/// The session cap of each replica, the first one lower so that creating after the kill
/// fills it and the proxy has to retry the other survivor on its 503.
const CAPS: [usize; REPLICAS] = [24, 30, 30];
/// The target of the issue: frame interval p99 of the survivors' sessions (ms).
const P99_TARGET_MS: f64 = 25.0;

/// A configuration or tool the test needs is missing: skip, except on CI (CI=true), where
/// skipping would hide that the test never ran.
fn missing(what: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("CI=true but {what}: the multi-replica test cannot run (tests/run.sh installs it)");
    }
    eprintln!("NOTICE: {what}: multi-replica test skipped (tests/run.sh sets it up)");
}

/// The routes of `deploy/kubernetes/ingress.yaml`: (path prefix, Service name), in order.
fn ingress_routes(text: &str) -> Vec<(String, String)> {
    let mut routes = Vec::new();
    let mut path: Option<String> = None;
    let mut in_service = false;
    for line in text.lines() {
        let t = line.trim();
        if let Some(p) = t.strip_prefix("- path:") {
            path = Some(p.trim().to_string());
            in_service = false;
        } else if t == "service:" {
            in_service = true;
        } else if let (Some(name), true) = (t.strip_prefix("name:"), in_service) {
            if let Some(p) = path.take() {
                routes.push((p, name.trim().to_string()));
            }
            in_service = false;
        } else if let Some(kind) = t.strip_prefix("pathType:") {
            assert_eq!(kind.trim(), "Prefix", "every rule is a Prefix rule: {t}");
        }
    }
    routes
}

/// HAProxy's configuration for the Ingress routes: a replica's prefix rule goes to that
/// replica alone (health-checked for liveness only, as its per-pod Service publishes
/// not-ready addresses); `/` goes to every ready replica (readiness: `/healthz`), round
/// robin, with a 503 or a refused connection retried on another one.
fn haproxy_config(
    routes: &[(String, String)],
    replicas: &HashMap<String, String>,
    port: u16,
) -> String {
    let mut front = format!(
        "global\n  maxconn 4096\n\ndefaults\n  mode http\n  timeout connect 2s\n  timeout client 1h\n  \
         timeout server 1h\n  timeout tunnel 1h\n  retries 3\n  option redispatch 1\n  \
         retry-on conn-failure empty-response 503\n\nfrontend fe\n  bind 127.0.0.1:{port}\n  \
         option forwardfor\n"
    );
    let mut backs = String::new();
    for (i, (path, service)) in routes.iter().enumerate() {
        let backend = format!("be_{service}");
        if path == "/" {
            front.push_str(&format!("  default_backend {backend}\n"));
            backs.push_str(&format!(
                "\nbackend {backend}\n  balance roundrobin\n  option httpchk GET /healthz\n"
            ));
            for (name, addr) in replicas {
                backs.push_str(&format!(
                    "  server {name} {addr} check inter 500ms fall 2 rise 1\n"
                ));
            }
        } else {
            // pathType: Prefix matches whole segments: the path itself or below it.
            front.push_str(&format!(
                "  acl route{i} path {path}\n  acl route{i} path_beg {path}/\n  use_backend {backend} if route{i}\n"
            ));
            backs.push_str(&format!(
                "\nbackend {backend}\n  option httpchk GET /healthz?probe=live\n"
            ));
            if let Some(addr) = replicas.get(service) {
                backs.push_str(&format!(
                    "  server {service} {addr} check inter 500ms fall 2 rise 1\n"
                ));
            }
        }
    }
    front + &backs
}

struct Haproxy(Child);

impl Drop for Haproxy {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn which(tool: &str) -> Option<std::path::PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .chain([Path::new("/usr/sbin").to_path_buf()])
            .map(|d| d.join(tool))
            .find(|p| p.is_file())
    })
}

/// Polls `check` every 100 ms until it gives a value or `limit` passes (then panics with
/// `what`).
async fn wait_for<T, F, Fut>(limit: Duration, what: &str, mut check: F) -> T
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Option<T>>,
{
    let end = Instant::now() + limit;
    loop {
        if let Some(v) = check().await {
            return v;
        }
        assert!(Instant::now() < end, "{what}: not within {limit:?}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

async fn list(base: &str) -> Vec<Value> {
    let v = common::get_json(&format!("{base}/api/sessions")).await;
    v.as_array().unwrap().clone()
}

fn live_ids(list: &[Value]) -> HashSet<String> {
    list.iter()
        .filter(|s| s["status"] == "live")
        .map(|s| s["id"].as_str().unwrap().to_string())
        .collect()
}

/// The `hello` of `ws_url` (through the proxy) — which replica answered.
async fn hello_replica(ws_url: &str) -> String {
    let (mut ws, _) = tokio::time::timeout(
        Duration::from_secs(10),
        tokio_tungstenite::connect_async(ws_url),
    )
    .await
    .unwrap_or_else(|_| panic!("{ws_url}: no connection in 10 s"))
    .unwrap_or_else(|e| panic!("{ws_url}: {e}"));
    let hello = next_of(&mut ws, "hello", Duration::from_secs(10)).await;
    let _ = ws.close(None).await;
    while let Ok(Some(_)) = tokio::time::timeout(Duration::from_secs(2), ws.next()).await {}
    hello["replica"].as_str().unwrap_or_default().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn three_replicas_behind_haproxy() {
    if cfg!(debug_assertions) {
        eprintln!("NOTICE: the multi-replica test needs --release (real-time physics); skipped");
        return;
    }
    let Some(base_db) = std::env::var("SEAARMS_TEST_DATABASE_URL")
        .ok()
        .filter(|u| !u.is_empty())
    else {
        return missing("SEAARMS_TEST_DATABASE_URL is not set (PostgreSQL)");
    };
    let Some(haproxy) = which("haproxy") else {
        return missing("haproxy is not installed");
    };
    let db_url = fresh_postgres_database(&base_db).await;

    // Three replicas named as the StatefulSet names its pods, on one database.
    let dirs: Vec<_> = (0..REPLICAS)
        .map(|i| temp_dir(&format!("cluster{i}")))
        .collect();
    let mut replicas: Vec<Option<Binary>> = Vec::new();
    let mut addrs = HashMap::new();
    for (i, dir) in dirs.iter().enumerate() {
        let name = format!("seaarms-{i}");
        let cap = CAPS[i].to_string();
        let b = Binary::start(
            dir,
            &[
                "--database-url",
                &db_url,
                "--replica-name",
                &name,
                "--max-sessions",
                &cap,
                "--physics-threads",
                "1",
                "--trusted-proxies",
                "127.0.0.1",
                "--session-burst",
                "1000",
                "--sessions-per-minute",
                "1000",
                "--max-sessions-per-client",
                "1000",
                "--unjoined-grace-secs",
                "600",
                "--abandon-grace-seconds",
                "600",
            ],
        );
        addrs.insert(name, b.base.trim_start_matches("http://").to_string());
        replicas.push(Some(b));
    }
    let direct: Vec<String> = replicas
        .iter()
        .map(|b| b.as_ref().unwrap().base.clone())
        .collect();

    // HAProxy routing exactly as the Ingress does.
    let ingress = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/kubernetes/ingress.yaml"),
    )
    .unwrap();
    let routes = ingress_routes(&ingress);
    assert!(
        routes.iter().any(|(p, s)| p == "/" && s == "seaarms"),
        "{routes:?}"
    );
    for i in 0..REPLICAS {
        let name = format!("seaarms-{i}");
        assert!(
            routes.contains(&(format!("/r/{name}"), name.clone())),
            "the Ingress routes /r/{name} to its pod's Service: {routes:?}"
        );
    }
    let port = free_port();
    let cfg_dir = temp_dir("haproxy");
    std::fs::create_dir_all(&cfg_dir).unwrap();
    let cfg = cfg_dir.join("haproxy.cfg");
    std::fs::write(&cfg, haproxy_config(&routes, &addrs, port)).unwrap();
    let check = Command::new(&haproxy)
        .arg("-c")
        .arg("-f")
        .arg(&cfg)
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "haproxy -c: {}",
        String::from_utf8_lossy(&check.stderr)
    );
    let _proxy = Haproxy(
        Command::new(&haproxy)
            .arg("-db")
            .arg("-f")
            .arg(&cfg)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let proxy = format!("http://127.0.0.1:{port}");
    let http = reqwest::Client::new();
    wait_for(
        Duration::from_secs(20),
        "the proxy sees every replica ready",
        || {
            let http = http.clone();
            let proxy = proxy.clone();
            async move {
                for i in 0..REPLICAS {
                    let r = http
                        .get(format!("{proxy}/r/seaarms-{i}/healthz"))
                        .send()
                        .await
                        .ok()?;
                    r.status().is_success().then_some(())?;
                }
                Some(())
            }
        },
    )
    .await;
    // Give the `/` backend's health checks (every 0.5 s) time to mark every server up.
    tokio::time::sleep(Duration::from_secs(2)).await;

    // 60 sessions created through the proxy, as trainees' pages create them.
    let mut created = Vec::new();
    for k in 0..SESSIONS {
        let (st, c) = common::create_at(
            &proxy,
            json!({"trainee": format!("t{k}"), "group": "cluster"}),
        )
        .await;
        assert_eq!(st, 201, "session {k}: {c}");
        let replica = c["replica"].as_str().unwrap().to_string();
        let base = c["base"].as_str().unwrap();
        assert_eq!(base, format!("/r/{replica}"), "{c}");
        let ws_url = c["ws_url"].as_str().unwrap();
        assert!(
            ws_url.starts_with(&format!("ws://127.0.0.1:{port}/r/{replica}/ws/sessions/")),
            "the session's URL goes through the proxy to its replica: {c}"
        );
        created.push(c);
    }
    let mut per_replica: HashMap<String, usize> = HashMap::new();
    for c in &created {
        *per_replica
            .entry(c["replica"].as_str().unwrap().to_string())
            .or_default() += 1;
    }
    eprintln!("sessions per replica: {per_replica:?}");
    assert_eq!(
        per_replica.len(),
        REPLICAS,
        "every replica took sessions: {per_replica:?}"
    );
    for (name, n) in &per_replica {
        assert!(
            *n >= SESSIONS / REPLICAS / 2,
            "{name} took only {n}: {per_replica:?}"
        );
    }

    // Each WebSocket, opened through the proxy, reaches the replica that holds its session.
    for c in &created {
        let got = hello_replica(c["ws_url"].as_str().unwrap()).await;
        assert_eq!(got, c["replica"].as_str().unwrap(), "{c}");
    }
    // A session's prefix on the wrong replica: 421 naming the right one.
    let c0 = &created[0];
    let holder = c0["replica"].as_str().unwrap();
    let other = (0..REPLICAS)
        .map(|i| format!("seaarms-{i}"))
        .find(|n| n != holder)
        .unwrap();
    let other_addr = &addrs[&other];
    let id0 = c0["id"].as_str().unwrap();
    let misdirected = |path: String| {
        let http = http.clone();
        async move {
            let r = http.get(path).bearer_auth(TEACHER).send().await.unwrap();
            assert_eq!(r.status().as_u16(), 421);
            // with the security headers every other answer carries (issue 29 item 14)
            assert!(r.headers().contains_key("content-security-policy"));
            assert!(r.headers().contains_key("x-content-type-options"));
            r.json::<Value>().await.unwrap()
        }
    };
    let base0 = c0["base"].as_str().unwrap();
    let body = misdirected(format!("http://{other_addr}{base0}/api/sessions/{id0}")).await;
    assert_eq!(body["detail"]["replica"], holder, "{body}");
    // … and its bare id on a replica that does not hold it: 421 from the directory.
    let body = misdirected(format!("http://{other_addr}/api/sessions/{id0}")).await;
    assert_eq!(body["detail"]["base"], format!("/r/{holder}"), "{body}");
    // so do its assessment and its CSV log (docs/api.md; they answered 404 and 403)
    for route in ["assessment", "log.csv"] {
        let body = misdirected(format!("http://{other_addr}/api/sessions/{id0}/{route}")).await;
        assert_eq!(body["detail"]["replica"], holder, "{route}: {body}");
    }

    // The instructor's list on any replica (and through the proxy) has all 60 live.
    let all_ids: HashSet<String> = created
        .iter()
        .map(|c| c["id"].as_str().unwrap().to_string())
        .collect();
    for base in direct.iter().chain([&proxy]) {
        let l = list(base).await;
        assert_eq!(
            live_ids(&l),
            all_ids,
            "{base} lists every replica's live sessions"
        );
        for s in l.iter().filter(|s| s["status"] == "live") {
            let id = s["id"].as_str().unwrap();
            let c = created.iter().find(|c| c["id"] == id).unwrap();
            assert_eq!(s["replica"], c["replica"], "{s}");
            assert_eq!(s["trainee"], c_trainee(&created, id), "{s}");
        }
    }

    // Frames before the kill, all 60 sessions through the proxy.
    let urls: Vec<String> = created
        .iter()
        .map(|c| c["ws_url"].as_str().unwrap().to_string())
        .collect();
    let before = seaarms::load::measure(&urls, &[], 50.0, Instant::now() + Duration::from_secs(5))
        .await
        .unwrap();
    eprintln!(
        "before the kill: {SESSIONS} sessions on {REPLICAS} replicas, frame interval p50 {:.1} ms p99 {:.1} ms, input latency p99 {:.1} ms, errors {}",
        before.frame_interval_ms_p50,
        before.frame_interval_ms_p99,
        before.latency_ms_p99,
        before.errors.len()
    );
    assert!(before.errors.is_empty(), "{:?}", before.errors);

    // SIGKILL one replica; the others declare it lost and mark its sessions interrupted.
    let victim = "seaarms-1";
    let victim_ids: HashSet<String> = created
        .iter()
        .filter(|c| c["replica"] == victim)
        .map(|c| c["id"].as_str().unwrap().to_string())
        .collect();
    let killed_at = Instant::now();
    replicas[1].take().unwrap().kill9();
    let survivors: Vec<String> = created
        .iter()
        .filter(|c| c["replica"] != victim)
        .map(|c| c["ws_url"].as_str().unwrap().to_string())
        .collect();
    // The survivors' frames while the replica is missed and declared lost.
    let after_task = tokio::spawn({
        let survivors = survivors.clone();
        async move {
            seaarms::load::measure(
                &survivors,
                &[],
                50.0,
                Instant::now() + Duration::from_secs(8),
            )
            .await
            .unwrap()
        }
    });
    let reason = seaarms::db::lost_reason(victim);
    let limit = HEARTBEAT_TIMEOUT + 3 * HEARTBEAT;
    let marked_after = wait_for(
        limit * 2,
        "the killed replica's sessions marked interrupted",
        || {
            let base = direct[0].clone();
            let victim_ids = victim_ids.clone();
            let reason = reason.clone();
            async move {
                let l = list(&base).await;
                let done = victim_ids.iter().all(|id| {
                    l.iter().any(|s| {
                        s["id"] == id.as_str()
                            && s["status"] == "ended"
                            && s["end_reason"] == reason.as_str()
                    })
                });
                done.then(|| killed_at.elapsed())
            }
        },
    )
    .await;
    eprintln!(
        "killed replica's {} sessions marked interrupted {:.2} s after SIGKILL (heartbeat {:?}, timeout {:?})",
        victim_ids.len(),
        marked_after.as_secs_f64(),
        HEARTBEAT,
        HEARTBEAT_TIMEOUT
    );
    // The last heartbeat was at most one period before the kill; a survivor notices at its
    // next beat after the timeout; one more period for the database round trips.
    assert!(marked_after <= limit, "{marked_after:?} > {limit:?}");
    // Their running attempts are interrupted too, in the shared records.
    let attempts = common::get_json(&format!("{}/api/attempts?group=cluster", direct[2])).await;
    let mut seen = 0;
    for a in attempts["attempts"].as_array().unwrap() {
        if victim_ids.contains(a["session"].as_str().unwrap()) {
            seen += 1;
            assert_eq!(a["outcome"], "interrupted", "{a}");
        }
    }
    assert!(
        seen >= victim_ids.len(),
        "every killed session had its attempt: {seen}"
    );
    // A trainee's page asks any replica about its session (bare path through the proxy):
    // ended, interrupted, with the reason naming the replica.
    let victim_c = created.iter().find(|c| c["replica"] == victim).unwrap();
    let r = http
        .get(format!(
            "{proxy}/api/sessions/{}",
            victim_c["id"].as_str().unwrap()
        ))
        .bearer_auth(victim_c["control_token"].as_str().unwrap())
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);
    let s: Value = r.json().await.unwrap();
    assert_eq!(s["status"], "ended", "{s}");
    assert_eq!(s["end_reason"], reason.as_str(), "{s}");

    let after = after_task.await.unwrap();
    eprintln!(
        "after the kill: {} sessions on {} replicas, frame interval p50 {:.1} ms p99 {:.1} ms, input latency p99 {:.1} ms, errors {}",
        survivors.len(),
        REPLICAS - 1,
        after.frame_interval_ms_p50,
        after.frame_interval_ms_p99,
        after.latency_ms_p99,
        after.errors.len()
    );
    assert!(after.errors.is_empty(), "{:?}", after.errors);
    assert!(
        after.frame_interval_ms_p99 <= P99_TARGET_MS,
        "survivors' frame interval p99 {:.1} ms > {P99_TARGET_MS} ms",
        after.frame_interval_ms_p99
    );

    // New sessions go to the survivors; seaarms-0 fills up (cap 24) and answers 503, and the
    // proxy retries seaarms-2 (cap 30), until both are full.
    let live_on = |name: &str| created.iter().filter(|c| c["replica"] == name).count();
    let room = (CAPS[0] - live_on("seaarms-0")) + (CAPS[2] - live_on("seaarms-2"));
    let mut new_on: HashMap<String, usize> = HashMap::new();
    for k in 0..room {
        let (st, c) = common::create_at(
            &proxy,
            json!({"trainee": format!("n{k}"), "group": "cluster"}),
        )
        .await;
        assert_eq!(st, 201, "new session {k} of {room}: {c}");
        *new_on
            .entry(c["replica"].as_str().unwrap().to_string())
            .or_default() += 1;
    }
    eprintln!("new sessions after the kill: {new_on:?}");
    assert!(!new_on.contains_key(victim), "{new_on:?}");
    assert_eq!(
        live_on("seaarms-0") + new_on.get("seaarms-0").copied().unwrap_or(0),
        CAPS[0]
    );
    assert_eq!(
        live_on("seaarms-2") + new_on.get("seaarms-2").copied().unwrap_or(0),
        CAPS[2]
    );
    let (st, c) = common::create_at(&proxy, json!({})).await;
    assert_eq!(st, 503, "every survivor is full: {c}");

    // A graceful stop (SIGTERM, no drain): its sessions end recorded, it leaves the
    // directory, and the other replica lists them ended at once (not live, not lost).
    let on_2: HashSet<String> = list(&direct[2])
        .await
        .iter()
        .filter(|s| s["status"] == "live" && s["replica"] == "seaarms-2")
        .map(|s| s["id"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(on_2.len(), CAPS[2]);
    replicas[2].take().unwrap().stop();
    let after_stop = list(&direct[0]).await;
    for id in &on_2 {
        let s = after_stop.iter().find(|s| s["id"] == id.as_str()).unwrap();
        assert_eq!(s["status"], "ended", "{s}");
        assert_eq!(s["end_reason"], "server shutdown", "{s}");
    }
    drop(replicas);
    for d in dirs.iter().chain([&cfg_dir]) {
        let _ = std::fs::remove_dir_all(d);
    }
}

fn c_trainee(created: &[Value], id: &str) -> String {
    let c = created.iter().position(|c| c["id"] == id).unwrap();
    format!("t{c}")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_drains_then_interrupts() {
    let dir = temp_dir("drain");
    let drain_s = 3;
    let mut b = Binary::start(&dir, &["--drain-seconds", &drain_s.to_string()]);
    let (st, c) = common::create_at(&b.base, json!({"trainee": "dora"})).await;
    assert_eq!(st, 201, "{c}");
    let id = c["id"].as_str().unwrap().to_string();
    let (mut ws, _) = tokio_tungstenite::connect_async(c["ws_url"].as_str().unwrap())
        .await
        .unwrap();
    next_of(&mut ws, "hello", Duration::from_secs(10)).await;
    let http = reqwest::Client::new();
    assert_eq!(metric(&b.base, "seaarms_draining").await, 0);

    b.signal("-TERM");
    let signalled = Instant::now();
    // Readiness fails, liveness holds, creation is refused — while the session still runs.
    let base = b.base.clone();
    wait_for(
        Duration::from_secs(2),
        "readiness 503 while draining",
        || {
            let http = http.clone();
            let base = base.clone();
            async move {
                let r = http.get(format!("{base}/healthz")).send().await.ok()?;
                (r.status().as_u16() == 503).then_some(())
            }
        },
    )
    .await;
    let live = http
        .get(format!("{}/healthz?probe=live", b.base))
        .send()
        .await
        .unwrap();
    assert_eq!(live.status().as_u16(), 200);
    let (st, body) = common::create_at(&b.base, json!({})).await;
    assert_eq!(st, 503, "{body}");
    assert!(
        body["error"].as_str().unwrap().contains("draining"),
        "{body}"
    );
    assert_eq!(metric(&b.base, "seaarms_draining").await, 1);
    // Frames queued before the signal come first: compare the first and the last of 1 s (a
    // debug build steps far slower than real time, so only "it advances" is asked).
    let state_t = |v: Value| v["t"].as_f64().unwrap();
    let t0 = state_t(next_of(&mut ws, "state", Duration::from_secs(5)).await);
    let mut t1 = t0;
    let until = Instant::now() + Duration::from_secs(1);
    while Instant::now() < until {
        t1 = state_t(next_of(&mut ws, "state", Duration::from_secs(5)).await);
    }
    assert!(
        t1 > t0,
        "the live session keeps stepping while draining: {t0} → {t1}"
    );

    // After the drain deadline: the session ends (server shutdown), the process exits.
    let ended = next_of(&mut ws, "ended", Duration::from_secs(drain_s + 10)).await;
    assert_eq!(ended["reason"], "server_shutdown", "{ended}");
    assert!(
        signalled.elapsed() >= Duration::from_secs(drain_s) - Duration::from_millis(300),
        "ended before the drain deadline"
    );
    let status = wait_for(Duration::from_secs(20), "exit after the drain", || {
        let s = b.exited();
        async move { s }
    })
    .await;
    assert!(status.success(), "{status:?}");
    // The record: the session interrupted by the stop, its running attempt interrupted.
    let db = seaarms::db::Db::open(&seaarms::db::default_url(&dir)).unwrap();
    let s = db.session(&id).await.unwrap().unwrap();
    assert_eq!(s.end_reason.as_deref(), Some("server shutdown"), "{s:?}");
    let attempts = db
        .attempts(&seaarms::db::AttemptFilter {
            session: Some(id.clone()),
            ..Default::default()
        })
        .await
        .unwrap();
    assert!(!attempts.is_empty());
    assert!(
        attempts
            .iter()
            .all(|a| a.outcome.as_deref() == Some("interrupted")),
        "{attempts:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
