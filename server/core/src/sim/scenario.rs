//! Scripted scenarios: the four dynamic case studies of Lim §4.2 as time charts (pure data),
//! and the runner loop that steps a [`Simulation`] through one and produces post-processing
//! rows (Lim §4.2: "dynamics data of both arms … are saved to files for post processing") and
//! a summary.
//!
//! The thesis's time charts (Figs 4-5, 4-12, 4-17, 4-29) survive only as captions, so the
//! stages follow the text; durations and signal levels are chosen here. Reaching the handle
//! (stage A) is scripted as a joint-space move to an IK posture through the joint servo: the
//! thesis's operator steered the jaw onto the object by joystick, which a fixed open-loop
//! script cannot reproduce to within the 4 cm capture radius. All other stages use the
//! open-loop valve signals (case studies 1–3) or the cooperative closed loop (case study 4) as
//! in the thesis.

use nalgebra::{DMatrix, Point3, Vector3};

use super::{Arm, ControlMethod, Input, SimParams, Simulation};
use crate::Error;
use crate::grasp::GraspState;
use crate::hydraulics::N_ACT;
use crate::kinematics::{self, KinData};
use crate::model::Model;

mod row;
pub use row::{Cell, Row, row};

/// What one arm does during a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArmCommand {
    /// Joystick valve commands (open loop) and jaw command.
    Valves {
        /// Six valve commands in [−1, 1].
        valves: [f64; N_ACT],
        /// Jaw command in [−1, 1] (+ opens).
        jaw: f64,
    },
    /// Move to a joint posture through the joint servo (q̇_ref = 2 s⁻¹·(q* − q), at most half
    /// the nominal speed), and jaw command.
    JointTarget {
        /// Target posture (rad).
        q: [f64; N_ACT],
        /// Jaw command.
        jaw: f64,
    },
}

impl ArmCommand {
    /// Valves at rest with a jaw command.
    pub const fn jaw(jaw: f64) -> ArmCommand {
        ArmCommand::Valves {
            valves: [0.0; N_ACT],
            jaw,
        }
    }
    /// One valve at `u`, others 0, jaw command `jaw`.
    pub const fn valve(j: usize, u: f64, jaw: f64) -> ArmCommand {
        let mut valves = [0.0; N_ACT];
        valves[j] = u;
        ArmCommand::Valves { valves, jaw }
    }
}

/// One stage of a time chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// Stage label of the thesis's chart ("A" … "E").
    pub stage: &'static str,
    /// Duration (s).
    pub duration_s: f64,
    /// Left (0) and right (1) arm commands.
    pub arms: [ArmCommand; 2],
    /// Control method.
    pub method: ControlMethod,
    /// Commanded object twist for closed loop (m/s, rad/s).
    pub object_velocity: [f64; 6],
}

impl Segment {
    fn open(stage: &'static str, duration_s: f64, left: ArmCommand, right: ArmCommand) -> Segment {
        Segment {
            stage,
            duration_s,
            arms: [left, right],
            method: ControlMethod::Open,
            object_velocity: [0.0; 6],
        }
    }
    fn closed(stage: &'static str, duration_s: f64, jaw: f64, v: [f64; 6]) -> Segment {
        Segment {
            stage,
            duration_s,
            arms: [ArmCommand::jaw(jaw); 2],
            method: ControlMethod::Closed,
            object_velocity: v,
        }
    }
}

/// A scripted scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name, e.g. `case1-single-arm`.
    pub name: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// Simulation parameters.
    pub params: SimParams,
    /// Time chart.
    pub segments: Vec<Segment>,
    /// Object lift commanded in closed loop (m), if any.
    pub commanded_lift_m: Option<f64>,
}

