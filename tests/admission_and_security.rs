//! Admission and browser security over real sockets: a flood of session creations from one
//! client cannot lock another out; the class join code is enforced; sessions nobody joins
//! end; the instructor can end any session; pages carry CSP, nosniff, DENY and no-referrer;
//! state changes need JSON and a same-origin (or allowed) `Origin`; every error is JSON;
//! oversize WebSocket messages close with 1009 and a close frame; a `seq` beyond 2⁵³ is
//! refused while the session streams on; tokens compare exactly; the instructor token is
//! printed only when generated, once, to stderr (the real binary).

#![allow(clippy::unwrap_used)]

mod common;

use std::net::{IpAddr, Ipv4Addr};
use std::time::{Duration, Instant};

use common::*;
use futures_util::SinkExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

fn http_from(local: IpAddr) -> reqwest::Client {
    reqwest::Client::builder()
        .local_address(local)
        .build()
        .unwrap()
}

async fn post_json(http: &reqwest::Client, url: String, body: Value) -> (u16, Value, Option<u64>) {
    let r = http.post(url).json(&body).send().await.unwrap();
    let status = r.status().as_u16();
    let retry = r
        .headers()
        .get("retry-after")
        .map(|v| v.to_str().unwrap().parse().unwrap());
    let text = r.text().await.unwrap();
    let v = serde_json::from_str(&text).unwrap_or_else(|_| panic!("non-JSON {status}: {text}"));
    (status, v, retry)
}

/// Issue 13 item 3: 70 rapid anonymous creations from one client (127.0.0.1) get its burst
/// (10) and then 429 with Retry-After; a second client (127.0.0.2, its own bucket) still gets
/// a session at once. Then the per-client cap of live sessions, and the same through a
/// trusted proxy's X-Forwarded-For.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flood_from_one_client_does_not_block_another() {
    let s = start().await;
    let a = http_from(IpAddr::V4(Ipv4Addr::LOCALHOST));
    let b = http_from(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 2)));
    let url = format!("{}/api/sessions", s.base);
    let mut created = 0;
    let mut limited = 0;
    for _ in 0..70 {
        let (st, v, retry) = post_json(&a, url.clone(), json!({})).await;
        match st {
            201 => created += 1,
            429 => {
                limited += 1;
                assert!(
                    v["error"]
                        .as_str()
                        .unwrap()
                        .contains("too many new sessions")
                );
                assert!(retry.unwrap() >= 1, "Retry-After");
            }
            other => panic!("unexpected {other}: {v}"),
        }
    }
    assert_eq!(created, 10, "the default burst");
    assert_eq!(limited, 60);
    let (st, v, _) = post_json(&b, url.clone(), json!({"label": "second client"})).await;
    assert_eq!(st, 201, "{v}");
    // The instructor token is not limited.
    for _ in 0..3 {
        let r = a
            .post(&url)
            .bearer_auth(TEACHER)
            .json(&json!({}))
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 201);
    }
    s.stop().await;

    // Per-client cap of live sessions (rate limit out of the way), through a trusted proxy:
    // the proxy's own address is shared, X-Forwarded-For tells the clients apart.
    let s = start_with(temp_dir("admission"), |c| {
        c.session_burst = 1000;
        c.max_sessions_per_client = 3;
        c.trusted_proxies = vec![Ipv4Addr::LOCALHOST.into()];
    })
    .await;
    let via = |client: &'static str| {
        a.post(format!("{}/api/sessions", s.base))
            .header("x-forwarded-for", client)
            .json(&json!({}))
            .send()
    };
    for _ in 0..3 {
        assert_eq!(via("198.51.100.7").await.unwrap().status().as_u16(), 201);
    }
    let r = via("198.51.100.7").await.unwrap();
    assert_eq!(r.status().as_u16(), 429);
    let v: Value = r.json().await.unwrap();
    assert!(
        v["error"].as_str().unwrap().contains("live sessions"),
        "{v}"
    );
    assert_eq!(via("198.51.100.8").await.unwrap().status().as_u16(), 201);
    s.stop().await;
}

