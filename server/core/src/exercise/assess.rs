//! The assessment of an attempt, computed from the simulation itself at 100 Hz: counted events
//! (strikes, drops, overloads, relief, joint-limit hits, slips), peaks (contact and internal force),
//! smoothness (LDLJ and SPARC of the tool's movements, the path ratio of its reaches:
//! [`super::smoothness`]; the RMS tool jerk; the shipped exercises score SPARC), posture (mean
//! Yoshikawa measure and JLM of the working arms, time near a singularity or a joint limit) and
//! idle time; then the score.
//!
//! # Score
//! Each scoring term maps one metric linearly from its `bad` value (0) to its `good` value (1),
//! clamped to [0, 1]; the score is
//!
//! > score = 100 × (steps completed / steps) × Σ wₖ·sₖ / Σ wₖ
//!
//! (100 × the completed fraction when there are no terms), less [`SLIP_PENALTY_POINTS`] per
//! slip of a jaw's load (at most [`SLIP_PENALTY_MAX_POINTS`]), never below 0. An attempt
//! **passes** when every
//! step is completed within the time limit, the score is at least `pass.min_score`, every
//! `pass.limits` entry holds, and, in a fault drill, the named fault is the injected one.
//!
//! # Events
//! The sampler detects what depends on the exercise (its obstacles and thresholds): strikes
//! of the exercise's obstacles, jaw overloads, joint-limit hits (within `limit_hit_deg` of a
//! limit) and drops (the last jaw lets go of the box above the seabed, [`DROP_HEIGHT_M`]).
//! Slips, relief openings and strikes are detected once, by the step ([`crate::sim::Event`]);
//! the sampler counts them from the step's tallies ([`crate::sim::GripState::slips`],
//! [`Simulation::relief_events`], [`crate::sim::ArmContacts::strikes`]: the seabed's as
//! seabed strikes, the vehicle's and the other arm's as obstacle strikes; the box and the
//! panel are the work) and tells the trainee ([`Event`]) when they grow.

use nalgebra::Vector3;
use serde::Serialize;

use super::smoothness::{MovementMeter, SmoothnessTotals};
use super::spec::{ExerciseSpec, Obstacle, Thresholds};
use crate::kinematics::{KinData, forward_kinematics};
use crate::model::Model;
use crate::sim::measures::{arm_measures, near_limits};
use crate::sim::{Arm, Partner, Simulation};

/// Interval between assessment samples (s): 0.01 (100 Hz, the record rate).
pub const SAMPLE_INTERVAL_S: f64 = 0.01;
/// A box let go with its lowest corner higher than this above the seabed is dropped (m): 0.02.
pub const DROP_HEIGHT_M: f64 = 0.02;
/// Score points taken off per slip of a jaw's load (a slip onset, [`crate::sim::Event::Slip`]):
/// 5. A slip is the trainee's loss of control of the load (docs/exercises.md);
/// five of them cost a grade band, as five seabed strikes would in a term weighted 1 of 5.
pub const SLIP_PENALTY_POINTS: f64 = 5.0;
/// The most the slips can take off the score (points): 20, so that the score still ranks
/// attempts that slipped (a drop fails them by the `drops` limit anyway).
pub const SLIP_PENALTY_MAX_POINTS: f64 = 20.0;
/// Interval of the tool positions the jerk is computed from (s): 0.05. The third difference
/// over 50 ms passes the operator's motion (well under 5 Hz) and suppresses the hydraulic
/// resonances (≳ 20 Hz) that no operator causes or can feel through the sticks; over 10 ms
/// they dominate the figure.
pub const JERK_INTERVAL_S: f64 = 0.05;

