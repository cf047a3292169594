//! Live training sessions: one dual-arm simulation per trainee, stepped at 1 kHz of
//! simulated time in real time on dedicated physics threads (never on the async reactor),
//! published as "latest state wins" snapshots on a `watch` channel.
//!
//! * [`SessionManager`]: create, find, list, expire, cap; owns the physics workers.
//! * [`physics`]: the worker threads that step sessions and publish frames.
//! * [`snapshot`]: building a [`crate::protocol::StateFrame`] (measures included) from a simulation.
//! * [`record`]: the recorder thread (CSV time series on disk; sessions, attempts and events
//!   in the records database, [`crate::db`]).
//! * [`command`]: the one [`command::Command`] type both edges parse into, applied in one place.
//! * [`admission`]: who may create sessions how often (per-client token buckets and caps).
//! * [`ws`]: the WebSocket endpoint; [`rest`]: the REST endpoints.

pub mod admission;
pub mod command;
pub mod pass_board;
pub mod physics;
pub mod record;
pub mod snapshot;

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

use axum::extract::ws::Utf8Bytes;
use seaarms_core::Model;
use seaarms_core::exercise::ExerciseRun;
use seaarms_core::sim::measures::{SimMeasures, measures};
use seaarms_core::sim::{Operator, Simulation, Sticks};
use tokio::sync::watch;

use crate::auth::Actor;
use crate::auth::sha256_hex;
use crate::catalogue::Scenario;
use crate::clock::unix_now;
use crate::ids::{random_hex, random_seed};
use crate::metrics::Metrics;
use crate::protocol::{ControlMethod, ControlMode, EndReason, Settings};
use crate::replay::checkpoints::{CHECKPOINT_INTERVAL_STEPS, Checkpoint, CheckpointCache};
use admission::ClientKey;
use command::fault::log_form::FaultEntry;
use command::{ActiveFault, SettingsChange, StickInput};
use record::{RecordMsg, Recorder};

/// Why an attempt's record ends; with the attempt's assessment, it gives the stored outcome.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AttemptStop {
    /// The exercise is done (the step that finished it; outcome `passed` or `failed`).
    Finished,
    /// The trainee moved on: a reset, a scenario switch, the session's end, or a headless
    /// attempt's time limit (an unfinished exercise is `abandoned`, free play `ended`).
    Left,
    /// The server shut down (`interrupted`, unless the exercise was already done).
    Interrupted,
}

impl AttemptStop {
    /// The outcome stored for an attempt ending so: `passed` or `failed` for a done
    /// exercise whatever stopped it; else `interrupted` on shutdown, `ended` for free play,
    /// `abandoned` for an unfinished exercise.
    pub fn outcome(self, assessment: Option<&seaarms_core::exercise::Assessment>) -> &'static str {
        match (assessment, self) {
            (Some(a), _) if a.done && a.passed => "passed",
            (Some(a), _) if a.done => "failed",
            (_, AttemptStop::Interrupted) => "interrupted",
            (None, _) => "ended",
            (Some(_), AttemptStop::Finished | AttemptStop::Left) => "abandoned",
        }
    }
}

/// Session settings and limits (from [`crate::config::ServeConfig`]).
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// Most live sessions at once.
    pub max_sessions: usize,
    /// A session whose trainee gives no input for this long ends (connected or not).
    pub idle_timeout: Duration,
    /// State frames per second (10–120).
    pub frame_hz: u32,
    /// Client messages per second allowed per connection.
    pub max_messages_per_second: u32,
    /// Physics worker threads.
    pub physics_threads: usize,
    /// A session no trainee has ever connected to ends after this long.
    pub unjoined_grace: Duration,
    /// A joined session with no trainee connection for this long ends (`abandoned`).
    pub abandon_grace: Duration,
    /// Most live sessions created by one client (peer address) at once.
    pub max_sessions_per_client: usize,
}

/// A published state frame: its sequence number and the serialized JSON, shared by every client.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Frame sequence number.
    pub seq: u64,
    /// `{"type": "state", ...}` text.
    pub json: Utf8Bytes,
}

