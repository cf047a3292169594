//! The autopilot: a scripted controller that works an exercise through the trainee's own
//! controls only — stick axes, grips, the object sticks, settings and the diagnosis answer,
//! at the page's send rate — reading only what the trainee's page shows (poses, joint angles,
//! line pressures, grasp state, the task panel). Its script lives in the exercise file, so
//! the file itself proves the exercise can be done with the controls a trainee has.
//!
//! Each action runs until it is done or its `timeout_s` runs out (then the script goes on;
//! the assessment decides whether the attempt passed).

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::condition::{Condition, Facts};
use super::spec::{ArmName, Scene};
use crate::control::rotation_error;
use crate::hydraulics::FaultKind;
use crate::sim::{Arm, Simulation};
use crate::sim::{ControlMethod, ControlMode};

/// Interval between autopilot commands (s): 0.02, the page's 50 Hz send rate.
pub const PILOT_INTERVAL_S: f64 = 0.02;

/// A point the autopilot can steer a tool to (`{"handle": 0}`, `{"target": "t1"}`,
/// `{"zone": "z"}` (its centre on the seabed), `{"point": [x, y, z]}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointRef {
    /// A box handle's centre, where it is now (0: the left arm's side handle, 1: the right
    /// arm's, 2: the lifting point over the centre of mass; [`crate::grasp::ObjectParams`]).
    Handle(usize),
    /// A target marker.
    Target(String),
    /// A zone's centre on the seabed.
    Zone(String),
    /// A fixed world point (m).
    Point([f64; 3]),
}

fn default_timeout() -> f64 {
    30.0
}

fn default_tolerance_m() -> f64 {
    0.01
}

/// What `move` steers to the goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Steer {
    /// The arm's tool point.
    #[default]
    Tool,
    /// The box's centre of mass (carried by the arm).
    Object,
}

/// One scripted action (`"do"` names the variant in the file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "do", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Change the stick mode and/or control method.
    Settings {
        /// New mode.
        #[serde(default)]
        mode: Option<ControlMode>,
        /// New method.
        #[serde(default)]
        method: Option<ControlMethod>,
    },
    /// Cartesian mode: steer `arm`'s tool (or the box it carries) to `to` + `offset_m`
    /// (proportional control on the linear sticks) until within `tolerance_m`; with `level`,
    /// the angular sticks keep the carried box level meanwhile.
    Move {
        /// Arm.
        arm: ArmName,
        /// Tool or carried box.
        #[serde(default)]
        steer: Steer,
        /// Keep the box level with the angular sticks.
        #[serde(default)]
        level: bool,
        /// Where.
        to: PointRef,
        /// Offset added to the point (m, world).
        #[serde(default)]
        offset_m: [f64; 3],
        /// Done within this distance (m).
        #[serde(default = "default_tolerance_m")]
        tolerance_m: f64,
        /// Also steer the tool's orientation to this rotation vector (rad, world; proportional
        /// control on the angular sticks) and finish only within [`ATTITUDE_TOLERANCE_RAD`]
        /// of it; without it the angular sticks stay at zero.
        #[serde(default)]
        attitude_rotvec: Option<[f64; 3]>,
        /// Give up after (s).
        #[serde(default = "default_timeout")]
        timeout_s: f64,
    },
    /// Joint mode: drive joint `joint` of `arm` to `angle_deg` (proportional control on its
    /// stick axis) until within `tolerance_deg`.
    Joint {
        /// Arm.
        arm: ArmName,
        /// Joint (0–5).
        joint: usize,
        /// Target angle (degrees).
        angle_deg: f64,
        /// Done within (degrees).
        tolerance_deg: f64,
        /// Give up after (s).
        #[serde(default = "default_timeout")]
        timeout_s: f64,
    },
    /// Close (or open) `arm`'s jaw: closing ends when the jaw holds the box or a panel item, or
    /// after
    /// `timeout_s`; opening runs for `timeout_s`.
    Grip {
        /// Arm.
        arm: ArmName,
        /// Close (true) or open.
        close: bool,
        /// Give up / run for (s).
        #[serde(default = "default_grip_s")]
        timeout_s: f64,
    },
    /// Hold the object sticks (closed loop; fractions of the maximum speeds) until `until`.
    Object {
        /// [vx vy vz wx wy wz] fractions in [−1, 1].
        velocity: [f64; 6],
        /// Stop when this holds.
        until: Condition,
        /// Give up after (s).
        #[serde(default = "default_timeout")]
        timeout_s: f64,
    },
    /// Hold `arm`'s sticks at `axes` until `until`; with `level`, the angular sticks keep the
    /// carried box level instead (as `move`'s `level`).
    Sticks {
        /// Arm.
        arm: ArmName,
        /// Axes in [−1, 1].
        axes: [f64; 6],
        /// Keep the box level with the angular sticks (overrides `axes[3..]`).
        #[serde(default)]
        level: bool,
        /// Stop when this holds.
        until: Condition,
        /// Give up after (s).
        #[serde(default = "default_timeout")]
        timeout_s: f64,
    },
    /// Do nothing for `s` seconds.
    Wait {
        /// Seconds.
        s: f64,
    },
    /// Do nothing until `until` holds.
    WaitUntil {
        /// Condition.
        until: Condition,
        /// Give up after (s).
        #[serde(default = "default_timeout")]
        timeout_s: f64,
    },
    /// Diagnose a hydraulic fault on `arm` from what the page shows (see [`Diagnosis`]) and
    /// name it.
    Diagnose {
        /// Arm to test.
        arm: ArmName,
    },
}