/// Every metric of an attempt. All numbers are finite.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Metrics {
    /// Simulated time from start to completion, or to now / the time limit (s).
    pub time_s: f64,
    /// Steps completed.
    pub steps_completed: f64,
    /// Times an arm entered the seabed (any joint origin, link midpoint or the tool point
    /// below the seabed surface).
    pub seabed_strikes: f64,
    /// Times an arm entered an obstacle box.
    pub obstacle_strikes: f64,
    /// Times the last jaw let go of the box with its lowest corner over 2 cm above the seabed.
    pub drops: f64,
    /// Times a jaw's load started slipping (the step's slip onsets, [`crate::sim::Event::Slip`]).
    pub slips: f64,
    /// Time a jaw's load spent slipping (s).
    pub slip_s: f64,
    /// Highest load fraction of a jaw against its static friction limits (1 = at the limit).
    pub peak_grip_load: f64,
    /// Highest jaw contact force (N).
    pub peak_contact_force_n: f64,
    /// Highest internal force magnitude (N).
    pub peak_internal_force_n: f64,
    /// Times a jaw's contact force rose above the overload threshold.
    pub overloads: f64,
    /// Relief-valve openings (Lim's overload events).
    pub relief_events: f64,
    /// Times a joint came within the hit distance of its limit.
    pub joint_limit_hits: f64,
    /// RMS jerk of the working arms' tool points (m/s³). Reported, not a measure of skill:
    /// it grows with a movement's amplitude / duration³ (issue 30; [`super::smoothness`]).
    pub jerk_rms_m_s3: f64,
    /// Movements of the working arms' tools ([`super::smoothness`], "Segmentation").
    pub movements: f64,
    /// Mean SPARC (spectral arc length) of those movements' speed profiles (dimensionless,
    /// ≤ 0, nearer 0 smoother; a minimum-jerk reach ≈ −1.40); 0 before the first. The
    /// shipped exercises' smoothness term.
    pub sparc: f64,
    /// Mean LDLJ (log dimensionless jerk) of those movements' speed profiles (dimensionless,
    /// nearer 0 smoother; a minimum-jerk reach −5.32); 0 before the first. Reported only: the
    /// shipped exercises score [`Metrics::sparc`] ([`super::smoothness`], "In the score").
    pub ldlj: f64,
    /// Mean path length / straight-line distance of the reaches among those movements
    /// (≥ 1, 1 = straight); 0 before the first reach. Reported only, as [`Metrics::ldlj`].
    pub path_ratio: f64,
    /// Mean translational Yoshikawa measure of the working arms (m³/s-like, per unit joint rate).
    pub mean_yoshikawa: f64,
    /// Mean joint-limit measure (JLM, Jun eq. 16) of the working arms.
    pub mean_jlm: f64,
    /// Time a working arm spent near a singularity (s).
    pub near_singularity_s: f64,
    /// Time a working arm spent with a joint near its limit (s).
    pub near_limit_s: f64,
    /// Time with no stick or grip input (s).
    pub idle_s: f64,
    /// Instructor interventions (pause, reset, release, faults, scenario changes).
    pub interventions: f64,
    /// Times the hot stab's side load rose above its limit (panel scenes; 0 without).
    pub side_load_faults: f64,
    /// Highest side load on the hot-stab receptacle (N).
    pub peak_side_load_n: f64,
}

impl Metrics {
    /// A metric by its field name.
    pub fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "time_s" => self.time_s,
            "steps_completed" => self.steps_completed,
            "seabed_strikes" => self.seabed_strikes,
            "obstacle_strikes" => self.obstacle_strikes,
            "drops" => self.drops,
            "slips" => self.slips,
            "slip_s" => self.slip_s,
            "peak_grip_load" => self.peak_grip_load,
            "peak_contact_force_n" => self.peak_contact_force_n,
            "peak_internal_force_n" => self.peak_internal_force_n,
            "overloads" => self.overloads,
            "relief_events" => self.relief_events,
            "joint_limit_hits" => self.joint_limit_hits,
            "jerk_rms_m_s3" => self.jerk_rms_m_s3,
            "movements" => self.movements,
            "sparc" => self.sparc,
            "ldlj" => self.ldlj,
            "path_ratio" => self.path_ratio,
            "mean_yoshikawa" => self.mean_yoshikawa,
            "mean_jlm" => self.mean_jlm,
            "near_singularity_s" => self.near_singularity_s,
            "near_limit_s" => self.near_limit_s,
            "idle_s" => self.idle_s,
            "interventions" => self.interventions,
            "side_load_faults" => self.side_load_faults,
            "peak_side_load_n" => self.peak_side_load_n,
            _ => return None,
        })
    }
}

/// RMS jerk of a point sampled at a fixed interval, from the third backward difference of
/// position, j ≈ (x₃ − 3x₂ + 3x₁ − x₀)/Δt³ (exact for cubic motion).
#[derive(Debug, Clone, Default)]
pub struct JerkMeter {
    last: Vec<Vector3<f64>>,
    sum_sq: f64,
    count: u64,
}