/// Names and descriptions of the built-in scenarios.
pub const SCENARIOS: &[(&str, &str)] = &[
    (
        "case1-single-arm",
        "Lim case study 1 (Fig. 4-5): left arm, no object; each joint driven in turn by a joystick signal, then released",
    ),
    (
        "case2-single-arm-load",
        "Lim case study 2 (Fig. 4-12): left arm reaches, grabs the 50 kg object, lifts it open loop, holds, releases it",
    ),
    (
        "case3-dual-open-loop",
        "Lim case study 3 (Fig. 4-17): right then left arm grab the object; open-loop lift and move left; release",
    ),
    (
        "case4-dual-closed-loop",
        "Lim case study 4 (Fig. 4-29): as case 3, but switched to closed-loop cooperative control to lift 0.2 m and move left",
    ),
];

/// Position-only damped-least-squares IK for the tool point of `model` (base frame), from
/// `q0`, respecting joint limits. Allocates (scenario set-up only).
pub fn ik_position(
    model: &Model,
    target: &Vector3<f64>,
    q0: &[f64; N_ACT],
) -> Result<[f64; N_ACT], Error> {
    let mut q = *q0;
    let mut kin = KinData::new(model);
    let mut err = f64::INFINITY;
    for _ in 0..500 {
        kinematics::jacobian(model, &mut kin, &q);
        let e = target - kin.tool_point;
        err = e.norm();
        if err < 1e-6 {
            return Ok(q);
        }
        let jv = kin.jacobian.rows(0, 3).into_owned();
        let a = &jv * jv.transpose() + DMatrix::<f64>::identity(3, 3) * 1e-4;
        let Some(ch) = a.cholesky() else { break };
        let dq = jv.transpose() * ch.solve(&DMatrix::from_column_slice(3, 1, e.as_slice()));
        for j in 0..N_ACT {
            let lim = model.joints[j].limits;
            q[j] = (q[j] + 0.5 * dq[j]).clamp(lim[0], lim[1]);
        }
    }
    Err(Error::NotConverged {
        what: "scenario IK",
        iterations: 500,
        residual: err,
    })
}

/// Height of the tool point over a side handle bar's centre at the case studies' grasp (m):
/// 0.01. The jaw, turned onto the bar by the wrist rotate alone, keeps the tilt the position
/// IK gives it; its fingers (4 cm tall, centred on the tool point) then reach down past the bar
/// (3 cm above the top face) far enough to touch the face. 1 cm up they clear it, and the pads
/// still cover 3 of the bar's 4 cm.
const GRIP_ABOVE_CENTRE_M: f64 = 0.01;

/// Postures of `arm` on the way to its handle: its reset tool point raised to `above_m` over
/// the handle (clear of the box: a joint-space move straight from the reset posture, whose jaw
/// is beside the box and below its top, would sweep the jaw through the box's side), then
/// `above_m` over the handle, then at it; the last two with the wrist rotate turned so that
/// the jaw's closing axis is normal to the bar ([`align_rotate`]): only the rotate moves (it
/// does not move the tool point), so the case studies keep the postures their figures were
/// taken at; the roll off the flats that the position IK leaves is within the tolerance
/// ([`crate::grasp::GripParams::max_roll_rad`]). [`align_jaw`] aligns the jaw fully, at the
/// cost of a different posture.
fn approach(
    params: &SimParams,
    model: &Model,
    arm: Arm,
    above_m: f64,
) -> Result<[[f64; N_ACT]; 3], Error> {
    let op = &params.object;
    let arm = arm.index();
    let base = &params.arms[arm].base;
    let mut obj = op.initial_pose;
    obj.translation.vector.z -= op.mass_kg * 9.81 / (4.0 * op.contact_stiffness_n_m);
    let handle = &op.handles[arm];
    // The tool point GRIP_ABOVE_CENTRE_M over the bar's centre (the pads take its upper part).
    let grip = handle.centre_m + Vector3::z() * GRIP_ABOVE_CENTRE_M;
    let local = (base.inverse() * obj * Point3::from(grip)).coords;
    let mut pre = ik_position(
        model,
        &(local + Vector3::new(0.0, 0.0, above_m)),
        &params.arms[arm].initial_q,
    )?;
    let mut at = ik_position(model, &local, &pre)?;
    let axis = base.inverse_transform_vector(&(obj.rotation * handle.axis));
    at[N_ACT - 1] = align_rotate(model, &at, &axis);
    pre[N_ACT - 1] = at[N_ACT - 1];
    let q0 = &params.arms[arm].initial_q;
    let mut up = kinematics::end_effector_pose(model, q0).translation.vector;
    up.z = local.z + above_m;
    let up = ik_position(model, &up, q0)?;
    Ok([up, pre, at])
}

