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
//!    stable for the stiff pressure–flow terms ([`crate::hydraulics::update_chambers`], per
//!    arm and actuator);
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
//!    ([`crate::grasp::seabed_contact`]), because a box touching on one corner has an effective mass
//!    of a few kg there and an explicit 2·10⁴ N·s/m dashpot would inject energy; the corner
//!    springs stay explicit (k·h²/m_eff ≈ 0.3);
//! 6. contacts of links and jaws (`contact.rs`): penalty spring–dampers with Coulomb
//!    friction, linearly implicit in the same (H + hD + h²K) matrix of each arm (and in the
//!    box's M̃), each side of a moving pair taking its share of the law.
//!
//! Configuration-dependent quantities (H, C q̇ + G, J, J̇q̇, the constraint matrix, the seabed
//! damping) are computed
//! once per 1 ms step and held over its sub-steps (they change by < 0.3 % in 1 ms at the
//! arms' speeds); pressures, forces, velocities and positions are updated every sub-step.
//! Everything is fixed-size and allocation-free; the result depends only on the inputs.
//!
//! # Simplifications (not modelled)
//! * The jaw is a flow-limited actuator (opening rate ∝ command, Table 1-1 speed) with a clamp
//!   force, not a chamber model; its grip on a handle is rigid up to the friction limits of
//!   the clamp force and slips beyond them (`constraint.rs`, "Finite grip"), or rigid
//!   whatever the load with [`SimParams::rigid_grasp`].
//! * Grasping is jaw–handle (capture radius); the box rests on the seabed on corner penalty
//!   springs with stick–slip friction (anchored spring-dampers capped at μN). With a panel ([`SimParams::panel`]) the jaws also take its valve
//!   T-bar and hot stab, whose loads act on the arms as JᵀF (see [`crate::panel`]). Links
//!   and jaws collide with the seabed, the box, the panel, the vehicle and the other arm
//!   (`contact.rs`, [`crate::collision`]), not with their own arm; the box does not collide
//!   with the panel or the vehicle.
//! * Valves are ideal critically lapped spools (Lim eq. 3.51) whose spool follows its command
//!   with a first-order lag ([`crate::hydraulics::SPOOL_TIME_CONSTANT_S`], 25 ms); no valve
//!   leakage, hose dynamics or pump/accumulator dynamics (supply is a fixed pressure).
//! * Water ([`StepParams::environment`], [`water`]): buoyancy from the links' mean density and
//!   the box's size, Morison drag and added mass on link pieces and the box, a uniform current
//!   that ramps to its set value (τ = 1.5 s) with its acceleration term; no wake, wall or
//!   free-surface effects, no rotational drag on the box.
//!
//! # Layout
//! * here: parameters, inputs, state and the [`Simulation`] with its public API;
//! * `operator.rs`: stage 0, the operator ([`Operator`]): sticks, grips and the control
//!   mode/method/speed settings to each step's [`Input`];
//! * `pipeline.rs`: the step as a list of named stages ([`Simulation::step`]);
//! * `events.rs`: what a step reports ([`Event`], [`Simulation::events`]);
//! * `measures.rs`: the posture measures of the current state, per arm and dual, with the one
//!   set of warning thresholds ([`measures::measures`]);
//! * `arm.rs`, `object.rs`, `constraint.rs`: the stages' per-arm, object and grasp-constraint
//!   parts;
//! * `panel.rs`: the intervention panel's stages (grasp, loads on the jaws, item update) and
//!   its read accessors ([`crate::panel`] holds its parameters and physics);
//! * `setup.rs`: parameter checks ([`SimParams::check`]) and the case-study setup
//!   ([`SimParams::case_study`] and its constants);
//! * `scenario.rs`: the thesis's scripted case-study scenarios and their CSV output.

mod arm;
mod constraint;
mod contact;
mod events;
pub mod measures;
mod object;
mod operator;
mod panel;
mod pipeline;
pub mod scenario;
mod setup;
pub mod water;

pub use crate::collision::{ArmPart, Partner};
pub use crate::panel::{Graspable, PanelParams, PanelState, StabPhase};
pub use constraint::{GripState, SLIP_NOTICE_M, SLIP_NOTICE_RAD};
pub use contact::{ArmContact, ArmContacts, ContactParams, Contacts, STRIKE_WINDOW_S, Strike};
pub use events::{Event, MAX_EVENTS_PER_STEP};
pub use operator::{
    ControlMode, JOG_ANGLE_RAD, JOG_GAIN_PER_S, JOG_JOINT_RAD, JOG_LINEAR_M, JOG_TIMEOUT_S,
    ORIENTATION_HOLD_GAIN_PER_S, ORIENTATION_LOST_RAD, ORIENTATION_SETTLE_S, Operator, Sticks,
};
pub use setup::{INITIAL_Q, LEFT_BASE_Y_M, OBJECT_XY_M, SEABED_Z_M, pose};
pub use water::{Current, Environment, Flow, Medium, Water};

