//! The exercise file (`exercises/<id>.json`): what the trainee must do, in what scene, how it
//! is judged, and the autopilot script that proves it can be done with the trainee's controls.
//! Parsed by the caller (the core has no file I/O); [`ExerciseSpec::check`] rejects a file
//! whose references do not resolve.

use serde::{Deserialize, Serialize};

use super::autopilot::Action;
use super::condition::Condition;
use crate::Error;
use crate::sim::measures::{NEAR_LIMIT_FRACTION, NEAR_SINGULAR_ISOTROPY};
use crate::sim::{ControlMethod, ControlMode};

/// A set of views the page may offer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ViewSet {
    /// Only the pilot cameras: the vehicle's pan-tilt camera, the wrist cameras, the fixed
    /// overview (no orbit, top, front or side view).
    Pilot,
}

/// One exercise, as stored in its file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExerciseSpec {
    /// Identifier (the file name without `.json`), e.g. `dual-lift`.
    pub id: String,
    /// Version, stamped into every assessment; bump it when the task or scoring changes.
    pub version: u32,
    /// Short title.
    pub title: String,
    /// The goal, one or two sentences addressed to the trainee.
    pub goal: String,
    /// Skills trained.
    pub skills: Vec<String>,
    /// Exercises (ids) the trainee must be proficient in before this one opens (issue 30
    /// item 4; [`super::progression`]). Checked across the whole set of files by
    /// [`super::progression::check_requires`]: known ids, no cycles. Not part of the
    /// assessment (no version bump when it changes).
    #[serde(default)]
    pub requires: Vec<String>,
    /// The controls the exercise starts with.
    pub control: ControlSpec,
    /// Scene: initial arm state, object, targets, zones, ghosts, obstacles.
    #[serde(default)]
    pub scene: Scene,
    /// Ordered steps; each completes when its condition has held for its `hold_s`.
    pub steps: Vec<StepSpec>,
    /// Time limit (s of simulated time); the attempt ends, failed, when it runs out.
    pub time_limit_s: f64,
    /// Pass criteria besides completing every step.
    pub pass: PassSpec,
    /// Scoring terms (see [`super::assess::score`]).
    pub scoring: Vec<ScoreTerm>,
    /// Thresholds of the assessment's counters.
    #[serde(default)]
    pub thresholds: Thresholds,
    /// A hidden fault for a diagnosis drill.
    #[serde(default)]
    pub fault_drill: Option<FaultDrill>,
    /// The views the page offers during the attempt: `pilot` allows only the vehicle's
    /// cameras (an assessed run as an ROV operator works, issue 28); absent: every view (the
    /// engineering views as training wheels).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<ViewSet>,
    /// How proficiency is judged on this exercise (issue 30): the benchmark's attempts in a
    /// row and distance, the CUSUM's failure rates and limit (defaults documented there).
    #[serde(default)]
    pub proficiency: super::proficiency::ProficiencySpec,
    /// The scripted controller for `seaarms exercise <id> --autopilot`.
    pub autopilot: Vec<Action>,
}

/// Which arm or arms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ArmSel {
    /// The left arm.
    Left,
    /// The right arm.
    Right,
    /// Either arm.
    Either,
    /// Both arms.
    Both,
}

impl ArmSel {
    /// The arm indices this selection covers.
    pub fn indices(self) -> &'static [usize] {
        match self {
            ArmSel::Left => &[0],
            ArmSel::Right => &[1],
            ArmSel::Either | ArmSel::Both => &[0, 1],
        }
    }
}

/// One named arm (autopilot actions, ghosts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ArmName {
    /// Left arm (index 0).
    Left,
    /// Right arm (index 1).
    Right,
}

impl ArmName {
    /// Index in per-arm arrays.
    pub fn index(self) -> usize {
        match self {
            ArmName::Left => 0,
            ArmName::Right => 1,
        }
    }
}

/// The controls at the start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Stick mode.
    pub mode: ControlMode,
    /// Control method.
    #[serde(default)]
    pub method: ControlMethod,
    /// Cartesian translation holds the jaw's orientation ([`crate::sim::Operator`]); absent:
    /// held, as in a new session. An attempt starts with this setting whatever came before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_orientation: Option<bool>,
    /// The working arm(s): their posture and smoothness are assessed.
    pub arm: ArmSel,
}

