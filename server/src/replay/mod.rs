//! Deterministic replay: an attempt is recorded as its initial conditions ([`Init`]) and the
//! log of the commands applied to it ([`log`], the commands' own log form); replaying builds
//! the same [`Live`] and applies the same commands before the same steps through the same
//! [`Live::apply`] and [`Live::advance`], so the state at any step is the recorded one bit for bit (the step is
//! deterministic: no clock, no randomness but the attempt's seed, no threads inside a step).
//!
//! A seek starts from the nearest earlier checkpoint ([`checkpoints`]: the state every 2 s of
//! simulated time, kept in a bounded cache the server's replays share) and re-simulates at
//! most one interval; a replay deposits the checkpoints it passes.
//!
//! An attempt recorded by another simulator ([`SIM_VERSION`] differs) is not replayed: the
//! same inputs would no longer give the same states, so the attempt says so instead.
//!
//! A practice attempt taken over from another attempt's replay at step `s` ([`Init::from`],
//! "take over from here") started from that replay's state: its replay is its source's
//! (initial conditions and log entries before `s`, [`splice`]) followed by its own log, whose
//! entries are stamped from `s` on (the simulation's clock carried over). A chain of
//! take-overs is followed to its first attempt, at most [`MAX_TAKE_OVERS`] links.

use std::sync::Arc;

use seaarms_core::Model;

use crate::catalogue::Scenario;
use crate::protocol::{ActiveFault, StateFrame};
use crate::sessions::Live;
use crate::sessions::snapshot::build_frame;
use checkpoints::{CHECKPOINT_INTERVAL_STEPS, Checkpoint, CheckpointCache};
use log::{Entry, Logged};

pub mod checkpoints;
pub mod synthetic;
pub mod track;

/// The record's format, written by the live state (it lives with the commands it logs).
pub use crate::sessions::command::log::{self, Init, SIM_VERSION};

/// Steps per simulated second (the 1 ms step).
pub const STEPS_PER_S: f64 = 1000.0;

/// Why an attempt cannot be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Recorded by another simulator.
    #[error(
        "recorded by simulator version {recorded}; this server is {current}, whose physics may \
         differ, so it cannot reproduce the recording exactly. Replay it with the seaarms \
         build {recorded}; its assessment and CSV remain valid"
    )]
    Version {
        /// The attempt's stamp.
        recorded: String,
        /// [`SIM_VERSION`].
        current: String,
    },
    /// The record is unreadable.
    #[error("the attempt's record cannot be read: {0}")]
    Record(String),
    /// The seek was given up (its request went away or ran out of time).
    #[error("the seek was cancelled")]
    Cancelled,
}

/// Most take-overs between a practice attempt and the attempt its chain starts from (a
/// take-over of a take-over of … ); a longer chain is not replayed, nor taken over again.
pub const MAX_TAKE_OVERS: usize = 8;

/// The log a practice attempt taken over at step `step` of a source whose (spliced) log is
/// `source` is replayed with: the source's entries applied before `step` (stamped before it),
/// then the attempt's own (`own`, stamped at `step` or later).
pub fn splice(mut source: Vec<Entry>, step: u64, own: Vec<Entry>) -> Vec<Entry> {
    source.retain(|e| e.k < step);
    source.extend(own);
    source
}

/// Whether an attempt stamped `sim_version` can be replayed here.
pub fn check_version(sim_version: &str) -> Result<(), ReplayError> {
    if sim_version == SIM_VERSION {
        Ok(())
    } else {
        Err(ReplayError::Version {
            recorded: sim_version.to_string(),
            current: SIM_VERSION.to_string(),
        })
    }
}

/// An attempt being replayed: its live state at some step.
pub struct Replay {
    models: [Arc<Model>; 2],
    init: Init,
    /// The log (shared by its scouts, [`Replay::scout`]).
    entries: Arc<Vec<Entry>>,
    live: Live,
    /// Next entry to apply.
    next: usize,
    /// Length (steps).
    duration_steps: u64,
    /// Where its checkpoints are kept, and its key there ([`CheckpointCache::key`]).
    cache: Arc<CheckpointCache>,
    key: String,
    /// Steps re-simulated since it was built (all seeks).
    simulated: u64,
}