use nalgebra::{Isometry3, IsometryMatrix3, Matrix6, Vector3};
use serde::{Deserialize, Serialize};

use crate::Error;
use crate::control::{self, ControlParams};
use crate::dynamics::{self, DynData, Inertials};
use crate::grasp::{GraspState, GripParams, ObjectParams, SeabedAnchors};
use crate::hydraulics::{Faults, HydraulicParams, N_ACT};
use crate::kinematics::{self, KinData};
use crate::model::Model;

/// One of the two arms. Per-arm arrays (`[T; 2]`) are indexed by [`Arm::index`], left first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Arm {
    /// The left arm (index 0).
    Left,
    /// The right arm (index 1).
    Right,
}

impl Arm {
    /// Both arms, left first (the order of every per-arm array).
    pub const BOTH: [Arm; 2] = [Arm::Left, Arm::Right];

    /// Index of this arm in every per-arm array: 0 left, 1 right.
    pub const fn index(self) -> usize {
        match self {
            Arm::Left => 0,
            Arm::Right => 1,
        }
    }
}

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
    /// The medium: [`Environment::Air`] (the thesis simulates in air) or sea water with
    /// buoyancy, drag, added mass and a current ([`water`]). Training sessions and exercises
    /// use [`Environment::subsea`] ([`SimParams::training`]).
    pub environment: Environment,
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
            environment: Environment::Air,
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
    /// The intervention panel (valve, hot stab): `None` (the default) leaves the simulation
    /// exactly as without it.
    pub panel: Option<PanelParams>,
    /// Rigid grasp (Lim §3.5.2.1 assumption (i): no slip whatever the load): false in
    /// [`SimParams::case_study`] (training: the jaws' grip is finite, [`GripParams`]); the
    /// case-study scenarios set it true, the thesis's setting.
    pub rigid_grasp: bool,
    /// The jaws' friction grip on the handles (used unless `rigid_grasp`).
    pub grip: GripParams,
    /// Contacts of the links and jaws with the seabed, the box, the panel, the vehicle and
    /// the other arm (`contact.rs`, [`crate::collision`]).
    pub contact: ContactParams,
}

/// Control method (Lim §4.1 "control mode"; Lim case studies 3 and 4). Wire and
/// exercise-file names `open`, `closed`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ControlMethod {
    /// Open loop: each input drives one joint's valve (or a joint-velocity reference through
    /// the servo).
    #[default]
    Open,
    /// Closed-loop cooperative object control: the operator commands the object's motion;
    /// active only while both jaws hold the object, otherwise the open-loop inputs apply.
    Closed,
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
            method: ControlMethod::Open,
            object_velocity: [0.0; 6],
            speed_scale: 1.0,
        }
    }
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
    /// The jaw's grip on the handle: load fraction, slip, slip and slide-out counts.
    pub grip: GripState,
    /// Per joint: at its end stop (past its limits) at the end of the step.
    pub at_end_stop: [bool; N_ACT],
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
    /// The seabed friction's anchors of the touching corners ([`crate::grasp::seabed_contact`]).
    seabed_anchors: SeabedAnchors,
}

impl ObjectState {
    /// The seabed friction's anchors: where each touching corner stuck to the seabed.
    pub fn seabed_anchors(&self) -> &SeabedAnchors {
        &self.seabed_anchors
    }
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
    /// Whether the object rests on the seabed, as the grasp state reports it (with hysteresis).
    surface: SurfaceLatch,
    /// The grasp state at the end of the last step ([`Event::Grasp`] on change).
    grasp: GraspState,
    /// The panel's state (when the parameters have a panel).
    panel: Option<PanelState>,
    /// The water's present motion, ramping towards the set current (still in air).
    flow: Flow,
}

/// The grasp state's "on the seabed" turns on when the seabed carries more than this normal
/// force (N): 10 — 4 % of the box's weight in water (249 N), 2 % in air; a box set down
/// crosses it within a millisecond of touching (the corner springs take 10 N at 5 µm).
pub const SURFACE_ON_N: f64 = 10.0;