impl JerkMeter {
    /// Adds a position sample taken `dt_s` after the previous one.
    pub fn add(&mut self, p: Vector3<f64>, dt_s: f64) {
        self.last.push(p);
        if self.last.len() > 4 {
            self.last.remove(0);
        }
        if self.last.len() == 4 {
            let [x0, x1, x2, x3] = [self.last[0], self.last[1], self.last[2], self.last[3]];
            let j = (x3 - 3.0 * x2 + 3.0 * x1 - x0) / dt_s.powi(3);
            if j.iter().all(|v| v.is_finite()) {
                self.sum_sq += j.norm_squared();
                self.count += 1;
            }
        }
    }

    /// Sum of squared jerk magnitudes and the number of jerk values so far.
    pub fn totals(&self) -> (f64, u64) {
        (self.sum_sq, self.count)
    }

    /// RMS jerk magnitude (m/s³), 0 before four samples.
    pub fn rms(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.sum_sq / self.count as f64).sqrt()
        }
    }
}

/// Points along an arm for strike tests: the origins of every joint frame, the midpoints
/// between consecutive ones, and the tool point (world frame).
pub fn arm_points(sim: &Simulation, arm: Arm, kin: &mut KinData, out: &mut Vec<Vector3<f64>>) {
    out.clear();
    let model = sim.model(arm);
    forward_kinematics(model, kin, &sim.arm(arm).q);
    let mut prev: Option<Vector3<f64>> = None;
    for f in &kin.joint_frames {
        let p = f.translation.vector;
        if let Some(a) = prev {
            out.push(0.5 * (a + p));
        }
        out.push(p);
        prev = Some(p);
    }
    let tool = sim.end_effector(arm).translation.vector;
    if let Some(a) = prev {
        out.push(0.5 * (a + tool));
    }
    out.push(tool);
}

/// Per joint: within `hit_deg` of a limit.
fn at_limits(model: &Model, q: &[f64; 6], hit_deg: f64) -> [bool; 6] {
    let d = hit_deg.to_radians();
    let mut out = [false; 6];
    for ((o, q), joint) in out.iter_mut().zip(q).zip(&model.joints) {
        *o = joint.is_limited() && (q - joint.limits[0] < d || joint.limits[1] - q < d);
    }
    out
}

fn inside(o: &Obstacle, p: &Vector3<f64>) -> bool {
    (0..3).all(|k| (p[k] - o.center_m[k]).abs() <= o.half_size_m[k])
}

/// A counted event, for banners and the record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// `strike`, `obstacle`, `drop`, `slip`, `overload`, `relief`, `limit`, `fault` or `step`.
    pub kind: &'static str,
    /// Simulated time (s).
    pub t: f64,
    /// What happened, for the trainee.
    pub text: String,
}

/// Accumulates the metrics of one attempt.
#[derive(Debug, Clone)]
pub struct Assessor {
    thresholds: Thresholds,
    working: Vec<usize>,
    obstacles: Vec<Obstacle>,
    kin: [KinData; 2],
    points: Vec<Vector3<f64>>,
    in_seabed: [bool; 2],
    /// The core's strike counts per arm and partner at the last sample.
    strikes_at_start: [[u64; 5]; 2],
    in_obstacle: [bool; 2],
    overloaded: [bool; 2],
    slips_at_start: [u64; 2],
    slips: [f64; 2],
    at_limit: [[bool; 6]; 2],
    was_holding: bool,
    relief_at_start: u64,
    side_faults_at_start: u64,
    jerk: [JerkMeter; 2],
    moves: [MovementMeter; 2],
    smooth: SmoothnessTotals,
    samples: u64,
    posture_samples: f64,
    yoshikawa_sum: f64,
    jlm_sum: f64,
    /// The metrics so far.
    pub metrics: Metrics,
}

