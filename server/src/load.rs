//! `seaarms load`: opens N trainee sessions that send random stick input at a steady rate,
//! plus M observers, against a running server, for a bounded time; reports frame interval
//! and input-to-state latency percentiles, skipped frames and errors. With
//! `--heavy-clients K`, K more clients meanwhile send the heaviest requests the limits accept
//! ([`heavy_requests`]) back to back, and the report adds how they were answered and the
//! server's step overruns during the run (from `/metrics`). Only loopback or the URL given is
//! contacted; the run stops by itself after `--seconds`.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde::{Deserialize, Serialize};
use tokio_tungstenite::tungstenite::Message;

/// Arguments of `seaarms load`.
#[derive(Debug, Clone, clap::Args)]
pub struct LoadArgs {
    /// Server base URL.
    #[arg(long, default_value = "http://127.0.0.1:8080")]
    pub url: String,
    /// Trainee sessions.
    #[arg(long, default_value_t = 10)]
    pub sessions: usize,
    /// Observers (spread over the sessions; need the instructor token).
    #[arg(long, default_value_t = 0)]
    pub observers: usize,
    /// Duration of the measurement (s).
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Stick messages per second per trainee.
    #[arg(long, default_value_t = 50.0)]
    pub input_hz: f64,
    /// Clients sending the heaviest accepted compute requests back to back meanwhile.
    #[arg(long, default_value_t = 0)]
    pub heavy_clients: usize,
}

/// What one client measured.
#[derive(Debug, Default)]
struct ClientStats {
    frame_intervals_ms: Vec<f64>,
    latencies_ms: Vec<f64>,
    frames: u64,
    skipped: u64,
    errors: Vec<String>,
}

/// The report printed as JSON.
#[derive(Debug, Serialize)]
pub struct LoadReport {
    /// Trainee sessions.
    pub sessions: usize,
    /// Observers.
    pub observers: usize,
    /// Measurement time (s).
    pub seconds: f64,
    /// What the clients saw of the frames (all clients; latencies: trainees).
    #[serde(flatten)]
    pub figures: FrameFigures,
    /// Errors (first few listed).
    pub errors: usize,
    /// Up to 10 error messages.
    pub error_samples: Vec<String>,
    /// Simulation steps the server dropped to stay real time during the run (`/metrics`).
    pub step_overruns: u64,
    /// How the heavy requests were answered (all zero without `--heavy-clients`).
    pub heavy: HeavyStats,
    /// p99 frame interval ≤ 25 ms, p99 latency ≤ 20 ms, no errors and no step overruns.
    pub meets_target: bool,
}

/// Answers to the heavy clients' requests.
#[derive(Debug, Default, Clone, Serialize)]
pub struct HeavyStats {
    /// Heavy clients.
    pub clients: usize,
    /// Requests sent.
    pub sent: u64,
    /// Answered 2xx.
    pub ok: u64,
    /// Answered 4xx (an unreachable posture target is a 422).
    pub client_errors: u64,
    /// Refused with 503 (compute queue full).
    pub busy_503: u64,
    /// Answered 504 (past the deadline).
    pub deadline_504: u64,
    /// Other statuses and transport errors.
    pub failed: u64,
    /// Bytes of answer received.
    pub bytes: u64,
    /// Slowest answer (s).
    pub max_seconds: f64,
    /// Slowest answer other than a 503 (s), by request name.
    pub slowest_seconds: std::collections::BTreeMap<&'static str, f64>,
}

impl HeavyStats {
    fn add(&mut self, o: &HeavyStats) {
        self.sent += o.sent;
        self.ok += o.ok;
        self.client_errors += o.client_errors;
        self.busy_503 += o.busy_503;
        self.deadline_504 += o.deadline_504;
        self.failed += o.failed;
        self.bytes += o.bytes;
        self.max_seconds = self.max_seconds.max(o.max_seconds);
        for (name, s) in &o.slowest_seconds {
            let e = self.slowest_seconds.entry(name).or_default();
            *e = e.max(*s);
        }
    }
}