/// Mutable state of a session, behind one mutex (held briefly by the physics worker each
/// tick and by handlers applying commands): the clock, the records and the core's operator
/// and simulation. Its fields are private: the edges (WebSocket, REST) change it only
/// through [`command::apply`] and read it through the accessors; the stepping engine
/// ([`physics`], [`snapshot`]) works on the fields directly.
pub struct Live {
    /// The simulation.
    sim: Simulation,
    /// Stage 0 of every step: sticks, grips and the settings (mode, method, speed) to the
    /// simulation's input.
    operator: Operator,
    /// Who paused the clock; `None` while it runs.
    paused: Option<Actor>,
    /// Last input sequence number applied.
    input_seq: u64,
    /// Active faults (one per arm, kind and actuator).
    faults: Vec<ActiveFault>,
    /// Steps taken since the clock origin.
    steps_since_origin: u64,
    /// Wall time of the clock origin (reset on resume so a pause never causes a catch-up burst).
    origin: Instant,
    /// Frames published.
    frame_seq: u64,
    /// The water's visibility the instructor set (m; `set_visibility`), for every page.
    visibility_m: Option<f64>,
    /// Each exercise attempt waits for the trainee's `ready` ([`Live::wait_for_ready`]).
    ready_gate: bool,
    /// The running attempt waits for `ready`: no steps pass, its clock reads 0.
    awaiting_ready: bool,
    /// When the next frame is due.
    next_frame: Instant,
    /// The measures of the last published frame ([`snapshot::build_frame`]).
    measures: SimMeasures,
    /// The step events not yet recorded that are recorded once per record row
    /// ([`physics::EventTally`]).
    tally: physics::EventTally,
    /// The arm models (left, right).
    models: [Arc<Model>; 2],
    /// What the session runs: free play, a case-study set-up, or an exercise.
    scenario: Scenario,
    /// The current attempt, when the scenario is an exercise.
    exercise: Option<ExerciseRun>,
    /// Seed of the next attempt's random draws: a live session draws each one from the
    /// operating system when the attempt before it starts, so no attempt's seed predicts the
    /// next one's (a drill's fault is drawn from it); a replay has only the one it was given.
    next_seed: u64,
    /// The session's id (records).
    session_id: String,
    /// The current attempt's id (records; a new one at every start).
    attempt_id: String,
    /// Where the running attempt was taken over from, when it is a practice attempt
    /// ([`Live::taking_over`]; a new attempt starts afresh and is not).
    practice: Option<command::log::Source>,
    /// Whether attempts are recorded (a replay records nothing).
    recording: bool,
    /// The running attempt's input log (when recording).
    log: Option<command::log::Writer>,
    /// Attempt records waiting for the recorder, oldest first ([`Live::take_records`]).
    pending: Vec<RecordMsg>,
    /// Where a live session's attempts find their benchmark pass lines (None: the file's
    /// marks; a replay takes the recorded lines instead, [`Live::set_pass_lines`]).
    pass_board: Option<Arc<pass_board::PassBoard>>,
    /// Where a live session deposits its running attempt's replay checkpoints
    /// ([`crate::replay::checkpoints`]; None: a replay's own state, a headless run).
    checkpoints: Option<Arc<CheckpointCache>>,
}

impl Live {
    /// A session's live state at its start: the scenario's simulation at its reset state, the
    /// settings (an exercise's own unless `mode`/`method` override them), and for an
    /// exercise its first attempt, seeded with `seed`; each attempt judged by the benchmark
    /// lines on `pass_board` when it starts (None: by the exercise file's marks).
    pub fn new(
        session_id: &str,
        models: &[Arc<Model>; 2],
        scenario: &Scenario,
        mode: Option<ControlMode>,
        method: Option<ControlMethod>,
        seed: u64,
        pass_board: Option<Arc<pass_board::PassBoard>>,
    ) -> Result<Live, seaarms_core::Error> {
        let mut live = Self::build(session_id, models, scenario, mode, method, seed, true)?;
        live.pass_board = pass_board;
        live.start_attempt();
        Ok(live)
    }

    /// The state at a recorded attempt's start ([`crate::replay::Init`]), recording nothing;
    /// `current`: the current flowing at that start (the simulation is reset after setting it,
    /// so the water moves at it steadily, as it did after the recorded session's reset — a
    /// current set mid-attempt ramps instead, `seaarms_core::sim::water::Flow`).
    pub fn replaying(
        models: &[Arc<Model>; 2],
        scenario: &Scenario,
        settings: Settings,
        faults: &[ActiveFault],
        sim_faults: [seaarms_core::hydraulics::Faults; 2],
        seed: u64,
        current: Option<seaarms_core::sim::Current>,
    ) -> Result<Live, seaarms_core::Error> {
        let mut live = Self::build(
            "replay",
            models,
            scenario,
            Some(settings.control_mode),
            Some(settings.control_method),
            seed,
            false,
        )?;
        live.start_attempt();
        live.operator.set_speed(settings.arm_speed);
        live.operator
            .set_hold_orientation(settings.hold_orientation);
        for f in faults {
            live.inject_fault(*f);
        }
        for arm in command::Arm::BOTH {
            *live.sim.faults_mut(arm) = sim_faults[arm.index()];
        }
        if let Some(c) = current {
            live.apply(&command::Command::SetCurrent(c)).map_err(|e| {
                seaarms_core::Error::InvalidParameter {
                    what: "current",
                    reason: e.to_string(),
                }
            })?;
            live.sim.reset();
        }
        Ok(live)
    }

    /// Judges the running attempt by the benchmark pass `lines` (a replay: the lines its record
    /// kept, [`crate::replay::Init::pass_lines`]).
    pub fn set_pass_lines(
        &mut self,
        lines: Option<seaarms_core::exercise::proficiency::PassLines>,
    ) {
        if let Some(run) = self.exercise.as_mut() {
            run.set_pass_lines(lines);
        }
    }

