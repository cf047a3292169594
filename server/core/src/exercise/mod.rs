//! Training exercises: a goal, ordered steps with completion conditions, a time limit, pass
//! criteria and a score, all from the exercise file; the attempt is judged from the
//! simulation itself.
//!
//! # Layout
//! * `spec`: [`ExerciseSpec`], the file format, and the scene's simulation parameters.
//! * `condition`: [`Condition`], when a step is done, its progress and readouts.
//! * `assess`: [`Metrics`] sampled at 100 Hz ([`Assessor`]), the score and pass limits.
//! * `smoothness`: LDLJ, SPARC and the path ratio of the tool's movements, and the
//!   segmentation into movements ([`smoothness::MovementMeter`]).
//! * `autopilot`: [`Autopilot`], the file's script worked through the trainee's controls.
//! * `proficiency`: benchmarks from reference operators, the learning and relapse CUSUMs, a
//!   trainee's state on an exercise.
//! * `progression`: which exercises require which ([`ExerciseSpec::requires`]): the set's
//!   check (known ids, no cycles) and what still locks an exercise for a trainee.
//! * here: [`ExerciseRun`], one attempt: step progress, the fault drill, the verdict.
//!
//! The caller steps the simulation and calls [`ExerciseRun::sample`] every
//! [`assess::SAMPLE_INTERVAL_S`] of simulated time; nothing here reads a clock.

pub mod assess;
pub mod autopilot;
pub mod condition;
pub mod proficiency;
pub mod progression;
pub mod smoothness;
pub mod spec;

pub use assess::{Assessor, Event, JerkMeter, Metrics};
pub use autopilot::{Action, Autopilot, PilotOutput};
pub use condition::{Condition, Facts, Readout};
pub use spec::ExerciseSpec;

use serde::Serialize;
use std::sync::Arc;

use crate::hydraulics::{Fault, FaultKind};
use crate::sim::{Arm, Simulation};

/// The drill's draw: splitmix64 (Steele, Lea & Flood 2014), so an attempt's fault and its
/// time follow from its seed alone.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn unit(state: &mut u64) -> f64 {
    (splitmix64(state) >> 11) as f64 / (1u64 << 53) as f64
}

/// Counters shown on the page (for banners).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Counters {
    /// Seabed and obstacle strikes.
    pub strikes: f64,
    /// Drops.
    pub drops: f64,
    /// Jaw overloads.
    pub overloads: f64,
    /// Relief events.
    pub relief: f64,
    /// Joint-limit hits.
    pub limit_hits: f64,
    /// Slips of a jaw's load.
    pub slips: f64,
}

/// The attempt's state for the task panel (the state frame's `exercise`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Status {
    /// Exercise id.
    pub id: String,
    /// Index of the current step (= `steps` when all are done).
    pub step: usize,
    /// Number of steps.
    pub steps: usize,
    /// The current step's text ("" when done).
    pub step_text: String,
    /// Overall progress in [0, 1].
    pub progress: f64,
    /// Simulated seconds since the start.
    pub elapsed_s: f64,
    /// Time limit (s).
    pub time_limit_s: f64,
    /// Finished (completed, failed or out of time).
    pub done: bool,
    /// Passed (false until done).
    pub passed: bool,
    /// Score so far (final when done).
    pub score: f64,
    /// Readouts of the current step.
    pub readouts: Vec<Readout>,
    /// Counters.
    pub counters: Counters,
    /// What each penalised metric costs so far (points, largest first; [`assess::costs`]).
    pub costs: Vec<assess::Cost>,
    /// The latest counted event.
    pub last_event: Option<Event>,
}

/// The diagnosis given in a fault drill.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnosisOut {
    /// The trainee's answer (empty when none was given).
    pub answer: String,
    /// The injected fault's name.
    pub fault: String,
    /// Simulated time of the injection (s since the start).
    pub injected_at_s: f64,
    /// The answer names the fault.
    pub correct: bool,
}

