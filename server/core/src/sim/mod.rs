//! The whole system: two Magnum arms with hydraulic actuators and jaws, a 50 kg object on the
//! seabed, grasping, and open/closed-loop control, stepped at 1 ms (Lim §3.4, §4.2).
//!
//! # Integration scheme
//! The hydraulics are stiff: the orifice law makes ∂q/∂P unbounded as ΔP → 0 (time constants
//! down to ~0.1 ms near stall or at the relief setting), relief valves are steeper still, and
//! the oil-column stiffness of the small wrist motors puts hydraulic resonances near
//! 150 Hz. An explicit 1 ms step blows up. Each 1 ms step (optionally split into
//! [`StepParams::substeps`] sub-steps; default 1, h = 1 ms, the thesis's own step) is:
//!
//! 1. chamber pressures: **backward Euler**, each chamber solved exactly in its own pressure
//!    (closed forms; safeguarded Newton in the laminar band and above relief) — unconditionally
//!    stable for the stiff pressure–flow terms ([`crate::hydraulics::update_chambers`], both
//!    arms' actuators in lockstep);
//! 2. joints: **semi-implicit (symplectic) Euler** with the viscous actuator damping treated
//!    implicitly ((H + hD)q̈ = T − Cq̇ − G − Dq̇ − JᵀF_c); the remaining hydraulic spring
//!    (ω_h ≈ 900 rad/s at most — the wrist rotate motor on its 0.15 L hoses — so
//!    ω_h·h ≲ 0.9) is inside the symplectic-Euler stability limit of 2;
//! 3. closed kinematic chain (jaws holding the object): contact wrenches from an exact
//!    acceleration-level constraint solve (12×12 SPD system) with Baumgarte position/velocity
//!    stabilization, so the grasp does not drift;
//! 4. joint end stops (cylinder bottoming out): stiff spring-dampers treated implicitly in the
//!    same (H + hD + h²K) matrix, so the closed chain stays consistent at a limit;
//! 5. seabed contact: the corner dashpots (normal damping and the regularized friction) are
//!    treated implicitly through the object's mass matrix, M̃ = M_o + h·C
//!    ([`grasp::seabed_contact`]), because a box touching on one corner has an effective mass
//!    of a few kg there and an explicit 2·10⁴ N·s/m dashpot would inject energy; the corner
//!    springs stay explicit (k·h²/m_eff ≈ 0.3).
//!
//! Configuration-dependent quantities (H, C q̇ + G, J, J̇q̇, the constraint matrix, the seabed
//! damping) are computed
//! once per 1 ms step and held over its sub-steps (they change by < 0.3 % in 1 ms at the
//! arms' speeds); pressures, forces, velocities and positions are updated every sub-step.
//! Everything is fixed-size and allocation-free; the result depends only on the inputs.
//!
//! # Simplifications (not modelled)
//! * The jaw is a flow-limited actuator (opening rate ∝ command, Table 1-1 speed) with a clamp
//!   force, not a chamber model; the grasp is rigid whatever the clamp force (no slip).
//! * Contact is jaw–handle only (capture radius) and box–seabed (corner penalty springs with
//!   friction); links do not collide with the object, the seabed or each other.
//! * Valves are ideal critically lapped spools with instantaneous response (Lim eq. 3.51);
//!   no valve leakage, hose dynamics or pump/accumulator dynamics (supply is a fixed pressure).
//! * Buoyancy (optional) uses the mean link density; drag is an optional quadratic joint term.

pub mod scenario;

use nalgebra::{Isometry3, Matrix3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::Error;
use crate::control::{self, ControlParams, CoopInputs};
use crate::dynamics::{self, DynData, Inertials, PairLinks};
use crate::grasp::{self, GraspState, ObjectParams};
use crate::hydraulics::{self, Faults, HydraulicParams, Linkage, N_ACT};
use crate::kinematics::{self, KinData};
use crate::linalg::{self, BlockCholesky, Cholesky, Pair};
use crate::model::Model;

/// Index of the left arm in every per-arm array.
pub const LEFT: usize = 0;
/// Index of the right arm in every per-arm array.
pub const RIGHT: usize = 1;

/// Overtravel beyond a joint limit at which q is clamped (rad): 0.1.
const HARD_STOP_RAD: f64 = 0.1;

/// Integration parameters (each default in its doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Step length (s): 0.001, the thesis's integration step (Lim §4.2).
    pub dt_s: f64,
    /// Sub-steps per step: 1 (h = 1 ms, as the thesis; see the module docs). The 10-minute
    /// random-input soak (tests/stability_soak.rs) passes at this setting, and trajectories
    /// agree with a 32-sub-step reference (h = 31 µs) to 0.31 mrad and 74 kPa over case 1's
    /// first 12 s, 0.23 mrad and 18 µm of object height over case 4's first 27 s
    /// (tests/integration_accuracy.rs; 2 sub-steps: about a third of those errors at twice the
    /// cost). More sub-steps cost time linearly.
    pub substeps: usize,
    /// Gravity, world frame (m/s²): (0, 0, −9.81).
    pub gravity: Vector3<f64>,
    /// Buoyancy of links and object in sea water: false (the thesis simulates in air).
    pub buoyancy: bool,
    /// Sea-water density for buoyancy (kg/m³): 1 025.
    pub water_density_kgm3: f64,
    /// Quadratic joint drag coefficient (N·m·s²/rad²), τ = −c·q̇|q̇|: 0 (off). A crude stand-in
    /// for hydrodynamic drag on the links.
    pub joint_drag: f64,
    /// Grasp constraint stabilization natural frequency (rad/s): 40 (Baumgarte, critically
    /// damped: k_p = ω², k_d = 2ω).
    pub constraint_omega: f64,
    /// Grasp constraint compliance (s²/kg-like regularization of the constraint matrix): 1e-7.
    /// Keeps the solve well posed near singular postures.
    pub constraint_compliance: f64,
    /// Joint end-stop stiffness (N·m/rad): 1e6 — the cylinder bottoming out; a stop taking
    /// the full 5 kN·m shoulder torque is penetrated by 5 mrad. Treated implicitly.
    pub stop_stiffness: f64,
    /// Joint end-stop damping (N·m·s/rad): 5e3. Treated implicitly.
    pub stop_damping: f64,
}

impl Default for StepParams {
    fn default() -> Self {
        StepParams {
            dt_s: 1.0e-3,
            substeps: 1,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            buoyancy: false,
            water_density_kgm3: 1025.0,
            joint_drag: 0.0,
            constraint_omega: 40.0,
            constraint_compliance: 1.0e-7,
            stop_stiffness: 1.0e6,
            stop_damping: 5.0e3,
        }
    }
}

