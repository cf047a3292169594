//! A replay seek on a warm attempt (issue 29 item 2: "≤ 50 ms per seek on this machine, at
//! any t of a 2-hour attempt"): a synthetic free-play attempt (`replay::synthetic`, the
//! arms moving and pressed into the seabed) of `SEAARMS_BENCH_ATTEMPT_S` simulated seconds
//! (default 7200, two hours; recording it and warming the cache take about 13 ms per
//! simulated second each, ~3 min for two hours), its checkpoints deposited by one replay to
//! its end, then:
//!
//! * `rest_seek_worst`: what `GET /api/attempts/{id}/replay?t=` does — a new replay of the
//!   attempt sharing the cache, a seek to the step just before a checkpoint near the end (the
//!   longest re-simulation, one whole interval), and the frame;
//! * `socket_seek_random`: a replay socket's seek from where it is to a random time, and the
//!   frame (the mean is about half an interval).

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use seaarms::replay::checkpoints::{CHECKPOINT_INTERVAL_STEPS, CheckpointCache};
use seaarms::replay::{Replay, log, synthetic};

fn bench(c: &mut Criterion) {
    let seconds: u64 = std::env::var("SEAARMS_BENCH_ATTEMPT_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(7200);
    let robots = seaarms::robots::Robots::load().expect("robots");
    let m = robots.get("magnum").expect("magnum");
    let models = [m.clone(), m];
    let attempt = synthetic::free_play(&models, "bench", seconds, &mut |_| {}).expect("attempt");
    let entries = log::decode(&attempt.inputs).expect("log");
    let cache = Arc::new(CheckpointCache::default());
    let replay = || {
        Replay::shared(
            &models,
            attempt.init.clone(),
            entries.clone(),
            attempt.sim_seconds,
            cache.clone(),
            "bench",
        )
        .expect("replay")
    };
    let mut warm = replay();
    warm.seek_step(seconds * 1000).expect("seek");
    let end = seconds * 1000;
    let worst = (end / CHECKPOINT_INTERVAL_STEPS - 1) * CHECKPOINT_INTERVAL_STEPS
        + CHECKPOINT_INTERVAL_STEPS
        - 1;
    let mut g = c.benchmark_group("replay_seek");
    g.sample_size(20);
    g.bench_function("rest_seek_worst", |b| {
        b.iter(|| {
            let mut r = replay();
            r.seek_step(black_box(worst)).expect("seek");
            black_box(r.frame());
        })
    });
    let mut r = replay();
    let mut x: u64 = 29;
    g.bench_function("socket_seek_random", |b| {
        b.iter(|| {
            // splitmix64's increment as a cheap sequence over the attempt
            x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
            r.seek_step(black_box((x >> 11) % end)).expect("seek");
            black_box(r.frame());
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