/// The class join code: missing or wrong (a trailing space included) → 403 JSON; the field
/// or the header → 201; the instructor token needs none.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_join_code_is_enforced() {
    let s = start_with(temp_dir("admission"), |c| {
        c.join_code = Some("tide-42".into())
    })
    .await;
    let http = reqwest::Client::new();
    let url = format!("{}/api/sessions", s.base);
    for body in [
        json!({}),
        json!({"join_code": "tide-41"}),
        json!({"join_code": "tide-42 "}),
        json!({"join_code": "TIDE-42"}),
    ] {
        let (st, v, _) = post_json(&http, url.clone(), body.clone()).await;
        assert_eq!(st, 403, "{body} → {v}");
        assert!(v["error"].as_str().unwrap().contains("join code"), "{v}");
    }
    let (st, v, _) = post_json(&http, url.clone(), json!({"join_code": "tide-42"})).await;
    assert_eq!(st, 201, "{v}");
    let r = http
        .post(&url)
        .header("x-join-code", "tide-42")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 201);
    let r = http
        .post(&url)
        .bearer_auth(TEACHER)
        .json(&json!({}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 201);
    s.stop().await;
}

async fn status_of(s: &Server, id: &str) -> Value {
    get_json(&format!("{}/api/sessions/{id}", s.base)).await
}

/// A session no trainee connects to ends after the grace period (1 s here); one a trainee
/// joined stays. The instructor ends any live session (204), then it is gone (404); a
/// trainee cannot end another trainee's session.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unjoined_sessions_end_and_the_instructor_ends_any() {
    let s = start_with(temp_dir("admission"), |c| c.unjoined_grace_secs = 1).await;
    let (_, lonely) = create(&s, json!({})).await;
    let (_, joined) = create(&s, json!({})).await;
    let (lid, jid) = (
        lonely["id"].as_str().unwrap(),
        joined["id"].as_str().unwrap(),
    );
    let jtok = joined["control_token"].as_str().unwrap();
    let mut ws = trainee(&s, jid, jtok).await;
    let deadline = Instant::now() + Duration::from_secs(15);
    loop {
        let v = status_of(&s, lid).await;
        if v["status"] == "ended" {
            assert_eq!(v["end_reason"], "no trainee joined", "{v}");
            break;
        }
        assert!(Instant::now() < deadline, "never ended: {v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    assert_eq!(status_of(&s, jid).await["status"], "live");

    let http = reqwest::Client::new();
    let (_, other) = create(&s, json!({})).await;
    let del = |id: String, tok: &'static str| {
        http.delete(format!("{}/api/sessions/{id}", s.base))
            .bearer_auth(tok)
            .send()
    };
    let other_tok: &'static str = other["control_token"].as_str().unwrap().to_string().leak();
    assert_eq!(
        del(jid.to_string(), other_tok)
            .await
            .unwrap()
            .status()
            .as_u16(),
        403,
        "another trainee's token"
    );
    assert_eq!(
        del(jid.to_string(), TEACHER)
            .await
            .unwrap()
            .status()
            .as_u16(),
        204
    );
    // The trainee is told why, as a typed message, before the close frame.
    let ended = next_of(&mut ws, "ended", Duration::from_secs(5)).await;
    assert_eq!(ended["reason"], "instructor", "{ended}");
    assert_eq!(ended["text"], "ended by instructor", "{ended}");
    assert_eq!(
        close_code(&mut ws).await,
        1000,
        "the trainee's socket closes"
    );
    let r = del(jid.to_string(), TEACHER).await.unwrap();
    assert_eq!(r.status().as_u16(), 404);
    let v: Value = r.json().await.unwrap();
    assert!(v["error"].as_str().unwrap().contains("no live session"));
    // The recorder writes the end asynchronously: poll (bounded).
    let deadline = Instant::now() + Duration::from_secs(10);
    while status_of(&s, jid).await["end_reason"] != "ended by instructor" {
        assert!(Instant::now() < deadline, "{}", status_of(&s, jid).await);
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    s.stop().await;
}

/// `curl -sI /` and friends: every page, module and API answer carries the four headers.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pages_carry_the_security_headers() {
    let s = start().await;
    let http = reqwest::Client::new();
    for path in [
        "/",
        "/instructor",
        "/web/workspace.html",
        "/web/app.js",
        "/static/three/three.module.js",
        "/api/robots",
        "/nowhere",
    ] {
        for head in [false, true] {
            let url = format!("{}{path}", s.base);
            let r = if head {
                http.head(&url)
            } else {
                http.get(&url)
            }
            .send()
            .await
            .unwrap();
            let h = r.headers();
            let get = |k: &str| {
                h.get(k)
                    .unwrap_or_else(|| panic!("{path}: no {k}"))
                    .to_str()
                    .unwrap()
                    .to_string()
            };
            let csp = get("content-security-policy");
            assert!(csp.contains("default-src 'self'"), "{csp}");
            assert!(csp.contains("frame-ancestors 'none'"), "{csp}");
            assert!(!csp.contains("unsafe-inline"), "{csp}");
            assert_eq!(get("x-content-type-options"), "nosniff");
            assert_eq!(get("x-frame-options"), "DENY");
            assert_eq!(get("referrer-policy"), "no-referrer");
        }
    }
    s.stop().await;
}