    /// A copy of this state for a replay's checkpoint ([`crate::replay`]): everything that
    /// steps (simulation, operator, exercise, clock and faults) cloned, so the copy continues
    /// bit for bit as this state does; the records are not copied (a replay records nothing:
    /// the copy has no input log and no pending records, and does not record). The session's
    /// own parts that no log entry sets are as a replay has them (input and frame numbers 0,
    /// not paused, the default visibility, no Ready gate), so a live session's checkpoint and
    /// a replay's at the same step are the same state.
    pub fn checkpoint(&self) -> Live {
        Live {
            sim: self.sim.clone(),
            operator: self.operator.clone(),
            paused: None,
            input_seq: 0,
            faults: self.faults.clone(),
            steps_since_origin: self.steps_since_origin,
            origin: self.origin,
            frame_seq: 0,
            visibility_m: None,
            ready_gate: false,
            awaiting_ready: false,
            next_frame: self.next_frame,
            measures: self.measures.clone(),
            tally: self.tally,
            models: self.models.clone(),
            scenario: self.scenario.clone(),
            exercise: self.exercise.clone(),
            next_seed: self.next_seed,
            session_id: "replay".to_string(),
            attempt_id: self.attempt_id.clone(),
            practice: None,
            recording: false,
            log: None,
            pending: Vec::new(),
            pass_board: None,
            checkpoints: None,
        }
    }

    /// Deposits the running attempt's state as its replay checkpoint at this step when the
    /// step is one ([`CHECKPOINT_INTERVAL_STEPS`]; a live session that keeps checkpoints, a
    /// recorded attempt that is not a practice attempt, whose replay log begins in its
    /// source's). Called after a step, where a replay takes its checkpoint before applying
    /// the log's next entries: this step's commands come after.
    fn deposit_checkpoint(&self) {
        let (Some(cache), Some(log)) = (self.checkpoints.as_ref(), self.log.as_ref()) else {
            return;
        };
        let k = self.sim.steps();
        if k == 0 || k % CHECKPOINT_INTERVAL_STEPS != 0 || self.practice.is_some() {
            return;
        }
        cache.insert(
            &CheckpointCache::live_key(&self.attempt_id),
            k,
            Checkpoint {
                live: self.checkpoint(),
                next: log.entries(),
            },
        );
    }

    /// Keeps the running and later attempts' replay checkpoints in `cache` as they run.
    pub fn keep_checkpoints(&mut self, cache: Arc<CheckpointCache>) {
        self.checkpoints = Some(cache);
    }

    fn build(
        session_id: &str,
        models: &[Arc<Model>; 2],
        scenario: &Scenario,
        mode: Option<ControlMode>,
        method: Option<ControlMethod>,
        seed: u64,
        recording: bool,
    ) -> Result<Live, seaarms_core::Error> {
        let sim = scenario.build_sim(models)?;
        let control = scenario.exercise().map(|e| e.control);
        let mut operator = Operator::new(&models[0], &models[1]);
        operator.set_mode(mode.or(control.map(|c| c.mode)).unwrap_or_default());
        operator.set_method(method.or(control.map(|c| c.method)).unwrap_or_default());
        operator.set_hold_orientation(control.and_then(|c| c.hold_orientation).unwrap_or(true));
        let now = Instant::now();
        let live = Live {
            measures: measures(&sim),
            sim,
            operator,
            paused: None,
            input_seq: 0,
            faults: Vec::new(),
            steps_since_origin: 0,
            origin: now,
            frame_seq: 0,
            visibility_m: None,
            ready_gate: false,
            awaiting_ready: false,
            next_frame: now,
            tally: Default::default(),
            models: models.clone(),
            scenario: scenario.clone(),
            exercise: None,
            next_seed: seed,
            session_id: session_id.to_string(),
            attempt_id: String::new(),
            practice: None,
            recording,
            log: None,
            pending: Vec::new(),
            pass_board: None,
            checkpoints: None,
        };
        Ok(live)
    }

    /// Starts a new attempt when the scenario is an exercise (the simulation is at its reset
    /// state).
    fn start_attempt(&mut self) {
        self.attempt_id = random_hex(8);
        self.practice = None;
        self.awaiting_ready = self.ready_gate && self.scenario.exercise().is_some();
        let seed = self.next_seed;
        self.next_seed = random_seed();
        self.exercise = self
            .scenario
            .exercise()
            .map(|spec| ExerciseRun::new(spec.clone(), &self.sim, seed));
        if let (Some(run), Some(board)) = (self.exercise.as_mut(), self.pass_board.as_ref()) {
            run.set_pass_lines(board.get(&run.spec().id));
        }
        if self.recording {
            let init = command::log::Init {
                format: command::log::FORMAT,
                scenario: self.scenario.name().to_string(),
                settings: self.settings(),
                faults: self.faults.iter().map(FaultEntry::from).collect(),
                sim_faults: command::Arm::BOTH.map(|a| self.sim.params().arms[a.index()].faults),
                seed,
                current: self
                    .sim
                    .environment()
                    .water()
                    .map(|w| w.current)
                    .filter(|c| c.speed_m_s > 0.0),
                pass_lines: self.exercise.as_ref().and_then(|r| r.pass_lines().cloned()),
                from: None,
            };
            self.record_start(&init);
        }
    }

