//! Ghost tracks (issue 30 item 5): an attempt's poses sampled at [`TRACK_HZ`], for drawing it
//! as a see-through "ghost" beside a live attempt or a debrief, time-aligned to their clock.
//!
//! * **What**: the attempt re-simulated from its record ([`Replay`], so each sample is the
//!   recorded state bit for bit before rounding) and, every [`TRACK_STEP`] steps and at its
//!   last step, the frame's ([`Replay::frame`], the live pages' [`StateFrame`]) time, each
//!   arm's joint angles, jaw opening, joint frames and tool pose (what the page's `Arm.update`
//!   draws), and the box's pose. Nothing else: no pressures, measures, names or events.
//! * **Rounding**: lengths and positions to [`POSITION_QUANTUM_M`] (0.1 mm), angles (rad) and
//!   rotation-matrix entries to [`VALUE_QUANTUM`] (1e-4), times to 1 ms — invisible at any
//!   zoom the pages allow, and about 1.46 kB of JSON per sample (1.76 MB for a 120 s
//!   attempt, measured in `tests/ghosts.rs`).
//! * **Poses** on the wire: 12 numbers, `[x, y, z, r00, r01, r02, r10, r11, r12, r20, r21,
//!   r22]` (position m, world; row-major rotation), the frame's `PoseOut` flattened.
//! * **Cache**: [`TrackCache`] keeps the JSON of ended attempts (their record never changes),
//!   bounded by [`MAX_TRACK_BYTES`], least recently used out first.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard};

use serde::Serialize;

use super::{Replay, ReplayError};
use crate::protocol::{ArmFrame, PoseOut, StateFrame};

/// Samples per simulated second.
pub const TRACK_HZ: f64 = 10.0;
/// Steps between samples (1 ms steps, [`TRACK_HZ`]).
pub const TRACK_STEP: u64 = 100;
/// Rounding of positions and lengths (m): 0.1 mm.
pub const POSITION_QUANTUM_M: f64 = 1e-4;
/// Rounding of joint angles (rad) and rotation-matrix entries.
pub const VALUE_QUANTUM: f64 = 1e-4;
/// Most bytes of track JSON the server keeps ([`TrackCache`]): 64 MB, about 37 tracks of
/// 120 s attempts.
pub const MAX_TRACK_BYTES: usize = 64 << 20;

/// An attempt's track.
#[derive(Debug, Clone, Serialize)]
pub struct Track {
    /// The attempt's id.
    pub attempt: String,
    /// Its length (s).
    pub duration_s: f64,
    /// Samples per second ([`TRACK_HZ`]; the last sample is at `duration_s`).
    pub hz: f64,
    /// The samples, in time order.
    pub samples: Vec<Sample>,
}

/// The poses at one time.
#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    /// Simulated time since the attempt's start (s).
    pub t: f64,
    /// Left and right arm.
    pub arms: [ArmSample; 2],
    /// The box's pose (12 numbers, see the module docs).
    pub object: [f64; 12],
}

/// One arm at one time.
#[derive(Debug, Clone, Serialize)]
pub struct ArmSample {
    /// Joint angles (rad).
    pub q: [f64; 6],
    /// Jaw opening (m).
    pub jaw_opening_m: f64,
    /// Joint frames after their motion, world (12 numbers each).
    pub joint_frames: Vec<[f64; 12]>,
    /// Tool pose, world (12 numbers).
    pub pose: [f64; 12],
}

/// `x` rounded to a multiple of `quantum` (a power of ten), the nearest double to that
/// decimal, so that the JSON stays short.
fn round(x: f64, quantum: f64) -> f64 {
    let per = (1.0 / quantum).round();
    (x * per).round() / per
}

fn pose(p: &PoseOut) -> [f64; 12] {
    let mut out = [0.0; 12];
    for i in 0..3 {
        out[i] = round(p.position[i], POSITION_QUANTUM_M);
        for j in 0..3 {
            out[3 + 3 * i + j] = round(p.rotation[i][j], VALUE_QUANTUM);
        }
    }
    out
}

fn arm(a: &ArmFrame) -> ArmSample {
    ArmSample {
        q: a.q.map(|q| round(q, VALUE_QUANTUM)),
        jaw_opening_m: round(a.jaw_opening_m, POSITION_QUANTUM_M),
        joint_frames: a.joint_frames.iter().map(pose).collect(),
        pose: pose(&a.pose),
    }
}