fn default_grip_s() -> f64 {
    3.0
}

impl Action {
    /// Checks references against the scene.
    pub fn check(&self, scene: &Scene) -> Result<(), String> {
        match self {
            Action::Move { to, .. } => match to {
                PointRef::Handle(i) if *i >= crate::grasp::N_HANDLES => {
                    Err(format!("handle {i} is not 0, 1 or 2 (the lifting point)"))
                }
                PointRef::Target(t) if !scene.targets.iter().any(|x| &x.id == t) => {
                    Err(format!("unknown target `{t}`"))
                }
                PointRef::Zone(z) if !scene.zones.iter().any(|x| &x.id == z) => {
                    Err(format!("unknown zone `{z}`"))
                }
                _ => Ok(()),
            },
            Action::Joint { joint, .. } if *joint > 5 => Err(format!("joint {joint} > 5")),
            Action::Object { until, .. }
            | Action::Sticks { until, .. }
            | Action::WaitUntil { until, .. } => until.check(scene),
            _ => Ok(()),
        }
    }
}

/// What the autopilot sends in one 20 ms slot, exactly what the page could send.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PilotOutput {
    /// A settings change to send first.
    pub settings: Option<(Option<ControlMode>, Option<ControlMethod>)>,
    /// Stick axes per arm, [−1, 1].
    pub axes: [[f64; 6]; 2],
    /// Grip per arm, [−1, 1] (+ opens, − closes).
    pub grips: [f64; 2],
    /// Object sticks, [−1, 1].
    pub object: [f64; 6],
    /// A diagnosis answer to send.
    pub answer: Option<&'static str>,
}

/// Proportional gain of `move` (stick fraction per metre of error): full stick beyond 10 cm.
const MOVE_GAIN_PER_M: f64 = 10.0;
/// Proportional gain of `level` (angular stick fraction per radian of tilt): full stick
/// beyond about 11°.
const LEVEL_GAIN_PER_RAD: f64 = 5.0;

/// Angular sticks that turn the box's z axis towards the world vertical: ω ∝ z_box × ẑ.
fn level_sticks(sim: &Simulation) -> Vector3<f64> {
    let z = sim.object().pose.rotation * Vector3::z();
    let axis = z.cross(&Vector3::z());
    let mut w = axis * LEVEL_GAIN_PER_RAD;
    if w.norm() > 1.0 {
        w /= w.norm();
    }
    w
}