    /// Records the running attempt's start with its initial conditions `init`, and opens its
    /// input log.
    fn record_start(&mut self, init: &command::log::Init) {
        let exercise = self.scenario.exercise();
        self.pending
            .push(RecordMsg::AttemptStarted(Box::new(record::AttemptStart {
                id: self.attempt_id.clone(),
                session: self.session_id.clone(),
                scenario: self.scenario.name().to_string(),
                exercise: exercise.map(|e| e.id.clone()),
                exercise_version: exercise.map(|e| format!("{}", e.version)),
                sim_version: command::log::SIM_VERSION.to_string(),
                started_unix: unix_now(),
                init: serde_json::to_value(init).unwrap_or_default(),
            })));
        self.log = Some(command::log::Writer::new());
    }

    /// A new session's live state that continues `state` (an attempt's replayed state,
    /// [`Live::checkpoint`]) as a practice attempt ("take over from here", issue 30 item 5):
    /// everything that steps carries over bit for bit (the simulation, the operator with its
    /// sticks, the exercise's run with its clock, assessment and steps done, the faults); the
    /// session's own parts are new (its id, a new attempt id and seed for later attempts, the
    /// wall clock, recording). The attempt waits for the trainee's `ready`, so its first
    /// frames show the state it starts from, and each later attempt does too (the page's
    /// sessions do). `init` is recorded as its initial conditions (with `from` naming the
    /// source attempt and step: its replay replays the source there first).
    pub fn taking_over(session_id: &str, state: Live, init: &command::log::Init) -> Live {
        let now = Instant::now();
        let mut live = Live {
            paused: None,
            input_seq: 0,
            steps_since_origin: 0,
            origin: now,
            frame_seq: 0,
            visibility_m: None,
            ready_gate: true,
            awaiting_ready: true,
            next_frame: now,
            next_seed: random_seed(),
            session_id: session_id.to_string(),
            attempt_id: random_hex(8),
            practice: init.from.clone(),
            recording: true,
            log: None,
            pending: Vec::new(),
            ..state
        };
        live.record_start(init);
        live
    }

    /// Ends the running attempt's record: its log's last piece and its outcome
    /// ([`AttemptStop::outcome`]).
    pub fn end_attempt(&mut self, stop: AttemptStop) {
        let Some(mut log) = self.log.take() else {
            return;
        };
        if let Some(cache) = &self.checkpoints {
            cache.settle(&self.attempt_id, log.entries());
        }
        let last = log.finish();
        if !last.is_empty() {
            self.pending.push(RecordMsg::AttemptInputs {
                id: self.attempt_id.clone(),
                bytes: last,
                sim_seconds: self.sim.time_s(),
            });
        }
        let assessment = self.exercise.as_ref().map(ExerciseRun::assessment);
        let outcome = stop.outcome(assessment.as_ref());
        self.pending
            .push(RecordMsg::AttemptEnded(Box::new(record::AttemptEnd {
                id: self.attempt_id.clone(),
                ended_unix: unix_now(),
                sim_seconds: self.sim.time_s(),
                outcome: outcome.to_string(),
                score: assessment.as_ref().map(|a| a.score),
                assessment: assessment.and_then(|a| serde_json::to_value(a).ok()),
            })));
    }

    /// Attempt records for the recorder, oldest first; with the log's piece so far and the
    /// attempt's simulated seconds when `piece` (about every second, so a killed server
    /// loses at most that, and its interrupted attempt keeps its length).
    pub fn take_records(&mut self, piece: bool) -> Vec<RecordMsg> {
        if piece {
            if let Some(bytes) = self.log.as_mut().map(|l| l.take_piece()) {
                self.pending.push(RecordMsg::AttemptInputs {
                    id: self.attempt_id.clone(),
                    bytes,
                    sim_seconds: self.sim.time_s(),
                });
            }
        }
        std::mem::take(&mut self.pending)
    }

    /// Logs what was applied in the running attempt, stamped with the current step.
    fn log(&mut self, what: command::log::Logged) {
        let k = self.sim.steps();
        if let Some(log) = self.log.as_mut() {
            log.push(&command::log::Entry { k, what });
        }
    }

    /// Counts an instructor's intervention in the running attempt (and logs it: it counts in
    /// the score).
    pub fn intervene(&mut self) {
        self.log(command::log::Logged::Intervention(
            command::log::Intervention::Intervention,
        ));
        if let Some(run) = self.exercise.as_mut() {
            run.intervention();
        }
    }

    /// An event of the current attempt at the current simulated time.
    pub fn event(&self, kind: &str, detail: serde_json::Value) -> Box<record::EventRecord> {
        Box::new(record::EventRecord {
            session: self.session_id.clone(),
            attempt: Some(self.attempt_id.clone()),
            t: self.sim.time_s(),
            kind: kind.to_string(),
            actor: None,
            detail,
        })
    }

    /// The current attempt's id.
    pub fn attempt_id(&self) -> &str {
        &self.attempt_id
    }

    /// The current attempt, when the scenario is an exercise.
    pub fn exercise(&self) -> Option<&ExerciseRun> {
        self.exercise.as_ref()
    }