/// One heavy request: what it is, the path, and the JSON body (`None`: no body).
#[derive(Debug, Clone)]
pub struct HeavyRequest {
    /// Short name for reports.
    pub name: &'static str,
    /// Path below the base URL (POST).
    pub path: &'static str,
    /// JSON body.
    pub body: Option<serde_json::Value>,
}

/// An n-joint spatial chain (alternating ±90° twists, 0.05 m links, limits ±3 rad) as an
/// inline model: the largest arm the core accepts has [`seaarms_core::model::MAX_JOINTS`].
pub fn chain_robot(n: usize) -> serde_json::Value {
    let joints: Vec<serde_json::Value> = (0..n)
        .map(|i| {
            let twist = if i % 2 == 0 { 1.0 } else { -1.0 } * std::f64::consts::FRAC_PI_2;
            serde_json::json!({"type": "revolute", "a": 0.05, "alpha": twist, "d": 0.05,
                               "limits": [-3.0, 3.0], "max_velocity": 1.0 + 0.01 * i as f64})
        })
        .collect();
    serde_json::json!({"name": format!("chain{n}"), "dh": "standard", "joints": joints})
}

/// The heaviest request of each compute route that the limits of [`crate::limits`] accept
/// (release build, 2-core machine: each well under 2 s of one core).
pub fn heavy_requests() -> Vec<HeavyRequest> {
    use crate::limits::{MAX_MAP_CELLS, MAX_POSTURE_START_JOINTS, MAX_STUDY_SERIES};
    use serde_json::json;
    let n = seaarms_core::model::MAX_JOINTS;
    let q = |sign: f64| -> Vec<f64> {
        (0..n)
            .map(|i| sign * (0.3 * ((i % 3) as f64 - 1.0) + 0.1))
            .collect()
    };
    let side = (MAX_MAP_CELLS as f64).sqrt().floor() as usize;
    // dual-pitch-yaw: every row is computed (no boundary stop); 64 points × 2 × 156 angles.
    let points: Vec<_> = (0..MAX_STUDY_SERIES)
        .map(|i| json!({"name": format!("P{i}"), "position": [0.9 + 0.01 * i as f64, 0.0, 0.2]}))
        .collect();
    vec![
        HeavyRequest {
            name: "dual analysis, 2 × 32 joints, polytope",
            path: "/api/analysis/dual",
            body: Some(json!({"arms": [
                {"robot": chain_robot(n), "q": q(1.0)},
                {"robot": chain_robot(n), "q": q(-1.0), "base": {"position": [0.0, 0.5, 0.0]}}
            ], "polytope": true})),
        },
        HeavyRequest {
            name: "analysis, 32 joints, polytope",
            path: "/api/analysis",
            body: Some(json!({"robot": chain_robot(n), "q": q(1.0), "polytope": true})),
        },
        HeavyRequest {
            name: "workspace map at the cell limit, free orientation, inside the reach",
            path: "/api/studies/workspace-map",
            body: Some(
                json!({"robot": "pa10", "orientation": "free", "nx": side, "nz": side,
                              "x_range": [-0.6, 0.6], "z_range": [-0.6, 0.6], "y": 0.6}),
            ),
        },
        HeavyRequest {
            name: "optimal posture, starts × joints at the limit, unreachable target",
            path: "/api/optimal-posture",
            body: Some(
                json!({"robot": chain_robot(n), "target_position": [3.0, 0.3, 0.2],
                              "alpha": 0.8, "starts": MAX_POSTURE_START_JOINTS / n}),
            ),
        },
        HeavyRequest {
            name: "dual pitch/yaw study at the row limit",
            path: "/api/studies/dual-pitch-yaw",
            body: Some(
                json!({"points": points, "pitch_deg": [0.0, 155.0], "yaw_deg": [0.0, 155.0], "step_deg": 1.0}),
            ),
        },
        HeavyRequest {
            name: "scenario run, case 4",
            path: "/api/scenarios/case4-dual-closed-loop/run",
            body: None,
        },
    ]
}