/// Proportional gain of `move`'s attitude (stick fraction per radian of error): full stick
/// beyond 0.2 rad.
const ATTITUDE_GAIN_PER_RAD: f64 = 5.0;
/// With [`Autopilot::settling`], `joint` finishes only with the joint this slow (rad/s):
/// 0.05 (about 3°/s).
const JOINT_STILL_RAD_S: f64 = 0.05;
/// `move` with an attitude finishes within this orientation error (rad): 0.02 (1.1°).
pub const ATTITUDE_TOLERANCE_RAD: f64 = 0.02;
/// Proportional gain of `joint` (stick fraction per degree of error): full stick beyond 10°.
const JOINT_GAIN_PER_DEG: f64 = 0.1;

/// Length of the sticks-centred watch that opens the diagnosis (s).
const WATCH_S: f64 = 2.0;
/// A joint that turns more than this in the watch with every stick centred is running away (°):
/// a closed-centre valve holds a healthy joint to a small fraction of a degree.
const RUNAWAY_DEG: f64 = 1.0;
/// A limited joint within this of a limit (°) is tested for an open valve holding it there.
const AT_LIMIT_DEG: f64 = 1.5;
/// Length of a full-stick jog of one joint (s).
const JOG_S: f64 = 0.6;
/// A jogged joint that turns less than this in the commanded direction does not answer its
/// stick (°); a healthy joint turns ≥ 9° in a [`JOG_S`] jog (Table 1-1's slowest 20°/s).
const ANSWERS_DEG: f64 = 2.0;
/// Length of the wrist-rotate spin (s) and the window at its end the supply is read over (s).
const SPIN_S: f64 = 0.6;
const SPIN_READ_S: f64 = 0.2;
/// Sticks centred after the spin while the rotate motor stops (s).
const COAST_S: f64 = 0.5;
/// Supply read from the spinning rotate motor below this fraction of the nameplate supply is
/// a supply drop: 0.8.
const SUPPLY_FRACTION: f64 = 0.8;
/// The rotate motor's speed [`LAG_READ_S`] into a full-stick spin over its steady speed below
/// this is air in the oil: 0.65 (healthy oil ≈ 0.81, bulk modulus × 0.03 ≈ 0.48: about their
/// geometric mean).
const LAG_RATIO: f64 = 0.65;
/// When the spin-up speed is read (s): 0.04, two slots. The valve's spool opens with a 25 ms
/// time constant (`hydraulics::SPOOL_TIME_CONSTANT_S`), so a healthy motor is then at ≈ 80 %
/// of its speed, while with soft (aerated) oil the pressure is still building.
const LAG_READ_S: f64 = 0.04;
/// Leak test: the loaded joints jogged (shoulder, elbow, wrist pitch), each 0.3 s out and back.
const LEAK_JOINTS: [usize; 3] = [1, 2, 3];
const LEAK_JOG_S: f64 = 0.3;
/// Leak test: settling time after the jogs (s), then the watch (s).
const LEAK_SETTLE_S: f64 = 0.7;
const LEAK_WATCH_S: f64 = 2.0;
/// A joint whose two line pressures drift by more than this in total over a sticks-centred watch
/// is leaking across its piston (Pa): 0.1 MPa; a shut healthy valve holds them to ≈ 0.01 MPa.
const LEAK_DRIFT_PA: f64 = 1.0e5;

/// The answers, as [`FaultKind::NAMES`] lists them.
const SUPPLY_DROP: &str = FaultKind::NAMES[0];
const STUCK_VALVE: &str = FaultKind::NAMES[1];
const LEAK: &str = FaultKind::NAMES[2];
const AIR: &str = FaultKind::NAMES[3];