impl Assessor {
    /// Starts assessing `sim` as it is now for `spec`.
    pub fn new(spec: &ExerciseSpec, sim: &Simulation) -> Assessor {
        Assessor {
            thresholds: spec.thresholds,
            working: spec.control.arm.indices().to_vec(),
            obstacles: spec.scene.obstacles.clone(),
            kin: [
                KinData::new(sim.model(Arm::Left)),
                KinData::new(sim.model(Arm::Right)),
            ],
            points: Vec::with_capacity(32),
            in_seabed: [false; 2],
            strikes_at_start: Arm::BOTH.map(|a| sim.contacts().arms[a.index()].strikes),
            in_obstacle: [false; 2],
            overloaded: [false; 2],
            slips_at_start: Arm::BOTH.map(|a| sim.arm(a).grip.slips),
            slips: [0.0; 2],
            // A joint that starts at a limit (the scene's posture) has not hit it.
            at_limit: Arm::BOTH
                .map(|a| at_limits(sim.model(a), &sim.arm(a).q, spec.thresholds.limit_hit_deg)),
            was_holding: false,
            relief_at_start: sim.relief_events(),
            side_faults_at_start: sim.panel().map_or(0, |p| p.side_load_faults),
            jerk: Default::default(),
            moves: Default::default(),
            smooth: SmoothnessTotals::default(),
            samples: 0,
            posture_samples: 0.0,
            yoshikawa_sum: 0.0,
            jlm_sum: 0.0,
            metrics: Metrics::default(),
        }
    }

