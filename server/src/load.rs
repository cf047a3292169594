//! `seaarms load`: opens N trainee sessions that send random stick input at a steady rate,
//! plus M observers, against a running server, for a bounded time; reports frame interval
//! and input-to-state latency percentiles, skipped frames and errors. Only loopback or the
//! URL given is contacted; the run stops by itself after `--seconds`.

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
    /// Frames received in all.
    pub frames: u64,
    /// Frame interval percentiles (ms), all clients.
    pub frame_interval_ms_p50: f64,
    /// 99th percentile.
    pub frame_interval_ms_p99: f64,
    /// Input-to-state latency percentiles (ms), trainees.
    pub latency_ms_p50: f64,
    /// 99th percentile.
    pub latency_ms_p99: f64,
    /// Frames skipped (gaps in frame sequence numbers).
    pub skipped_frames: u64,
    /// Errors (first few listed).
    pub errors: usize,
    /// Up to 10 error messages.
    pub error_samples: Vec<String>,
    /// p99 frame interval ≤ 25 ms, p99 latency ≤ 20 ms and no errors.
    pub meets_target: bool,
}

#[derive(Deserialize)]
struct Created {
    id: String,
    control_token: String,
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
        let resp = http
            .post(format!("{}/api/sessions", args.url))
            .json(&serde_json::json!({"label": format!("load-{i}")}))
            .send()
            .await?;
        if !resp.status().is_success() {
            anyhow::bail!(
                "creating session {i}: {} {}",
                resp.status(),
                resp.text().await.unwrap_or_default()
            );
        }
        created.push(resp.json::<Created>().await?);
    }
    let deadline = Instant::now() + Duration::from_secs_f64(args.seconds);
    let mut tasks = Vec::new();
    for (i, c) in created.iter().enumerate() {
        let url = format!(
            "{}/ws/sessions/{}?token={}",
            ws_base(&args.url),
            c.id,
            c.control_token
        );
        tasks.push(tokio::spawn(client(
            url,
            true,
            args.input_hz,
            deadline,
            i as u64 + 1,
        )));
    }
    if args.observers > 0 {
        let token = instructor_token.ok_or_else(|| {
            anyhow::anyhow!("observers need --instructor-token / SEAARMS_INSTRUCTOR_TOKEN")
        })?;
        for k in 0..args.observers {
            let c = &created[k % created.len().max(1)];
            let url = format!(
                "{}/ws/sessions/{}?token={}&role=observer",
                ws_base(&args.url),
                c.id,
                token
            );
            tasks.push(tokio::spawn(client(url, false, 0.0, deadline, 0)));
        }
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
    for c in &created {
        let _ = http
            .delete(format!("{}/api/sessions/{}", args.url, c.id))
            .bearer_auth(&c.control_token)
            .send()
            .await;
    }
    let fi50 = percentile(&mut all.frame_intervals_ms, 0.5);
    let fi99 = percentile(&mut all.frame_intervals_ms, 0.99);
    let l50 = percentile(&mut all.latencies_ms, 0.5);
    let l99 = percentile(&mut all.latencies_ms, 0.99);
    Ok(LoadReport {
        sessions: args.sessions,
        observers: args.observers,
        seconds: args.seconds,
        frames: all.frames,
        frame_interval_ms_p50: fi50,
        frame_interval_ms_p99: fi99,
        latency_ms_p50: l50,
        latency_ms_p99: l99,
        skipped_frames: all.skipped,
        errors: all.errors.len(),
        error_samples: all.errors.iter().take(10).cloned().collect(),
        meets_target: fi99 <= 25.0 && (args.sessions == 0 || l99 <= 20.0) && all.errors.is_empty(),
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