/// … and off only when the box's lowest corner is this far clear of the seabed (m): 0.005.
/// A box pivoting on a corner under a jaw, or bouncing as it is lifted off, makes and breaks
/// contact many times a second (measured: 44 contact changes in a dragged one-arm pick, gaps
/// of 1–130 ms) with its corner lifting well under a millimetre between touches; each change
/// would be an event the trainee sees and the record keeps. 5 mm is clear of that and far
/// below any deliberate lift (the exercises lift 10 cm), so the colour (Lim §4.1) follows a
/// lift or a set-down at once to the eye.
pub const SURFACE_OFF_GAP_M: f64 = 0.005;

/// The "object on the seabed" flag of the grasp state, from the contact with hysteresis: on
/// when the seabed's normal force exceeds [`SURFACE_ON_N`], off when the lowest corner is
/// more than [`SURFACE_OFF_GAP_M`] above the seabed, unchanged in between.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct SurfaceLatch {
    /// The reported flag.
    on: bool,
}

impl SurfaceLatch {
    /// One step with the seabed's normal force `normal_n` (N) and the lowest corner's height
    /// above the seabed `gap_m` (m; negative while pressed in).
    fn update(&mut self, normal_n: f64, gap_m: f64) {
        if normal_n > SURFACE_ON_N {
            self.on = true;
        } else if gap_m > SURFACE_OFF_GAP_M {
            self.on = false;
        }
    }
}

/// Height of the object's lowest corner above the seabed (m; negative while pressed in).
fn lowest_corner_gap_m(op: &ObjectParams, pose: &Isometry3<f64>) -> f64 {
    op.corners()
        .iter()
        .map(|c| (pose * nalgebra::Point3::from(*c)).z)
        .fold(f64::INFINITY, f64::min)
        - op.seabed_z_m
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
    params: SimParams,
    state: State,
    work: [ArmWork; 2],
    /// Steps on which a non-finite value appeared and the state was rolled back (should stay 0).
    numerical_faults: u64,
    /// The last step's events ([`Simulation::events`]; preallocated to
    /// [`MAX_EVENTS_PER_STEP`]).
    events: Vec<Event>,
    /// The contact report of the last step.
    contacts: Contacts,
    /// The contact stage's workspace (`contact.rs`; taken out during a step).
    contact_work: Option<Box<contact::ContactWork>>,
}