/// Cross-site requests: a text/plain body is 415; a foreign Origin is 403 for POST, DELETE
/// and the WebSocket upgrade; the served host's own origin and `--allowed-origins` pass;
/// `Origin: null` does not.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn state_changes_need_json_and_an_allowed_origin() {
    let s = start_with(temp_dir("admission"), |c| {
        c.allowed_origins = vec!["https://sim.example.org".into()];
    })
    .await;
    let http = reqwest::Client::new();
    let url = format!("{}/api/sessions", s.base);
    let own = s.base.clone();
    let r = http
        .post(&url)
        .header("content-type", "text/plain")
        .body("{}")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 415);
    let v: Value = r.json().await.unwrap();
    assert!(v["error"].as_str().unwrap().contains("application/json"));
    // A form post (urlencoded) too.
    let r = http
        .post(&url)
        .header("content-type", "application/x-www-form-urlencoded")
        .body("a=1")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 415);
    for (origin, want) in [
        ("http://evil.example", 403),
        ("null", 403),
        ("http://127.0.0.1:1", 403),
        (own.as_str(), 201),
        ("https://sim.example.org", 201),
    ] {
        let r = http
            .post(&url)
            .header("origin", origin)
            .json(&json!({}))
            .send()
            .await
            .unwrap();
        let st = r.status().as_u16();
        let v: Value = r.json().await.unwrap();
        assert_eq!(st, want, "Origin {origin}: {v}");
    }
    let (id, tok) = new_session(&s).await;
    let (id, tok) = (id.as_str(), tok.as_str());
    let q = format!("token={tok}");
    assert_eq!(
        connect_with(&s, id, &q, &[("origin", "http://evil.example")])
            .await
            .err(),
        Some(403)
    );
    let mut ok = connect_with(&s, id, &q, &[("origin", own.as_str())])
        .await
        .unwrap();
    next_of(&mut ok, "hello", Duration::from_secs(5)).await;
    assert!(
        connect_with(&s, id, &q, &[("origin", "https://sim.example.org")])
            .await
            .is_ok()
    );
    let r = http
        .delete(format!("{}/api/sessions/{id}", s.base))
        .bearer_auth(tok)
        .header("origin", "http://evil.example")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 403);
    s.stop().await;
}