/// `seaarms_step_overruns_total` from the server's `/metrics`.
async fn step_overruns(http: &reqwest::Client, url: &str) -> anyhow::Result<u64> {
    let text = http
        .get(format!("{url}/metrics"))
        .send()
        .await?
        .text()
        .await?;
    text.lines()
        .find_map(|l| l.strip_prefix("seaarms_step_overruns_total "))
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| anyhow::anyhow!("no seaarms_step_overruns_total in /metrics"))
}

/// Sends the heavy requests (starting at `first`) back to back until `deadline`; after a 503
/// it pauses 100 ms (not the `Retry-After`: the point is to keep the queue full).
async fn heavy_client(
    http: reqwest::Client,
    url: String,
    requests: std::sync::Arc<Vec<HeavyRequest>>,
    first: usize,
    deadline: Instant,
) -> HeavyStats {
    let mut stats = HeavyStats::default();
    let mut i = first;
    while Instant::now() < deadline {
        let r = &requests[i % requests.len()];
        i += 1;
        let mut req = http.post(format!("{url}{}", r.path));
        if let Some(body) = &r.body {
            req = req.json(body);
        }
        let t0 = Instant::now();
        stats.sent += 1;
        let status = match req.send().await {
            Ok(resp) => {
                let status = resp.status().as_u16();
                match resp.bytes().await {
                    Ok(b) => {
                        stats.bytes += b.len() as u64;
                        status
                    }
                    Err(_) => 0,
                }
            }
            Err(_) => 0,
        };
        let seconds = t0.elapsed().as_secs_f64();
        stats.max_seconds = stats.max_seconds.max(seconds);
        if status != 503 {
            let e = stats.slowest_seconds.entry(r.name).or_default();
            *e = e.max(seconds);
        }
        match status {
            200..=299 => stats.ok += 1,
            503 => {
                stats.busy_503 += 1;
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
            504 => stats.deadline_504 += 1,
            400..=499 => stats.client_errors += 1,
            _ => stats.failed += 1,
        }
    }
    stats
}

#[derive(Deserialize)]
struct Created {
    id: String,
    control_token: String,
    /// Path prefix of the session's URLs (`/r/<replica>` behind a proxy of replicas).
    #[serde(default)]
    base: String,
}

#[derive(Deserialize)]
struct FrameHead {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    seq: u64,
    #[serde(default)]
    input_seq: u64,
    #[serde(default)]
    message: Option<String>,
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let i = ((v.len() - 1) as f64 * p).round() as usize;
    v[i.min(v.len() - 1)]
}

fn ws_base(url: &str) -> String {
    url.replacen("http://", "ws://", 1)
        .replacen("https://", "wss://", 1)
}

/// Runs the load test.
pub async fn run(args: LoadArgs, instructor_token: Option<String>) -> anyhow::Result<LoadReport> {
    let http = reqwest::Client::new();
    let mut created = Vec::new();
    for i in 0..args.sessions {
        // The instructor token lifts the per-client creation limits (one client opens them all).
        let mut req = http
            .post(format!("{}/api/sessions", args.url))
            .json(&serde_json::json!({"label": format!("load-{i}")}));
        if let Some(token) = &instructor_token {
            req = req.bearer_auth(token);
        }
        let resp = req.send().await?;
        if !resp.status().is_success() {
            anyhow::bail!(
                "creating session {i}: {} {}",
                resp.status(),
                resp.text().await.unwrap_or_default()
            );
        }
        created.push(resp.json::<Created>().await?);
    }
    let overruns_before = step_overruns(&http, &args.url).await?;
    let deadline = Instant::now() + Duration::from_secs_f64(args.seconds);
    let requests = std::sync::Arc::new(heavy_requests());
    let heavy_tasks: Vec<_> = (0..args.heavy_clients)
        .map(|k| {
            tokio::spawn(heavy_client(
                http.clone(),
                args.url.clone(),
                requests.clone(),
                k,
                deadline,
            ))
        })
        .collect();
    let trainees: Vec<String> = created
        .iter()
        .map(|c| {
            format!(
                "{}{}/ws/sessions/{}?token={}",
                ws_base(&args.url),
                c.base,
                c.id,
                c.control_token
            )
        })
        .collect();
    let mut observers = Vec::new();
    if args.observers > 0 {
        let token = instructor_token.ok_or_else(|| {
            anyhow::anyhow!("observers need --instructor-token / SEAARMS_INSTRUCTOR_TOKEN")
        })?;
        for k in 0..args.observers {
            let c = &created[k % created.len().max(1)];
            observers.push(format!(
                "{}{}/ws/sessions/{}?token={}&role=observer",
                ws_base(&args.url),
                c.base,
                c.id,
                token
            ));
        }
    }
    let all = measure(&trainees, &observers, args.input_hz, deadline).await?;
    let mut heavy = HeavyStats {
        clients: args.heavy_clients,
        ..HeavyStats::default()
    };
    for t in heavy_tasks {
        heavy.add(&t.await?);
    }
    let overruns = step_overruns(&http, &args.url)
        .await?
        .saturating_sub(overruns_before);
    for c in &created {
        let _ = http
            .delete(format!("{}{}/api/sessions/{}", args.url, c.base, c.id))
            .bearer_auth(&c.control_token)
            .send()
            .await;
    }
    Ok(LoadReport {
        sessions: args.sessions,
        observers: args.observers,
        seconds: args.seconds,
        errors: all.errors.len(),
        error_samples: all.errors.iter().take(10).cloned().collect(),
        step_overruns: overruns,
        heavy,
        meets_target: all.frame_interval_ms_p99 <= 25.0
            && (args.sessions == 0 || all.latency_ms_p99 <= 20.0)
            && all.errors.is_empty()
            && overruns == 0,
        figures: all,
    })
}

/// What WebSocket clients saw of the state frames: the figures `seaarms load` reports.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FrameFigures {
    /// State frames received.
    pub frames: u64,
    /// Median interval between a client's frames (ms).
    pub frame_interval_ms_p50: f64,
    /// 99th percentile of the interval between a client's frames (ms).
    pub frame_interval_ms_p99: f64,
    /// Median time from an input sent to the first frame that applied it (ms).
    pub latency_ms_p50: f64,
    /// 99th percentile of that latency (ms).
    pub latency_ms_p99: f64,
    /// Frames a client skipped (latest state wins).
    pub skipped_frames: u64,
    /// What went wrong (connects, receives, server errors, closes); the report counts them.
    #[serde(skip)]
    pub errors: Vec<String>,
}