/// The wrist-rotate angle (the last joint, about the tool's z axis; it does not move the tool
/// point) nearest to `q`'s at which the jaw's closing axis (tool y) is normal to a bar along
/// `axis` (base frame): tool y(θ) = cos θ·y₀ − sin θ·x₀ for a turn θ, so y·a = 0 at
/// tan θ = (y₀·a)/(x₀·a). Both senses of the turn are tried (the joint's sense in the tool
/// frame) and the better kept. Allocates (scenario set-up only).
pub fn align_rotate(model: &Model, q: &[f64; N_ACT], axis: &Vector3<f64>) -> f64 {
    let tool = kinematics::end_effector_pose(model, q);
    let (x0, y0) = (tool.rotation * Vector3::x(), tool.rotation * Vector3::y());
    let theta = y0.dot(axis).atan2(x0.dot(axis));
    // The smallest turn with y·a = 0: θ modulo π into [−π/2, π/2].
    let theta = theta - (theta / std::f64::consts::PI).round() * std::f64::consts::PI;
    let skew = |qr: f64| {
        let mut t = *q;
        t[N_ACT - 1] = qr;
        let y = kinematics::end_effector_pose(model, &t).rotation * Vector3::y();
        y.dot(axis).abs()
    };
    let last = q[N_ACT - 1];
    if skew(last + theta) <= skew(last - theta) {
        last + theta
    } else {
        last - theta
    }
}

/// Damped-least-squares IK from `q0` (respecting joint limits) that keeps the tool point at
/// `target` (base frame) and turns the jaw onto a bar with axis `axis` and flat normal `flat`
/// (base frame): the closing axis (tool y) normal to the bar and along the pair of flats it is
/// nearer to (skew and roll 0, [`crate::grasp::Alignment`]); the bar's angle in the pads'
/// plane is left free. Five conditions on six joints; finite-difference Jacobian. Allocates
/// (scenario set-up only).
pub fn align_jaw(
    model: &Model,
    q0: &[f64; N_ACT],
    target: &Vector3<f64>,
    axis: &Vector3<f64>,
    flat: &Vector3<f64>,
) -> Result<[f64; N_ACT], Error> {
    let other = axis.cross(flat);
    let n0 = kinematics::end_effector_pose(model, q0).rotation * Vector3::y();
    // The closing axis goes along the nearer pair of flats: normal to the other pair.
    let normal_to = if n0.dot(flat).abs() >= n0.dot(&other).abs() {
        other
    } else {
        *flat
    };
    let residual = |q: &[f64; N_ACT]| {
        let t = kinematics::end_effector_pose(model, q);
        let n = t.rotation * Vector3::y();
        let e = t.translation.vector - target;
        nalgebra::DVector::from_column_slice(&[e.x, e.y, e.z, n.dot(axis), n.dot(&normal_to)])
    };
    let mut q = *q0;
    let mut err = f64::INFINITY;
    for _ in 0..200 {
        let r = residual(&q);
        err = r.norm();
        if err < 1e-9 {
            return Ok(q);
        }
        let mut j = DMatrix::<f64>::zeros(5, N_ACT);
        for c in 0..N_ACT {
            let mut qp = q;
            qp[c] += 1e-7;
            j.set_column(c, &((residual(&qp) - &r) / 1e-7));
        }
        let a = &j * j.transpose() + DMatrix::<f64>::identity(5, 5) * 1e-6;
        let Some(ch) = a.cholesky() else { break };
        let dq = j.transpose() * ch.solve(&r);
        for c in 0..N_ACT {
            let lim = model.joints[c].limits;
            q[c] = (q[c] - 0.5 * dq[c]).clamp(lim[0], lim[1]);
        }
    }
    Err(Error::NotConverged {
        what: "scenario jaw alignment",
        iterations: 200,
        residual: err,
    })
}