/// `ws_url` comes from `--public-url` when set, else from a Host that passes the syntax
/// check and is one the server answers for; a malformed Host is a 400, never echoed. Issue
/// 29 item 7 (DNS rebinding): `Host: evil.example` with a matching Origin created a session
/// whose `ws_url` pointed at evil.example; a loopback server now answers 421 on every route
/// to a Host it was not told (`--allowed-hosts`), with the security headers.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ws_url_comes_from_the_public_url_or_a_checked_host() {
    let s = start().await;
    let http = reqwest::Client::new();
    for (method, path) in [
        ("POST", "/api/sessions"),
        ("GET", "/"),
        ("GET", "/api/sessions"),
        ("GET", "/healthz"),
        ("GET", "/ws/sessions/0123456789abcdef?token=x"),
    ] {
        let r = http
            .request(method.parse().unwrap(), format!("{}{path}", s.base))
            .header("host", "evil.example")
            .header("origin", "http://evil.example")
            .json(&json!({}))
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 421, "{method} {path}");
        assert!(
            r.headers().contains_key("content-security-policy"),
            "{path}"
        );
        let v: Value = r.json().await.unwrap();
        assert!(v["error"].as_str().unwrap().contains("evil.example"), "{v}");
    }
    // the loopback names and the bound address itself are this server
    let port = s.base.rsplit(':').next().unwrap().to_string();
    for host in [format!("localhost:{port}"), format!("127.0.0.1:{port}")] {
        let r = http
            .get(format!("{}/healthz", s.base))
            .header("host", host.as_str())
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 200, "{host}");
    }
    s.stop().await;
    let s = start_with(temp_dir("admission"), |c| {
        c.allowed_hosts = vec!["sim.example.org".into()];
    })
    .await;
    let http = reqwest::Client::new();
    let url = format!("{}/api/sessions", s.base);
    let r = http
        .post(&url)
        .header("host", "evil.example/\"><x")
        .json(&json!({}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 400);
    let v: Value = r.json().await.unwrap();
    assert!(v["error"].as_str().unwrap().contains("Host"), "{v}");
    let r = http
        .post(&url)
        .header("host", "Sim.Example.org:8443")
        .json(&json!({}))
        .send()
        .await
        .unwrap();
    let v: Value = r.json().await.unwrap();
    assert!(
        v["ws_url"]
            .as_str()
            .unwrap()
            .starts_with("ws://sim.example.org:8443/ws/sessions/"),
        "{v}"
    );
    s.stop().await;
    let s = start_with(temp_dir("admission"), |c| {
        c.public_url = Some("https://sim.example.org".into());
    })
    .await;
    let (_, v) = create(&s, json!({})).await;
    assert!(
        v["ws_url"]
            .as_str()
            .unwrap()
            .starts_with("wss://sim.example.org/ws/sessions/"),
        "{v}"
    );
    s.stop().await;
}

/// Every error body is JSON with an `error` message: 404, 405, 413 (on a route that reads raw
/// bytes), axum's own WebSocket and query rejections.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_error_is_json() {
    let s = start().await;
    let (_, c) = create(&s, json!({})).await;
    let id = c["id"].as_str().unwrap();
    let http = reqwest::Client::new();
    let big = format!(r#"{{"label": "{}"}}"#, "x".repeat(70 * 1024));
    let cases = [
        (http.get(format!("{}/api/nothing", s.base)), 404, "no route"),
        (
            http.put(format!("{}/api/robots", s.base)),
            405,
            "not allowed",
        ),
        (
            http.post(format!("{}/api/sessions", s.base))
                .header("content-type", "application/json")
                .body(big),
            413,
            "larger than",
        ),
        (
            http.get(format!("{}/ws/sessions/{id}?token=x", s.base)),
            400,
            "",
        ),
        (
            http.get(format!(
                "{}/api/sessions/{id}/log.csv?token=a&token=b",
                s.base
            )),
            400,
            "",
        ),
    ];
    for (req, status, needle) in cases {
        let r = req.send().await.unwrap();
        let st = r.status().as_u16();
        let ct = r.headers()["content-type"].to_str().unwrap().to_string();
        let text = r.text().await.unwrap();
        assert_eq!(st, status, "{text}");
        assert!(ct.starts_with("application/json"), "{status}: {ct} {text}");
        let v: Value = serde_json::from_str(&text).unwrap();
        let msg = v["error"].as_str().unwrap();
        assert!(!msg.is_empty() && msg.contains(needle), "{msg}");
    }
    s.stop().await;
}