    /// Takes one sample, [`SAMPLE_INTERVAL_S`] after the last; `idle` says the trainee gave no
    /// input. Pushes the events counted in this sample to `events`.
    pub fn sample(&mut self, sim: &Simulation, idle: bool, events: &mut Vec<Event>) {
        let dt = SAMPLE_INTERVAL_S;
        let t = sim.time_s();
        let th = self.thresholds;
        let m = &mut self.metrics;
        let seabed = sim.params().object.seabed_z_m;
        for arm in Arm::BOTH {
            let i = arm.index();
            arm_points(sim, arm, &mut self.kin[i], &mut self.points);
            // Strikes on the seabed, the vehicle and the other arm: the core's (counted per
            // partner at first contact, `sim::Event::Strike`); with contacts off, a point of
            // the arm going below the seabed plane.
            let contacts = &sim.contacts().arms[i];
            let new_strikes = |p: Partner, at_start: &[[u64; 5]; 2]| {
                contacts.strikes[p.index()].saturating_sub(at_start[i][p.index()])
            };
            let speed = contacts.last_strike.map_or(0.0, |s| s.impact_speed_m_s);
            let below = !sim.params().contact.enabled && self.points.iter().any(|p| p.z < seabed);
            let seabed_now = new_strikes(Partner::Seabed, &self.strikes_at_start) as f64
                + f64::from(below && !self.in_seabed[i]);
            if seabed_now > 0.0 {
                m.seabed_strikes += seabed_now;
                events.push(Event {
                    kind: "strike",
                    t,
                    text: format!("{} arm struck the seabed at {speed:.2} m/s", side(arm)),
                });
            }
            self.in_seabed[i] = below;
            for p in [Partner::Vehicle, Partner::OtherArm] {
                if new_strikes(p, &self.strikes_at_start) > 0 {
                    m.obstacle_strikes += new_strikes(p, &self.strikes_at_start) as f64;
                    let what = if p == Partner::Vehicle {
                        "the vehicle"
                    } else {
                        "the other arm"
                    };
                    events.push(Event {
                        kind: "obstacle",
                        t,
                        text: format!("{} arm struck {what} at {speed:.2} m/s", side(arm)),
                    });
                }
            }
            self.strikes_at_start[i] = contacts.strikes;
            let hit = self
                .points
                .iter()
                .any(|p| self.obstacles.iter().any(|o| inside(o, p)));
            if hit && !self.in_obstacle[i] {
                m.obstacle_strikes += 1.0;
                events.push(Event {
                    kind: "obstacle",
                    t,
                    text: format!("{} arm struck an obstacle", side(arm)),
                });
            }
            self.in_obstacle[i] = hit;
            let st = sim.arm(arm);
            let f = Vector3::new(
                st.contact_wrench[0],
                st.contact_wrench[1],
                st.contact_wrench[2],
            )
            .norm();
            m.peak_contact_force_n = m.peak_contact_force_n.max(f);
            let over = f > th.overload_force_n;
            if over && !self.overloaded[i] {
                m.overloads += 1.0;
                events.push(Event {
                    kind: "overload",
                    t,
                    text: format!("{} jaw overloaded: {:.0} N", side(arm), f),
                });
            }
            self.overloaded[i] = over;
            m.peak_grip_load = m.peak_grip_load.max(st.grip.load_fraction);
            let slips = st.grip.slips.saturating_sub(self.slips_at_start[i]) as f64;
            if slips > self.slips[i] {
                events.push(Event {
                    kind: "slip",
                    t,
                    text: format!(
                        "{} jaw: the load is slipping: it pulls harder than the grip's \
                         friction can hold (−{SLIP_PENALTY_POINTS:.0} points)",
                        side(arm),
                    ),
                });
            }
            self.slips[i] = slips;
            if st.grip.slipping {
                m.slip_s += dt;
            }
            let model = sim.model(arm);
            let at = at_limits(model, &st.q, th.limit_hit_deg);
            for (k, &hit_now) in at.iter().enumerate() {
                if hit_now && !self.at_limit[i][k] {
                    m.joint_limit_hits += 1.0;
                    events.push(Event {
                        kind: "limit",
                        t,
                        text: format!("{} joint {} at its limit", side(arm), k + 1),
                    });
                }
                self.at_limit[i][k] = hit_now;
            }
        }
        m.slips = self.slips[0] + self.slips[1];
        let w = sim.internal_wrench();
        m.peak_internal_force_n = m
            .peak_internal_force_n
            .max(Vector3::new(w[0], w[1], w[2]).norm());
        let holding = Arm::BOTH.iter().any(|&a| sim.arm(a).holding);
        // A drop: the last jaw lets go with the box's lowest corner more than
        // DROP_HEIGHT_M above the seabed (it falls); a box set down, even on an edge, is not.
        let pose = sim.object().pose;
        let lowest = sim
            .params()
            .object
            .corners()
            .iter()
            .map(|c| (pose * nalgebra::Point3::from(*c)).z)
            .fold(f64::INFINITY, f64::min);
        if self.was_holding && !holding && lowest - seabed > DROP_HEIGHT_M {
            m.drops += 1.0;
            events.push(Event {
                kind: "drop",
                t,
                text: "The box was dropped".into(),
            });
        }
        self.was_holding = holding;
        let relief = sim.relief_events().saturating_sub(self.relief_at_start) as f64;
        if relief > m.relief_events {
            events.push(Event {
                kind: "relief",
                t,
                text: "Relief valve opened: the arm is overloaded".into(),
            });
        }
        m.relief_events = relief;
        if let Some(p) = sim.panel() {
            let faults = p.side_load_faults.saturating_sub(self.side_faults_at_start) as f64;
            if faults > m.side_load_faults {
                events.push(Event {
                    kind: "overload",
                    t,
                    text: "Side load on the hot stab over its limit".into(),
                });
            }
            m.side_load_faults = faults;
            m.peak_side_load_n = m.peak_side_load_n.max(p.side_load_n);
        }
        let (mut near_s, mut near_l) = (false, false);
        let every = (JERK_INTERVAL_S / dt).round().max(1.0) as u64;
        let jerk_sample = self.samples % every == 0;
        self.samples += 1;
        for &i in &self.working {
            let arm = Arm::BOTH[i];
            let tool = sim.end_effector(arm).translation.vector;
            if jerk_sample {
                self.jerk[i].add(tool, JERK_INTERVAL_S);
            }
            if let Some(mv) = self.moves[i].add(tool, dt) {
                self.smooth.add(&mv);
            }
            let me = arm_measures(sim, arm);
            let q = sim.arm(arm).q;
            self.yoshikawa_sum += me.translational.yoshikawa;
            self.jlm_sum += me.jlm;
            self.posture_samples += 1.0;
            near_s |= me.translational.isotropy < th.singular_isotropy;
            near_l |= near_limits(sim.model(arm), &q, th.near_limit_fraction)
                .iter()
                .any(|b| *b);
        }
        if near_s {
            m.near_singularity_s += dt;
        }
        if near_l {
            m.near_limit_s += dt;
        }
        if idle {
            m.idle_s += dt;
        }
        let (s, n) = self
            .jerk
            .iter()
            .map(JerkMeter::totals)
            .fold((0.0, 0), |(a, b), (c, d)| (a + c, b + d));
        m.jerk_rms_m_s3 = if n == 0 { 0.0 } else { (s / n as f64).sqrt() };
        if self.posture_samples > 0.0 {
            m.mean_yoshikawa = self.yoshikawa_sum / self.posture_samples;
            m.mean_jlm = self.jlm_sum / self.posture_samples;
        }
        self.write_smoothness();
    }
}