/// Connects every `trainees` URL (a trainee sending random sticks at `input_hz`) and every
/// `observers` URL (read-only) until `deadline`, and measures their frames: the one frame
/// measurement of `seaarms load`, also used by the multi-replica test (`tests/cluster.rs`).
pub async fn measure(
    trainees: &[String],
    observers: &[String],
    input_hz: f64,
    deadline: Instant,
) -> anyhow::Result<FrameFigures> {
    let mut tasks = Vec::new();
    for (i, url) in trainees.iter().enumerate() {
        tasks.push(tokio::spawn(client(
            url.clone(),
            true,
            input_hz,
            deadline,
            i as u64 + 1,
        )));
    }
    for url in observers {
        tasks.push(tokio::spawn(client(url.clone(), false, 0.0, deadline, 0)));
    }
    let mut all = ClientStats::default();
    for t in tasks {
        let s = t.await?;
        all.frame_intervals_ms.extend(s.frame_intervals_ms);
        all.latencies_ms.extend(s.latencies_ms);
        all.frames += s.frames;
        all.skipped += s.skipped;
        all.errors.extend(s.errors);
    }
    Ok(FrameFigures {
        frames: all.frames,
        frame_interval_ms_p50: percentile(&mut all.frame_intervals_ms, 0.5),
        frame_interval_ms_p99: percentile(&mut all.frame_intervals_ms, 0.99),
        latency_ms_p50: percentile(&mut all.latencies_ms, 0.5),
        latency_ms_p99: percentile(&mut all.latencies_ms, 0.99),
        skipped_frames: all.skipped,
        errors: all.errors,
    })
}

