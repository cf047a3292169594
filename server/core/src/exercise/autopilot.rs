//! The autopilot: a scripted controller that works an exercise through the trainee's own
//! controls only — stick axes, grips, the object sticks, settings and the diagnosis answer,
//! at the page's send rate — reading only what the trainee's page shows (poses, joint angles,
//! line pressures, grasp state, the task panel). Its script lives in the exercise file, so
//! the file itself proves the exercise can be done with the controls a trainee has.
//!
//! Each action runs until it is done or its `timeout_s` runs out (then the script goes on;
//! the assessment decides whether the attempt passed).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::condition::{Condition, Facts};
use super::spec::{ArmName, DrillFault, Method, Mode, Scene};
use crate::sim::{Arm, Simulation};

/// Interval between autopilot commands (s): 0.02, the page's 50 Hz send rate.
pub const PILOT_INTERVAL_S: f64 = 0.02;

/// A point the autopilot can steer a tool to (`{"handle": 0}`, `{"target": "t1"}`,
/// `{"zone": "z"}` (its centre on the seabed), `{"point": [x, y, z]}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointRef {
    /// A box handle (0: the left arm's, 1: the right arm's), where it is now.
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

/// One scripted action (`"do"` names the variant in the file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "do", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Change the stick mode and/or control method.
    Settings {
        /// New mode.
        #[serde(default)]
        mode: Option<Mode>,
        /// New method.
        #[serde(default)]
        method: Option<Method>,
    },
    /// Cartesian mode: steer `arm`'s tool to `to` + `offset_m` (proportional control on the
    /// linear sticks) until within `tolerance_m`.
    Move {
        /// Arm.
        arm: ArmName,
        /// Where.
        to: PointRef,
        /// Offset added to the point (m, world).
        #[serde(default)]
        offset_m: [f64; 3],
        /// Done within this distance (m).
        #[serde(default = "default_tolerance_m")]
        tolerance_m: f64,
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
    /// Close (or open) `arm`'s jaw: closing ends when the jaw holds the box or after
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
    /// Hold `arm`'s sticks at `axes` until `until`.
    Sticks {
        /// Arm.
        arm: ArmName,
        /// Axes in [−1, 1].
        axes: [f64; 6],
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
                PointRef::Handle(i) if *i > 1 => Err(format!("handle {i} is not 0 or 1")),
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
    pub settings: Option<(Option<Mode>, Option<Method>)>,
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
/// Proportional gain of `joint` (stick fraction per degree of error): full stick beyond 10°.
const JOINT_GAIN_PER_DEG: f64 = 0.1;

/// The fault-diagnosis procedure, from what the page shows: joint angles and line pressures.
///
/// 1. Sticks at zero for 1.5 s: a joint that moves by more than 2° with its stick at zero
///    has a **stuck valve** (a spool held open drives it at a good fraction of full speed).
/// 2. Still nothing? Drive the shoulder (joint 2) against its load at full stick for 1 s,
///    then let go; compare the highest inlet-side line pressure seen against the nominal
///    supply: below 75 % of it is a **supply drop**.
/// 3. With the stick at zero after that, a joint whose two line pressures converge (their
///    difference falls by more than half in 1.5 s) while it sags is **leaking** across the
///    piston; otherwise the slow pressure build-up is **air** in the oil.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Diagnosis {
    phase: u8,
    t0: f64,
    q0: [f64; 6],
    peak_p: f64,
    dp0: f64,
}

/// Runs a script.
#[derive(Debug, Clone)]
pub struct Autopilot {
    script: Vec<Action>,
    index: usize,
    started_s: Option<f64>,
    mode: Mode,
    diagnosis: Diagnosis,
    answered: bool,
}

impl Autopilot {
    /// Starts `script` with the sticks in `mode`.
    pub fn new(script: Vec<Action>, mode: Mode) -> Autopilot {
        Autopilot {
            script,
            index: 0,
            started_s: None,
            mode,
            diagnosis: Diagnosis::default(),
            answered: false,
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
                    o * nalgebra::Point3::from(sim.params().object.handles_m[(*i).min(1)])
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
                to,
                offset_m,
                tolerance_m,
                timeout_s,
            } => {
                let goal = Self::point(sim, facts.scene, to) + Vector3::from(*offset_m);
                let err = goal - sim.end_effector(Arm::BOTH[arm.index()]).translation.vector;
                if err.norm() <= *tolerance_m || elapsed > *timeout_s {
                    true
                } else {
                    let mut v = err * MOVE_GAIN_PER_M;
                    if v.norm() > 1.0 {
                        v /= v.norm();
                    }
                    out.axes[arm.index()][..3].copy_from_slice(v.as_slice());
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
                let q = sim.arm(Arm::BOTH[arm.index()]).q[*joint].to_degrees();
                let e = angle_deg - q;
                if e.abs() <= *tolerance_deg || elapsed > *timeout_s {
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
                elapsed > *timeout_s || (*close && sim.arm(Arm::BOTH[arm.index()]).holding)
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
                until,
                timeout_s,
            } => {
                out.axes[arm.index()] = *axes;
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
        let t = sim.time_s();
        let st = sim.arm(arm);
        let d = &mut self.diagnosis;
        let supply = sim.params().arms[arm.index()].hydraulics.supply_pa;
        let answer = |out: &mut PilotOutput, a: &'static str| {
            out.answer = Some(a);
            true
        };
        match d.phase {
            0 => {
                d.phase = 1;
                d.t0 = t;
                d.q0 = st.q;
                false
            }
            1 => {
                if st
                    .q
                    .iter()
                    .zip(d.q0)
                    .any(|(q, q0)| (q - q0).abs() > 2f64.to_radians())
                {
                    return answer(
                        out,
                        DrillFault::StuckValve {
                            joint: 0,
                            spool: 0.0,
                        }
                        .answer(),
                    );
                }
                if t - d.t0 > 1.5 {
                    d.phase = 2;
                    d.t0 = t;
                }
                false
            }
            2 => {
                out.axes[arm.index()][1] = 1.0;
                d.peak_p = d.peak_p.max(st.p_in[1].max(st.p_out[1]));
                if t - d.t0 > 1.0 {
                    if d.peak_p < 0.75 * supply {
                        return answer(out, DrillFault::SupplyDrop { drop_pa: 0.0 }.answer());
                    }
                    d.phase = 3;
                    d.t0 = t;
                    d.dp0 = (st.p_in[1] - st.p_out[1]).abs();
                }
                false
            }
            _ => {
                if t - d.t0 > 1.5 {
                    let dp = (st.p_in[1] - st.p_out[1]).abs();
                    let a = if dp < 0.5 * d.dp0 {
                        DrillFault::Leak {
                            joint: 0,
                            coefficient_m3_s_pa: 0.0,
                        }
                        .answer()
                    } else {
                        DrillFault::Air {
                            bulk_modulus_scale: 1.0,
                        }
                        .answer()
                    };
                    return answer(out, a);
                }
                false
            }
        }
    }

    /// The stick mode the autopilot believes is set.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Whether it has sent its diagnosis.
    pub fn answered(&self) -> bool {
        self.answered
    }
}