/// The fault-diagnosis procedure: what a pilot does with the sticks in joint mode (a centred
/// stick shuts its closed-centre valve, so what the arm does then is the hydraulics) while
/// reading the page: joint angles and speeds, the line pressures P_I, P_O, the joint limits
/// and the nameplate supply pressure (Lim Table 1-1). It never reads the fault settings.
///
/// 1. **Watch** ([`WATCH_S`], sticks centred): a joint that turns by more than
///    [`RUNAWAY_DEG`] is jogged at full stick against its motion; a joint resting at a limit
///    is jogged away from it. One that does not answer its stick ([`ANSWERS_DEG`]) has a
///    **stuck valve** (the spool ignores the stick and drives it to its stop); a runaway joint
///    that answers is creeping on a **leak**.
/// 2. **Spin** the wrist rotate motor at full stick for [`SPIN_S`] (unloaded, equal-area
///    motor: in steady motion the two orifice drops are equal, so P_I + P_O = P_s, eq. 3.48):
///    a supply read below [`SUPPLY_FRACTION`] of the nameplate is a **supply drop**; a speed
///    [`LAG_READ_S`] in below [`LAG_RATIO`] of the steady speed is **air** (the pressure rate β/V of
///    eq. 3.56 falls with β, so the pressure builds late).
/// 3. **Leak test**: jog the loaded joints out and back, let them settle, watch the gauges with
///    the sticks centred: line pressures that keep drifting ([`LEAK_DRIFT_PA`]) as the two
///    chambers bleed into each other (the cross-piston leakage `hydraulics::chamber` adds to
///    eq. 3.56) are a **leak**.
///
/// If no test crosses its threshold the answer is the symptom closest to its threshold.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Diagnosis {
    phase: Phase,
    t0: f64,
    q0: [f64; 6],
    p0: [[f64; 6]; 2],
    tested: [bool; 6],
    spin_first: Option<f64>,
    spin_sum_pa: f64,
    spin_n: u32,
    supply_ratio: f64,
    lag_ratio: f64,
    leak_drift_pa: f64,
}

/// Where the procedure is.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
enum Phase {
    /// Not begun.
    #[default]
    Start,
    /// Sticks centred, watching ([`WATCH_S`]).
    Watch,
    /// Full stick `dir` on `joint` ([`JOG_S`]); `at_limit`: jogged away from a stop rather
    /// than against a runaway.
    Jog {
        joint: usize,
        dir: f64,
        at_limit: bool,
    },
    /// Rotate at full stick ([`SPIN_S`]).
    Spin,
    /// Sticks centred after the spin ([`COAST_S`]).
    Coast,
    /// Leak-test jog k: joint `LEAK_JOINTS[k / 2]`, out for even k, back for odd.
    LeakJog(usize),
    /// Sticks centred after the jogs ([`LEAK_SETTLE_S`]).
    LeakSettle,
    /// Sticks centred, reading the gauges' drift ([`LEAK_WATCH_S`]).
    LeakWatch,
}

impl Diagnosis {
    fn begin(&mut self, phase: Phase, t: f64, st: &crate::sim::ArmState) {
        self.phase = phase;
        self.t0 = t;
        self.q0 = st.q;
        self.p0 = [st.p_in, st.p_out];
    }

    /// Largest total drift of a joint's two line pressures since the phase began (Pa).
    fn pressure_drift(&self, st: &crate::sim::ArmState) -> f64 {
        (0..6)
            .map(|j| (st.p_in[j] - self.p0[0][j]).abs() + (st.p_out[j] - self.p0[1][j]).abs())
            .fold(0.0, f64::max)
    }

    /// The next untested limited joint within [`AT_LIMIT_DEG`] of a limit, with the jog
    /// direction away from it.
    fn next_at_limit(&self, sim: &Simulation, arm: Arm) -> Option<(usize, f64)> {
        let q = sim.arm(arm).q;
        let near = AT_LIMIT_DEG.to_radians();
        sim.model(arm)
            .joints
            .iter()
            .enumerate()
            .take(6)
            .filter(|(j, joint)| joint.is_limited() && !self.tested[*j])
            .find_map(|(j, joint)| {
                if q[j] - joint.limits[0] < near {
                    Some((j, 1.0))
                } else if joint.limits[1] - q[j] < near {
                    Some((j, -1.0))
                } else {
                    None
                }
            })
    }