/// Oversize client messages: just over the documented 16 KiB limit, and far over the
/// transport's 64 KiB, both end with a close frame carrying 1009 (RFC 6455 §7.4.1, message
/// too big); the session streams on for a new connection.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn oversize_messages_close_with_1009() {
    let s = start().await;
    let (id, tok) = new_session(&s).await;
    let (id, tok) = (id.as_str(), tok.as_str());
    let q = format!("token={tok}");
    for size in [20 * 1024, 200 * 1024] {
        let mut ws = trainee(&s, id, tok).await;
        let big = json!({"type": "input", "seq": 1, "pad": "x".repeat(size)}).to_string();
        ws.send(Message::Text(big.into())).await.unwrap();
        assert_eq!(close_code(&mut ws).await, 1009, "{size} bytes");
    }
    let mut ws = connect(&s, id, &q).await.unwrap();
    next_of(&mut ws, "state", Duration::from_secs(5)).await;
    s.stop().await;
}

/// `seq` = 2⁵³ + 1 (beyond JavaScript's exact integers) is refused with an error message and
/// changes nothing; the session keeps streaming and a later ordinary seq is echoed.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_seq_beyond_2_53_is_refused_and_the_session_streams_on() {
    let s = start().await;
    let (id, tok) = new_session(&s).await;
    let (id, tok) = (id.as_str(), tok.as_str());
    let mut ws = trainee(&s, id, tok).await;
    let too_big: u64 = (1 << 53) + 1;
    send(&mut ws, json!({"type": "input", "seq": too_big})).await;
    let e = next_of(&mut ws, "error", Duration::from_secs(5)).await;
    assert!(e["message"].as_str().unwrap().contains("seq"), "{e}");
    send(&mut ws, json!({"type": "input", "seq": 7})).await;
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let t0 = first["t"].as_f64().unwrap();
    let later = state_after(&mut ws, t0 + 0.2).await;
    assert_eq!(later["input_seq"], 7, "{}", later["input_seq"]);
    // 2⁵³ − 1 itself is accepted (Number.MAX_SAFE_INTEGER).
    send(&mut ws, json!({"type": "input", "seq": (1u64 << 53) - 1})).await;
    let last = state_after(&mut ws, later["t"].as_f64().unwrap() + 0.2).await;
    assert_eq!(last["input_seq"].as_u64(), Some((1 << 53) - 1));
    s.stop().await;
}

/// Tokens compare exactly: an extra space, another case or a prefix is refused. (Trailing
/// whitespace of a header value is not part of it — HTTP parsers strip it, RFC 9110 §5.5 —
/// so the trailing-space case is checked on the WebSocket's query token.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tokens_compare_exactly() {
    let s = start().await;
    let http = reqwest::Client::new();
    let list = |auth: String| {
        http.get(format!("{}/api/sessions", s.base))
            .header("authorization", auth)
            .send()
    };
    assert_eq!(
        list(format!("Bearer {TEACHER}"))
            .await
            .unwrap()
            .status()
            .as_u16(),
        200
    );
    for bad in [
        format!("Bearer  {TEACHER}"),
        format!("Bearer {TEACHER}\u{a0}"),
        format!("Bearer {}", TEACHER.to_uppercase()),
        format!("Bearer {}", &TEACHER[..TEACHER.len() - 1]),
    ] {
        assert_eq!(
            list(bad.clone()).await.unwrap().status().as_u16(),
            403,
            "{bad:?}"
        );
    }
    let (id, tok) = new_session(&s).await;
    let (id, tok) = (id.as_str(), tok.as_str());
    for query in [
        format!("token={tok}%20"),
        format!("token=%20{tok}"),
        format!("token={TEACHER}%20&role=observer"),
    ] {
        assert_eq!(connect(&s, id, &query).await.err(), Some(403), "{query}");
    }
    assert!(
        connect(&s, id, &format!("token={TEACHER}&role=observer"))
            .await
            .is_ok()
    );
    s.stop().await;
}