/// Everything fixed about one arm.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmParams {
    /// Pose of the arm base in the world frame.
    pub base: Isometry3<f64>,
    /// Link inertial parameters.
    pub inertials: Inertials,
    /// Actuators and valves.
    pub hydraulics: HydraulicParams,
    /// Joint angles at reset (rad).
    pub initial_q: [f64; N_ACT],
    /// Fault injection (mutable at run time through [`Simulation::faults_mut`]).
    pub faults: Faults,
}

/// Everything fixed about the simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimParams {
    /// Left (index 0) and right (index 1) arm.
    pub arms: [ArmParams; 2],
    /// The object and the seabed.
    pub object: ObjectParams,
    /// Integration.
    pub step: StepParams,
    /// Controllers.
    pub control: ControlParams,
}

/// Right arm base at the world origin, left arm base 1.0 m to its left (+y), both facing +x
/// (Lim §4.3.2: "the Y coordinate of the right arm was 0.0 m and the left arm was 1.0 m").
pub const LEFT_BASE_Y_M: f64 = 1.0;
/// Seabed height below the arm bases (m): −0.45 (assumed: the 50 kg box's handles then sit
/// at z ≈ −0.22, inside the thesis's case-study workspace after a 0.2 m lift).
pub const SEABED_Z_M: f64 = -0.45;
/// Object centre (x, y) on the seabed (m): (1.0, 0.5), midway between the arms.
pub const OBJECT_XY_M: [f64; 2] = [1.0, 0.5];
/// Reset posture of both arms (rad): swing 0, shoulder 30°, elbow −70°, pitch −20°, yaw 0,
/// rotate 0 — jaws raised in front of the arm, clear of the object.
pub const INITIAL_Q: [f64; N_ACT] = [0.0, 30.0 * DEG, -70.0 * DEG, -20.0 * DEG, 0.0, 0.0];
const DEG: f64 = std::f64::consts::PI / 180.0;

impl SimParams {
    /// The case-study setup: two Magnum arms ([`HydraulicParams::magnum`], [`Inertials::magnum`]),
    /// bases per [`LEFT_BASE_Y_M`], the 50 kg box at [`OBJECT_XY_M`] on the seabed at
    /// [`SEABED_Z_M`], default step and control parameters.
    pub fn case_study(left: &Model, right: &Model) -> Result<SimParams, Error> {
        let arm = |m: &Model, y: f64| -> Result<ArmParams, Error> {
            let inertials = Inertials::magnum(m)?;
            let hydraulics = HydraulicParams::magnum(m, &inertials)?;
            Ok(ArmParams {
                base: Isometry3::translation(0.0, y, 0.0),
                inertials,
                hydraulics,
                initial_q: INITIAL_Q,
                faults: Faults::default(),
            })
        };
        Ok(SimParams {
            arms: [arm(left, LEFT_BASE_Y_M)?, arm(right, 0.0)?],
            object: ObjectParams::case_study_box(OBJECT_XY_M[0], OBJECT_XY_M[1], SEABED_Z_M),
            step: StepParams::default(),
            control: ControlParams::default(),
        })
    }
}

/// Control method (Lim §4.1 "control mode").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ControlMethod {
    /// Each input drives one joint's valve (or a joint-velocity reference through the servo).
    #[default]
    OpenLoop,
    /// Cooperative object control; active only while both jaws hold the object, otherwise the
    /// open-loop inputs apply.
    ClosedLoop,
}

/// One arm's operator inputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmInput {
    /// Valve commands of the six joints in [−1, 1] (joystick axes).
    pub valves: [f64; N_ACT],
    /// Jaw command in [−1, 1]: + opens, − closes.
    pub jaw: f64,
    /// Joint-velocity reference (rad/s) for Cartesian teleoperation; when `Some`, it replaces
    /// `valves` and the joint servo computes the valve commands.
    pub joint_velocity_ref: Option<[f64; N_ACT]>,
}

/// Inputs of one step. Validation rule (applied by [`Simulation::step`], never an error):
/// non-finite numbers count as 0; valve and jaw commands are clamped to [−1, 1]; joint-velocity
/// references to ±2 × the joint's nominal speed; the object twist to the controller's speed
/// limits; `speed_scale` to [0, 1] (non-finite → 0, i.e. stop).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Input {
    /// Left (0) and right (1) arm.
    pub arms: [ArmInput; 2],
    /// Control method.
    pub method: ControlMethod,
    /// Commanded object twist for closed loop (m/s, rad/s; world frame; vx vy vz wx wy wz).
    pub object_velocity: [f64; 6],
    /// Arm speed setting in (0, 1] (Lim §4.1 "arm speed"): scales every input.
    pub speed_scale: f64,
}

impl Default for Input {
    fn default() -> Self {
        Input {
            arms: [ArmInput::default(); 2],
            method: ControlMethod::OpenLoop,
            object_velocity: [0.0; 6],
            speed_scale: 1.0,
        }
    }
}

#[inline]
fn finite_or(x: f64, d: f64) -> f64 {
    if x.is_finite() { x } else { d }
}

/// State of one arm (plain data, `Copy`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    /// Joint angles (rad).
    pub q: [f64; N_ACT],
    /// Joint velocities (rad/s).
    pub qd: [f64; N_ACT],
    /// Inlet line pressures P_I (Pa).
    pub p_in: [f64; N_ACT],
    /// Outlet line pressures P_O (Pa).
    pub p_out: [f64; N_ACT],
    /// Spool commands applied in the last step, after speed scale, control and faults.
    pub spool: [f64; N_ACT],
    /// Actuator joint torques T (eq. 3.54) in the last sub-step (N·m).
    pub torque: [f64; N_ACT],
    /// Jaw opening (m).
    pub jaw_opening_m: f64,
    /// Jaw clamp force on the handle (N), 0 when not closed on it.
    pub clamp_force_n: f64,
    /// The jaw holds the object.
    pub holding: bool,
    /// The tool point touches the object's handle (within the capture radius).
    pub contact: bool,
    /// Pose of the tool frame in the object frame, fixed while holding.
    pub grasp_rel: Isometry3<f64>,
    /// Contact wrench of this end-effector on the object (N, N·m; world frame, at the tool
    /// point), 0 when not holding.
    pub contact_wrench: [f64; 6],
    /// Relief valve open per actuator (at the end of the step).
    pub relief_open: [bool; N_ACT],
    /// Rising edges of relief opening, all actuators, since reset.
    pub relief_events: u64,
    /// Joint-servo integrated reference (rad).
    servo_ref: [f64; N_ACT],
    servo_active: bool,
}

