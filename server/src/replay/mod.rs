//! Deterministic replay: an attempt is recorded as its initial conditions ([`Init`]) and the
//! log of everything applied to it ([`log`]); replaying builds the same [`Live`] and applies
//! the same entries before the same steps through the same [`Live::apply`] and
//! [`Live::advance`], so the state at any step is the recorded one bit for bit (the step is
//! deterministic: no clock, no randomness but the attempt's seed, no threads inside a step).
//!
//! An attempt recorded by another simulator ([`SIM_VERSION`] differs) is not replayed: the
//! same inputs would no longer give the same states, so the attempt says so instead.

pub mod log;

use std::sync::Arc;

use seaarms_core::Model;
use seaarms_core::hydraulics::Faults;
use serde::{Deserialize, Serialize};

use crate::protocol::{Settings, StateFrame};
use crate::sessions::command::{ActiveFault, Arm, Command, Current, Fault, FaultKind};
use crate::sessions::snapshot::build_frame;
use crate::sessions::{Live, Scenario};
use log::{Applied, Entry, FaultEntry};

/// The simulator's version stamp: the crate version and a hash of every source that decides
/// what the logged inputs do (see `build.rs`).
pub const SIM_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("SEAARMS_SIM_HASH"));

/// Steps per simulated second (the 1 ms step).
pub const STEPS_PER_S: f64 = 1000.0;

/// An attempt's initial conditions: with the log, all replay needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Init {
    /// Log format ([`log::FORMAT`]).
    pub format: u32,
    /// Scenario name or exercise id.
    pub scenario: String,
    /// Settings at the start.
    pub settings: Settings,
    /// Instructor faults active at the start (shown in frames).
    pub faults: Vec<FaultEntry>,
    /// The simulation's fault parameters per arm at the start (left, right), exactly.
    pub sim_faults: [Faults; 2],
    /// Seed of the attempt's random draws.
    pub seed: u64,
    /// The water's current at the start (a subsea scenario with a current set; absent:
    /// still water or air).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current: Option<Current>,
}

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

/// A fault as logged.
pub fn fault_entry(f: &ActiveFault) -> FaultEntry {
    FaultEntry {
        arm: f.arm.index(),
        kind: f.fault.kind().name().to_string(),
        joint: f.fault.joint(),
        value: f.fault.value(),
    }
}

/// A logged fault back as a fault.
pub fn active_fault(e: &FaultEntry) -> Result<ActiveFault, String> {
    let kind = FaultKind::parse(&e.kind).ok_or_else(|| format!("unknown fault `{}`", e.kind))?;
    let arm = *Arm::BOTH
        .get(e.arm)
        .ok_or_else(|| format!("arm {}", e.arm))?;
    Ok(ActiveFault {
        arm,
        fault: Fault::new(kind, e.joint, e.value)?,
        // A debrief shows every fault, silent ones too.
        silent: false,
    })
}

/// An attempt being replayed: its live state at some step.
pub struct Replay {
    models: [Arc<Model>; 2],
    init: Init,
    entries: Vec<Entry>,
    live: Live,
    /// Next entry to apply.
    next: usize,
    /// Length (steps).
    duration_steps: u64,
}

impl Replay {
    /// Prepares a replay at step 0. `duration_s`: the attempt's length (its last entry's
    /// time when it is still running or was cut off).
    pub fn new(
        models: &[Arc<Model>; 2],
        init: Init,
        entries: Vec<Entry>,
        duration_s: f64,
    ) -> Result<Replay, ReplayError> {
        let live = Self::start(models, &init)?;
        let last = entries.last().map_or(0, |e| e.k);
        let duration_steps = ((duration_s.max(0.0) * STEPS_PER_S).round() as u64).max(last);
        Ok(Replay {
            models: models.clone(),
            init,
            entries,
            live,
            next: 0,
            duration_steps,
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
        let scenario = Scenario::resolve(&init.scenario)
            .ok_or_else(|| ReplayError::Record(format!("unknown scenario `{}`", init.scenario)))?;
        let faults = init
            .faults
            .iter()
            .map(active_fault)
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

    /// Moves to `step` (clamped to the length): forward by stepping, backward by starting
    /// again from the initial conditions.
    pub fn seek_step(&mut self, step: u64) -> Result<(), ReplayError> {
        let step = step.min(self.duration_steps);
        if step < self.live.sim().steps() {
            self.live = Self::start(&self.models, &self.init)?;
            self.next = 0;
        }
        while self.live.sim().steps() < step {
            let k = self.live.sim().steps();
            while let Some(e) = self.entries.get(self.next).filter(|e| e.k <= k) {
                apply_entry(&mut self.live, e)?;
                self.next += 1;
            }
            self.live.advance();
        }
        Ok(())
    }

    /// Moves to time `t` (s), to the nearest step.
    pub fn seek(&mut self, t: f64) -> Result<(), ReplayError> {
        let t = if t.is_finite() { t.max(0.0) } else { 0.0 };
        self.seek_step((t * STEPS_PER_S).round() as u64)
    }

    /// The state frame now (the live session's frame format).
    pub fn frame(&mut self) -> StateFrame {
        build_frame(&mut self.live)
    }
}

/// Applies one logged entry, through the same [`Live::apply`] a live session uses.
fn apply_entry(live: &mut Live, e: &Entry) -> Result<(), ReplayError> {
    let command = match &e.what {
        Applied::Input { v } => {
            if v.len() != log::INPUT_VALUES {
                return Err(ReplayError::Record(format!("input of {} values", v.len())));
            }
            Command::Input(crate::sessions::command::StickInput::from_quanta(v))
        }
        Applied::Settings {
            mode,
            method,
            speed,
        } => Command::Settings(crate::sessions::command::SettingsChange {
            control_mode: *mode,
            control_method: *method,
            arm_speed: *speed,
        }),
        Applied::Release => Command::Release,
        Applied::Diagnose { answer } => Command::Diagnose(answer.clone()),
        Applied::Fault { fault } => {
            Command::InjectFault(active_fault(fault).map_err(ReplayError::Record)?)
        }
        Applied::ClearFaults => Command::ClearFaults,
        Applied::Current {
            speed_m_s,
            heading_deg,
        } => Command::current(*speed_m_s, *heading_deg)
            .map_err(|e| ReplayError::Record(e.to_string()))?,
        Applied::Intervention => {
            live.intervene();
            return Ok(());
        }
    };
    live.apply(&command)
        .map(|_| ())
        .map_err(|e| ReplayError::Record(e.to_string()))
}