    /// What the session runs.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Switches to `scenario`: a fresh simulation (an exercise has its own scene), faults
    /// cleared, inputs cleared, an exercise's settings, a new attempt.
    pub fn set_scenario(&mut self, scenario: Scenario) -> Result<(), seaarms_core::Error> {
        let sim = scenario.build_sim(&self.models)?;
        self.end_attempt(AttemptStop::Left);
        self.sim = sim;
        self.faults.clear();
        self.scenario = scenario;
        if let Some(c) = self.scenario.exercise().map(|e| e.control) {
            self.apply_settings(&SettingsChange {
                control_mode: Some(c.mode),
                control_method: Some(c.method),
                arm_speed: None,
                hold_orientation: Some(c.hold_orientation.unwrap_or(true)),
            });
        }
        self.reset();
        Ok(())
    }

    /// No stick, grip or object input above the exercise's idle threshold (0.05 by
    /// default, under the page's dead zone).
    pub fn idle(&self) -> bool {
        let th = self
            .scenario
            .exercise()
            .map_or(0.05, |e| e.thresholds.idle_input);
        self.operator.idle(th)
    }

    /// The arm models (left, right).
    pub fn models(&self) -> &[Arc<Model>; 2] {
        &self.models
    }

    /// The simulation (read-only).
    pub fn sim(&self) -> &Simulation {
        &self.sim
    }

    /// The measures of the last published frame (per arm and dual; computed once per frame).
    pub fn measures(&self) -> &SimMeasures {
        &self.measures
    }

    /// Current settings (the operator's).
    pub fn settings(&self) -> Settings {
        Settings {
            control_mode: self.operator.mode(),
            control_method: self.operator.method(),
            arm_speed: self.operator.speed(),
            hold_orientation: self.operator.hold_orientation(),
        }
    }

    /// Whether the clock is paused.
    pub fn paused(&self) -> bool {
        self.paused.is_some()
    }

    /// Whether no steps pass: paused, or an attempt waiting for `ready`.
    pub fn clock_stopped(&self) -> bool {
        self.paused.is_some() || self.awaiting_ready
    }

    /// From now on (this attempt included) each exercise attempt waits for the trainee's
    /// `ready` before its clock starts (`true`), or starts at once (`false`).
    pub fn wait_for_ready(&mut self, on: bool) {
        self.ready_gate = on;
        self.awaiting_ready = on && self.scenario.exercise().is_some();
    }

    /// The running attempt waits for `ready`.
    pub fn awaiting_ready(&self) -> bool {
        self.awaiting_ready
    }

    /// The trainee has read the goal: the attempt's clock starts.
    pub fn ready(&mut self) {
        self.awaiting_ready = false;
    }

    /// Who paused the clock, while it is paused.
    pub fn paused_by(&self) -> Option<Actor> {
        self.paused
    }

    /// Active faults.
    pub fn faults(&self) -> &[ActiveFault] {
        &self.faults
    }

    /// New stick input for the operator (read by the mode it is in at each step,
    /// [`Operator::input`]); the grips drive the jaws.
    pub fn apply_input(&mut self, input: &StickInput) {
        let sticks = input.arms.map(|a| Sticks {
            axes: a.axes,
            grip: a.grip,
        });
        self.operator.set_sticks(&sticks, &input.object);
        self.input_seq = self.input_seq.max(input.seq);
    }

    /// Changes settings; a mode change stops every stick command.
    pub fn apply_settings(&mut self, change: &SettingsChange) {
        if let Some(s) = change.arm_speed {
            self.operator.set_speed(s);
        }
        if let Some(m) = change.control_mode {
            self.operator.set_mode(m);
        }
        if let Some(m) = change.control_method {
            self.operator.set_method(m);
        }
        if let Some(h) = change.hold_orientation {
            self.operator.set_hold_orientation(h);
        }
    }

    /// Back to the initial position (Lim §4.1): simulation reset, inputs cleared, fresh
    /// resolvers (an attempt's start never depends on what came before it). Faults are cleared
    /// — the drill's own and the instructor's — except the instructor's `persistent` ones, so
    /// a silent fault ends with its attempt (issue 29: a reset revealed it).
    pub fn reset(&mut self) {
        self.end_attempt(AttemptStop::Left);
        let kept: Vec<ActiveFault> = self
            .faults
            .iter()
            .filter(|f| f.persistent)
            .copied()
            .collect();
        self.clear_faults();
        for f in kept {
            self.inject_fault(f);
        }
        self.sim.reset();
        self.operator.reset();
        self.tally = Default::default();
        self.start_attempt();
    }

    /// Pauses the clock on behalf of `by`, or resumes it (`None`); who may lift whose pause
    /// is [`Live::pause_as`]'s rule.
    pub fn set_paused(&mut self, by: Option<Actor>) {
        self.paused = by;
    }

    /// Sets the water's visibility every page draws (m).
    pub fn set_visibility(&mut self, visibility_m: f64) {
        self.visibility_m = Some(visibility_m);
    }

    /// A keyboard tap on `arm` (`seaarms_core::sim::Operator::jog`).
    pub fn jog(&mut self, arm: seaarms_core::sim::Arm, axes: &[f64; 6]) {
        self.operator.jog(&self.sim, arm, axes);
    }