/// State of the object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectState {
    /// Pose of the object frame (COM), world.
    pub pose: Isometry3<f64>,
    /// COM velocity (m/s), world.
    pub velocity: Vector3<f64>,
    /// Angular velocity (rad/s), world.
    pub angular_velocity: Vector3<f64>,
    /// Seabed normal force (N) in the last sub-step.
    pub seabed_force_n: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct State {
    arms: [ArmState; 2],
    object: ObjectState,
    time_s: f64,
    steps: u64,
    coop_active: bool,
    coop_ref: Isometry3<f64>,
    internal: [f64; 6],
}

/// Per-arm workspace (Data): preallocated kinematics/dynamics results.
#[derive(Debug, Clone)]
struct ArmWork {
    kin: KinData,
    dynd: DynData,
    /// World-frame 6×6 tool Jacobian.
    jw: Matrix6<f64>,
    /// World-frame tool pose.
    tool: Isometry3<f64>,
}

/// The whole-system simulation (Model: the two arm models and [`SimParams`]; Data: state and
/// preallocated workspaces).
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The arm models with their bases composed in ([`Model::based_at`]): joint frames,
    /// Jacobians, tool poses and the dynamics are all in the world frame.
    models: [Model; 2],
    /// Both arms' link data paired for [`dynamics::step_terms_pair`]; `None` when the arms'
    /// joints differ in kind (then each arm's terms are computed on their own).
    pair_links: Option<PairLinks<N_ACT>>,
    /// Per arm and actuator, (sin, cos) of φ₀ − θ_offset of a cylinder linkage
    /// ([`Linkage::pin_sin_cos`]): the step gets the pin angle from the joint's trigonometry.
    linkage_phase: [[(f64, f64); N_ACT]; 2],
    params: SimParams,
    state: State,
    work: [ArmWork; 2],
    /// Steps on which a non-finite value appeared and the state was rolled back (should stay 0).
    numerical_faults: u64,
}

/// Factor of the grasp constraint system of one step (see `step_inner`): one 6×6 block per
/// arm holding the object. Lives on the stack for one step, so the variants' different
/// sizes cost nothing.
#[allow(clippy::large_enum_variant)]
enum ConstraintFactor {
    /// Only this arm holds.
    One(usize, Cholesky<6>),
    /// Both arms hold: the 12×12 system in 6×6 blocks.
    Both(BlockCholesky<6>),
}

impl ConstraintFactor {
    /// Contact wrenches f with (constraint matrix)·f = b; zero for an arm not holding.
    fn solve(&self, b: &[Vector6<f64>; 2]) -> [Vector6<f64>; 2] {
        match self {
            ConstraintFactor::One(i, ch) => {
                let mut f = [Vector6::zeros(); 2];
                f[*i] = ch.solve(&b[*i]);
                f
            }
            ConstraintFactor::Both(ch) => {
                let (f0, f1) = ch.solve(&b[0], &b[1]);
                [f0, f1]
            }
        }
    }
}