/// The scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Initial joint angles (degrees) per arm, left then right; default the initial
    /// position of Lim §4.1.
    #[serde(default)]
    pub initial_q_deg: Option<[[f64; 6]; 2]>,
    /// Box centre on the seabed (x, y, m); default where Lim's case studies put it.
    #[serde(default)]
    pub object_xy_m: Option<[f64; 2]>,
    /// Floating markers the jaw tip must touch.
    #[serde(default)]
    pub targets: Vec<Target>,
    /// Marked zones on the seabed.
    #[serde(default)]
    pub zones: Vec<Zone>,
    /// Ghost arms showing joint angles to reach.
    #[serde(default)]
    pub ghosts: Vec<Ghost>,
    /// Boxes the arms must not strike.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// The intervention panel (valve, hot stab; [`crate::panel::PanelParams::standard`]).
    #[serde(default)]
    pub panel: bool,
    /// The medium: `"subsea"` (the default: sea water, [`crate::sim::Environment::subsea`])
    /// or `"air"`.
    #[serde(default)]
    pub environment: crate::sim::Medium,
    /// The jaws' grasp: `false` (the default), their finite friction grip, which slips and can
    /// drop the box ([`crate::grasp::GripParams`]); `true`, Lim's rigid grasp (§3.5.2.1
    /// assumption (i)). Fixed for the attempt (the replay rebuilds it from the exercise).
    #[serde(default)]
    pub rigid_grasp: bool,
}

/// A floating marker.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    /// Identifier.
    pub id: String,
    /// Position (m, world).
    pub position_m: [f64; 3],
    /// Touch tolerance (m).
    pub radius_m: f64,
}

/// A zone on the seabed: an x–y rectangle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zone {
    /// Identifier.
    pub id: String,
    /// Centre (x, y, m, world).
    pub center_m: [f64; 2],
    /// Half sizes (x, y, m): the object's centre must lie within them.
    pub half_size_m: [f64; 2],
}

/// A ghost: joint angles drawn for the trainee to match.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ghost {
    /// Which arm.
    pub arm: ArmName,
    /// Joint angles (degrees).
    pub q_deg: [f64; 6],
}

/// An axis-aligned box obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// Identifier.
    pub id: String,
    /// Centre (m, world).
    pub center_m: [f64; 3],
    /// Half sizes (m).
    pub half_size_m: [f64; 3],
}

/// One step of the exercise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepSpec {
    /// Identifier.
    pub id: String,
    /// What to do, addressed to the trainee.
    pub text: String,
    /// When it is done.
    pub done_when: Condition,
    /// How long the condition must hold without a break (s).
    #[serde(default)]
    pub hold_s: f64,
}

/// Pass criteria: every step completed within the time limit, a score of at least
/// `min_score` (or, with `marks` = `benchmark` once the reference operators' benchmark
/// applies, every benchmarked measure on the better side of its line instead), and every limit
/// met.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassSpec {
    /// Lowest passing score (0–100): the pass mark while the marks are fixed, or while the
    /// benchmark does not apply yet.
    pub min_score: f64,
    /// Limits on assessment metrics (they hold under either marks).
    #[serde(default)]
    pub limits: Vec<Limit>,
    /// Where the pass marks come from: `fixed` (default: `min_score`) or `benchmark` (the
    /// reference operators' benchmark, mean ∓ k·SD on each measure of
    /// `proficiency.benchmark_on`, k = `proficiency.benchmark_sd`;
    /// [`super::proficiency::PassLines`]).
    #[serde(default)]
    pub marks: PassMarks,
}

/// Where an exercise's pass marks come from ([`PassSpec::marks`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PassMarks {
    /// The file's `min_score`.
    #[default]
    Fixed,
    /// The reference operators' benchmark where it applies, else the file's `min_score`.
    Benchmark,
}

/// A limit on one metric of the assessment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limit {
    /// Metric name (a numeric field of [`super::assess::Metrics`]).
    pub metric: String,
    /// Most allowed.
    #[serde(default)]
    pub max: Option<f64>,
    /// Least allowed.
    #[serde(default)]
    pub min: Option<f64>,
}

/// One scoring term: a metric mapped linearly from `bad` (0) to `good` (1), clamped, weighted.
/// `good` may be above or below `bad` (higher or lower is better).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreTerm {
    /// Metric name (a numeric field of [`super::assess::Metrics`]).
    pub metric: String,
    /// Value scoring 1.
    pub good: f64,
    /// Value scoring 0.
    pub bad: f64,
    /// Weight (> 0).
    pub weight: f64,
}