/// Jaw command that opens the jaw fully.
const OPEN: f64 = 1.0;
/// Jaw command that closes the jaw fully.
const CLOSE: f64 = -1.0;
/// Both valves and jaw at rest.
const REST: ArmCommand = ArmCommand::jaw(0.0);

/// Builds scenario `name` for the two models, in the thesis's setting: in air, rigid grasp
/// (Lim §3.5.2.1 assumption (i)) and the closed loop's equal share W⁺ (eq. 3.46). Set
/// [`SimParams::rigid_grasp`] false on the result for the jaws' finite grip (and
/// [`crate::control::ControlParams::moment_free_share`] true for the share it can carry).
pub fn scenario(name: &str, left: &Model, right: &Model) -> Result<Scenario, Error> {
    let mut params = SimParams::case_study(left, right)?;
    params.rigid_grasp = true;
    params.control.moment_free_share = false;
    let Some(idx) = SCENARIOS.iter().position(|(n, _)| *n == name) else {
        return Err(Error::InvalidParameter {
            what: "scenario",
            reason: format!("unknown scenario {name:?}"),
        });
    };
    let (name, description) = SCENARIOS[idx];
    let mut commanded_lift_m = None;
    let segments = match idx {
        0 => joint_sweep(),
        1 => single_arm_load(&params, left)?,
        _ => {
            let mut segments = dual_grasp(&params, left, right)?;
            if idx == 2 {
                segments.extend(open_loop_lift());
            } else {
                let (lift, lift_m) = closed_loop_lift();
                segments.extend(lift);
                commanded_lift_m = Some(lift_m);
            }
            segments
        }
    };
    Ok(Scenario {
        name,
        description,
        params,
        segments,
        commanded_lift_m,
    })
}

/// Case study 1: each joint of the left arm +0.6 for 2 s, pause 1 s, −0.6 for 2 s, pause 1 s;
/// then 4 s at rest.
fn joint_sweep() -> Vec<Segment> {
    let mut segments = Vec::new();
    for j in 0..N_ACT {
        segments.push(Segment::open(
            "A",
            2.0,
            ArmCommand::valve(j, 0.6, 0.0),
            REST,
        ));
        segments.push(Segment::open("A", 1.0, REST, REST));
        segments.push(Segment::open(
            "A",
            2.0,
            ArmCommand::valve(j, -0.6, 0.0),
            REST,
        ));
        segments.push(Segment::open("A", 1.0, REST, REST));
    }
    segments.push(Segment::open("B", 4.0, REST, REST));
    segments
}

/// Case study 2: the left arm reaches the handle (A), grabs (B), lifts with the shoulder open
/// loop and holds (C), releases (D).
fn single_arm_load(params: &SimParams, left: &Model) -> Result<Vec<Segment>, Error> {
    let [up, pre, at] = approach(params, left, Arm::Left, 0.10)?;
    Ok(vec![
        Segment::open("A", 3.0, ArmCommand::JointTarget { q: up, jaw: OPEN }, REST),
        Segment::open(
            "A",
            3.0,
            ArmCommand::JointTarget { q: pre, jaw: OPEN },
            REST,
        ),
        Segment::open("A", 4.0, ArmCommand::JointTarget { q: at, jaw: OPEN }, REST),
        Segment::open("B", 1.5, ArmCommand::jaw(CLOSE), REST),
        Segment::open("B", 3.5, REST, REST),
        Segment::open("C", 2.0, ArmCommand::valve(1, 0.3, 0.0), REST),
        Segment::open("C", 4.0, REST, REST),
        Segment::open("D", 1.0, ArmCommand::jaw(OPEN), REST),
        Segment::open("D", 4.0, REST, REST),
    ])
}

