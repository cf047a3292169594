//! Physics workers: OS threads (never the async reactor) that step their sessions at 1 kHz
//! of simulated time in real time and publish frames at the frame rate.
//!
//! Each worker wakes every millisecond, and for each of its sessions runs as many 1 ms steps
//! as the wall clock is ahead of the session's simulated clock (so the average rate is
//! exactly 1 kHz whatever the scheduler does), capped at [`MAX_CATCH_UP_STEPS`]; a larger
//! backlog is dropped and counted as a step overrun. A paused session's clock origin moves,
//! so resuming never causes a burst. Publishing a frame never waits on a client: the frame is
//! put on a `watch` channel and each connection sends whatever is latest when it can.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use seaarms_core::control::teleop::cartesian_to_joint_velocity;
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::Arm;

use super::record::{EventRecord, RecordMsg, RecordSender, SessionRow};
use super::snapshot::build_frame;
use super::{Frame, Live, Session};
use crate::metrics::Metrics;
use crate::protocol::{ControlMethod, ControlMode, ServerMessage, arm_name, grasp_name};

/// Most 1 ms steps one session may run in one wake-up to catch up (50 ms of simulated time).
pub const MAX_CATCH_UP_STEPS: u64 = 50;
/// Record rows every this many steps (100 Hz).
pub const RECORD_EVERY_STEPS: u64 = 10;
/// The attempt's input log goes to the recorder every this many steps (1 s: what a killed
/// server can lose).
pub const ATTEMPT_PIECE_STEPS: u64 = 1000;

/// Handle to one worker thread.
pub struct WorkerHandle {
    sessions: Arc<Mutex<Vec<Arc<Session>>>>,
    generation: Arc<AtomicU64>,
    stop: Arc<AtomicBool>,
    thread: Mutex<Option<JoinHandle<()>>>,
}

impl WorkerHandle {
    /// Starts stepping `session` on this worker.
    pub fn add(&self, session: Arc<Session>) {
        self.sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(session);
        self.generation.fetch_add(1, Ordering::Release);
    }

    /// Stops stepping the session `id` (no-op when not here).
    pub fn remove(&self, id: &str) {
        self.sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|s| s.id != id);
        self.generation.fetch_add(1, Ordering::Release);
    }

    /// Stops the thread and waits for it.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take() {
            let _ = t.join();
        }
    }
}

/// Spawns worker `index`.
pub fn spawn_worker(
    index: usize,
    recorder: RecordSender,
    metrics: Arc<Metrics>,
    frame_hz: u32,
) -> WorkerHandle {
    let sessions: Arc<Mutex<Vec<Arc<Session>>>> = Arc::default();
    let generation = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let frame_interval = Duration::from_secs_f64(1.0 / f64::from(frame_hz.clamp(10, 120)));
    let thread = {
        let (sessions, generation, stop) = (sessions.clone(), generation.clone(), stop.clone());
        std::thread::Builder::new()
            .name(format!("physics-{index}"))
            .spawn(move || {
                let mut local: Vec<Arc<Session>> = Vec::new();
                let mut seen = u64::MAX;
                let tick = Duration::from_millis(1);
                let mut next = Instant::now();
                while !stop.load(Ordering::Relaxed) {
                    let g = generation.load(Ordering::Acquire);
                    if g != seen {
                        local = sessions.lock().unwrap_or_else(|e| e.into_inner()).clone();
                        seen = g;
                    }
                    for s in &local {
                        step_session(s, &recorder, &metrics, frame_interval);
                    }
                    next += tick;
                    let now = Instant::now();
                    if next > now {
                        std::thread::sleep(next - now);
                    } else if now - next > Duration::from_millis(20) {
                        // The worker itself fell behind (machine overloaded): do not spiral.
                        next = now;
                    }
                }
            })
            .expect("spawning a physics thread")
    };
    WorkerHandle {
        sessions,
        generation,
        stop,
        thread: Mutex::new(Some(thread)),
    }
}

/// Runs the steps due for one session and publishes a frame when one is due.
pub fn step_session(
    session: &Session,
    recorder: &RecordSender,
    metrics: &Metrics,
    frame_interval: Duration,
) {
    let mut guard = session.live();
    let live: &mut Live = &mut guard;
    let now = Instant::now();
    if live.paused() {
        live.origin = now;
        live.steps_since_origin = 0;
    } else {
        let due = (now.duration_since(live.origin).as_micros() / 1000) as u64;
        let mut todo = due.saturating_sub(live.steps_since_origin);
        if todo > MAX_CATCH_UP_STEPS {
            metrics
                .step_overruns
                .fetch_add(todo - MAX_CATCH_UP_STEPS, Ordering::Relaxed);
            live.steps_since_origin = due - MAX_CATCH_UP_STEPS;
            todo = MAX_CATCH_UP_STEPS;
        }
        for _ in 0..todo {
            let row_due = live.advance();
            live.steps_since_origin += 1;
            metrics.steps.fetch_add(1, Ordering::Relaxed);
            if row_due {
                record_row(session, live, recorder);
            }
        }
    }
    if now >= live.next_frame {
        live.frame_seq += 1;
        let frame = build_frame(live);
        // Sized for a typical frame (≈ 5 KiB) so serialization does not keep reallocating.
        let mut buf = Vec::with_capacity(8 * 1024);
        match serde_json::to_writer(&mut buf, &ServerMessage::State(Box::new(frame)))
            .map(|()| String::from_utf8(buf).unwrap_or_default())
        {
            Ok(json) => {
                let seq = live.frame_seq;
                session.frames.send_replace(Some(Frame {
                    seq,
                    json: json.into(),
                }));
                metrics.frames_published.fetch_add(1, Ordering::Relaxed);
            }
            Err(e) => tracing::error!(id = %session.id, "frame serialization failed: {e}"),
        }
        live.next_frame += frame_interval;
        if live.next_frame < now {
            live.next_frame = now + frame_interval;
        }
    }
}

