//! Stage 0 of the step: the operator. The trainee's sticks (six axes and a grip per arm,
//! fractions of full stick), the object twist of the closed loop (fractions of the
//! controller's maximum speeds) and the settings (control mode, control method, arm speed)
//! become the simulation's [`Input`] for each step.
//!
//! [`Operator`] owns everything between the sticks and the valves that is not the
//! simulation: the one control-mode setting and the decision it makes ([`Operator::input`]:
//! joint mode puts each axis on its joint's valve, Cartesian mode resolves the axes into
//! joint-velocity references by redundancy resolution, [`cartesian_to_joint_velocity`]),
//! the two arms' redundancy resolvers, the method and speed setting, and the release timer
//! that drives both jaws open. The live session, the headless exercises, the replay and the
//! tests all drive the simulation through it ([`Operator::step`]).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::{Arm, ControlMethod, Input, Simulation};
use crate::control::teleop::{
    MAX_ANGULAR_SPEED_RAD_S, MAX_LINEAR_SPEED_M_S, cartesian_to_joint_velocity,
};
use crate::grasp::GraspState;
use crate::hydraulics::N_ACT;
use crate::model::Model;
use crate::redundancy::{Redundancy, RedundancyParams};

/// How the sticks are read (Lim §4.1 "control mode"). Wire and exercise-file names
/// `joint`, `cartesian`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ControlMode {
    /// Each axis drives one joint's valve.
    #[default]
    Joint,
    /// The axes are the tool's linear and angular velocity (world frame, fractions of
    /// [`crate::control::teleop::MAX_LINEAR_SPEED_M_S`] and
    /// [`crate::control::teleop::MAX_ANGULAR_SPEED_RAD_S`]); redundancy resolution picks
    /// the joint velocities.
    Cartesian,
}

/// Gain of the orientation hold (1/s): the angular rate commanded per radian of orientation
/// error while a Cartesian translation holds the jaw's orientation ([`Operator::input`]). A
/// time constant of 0.125 s, five times the valve spool's lag
/// ([`crate::hydraulics::SPOOL_TIME_CONSTANT_S`], 25 ms), so the correction does not excite
/// the servo; measured on 20 cm moves from the start posture (tests/orientation_hold.rs), the
/// jaw turns by at most 1.13° at K = 4 s⁻¹, 0.66° at 8 s⁻¹ and 0.40° at 12 s⁻¹ (the joint
/// servo's per-joint lag, caught up after the stick is centred, is what turns it).
pub const ORIENTATION_HOLD_GAIN_PER_S: f64 = 8.0;

/// How long the hold goes on after the translation stick is centred (s): the joints come to
/// rest at different rates (spool lag, inertia) and would turn the jaw by a degree or two
/// as they stop; the hold keeps correcting while they do.
pub const ORIENTATION_SETTLE_S: f64 = 0.5;

/// Orientation error (rad) above which the hold is reported lost (a joint limit or a
/// singularity keeps the resolver from turning the jaw back): 2°, twice the acceptance's 1°
/// over a 20 cm move.
pub const ORIENTATION_LOST_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// A jog at full arm speed and a full axis (the amounts scale with both): a joint turns by 2°
/// (joint mode); the jaw moves by 1 cm or turns by 2° (Cartesian mode). A keyboard tap is a
/// jog (issue 28: a tap moves a bounded, repeatable amount at every arm speed), small enough
/// to line a jaw up within the exercises' ±3° and 1 cm tolerances in a few taps.
pub const JOG_JOINT_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// See [`JOG_JOINT_RAD`].
pub const JOG_LINEAR_M: f64 = 0.01;
/// See [`JOG_JOINT_RAD`].
pub const JOG_ANGLE_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// Gain of a jog's approach to its target (1/s; rate ∝ remaining distance, at most the
/// joints' nominal speeds or the Cartesian maxima, times the arm speed).
pub const JOG_GAIN_PER_S: f64 = 8.0;
/// A jog gives up after this long (s): a target behind an obstacle or a limit.
pub const JOG_TIMEOUT_S: f64 = 3.0;
/// A jog is done within these of its target: 0.01° per joint; 0.1 mm and 0.01° for the jaw.
const JOG_DONE_RAD: f64 = 0.01 * std::f64::consts::PI / 180.0;
const JOG_DONE_M: f64 = 1.0e-4;

