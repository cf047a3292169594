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

use seaarms_core::sim::{Arm, Event};
use serde_json::json;

use super::record::{EventRecord, RecordMsg, RecordSender, SessionRow};
use super::snapshot::build_frame;
use super::{Frame, Live, Session};
use crate::metrics::Metrics;
use crate::protocol::{ServerMessage, arm_name, grasp_name};

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
    if live.clock_stopped() {
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
    /// One 1 ms step of the session: the core's operator turns the latest commands into the
    /// simulation's input and the simulation steps ([`seaarms_core::sim::Operator::step`]);
    /// the step's events go to the records ([`Live::record_events`]); every
    /// [`RECORD_EVERY_STEPS`] steps the exercise attempt takes an assessment sample; a live
    /// session's attempt leaves its replay checkpoints ([`Live::deposit_checkpoint`]).
    /// Returns whether a record row is due (the same cadence). The real-time worker,
    /// headless attempts and replays all step through here.
    pub fn advance(&mut self) -> bool {
        self.operator.step(&mut self.sim);
        self.record_events();
        let due = self.sim.steps() % RECORD_EVERY_STEPS == 0;
        if due {
            let idle = self.idle();
            if let Some(run) = self.exercise.as_mut() {
                run.sample(&mut self.sim, idle);
            }
        }
        self.deposit_checkpoint();
        due
    }

    /// The last step's events for the records (only while recording): grasp changes, slip
    /// onsets and slide-outs at once, with the step's time; relief openings and end stops
    /// tallied and recorded once per record row ([`EventTally`]; a relief valve at its
    /// setting can open and close every millisecond).
    fn record_events(&mut self) {
        if !self.recording || self.sim.events().is_empty() {
            return;
        }
        for i in 0..self.sim.events().len() {
            let e = self.sim.events()[i];
            let (kind, detail) = match e {
                Event::Grasp(state) => ("grasp", json!({"state": grasp_name(state)})),
                Event::Slip { arm, load_fraction } => (
                    "slip",
                    json!({"arm": arm_name(arm), "load_fraction": load_fraction}),
                ),
                Event::SlidOut { arm } => ("slid_out", json!({"arm": arm_name(arm)})),
                Event::Strike { arm, strike } => (
                    "strike",
                    json!({
                        "arm": arm_name(arm),
                        "partner": strike.partner.as_str(),
                        "part": super::snapshot::part_name(strike.part),
                        "point_m": strike.point_m,
                        "t": strike.time_s,
                        "impact_speed_m_s": strike.impact_speed_m_s,
                        "peak_force_n": strike.peak_force_n,
                    }),
                ),
                Event::Relief { arm, actuator } => {
                    self.tally.relief += 1;
                    self.tally.relief_first.get_or_insert((arm, actuator));
                    continue;
                }
                Event::EndStop { arm, joint } => {
                    self.tally.end_stops += 1;
                    self.tally.end_stop_first.get_or_insert((arm, joint));
                    continue;
                }
            };
            let record = self.event(kind, detail);
            self.pending.push(RecordMsg::Event(record));
        }
    }
}

/// Relief openings and end stops since the last record row: recorded as at most one
/// `relief` and one `end_stop` event per row, with the first one's arm and joint.
#[derive(Debug, Clone, Copy, Default)]
pub struct EventTally {
    /// Relief openings since the last row.
    relief: u64,
    /// The first of them: arm and actuator.
    relief_first: Option<(Arm, usize)>,
    /// End stops reached since the last row.
    end_stops: u64,
    /// The first of them: arm and joint.
    end_stop_first: Option<(Arm, usize)>,
}

fn record_row(session: &Session, live: &mut Live, recorder: &RecordSender) {
    let piece = live.sim.steps() % ATTEMPT_PIECE_STEPS == 0;
    for msg in live.take_records(piece) {
        recorder.send(msg);
    }
    let sim = &live.sim;
    let row = Box::new(SessionRow::from_sim(sim, &live.attempt_id));
    let tally = std::mem::take(&mut live.tally);
    if let Some((arm, joint)) = tally.relief_first {
        session.overloads.fetch_add(tally.relief, Ordering::Relaxed);
        recorder.send(RecordMsg::Event(live.event(
            "relief",
            json!({"count": live.sim.relief_events(), "arm": arm_name(arm), "joint": joint}),
        )));
    }
    if let Some((arm, joint)) = tally.end_stop_first {
        recorder.send(RecordMsg::Event(live.event(
            "end_stop",
            json!({"arm": arm_name(arm), "joint": joint, "count": tally.end_stops}),
        )));
    }
    if let Some(run) = live.exercise.as_mut() {
        // Slips and relief openings are recorded from the step's events above; the
        // attempt's own notices of them (for the trainee's banner) are not recorded twice.
        for e in run
            .take_events()
            .into_iter()
            .filter(|e| !matches!(e.kind, "slip" | "relief"))
        {
            recorder.send(RecordMsg::Event(Box::new(EventRecord {
                session: live.session_id.clone(),
                attempt: Some(live.attempt_id.clone()),
                t: e.t,
                kind: "exercise".into(),
                actor: None,
                detail: json!({"kind": e.kind, "text": e.text}),
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
}