/// Case studies 3 and 4, stages A–B: the right arm reaches and grabs its handle, then the
/// left arm.
fn dual_grasp(params: &SimParams, left: &Model, right: &Model) -> Result<Vec<Segment>, Error> {
    let [lup, lpre, lat] = approach(params, left, Arm::Left, 0.10)?;
    let [rup, rpre, rat] = approach(params, right, Arm::Right, 0.10)?;
    let tgt = |q: [f64; N_ACT], jaw: f64| ArmCommand::JointTarget { q, jaw };
    Ok(vec![
        Segment::open("A", 3.0, tgt(lup, OPEN), tgt(rup, OPEN)),
        Segment::open("A", 3.0, tgt(lpre, OPEN), tgt(rpre, OPEN)),
        Segment::open("A", 4.0, tgt(lpre, OPEN), tgt(rat, OPEN)),
        Segment::open("A", 1.5, REST, ArmCommand::jaw(CLOSE)),
        Segment::open("A", 2.5, REST, REST),
        Segment::open("B", 4.0, tgt(lat, OPEN), REST),
        Segment::open("B", 1.5, ArmCommand::jaw(CLOSE), REST),
    ])
}

/// Case study 3 after the grasp: lift open loop (C), move left (D), release (E).
fn open_loop_lift() -> Vec<Segment> {
    // C: lift with the shoulders (signal 2) and elbows (signal 3) of both arms.
    let lift = ArmCommand::Valves {
        valves: [0.0, 0.4, 0.2, 0.0, 0.0, 0.0],
        jaw: 0.0,
    };
    // D: move left: both swing joints the same way.
    let swing = ArmCommand::valve(0, 0.4, 0.0);
    vec![
        Segment::open("B", 3.0, REST, REST),
        Segment::open("C", 3.0, lift, lift),
        Segment::open("C", 2.0, REST, REST),
        Segment::open("D", 2.0, swing, swing),
        Segment::open("D", 2.0, REST, REST),
        Segment::open("E", 1.0, ArmCommand::jaw(OPEN), ArmCommand::jaw(OPEN)),
        Segment::open("E", 4.0, REST, REST),
    ]
}

/// Case study 4 after the grasp: switch to the cooperative closed loop, lift (C), move left
/// (D), release (E). Returns the segments and the commanded lift (m).
fn closed_loop_lift() -> (Vec<Segment>, f64) {
    let v = 0.05;
    let t = 4.0;
    let segments = vec![
        Segment::open("B", 1.0, REST, REST),
        Segment::closed("B", 2.0, 0.0, [0.0; 6]),
        Segment::closed("C", t, 0.0, [0.0, 0.0, v, 0.0, 0.0, 0.0]),
        Segment::closed("C", 2.0, 0.0, [0.0; 6]),
        Segment::closed("D", 2.0, 0.0, [0.0, v, 0.0, 0.0, 0.0, 0.0]),
        Segment::closed("D", 2.0, 0.0, [0.0; 6]),
        Segment::open("E", 1.0, ArmCommand::jaw(OPEN), ArmCommand::jaw(OPEN)),
        Segment::open("E", 4.0, REST, REST),
    ];
    (segments, v * t)
}

impl Scenario {
    /// Total scripted duration (s).
    pub fn duration_s(&self) -> f64 {
        self.segments.iter().map(|s| s.duration_s).sum()
    }