    /// Drives both jaws open for `duration_s` of simulated time, whatever the sticks say.
    pub fn release(&mut self, duration_s: f64) {
        self.operator.release(self.sim.time_s() + duration_s);
    }

    /// Injects a fault, replacing one of the same kind on the same arm and actuator.
    pub fn inject_fault(&mut self, fault: ActiveFault) {
        fault.fault.apply_to(self.sim.faults_mut(fault.arm));
        self.faults.retain(|f| !f.same_slot(&fault));
        self.faults.push(fault);
    }

    /// Answers the running exercise's diagnosis drill.
    pub fn diagnose(&mut self, answer: &str) -> Result<(), String> {
        let run = self
            .exercise
            .as_mut()
            .ok_or_else(|| "no exercise is running".to_string())?;
        run.diagnose(answer).map(|_| ())
    }

    /// Sets the water's current (refused in air).
    pub fn set_current(
        &mut self,
        current: seaarms_core::sim::water::Current,
    ) -> Result<(), seaarms_core::Error> {
        self.sim.set_current(current)
    }

    /// Removes every fault.
    pub fn clear_faults(&mut self) {
        for arm in command::Arm::BOTH {
            *self.sim.faults_mut(arm) = Default::default();
        }
        self.faults.clear();
    }
}

/// One trainee's session.
pub struct Session {
    /// Id (hex).
    pub id: String,
    /// Trainee label.
    pub label: String,
    /// The trainee's class or group ("" when none).
    pub group: String,
    /// Token that lets a trainee control this session.
    pub control_token: String,
    /// Creation time (Unix seconds).
    pub created_unix: f64,
    /// The live state.
    live: Mutex<Live>,
    /// Latest frame (latest state wins).
    pub frames: watch::Sender<Option<Frame>>,
    /// Instructor messages and other one-off notices to every client.
    pub notices: tokio::sync::broadcast::Sender<Utf8Bytes>,
    /// Trainee connections open now.
    pub trainees: AtomicU64,
    /// Last trainee activity (Unix seconds, as f64 bits).
    last_activity: AtomicU64,
    /// Set once the session has ended.
    pub ended: AtomicBool,
    /// Why it ended (set with `ended`; sent to clients as the `ended` message).
    pub end_reason: OnceLock<EndReason>,
    /// Relief events (overloads) since creation, all resets included.
    pub overloads: AtomicU64,
    /// Models (left, right) for `hello`.
    pub models: [Arc<Model>; 2],
    /// The client that created it (for the per-client cap).
    pub client: ClientKey,
    /// Set once a trainee has connected (sessions never joined end after a grace period).
    pub joined: AtomicBool,
    /// When the last trainee connection closed (Unix seconds, as f64 bits; 0 before).
    trainee_left: AtomicU64,
}

impl Session {
    /// Locks the live state (a poisoned lock is recovered: the state is plain data).
    pub fn live(&self) -> MutexGuard<'_, Live> {
        self.live.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Marks trainee activity now.
    pub fn touch(&self) {
        self.last_activity
            .store(unix_now().to_bits(), Ordering::Relaxed);
    }

    /// Seconds since the last trainee activity.
    pub fn idle_seconds(&self) -> f64 {
        unix_now() - f64::from_bits(self.last_activity.load(Ordering::Relaxed))
    }

    /// Seconds since creation.
    pub fn age_seconds(&self) -> f64 {
        unix_now() - self.created_unix
    }

    /// Marks that the last trainee connection has closed, now.
    pub fn trainee_left(&self) {
        self.trainee_left
            .store(unix_now().to_bits(), Ordering::Relaxed);
    }

    /// Seconds since the last trainee connection closed.
    pub fn seconds_since_trainee_left(&self) -> f64 {
        unix_now() - f64::from_bits(self.trainee_left.load(Ordering::Relaxed))
    }
}

/// Why a session could not be created.
#[derive(Debug, thiserror::Error)]
pub enum CreateError {
    /// The cap is reached.
    #[error("the server is full ({0} live sessions); try again later")]
    Full(usize),
    /// This client already has its share of live sessions.
    #[error("this client already has {0} live sessions (the most per client); end one first")]
    ClientFull(usize),
    /// Unknown scenario.
    #[error("unknown scenario `{0}`")]
    UnknownScenario(String),
    /// The simulation refused its parameters.
    #[error("simulation: {0}")]
    Sim(String),
    /// Records cannot be written (disk below the free-space floor, folder not writable).
    #[error("{0}")]
    Recording(String),
}

/// All sessions of the server.
pub struct SessionManager {
    /// Settings.
    pub config: SessionConfig,
    live: Mutex<HashMap<String, Arc<Session>>>,
    workers: Vec<physics::WorkerHandle>,
    next_worker: AtomicU64,
    /// The recorder (disk).
    pub recorder: Recorder,
    /// Counters.
    pub metrics: Arc<Metrics>,
    magnum: Arc<Model>,
    /// The benchmark pass lines attempts start with.
    pass_board: Arc<pass_board::PassBoard>,
    /// The replay checkpoints live sessions deposit and replays share.
    checkpoints: Arc<CheckpointCache>,
}