    /// One 20 ms slot: sets `arm`'s sticks in `axes` and returns the answer once known.
    fn tick(&mut self, sim: &Simulation, arm: Arm, axes: &mut [f64; 6]) -> Option<&'static str> {
        let t = sim.time_s();
        let st = *sim.arm(arm);
        let supply_pa = sim.params().arms[arm.index()].hydraulics.supply_pa;
        *axes = [0.0; 6];
        // Phases end at the slot boundary; the next phase's sticks go out in the same slot.
        loop {
            let elapsed = t - self.t0;
            match self.phase {
                Phase::Start => self.begin(Phase::Watch, t, &st),
                Phase::Watch if elapsed + 1e-9 >= WATCH_S => {
                    self.leak_drift_pa = self.leak_drift_pa.max(self.pressure_drift(&st));
                    let (j, dq) =
                        (0..6)
                            .map(|j| (j, st.q[j] - self.q0[j]))
                            .fold(
                                (0, 0.0_f64),
                                |a, b| if b.1.abs() > a.1.abs() { b } else { a },
                            );
                    if dq.abs() > RUNAWAY_DEG.to_radians() {
                        let dir = -dq.signum();
                        self.begin(
                            Phase::Jog {
                                joint: j,
                                dir,
                                at_limit: false,
                            },
                            t,
                            &st,
                        );
                    } else if let Some((joint, dir)) = self.next_at_limit(sim, arm) {
                        self.begin(
                            Phase::Jog {
                                joint,
                                dir,
                                at_limit: true,
                            },
                            t,
                            &st,
                        );
                    } else {
                        self.begin(Phase::Spin, t, &st);
                    }
                }
                Phase::Jog {
                    joint,
                    dir,
                    at_limit,
                } if elapsed + 1e-9 >= JOG_S => {
                    let moved = (st.q[joint] - self.q0[joint]) * dir;
                    if moved < ANSWERS_DEG.to_radians() {
                        return Some(STUCK_VALVE);
                    }
                    if !at_limit {
                        return Some(LEAK);
                    }
                    self.tested[joint] = true;
                    match self.next_at_limit(sim, arm) {
                        Some((joint, dir)) => self.begin(
                            Phase::Jog {
                                joint,
                                dir,
                                at_limit: true,
                            },
                            t,
                            &st,
                        ),
                        None => self.begin(Phase::Spin, t, &st),
                    }
                }
                Phase::Spin if elapsed + 1e-9 >= SPIN_S => {
                    let steady = st.qd[5];
                    self.supply_ratio = if self.spin_n > 0 {
                        self.spin_sum_pa / f64::from(self.spin_n) / supply_pa
                    } else {
                        1.0
                    };
                    self.lag_ratio = match self.spin_first {
                        Some(first) if steady.abs() > 1e-6 => first / steady,
                        _ => 1.0,
                    };
                    self.begin(Phase::Coast, t, &st);
                }
                Phase::Coast if elapsed + 1e-9 >= COAST_S => {
                    if self.supply_ratio < SUPPLY_FRACTION {
                        return Some(SUPPLY_DROP);
                    }
                    if self.lag_ratio < LAG_RATIO {
                        return Some(AIR);
                    }
                    self.begin(Phase::LeakJog(0), t, &st);
                }
                Phase::LeakJog(k) if elapsed + 1e-9 >= LEAK_JOG_S => {
                    let next = if k + 1 < 2 * LEAK_JOINTS.len() {
                        Phase::LeakJog(k + 1)
                    } else {
                        Phase::LeakSettle
                    };
                    self.begin(next, t, &st);
                }
                Phase::LeakSettle if elapsed + 1e-9 >= LEAK_SETTLE_S => {
                    self.begin(Phase::LeakWatch, t, &st)
                }
                Phase::LeakWatch if elapsed + 1e-9 >= LEAK_WATCH_S => {
                    self.leak_drift_pa = self.leak_drift_pa.max(self.pressure_drift(&st));
                    return Some(self.closest());
                }
                _ => break,
            }
        }
        let elapsed = t - self.t0;
        match self.phase {
            Phase::Jog { joint, dir, .. } => axes[joint] = dir,
            Phase::Spin => {
                axes[5] = 1.0;
                // The spin-up reading after [`LAG_READ_S`] at full stick, then the supply read.
                if self.spin_first.is_none() && elapsed + 1e-9 >= LAG_READ_S {
                    self.spin_first = Some(st.qd[5]);
                }
                if elapsed + 1e-9 >= SPIN_S - SPIN_READ_S {
                    self.spin_sum_pa += st.p_in[5] + st.p_out[5];
                    self.spin_n += 1;
                }
            }
            Phase::LeakJog(k) => {
                axes[LEAK_JOINTS[k / 2]] = if k % 2 == 0 { 1.0 } else { -1.0 };
            }
            _ => {}
        }
        None
    }

    /// The leak test found nothing past its threshold: the symptom nearest its threshold,
    /// each scaled so that 1 is the threshold.
    fn closest(&self) -> &'static str {
        if self.leak_drift_pa > LEAK_DRIFT_PA {
            return LEAK;
        }
        let scores = [
            (
                (1.0 - self.supply_ratio) / (1.0 - SUPPLY_FRACTION),
                SUPPLY_DROP,
            ),
            ((1.0 - self.lag_ratio) / (1.0 - LAG_RATIO), AIR),
            (self.leak_drift_pa / LEAK_DRIFT_PA, LEAK),
        ];
        scores
            .iter()
            .fold(
                (f64::NEG_INFINITY, LEAK),
                |a, b| if b.0 > a.0 { *b } else { a },
            )
            .1
    }
}