impl Assessor {
    /// Ends the attempt's assessment: measures the working arms' movements still open (the
    /// tool may still be moving as the last step completes).
    pub fn finish(&mut self) {
        for &i in &self.working {
            if let Some(mv) = self.moves[i].finish(SAMPLE_INTERVAL_S) {
                self.smooth.add(&mv);
            }
        }
        self.write_smoothness();
    }

    fn write_smoothness(&mut self) {
        let m = &mut self.metrics;
        m.movements = f64::from(self.smooth.movements);
        m.sparc = self.smooth.mean_sparc();
        m.ldlj = self.smooth.mean_ldlj();
        m.path_ratio = self.smooth.mean_path_ratio();
    }
}

fn side(arm: Arm) -> &'static str {
    match arm {
        Arm::Left => "Left",
        Arm::Right => "Right",
    }
}

/// One scoring term as applied.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TermScore {
    /// Metric.
    pub metric: String,
    /// Its value.
    pub value: f64,
    /// Value scoring 1.
    pub good: f64,
    /// Value scoring 0.
    pub bad: f64,
    /// Weight.
    pub weight: f64,
    /// Sub-score in [0, 1].
    pub score: f64,
}

/// One pass limit as checked.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LimitCheck {
    /// Metric.
    pub metric: String,
    /// Its value.
    pub value: f64,
    /// Most allowed.
    pub max: Option<f64>,
    /// Least allowed.
    pub min: Option<f64>,
    /// Met.
    pub met: bool,
}

/// The score (0–100) and its terms, per the module docs.
pub fn score(spec: &ExerciseSpec, metrics: &Metrics) -> (f64, Vec<TermScore>) {
    let terms: Vec<TermScore> = spec
        .scoring
        .iter()
        .map(|t| {
            let value = metrics.get(&t.metric).unwrap_or(0.0);
            let s = ((value - t.bad) / (t.good - t.bad)).clamp(0.0, 1.0);
            TermScore {
                metric: t.metric.clone(),
                value,
                good: t.good,
                bad: t.bad,
                weight: t.weight,
                score: if s.is_finite() { s } else { 0.0 },
            }
        })
        .collect();
    let total_w: f64 = terms.iter().map(|t| t.weight).sum();
    let weighted = if total_w > 0.0 {
        terms.iter().map(|t| t.weight * t.score).sum::<f64>() / total_w
    } else {
        1.0
    };
    let completed = metrics.steps_completed / spec.steps.len().max(1) as f64;
    let penalty = (SLIP_PENALTY_POINTS * metrics.slips).min(SLIP_PENALTY_MAX_POINTS);
    (
        (100.0 * completed.clamp(0.0, 1.0) * weighted - penalty).max(0.0),
        terms,
    )
}

/// What each penalised metric costs so far (points), largest first: per scoring term the
/// points it takes off a completed attempt's score, 100 × wₖ·(1 − sₖ)/Σw (its share of the
/// weighted sum, [`score`]), and the slips' penalty ([`SLIP_PENALTY_POINTS`] each, at most
/// [`SLIP_PENALTY_MAX_POINTS`]) as metric `slips`; only costs of at least 0.5 points.
pub fn costs(spec: &ExerciseSpec, metrics: &Metrics) -> Vec<Cost> {
    let (_, terms) = score(spec, metrics);
    let total_w: f64 = terms.iter().map(|t| t.weight).sum();
    let mut out: Vec<Cost> = terms
        .iter()
        .filter(|_| total_w > 0.0)
        .map(|t| Cost {
            metric: t.metric.clone(),
            value: t.value,
            points: 100.0 * t.weight * (1.0 - t.score) / total_w,
        })
        .collect();
    out.push(Cost {
        metric: "slips".into(),
        value: metrics.slips,
        points: (SLIP_PENALTY_POINTS * metrics.slips).min(SLIP_PENALTY_MAX_POINTS),
    });
    out.retain(|c| c.points >= 0.5 && c.points.is_finite());
    out.sort_by(|a, b| b.points.total_cmp(&a.points));
    out
}

/// A penalised metric's cost ([`costs`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cost {
    /// The metric (a scoring term's, or `slips`).
    pub metric: String,
    /// Its value now.
    pub value: f64,
    /// Points it takes off the score.
    pub points: f64,
}

