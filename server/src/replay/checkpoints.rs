//! Replay checkpoints (issue 29 item 2): copies of a replay's state every
//! [`CHECKPOINT_INTERVAL_STEPS`] of simulated time, kept in one bounded in-memory cache that
//! every replay of the server shares (the REST seek and the replay sockets), so that a seek
//! re-simulates at most one interval from the nearest earlier checkpoint instead of the whole
//! attempt from its start.
//!
//! * **Where they come from**:
//!   - a live session deposits its running attempt's state as it passes each interval
//!     ([`CheckpointCache::live_key`]), and at the attempt's end they are filed under the
//!     final log's key ([`CheckpointCache::settle`]): the first seek of a debrief opened after
//!     an attempt already finds them (a copy every 2 s, ~35 KB/s per session);
//!   - a replay that steps past a multiple of the interval deposits the state there (if the
//!     cache has none): an attempt whose checkpoints are gone (evicted, or recorded before the
//!     server started) costs its first seek the re-simulation up to its target (about 13 ms
//!     per simulated second, on the compute pool, cancellable) and fills the cache on the way;
//!     every later seek, by anyone, to any time up to there costs at most one interval. A seek
//!     cancelled half-way keeps what it deposited.
//! * **What a checkpoint is**: [`Live::checkpoint`] (the simulation, operator, exercise run and
//!   clock, records excluded, the session's own parts as a replay has them) and the replay's
//!   position in the input log (`next`, the first entry not yet applied). Restoring clones it
//!   again, so the cached one is never stepped; the step is deterministic and the clone is
//!   deep, so the restored replay continues bit for bit as the uninterrupted one
//!   (`tests/replay.rs`, for replays' and live sessions' checkpoints).
//! * **Keys**: the attempt id and the number of log entries read. An ended attempt's log
//!   never changes; a running attempt's log grows, and a longer log is another key, so a
//!   checkpoint always belongs to exactly the entries it was computed from. A live session's
//!   go under a provisional key until its attempt ends and the log's length is known.
//! * **Memory**: at most [`MAX_CHECKPOINTS`] over all attempts, the least recently used
//!   evicted first; [`CHECKPOINT_BYTES`] each (measured), so about 280 MB at most. With live
//!   sessions depositing, the cache holds the last ~400 s of 20 sessions' attempts (or the
//!   ones replayed since), so a debrief soon after its attempt seeks at once; an older one
//!   pays its first seek as above.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex, MutexGuard};

use crate::sessions::Live;

/// Simulated time between checkpoints: 2 s (2000 steps). A replay re-simulates about 13 ms
/// per simulated second on this project's 2-core test machine (release; 12–18 ms measured over
/// 10 s stretches of a free-play attempt with the arms moving and striking the seabed), so
/// a seek re-simulates at most 2 s ≈ 25–36 ms, under the 50 ms per seek with room for
/// the restore and the frame (`benches/replay_seek.rs`).
pub const CHECKPOINT_INTERVAL_STEPS: u64 = 2000;

/// Approximate memory of one checkpoint (bytes): 70 KB measured (resident memory grown by
/// 1000 copies of a free-play replay's state: the simulation with its two models and contact
/// workspace ~46 KB, the operator, exercise run and measures the rest).
pub const CHECKPOINT_BYTES: usize = 70_000;

/// Most checkpoints kept over all attempts: 4000 ≈ 280 MB ([`CHECKPOINT_BYTES`] each), enough
/// for every 2 s of one 2-hour attempt (3600) and some more; beyond it the least recently
/// used go first.
pub const MAX_CHECKPOINTS: usize = 4000;

/// A replay's state at a step that is a multiple of [`CHECKPOINT_INTERVAL_STEPS`].
pub struct Checkpoint {
    /// The state (records excluded).
    pub live: Live,
    /// The first log entry not yet applied.
    pub next: usize,
}

/// One cached checkpoint and when it was last used.
struct Slot {
    checkpoint: Arc<Checkpoint>,
    used: u64,
}

#[derive(Default)]
struct Inner {
    /// By key, then by step.
    by_key: HashMap<String, BTreeMap<u64, Slot>>,
    /// Use order: tick → (key, step); the first is the least recently used.
    lru: BTreeMap<u64, (String, u64)>,
    /// Increases at every use.
    tick: u64,
}

impl Inner {
    fn touch(&mut self, key: &str, step: u64) {
        self.tick += 1;
        let tick = self.tick;
        if let Some(slot) = self.by_key.get_mut(key).and_then(|m| m.get_mut(&step)) {
            self.lru.remove(&slot.used);
            slot.used = tick;
            self.lru.insert(tick, (key.to_string(), step));
        }
    }