/// Runs a script.
#[derive(Debug, Clone)]
pub struct Autopilot {
    script: Vec<Action>,
    index: usize,
    started_s: Option<f64>,
    mode: ControlMode,
    diagnosis: Diagnosis,
    answered: bool,
    /// A `joint` action finishes only with the joint nearly still ([`Autopilot::settling`]).
    settle: bool,
}

impl Autopilot {
    /// The script's `joint` actions finish only with the joint nearly still
    /// ([`JOINT_STILL_RAD_S`]): for an operator who reacts late (a human-paced driver) and
    /// may pass through the tolerance and must come back.
    pub fn settling(mut self) -> Autopilot {
        self.settle = true;
        self
    }

    /// Starts `script` with the sticks in `mode`.
    pub fn new(script: Vec<Action>, mode: ControlMode) -> Autopilot {
        Autopilot {
            script,
            index: 0,
            started_s: None,
            mode,
            diagnosis: Diagnosis::default(),
            answered: false,
            settle: false,
        }
    }

    /// Whether the script has run out.
    pub fn finished(&self) -> bool {
        self.index >= self.script.len()
    }

    fn point(sim: &Simulation, scene: &Scene, p: &PointRef) -> Vector3<f64> {
        match p {
            PointRef::Handle(i) => {
                {
                    let o = sim.object().pose;
                    let handles = &sim.params().object.handles;
                    o * nalgebra::Point3::from(handles[(*i).min(handles.len() - 1)].centre_m)
                }
                .coords
            }
            PointRef::Target(id) => scene
                .targets
                .iter()
                .find(|t| &t.id == id)
                .map_or(Vector3::zeros(), |t| Vector3::from(t.position_m)),
            PointRef::Zone(id) => scene
                .zones
                .iter()
                .find(|z| &z.id == id)
                .map_or(Vector3::zeros(), |z| {
                    Vector3::new(z.center_m[0], z.center_m[1], sim.params().object.seabed_z_m)
                }),
            PointRef::Point(p) => Vector3::from(*p),
        }
    }