    /// The step input for `seg` given the current simulation state (`_t_s` is the scenario time).
    pub fn input_at(&self, sim: &Simulation, seg: &Segment, _t_s: f64) -> Input {
        let mut input = Input {
            method: seg.method,
            object_velocity: seg.object_velocity,
            speed_scale: 1.0,
            ..Input::default()
        };
        for (arm, cmd) in Arm::BOTH.into_iter().zip(&seg.arms) {
            let i = arm.index();
            match *cmd {
                ArmCommand::Valves { valves, jaw } => {
                    input.arms[i].valves = valves;
                    input.arms[i].jaw = jaw;
                }
                ArmCommand::JointTarget { q, jaw } => {
                    let a = sim.arm(arm);
                    let acts = &sim.params().arms[i].hydraulics.actuators;
                    let r: [f64; N_ACT] = core::array::from_fn(|j| {
                        let lim = 0.5 * acts[j].nominal_speed_rad_s;
                        (2.0 * (q[j] - a.q[j])).clamp(-lim, lim)
                    });
                    input.arms[i].joint_velocity_ref = Some(r);
                    input.arms[i].jaw = jaw;
                }
            }
        }
        input
    }
}

/// Outcome of a scenario run (serialized as the `POST /api/scenarios/{name}/run` summary).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: &'static str,
    /// The medium it ran in: `"air"` (the thesis's setting, every case study) or `"subsea"`.
    pub environment: &'static str,
    /// Highest line pressure of any actuator (Pa).
    pub peak_line_pressure_pa: f64,
    /// Relief valve setting (Pa), for reference.
    pub relief_setting_pa: f64,
    /// Largest |internal force| (N).
    pub peak_internal_force_n: f64,
    /// Largest |internal torque| (N·m).
    pub peak_internal_torque_nm: f64,
    /// Relief valve openings (rising edges) of both arms.
    pub relief_events: u64,
    /// Highest object COM height above its initial height (m).
    pub object_lift_m: f64,
    /// Object lift over the first closed-loop lift stage (C), if the scenario has one (m).
    pub closed_loop_lift_m: Option<f64>,
    /// Commanded closed-loop lift (m), if any.
    pub commanded_lift_m: Option<f64>,
    /// Grasp state at the end.
    pub final_grasp_state: GraspState,
    /// Largest grasp constraint position error while holding (m).
    pub peak_grasp_error_m: f64,
    /// Largest |q̇| of any joint over the last second (rad/s).
    pub final_max_joint_speed_rad_s: f64,
    /// Simulated time (s).
    pub sim_seconds: f64,
    /// Steps rolled back for non-finite values (0 expected).
    pub numerical_faults: u64,
    /// The grasp model the run used: `rigid` (Lim's assumption (i), the case studies'
    /// default) or `finite` (the jaws' friction grip, [`crate::grasp::GripParams`]).
    pub grasp_model: &'static str,
    /// Highest load fraction λ of each jaw (left, right) against its static friction limits
    /// (> 1: a finite grip would slip there; [`crate::grasp::GripCapacity::load_fraction`]).
    pub peak_grip_load: [f64; 2],
    /// Slip onsets of both jaws (0 with the rigid grasp).
    pub slips: u64,
    /// Grasps lost by slipping, both jaws.
    pub drops: u64,
    /// Time of the first slip (s), if any.
    pub first_slip_s: Option<f64>,
    /// Time of the first grasp lost by slipping (s), if any.
    pub first_drop_s: Option<f64>,
}

/// Rows are recorded every this many steps (10 ms, 100 Hz) to keep the CSV small.
pub const RECORD_EVERY_STEPS: u64 = 10;