/// The assessment of an attempt.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Assessment {
    /// Exercise id.
    pub exercise: String,
    /// Exercise version.
    pub version: u32,
    /// Seed of the attempt's random draws.
    pub seed: u64,
    /// Every step done within the time limit.
    pub completed: bool,
    /// Passed (see [`assess`]).
    pub passed: bool,
    /// The attempt has finished.
    pub done: bool,
    /// Score 0–100.
    pub score: f64,
    /// Time of each completed step from the start of that step (s).
    pub step_times_s: Vec<f64>,
    /// Number of steps.
    pub steps_total: usize,
    /// Every metric.
    #[serde(flatten)]
    pub metrics: Metrics,
    /// Scoring terms as applied.
    pub terms: Vec<assess::TermScore>,
    /// Pass limits as checked.
    pub limits: Vec<assess::LimitCheck>,
    /// The fault drill's verdict.
    pub diagnosis: Option<DiagnosisOut>,
    /// Why it did not pass (empty when it passed or is still running).
    pub failed_because: Vec<String>,
    /// The pass marks it is judged by.
    pub pass_marks: PassMarksOut,
}

/// The pass marks an attempt is judged by ([`spec::PassSpec`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassMarksOut {
    /// `fixed` (the file's `min_score`) or `benchmark` (the reference operators' lines).
    pub kind: &'static str,
    /// The file's pass mark (the one that applies when `kind` is `fixed`).
    pub min_score: f64,
    /// The benchmark's lines (when `kind` is `benchmark`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub benchmark: Option<proficiency::PassLines>,
    /// Why the file's mark applies although the exercise asks for the benchmark.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One attempt at an exercise.
#[derive(Debug, Clone)]
pub struct ExerciseRun {
    spec: Arc<ExerciseSpec>,
    seed: u64,
    start_s: f64,
    rest_z_m: f64,
    step: usize,
    step_started_s: f64,
    hold_since: Option<f64>,
    step_times: Vec<f64>,
    done: bool,
    drill: Option<(f64, Fault)>,
    fault_injected: bool,
    /// The drill's window has ended ([`Condition::FaultWindowOver`]).
    fault_window_over: bool,
    answer: Option<String>,
    assessor: Assessor,
    last_event: Option<Event>,
    events: Vec<Event>,
    /// The benchmark's pass lines, when the exercise's marks are `benchmark` and it applied
    /// at the start ([`Self::set_pass_lines`]).
    pass_lines: Option<proficiency::PassLines>,
}

impl ExerciseRun {
    /// Starts an attempt on `sim` as it is now (normally just reset); `seed` draws the
    /// drill's fault and time.
    pub fn new(spec: Arc<ExerciseSpec>, sim: &Simulation, seed: u64) -> ExerciseRun {
        let mut state = seed;
        let drill = spec.fault_drill.as_ref().map(|d| {
            let at = d.window_s[0] + unit(&mut state) * (d.window_s[1] - d.window_s[0]);
            let k = ((unit(&mut state) * d.choices.len() as f64) as usize).min(d.choices.len() - 1);
            (at, d.choices[k])
        });
        ExerciseRun {
            assessor: Assessor::new(&spec, sim),
            rest_z_m: sim.object().pose.translation.z,
            start_s: sim.time_s(),
            step_started_s: sim.time_s(),
            seed,
            step: 0,
            hold_since: None,
            step_times: Vec::new(),
            done: false,
            drill,
            fault_injected: false,
            fault_window_over: false,
            answer: None,
            last_event: None,
            events: Vec::new(),
            pass_lines: None,
            spec,
        }
    }

    /// Judges the attempt by the reference operators' benchmark `lines` (the benchmark as it
    /// stands at the attempt's start; None: it does not apply). Ignored unless the exercise's
    /// `pass.marks` is `benchmark`.
    pub fn set_pass_lines(&mut self, lines: Option<proficiency::PassLines>) {
        self.pass_lines = lines.filter(|_| self.spec.pass.marks == spec::PassMarks::Benchmark);
    }

    /// The benchmark's pass lines this attempt is judged by ([`Self::set_pass_lines`]).
    pub fn pass_lines(&self) -> Option<&proficiency::PassLines> {
        self.pass_lines.as_ref()
    }

    /// The exercise.
    pub fn spec(&self) -> &Arc<ExerciseSpec> {
        &self.spec
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Finished.
    pub fn done(&self) -> bool {
        self.done
    }

    /// What conditions read besides the simulation.
    pub fn facts(&self) -> Facts<'_> {
        Facts {
            scene: &self.spec.scene,
            rest_z_m: self.rest_z_m,
            fault_window_over: self.fault_window_over,
            answer: self.answer.as_deref(),
        }
    }