    /// The commands for the next 20 ms.
    pub fn tick(&mut self, sim: &Simulation, facts: &Facts<'_>) -> PilotOutput {
        let mut out = PilotOutput::default();
        let t = sim.time_s();
        let Some(action) = self.script.get(self.index).cloned() else {
            return out;
        };
        let started = *self.started_s.get_or_insert(t);
        let elapsed = t - started;
        let done = match &action {
            Action::Settings { mode, method } => {
                if let Some(m) = mode {
                    self.mode = *m;
                }
                out.settings = Some((*mode, *method));
                true
            }
            Action::Move {
                arm,
                steer,
                level,
                to,
                offset_m,
                tolerance_m,
                attitude_rotvec,
                timeout_s,
            } => {
                let goal = Self::point(sim, facts.scene, to) + Vector3::from(*offset_m);
                let tool = sim.end_effector(Arm::BOTH[arm.index()]);
                let now = match steer {
                    Steer::Tool => tool.translation.vector,
                    Steer::Object => sim.object().pose.translation.vector,
                };
                let err = goal - now;
                let att = attitude_rotvec.map_or(Vector3::zeros(), |r| {
                    let want = UnitQuaternion::from_scaled_axis(Vector3::from(r));
                    rotation_error(&want, &tool.rotation)
                });
                let there = err.norm() <= *tolerance_m && att.norm() <= ATTITUDE_TOLERANCE_RAD;
                if there || elapsed > *timeout_s {
                    true
                } else {
                    let mut v = err * MOVE_GAIN_PER_M;
                    if v.norm() > 1.0 {
                        v /= v.norm();
                    }
                    out.axes[arm.index()][..3].copy_from_slice(v.as_slice());
                    if *level {
                        out.axes[arm.index()][3..].copy_from_slice(level_sticks(sim).as_slice());
                    } else {
                        let mut w = att * ATTITUDE_GAIN_PER_RAD;
                        if w.norm() > 1.0 {
                            w /= w.norm();
                        }
                        out.axes[arm.index()][3..].copy_from_slice(w.as_slice());
                    }
                    false
                }
            }
            Action::Joint {
                arm,
                joint,
                angle_deg,
                tolerance_deg,
                timeout_s,
            } => {
                let st = sim.arm(Arm::BOTH[arm.index()]);
                let q = st.q[*joint].to_degrees();
                let e = angle_deg - q;
                let still = !self.settle || st.qd[*joint].abs() <= JOINT_STILL_RAD_S;
                if (e.abs() <= *tolerance_deg && still) || elapsed > *timeout_s {
                    true
                } else {
                    out.axes[arm.index()][*joint] = (e * JOINT_GAIN_PER_DEG).clamp(-1.0, 1.0);
                    false
                }
            }
            Action::Grip {
                arm,
                close,
                timeout_s,
            } => {
                out.grips[arm.index()] = if *close { -1.0 } else { 1.0 };
                let a = Arm::BOTH[arm.index()];
                let holds =
                    sim.arm(a).holding || sim.panel().is_some_and(|p| p.held_by(a).is_some());
                elapsed > *timeout_s || (*close && holds)
            }
            Action::Object {
                velocity,
                until,
                timeout_s,
            } => {
                out.object = *velocity;
                until.evaluate(sim, facts).met || elapsed > *timeout_s
            }
            Action::Sticks {
                arm,
                axes,
                level,
                until,
                timeout_s,
            } => {
                out.axes[arm.index()] = *axes;
                if *level {
                    out.axes[arm.index()][3..].copy_from_slice(level_sticks(sim).as_slice());
                }
                until.evaluate(sim, facts).met || elapsed > *timeout_s
            }
            Action::Wait { s } => elapsed > *s,
            Action::WaitUntil { until, timeout_s } => {
                until.evaluate(sim, facts).met || elapsed > *timeout_s
            }
            Action::Diagnose { arm } => self.diagnose(sim, Arm::BOTH[arm.index()], &mut out),
        };
        // Holding a grip while the next actions run keeps a grasp: a closed jaw stays closed
        // with a zero command, so nothing more is needed here.
        if done {
            self.index += 1;
            self.started_s = None;
        }
        out
    }

    fn diagnose(&mut self, sim: &Simulation, arm: Arm, out: &mut PilotOutput) -> bool {
        // Joint mode: a centred stick shuts the valve (no servo holding the joint).
        if self.mode != ControlMode::Joint {
            self.mode = ControlMode::Joint;
            out.settings = Some((Some(ControlMode::Joint), None));
        }
        match self.diagnosis.tick(sim, arm, &mut out.axes[arm.index()]) {
            Some(answer) => {
                out.answer = Some(answer);
                self.answered = true;
                true
            }
            None => false,
        }
    }
    /// The stick mode the autopilot believes is set.
    pub fn mode(&self) -> ControlMode {
        self.mode
    }