/// Thresholds that turn continuous signals into counted events.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Thresholds {
    /// A jaw's contact force above this is an overload event (N): 2 000 — about 4 × the
    /// 50 kg box's weight, well under what the jaw and wrist take.
    pub overload_force_n: f64,
    /// Internal force the grasp should stay under (N), reported per attempt: 500.
    pub internal_force_n: f64,
    /// Translational isotropy (σ_min/σ_max) below which the arm is near a singularity: 0.05,
    /// the state frame's warning level.
    pub singular_isotropy: f64,
    /// A joint within this fraction of its range from a limit is "near a limit": 0.05, the
    /// state frame's warning level.
    pub near_limit_fraction: f64,
    /// A joint within this many degrees of a limit has hit it: 1.
    pub limit_hit_deg: f64,
    /// Sticks and grips all below this magnitude are idle: 0.05 (below the page's own stick
    /// dead zone, 0.12 in `web/input.js`, so any stick the page sends counts as input).
    pub idle_input: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds {
            overload_force_n: 2000.0,
            internal_force_n: 500.0,
            singular_isotropy: NEAR_SINGULAR_ISOTROPY,
            near_limit_fraction: NEAR_LIMIT_FRACTION,
            limit_hit_deg: 1.0,
            idle_input: 0.05,
        }
    }
}

/// A hidden fault injected at a random time for the trainee to diagnose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultDrill {
    /// The arm that gets the fault.
    pub arm: ArmName,
    /// Injection time window after the start (s); the time is drawn uniformly from it.
    pub window_s: [f64; 2],
    /// The faults one is drawn from (uniformly).
    pub choices: Vec<crate::hydraulics::Fault>,
}

impl ExerciseSpec {
    /// Checks what serde cannot: non-empty steps, positive time limit and weights, metric
    /// names that exist, target and zone references that resolve, finite numbers.
    pub fn check(&self) -> Result<(), Error> {
        let bad = |m: String| {
            Err(Error::InvalidParameter {
                what: "exercise",
                reason: format!("{}: {m}", self.id),
            })
        };
        if self.steps.is_empty() {
            return bad("no steps".into());
        }
        if !(self.time_limit_s.is_finite() && self.time_limit_s > 0.0) {
            return bad("time_limit_s must be positive".into());
        }
        if !(0.0..=100.0).contains(&self.pass.min_score) {
            return bad("pass.min_score must be in [0, 100]".into());
        }
        if let Err(m) = self.proficiency.check() {
            return bad(m);
        }
        for t in &self.scoring {
            if super::assess::Metrics::default().get(&t.metric).is_none() {
                return bad(format!("unknown scoring metric `{}`", t.metric));
            }
            if !(t.weight.is_finite() && t.weight > 0.0 && t.good.is_finite() && t.bad.is_finite())
                || t.good == t.bad
            {
                return bad(format!("scoring term `{}`: bad numbers", t.metric));
            }
        }
        for l in &self.pass.limits {
            if super::assess::Metrics::default().get(&l.metric).is_none() {
                return bad(format!("unknown limit metric `{}`", l.metric));
            }
        }
        for s in &self.steps {
            s.done_when
                .check(&self.scene)
                .or_else(|m| bad(format!("step {}: {m}", s.id)))?;
            if !(s.hold_s.is_finite() && s.hold_s >= 0.0) {
                return bad(format!("step {}: hold_s must be ≥ 0", s.id));
            }
        }
        for a in &self.autopilot {
            a.check(&self.scene)
                .or_else(|m| bad(format!("autopilot: {m}")))?;
        }
        if let Some(d) = &self.fault_drill {
            if d.choices.is_empty() || !(d.window_s[0] >= 0.0 && d.window_s[1] >= d.window_s[0]) {
                return bad("fault_drill needs choices and a window [a, b] with 0 ≤ a ≤ b".into());
            }
        }
        Ok(())
    }

    /// Simulation parameters for this exercise's scene, from the case-study set-up in the
    /// scene's medium.
    pub fn sim_params(
        &self,
        left: &crate::Model,
        right: &crate::Model,
    ) -> Result<crate::sim::SimParams, Error> {
        let mut p = crate::sim::SimParams::case_study(left, right)?
            .with_environment(self.scene.environment.environment());
        if let Some(q) = self.scene.initial_q_deg {
            for (arm, q) in p.arms.iter_mut().zip(q) {
                arm.initial_q = q.map(f64::to_radians);
            }
        }
        if let Some([x, y]) = self.scene.object_xy_m {
            let z = p.object.seabed_z_m;
            p.object = crate::grasp::ObjectParams::case_study_box(x, y, z);
        }
        if self.scene.panel {
            p = p.with_panel(crate::panel::PanelParams::standard());
        }
        p.rigid_grasp = self.scene.rigid_grasp;
        Ok(p)
    }

    /// A target by id.
    pub fn target(&self, id: &str) -> Option<&Target> {
        self.scene.targets.iter().find(|t| t.id == id)
    }

    /// A zone by id.
    pub fn zone(&self, id: &str) -> Option<&Zone> {
        self.scene.zones.iter().find(|z| z.id == id)
    }
}