    fn evict_oldest(&mut self) {
        let Some((_, (key, step))) = self.lru.pop_first() else {
            return;
        };
        if let Some(m) = self.by_key.get_mut(&key) {
            m.remove(&step);
            if m.is_empty() {
                self.by_key.remove(&key);
            }
        }
    }
}

/// The bounded checkpoint cache (see the module docs); shared by the server's replays.
pub struct CheckpointCache {
    inner: Mutex<Inner>,
    max: usize,
}

impl CheckpointCache {
    /// An empty cache keeping at most `max` checkpoints.
    pub fn new(max: usize) -> CheckpointCache {
        CheckpointCache {
            inner: Mutex::new(Inner::default()),
            max,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The cache key of an attempt's replay that read `entries` log entries.
    pub fn key(attempt: &str, entries: usize) -> String {
        format!("{attempt}#{entries}")
    }

    /// The provisional key of `attempt`'s checkpoints while a live session runs it (its log
    /// still growing): [`CheckpointCache::settle`] files them under the final key.
    pub fn live_key(attempt: &str) -> String {
        format!("{attempt}#live")
    }

    /// Files the checkpoints a live session deposited for `attempt` under the key of its
    /// finished log of `entries` entries (where its replays look), keeping their use order;
    /// a step that key already has keeps its own.
    pub fn settle(&self, attempt: &str, entries: usize) {
        let from = Self::live_key(attempt);
        let to = Self::key(attempt, entries);
        let mut guard = self.lock();
        let inner = &mut *guard;
        let Some(deposited) = inner.by_key.remove(&from) else {
            return;
        };
        let target = inner.by_key.entry(to.clone()).or_default();
        for (step, slot) in deposited {
            match target.entry(step) {
                std::collections::btree_map::Entry::Occupied(_) => {
                    inner.lru.remove(&slot.used);
                }
                std::collections::btree_map::Entry::Vacant(v) => {
                    inner.lru.insert(slot.used, (to.clone(), step));
                    v.insert(slot);
                }
            }
        }
    }

    /// The latest checkpoint of `key` at or before `step`, with its step (marked used).
    pub fn at_or_before(&self, key: &str, step: u64) -> Option<(u64, Arc<Checkpoint>)> {
        let mut inner = self.lock();
        let (at, checkpoint) = inner
            .by_key
            .get(key)?
            .range(..=step)
            .next_back()
            .map(|(s, slot)| (*s, slot.checkpoint.clone()))?;
        inner.touch(key, at);
        Some((at, checkpoint))
    }

    /// The step of `key`'s latest checkpoint at or before `step` (not marked used).
    pub fn latest_at_or_before(&self, key: &str, step: u64) -> Option<u64> {
        self.lock()
            .by_key
            .get(key)?
            .range(..=step)
            .next_back()
            .map(|(s, _)| *s)
    }

    /// Whether `key` has a checkpoint at `step`.
    pub fn has(&self, key: &str, step: u64) -> bool {
        self.lock()
            .by_key
            .get(key)
            .is_some_and(|m| m.contains_key(&step))
    }

    /// Keeps `checkpoint` as `key`'s at `step` (a present one stays), evicting the least
    /// recently used beyond the cache's size.
    pub fn insert(&self, key: &str, step: u64, checkpoint: Checkpoint) {
        if self.max == 0 {
            return;
        }
        let mut inner = self.lock();
        if inner.by_key.get(key).is_some_and(|m| m.contains_key(&step)) {
            return;
        }
        while inner.lru.len() >= self.max {
            inner.evict_oldest();
        }
        inner.tick += 1;
        let used = inner.tick;
        inner.lru.insert(used, (key.to_string(), step));
        inner.by_key.entry(key.to_string()).or_default().insert(
            step,
            Slot {
                checkpoint: Arc::new(checkpoint),
                used,
            },
        );
    }

    /// Checkpoints kept.
    pub fn len(&self) -> usize {
        self.lock().lru.len()
    }

    /// No checkpoint kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The steps of `key`'s checkpoints, in order.
    pub fn steps(&self, key: &str) -> Vec<u64> {
        self.lock()
            .by_key
            .get(key)
            .map(|m| m.keys().copied().collect())
            .unwrap_or_default()
    }
}

impl Default for CheckpointCache {
    /// A cache of [`MAX_CHECKPOINTS`].
    fn default() -> CheckpointCache {
        CheckpointCache::new(MAX_CHECKPOINTS)
    }
}