async fn client(
    url: String,
    trainee: bool,
    input_hz: f64,
    deadline: Instant,
    seed: u64,
) -> ClientStats {
    let mut stats = ClientStats::default();
    // State frames are a few KiB: a 16 KiB read buffer instead of tungstenite's 128 KiB one
    // (re-zeroed on reads) keeps the load client's own CPU use down on a shared machine.
    let config = tokio_tungstenite::tungstenite::protocol::WebSocketConfig::default()
        .read_buffer_size(16 * 1024);
    let (ws, _) = match tokio_tungstenite::connect_async_with_config(&url, Some(config), true).await
    {
        Ok(c) => c,
        Err(e) => {
            stats.errors.push(format!("connect: {e}"));
            return stats;
        }
    };
    let (mut tx, mut rx) = ws.split();
    let mut rng = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next_rand = move || {
        // xorshift64*: deterministic per client.
        rng ^= rng >> 12;
        rng ^= rng << 25;
        rng ^= rng >> 27;
        (rng.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let period = if input_hz > 0.0 {
        Duration::from_secs_f64(1.0 / input_hz)
    } else {
        Duration::from_secs(3600)
    };
    let mut ticker = tokio::time::interval(period);
    let mut seq = 0u64;
    let mut pending: VecDeque<(u64, Instant)> = VecDeque::new();
    let mut last_frame: Option<(u64, Instant)> = None;
    let sleep = tokio::time::sleep_until(deadline.into());
    tokio::pin!(sleep);
    loop {
        tokio::select! {
            _ = &mut sleep => break,
            _ = ticker.tick(), if trainee => {
                seq += 1;
                let axes: Vec<f64> = (0..6).map(|_| (next_rand() * 0.5 * 100.0).round() / 100.0).collect();
                let msg = serde_json::json!({"type": "input", "seq": seq, "arms": {"left": {"axes": axes, "grip": 0.0}, "right": {"axes": axes, "grip": 0.0}}});
                pending.push_back((seq, Instant::now()));
                if pending.len() > 10_000 {
                    pending.pop_front();
                }
                if let Err(e) = tx.send(Message::Text(msg.to_string().into())).await {
                    stats.errors.push(format!("send: {e}"));
                    break;
                }
            }
            msg = rx.next() => {
                let now = Instant::now();
                match msg {
                    Some(Ok(Message::Text(t))) => {
                        let Ok(head) = serde_json::from_str::<FrameHead>(&t) else {
                            stats.errors.push("unparsable server message".into());
                            continue;
                        };
                        match head.kind.as_str() {
                            "state" => {
                                stats.frames += 1;
                                if let Some((prev_seq, prev_t)) = last_frame {
                                    stats.frame_intervals_ms.push(now.duration_since(prev_t).as_secs_f64() * 1e3);
                                    if head.seq > prev_seq + 1 {
                                        stats.skipped += head.seq - prev_seq - 1;
                                    }
                                }
                                last_frame = Some((head.seq, now));
                                while let Some(&(s, sent)) = pending.front() {
                                    if s > head.input_seq {
                                        break;
                                    }
                                    stats.latencies_ms.push(now.duration_since(sent).as_secs_f64() * 1e3);
                                    pending.pop_front();
                                }
                            }
                            "error" => stats.errors.push(format!("server: {}", head.message.unwrap_or_default())),
                            _ => {}
                        }
                    }
                    Some(Ok(Message::Close(f))) => {
                        stats.errors.push(format!("closed by server: {f:?}"));
                        break;
                    }
                    Some(Ok(_)) => {}
                    Some(Err(e)) => {
                        stats.errors.push(format!("receive: {e}"));
                        break;
                    }
                    None => break,
                }
            }
        }
    }
    let _ = tx.send(Message::Close(None)).await;
    stats
}