/// What a new session is created with ([`SessionManager::create`]).
#[derive(Debug, Clone, Default)]
pub struct NewSession {
    /// Scenario or exercise name; `training` when absent.
    pub scenario: Option<String>,
    /// Control mode (else the exercise's, else joint).
    pub mode: Option<ControlMode>,
    /// Control method (else the exercise's, else open).
    pub method: Option<ControlMethod>,
    /// Trainee label.
    pub label: Option<String>,
    /// Trainee group.
    pub group: Option<String>,
    /// Exercise attempts wait for the trainee's `ready` ([`Live::wait_for_ready`]).
    pub wait_for_ready: bool,
}

impl SessionManager {
    /// Starts the physics workers and the recorder.
    pub fn start(
        config: SessionConfig,
        recorder: Recorder,
        metrics: Arc<Metrics>,
        magnum: Arc<Model>,
    ) -> Arc<SessionManager> {
        let workers = (0..config.physics_threads.max(1))
            .map(|i| physics::spawn_worker(i, recorder.sender(), metrics.clone(), config.frame_hz))
            .collect();
        Arc::new(SessionManager {
            config,
            live: Mutex::new(HashMap::new()),
            workers,
            next_worker: AtomicU64::new(0),
            recorder,
            metrics,
            magnum,
            pass_board: Arc::default(),
            checkpoints: Arc::default(),
        })
    }

    /// The benchmark pass lines the sessions' attempts start with.
    pub fn pass_board(&self) -> &Arc<pass_board::PassBoard> {
        &self.pass_board
    }

    /// The replay checkpoints: the sessions' attempts deposit theirs as they run, and every
    /// replay of the server shares them ([`crate::replay::checkpoints`]).
    pub fn checkpoints(&self) -> &Arc<CheckpointCache> {
        &self.checkpoints
    }

    /// The arm model sessions use (both arms).
    pub fn magnum(&self) -> Arc<Model> {
        self.magnum.clone()
    }

    fn map(&self) -> MutexGuard<'_, HashMap<String, Arc<Session>>> {
        self.live.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Creates a session for `client` and starts stepping it.
    pub fn create(&self, client: ClientKey, new: NewSession) -> Result<Arc<Session>, CreateError> {
        let NewSession {
            scenario,
            mode,
            method,
            label,
            group,
            wait_for_ready,
        } = new;
        let name = scenario.unwrap_or_else(|| "training".to_string());
        let scenario = Scenario::resolve(&name).ok_or(CreateError::UnknownScenario(name))?;
        self.check_caps(&self.map(), client)?;
        self.recorder.admit().map_err(CreateError::Recording)?;
        let models = [self.magnum.clone(), self.magnum.clone()];
        let id = random_hex(8);
        let mut live = Live::new(
            &id,
            &models,
            &scenario,
            mode,
            method,
            random_seed(),
            Some(self.pass_board.clone()),
        )
        .map_err(|e| CreateError::Sim(e.to_string()))?;
        live.keep_checkpoints(self.checkpoints.clone());
        live.wait_for_ready(wait_for_ready);
        self.launch(client, id, live, label, group)
    }

    /// Creates a session for `client` whose first attempt continues `state` as a practice
    /// attempt recorded with `init` ([`Live::taking_over`]; "take over from here"), for the
    /// trainee `label` of `group`; the same caps as [`SessionManager::create`].
    pub fn create_taking_over(
        &self,
        client: ClientKey,
        state: Live,
        init: &command::log::Init,
        label: &str,
        group: &str,
    ) -> Result<Arc<Session>, CreateError> {
        self.check_caps(&self.map(), client)?;
        self.recorder.admit().map_err(CreateError::Recording)?;
        let id = random_hex(8);
        let mut live = Live::taking_over(&id, state, init);
        // Its later attempts (a reset) start judged as any session's, and leave their
        // checkpoints (the practice attempt's replay log begins in its source's: none).
        live.pass_board = Some(self.pass_board.clone());
        live.keep_checkpoints(self.checkpoints.clone());
        self.launch(
            client,
            id,
            live,
            Some(label.to_string()),
            Some(group.to_string()),
        )
    }