/// A jog under way: its target, and when it gives up.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Jog {
    /// Joint angles (rad), joint mode.
    Joints([f64; N_ACT], f64),
    /// The jaw's pose (world), Cartesian mode.
    Pose(Isometry3<f64>, f64),
}

/// One arm's sticks: six axes and the grip, each in [−1, 1] (fractions of full stick).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sticks {
    /// Joint mode: one valve per axis (joints 1–6). Cartesian mode: the tool's velocity
    /// [vx vy vz wx wy wz] (world frame).
    pub axes: [f64; N_ACT],
    /// Jaw: + opens, − closes.
    pub grip: f64,
}

/// The operator stage: the settings, the latest sticks, the resolvers and the release timer
/// (see the module docs). Preallocated: [`Operator::input`] does not allocate.
#[derive(Debug, Clone)]
pub struct Operator {
    /// The control mode.
    mode: ControlMode,
    /// The latest sticks per arm (left, right).
    sticks: [Sticks; 2],
    /// The latest object twist command (fractions of the controller's maximum speeds).
    object: [f64; 6],
    /// Both jaws are driven open until this simulated time (s).
    release_until_s: f64,
    /// Redundancy resolvers for Cartesian mode, one per arm.
    redundancy: [Redundancy; 2],
    /// The arm models (left, right) in their own base frames, as the resolvers use them.
    models: [Model; 2],
    /// Cartesian translation holds the jaw's orientation (default) or leaves the three spare
    /// DOF to the redundancy resolution (the translational-only option).
    hold_orientation: bool,
    /// Per arm: the jaw orientation (world) held during the current translation, and the
    /// simulated time until which it is held after the stick is centred.
    held: [Option<(UnitQuaternion<f64>, f64)>; 2],
    /// Per arm: the held orientation's error at the last input (rad; 0 when not holding).
    orientation_error_rad: [f64; 2],
    /// Per arm: the jog under way ([`Operator::jog`]).
    jogs: [Option<Jog>; 2],
    /// The next step's input: method and speed are the settings; valves, jaws, joint-velocity
    /// references and the object twist are filled by [`Operator::input`].
    input: Input,
}

impl Operator {
    /// An operator for arms `left` and `right` (the models as given to [`Simulation::new`],
    /// in their own base frames): joint mode, open loop, full speed, sticks centred.
    pub fn new(left: &Model, right: &Model) -> Operator {
        Operator {
            mode: ControlMode::Joint,
            sticks: [Sticks::default(); 2],
            object: [0.0; 6],
            release_until_s: 0.0,
            redundancy: [
                Redundancy::new(left, RedundancyParams::default()),
                Redundancy::new(right, RedundancyParams::default()),
            ],
            models: [left.clone(), right.clone()],
            hold_orientation: true,
            held: [None; 2],
            orientation_error_rad: [0.0; 2],
            jogs: [None; 2],
            input: Input::default(),
        }
    }

    /// Whether a Cartesian translation holds the jaw's orientation (the default).
    pub fn hold_orientation(&self) -> bool {
        self.hold_orientation
    }

    /// Cartesian translation holds the jaw's orientation (`true`, the default) or resolves
    /// only the three translational rows, leaving the spare DOF to the redundancy resolution
    /// (`false`).
    pub fn set_hold_orientation(&mut self, hold: bool) {
        self.hold_orientation = hold;
        self.held = [None; 2];
        self.orientation_error_rad = [0.0; 2];
    }

    /// `arm`'s orientation error while a translation holds it (rad; 0 otherwise): above
    /// [`ORIENTATION_LOST_RAD`] the hold is lost (a limit or a singularity).
    pub fn orientation_error_rad(&self, arm: Arm) -> f64 {
        self.orientation_error_rad[arm.index()]
    }

    /// The control mode.
    pub fn mode(&self) -> ControlMode {
        self.mode
    }

    /// The control method.
    pub fn method(&self) -> ControlMethod {
        self.input.method
    }