impl Replay {
    /// Prepares a replay at step 0, with checkpoints of its own (a cache of
    /// [`checkpoints::MAX_CHECKPOINTS`] only it uses; [`Replay::shared`] for the server's).
    /// `duration_s`: the attempt's length (its last entry's time when it is still running or
    /// was cut off).
    pub fn new(
        models: &[Arc<Model>; 2],
        init: Init,
        entries: Vec<Entry>,
        duration_s: f64,
    ) -> Result<Replay, ReplayError> {
        Self::shared(
            models,
            init,
            entries,
            duration_s,
            Arc::new(CheckpointCache::default()),
            "replay",
        )
    }

    /// [`Replay::new`] keeping its checkpoints in `cache` under attempt `attempt`'s key, where
    /// every replay of the same attempt (and log) finds them.
    pub fn shared(
        models: &[Arc<Model>; 2],
        init: Init,
        entries: Vec<Entry>,
        duration_s: f64,
        cache: Arc<CheckpointCache>,
        attempt: &str,
    ) -> Result<Replay, ReplayError> {
        let key = CheckpointCache::key(attempt, entries.len());
        let mut replay = Self::unshared(models, init, entries, duration_s, cache)?;
        replay.key = key;
        Ok(replay)
    }

    fn unshared(
        models: &[Arc<Model>; 2],
        init: Init,
        entries: Vec<Entry>,
        duration_s: f64,
        cache: Arc<CheckpointCache>,
    ) -> Result<Replay, ReplayError> {
        let live = Self::start(models, &init)?;
        let last = entries.last().map_or(0, |e| e.k);
        let duration_steps = ((duration_s.max(0.0) * STEPS_PER_S).round() as u64).max(last);
        Ok(Replay {
            models: models.clone(),
            init,
            entries: Arc::new(entries),
            live,
            next: 0,
            duration_steps,
            cache,
            key: String::new(),
            simulated: 0,
        })
    }

    fn start(models: &[Arc<Model>; 2], init: &Init) -> Result<Live, ReplayError> {
        if init.format != log::FORMAT {
            return Err(ReplayError::Record(format!(
                "log format {} (this server reads {})",
                init.format,
                log::FORMAT
            )));
        }
        if let Some(from) = &init.from {
            return Err(ReplayError::Record(format!(
                "a practice attempt starts from attempt `{}`'s replay: splice its source first",
                from.attempt
            )));
        }
        let scenario = Scenario::resolve(&init.scenario)
            .ok_or_else(|| ReplayError::Record(format!("unknown scenario `{}`", init.scenario)))?;
        let faults = init
            .faults
            .iter()
            .map(ActiveFault::try_from)
            .collect::<Result<Vec<_>, _>>()
            .map_err(ReplayError::Record)?;
        let mut live = Live::replaying(
            models,
            &scenario,
            init.settings,
            &faults,
            init.sim_faults,
            init.seed,
            init.current,
        )
        .map_err(|e| ReplayError::Record(e.to_string()))?;
        live.set_pass_lines(init.pass_lines.clone());
        Ok(live)
    }

    /// Length (s).
    pub fn duration_s(&self) -> f64 {
        self.duration_steps as f64 / STEPS_PER_S
    }

    /// Current time (s since the attempt's start).
    pub fn time_s(&self) -> f64 {
        self.live.sim().time_s()
    }

    /// At the attempt's end.
    pub fn at_end(&self) -> bool {
        self.live.sim().steps() >= self.duration_steps
    }

    /// The state now.
    pub fn live(&self) -> &Live {
        &self.live
    }

    /// Moves to `step` (clamped to the length): from the latest checkpoint at or before it
    /// when that is ahead of the current step or the seek goes back (else from the current
    /// step, or from the initial conditions when none is earlier), then by stepping.
    pub fn seek_step(&mut self, step: u64) -> Result<(), ReplayError> {
        self.seek_step_checked(step, &|| true)
    }