    /// Adds session `id` running `live` (caps checked again under the lock), records its
    /// creation and starts stepping it.
    fn launch(
        &self,
        client: ClientKey,
        id: String,
        live: Live,
        label: Option<String>,
        group: Option<String>,
    ) -> Result<Arc<Session>, CreateError> {
        let models = live.models().clone();
        let scenario = live.scenario().name().to_string();
        let (frames, _) = watch::channel(None);
        let (notices, _) = tokio::sync::broadcast::channel(16);
        let label = crate::names::display_name(&label.unwrap_or_default());
        let group = crate::names::display_name(&group.unwrap_or_default());
        let session = Arc::new(Session {
            id,
            label,
            group,
            control_token: random_hex(16),
            created_unix: unix_now(),
            live: Mutex::new(live),
            frames,
            notices,
            trainees: AtomicU64::new(0),
            last_activity: AtomicU64::new(unix_now().to_bits()),
            ended: AtomicBool::new(false),
            end_reason: OnceLock::new(),
            overloads: AtomicU64::new(0),
            models,
            client,
            joined: AtomicBool::new(false),
            trainee_left: AtomicU64::new(0),
        });
        {
            let mut map = self.map();
            self.check_caps(&map, client)?;
            map.insert(session.id.clone(), session.clone());
        }
        self.recorder.send(RecordMsg::Created {
            id: session.id.clone(),
            label: session.label.clone(),
            group: session.group.clone(),
            scenario,
            created_unix: session.created_unix,
            token_sha256: sha256_hex(&session.control_token),
        });
        let w = self.next_worker.fetch_add(1, Ordering::Relaxed) as usize % self.workers.len();
        self.workers[w].add(session.clone());
        self.metrics
            .sessions_created
            .fetch_add(1, Ordering::Relaxed);
        self.metrics
            .sessions_live
            .store(self.map().len() as u64, Ordering::Relaxed);
        tracing::info!(id = %session.id, "session created");
        Ok(session)
    }

    /// The global cap and the per-client cap.
    fn check_caps(
        &self,
        map: &HashMap<String, Arc<Session>>,
        client: ClientKey,
    ) -> Result<(), CreateError> {
        if map.len() >= self.config.max_sessions {
            return Err(CreateError::Full(map.len()));
        }
        if client != ClientKey::Exempt {
            let mine = map.values().filter(|s| s.client == client).count();
            if mine >= self.config.max_sessions_per_client {
                return Err(CreateError::ClientFull(mine));
            }
        }
        Ok(())
    }

    /// A live session by id.
    pub fn get(&self, id: &str) -> Option<Arc<Session>> {
        self.map().get(id).cloned()
    }

    /// Every live session.
    pub fn all(&self) -> Vec<Arc<Session>> {
        let mut v: Vec<_> = self.map().values().cloned().collect();
        v.sort_by(|a, b| a.created_unix.total_cmp(&b.created_unix));
        v
    }

    /// Ends a session: stops stepping, records the end, tells clients.
    pub fn end(&self, id: &str, reason: EndReason) {
        let Some(session) = self.map().remove(id) else {
            return;
        };
        let _ = session.end_reason.set(reason);
        session.ended.store(true, Ordering::Relaxed);
        for w in &self.workers {
            w.remove(id);
        }
        let sim_seconds = {
            let mut live = session.live();
            live.end_attempt(match reason {
                EndReason::ServerShutdown => AttemptStop::Interrupted,
                _ => AttemptStop::Left,
            });
            for msg in live.take_records(false) {
                self.recorder.send(msg);
            }
            live.sim.time_s()
        };
        self.recorder.send(RecordMsg::Ended {
            id: id.to_string(),
            ended_unix: unix_now(),
            sim_seconds,
            reason: reason.text().to_string(),
            overloads: session.overloads.load(Ordering::Relaxed),
        });
        // Waking every client's writer: it sees `ended` and sends the `ended` message with
        // `end_reason`, then the close frame.
        session.frames.send_modify(|_| {});
        self.metrics
            .sessions_live
            .store(self.map().len() as u64, Ordering::Relaxed);
        tracing::info!(%id, reason = reason.text(), "session ended");
    }

    /// Ends sessions no trainee joined within the grace period, joined sessions whose
    /// trainee left (no trainee connection for the abandon grace), and sessions whose trainee
    /// gave no input for the idle timeout, connected or not.
    pub fn expire_idle(&self) {
        let limit = self.config.idle_timeout.as_secs_f64();
        let unjoined = self.config.unjoined_grace.as_secs_f64();
        let abandon = self.config.abandon_grace;
        for s in self.all() {
            let connected = s.trainees.load(Ordering::Relaxed) != 0;
            let joined = s.joined.load(Ordering::Relaxed);
            if !joined && s.age_seconds() > unjoined {
                self.end(&s.id, EndReason::NoTraineeJoined);
            } else if joined && !connected && s.seconds_since_trainee_left() > abandon.as_secs_f64()
            {
                let grace_s = abandon.as_secs();
                self.end(&s.id, EndReason::Abandoned { grace_s });
            } else if s.idle_seconds() > limit {
                self.end(&s.id, EndReason::IdleTimeout);
            }
        }
    }

    /// How often [`SessionManager::expire_idle`] should run: a quarter of the shortest of
    /// the idle timeout and the grace periods, between 0.25 s and 5 s.
    pub fn expiry_interval(&self) -> Duration {
        let shortest = self
            .config
            .idle_timeout
            .min(self.config.unjoined_grace)
            .min(self.config.abandon_grace);
        (shortest / 4).clamp(Duration::from_millis(250), Duration::from_secs(5))
    }

    /// Ends every session (graceful shutdown) and flushes the recorder.
    pub fn shutdown(&self) {
        for s in self.all() {
            self.end(&s.id, EndReason::ServerShutdown);
        }
        for w in &self.workers {
            w.stop();
        }
        self.recorder.shutdown();
    }
}