    /// The arm speed setting (Lim §4.1 "arm speed"; the simulation clamps it to [0, 1]).
    pub fn speed(&self) -> f64 {
        self.input.speed_scale
    }

    /// Sets the control mode; every stick command stops (a stick held over the change must
    /// not drive the arm the other way).
    pub fn set_mode(&mut self, mode: ControlMode) {
        self.mode = mode;
        self.held = [None; 2];
        self.jogs = [None; 2];
        for s in &mut self.sticks {
            s.axes = [0.0; N_ACT];
        }
    }

    /// Sets the control method (applies from the next step).
    pub fn set_method(&mut self, method: ControlMethod) {
        self.input.method = method;
    }

    /// Sets the arm speed (applies from the next step).
    pub fn set_speed(&mut self, speed: f64) {
        self.input.speed_scale = speed;
    }

    /// New sticks for both arms and the object twist command (fractions of the controller's
    /// maximum speeds, [`crate::control::ControlParams::max_object_speed_m_s`] and
    /// [`crate::control::ControlParams::max_object_rate_rad_s`]). A grip ends a release's
    /// hold on the jaws.
    pub fn set_sticks(&mut self, sticks: &[Sticks; 2], object: &[f64; 6]) {
        self.sticks = *sticks;
        self.object = *object;
    }

    /// Drives both jaws open until simulated time `until_s`, whatever the grips say; after
    /// it the jaws stay open until the next [`Operator::set_sticks`].
    pub fn release(&mut self, until_s: f64) {
        self.release_until_s = until_s;
    }

    /// Back to rest: sticks centred, no release, fresh resolvers (an attempt's start never
    /// depends on what came before it). The settings are kept.
    pub fn reset(&mut self) {
        self.sticks = [Sticks::default(); 2];
        self.object = [0.0; 6];
        self.release_until_s = 0.0;
        self.redundancy = [
            Redundancy::new(&self.models[0], RedundancyParams::default()),
            Redundancy::new(&self.models[1], RedundancyParams::default()),
        ];
        self.input.arms = Default::default();
        self.input.object_velocity = [0.0; 6];
        self.held = [None; 2];
        self.orientation_error_rad = [0.0; 2];
        self.jogs = [None; 2];
    }

    /// A jog of `arm` (a keyboard tap): `axes` (each in [−1, 1], as a stick's; clamped,
    /// non-finite read as 0) times the arm speed times [`JOG_JOINT_RAD`] per joint in joint
    /// mode, or [`JOG_LINEAR_M`] along and [`JOG_ANGLE_RAD`] about the world axes at the jaw in
    /// Cartesian mode. The target is taken from `sim` now (joint targets within the limits);
    /// the arm goes there by the joint servo and stops, whatever the tap's length. A stick
    /// on that arm, a mode change or a reset cancels it; it gives up after
    /// [`JOG_TIMEOUT_S`]. Nothing in closed loop while both jaws hold (the object is driven
    /// then).
    pub fn jog(&mut self, sim: &Simulation, arm: Arm, axes: &[f64; N_ACT]) {
        let a: [f64; N_ACT] =
            core::array::from_fn(|k| crate::finite_or(axes[k], 0.0).clamp(-1.0, 1.0));
        let i = arm.index();
        let speed = crate::finite_or(self.input.speed_scale, 0.0).clamp(0.0, 1.0);
        if a.iter().all(|v| *v == 0.0) || speed == 0.0 {
            return;
        }
        let until = sim.time_s() + JOG_TIMEOUT_S;
        self.jogs[i] = Some(match self.mode {
            ControlMode::Joint => {
                let q = sim.arm(arm).q;
                let joints = &sim.model(arm).joints;
                Jog::Joints(
                    core::array::from_fn(|j| {
                        let t = q[j] + a[j] * speed * JOG_JOINT_RAD;
                        let [lo, hi] = joints[j].limits;
                        t.clamp(lo.min(q[j]), hi.max(q[j]))
                    }),
                    until,
                )
            }
            ControlMode::Cartesian => {
                let now = sim.end_effector(arm);
                let d = Vector3::new(a[0], a[1], a[2]) * (speed * JOG_LINEAR_M);
                let r = UnitQuaternion::from_scaled_axis(
                    Vector3::new(a[3], a[4], a[5]) * (speed * JOG_ANGLE_RAD),
                );
                Jog::Pose(
                    Isometry3::from_parts(
                        Translation3::from(now.translation.vector + d),
                        r * now.rotation,
                    ),
                    until,
                )
            }
        });
    }