/// Runs `sc` from reset, calling `on_row` every [`RECORD_EVERY_STEPS`] steps (and at t = 0).
pub fn run(
    sc: &Scenario,
    left: &Model,
    right: &Model,
    mut on_row: impl FnMut(&Row),
) -> Result<Summary, Error> {
    let mut sim = Simulation::new(left.clone(), right.clone(), sc.params.clone())?;
    let dt = sc.params.step.dt_s;
    let relief = sc
        .params
        .arms
        .iter()
        .map(|a| a.hydraulics.relief_pa)
        .fold(0.0, f64::max);
    let z0 = sim.object().pose.translation.z;
    let mut s = Summary {
        scenario: sc.name,
        environment: sc.params.step.environment.name(),
        peak_line_pressure_pa: 0.0,
        relief_setting_pa: relief,
        peak_internal_force_n: 0.0,
        peak_internal_torque_nm: 0.0,
        relief_events: 0,
        object_lift_m: 0.0,
        closed_loop_lift_m: None,
        commanded_lift_m: sc.commanded_lift_m,
        final_grasp_state: GraspState::Free,
        peak_grasp_error_m: 0.0,
        final_max_joint_speed_rad_s: 0.0,
        sim_seconds: 0.0,
        numerical_faults: 0,
        grasp_model: if sc.params.rigid_grasp {
            "rigid"
        } else {
            "finite"
        },
        peak_grip_load: [0.0; 2],
        slips: 0,
        drops: 0,
        first_slip_s: None,
        first_drop_s: None,
    };
    on_row(&row(
        &sim,
        sc.segments.first().map(|s| s.stage).unwrap_or(""),
    ));
    let total = sc.duration_s();
    let mut lift_start: Option<f64> = None;
    let mut lift_end: Option<f64> = None;
    for seg in &sc.segments {
        let n = (seg.duration_s / dt).round() as u64;
        let closed_lift = seg.stage == "C" && seg.method == ControlMethod::Closed;
        if closed_lift && lift_start.is_none() {
            lift_start = Some(sim.object().pose.translation.z);
        }
        for _ in 0..n {
            let input = sc.input_at(&sim, seg, sim.time_s());
            sim.step(&input);
            for a in Arm::BOTH {
                let arm = sim.arm(a);
                for j in 0..N_ACT {
                    s.peak_line_pressure_pa =
                        s.peak_line_pressure_pa.max(arm.p_in[j]).max(arm.p_out[j]);
                }
                s.peak_grasp_error_m = s.peak_grasp_error_m.max(sim.grasp_position_error(a));
                let g = &arm.grip;
                s.peak_grip_load[a.index()] = s.peak_grip_load[a.index()].max(g.load_fraction);
                if g.slipping && s.first_slip_s.is_none() {
                    s.first_slip_s = Some(sim.time_s());
                }
                if g.slid_out > 0 && s.first_drop_s.is_none() {
                    s.first_drop_s = Some(sim.time_s());
                }
                if sim.time_s() > total - 1.0 {
                    for j in 0..N_ACT {
                        s.final_max_joint_speed_rad_s =
                            s.final_max_joint_speed_rad_s.max(arm.qd[j].abs());
                    }
                }
            }
            let fi = sim.internal_wrench();
            s.peak_internal_force_n = s
                .peak_internal_force_n
                .max(Vector3::new(fi[0], fi[1], fi[2]).norm());
            s.peak_internal_torque_nm = s
                .peak_internal_torque_nm
                .max(Vector3::new(fi[3], fi[4], fi[5]).norm());
            s.object_lift_m = s.object_lift_m.max(sim.object().pose.translation.z - z0);
            if sim.steps() % RECORD_EVERY_STEPS == 0 {
                on_row(&row(&sim, seg.stage));
            }
        }
        if closed_lift {
            lift_end = Some(sim.object().pose.translation.z);
        }
    }
    if let (Some(a), Some(b)) = (lift_start, lift_end) {
        s.closed_loop_lift_m = Some(b - a);
    }
    s.relief_events = sim.relief_events();
    s.slips = Arm::BOTH.iter().map(|&a| sim.arm(a).grip.slips).sum();
    s.drops = Arm::BOTH.iter().map(|&a| sim.arm(a).grip.slid_out).sum();
    s.final_grasp_state = sim.grasp_state();
    s.sim_seconds = sim.time_s();
    s.numerical_faults = sim.numerical_faults();
    Ok(s)
}