/// Status of `GET /api/sessions` with a bearer token, over a plain std socket.
fn list_status(base: &str, token: &str) -> u16 {
    use std::io::{Read, Write};
    let addr = base.trim_start_matches("http://");
    let mut tcp = std::net::TcpStream::connect(addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        tcp,
        "GET /api/sessions HTTP/1.1\r\nHost: {addr}\r\nAuthorization: Bearer {token}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut head = [0u8; 12];
    tcp.read_exact(&mut head).unwrap();
    String::from_utf8_lossy(&head[9..12]).parse().unwrap()
}

/// The real binary: output of one run until it prints its address, then stopped;
/// `probe(base)` runs while it serves.
fn run_binary(args: &[&str], probe: impl FnOnce(&str)) -> (String, String, String) {
    use std::io::{BufRead, BufReader, Read};
    use std::process::{Command, Stdio};
    let dir = temp_dir("admission");
    let mut child = Command::new(env!("CARGO_BIN_EXE_seaarms"))
        .args(["--bind", "127.0.0.1:0", "--data-dir"])
        .arg(&dir)
        .args(args)
        .env_remove("SEAARMS_INSTRUCTOR_TOKEN")
        .env("RUST_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut stdout = String::new();
    let mut base = String::new();
    // Two lines: the address, the dashboard (bounded: the binary prints them at start-up).
    for _ in 0..2 {
        let mut line = String::new();
        if out.read_line(&mut line).unwrap() == 0 {
            break;
        }
        if let Some(rest) = line.trim().strip_prefix("seaarms serving on ") {
            base = rest.to_string();
        }
        stdout.push_str(&line);
    }
    if !base.is_empty() {
        probe(&base);
    }
    child.kill().unwrap();
    child.wait().unwrap();
    out.read_to_string(&mut stdout).unwrap();
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    let _ = std::fs::remove_dir_all(dir);
    (stdout, stderr, base)
}

/// A generated instructor token is printed once, to stderr, never to stdout; a configured
/// one is printed nowhere, `--help` included.
#[test]
fn the_instructor_token_is_printed_only_when_generated_and_only_to_stderr() {
    let mut probed = None;
    let (stdout, stderr, base) = run_binary(&[], |base| {
        probed = Some((list_status(base, "wrong-token"), base.to_string()));
    });
    assert!(base.starts_with("http://127.0.0.1:"), "{stdout}");
    assert_eq!(probed.map(|p| p.0), Some(403));
    let line = stderr
        .lines()
        .find(|l| l.starts_with("instructor token"))
        .unwrap_or_else(|| panic!("no token line in stderr: {stderr}"));
    let token = line.rsplit(": ").next().unwrap();
    assert_eq!(token.len(), 32, "16 random bytes in hex: {line}");
    assert_eq!(stderr.matches(token).count(), 1, "{stderr}");
    assert!(!stdout.contains(token), "{stdout}");

    // The printed token is the one the server uses (a second run: the first is stopped).
    // Configured explicitly here, so it must then not be printed either.
    let mut status = 0;
    let (_, stderr2, _) = run_binary(&["--instructor-token", token], |base| {
        status = list_status(base, token);
    });
    assert_eq!(status, 200);
    assert!(!stderr2.contains(token), "{stderr2}");

    let secret = "operator-secret-7d1f";
    let (stdout, stderr, base) = run_binary(&["--instructor-token", secret], |base| {
        assert_eq!(list_status(base, secret), 200);
    });
    assert!(base.starts_with("http://127.0.0.1:"), "{stdout}");
    assert!(!stdout.contains(secret), "{stdout}");
    assert!(!stderr.contains(secret), "{stderr}");
    assert!(!stderr.contains("instructor token"), "{stderr}");

    // Nor does `--help` show the environment's token or join code (clap would by default).
    let help = std::process::Command::new(env!("CARGO_BIN_EXE_seaarms"))
        .arg("--help")
        .env("SEAARMS_INSTRUCTOR_TOKEN", secret)
        .env("SEAARMS_JOIN_CODE", "class-code-91")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(text.contains("SEAARMS_INSTRUCTOR_TOKEN"), "{text}");
    assert!(
        !text.contains(secret) && !text.contains("class-code-91"),
        "{text}"
    );
}

/// Issue 29 item 6: no token in a URL. `POST /api/signin` with the instructor token sets an
/// `HttpOnly`, `SameSite=Strict` cookie (a digest, not the token) that opens the instructor's
/// routes; a new session's response sets its trainee's cookie, which opens that session's
/// record and no other's.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sign_in_and_session_cookies_stand_in_for_the_token() {
    let s = start().await;
    let http = reqwest::Client::new();
    let signin = format!("{}/api/signin", s.base);
    let r = http
        .post(&signin)
        .json(&json!({"token": "not-it"}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 403);
    assert!(r.headers().get("set-cookie").is_none());
    let r = http
        .post(&signin)
        .json(&json!({"token": TEACHER}))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 204);
    let set = r.headers()["set-cookie"].to_str().unwrap().to_string();
    assert!(
        set.contains("HttpOnly") && set.contains("SameSite=Strict"),
        "{set}"
    );
    assert!(
        !set.contains(TEACHER),
        "the cookie carries the token itself: {set}"
    );
    let instructor = set.split(';').next().unwrap().to_string();
    let get = |path: String, cookie: String| {
        let http = http.clone();
        async move {
            http.get(path)
                .header("cookie", cookie)
                .send()
                .await
                .unwrap()
                .status()
                .as_u16()
        }
    };
    assert_eq!(
        get(format!("{}/api/results.csv", s.base), instructor.clone()).await,
        200
    );
    assert_eq!(
        get(format!("{}/api/sessions", s.base), instructor.clone()).await,
        200
    );
    assert_eq!(
        get(
            format!("{}/api/results.csv", s.base),
            "seaarms_instructor=x".into()
        )
        .await,
        403
    );
    // what a page without a token asks first (the debrief)
    let who = |cookie: String| {
        let http = http.clone();
        let url = format!("{}/api/signin", s.base);
        async move {
            let r = http.get(url).header("cookie", cookie).send().await.unwrap();
            r.json::<Value>().await.unwrap()
        }
    };
    assert_eq!(
        who(instructor.clone()).await,
        json!({"instructor": true, "trainee_sessions": 0})
    );
    assert_eq!(
        who("seaarms_instructor=x".into()).await,
        json!({"instructor": false, "trainee_sessions": 0})
    );

    // a trainee's session cookie opens its own session's record only
    let made = |_: ()| {
        let http = http.clone();
        let url = format!("{}/api/sessions", s.base);
        async move {
            let r = http.post(url).json(&json!({})).send().await.unwrap();
            let cookie = r.headers()["set-cookie"].to_str().unwrap().to_string();
            let v: Value = r.json().await.unwrap();
            (v["id"].as_str().unwrap().to_string(), cookie)
        }
    };
    let (a, cookie_a) = made(()).await;
    let (b, _) = made(()).await;
    assert!(
        cookie_a.starts_with(&format!("seaarms_t_{a}=")),
        "{cookie_a}"
    );
    assert!(cookie_a.contains("HttpOnly") && cookie_a.contains("SameSite=Strict"));
    let ca = cookie_a.split(';').next().unwrap().to_string();
    assert_eq!(
        get(format!("{}/api/sessions/{a}/log.csv", s.base), ca.clone()).await,
        200
    );
    assert_eq!(
        get(format!("{}/api/sessions/{b}/log.csv", s.base), ca.clone()).await,
        403
    );
    assert_eq!(get(format!("{}/api/results.csv", s.base), ca).await, 403);
    s.stop().await;
}