    /// Whether `arm` has a jog under way.
    pub fn jogging(&self, arm: Arm) -> bool {
        self.jogs[arm.index()].is_some()
    }

    /// No stick, grip or object input: every axis and grip below `threshold` in magnitude
    /// and no object twist in the last [`Operator::input`] (|v| < 10⁻¹²).
    pub fn idle(&self, threshold: f64) -> bool {
        let small = |v: &f64| v.abs() < threshold;
        self.sticks
            .iter()
            .all(|s| s.axes.iter().all(small) && small(&s.grip))
            && self.input.object_velocity.iter().all(|v| v.abs() < 1e-12)
    }

    /// Stage 0: the input of `sim`'s next step. While a release runs both jaws are driven
    /// open. Joint mode puts each axis on its valve; Cartesian mode turns each arm's axes
    /// into a joint-velocity reference for the joint servo ([`cartesian_to_joint_velocity`]),
    /// holding the tool's orientation while both jaws hold the object (their closed chain
    /// fixes it) and, with [`Operator::hold_orientation`], during a translation of a jaw that
    /// holds nothing: the jaw's
    /// orientation when the translation began is held by an angular-rate command
    /// ω = K·θ (θ the rotation vector from the jaw's orientation to the held one, world;
    /// K = [`ORIENTATION_HOLD_GAIN_PER_S`]) on the six-row resolution, and for
    /// [`ORIENTATION_SETTLE_S`] after the stick is centred. Turning the jaw (an angular axis)
    /// ends the hold. The object twist is scaled to the
    /// controller's maximum speeds.
    pub fn input(&mut self, sim: &Simulation) -> &Input {
        let releasing = sim.time_s() < self.release_until_s;
        let chain = sim.grasp_state() == GraspState::BothHolding;
        let dt_s = sim.params().step.dt_s;
        for arm in Arm::BOTH {
            let i = arm.index();
            if releasing {
                self.sticks[i].grip = 1.0;
            }
            let a = &mut self.input.arms[i];
            a.jaw = self.sticks[i].grip;
            // A jog runs while its arm's sticks are centred (a stick takes over).
            if self.sticks[i].axes.iter().any(|v| *v != 0.0)
                || self.jogs[i].is_some_and(|j| match j {
                    Jog::Joints(_, until) | Jog::Pose(_, until) => sim.time_s() >= until,
                })
            {
                self.jogs[i] = None;
            }
            if let Some(jog) = self.jogs[i] {
                let (valves, qd_ref, done) = jog_step(
                    &jog,
                    sim,
                    arm,
                    &mut self.redundancy[i],
                    &self.models[i],
                    dt_s,
                );
                (a.valves, a.joint_velocity_ref) = (valves, Some(qd_ref));
                if done {
                    self.jogs[i] = None;
                }
                continue;
            }
            // The control-mode decision (the only one).
            (a.valves, a.joint_velocity_ref) = match self.mode {
                ControlMode::Joint => (self.sticks[i].axes, None),
                ControlMode::Cartesian => {
                    let mut axes = self.sticks[i].axes;
                    let translating = axes[..3].iter().any(|v| *v != 0.0);
                    let turning = axes[3..].iter().any(|v| *v != 0.0);
                    let t = sim.time_s();
                    let settling = self.held[i].is_some_and(|(_, until)| t < until);
                    // Not while the jaw holds the box: a box lifted by one jaw pivots on its
                    // seabed edge and turns the jaw with it (held, the pads' torsion limit
                    // let the bar go at lift-off; the attitude is the operator's before the
                    // grasp).
                    let free = !sim.arm(arm).holding;
                    let hold = self.hold_orientation
                        && free
                        && (translating || settling)
                        && !turning
                        && !chain;
                    self.orientation_error_rad[i] = 0.0;
                    if hold {
                        let now = sim.end_effector(arm).rotation;
                        let (held, _) = *self.held[i].get_or_insert((now, 0.0));
                        if translating {
                            self.held[i] = Some((held, t + ORIENTATION_SETTLE_S));
                        }
                        let theta = (held * now.inverse()).scaled_axis();
                        self.orientation_error_rad[i] = theta.norm();
                        for k in 0..3 {
                            axes[3 + k] = (ORIENTATION_HOLD_GAIN_PER_S * theta[k]
                                / MAX_ANGULAR_SPEED_RAD_S)
                                .clamp(-1.0, 1.0);
                        }
                    } else {
                        self.held[i] = None;
                    }
                    (
                        [0.0; N_ACT],
                        Some(cartesian_to_joint_velocity(
                            &mut self.redundancy[i],
                            &self.models[i],
                            &sim.params().arms[i].base.rotation,
                            &sim.arm(arm).q,
                            &axes,
                            chain || hold,
                            dt_s,
                        )),
                    )
                }
            };
        }
        let cp = &sim.params().control;
        for (k, (v, f)) in self
            .input
            .object_velocity
            .iter_mut()
            .zip(self.object)
            .enumerate()
        {
            let max = if k < 3 {
                cp.max_object_speed_m_s
            } else {
                cp.max_object_rate_rad_s
            };
            *v = f * max;
        }
        &self.input
    }