impl Simulation {
    /// Builds a simulation of `left` and `right` (6-joint revolute models) with `params`, at its
    /// reset state.
    pub fn new(left: Model, right: Model, params: SimParams) -> Result<Simulation, Error> {
        for m in [&left, &right] {
            if m.dof() != N_ACT {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "the simulation needs 6-joint arms, {} has {}",
                        m.name,
                        m.dof()
                    ),
                });
            }
        }
        for (i, a) in params.arms.iter().enumerate() {
            if a.inertials.links.len() != N_ACT {
                return Err(Error::InvalidParameter {
                    what: "inertials",
                    reason: format!("arm {i} needs 6 links"),
                });
            }
            if a.inertials
                .links
                .iter()
                .any(|l| l.mass_kg.is_nan() || l.mass_kg <= 0.0 || !l.mass_kg.is_finite())
            {
                return Err(Error::InvalidParameter {
                    what: "inertials",
                    reason: "masses must be finite and > 0".into(),
                });
            }
            if a.initial_q.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite {
                    what: "initial_q",
                    index: i,
                });
            }
        }
        let s = &params.step;
        if !(s.dt_s > 0.0 && s.dt_s <= 0.01) || s.substeps == 0 || s.substeps > 1000 {
            return Err(Error::InvalidParameter {
                what: "step",
                reason: "dt_s in (0, 0.01] and 1..=1000 substeps".into(),
            });
        }
        if params.object.mass_kg.is_nan() || params.object.mass_kg <= 0.0 {
            return Err(Error::InvalidParameter {
                what: "object",
                reason: "mass must be > 0".into(),
            });
        }
        let work = [
            ArmWork {
                kin: KinData::new(&left),
                dynd: DynData::new(&left),
                jw: Matrix6::zeros(),
                tool: Isometry3::identity(),
            },
            ArmWork {
                kin: KinData::new(&right),
                dynd: DynData::new(&right),
                jw: Matrix6::zeros(),
                tool: Isometry3::identity(),
            },
        ];
        let blank_arm = ArmState {
            q: [0.0; N_ACT],
            qd: [0.0; N_ACT],
            p_in: [0.0; N_ACT],
            p_out: [0.0; N_ACT],
            spool: [0.0; N_ACT],
            torque: [0.0; N_ACT],
            jaw_opening_m: 0.0,
            clamp_force_n: 0.0,
            holding: false,
            contact: false,
            grasp_rel: Isometry3::identity(),
            contact_wrench: [0.0; 6],
            relief_open: [false; N_ACT],
            relief_events: 0,
            servo_ref: [0.0; N_ACT],
            servo_active: false,
        };
        let state = State {
            arms: [blank_arm; 2],
            object: ObjectState {
                pose: Isometry3::identity(),
                velocity: Vector3::zeros(),
                angular_velocity: Vector3::zeros(),
                seabed_force_n: 0.0,
            },
            time_s: 0.0,
            steps: 0,
            coop_active: false,
            coop_ref: Isometry3::identity(),
            internal: [0.0; 6],
        };
        // Bases composed into the models: kinematics and dynamics come out in the world frame.
        let models = [
            left.based_at(&params.arms[LEFT].base),
            right.based_at(&params.arms[RIGHT].base),
        ];
        let pair_links = PairLinks::new(
            [&models[0], &models[1]],
            [&params.arms[0].inertials, &params.arms[1].inertials],
        );
        let linkage_phase = core::array::from_fn(|i| {
            core::array::from_fn(|j| match params.arms[i].hydraulics.actuators[j].linkage {
                Linkage::Linear { phi0_rad, .. } => {
                    crate::trig::sin_cos(phi0_rad - models[i].joints[j].offset)
                }
                Linkage::Rotary => (0.0, 1.0),
            })
        });
        let mut sim = Simulation {
            models,
            pair_links,
            linkage_phase,
            params,
            state,
            work,
            numerical_faults: 0,
        };
        sim.reset();
        Ok(sim)
    }

    /// Back to the initial position (Lim §4.1 "Initial Position"): arms at their initial q,
    /// at rest, line pressures balancing gravity around half supply, jaws open, object resting
    /// on the seabed, counters cleared. Faults are kept.
    #[allow(clippy::needless_range_loop)]
    pub fn reset(&mut self) {
        let g = self.params.step.gravity;
        for i in 0..2 {
            let ap = &self.params.arms[i];
            let model = &self.models[i];
            let a = &mut self.state.arms[i];
            a.q = ap.initial_q;
            a.qd = [0.0; N_ACT];
            a.spool = [0.0; N_ACT];
            a.jaw_opening_m = ap.hydraulics.jaw.max_opening_m;
            a.clamp_force_n = 0.0;
            a.holding = false;
            a.contact = false;
            a.grasp_rel = Isometry3::identity();
            a.contact_wrench = [0.0; 6];
            a.relief_open = [false; N_ACT];
            a.relief_events = 0;
            a.servo_active = false;
            a.servo_ref = a.q;
            // Pressures that hold the arm still: A_I P_I − A_O P_O = G/Ĵ, mean half supply.
            let w = &mut self.work[i];
            kinematics::jacobian(model, &mut w.kin, &a.q);
            let mut tau = [0.0; N_ACT];
            let rho = if self.params.step.buoyancy {
                self.params.step.water_density_kgm3
            } else {
                0.0
            };
            dynamics::rnea(
                model,
                &ap.inertials,
                &w.kin,
                &[0.0; N_ACT],
                &[0.0; N_ACT],
                &g,
                rho,
                &mut tau,
                &mut w.dynd,
            );
            let hp = &ap.hydraulics;
            for j in 0..N_ACT {
                let act = &hp.actuators[j];
                let (_, jh) = act.linkage.coordinate(a.q[j]);
                let f = tau[j] / jh;
                let base = (act.area_in + act.area_out) * 0.5 * hp.supply_pa;
                a.p_in[j] = ((f + base) / (2.0 * act.area_in)).clamp(0.0, hp.relief_pa);
                a.p_out[j] = ((base - f) / (2.0 * act.area_out)).clamp(0.0, hp.relief_pa);
                a.torque[j] = tau[j];
            }
        }
        let op = &self.params.object;
        // Settled on its corner springs: sunk by m·g/(4k).
        let sink = op.mass_kg * g.norm() / (4.0 * op.contact_stiffness_n_m);
        let mut pose = op.initial_pose;
        pose.translation.vector.z -= sink;
        self.state.object = ObjectState {
            pose,
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
            seabed_force_n: op.mass_kg * g.norm(),
        };
        self.state.time_s = 0.0;
        self.state.steps = 0;
        self.state.coop_active = false;
        self.state.coop_ref = pose;
        self.state.internal = [0.0; 6];
        self.numerical_faults = 0;
        self.update_kinematics();
        for i in 0..2 {
            self.state.arms[i].contact = self.in_contact(i);
        }
    }

    fn update_kinematics(&mut self) {
        for i in 0..2 {
            // The models carry their bases: these are world-frame results. The Jacobian goes
            // straight into `jw` (`kin.jacobian` is not kept: nothing here reads it).
            let w = &mut self.work[i];
            kinematics::jacobian6(
                &self.models[i],
                &mut w.kin,
                &self.state.arms[i].q,
                &mut w.jw,
            );
            w.tool = w.kin.end_effector();
        }
    }

    fn in_contact(&self, i: usize) -> bool {
        let op = &self.params.object;
        let handle = self.state.object.pose * nalgebra::Point3::from(op.handles_m[i]);
        (self.work[i].tool.translation.vector - handle.coords).norm() <= op.capture_radius_m
    }

    /// Parameters (read-only).
    pub fn params(&self) -> &SimParams {
        &self.params
    }
    /// Fault injection of arm `arm` (0 left, 1 right); changes apply from the next step.
    pub fn faults_mut(&mut self, arm: usize) -> &mut Faults {
        &mut self.params.arms[arm.min(1)].faults
    }
    /// Simulated time since reset (s).
    pub fn time_s(&self) -> f64 {
        self.state.time_s
    }
    /// Steps since reset.
    pub fn steps(&self) -> u64 {
        self.state.steps
    }
    /// State of arm `arm` (0 left, 1 right).
    pub fn arm(&self, arm: usize) -> &ArmState {
        &self.state.arms[arm.min(1)]
    }
    /// Object state.
    pub fn object(&self) -> &ObjectState {
        &self.state.object
    }
    /// World pose of arm `arm`'s end-effector (tool point, flange orientation).
    pub fn end_effector(&self, arm: usize) -> Isometry3<f64> {
        self.work[arm.min(1)].tool
    }
    /// World-frame 6×6 Jacobian of arm `arm`'s tool point.
    pub fn jacobian_world(&self, arm: usize) -> &Matrix6<f64> {
        &self.work[arm.min(1)].jw
    }
    /// Internal force/torque F_int (eq. 3.41; 6) while both jaws hold, else zeros.
    pub fn internal_wrench(&self) -> [f64; 6] {
        self.state.internal
    }
    /// Grasp state (Lim §4.1 colour code).
    pub fn grasp_state(&self) -> GraspState {
        let a = &self.state.arms;
        GraspState::classify(
            [a[0].holding, a[1].holding],
            [a[0].contact, a[1].contact],
            self.state.object.seabed_force_n > 0.0,
        )
    }
    /// Whether the cooperative closed loop is currently in control.
    pub fn closed_loop_active(&self) -> bool {
        self.state.coop_active
    }
    /// Relief events of both arms since reset.
    pub fn relief_events(&self) -> u64 {
        self.state.arms[0].relief_events + self.state.arms[1].relief_events
    }
    /// Steps rolled back because a value went non-finite (a safety net; 0 in every test).
    pub fn numerical_faults(&self) -> u64 {
        self.numerical_faults
    }
    /// Grasp position error of arm `arm` while holding (m): the distance of the tool point
    /// from where the grasp fixes it on the object; 0 when not holding. The cheap half of
    /// [`Simulation::grasp_error`], for per-step monitoring.
    pub fn grasp_position_error(&self, arm: usize) -> f64 {
        let i = arm.min(1);
        let a = &self.state.arms[i];
        if !a.holding {
            return 0.0;
        }
        let des = self.state.object.pose * nalgebra::Point3::from(a.grasp_rel.translation.vector);
        (self.work[i].tool.translation.vector - des.coords).norm()
    }

    /// Grasp constraint error of arm `arm` while holding: (position m, orientation rad).
    pub fn grasp_error(&self, arm: usize) -> (f64, f64) {
        let i = arm.min(1);
        let a = &self.state.arms[i];
        if !a.holding {
            return (0.0, 0.0);
        }
        let des = self.state.object.pose * a.grasp_rel;
        let t = self.work[i].tool;
        (
            (t.translation.vector - des.translation.vector).norm(),
            control::rotation_error(&t.rotation, &des.rotation).norm(),
        )
    }

    /// Advances the simulation by one step (`params.step.dt_s`). Never panics; inputs are
    /// validated per the rule on [`Input`].
    pub fn step(&mut self, input: &Input) {
        let saved = self.state;
        self.step_inner(input);
        if !self.state_is_finite() {
            // Safety net: roll back, stop the arms, count it.
            self.state = saved;
            for a in self.state.arms.iter_mut() {
                a.qd = [0.0; N_ACT];
            }
            self.state.object.velocity = Vector3::zeros();
            self.state.object.angular_velocity = Vector3::zeros();
            self.state.time_s += self.params.step.dt_s;
            self.state.steps += 1;
            self.numerical_faults += 1;
            self.update_kinematics();
        }
    }

    fn state_is_finite(&self) -> bool {
        // x·0 is 0 for finite x and NaN for ±∞ or NaN, so one NaN test at the end covers
        // every value (straight-line arithmetic instead of a branch per value).
        let s = &self.state;
        let z = |v: &[f64]| v.iter().fold(0.0, |acc, x| acc + x * 0.0);
        let mut probe = 0.0;
        for a in &s.arms {
            probe += z(&a.q) + z(&a.qd) + z(&a.p_in) + z(&a.p_out) + z(&a.contact_wrench);
        }
        let o = &s.object;
        probe += z(o.pose.translation.vector.as_slice())
            + z(o.pose.rotation.coords.as_slice())
            + z(o.velocity.as_slice())
            + z(o.angular_velocity.as_slice())
            + z(&s.internal);
        !probe.is_nan()
    }

    #[allow(clippy::needless_range_loop)] // per-arm arrays indexed in parallel read clearer
    fn step_inner(&mut self, input: &Input) {
        let sp = self.params.step;
        let dt = sp.dt_s;
        let speed = finite_or(input.speed_scale, 0.0).clamp(0.0, 1.0);
        // ---- jaws and grasp transitions (kinematics are current for the state's q) ----
        for i in 0..2 {
            let contact = self.in_contact(i);
            let op = &self.params.object;
            let jaw = &self.params.arms[i].hydraulics.jaw;
            let cmd = finite_or(input.arms[i].jaw, 0.0).clamp(-1.0, 1.0) * speed;
            let tool = self.work[i].tool;
            let obj = self.state.object.pose;
            let a = &mut self.state.arms[i];
            let was_open_enough = a.jaw_opening_m >= op.handle_width_m - 1e-9;
            let stop = if contact && was_open_enough {
                op.handle_width_m
            } else {
                0.0
            };
            a.jaw_opening_m =
                (a.jaw_opening_m + cmd * jaw.speed_m_s * dt).clamp(stop, jaw.max_opening_m);
            let closed_on_handle =
                contact && was_open_enough && a.jaw_opening_m <= op.handle_width_m + 1e-9;
            if closed_on_handle && cmd < 0.0 {
                a.clamp_force_n =
                    jaw.clamp_force_n * (-cmd).min(1.0).max(a.clamp_force_n / jaw.clamp_force_n);
            } else if !closed_on_handle || cmd > 0.0 {
                a.clamp_force_n = 0.0;
            }
            if !a.holding && closed_on_handle && cmd < 0.0 {
                a.holding = true;
                a.grasp_rel = obj.inverse() * tool;
            } else if a.holding && a.jaw_opening_m > op.handle_width_m + 0.002 {
                a.holding = false;
                a.contact_wrench = [0.0; 6];
            }
            a.contact = contact || a.holding;
        }
        let holding = [self.state.arms[0].holding, self.state.arms[1].holding];
        // ---- control → spool commands ----
        let both = holding[0] && holding[1];
        let coop = input.method == ControlMethod::ClosedLoop && both;
        if coop && !self.state.coop_active {
            self.state.coop_ref = self.state.object.pose;
        }
        self.state.coop_active = coop;
        let mut spools = [[0.0; N_ACT]; 2];
        let nominal: [[f64; N_ACT]; 2] = core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                self.params.arms[i].hydraulics.actuators[j].nominal_speed_rad_s
            })
        });
        if coop {
            let cp = &self.params.control;
            let ov = &input.object_velocity;
            let mut lin = Vector3::new(
                finite_or(ov[0], 0.0),
                finite_or(ov[1], 0.0),
                finite_or(ov[2], 0.0),
            ) * speed;
            let mut ang = Vector3::new(
                finite_or(ov[3], 0.0),
                finite_or(ov[4], 0.0),
                finite_or(ov[5], 0.0),
            ) * speed;
            if lin.norm() > cp.max_object_speed_m_s {
                lin *= cp.max_object_speed_m_s / lin.norm();
            }
            if ang.norm() > cp.max_object_rate_rad_s {
                ang *= cp.max_object_rate_rad_s / ang.norm();
            }
            let twist = Vector6::new(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z);
            let obj = self.state.object.pose;
            let r = self.grasp_radii();
            let contact = [
                Vector6::from(self.state.arms[0].contact_wrench),
                Vector6::from(self.state.arms[1].contact_wrench),
            ];
            let ci = CoopInputs {
                object: &obj,
                r: &r,
                jacobians: [&self.work[0].jw, &self.work[1].jw],
                contact: &contact,
                twist: &twist,
                nominal_speed: &nominal,
            };
            spools = control::cooperative(&ci, &mut self.state.coop_ref, dt, cp);
            for a in self.state.arms.iter_mut() {
                a.servo_active = false;
            }
        } else {
            for (i, sp_i) in spools.iter_mut().enumerate() {
                let ai = &input.arms[i];
                let a = &mut self.state.arms[i];
                match ai.joint_velocity_ref {
                    Some(r) => {
                        if !a.servo_active {
                            a.servo_ref = a.q;
                            a.servo_active = true;
                        }
                        let qd_ref: [f64; N_ACT] = core::array::from_fn(|j| {
                            (finite_or(r[j], 0.0) * speed)
                                .clamp(-2.0 * nominal[i][j], 2.0 * nominal[i][j])
                        });
                        *sp_i = control::joint_servo(
                            &qd_ref,
                            &a.q,
                            &mut a.servo_ref,
                            &nominal[i],
                            dt,
                            &self.params.control,
                        );
                    }
                    None => {
                        a.servo_active = false;
                        let v: [f64; N_ACT] =
                            core::array::from_fn(|j| finite_or(ai.valves[j], 0.0).clamp(-1.0, 1.0));
                        *sp_i = control::open_loop(&v, speed);
                    }
                }
            }
        }
        for (i, sp_i) in spools.iter_mut().enumerate() {
            for (j, s) in sp_i.iter_mut().enumerate() {
                if let Some(u) = self.params.arms[i].faults.stuck_valve[j] {
                    *s = finite_or(u, 0.0).clamp(-1.0, 1.0);
                }
            }
            self.state.arms[i].spool = *sp_i;
        }
        // ---- per-step dynamics terms (held over the sub-steps) ----
        let h = dt / sp.substeps as f64;
        let rho = if sp.buoyancy {
            sp.water_density_kgm3
        } else {
            0.0
        };
        let mut chol: [Option<Cholesky<N_ACT>>; 2] = [None, None];
        let mut bias = [Vector6::zeros(); 2];
        let mut damp = [[0.0; N_ACT]; 2];
        // Z = L⁻¹Jᵀ per holding arm (see below).
        let mut z = [Matrix6::zeros(); 2];
        let mut jdqd = [Vector6::zeros(); 2];
        // Actuator coordinate x, Ĵ and q at the start of the step; within the step
        // x = x₀ + Ĵ·(q − q₀) (the linkage curvature changes x by < 1 µm over 1 ms).
        let mut x0 = [[0.0; N_ACT]; 2];
        let mut jhat = [[0.0; N_ACT]; 2];
        let q0 = [self.state.arms[0].q, self.state.arms[1].q];
        // H, C q̇ + G and J̇q̇ (q̈ = 0) in one pass over the links (eq. 3.38), world frame, both
        // arms in lockstep (one arm at a time if their joint kinds differ).
        let (arms, work, models) = (&self.params.arms, &self.work, &self.models);
        let qd = [&self.state.arms[0].qd, &self.state.arms[1].qd];
        let mut all_terms = match &self.pair_links {
            Some(links) => {
                dynamics::step_terms_pair(links, [&work[0].kin, &work[1].kin], qd, &sp.gravity, rho)
            }
            None => core::array::from_fn(|i| {
                dynamics::step_terms::<N_ACT>(
                    &models[i],
                    &arms[i].inertials,
                    &work[i].kin,
                    qd[i],
                    &sp.gravity,
                    rho,
                )
            }),
        };
        for (i, terms) in all_terms.iter_mut().enumerate() {
            let ap = &self.params.arms[i];
            let model = &self.models[i];
            let a = &self.state.arms[i];
            let w = &self.work[i];
            jdqd[i] = Vector6::from(terms.tool_bias);
            // H̃ = H + h·(damping, end stops) on the diagonal, formed in place.
            let m = &mut terms.mass_matrix;
            for r in 0..N_ACT {
                let act = &ap.hydraulics.actuators[r];
                let pin = Linkage::pin_sin_cos(
                    self.linkage_phase[i][r],
                    self.work[i].kin.joint_sin_cos[r],
                );
                let (x, jh) = act.linkage.coordinate_sin_cos(a.q[r], pin);
                x0[i][r] = x;
                jhat[i][r] = jh;
                damp[i][r] = act.damping * jh * jh + 2.0 * sp.joint_drag * a.qd[r].abs();
                m[(r, r)] += h * damp[i][r];
                let lim = model.joints[r].limits;
                if a.q[r] < lim[0] || a.q[r] > lim[1] {
                    // End stop engaged at the start of the step: implicit spring-damper.
                    m[(r, r)] += h * sp.stop_damping + h * h * sp.stop_stiffness;
                }
                bias[i][r] = terms.bias[r] + sp.joint_drag * a.qd[r] * a.qd[r].abs()
                    - 2.0 * sp.joint_drag * a.qd[r].abs() * a.qd[r];
            }
            chol[i] = Cholesky::factor(m);
            if let (Some(ch), true) = (&chol[i], a.holding) {
                // Z = L⁻¹Jᵀ (H̃ = LLᵀ): J·H̃⁻¹·Jᵀ = ZᵀZ, H̃⁻¹Jᵀf = L⁻ᵀ(Zf). Only a holding
                // arm enters the constraint solve.
                z[i] = ch.forward_columns(&w.jw.transpose());
            }
        }
        // Object inertia (world) and its inverse. The body axes are principal, so with R's
        // columns r_k: R·diag(d)·Rᵀ = Σ d_k·r_k·r_kᵀ, and the inverse takes 1/d_k.
        let op = &self.params.object;
        let rot = self.state.object.pose.rotation.to_rotation_matrix();
        let d = op.principal_inertia();
        let d_inv = if d.iter().all(|&x| x > 0.0 && x.is_finite()) {
            d.map(|x| 1.0 / x)
        } else {
            Vector3::repeat(1.0)
        };
        let world = |e: &Vector3<f64>| -> Matrix3<f64> {
            let r = rot.matrix();
            let mut m = Matrix3::zeros();
            for k in 0..3 {
                let c = r.column(k);
                m += (c * e[k]) * c.transpose();
            }
            m
        };
        let iw = world(&d);
        let iw_inv = world(&d_inv);
        // Seabed contact at the start of the step. Its dashpots (normal damping and the
        // regularized friction) are stiff for a box touching on one corner or edge — there
        // the effective mass is a few kg, and explicit damping of 2·10⁴ N·s/m at h = 1 ms
        // injects energy. They are treated implicitly (linearly implicit Euler): the object's
        // mass matrix becomes M̃ = M_o + h·C with C the contact's damping matrix, held over
        // the step like H; the spring forces stay explicit (k·h²/m_eff ≈ 0.3).
        let o0 = self.state.object;
        let contact0 = grasp::seabed_contact(op, &o0.pose, &o0.velocity, &o0.angular_velocity);
        let object_factor = contact0.damping.and_then(|c| {
            let mut m = c * h;
            for k in 0..3 {
                m[(k, k)] += op.mass_kg;
            }
            let mut rot_block = m.fixed_view_mut::<3, 3>(3, 3);
            rot_block += iw;
            Cholesky::factor(&m)
        });
        // M̃⁻¹ itself (6×6, symmetric) when an arm also holds the object: the grasp blocks
        // take it in 3×3 pieces, and applied to a wrench it costs one product. Formed from
        // the factor, L⁻ᵀ·D⁻¹·L⁻¹ (a third of the work of six solves on unit vectors).
        let object_mobility = match &object_factor {
            Some(ch) if holding[0] || holding[1] => Some(ch.inverse()),
            _ => None,
        };
        // M̃⁻¹ applied to a wrench (force, moment about the COM): blockwise M_o⁻¹ =
        // blockdiag(I/m, I_w⁻¹) when nothing touches.
        let inv_mass = 1.0 / op.mass_kg;
        let mo_inv = |w: &Vector6<f64>| match (&object_mobility, &object_factor) {
            (Some(x), _) => x * w,
            (None, Some(ch)) => ch.solve(w),
            (None, None) => {
                let a = iw_inv * Vector3::new(w[3], w[4], w[5]);
                Vector6::new(
                    w[0] * inv_mass,
                    w[1] * inv_mass,
                    w[2] * inv_mass,
                    a.x,
                    a.y,
                    a.z,
                )
            }
        };
        // Wⁱᵀ·M̃⁻¹·Wᵏ.
        let mobility = |ri: &Vector3<f64>, rk: &Vector3<f64>| -> Matrix6<f64> {
            // Formed only while an arm holds, when `object_mobility` exists if anything touches.
            debug_assert!(object_mobility.is_some() || object_factor.is_none());
            match &object_mobility {
                Some(x) => grasp::mobility_block_general(ri, rk, x),
                None => grasp::mobility_block(ri, rk, inv_mass, &iw_inv),
            }
        };
        // Wⁱᵀ·M̃⁻¹·Wⁱ for a diagonal block: with the general M̃⁻¹ only its lower triangle.
        let mobility_diag = |ri: &Vector3<f64>| -> Matrix6<f64> {
            match &object_mobility {
                Some(x) => grasp::mobility_block_general_lower(ri, x),
                None => mobility(ri, ri),
            }
        };
        let obj_weight = sp.gravity
            * (op.mass_kg
                - if sp.buoyancy {
                    sp.water_density_kgm3 * op.size_m.x * op.size_m.y * op.size_m.z
                } else {
                    0.0
                });
        // Constraint system.
        let r = self.grasp_radii();
        let active = [
            holding[0] && chol[0].is_some(),
            holding[1] && chol[1].is_some(),
        ];
        // Diagonal blocks W_iᵀM_o⁻¹W_i + Z_iᵀZ_i + εI, and the coupling W₁ᵀM_o⁻¹W₀ (the
        // factorizations read lower triangles only).
        let diag = |i: usize| {
            mobility_diag(&r[i])
                + linalg::gram_lower(&z[i])
                + Matrix6::identity() * sp.constraint_compliance
        };
        let constraint = match active {
            [true, true] => BlockCholesky::factor(&diag(0), &mobility(&r[1], &r[0]), &diag(1))
                .map(ConstraintFactor::Both),
            [true, false] => Cholesky::factor(&diag(0)).map(|c| ConstraintFactor::One(0, c)),
            [false, true] => Cholesky::factor(&diag(1)).map(|c| ConstraintFactor::One(1, c)),
            [false, false] => None,
        };
        // Baumgarte position error and velocity-product terms per holding arm.
        let kp = sp.constraint_omega * sp.constraint_omega;
        let kd = 2.0 * sp.constraint_omega;
        let mut c_const = [Vector6::zeros(); 2];
        for i in 0..2 {
            if !active[i] {
                continue;
            }
            let des = self.state.object.pose * self.state.arms[i].grasp_rel;
            let t = self.work[i].tool;
            let ep = t.translation.vector - des.translation.vector;
            let er = control::rotation_error(&t.rotation, &des.rotation);
            let w = self.state.object.angular_velocity;
            let cen = w.cross(&w.cross(&r[i]));
            c_const[i] = -jdqd[i]
                + Vector6::new(
                    cen.x - kp * ep.x,
                    cen.y - kp * ep.y,
                    cen.z - kp * ep.z,
                    -kp * er.x,
                    -kp * er.y,
                    -kp * er.z,
                );
        }
        // ---- sub-steps ----
        let mut relief_now = [[false; N_ACT]; 2];
        let mut fc = [Vector6::zeros(); 2];
        // Fault-adjusted supply pressure, bulk modulus and leakage of each arm (arm i in
        // lane i), constant over the step's sub-steps.
        let hps = [
            &self.params.arms[0].hydraulics,
            &self.params.arms[1].hydraulics,
        ];
        let faults = [&self.params.arms[0].faults, &self.params.arms[1].faults];
        let supply = Pair(core::array::from_fn(|i| {
            let (hp, f) = (hps[i], faults[i]);
            hp.supply_pa - finite_or(f.supply_drop_pa, 0.0).clamp(0.0, hp.supply_pa)
        }));
        let beta = Pair(core::array::from_fn(|i| {
            let (hp, f) = (hps[i], faults[i]);
            hp.bulk_modulus_pa * finite_or(f.bulk_modulus_scale, 1.0).clamp(0.01, 1.0)
        }));
        let leak: [Pair; N_ACT] = core::array::from_fn(|j| {
            Pair(core::array::from_fn(|i| {
                finite_or(faults[i].leak_m3_s_pa[j], 0.0).clamp(0.0, 1e-8)
            }))
        });
        let sys = hydraulics::PairSystem::new(hps, supply, beta, h);
        for substep in 0..sp.substeps {
            let mut qdd_free = [Vector6::zeros(); 2];
            // Chamber pressures (eqs 3.48–3.50, 3.56): actuator j of both arms in lockstep.
            {
                let [a0, a1] = &mut self.state.arms;
                for j in 0..N_ACT {
                    let lane = |i: usize, a: &ArmState| {
                        let jh = jhat[i][j];
                        (x0[i][j] + jh * (a.q[j] - q0[i][j]), jh * a.qd[j])
                    };
                    let ((x_0, xd_0), (x_1, xd_1)) = (lane(0, a0), lane(1, a1));
                    let mut p_in = Pair([a0.p_in[j], a1.p_in[j]]);
                    let mut p_out = Pair([a0.p_out[j], a1.p_out[j]]);
                    let fl = hydraulics::update_chambers_pair(
                        [&hps[0].actuators[j], &hps[1].actuators[j]],
                        hps,
                        &sys,
                        leak[j],
                        Pair([a0.spool[j], a1.spool[j]]),
                        Pair([x_0, x_1]),
                        Pair([xd_0, xd_1]),
                        &mut p_in,
                        &mut p_out,
                    );
                    [a0.p_in[j], a1.p_in[j]] = p_in.0;
                    [a0.p_out[j], a1.p_out[j]] = p_out.0;
                    relief_now[0][j] = fl[0].relief_open;
                    relief_now[1][j] = fl[1].relief_open;
                }
            }
            for i in 0..2 {
                let hp = hps[i];
                let a = &mut self.state.arms[i];
                let mut rhs = Vector6::zeros();
                for j in 0..N_ACT {
                    let act = &hp.actuators[j];
                    let jh = jhat[i][j];
                    let t = jh * (act.area_in * a.p_in[j] - act.area_out * a.p_out[j]);
                    a.torque[j] = t - damp[i][j] * a.qd[j];
                    rhs[j] = t - bias[i][j] - damp[i][j] * a.qd[j];
                    let lim = self.models[i].joints[j].limits;
                    let pen = if a.q[j] < lim[0] {
                        a.q[j] - lim[0]
                    } else if a.q[j] > lim[1] {
                        a.q[j] - lim[1]
                    } else {
                        0.0
                    };
                    if pen != 0.0 {
                        rhs[j] -= sp.stop_stiffness * pen + sp.stop_damping * a.qd[j];
                    }
                }
                if let Some(ch) = &chol[i] {
                    qdd_free[i] = ch.solve(&rhs);
                }
            }
            // Object free acceleration: gravity, seabed, gyroscopic.
            let o = self.state.object;
            let (sea, normal) = if substep == 0 {
                (contact0.wrench, contact0.normal_n)
            } else {
                grasp::seabed_wrench(op, &o.pose, &o.velocity, &o.angular_velocity)
            };
            let gyro = o.angular_velocity.cross(&(iw * o.angular_velocity));
            let wrench = Vector6::new(
                obj_weight.x + sea[0],
                obj_weight.y + sea[1],
                obj_weight.z + sea[2],
                sea[3] - gyro.x,
                sea[4] - gyro.y,
                sea[5] - gyro.z,
            );
            let mut acc_o = mo_inv(&wrench);
            let vo = Vector6::new(
                o.velocity.x,
                o.velocity.y,
                o.velocity.z,
                o.angular_velocity.x,
                o.angular_velocity.y,
                o.angular_velocity.z,
            );
            if let Some(ch) = &constraint {
                let mut b = [Vector6::zeros(); 2];
                for i in 0..2 {
                    if !active[i] {
                        continue;
                    }
                    let qd = Vector6::from(self.state.arms[i].qd);
                    let ev = self.work[i].jw * qd - grasp::grasp_point_twist(&r[i], &vo);
                    let ci = c_const[i] - ev * kd;
                    b[i] = self.work[i].jw * qdd_free[i]
                        - grasp::grasp_point_twist(&r[i], &acc_o)
                        - ci;
                }
                let f = ch.solve(&b);
                for i in 0..2 {
                    if !active[i] {
                        continue;
                    }
                    fc[i] = f[i];
                    if let Some(ch) = &chol[i] {
                        qdd_free[i] -= ch.backward(&(z[i] * f[i]));
                    }
                    acc_o += mo_inv(&grasp::wrench_at_com(&r[i], &f[i]));
                }
            }
            // Semi-implicit Euler.
            for i in 0..2 {
                let model = &self.models[i];
                let a = &mut self.state.arms[i];
                for j in 0..N_ACT {
                    a.qd[j] += h * qdd_free[i][j];
                    a.q[j] += h * a.qd[j];
                    // Hard backstop far beyond the elastic end stop (never reached in
                    // normal use): keeps q bounded whatever happens.
                    let lim = model.joints[j].limits;
                    if a.q[j] < lim[0] - HARD_STOP_RAD {
                        a.q[j] = lim[0] - HARD_STOP_RAD;
                        a.qd[j] = a.qd[j].max(0.0);
                    } else if a.q[j] > lim[1] + HARD_STOP_RAD {
                        a.q[j] = lim[1] + HARD_STOP_RAD;
                        a.qd[j] = a.qd[j].min(0.0);
                    }
                }
            }
            let ob = &mut self.state.object;
            ob.velocity += h * Vector3::new(acc_o[0], acc_o[1], acc_o[2]);
            ob.angular_velocity += h * Vector3::new(acc_o[3], acc_o[4], acc_o[5]);
            ob.pose.translation.vector += h * ob.velocity;
            ob.pose.rotation = crate::trig::quaternion_from_scaled_axis(&(ob.angular_velocity * h))
                * ob.pose.rotation;
            ob.pose.rotation.renormalize();
            ob.seabed_force_n = normal;
        }
        // ---- outputs ----
        for i in 0..2 {
            let a = &mut self.state.arms[i];
            for j in 0..N_ACT {
                if relief_now[i][j] && !a.relief_open[j] {
                    a.relief_events += 1;
                }
                a.relief_open[j] = relief_now[i][j];
            }
            a.contact_wrench = if active[i] {
                [fc[i][0], fc[i][1], fc[i][2], fc[i][3], fc[i][4], fc[i][5]]
            } else {
                [0.0; 6]
            };
        }
        self.state.internal = if active[0] && active[1] {
            let fint = grasp::internal_wrench(&r, &fc);
            [fint[0], fint[1], fint[2], fint[3], fint[4], fint[5]]
        } else {
            [0.0; 6]
        };
        self.state.time_s += dt;
        self.state.steps += 1;
        self.update_kinematics();
        for i in 0..2 {
            let c = self.in_contact(i);
            self.state.arms[i].contact = c || self.state.arms[i].holding;
        }
    }

    /// Grasp points relative to the object COM (world frame): the holding tool frames, or the
    /// handles when not holding.
    fn grasp_radii(&self) -> [Vector3<f64>; 2] {
        let o = &self.state.object.pose;
        core::array::from_fn(|i| {
            let a = &self.state.arms[i];
            if a.holding {
                o.rotation * a.grasp_rel.translation.vector
            } else {
                o.rotation * self.params.object.handles_m[i]
            }
        })
    }
}

/// Convenience: an isometry from a translation and a rotation vector.
pub fn pose(t: [f64; 3], r: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
    )
}