/// A frame's sample (rounded).
pub fn sample(f: &StateFrame) -> Sample {
    Sample {
        t: round(f.t, 1e-3),
        arms: [arm(&f.arms.left), arm(&f.arms.right)],
        object: pose(&f.object.pose),
    }
}

/// Re-simulates `replay` (from its current step back to the start if needed) over the whole
/// attempt and samples it; asks `keep_going` every simulated second
/// ([`Replay::seek_step_checked`]).
pub fn build(
    replay: &mut Replay,
    attempt: &str,
    keep_going: &dyn Fn() -> bool,
) -> Result<Track, ReplayError> {
    let end = Replay::step_at(replay.duration_s());
    let mut samples = Vec::with_capacity((end / TRACK_STEP) as usize + 2);
    let mut k = 0;
    loop {
        replay.seek_step_checked(k, keep_going)?;
        samples.push(sample(&replay.frame()));
        if k >= end {
            break;
        }
        k = (k + TRACK_STEP).min(end);
    }
    Ok(Track {
        attempt: attempt.to_string(),
        duration_s: replay.duration_s(),
        hz: TRACK_HZ,
        samples,
    })
}

/// One cached track's JSON and when it was last used.
struct Slot {
    json: Arc<str>,
    used: u64,
}

#[derive(Default)]
struct Inner {
    by_attempt: HashMap<String, Slot>,
    bytes: usize,
    tick: u64,
}

/// The ended attempts' track JSON, bounded by bytes ([`MAX_TRACK_BYTES`] by default), the least
/// recently used evicted first.
pub struct TrackCache {
    inner: Mutex<Inner>,
    max_bytes: usize,
}

impl Default for TrackCache {
    fn default() -> TrackCache {
        TrackCache::new(MAX_TRACK_BYTES)
    }
}

impl TrackCache {
    /// An empty cache keeping at most `max_bytes` of JSON.
    pub fn new(max_bytes: usize) -> TrackCache {
        TrackCache {
            inner: Mutex::new(Inner::default()),
            max_bytes,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The track of `attempt`, if kept (marked used).
    pub fn get(&self, attempt: &str) -> Option<Arc<str>> {
        let mut inner = self.lock();
        inner.tick += 1;
        let tick = inner.tick;
        inner.by_attempt.get_mut(attempt).map(|s| {
            s.used = tick;
            s.json.clone()
        })
    }

    /// Keeps `json` as `attempt`'s track, evicting the least recently used beyond the bound
    /// (a track larger than the whole bound is not kept).
    pub fn insert(&self, attempt: &str, json: Arc<str>) {
        if json.len() > self.max_bytes {
            return;
        }
        let mut inner = self.lock();
        inner.tick += 1;
        let used = inner.tick;
        let len = json.len();
        if let Some(old) = inner
            .by_attempt
            .insert(attempt.to_string(), Slot { json, used })
        {
            inner.bytes -= old.json.len();
        }
        inner.bytes += len;
        while inner.bytes > self.max_bytes {
            let Some(oldest) = inner
                .by_attempt
                .iter()
                .min_by_key(|(_, s)| s.used)
                .map(|(k, _)| k.clone())
            else {
                break;
            };
            if let Some(s) = inner.by_attempt.remove(&oldest) {
                inner.bytes -= s.json.len();
            }
        }
    }

    /// Tracks kept and their bytes.
    pub fn usage(&self) -> (usize, usize) {
        let inner = self.lock();
        (inner.by_attempt.len(), inner.bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_gives_the_nearest_short_decimal() {
        assert_eq!(round(0.123_456, POSITION_QUANTUM_M), 0.1235);
        assert_eq!(round(-1.000_04, VALUE_QUANTUM), -1.0);
        assert_eq!(round(0.1235, 1e-4).to_string(), "0.1235");
    }

    #[test]
    fn cache_evicts_the_least_recently_used_beyond_its_bytes() {
        let c = TrackCache::new(10);
        c.insert("a", Arc::from("aaaa"));
        c.insert("b", Arc::from("bbbb"));
        assert!(c.get("a").is_some()); // a used after b
        c.insert("c", Arc::from("cccc")); // 12 > 10: b goes
        assert!(c.get("b").is_none());
        assert_eq!(c.usage(), (2, 8));
        c.insert("d", Arc::from("x".repeat(11)));
        assert_eq!(c.usage(), (2, 8), "larger than the bound: not kept");
    }
}