    /// Stage 0 and the step: [`Operator::input`], then [`Simulation::step`].
    pub fn step(&mut self, sim: &mut Simulation) {
        let input = self.input(sim);
        sim.step(input);
    }
}

/// One input of a jog: centred valves and the servo's joint-velocity reference towards the
/// target (rate = [`JOG_GAIN_PER_S`] × the remaining distance, capped at the nominal joint
/// speeds or the Cartesian maxima), and whether the target is reached.
fn jog_step(
    jog: &Jog,
    sim: &Simulation,
    arm: Arm,
    resolver: &mut Redundancy,
    model: &Model,
    dt_s: f64,
) -> ([f64; N_ACT], [f64; N_ACT], bool) {
    match jog {
        Jog::Joints(target, _) => {
            let q = sim.arm(arm).q;
            let hp = &sim.params().arms[arm.index()].hydraulics;
            let done = (0..N_ACT).all(|j| (target[j] - q[j]).abs() < JOG_DONE_RAD);
            let qd = core::array::from_fn(|j| {
                let max = hp.actuators[j].nominal_speed_rad_s;
                (JOG_GAIN_PER_S * (target[j] - q[j])).clamp(-max, max)
            });
            ([0.0; N_ACT], if done { [0.0; N_ACT] } else { qd }, done)
        }
        Jog::Pose(target, _) => {
            let now = sim.end_effector(arm);
            let dp = target.translation.vector - now.translation.vector;
            let theta = (target.rotation * now.rotation.inverse()).scaled_axis();
            let done = dp.norm() < JOG_DONE_M && theta.norm() < JOG_DONE_RAD;
            if done {
                return ([0.0; N_ACT], [0.0; N_ACT], true);
            }
            let axes: [f64; N_ACT] = core::array::from_fn(|k| {
                let v = if k < 3 {
                    dp[k] / MAX_LINEAR_SPEED_M_S
                } else {
                    theta[k - 3] / MAX_ANGULAR_SPEED_RAD_S
                };
                (JOG_GAIN_PER_S * v).clamp(-1.0, 1.0)
            });
            let qd = cartesian_to_joint_velocity(
                resolver,
                model,
                &sim.params().arms[arm.index()].base.rotation,
                &sim.arm(arm).q,
                &axes,
                true,
                dt_s,
            );
            ([0.0; N_ACT], qd, false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ModelSpec;
    use crate::sim::SimParams;

    fn setup() -> (Operator, Simulation) {
        let text = crate::robots::builtin_text("magnum").unwrap_or_else(|| panic!("magnum"));
        let spec: ModelSpec = serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}"));
        let m = Model::from_spec(&spec).unwrap_or_else(|e| panic!("{e}"));
        let p = SimParams::case_study(&m, &m).unwrap_or_else(|e| panic!("{e}"));
        let op = Operator::new(&m, &m);
        let sim = Simulation::new(m.clone(), m, p).unwrap_or_else(|e| panic!("{e}"));
        (op, sim)
    }

    const AXES: [f64; 6] = [0.5, -0.25, 0.0, 0.0, 0.75, -1.0];

    /// Joint mode puts each axis on its valve; Cartesian mode leaves the valves centred and
    /// gives the servo a joint-velocity reference (zero for a centred stick), the same axes
    /// read the other way; a mode change centres the sticks but not the grips.
    #[test]
    fn the_mode_decides_how_the_axes_are_read() {
        let (mut op, sim) = setup();
        let sticks = [
            Sticks {
                axes: AXES,
                grip: -0.5,
            },
            Sticks::default(),
        ];
        op.set_sticks(&sticks, &[0.0; 6]);
        let joint = *op.input(&sim);
        assert_eq!(joint.arms[0].valves, AXES);
        assert_eq!(joint.arms[0].jaw, -0.5);
        assert!(joint.arms.iter().all(|a| a.joint_velocity_ref.is_none()));
        op.set_mode(ControlMode::Cartesian);
        assert_eq!(
            op.input(&sim).arms[0].jaw,
            -0.5,
            "grips survive a mode change"
        );
        let linear = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
        op.set_sticks(
            &[
                Sticks {
                    axes: linear,
                    grip: 0.0,
                },
                Sticks::default(),
            ],
            &[0.0; 6],
        );
        let cart = *op.input(&sim);
        assert_eq!(cart.arms[0].valves, [0.0; 6]);
        let qd = cart.arms[0]
            .joint_velocity_ref
            .unwrap_or_else(|| panic!("a reference"));
        assert!(qd.iter().any(|v| v.abs() > 1e-6), "{qd:?}");
        assert_eq!(cart.arms[1].joint_velocity_ref, Some([0.0; 6]));
        // The reference moves the tool as commanded: J·q̇ ≈ 0.5 × 0.2 m/s along world x
        // (teleop::MAX_LINEAR_SPEED_M_S), computed with the simulation's world Jacobian.
        let v = sim.jacobian_world(Arm::Left) * nalgebra::Vector6::from(qd);
        assert!(
            (v[0] - 0.1).abs() < 1e-3 && v[1].abs() < 1e-3 && v[2].abs() < 1e-3,
            "{v}"
        );
    }

    /// A release drives both jaws open until its end, and they stay open until new sticks.
    #[test]
    fn a_release_opens_the_jaws_until_new_sticks() {
        let (mut op, mut sim) = setup();
        let closing = [Sticks {
            axes: [0.0; 6],
            grip: -1.0,
        }; 2];
        op.set_sticks(&closing, &[0.0; 6]);
        op.release(sim.time_s() + 0.005);
        for _ in 0..10 {
            op.step(&mut sim);
            assert_eq!(op.input(&sim).arms.map(|a| a.jaw), [1.0, 1.0]);
        }
        op.set_sticks(&closing, &[0.0; 6]);
        assert_eq!(op.input(&sim).arms.map(|a| a.jaw), [-1.0, -1.0]);
    }

    /// The object twist is a fraction of the controller's maximum speeds (ControlParams:
    /// 0.2 m/s, 0.5 rad/s); method and speed are the settings.
    #[test]
    fn the_object_twist_and_the_settings_reach_the_input() {
        let (mut op, sim) = setup();
        op.set_method(ControlMethod::Closed);
        op.set_speed(0.5);
        op.set_sticks(&[Sticks::default(); 2], &[1.0, 0.0, -0.5, 0.0, 0.0, 1.0]);
        let input = *op.input(&sim);
        assert!(!op.idle(0.05));
        assert_eq!(input.object_velocity, [0.2, 0.0, -0.1, 0.0, 0.0, 0.5]);
        assert_eq!(
            (input.method, input.speed_scale),
            (ControlMethod::Closed, 0.5)
        );
        op.reset();
        op.input(&sim);
        assert!(op.idle(0.05));
        assert_eq!((op.method(), op.speed()), (ControlMethod::Closed, 0.5));
    }
}