impl Simulation {
    /// Builds a simulation of `left` and `right` (6-joint revolute models) with `params`, at its
    /// reset state.
    pub fn new(left: Model, right: Model, params: SimParams) -> Result<Simulation, Error> {
        params.check(&left, &right)?;
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
            grip: GripState::default(),
            at_end_stop: [false; N_ACT],
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
                seabed_anchors: SeabedAnchors::default(),
            },
            time_s: 0.0,
            steps: 0,
            coop_active: false,
            coop_ref: Isometry3::identity(),
            internal: [0.0; 6],
            surface: SurfaceLatch::default(),
            grasp: GraspState::Free,
            panel: None,
            flow: Flow::default(),
        };
        // Bases composed into the models: kinematics and dynamics come out in the world frame.
        let models = [
            left.based_at(&params.arms[Arm::Left.index()].base),
            right.based_at(&params.arms[Arm::Right.index()].base),
        ];
        let mut sim = Simulation {
            models,
            params,
            state,
            work,
            numerical_faults: 0,
            events: Vec::with_capacity(MAX_EVENTS_PER_STEP),
            contacts: Contacts::default(),
            contact_work: Some(Box::new(contact::ContactWork::new())),
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
            a.grip = GripState::default();
            a.at_end_stop = [false; N_ACT];
            a.servo_active = false;
            a.servo_ref = a.q;
            // Pressures that hold the arm still: A_I P_I − A_O P_O = G/Ĵ, mean half supply.
            let w = &mut self.work[i];
            kinematics::jacobian(model, &mut w.kin, &a.q);
            let mut tau = [0.0; N_ACT];
            let rho = self.params.step.environment.density_kgm3();
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
        // Settled on its corner springs: sunk by (m − ρV)·g/(4k), its weight in the medium.
        let wet_kg = object::wet_mass_kg(op, &self.params.step.environment);
        let sink = wet_kg * g.norm() / (4.0 * op.contact_stiffness_n_m);
        let mut pose = op.initial_pose;
        pose.translation.vector.z -= sink;
        self.state.object = ObjectState {
            pose,
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
            seabed_force_n: wet_kg * g.norm(),
            seabed_anchors: SeabedAnchors::default(),
        };
        self.state.time_s = 0.0;
        self.state.steps = 0;
        self.state.coop_active = false;
        self.state.coop_ref = pose;
        self.state.internal = [0.0; 6];
        self.state.surface = SurfaceLatch {
            on: self.state.object.seabed_force_n > SURFACE_ON_N,
        };
        self.state.panel = self.params.panel.as_ref().map(PanelState::initial);
        // The set current has been flowing all along: no ramp after a reset.
        self.state.flow = self
            .params
            .step
            .environment
            .water()
            .map_or(Flow::default(), |w| Flow::steady(&w.current));
        self.numerical_faults = 0;
        self.events.clear();
        self.contacts = Contacts::default();
        self.update_kinematics();
        for i in 0..2 {
            self.state.arms[i].contact = self.reach(i).is_some();
            self.state.arms[i].at_end_stop =
                arm::at_end_stops(&self.models[i], &self.state.arms[i].q);
        }
        self.state.grasp = self.grasp_state();
    }

    /// Parameters (read-only).
    pub fn params(&self) -> &SimParams {
        &self.params
    }
    /// Fault injection of `arm`; changes apply from the next step.
    pub fn faults_mut(&mut self, arm: Arm) -> &mut Faults {
        &mut self.params.arms[arm.index()].faults
    }
    /// Simulated time since reset (s).
    pub fn time_s(&self) -> f64 {
        self.state.time_s
    }
    /// Steps since reset.
    pub fn steps(&self) -> u64 {
        self.state.steps
    }
    /// State of `arm`.
    pub fn arm(&self, arm: Arm) -> &ArmState {
        &self.state.arms[arm.index()]
    }
    /// Object state.
    pub fn object(&self) -> &ObjectState {
        &self.state.object
    }
    /// World pose of arm `arm`'s end-effector (tool point, flange orientation).
    pub fn end_effector(&self, arm: Arm) -> Isometry3<f64> {
        self.work[arm.index()].tool
    }
    /// The model of arm `arm`, its base composed in ([`Model::based_at`]): its forward
    /// kinematics come out in the world frame.
    pub fn model(&self, arm: Arm) -> &Model {
        &self.models[arm.index()]
    }
    /// World-frame 6×6 Jacobian of arm `arm`'s tool point.
    pub fn jacobian_world(&self, arm: Arm) -> &Matrix6<f64> {
        &self.work[arm.index()].jw
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
            self.state.surface.on,
        )
    }
    /// What happened in the last step, in the order the stages detected it (see
    /// [`Event`] for each detector); empty after a reset. The list is overwritten by the next
    /// step: read it after each step.
    pub fn events(&self) -> &[Event] {
        &self.events
    }
    /// World poses of arm `arm`'s joint frames after their motion (its z axis is the joint
    /// axis), for the state's q: the kinematics the step computed.
    pub fn joint_frames(&self, arm: Arm) -> &[IsometryMatrix3<f64>] {
        &self.work[arm.index()].kin.joint_frames
    }
    /// Whether the cooperative closed loop is currently in control.
    pub fn closed_loop_active(&self) -> bool {
        self.state.coop_active
    }
    /// Relief events of both arms since reset.
    pub fn relief_events(&self) -> u64 {
        self.state.arms[0].relief_events + self.state.arms[1].relief_events
    }
    /// The medium the arms work in (with the current, when submerged).
    pub fn environment(&self) -> &Environment {
        &self.params.step.environment
    }
    /// The water's present motion: the current as it ramps towards the set one
    /// ([`Flow::advance`]); `None` in air.
    pub fn flow(&self) -> Option<&Flow> {
        self.params
            .step
            .environment
            .water()
            .map(|_| &self.state.flow)
    }
    /// Advances the water's motion by one step towards the set current (stage 0 of the
    /// step; nothing in air).
    pub(super) fn advance_flow(&mut self) {
        if let Some(w) = self.params.step.environment.water() {
            let set = w.current.velocity();
            self.state.flow.advance(&set, self.params.step.dt_s);
        }
    }
    /// Sets the water's current. The water does not jump to it: from the next step the flow
    /// ramps towards it with the time constant [`water::CURRENT_TIME_CONSTANT_S`]
    /// ([`Simulation::flow`]). In air there is no water to move: an error, and nothing
    /// changes.
    pub fn set_current(&mut self, current: Current) -> Result<(), Error> {
        match &mut self.params.step.environment {
            Environment::Subsea(w) => {
                w.current = current;
                Ok(())
            }
            Environment::Air => Err(Error::InvalidParameter {
                what: "current",
                reason: "the simulation is in air: there is no water current to set".into(),
            }),
        }
    }
    /// The contacts of the last step: per arm the strongest (what, where, force), counts and
    /// the strike record ([`ContactParams`]).
    pub fn contacts(&self) -> &Contacts {
        &self.contacts
    }
    /// Steps rolled back because a value went non-finite (a safety net; 0 in every test).
    pub fn numerical_faults(&self) -> u64 {
        self.numerical_faults
    }
    /// Grasp position error of arm `arm` while holding (m): the distance of the tool point
    /// from where the grasp fixes it on the object; 0 when not holding. The cheap half of
    /// [`Simulation::grasp_error`], for per-step monitoring.
    pub fn grasp_position_error(&self, arm: Arm) -> f64 {
        let i = arm.index();
        let a = &self.state.arms[i];
        if !a.holding {
            return 0.0;
        }
        let des = self.state.object.pose * nalgebra::Point3::from(a.grasp_rel.translation.vector);
        (self.work[i].tool.translation.vector - des.coords).norm()
    }

    /// Grasp constraint error of arm `arm` while holding: (position m, orientation rad).
    pub fn grasp_error(&self, arm: Arm) -> (f64, f64) {
        let i = arm.index();
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
        self.events.clear();
        self.step_inner(input);
        if !self.state_is_finite() {
            // Safety net: roll back, stop the arms, count it (and forget what it reported).
            self.events.clear();
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
        let o = &self.state.object;
        let gap = lowest_corner_gap_m(&self.params.object, &o.pose);
        self.state.surface.update(o.seabed_force_n, gap);
        let grasp = self.grasp_state();
        if grasp != self.state.grasp {
            self.state.grasp = grasp;
            self.events.push(Event::Grasp(grasp));
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
        !probe.is_nan() && s.panel.as_ref().is_none_or(PanelState::is_finite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The latch against chatter like the (issue 27: a box pivoting on a corner under a
    /// slipping jaw toggled its seabed contact 48 times in 0.5 s, gaps of 1–130 ms, the corner
    /// lifting well under a millimetre between touches): 10 s of a corner bouncing on the
    /// seabed — touching (normal force up to 200 N, 5 µm pressed in) and lifting (0 N, up to
    /// 0.8 mm clear) with a pseudo-random rhythm of 1–130 ms — after a firm set-down, then a
    /// lift 10 cm clear. The raw contact changes hundreds of times; the latch changes twice
    /// (on at the set-down, off at the lift), well under one change a second.
    #[test]
    fn the_seabed_latch_ignores_a_bouncing_corner_and_follows_a_lift() {
        let dt = 1e-3;
        let mut latch = SurfaceLatch::default();
        let (mut raw, mut raw_changes, mut latch_changes) = (false, 0u32, 0u32);
        let mut on = latch.on;
        let mut step = |latch: &mut SurfaceLatch, n: f64, gap: f64| {
            latch.update(n, gap);
            let touching = n > 0.0;
            if touching != raw {
                raw = touching;
                raw_changes += 1;
            }
            if latch.on != on {
                on = latch.on;
                latch_changes += 1;
            }
        };
        // Set down: pressed in, carrying the weight in water.
        for _ in 0..500 {
            step(&mut latch, 249.0, -6e-5);
        }
        // Bouncing: a linear congruential sequence picks each phase's length (1–130 ms).
        let mut seed: u64 = 27;
        let mut next = || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            1 + (seed >> 33) % 130
        };
        let mut t = 0.0;
        let mut touching = true;
        while t < 10.0 {
            let n_steps = next();
            for k in 0..n_steps {
                let s = k as f64 / n_steps as f64;
                let (n, gap) = if touching {
                    (200.0 * (std::f64::consts::PI * s).sin(), -5e-6)
                } else {
                    (0.0, 8e-4 * (std::f64::consts::PI * s).sin())
                };
                step(&mut latch, n, gap);
                t += dt;
            }
            touching = !touching;
        }
        // Lifted clear.
        for k in 0..2000 {
            step(&mut latch, 0.0, 0.1 * f64::from(k) / 2000.0);
        }
        assert!(
            raw_changes > 100,
            "the corner bounced only {raw_changes} times"
        );
        assert_eq!(latch_changes, 2, "{raw_changes} raw contact changes");
        assert!(!latch.on, "lifted 10 cm: off the seabed");
    }
}