    /// The drill's fault, once injected (for records; the trainee's page is not told).
    pub fn injected_fault(&self) -> Option<(Arm, Fault)> {
        let arm = self.spec.fault_drill.as_ref()?.arm;
        self.drill
            .filter(|_| self.fault_injected)
            .map(|(_, f)| (Arm::BOTH[arm.index()], f))
    }

    /// Records the trainee's diagnosis (the first one counts).
    pub fn diagnose(&mut self, answer: &str) -> Result<(), String> {
        if self.spec.fault_drill.is_none() {
            return Err("this exercise has no fault to diagnose".into());
        }
        if !FaultKind::NAMES.contains(&answer) {
            return Err(format!(
                "answer must be one of {}",
                FaultKind::NAMES.join(", ")
            ));
        }
        if self.answer.is_none() && !self.done {
            self.answer = Some(answer.to_string());
        }
        Ok(())
    }

    /// Counts an instructor intervention.
    pub fn intervention(&mut self) {
        if !self.done {
            self.assessor.metrics.interventions += 1.0;
        }
    }

    /// Events counted since the last call (for the record), oldest first.
    pub fn take_events(&mut self) -> Vec<Event> {
        std::mem::take(&mut self.events)
    }

    /// One assessment sample ([`assess::SAMPLE_INTERVAL_S`] after the last): injects the
    /// drill's fault when due, updates the metrics, advances the steps, ends the attempt on
    /// completion or at the time limit. `idle`: the trainee gave no input.
    pub fn sample(&mut self, sim: &mut Simulation, idle: bool) {
        if self.done {
            return;
        }
        let t = sim.time_s();
        let elapsed = t - self.start_s;
        if let (Some((at, fault)), false) = (self.drill, self.fault_injected) {
            if elapsed >= at {
                if let Some(d) = &self.spec.fault_drill {
                    fault.apply_to(sim.faults_mut(Arm::BOTH[d.arm.index()]));
                }
                self.fault_injected = true;
            }
        }
        if let Some(d) = &self.spec.fault_drill {
            self.fault_window_over = self.fault_injected && elapsed >= d.window_s[1];
        }
        let mut events = Vec::new();
        self.assessor.sample(sim, idle, &mut events);
        let facts = Facts {
            scene: &self.spec.scene,
            rest_z_m: self.rest_z_m,
            fault_window_over: self.fault_window_over,
            answer: self.answer.as_deref(),
        };
        // Steps whose condition already holds complete in the same sample, one after another.
        while let Some(step) = self.spec.steps.get(self.step) {
            if !step.done_when.evaluate(sim, &facts).met {
                self.hold_since = None;
                break;
            }
            let since = *self.hold_since.get_or_insert(t);
            if t - since + 1e-9 < step.hold_s {
                break;
            }
            self.step_times.push(t - self.step_started_s);
            events.push(Event {
                kind: "step",
                t,
                text: format!("Done: {}", step.text),
            });
            self.step += 1;
            self.step_started_s = t;
            self.hold_since = None;
        }
        self.assessor.metrics.steps_completed = self.step as f64;
        self.assessor.metrics.time_s = elapsed;
        if self.step >= self.spec.steps.len() || elapsed >= self.spec.time_limit_s {
            self.done = true;
            self.assessor.finish();
        }
        if let Some(e) = events.last() {
            self.last_event = Some(e.clone());
        }
        self.events.extend(events);
    }