/// The pass limits of `spec` checked against `metrics`.
pub fn limits(spec: &ExerciseSpec, metrics: &Metrics) -> Vec<LimitCheck> {
    spec.pass
        .limits
        .iter()
        .map(|l| {
            let value = metrics.get(&l.metric).unwrap_or(0.0);
            LimitCheck {
                metric: l.metric.clone(),
                value,
                max: l.max,
                min: l.min,
                met: l.max.is_none_or(|m| value <= m) && l.min.is_none_or(|m| value >= m),
            }
        })
        .collect()
}

#[cfg(test)]
mod metric_tests {
    use super::*;

    /// Known jerk profile: x(t) = c·t³/6 has jerk c everywhere, and the third difference is
    /// exact for cubics; a constant-velocity motion has zero jerk.
    #[test]
    fn jerk_of_a_cubic_is_its_constant() {
        let c = 7.5;
        let mut m = JerkMeter::default();
        let mut still = JerkMeter::default();
        for k in 0..40 {
            let t = k as f64 * JERK_INTERVAL_S;
            m.add(Vector3::new(c * t.powi(3) / 6.0, 0.0, 0.0), JERK_INTERVAL_S);
            still.add(Vector3::new(0.3 * t, -0.1 * t, 0.0), JERK_INTERVAL_S);
        }
        assert!((m.rms() - c).abs() < 1e-6 * c, "{}", m.rms());
        assert_eq!(m.totals().1, 37);
        assert!(still.rms() < 1e-9);
    }

    /// A square-wave jerk ±j (alternating each interval) has RMS exactly j: the positions are
    /// built by integrating the piecewise-constant jerk three times with the same sampling.
    #[test]
    fn jerk_rms_of_a_square_wave() {
        let (j, h) = (3.0, JERK_INTERVAL_S);
        let mut m = JerkMeter::default();
        let (mut x, mut v, mut a) = (0.0f64, 0.0f64, 0.0f64);
        m.add(Vector3::new(x, 0.0, 0.0), h);
        for k in 0..60 {
            let jk = if (k / 5) % 2 == 0 { j } else { -j };
            // Exact integration over one interval with constant jerk.
            x += v * h + a * h * h / 2.0 + jk * h.powi(3) / 6.0;
            v += a * h + jk * h * h / 2.0;
            a += jk * h;
            m.add(Vector3::new(x, 0.0, 0.0), h);
        }
        // The third difference of exact samples mixes neighbouring intervals at each sign
        // change, so the RMS lies a little under j; within the interior it is exactly j.
        assert!(m.rms() <= j + 1e-9 && m.rms() > 0.8 * j, "{}", m.rms());
    }

    /// The score formula of the module docs on hand-computed values.
    #[test]
    fn score_is_the_weighted_linear_map_times_completion() {
        let spec: ExerciseSpec = serde_json::from_str(
            r#"{"id":"t","version":1,"title":"t","goal":"g","skills":[],
            "control":{"mode":"joint","arm":"left"},
            "steps":[{"id":"a","text":"a","done_when":{"kind":"released"}},
                     {"id":"b","text":"b","done_when":{"kind":"released"}}],
            "time_limit_s":100,"pass":{"min_score":50,"limits":[{"metric":"drops","max":0}]},
            "scoring":[{"metric":"time_s","good":20,"bad":100,"weight":3},
                       {"metric":"mean_jlm","good":0.8,"bad":0.4,"weight":1}],
            "autopilot":[]}"#,
        )
        .expect("spec");
        spec.check().expect("valid");
        let m = Metrics {
            time_s: 40.0,
            mean_jlm: 0.9,
            steps_completed: 2.0,
            drops: 1.0,
            ..Metrics::default()
        };
        let (s, terms) = score(&spec, &m);
        // time: (100 − 40)/(100 − 20) = 0.75; JLM clamped to 1; (3·0.75 + 1)/4 = 0.8125.
        assert!((terms[0].score - 0.75).abs() < 1e-12 && terms[1].score == 1.0);
        assert!((s - 81.25).abs() < 1e-9, "{s}");
        let half = Metrics {
            steps_completed: 1.0,
            ..m
        };
        assert!((score(&spec, &half).0 - 40.625).abs() < 1e-9);
        let l = limits(&spec, &m);
        assert!(!l[0].met && l[0].value == 1.0);
    }
}