    /// [`Replay::seek_step`], asking `keep_going` every simulated second
    /// ([`ReplayError::Cancelled`] when it says no: the seek stops where it is, and the
    /// checkpoints it passed stay).
    pub fn seek_step_checked(
        &mut self,
        step: u64,
        keep_going: &dyn Fn() -> bool,
    ) -> Result<(), ReplayError> {
        let step = step.min(self.duration_steps);
        let now = self.live.sim().steps();
        match self.cache.at_or_before(&self.key, step) {
            Some((at, checkpoint)) if at > now || step < now => {
                self.live = checkpoint.live.checkpoint();
                self.next = checkpoint.next;
            }
            _ if step < now => {
                self.live = Self::start(&self.models, &self.init)?;
                self.next = 0;
            }
            _ => {}
        }
        while self.live.sim().steps() < step {
            let k = self.live.sim().steps();
            if k > 0 && k % CHECKPOINT_INTERVAL_STEPS == 0 && !self.cache.has(&self.key, k) {
                let checkpoint = Checkpoint {
                    live: self.live.checkpoint(),
                    next: self.next,
                };
                self.cache.insert(&self.key, k, checkpoint);
            }
            if k % STEPS_PER_S as u64 == 0 && !keep_going() {
                return Err(ReplayError::Cancelled);
            }
            while let Some(e) = self.entries.get(self.next).filter(|e| e.k <= k) {
                match &e.what {
                    Logged::Command(command) => {
                        self.live
                            .apply(command)
                            .map_err(|e| ReplayError::Record(e.to_string()))?;
                    }
                    Logged::Intervention(_) => self.live.intervene(),
                }
                self.next += 1;
            }
            self.live.advance();
            self.simulated += 1;
        }
        Ok(())
    }

    /// Steps re-simulated since the replay was built, over all its seeks (what seeking cost).
    pub fn steps_simulated(&self) -> u64 {
        self.simulated
    }

    /// Steps a seek to `step` would re-simulate now (the same choice of start as
    /// [`Replay::seek_step_checked`]: the latest checkpoint at or before it when that is ahead
    /// or the seek goes back, else the current step, else the start).
    pub fn seek_cost(&self, step: u64) -> u64 {
        let step = step.min(self.duration_steps);
        let now = self.live.sim().steps();
        match self.cache.latest_at_or_before(&self.key, step) {
            Some(at) if at > now || step < now => step - at,
            _ if step < now => step,
            _ => step - now,
        }
    }

    /// A new replay of the same attempt at step 0, sharing the log and the checkpoints: a
    /// long seek runs on it elsewhere (the compute pool) and leaves its checkpoints behind,
    /// so that this replay's own seek there then costs at most one interval.
    pub fn scout(&self) -> Result<Replay, ReplayError> {
        Ok(Replay {
            models: self.models.clone(),
            init: self.init.clone(),
            entries: self.entries.clone(),
            live: Self::start(&self.models, &self.init)?,
            next: 0,
            duration_steps: self.duration_steps,
            cache: self.cache.clone(),
            key: self.key.clone(),
            simulated: 0,
        })
    }

    /// The steps of this replay's checkpoints in its cache, in order.
    pub fn checkpoint_steps(&self) -> Vec<u64> {
        self.cache.steps(&self.key)
    }

    /// Moves to time `t` (s), to the nearest step.
    pub fn seek(&mut self, t: f64) -> Result<(), ReplayError> {
        self.seek_checked(t, &|| true)
    }

    /// [`Replay::seek`], cancellable ([`Replay::seek_step_checked`]).
    pub fn seek_checked(
        &mut self,
        t: f64,
        keep_going: &dyn Fn() -> bool,
    ) -> Result<(), ReplayError> {
        self.seek_step_checked(Self::step_at(t), keep_going)
    }

    /// The step of time `t` (s; the nearest, 0 for a negative or non-finite `t`).
    pub fn step_at(t: f64) -> u64 {
        let t = if t.is_finite() { t.max(0.0) } else { 0.0 };
        (t * STEPS_PER_S).round() as u64
    }

    /// The state frame now (the live session's frame format).
    pub fn frame(&mut self) -> StateFrame {
        build_frame(&mut self.live)
    }
}