impl Live {
    /// One 1 ms step of the session: the latest commands become the simulation's input
    /// ([`Live::apply_control`]), the simulation steps, and every
    /// [`RECORD_EVERY_STEPS`] steps the exercise attempt takes an assessment sample.
    /// Returns whether a record row is due (the same cadence). The real-time worker and
    /// headless attempts both step through here.
    pub fn advance(&mut self) -> bool {
        self.apply_control();
        self.sim.step(&self.input);
        let due = self.sim.steps() % RECORD_EVERY_STEPS == 0;
        if due {
            let idle = self.idle();
            if let Some(run) = self.exercise.as_mut() {
                run.sample(&mut self.sim, idle);
            }
        }
        due
    }

    /// Turns the latest commands into the simulation's input for the next step: Cartesian
    /// sticks become joint-velocity references by redundancy resolution; the settings set
    /// the method and speed scale.
    fn apply_control(&mut self) {
        self.input.speed_scale = self.settings.arm_speed;
        self.input.method = match self.settings.control_method {
            ControlMethod::Open => seaarms_core::sim::ControlMethod::OpenLoop,
            ControlMethod::Closed => seaarms_core::sim::ControlMethod::ClosedLoop,
        };
        let releasing = self.sim.time_s() < self.release_until_s;
        // Both jaws on the box: its closed chain fixes the tools' orientation (teleop docs).
        let chain = self.sim.grasp_state() == GraspState::BothHolding;
        for arm in Arm::BOTH {
            let i = arm.index();
            if releasing {
                self.input.arms[i].jaw = 1.0;
            }
            self.input.arms[i].joint_velocity_ref = match self.settings.control_mode {
                ControlMode::Joint => None,
                ControlMode::Cartesian => Some(cartesian_to_joint_velocity(
                    &mut self.redundancy[i],
                    &self.models[i],
                    &self.sim.params().arms[i].base.rotation,
                    &self.sim.arm(arm).q,
                    &self.cartesian[i],
                    chain,
                    1e-3,
                )),
            };
        }
    }
}

fn record_row(session: &Session, live: &mut Live, recorder: &RecordSender) {
    let piece = live.sim.steps() % ATTEMPT_PIECE_STEPS == 0;
    for msg in live.take_records(piece) {
        recorder.send(msg);
    }
    let sim = &live.sim;
    let row = Box::new(SessionRow::from_sim(sim, &live.attempt_id));
    let grasp = sim.grasp_state();
    let relief = sim.relief_events();
    if relief > live.relief_recorded {
        session
            .overloads
            .fetch_add(relief - live.relief_recorded, Ordering::Relaxed);
        recorder.send(RecordMsg::Event(
            live.event("relief", serde_json::json!({"count": relief})),
        ));
    }
    live.relief_recorded = relief;
    grip_events(live, recorder);
    if let Some(run) = live.exercise.as_mut() {
        for e in run.take_events() {
            recorder.send(RecordMsg::Event(Box::new(EventRecord {
                session: live.session_id.clone(),
                attempt: Some(live.attempt_id.clone()),
                t: e.t,
                kind: "exercise".into(),
                actor: None,
                detail: serde_json::json!({"kind": e.kind, "text": e.text}),
            })));
        }
    }
    // A finished exercise ends its attempt there and then (outcome passed or failed), so its
    // debrief opens from the trainee's completion card; "try again" starts the next one.
    if live.log.is_some() && live.exercise.as_ref().is_some_and(|run| run.done()) {
        live.end_attempt(super::AttemptStop::Finished);
        for msg in live.take_records(false) {
            recorder.send(msg);
        }
    }
    recorder.send(RecordMsg::Row {
        id: session.id.clone(),
        row,
        overloads: session.overloads.load(Ordering::Relaxed),
    });
    if grasp != live.last_grasp {
        recorder.send(RecordMsg::Event(
            live.event("grasp", serde_json::json!({"state": grasp_name(grasp)})),
        ));
        live.last_grasp = grasp;
    }
}

/// `slip` events (a jaw's bar started slipping: `{"arm", "load_fraction"}`) and `drop` events
/// (the bar slid out of the jaw: `{"arm"}`), from the simulation's per-jaw counts.
fn grip_events(live: &mut Live, recorder: &RecordSender) {
    for arm in Arm::BOTH {
        let i = arm.index();
        let g = live.sim.arm(arm).grip;
        let (slips, drops) = live.grip_recorded[i];
        if g.slips > slips {
            recorder.send(RecordMsg::Event(live.event(
                "slip",
                serde_json::json!({"arm": arm_name(arm), "load_fraction": g.load_fraction}),
            )));
        }
        if g.drops > drops {
            recorder.send(RecordMsg::Event(
                live.event("drop", serde_json::json!({"arm": arm_name(arm)})),
            ));
        }
        live.grip_recorded[i] = (g.slips, g.drops);
    }
}