    /// The task panel's view of the attempt.
    pub fn status(&self, sim: &Simulation) -> Status {
        let facts = self.facts();
        let steps = self.spec.steps.len();
        let (text, fraction, readouts) = match self.spec.steps.get(self.step) {
            Some(s) if !self.done => {
                let v = s.done_when.evaluate(sim, &facts);
                let hold = match (self.hold_since, s.hold_s > 0.0) {
                    (Some(since), true) => ((sim.time_s() - since) / s.hold_s).clamp(0.0, 1.0),
                    _ => 1.0,
                };
                let mut r = Vec::new();
                s.done_when.readouts(sim, &facts, &mut r);
                if s.hold_s > 0.0 {
                    r.push(Readout {
                        label: "Hold".into(),
                        value: self.hold_since.map_or(0.0, |h| sim.time_s() - h),
                        target: s.hold_s,
                        unit: "s",
                    });
                }
                (s.text.clone(), 0.99 * v.fraction * hold, r)
            }
            _ => (String::new(), 0.0, Vec::new()),
        };
        let a = self.assessment();
        let m = &a.metrics;
        Status {
            id: self.spec.id.clone(),
            step: self.step,
            steps,
            step_text: text,
            progress: ((self.step as f64 + fraction) / steps.max(1) as f64).clamp(0.0, 1.0),
            elapsed_s: m.time_s,
            time_limit_s: self.spec.time_limit_s,
            done: self.done,
            passed: a.passed,
            score: a.score,
            readouts,
            counters: Counters {
                strikes: m.seabed_strikes + m.obstacle_strikes,
                drops: m.drops,
                overloads: m.overloads,
                relief: m.relief_events,
                limit_hits: m.joint_limit_hits,
                slips: m.slips,
            },
            costs: assess::costs(&self.spec, m),
            last_event: self.last_event.clone(),
        }
    }

    fn pass_marks(&self) -> PassMarksOut {
        let benchmark_asked = self.spec.pass.marks == spec::PassMarks::Benchmark;
        PassMarksOut {
            kind: if self.pass_lines.is_some() {
                "benchmark"
            } else {
                "fixed"
            },
            min_score: self.spec.pass.min_score,
            benchmark: self.pass_lines.clone(),
            note: (benchmark_asked && self.pass_lines.is_none()).then(|| {
                format!(
                    "the benchmark needs {} reference attempts on each measure; until then the \
                     exercise's pass mark applies",
                    self.spec.proficiency.min_reference_attempts
                )
            }),
        }
    }

    /// The assessment (final once [`Self::done`]).
    pub fn assessment(&self) -> Assessment {
        let metrics = self.assessor.metrics;
        let (score, terms) = assess::score(&self.spec, &metrics);
        let limits = assess::limits(&self.spec, &metrics);
        let completed = self.step >= self.spec.steps.len();
        let diagnosis = self.drill.map(|(at, f)| DiagnosisOut {
            answer: self.answer.clone().unwrap_or_default(),
            fault: f.kind().name().to_string(),
            injected_at_s: at,
            correct: self.answer.as_deref() == Some(f.kind().name()),
        });
        let mut failed = Vec::new();
        if self.done {
            if !completed {
                failed.push(format!(
                    "{} of {} steps done in the {:.0} s time limit",
                    self.step,
                    self.spec.steps.len(),
                    self.spec.time_limit_s
                ));
            }
            match &self.pass_lines {
                Some(b) => {
                    for l in &b.lines {
                        let value = if l.metric == "score" {
                            score
                        } else {
                            metrics.get(&l.metric).unwrap_or(f64::NAN)
                        };
                        if !l.met_by(value) {
                            failed.push(format!(
                                "{} = {value:.2} is {} the benchmark line {:.2} (reference mean \
                                 {:.2} {} {} SD of {:.2}, {} attempts)",
                                l.metric,
                                if l.higher_is_better { "below" } else { "above" },
                                l.line,
                                l.mean,
                                if l.higher_is_better { "−" } else { "+" },
                                b.k,
                                l.sd,
                                b.reference_attempts
                            ));
                        }
                    }
                }
                None if score < self.spec.pass.min_score => failed.push(format!(
                    "score {score:.0} is below the pass mark {:.0}",
                    self.spec.pass.min_score
                )),
                None => {}
            }
            for l in limits.iter().filter(|l| !l.met) {
                failed.push(format!("{} = {} is outside its limit", l.metric, l.value));
            }
            if let Some(d) = diagnosis.as_ref().filter(|d| !d.correct) {
                failed.push(format!("the fault was {}, not `{}`", d.fault, d.answer));
            }
        }
        Assessment {
            exercise: self.spec.id.clone(),
            version: self.spec.version,
            seed: self.seed,
            completed,
            passed: self.done && failed.is_empty(),
            done: self.done,
            score,
            step_times_s: self.step_times.clone(),
            steps_total: self.spec.steps.len(),
            metrics,
            terms,
            limits,
            diagnosis,
            failed_because: failed,
            pass_marks: self.pass_marks(),
        }
    }
}