    /// Whether it has sent its diagnosis.
    pub fn answered(&self) -> bool {
        self.answered
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hydraulics::Faults;
    use crate::model::{Model, ModelSpec};
    use crate::sim::{Input, SimParams};

    fn magnum() -> Model {
        let text = crate::robots::builtin_text("magnum").unwrap_or_else(|| panic!("magnum"));
        let spec: ModelSpec = serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}"));
        Model::from_spec(&spec).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Lim's case-study set-up, settled for 0.5 s, then `fault` on the left arm and 3 s for
    /// its symptom to develop (a stuck valve drives its joint to the stop); then the
    /// procedure, stepped in 20 ms slots with joint-mode sticks (stick = valve command).
    fn diagnose_with(fault: impl Fn(&mut Faults)) -> (&'static str, Diagnosis) {
        let m = magnum();
        let p = SimParams::case_study(&m, &m).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = Simulation::new(m.clone(), m, p).unwrap_or_else(|e| panic!("{e}"));
        let mut input = Input::default();
        for k in 0..3500 {
            if k == 500 {
                fault(sim.faults_mut(Arm::Left));
            }
            sim.step(&input);
        }
        let mut d = Diagnosis::default();
        for _ in 0..2000 {
            let mut axes = [0.0; 6];
            if let Some(answer) = d.tick(&sim, Arm::Left, &mut axes) {
                return (answer, d);
            }
            input.arms[0].valves = axes;
            for _ in 0..20 {
                sim.step(&input);
            }
        }
        panic!("no answer in 40 s");
    }

    /// A healthy arm crosses no threshold, each by a wide margin: the supply read from the
    /// spinning rotate motor is the nameplate (P_I + P_O = P_s for an equal-area motor in steady
    /// motion, eq. 3.48 with equal orifice flows in and out), the motor is at speed within one
    /// slot, and a shut valve holds the line pressures.
    #[test]
    fn healthy_arm_crosses_no_threshold() {
        let (_, d) = diagnose_with(|_| {});
        assert_eq!(d.phase, Phase::LeakWatch, "went the whole way");
        assert!((d.supply_ratio - 1.0).abs() < 0.02, "{}", d.supply_ratio);
        assert!(d.lag_ratio > 0.75, "{}", d.lag_ratio);
        assert!(
            d.leak_drift_pa < 0.25 * LEAK_DRIFT_PA,
            "{}",
            d.leak_drift_pa
        );
    }

    /// The supply read matches the dropped supply (the same closed form as above, with
    /// P_s − drop), and each fault kind is named, on joints and sizes other than the
    /// exercise file's.
    #[test]
    fn each_fault_is_named() {
        let (a, d) = diagnose_with(|f| f.supply_drop_pa = 2.0e6);
        assert_eq!(a, SUPPLY_DROP);
        let expected = (6.89e6 - 2.0e6) / 6.89e6;
        assert!(
            (d.supply_ratio - expected).abs() < 0.02,
            "{} vs {expected}",
            d.supply_ratio
        );
        // At its stop (wrist yaw at 21°/s reaches −60° from 0° within the 3 s; the wrist
        // pitch, the joint used before, now runs its jaw onto the seabed short of its stop) …
        let (a, d) = diagnose_with(|f| f.stuck_valve[4] = Some(-0.7));
        assert_eq!(a, STUCK_VALVE);
        assert!(
            d.tested == [false; 6]
                && matches!(
                    d.phase,
                    Phase::Jog {
                        joint: 4,
                        at_limit: true,
                        ..
                    }
                ),
            "{d:?}"
        );
        // … and still running (swing at 4°/s is 12° from 0 after 3 s, 25° is its stop).
        let (a, d) = diagnose_with(|f| f.stuck_valve[0] = Some(-0.2));
        assert_eq!(a, STUCK_VALVE);
        assert!(
            matches!(
                d.phase,
                Phase::Jog {
                    joint: 0,
                    at_limit: false,
                    ..
                }
            ),
            "{d:?}"
        );
        let (a, _) = diagnose_with(|f| f.leak_m3_s_pa[1] = 5e-11);
        assert_eq!(a, LEAK);
        let (a, d) = diagnose_with(|f| f.bulk_modulus_scale = 0.03);
        assert_eq!(a, AIR, "{d:?}");
    }
}
