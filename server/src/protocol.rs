//! Wire types of the sessions — the contract between the server and the page: the session
//! socket `/ws/sessions/{id}`, the session actions `POST /api/sessions/{id}/actions`
//! ([`Action`]) and the replay socket `/ws/replay/{id}` ([`ReplayClientMessage`]). Explicit
//! types, `#[serde(tag = "type")]`; parse and validate at the edge into typed commands
//! (`crate::sessions::command`).
//!
//! Client → server: [`ClientMessage`]. Server → client: a one-time [`Hello`], then a
//! [`StateFrame`] at the frame rate (latest state wins: a slow client skips frames), plus
//! [`ServerMessage::Error`], [`ServerMessage::Message`] and [`ServerMessage::Pong`]; when the
//! session ends, one [`ServerMessage::Ended`] (with its [`EndReason`]) right before the close
//! frame (code 1000, reason `session ended`). The replay socket sends the same [`Hello`] (with
//! `replay`) and frames, and [`ServerMessage::Replay`] statuses.
//!
//! **Core types on the wire.** The simulation's internal state (its `Simulation`, `Input`,
//! arm and object states) never is: frames copy what they show into the `…Frame` types here.
//! A few core types are sent as they are, because they are data with their own documented
//! serde schema, the same on disk and on the wire: the robot model file
//! ([`seaarms_core::ModelSpec`], `hello.arms[].model`), the exercise file
//! ([`ExerciseSpec`], `hello.exercise`, the `scenario` message) and its scene items
//! (`spec::{Target, Zone, Ghost, Obstacle}`, [`SceneOut`]), the water's current
//! (`seaarms_core::sim::Current`, `state.current`) and an exercise's status
//! (`seaarms_core::exercise::Status`, `state.exercise`). A change to those types changes the
//! wire. Enums are mapped to wire strings here ([`arm_name`], [`grasp_name`],
//! [`fault_label`]); the control mode and method are the core's own enums.

use std::sync::Arc;

use nalgebra::{Isometry3, IsometryMatrix3, Matrix3};
use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::grasp::GraspState;
use serde::{Deserialize, Serialize, Serializer};

use seaarms_core::hydraulics::Fault;
use seaarms_core::sim::Arm;

/// Largest WebSocket message accepted from a client (bytes); a larger one closes the
/// connection with a close frame, code 1009 (message too big, RFC 6455 §7.4.1).
pub const MAX_CLIENT_MESSAGE_BYTES: usize = 16 * 1024;

/// Largest `seq` of an input message: 2⁵³ − 1, the largest integer a JavaScript number holds
/// exactly (`Number.MAX_SAFE_INTEGER`). A larger one is refused with an `error` message (the
/// session goes on), so `input_seq` can never be pushed out of the page's reach.
pub const MAX_INPUT_SEQ: u64 = (1 << 53) - 1;

/// A pose: position (m) and 3×3 rotation matrix (rows), base frame (also the analysis
/// routes' pose, [`crate::api::wire`]).
#[derive(Debug, Clone, Serialize)]
pub struct PoseOut {
    /// [x, y, z] (m).
    pub position: [f64; 3],
    /// Row-major 3×3 rotation.
    pub rotation: [[f64; 3]; 3],
}

impl PoseOut {
    fn new(r: &Matrix3<f64>, p: &nalgebra::Vector3<f64>) -> PoseOut {
        PoseOut {
            position: [p.x, p.y, p.z],
            rotation: [
                [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
            ],
        }
    }
}

impl From<&Isometry3<f64>> for PoseOut {
    fn from(t: &Isometry3<f64>) -> PoseOut {
        PoseOut::new(
            t.rotation.to_rotation_matrix().matrix(),
            &t.translation.vector,
        )
    }
}

impl From<&IsometryMatrix3<f64>> for PoseOut {
    fn from(t: &IsometryMatrix3<f64>) -> PoseOut {
        PoseOut::new(t.rotation.matrix(), &t.translation.vector)
    }
}

/// Wire name of an arm.
pub fn arm_name(arm: Arm) -> &'static str {
    match arm {
        Arm::Left => "left",
        Arm::Right => "right",
    }
}

/// An arm from its wire name.
pub fn parse_arm(name: &str) -> Option<Arm> {
    match name {
        "left" => Some(Arm::Left),
        "right" => Some(Arm::Right),
        _ => None,
    }
}

/// Wire name of a grasp state (state frames, session summaries, records).
pub fn grasp_name(state: GraspState) -> &'static str {
    // The core's names are the wire names (pinned by this module's tests).
    state.as_str()
}

fn serialize_grasp<S: Serializer>(state: &GraspState, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(grasp_name(*state))
}

/// A fault active on one arm: set by the instructor's `fault` action
/// (`crate::sessions::command::fault`), serialized as its label ([`fault_label`]) in state
/// frames and summaries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveFault {
    /// Which arm.
    pub arm: Arm,
    /// What and how much.
    pub fault: Fault,
    /// Injected without telling the trainee (a diagnosis drill): it acts on the simulation
    /// like any fault but is left out of the state frames and of the trainee's summary; only
    /// the instructor's session summary lists it.
    pub silent: bool,
    /// Kept across the trainee's "try again" (a reset); otherwise a reset clears it, so a
    /// silent fault ends with its attempt and is shown in that attempt's debrief only.
    pub persistent: bool,
}

impl ActiveFault {
    /// Whether `other` replaces this one (same arm, kind and actuator).
    pub fn same_slot(&self, other: &ActiveFault) -> bool {
        self.arm == other.arm
            && self.fault.kind() == other.fault.kind()
            && self.fault.joint() == other.fault.joint()
    }
}

/// An active fault as users see it: `supply_drop:left:3000000Pa`, `stuck_valve:right:2:0.5`,
/// `leak:left:1:5e-10`, `air:right:0.3`.
pub fn fault_label(f: &ActiveFault) -> String {
    let arm = arm_name(f.arm);
    let kind = f.fault.kind().name();
    match f.fault {
        Fault::SupplyDrop { drop_pa } => format!("{kind}:{arm}:{drop_pa:.0}Pa"),
        Fault::StuckValve { joint, spool } => format!("{kind}:{arm}:{joint}:{spool}"),
        Fault::Leak {
            joint,
            coefficient_m3_s_pa,
        } => format!("{kind}:{arm}:{joint}:{coefficient_m3_s_pa:e}"),
        Fault::Air { bulk_modulus_scale } => format!("{kind}:{arm}:{bulk_modulus_scale}"),
    }
}

impl Serialize for ActiveFault {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&fault_label(self))
    }
}

/// Per-arm stick input: six axes and a grip, each in [−1, 1].
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ArmAxes {
    /// Joint mode: axis i drives joint i's valve (swing, shoulder, elbow, pitch, yaw, rotate).
    /// Cartesian mode: end-effector [vx, vy, vz, wx, wy, wz] as fractions of the maximum speed.
    #[serde(default)]
    pub axes: Vec<f64>,
    /// Jaw: +1 opens, −1 closes.
    #[serde(default)]
    pub grip: f64,
}

/// Both arms' sticks.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ArmsAxes {
    /// Left arm (index 0).
    #[serde(default)]
    pub left: Option<ArmAxes>,
    /// Right arm (index 1).
    #[serde(default)]
    pub right: Option<ArmAxes>,
}

/// Joint or Cartesian teleoperation (Lim §4.1 "control mode"; wire names `joint`,
/// `cartesian`) and open- or closed-loop cooperative control (Lim case studies 3 and 4; wire
/// names `open`, `closed`): the core operator's own settings, one enum each.
pub use seaarms_core::sim::{ControlMethod, ControlMode};

/// Everything a client may send.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMessage {
    /// Stick input, sent at a steady rate with increasing `seq`.
    Input {
        /// Sequence number, echoed as `input_seq` in state frames once applied.
        seq: u64,
        /// Per-arm axes and grip.
        #[serde(default)]
        arms: ArmsAxes,
        /// Closed loop: commanded object twist [vx, vy, vz, wx, wy, wz] as fractions of the
        /// controller's maximum speeds, each in [−1, 1].
        #[serde(default)]
        object: Option<Vec<f64>>,
    },
    /// A keyboard tap: `arm` (`left`, `right`) moves a bounded amount along `axes` (six
    /// values in [−1, 1], as a stick's) and stops (docs/api.md).
    Jog {
        /// `left` or `right`.
        arm: String,
        /// Joint mode: per joint; Cartesian mode: [vx vy vz wx wy wz] (world frame).
        axes: Vec<f64>,
    },
    /// Change settings; absent fields are unchanged.
    Settings {
        /// Joint or Cartesian.
        #[serde(default)]
        control_mode: Option<ControlMode>,
        /// Open or closed loop.
        #[serde(default)]
        control_method: Option<ControlMethod>,
        /// Arm speed in (0, 1] (Lim Fig. 4-3).
        #[serde(default)]
        arm_speed: Option<f64>,
        /// Cartesian translation holds the jaw's orientation (true) or leaves the spare DOF
        /// to the redundancy resolution (false, "translation only").
        #[serde(default)]
        hold_orientation: Option<bool>,
    },
    /// Back to the initial position (Lim §4.1 "Initial Position").
    Reset,
    /// Pause the simulation clock.
    Pause,
    /// Resume it.
    Resume,
    /// Open both jaws (drop the object).
    Release,
    /// The trainee has read the goal: the exercise attempt's clock starts (a session created
    /// with `wait_for_ready`; otherwise nothing).
    Ready,
    /// Fault-diagnosis drill: name the fault (`supply_drop`, `stuck_valve`, `leak`, `air`).
    Diagnose {
        /// The answer.
        answer: String,
    },
    /// Latency probe: answered by a `pong` with the same `t`.
    Ping {
        /// Client timestamp (any unit; echoed).
        t: f64,
    },
}

/// `POST /api/sessions/{id}/actions`: instructor actions on a session (a trainee may give `reset`, `pause`, `resume` and
/// `release` to its own session).
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Back to the initial position.
    Reset,
    /// Pause the clock.
    Pause,
    /// Resume it.
    Resume,
    /// Open both jaws.
    Release,
    /// Change scenario (resets the session).
    Scenario {
        /// Scenario name.
        scenario: String,
    },
    /// Inject a fault.
    Fault {
        /// `supply_drop` (value: Pa, 0..6.89e6), `stuck_valve` (joint 0..5, value: spool in
        /// [−1, 1]), `leak` (joint, value: m³/(s·Pa) in [0, 1e-9]), `air` (value: bulk-modulus
        /// scale in [0.01, 1]).
        fault: String,
        /// `left` or `right`.
        arm: String,
        /// Joint index 0..5 (stuck_valve, leak).
        #[serde(default)]
        joint: Option<usize>,
        /// Size of the fault (see `fault`).
        value: f64,
        /// Injected without telling the trainee: left out of the state frames and the
        /// trainee's view; the instructor's session summary lists it with `"silent": true`.
        #[serde(default)]
        silent: bool,
        /// Kept when the trainee resets ("try again"); a reset clears other faults.
        #[serde(default)]
        persistent: bool,
    },
    /// Remove every fault.
    ClearFaults,
    /// Set the water's current (a subsea session): speed in [0, 2.5] m/s, heading (the
    /// direction it flows towards, degrees from +x towards +y) within ±360°.
    SetCurrent {
        /// Speed (m/s).
        speed_m_s: f64,
        /// Heading (degrees).
        heading_deg: f64,
    },
    /// Set how far one sees in the water on every page of the session (m, in [0.5, 50]).
    SetVisibility {
        /// Visibility (m).
        visibility_m: f64,
    },
    /// Show a message on the trainee's page.
    Message {
        /// Up to 500 characters.
        text: String,
    },
}

/// Current settings of a session.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct Settings {
    /// Joint or Cartesian.
    pub control_mode: ControlMode,
    /// Open or closed loop.
    pub control_method: ControlMethod,
    /// Arm speed in (0, 1].
    pub arm_speed: f64,
    /// Cartesian translation holds the jaw's orientation (the default for a new session;
    /// false: translation only, the spare DOF to the redundancy resolution). Absent in
    /// records made before the hold existed: false, as they ran.
    #[serde(default)]
    pub hold_orientation: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            control_mode: ControlMode::Joint,
            control_method: ControlMethod::Open,
            arm_speed: 1.0,
            hold_orientation: true,
        }
    }
}

/// One arm as the page draws it.
#[derive(Debug, Clone, Serialize)]
pub struct ArmModelOut {
    /// The model in the inline-model schema (DH table, limits, velocities).
    pub model: seaarms_core::ModelSpec,
    /// Base pose in the world frame.
    pub base: PoseOut,
}

/// The object as the page draws it.
#[derive(Debug, Clone, Serialize)]
pub struct ObjectModelOut {
    /// Box size [x, y, z] (m).
    pub size_m: [f64; 3],
    /// Mass (kg).
    pub mass_kg: f64,
}

/// A scenario a live session can start from (`hello.scenarios`, the `scenario` field of
/// `POST /api/sessions`).
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioOut {
    /// Name to create a session with.
    pub name: &'static str,
    /// What it sets up.
    pub description: &'static str,
}

/// First message on every connection.
#[derive(Debug, Clone, Serialize)]
pub struct Hello {
    /// Session id.
    pub session: String,
    /// `trainee` (may control) or `observer` (read-only).
    pub role: &'static str,
    /// Left and right arm models with their bases.
    pub arms: [ArmModelOut; 2],
    /// The object.
    pub object: ObjectModelOut,
    /// Height of the seabed surface (m, world z).
    pub seabed_z_m: f64,
    /// Current settings.
    pub settings: Settings,
    /// Scenario the session was created with.
    pub scenario: String,
    /// State frames per second.
    pub frame_hz: u32,
    /// Most messages per second the server accepts from this connection (bursts of two
    /// seconds' worth); the page sends input below this rate.
    pub max_messages_per_second: u32,
    /// Scenarios a new session can start from (the page's scenario menu).
    pub scenarios: Vec<ScenarioOut>,
    /// The exercise file when the session runs an exercise, else `null`.
    pub exercise: Option<Arc<ExerciseSpec>>,
    /// What to draw besides the arms and the box.
    pub scene: SceneOut,
    /// The replica serving this connection (live sessions; absent in replays).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replica: Option<String>,
    /// On the replay socket: the attempt replayed and its length (absent on live sessions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayOut>,
}

/// The attempt a replay socket plays (`hello.replay`).
#[derive(Debug, Clone, Serialize)]
pub struct ReplayOut {
    /// Attempt id.
    pub attempt: String,
    /// Its length (s).
    pub duration_s: f64,
}

/// Everything a client may send on the replay socket `/ws/replay/{id}`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ReplayClientMessage {
    /// Play from the current time (from the start when at the end).
    Play,
    /// Stop playing.
    Pause,
    /// Move to `t` (s since the attempt's start; finite, clamped to its length).
    Seek {
        /// Time (s).
        t: f64,
    },
    /// Playback speed (0.25–8×).
    Speed {
        /// Speed factor.
        value: f64,
    },
}

/// What the page draws besides the arms and the box: the box's handles, the exercise's
/// targets, zones, ghosts and obstacles.
#[derive(Debug, Clone, Serialize)]
pub struct SceneOut {
    /// Handle bar centres in the box's frame (m): index 0 the left arm's side handle, 1 the
    /// right's, 2 the lifting point over the centre of mass. Every bar runs along the box's
    /// x axis (`handle_axes`).
    pub handles_m: Vec<[f64; 3]>,
    /// Each handle bar's axis in the box's frame (unit).
    pub handle_axes: Vec<[f64; 3]>,
    /// How each handle's bar stands on the box: "ends" (a grab handle on two end posts) or
    /// "centre" (the lifting point's T-handle on one post down to the top face).
    pub handle_posts: Vec<&'static str>,
    /// Radius around a handle's bar within which a closing jaw aligned with it grasps it (m).
    pub capture_radius_m: f64,
    /// Floating markers.
    pub targets: Vec<seaarms_core::exercise::spec::Target>,
    /// Zones on the seabed.
    pub zones: Vec<seaarms_core::exercise::spec::Zone>,
    /// Ghost postures.
    pub ghosts: Vec<seaarms_core::exercise::spec::Ghost>,
    /// Obstacle boxes.
    pub obstacles: Vec<seaarms_core::exercise::spec::Obstacle>,
    /// The intervention panel, when the scene has one.
    pub panel: Option<PanelSceneOut>,
}

/// The panel as the page draws it (world frame, m).
#[derive(Debug, Clone, Serialize)]
pub struct PanelSceneOut {
    /// Pose of the panel frame (centre of the face; x into the panel).
    pub pose: PoseOut,
    /// Plate size: thickness, width, height.
    pub size_m: [f64; 3],
    /// Valve T-bar grip point at 0°.
    pub valve_grip_m: [f64; 3],
    /// Hot-stab receptacle mouth.
    pub receptacle_m: [f64; 3],
    /// Holster mouth.
    pub holster_m: [f64; 3],
}

/// The panel's moving parts in a state frame.
#[derive(Debug, Clone, Serialize)]
pub struct PanelFrame {
    /// Valve angle (degrees, 0 closed, 90 open).
    pub valve_angle_deg: f64,
    /// `holstered`, `held`, `inserting`, `seated` or `dropped`.
    pub stab_phase: &'static str,
    /// Pose of the hot stab.
    pub stab_pose: PoseOut,
    /// Insertion depth (m).
    pub stab_depth_m: f64,
    /// Side load on the stab (N).
    pub side_load_n: f64,
}

impl SceneOut {
    /// The scene of a simulation running `exercise` (or free play).
    pub fn new(params: &seaarms_core::sim::SimParams, exercise: Option<&ExerciseSpec>) -> SceneOut {
        let h = &params.object.handles;
        let scene = exercise.map(|e| e.scene.clone()).unwrap_or_default();
        let v = |x: &nalgebra::Vector3<f64>| [x.x, x.y, x.z];
        SceneOut {
            handles_m: h.iter().map(|h| v(&h.centre_m)).collect(),
            handle_axes: h.iter().map(|h| v(&h.axis)).collect(),
            handle_posts: h
                .iter()
                .map(|h| match h.posts {
                    seaarms_core::grasp::Posts::Ends => "ends",
                    seaarms_core::grasp::Posts::Centre => "centre",
                })
                .collect(),
            capture_radius_m: params.object.capture_radius_m,
            targets: scene.targets,
            zones: scene.zones,
            ghosts: scene.ghosts,
            obstacles: scene.obstacles,
            panel: params.panel.as_ref().map(|p| {
                let v = |x: nalgebra::Vector3<f64>| [x.x, x.y, x.z];
                PanelSceneOut {
                    pose: PoseOut::from(&p.pose),
                    size_m: v(p.size_m),
                    valve_grip_m: v(p.valve_grip_m()),
                    receptacle_m: v(p.receptacle_mouth_m()),
                    holster_m: v(p.holster_mouth_m()),
                }
            }),
        }
    }
}

/// Why a session ended (the `ended` message's `reason` is its [`EndReason::code`]; its
/// [`EndReason::text`] is the session record's `end_reason`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndReason {
    /// An instructor ended it (`DELETE /api/sessions/{id}` or the `end` action).
    Instructor,
    /// The trainee ended it.
    Trainee,
    /// No input for the idle timeout (a trainee connected but inactive, or none connected).
    IdleTimeout,
    /// No trainee joined within the grace period after creation.
    NoTraineeJoined,
    /// The trainee left: its last connection closed and none came back within the grace.
    Abandoned {
        /// The grace period (s, `--abandon-grace-seconds`).
        grace_s: u64,
    },
    /// The server is shutting down.
    ServerShutdown,
}

impl EndReason {
    /// Wire code (the `ended` message's `reason`).
    pub fn code(self) -> &'static str {
        match self {
            EndReason::Instructor => "instructor",
            EndReason::Trainee => "trainee",
            EndReason::IdleTimeout => "idle_timeout",
            EndReason::NoTraineeJoined => "no_trainee_joined",
            EndReason::Abandoned { .. } => "abandoned",
            EndReason::ServerShutdown => "server_shutdown",
        }
    }

    /// Human text, as session records and summaries give it (`end_reason`).
    pub fn text(self) -> String {
        match self {
            EndReason::Instructor => "ended by instructor".into(),
            EndReason::Trainee => "ended by trainee".into(),
            EndReason::IdleTimeout => "idle timeout".into(),
            EndReason::NoTraineeJoined => "no trainee joined".into(),
            EndReason::Abandoned { grace_s } => {
                format!("the trainee left: no connection for {grace_s} s")
            }
            EndReason::ServerShutdown => "server shutdown".into(),
        }
    }
}

impl Serialize for EndReason {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.code())
    }
}

/// Ellipsoid radii (m/s) along unit axes, world frame.
#[derive(Debug, Clone, Serialize)]
pub struct EllipsoidFrame {
    /// Semi-axes.
    pub radii: [f64; 3],
    /// Unit directions (one per radius).
    pub axes: [[f64; 3]; 3],
}

/// Translational manipulability measures.
#[derive(Debug, Clone, Serialize)]
pub struct MeasuresFrame {
    /// √det(JJᵀ).
    pub yoshikawa: f64,
    /// σmin/σmax.
    pub isotropy: f64,
    /// Yoshikawa × isotropy (Lim eq. 4.1).
    pub hong: f64,
    /// σmax/σmin; null at a singularity.
    pub condition_number: Option<f64>,
    /// Joint-limit measure (Jun eq. 16); absent for the dual ellipsoid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jlm: Option<f64>,
}

/// One arm in a state frame.
#[derive(Debug, Clone, Serialize)]
pub struct ArmFrame {
    /// Joint angles (rad).
    pub q: [f64; 6],
    /// Joint velocities (rad/s).
    pub qd: [f64; 6],
    /// Inlet line pressures (Pa).
    pub p_in: [f64; 6],
    /// Outlet line pressures (Pa).
    pub p_out: [f64; 6],
    /// Jaw opening (m).
    pub jaw_opening_m: f64,
    /// The jaw holds the object.
    pub holding: bool,
    /// The jaw touches the object.
    pub contact: bool,
    /// End-effector pose, world.
    pub pose: PoseOut,
    /// Joint frames after their motion, world (for drawing the links).
    pub joint_frames: Vec<PoseOut>,
    /// Translational manipulability ellipsoid at the end-effector, world.
    pub ellipsoid: EllipsoidFrame,
    /// Its measures.
    pub measures: MeasuresFrame,
    /// Contact force (N) and torque (N·m) on the object, world.
    pub contact_force_n: [f64; 3],
    /// Contact torque (N·m).
    pub contact_torque_nm: [f64; 3],
    /// Relief valve open, per actuator.
    pub relief_open: [bool; 6],
    /// The jaw's load fraction against its static friction limits (0 when not holding; ≥ 1
    /// slips; see docs/physics.md "Grasp and the dynamic case studies").
    pub grip_load: f64,
    /// The bar is slipping in the jaw.
    pub slipping: bool,
    /// What this jaw would grasp if it closed now (`handle-0`, `handle-1`, `valve`, `stab`),
    /// or `null`: the page's capture cue.
    pub capture: Option<&'static str>,
    /// The arm's strongest contact with the world in the last step (links and jaw on the
    /// seabed, the box, the panel, the vehicle, the other arm; not the grasp), or `null`.
    pub touch: Option<TouchOut>,
    /// The arm's strikes since reset, all partners (`sim::Event::Strike`).
    pub strikes: u64,
}

/// An arm's strongest contact with the world ([`ArmFrame::touch`]).
#[derive(Debug, Clone, Serialize)]
pub struct TouchOut {
    /// `seabed`, `box`, `panel`, `vehicle` or `other-arm`.
    pub partner: &'static str,
    /// `link-0` … `link-5`, `wrist`, `finger-0`, `finger-1`.
    pub part: String,
    /// Contact point on the arm, world (m).
    pub point_m: [f64; 3],
    /// Normal force (N) of this point.
    pub force_n: f64,
    /// Sum of the normal forces of all the arm's contact points (N).
    pub total_force_n: f64,
    /// Penetration (m) of this point.
    pub depth_m: f64,
}

/// The dual-arm ellipsoid (Lim eq. 3.68), present while both jaws hold the object.
#[derive(Debug, Clone, Serialize)]
pub struct DualFrame {
    /// Ellipsoid at the object, world.
    pub ellipsoid: EllipsoidFrame,
    /// Its measures.
    pub measures: MeasuresFrame,
}

/// The object in a state frame.
#[derive(Debug, Clone, Serialize)]
pub struct ObjectFrame {
    /// Pose, world.
    pub pose: PoseOut,
    /// Linear velocity (m/s).
    pub velocity: [f64; 3],
}

/// Where a practice attempt was taken over from ([`StateFrame::practice`]).
#[derive(Debug, Clone, Serialize)]
pub struct PracticeOut {
    /// The source attempt's id.
    pub attempt: String,
    /// Seconds since the source's start.
    pub t: f64,
}

/// A state frame (server → client at the frame rate).
#[derive(Debug, Clone, Serialize)]
pub struct StateFrame {
    /// Simulated time (s).
    pub t: f64,
    /// Frame sequence number (gaps = frames this client skipped).
    pub seq: u64,
    /// Last input `seq` applied.
    pub input_seq: u64,
    /// Clock paused.
    pub paused: bool,
    /// Who paused it (`instructor`, `trainee`), `null` while running.
    pub paused_by: Option<crate::auth::Actor>,
    /// The exercise attempt waits for the trainee's `ready` (the session was created with
    /// `wait_for_ready`): no steps pass and its clock reads 0.
    pub awaiting_ready: bool,
    /// The running attempt is a practice attempt taken over from another attempt's replay
    /// ("take over from here"); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub practice: Option<PracticeOut>,
    /// Current settings.
    pub settings: Settings,
    /// Left and right arm.
    pub arms: ArmsFrame,
    /// Dual-arm ellipsoid, when both jaws hold the object.
    pub dual: Option<DualFrame>,
    /// The object.
    pub object: ObjectFrame,
    /// `free`, `one_on_surface`, `one_lifted`, `one_holding_other_contact`, `both_holding`.
    #[serde(serialize_with = "serialize_grasp")]
    pub grasp: GraspState,
    /// Internal force (N) on the object (Lim eq. 3.47).
    pub internal_force_n: [f64; 3],
    /// Internal torque (N·m).
    pub internal_torque_nm: [f64; 3],
    /// Relief-valve openings since reset (overload events).
    pub relief_events: u64,
    /// Active warnings: `near_singularity:left`, `near_joint_limit:right:3`, `relief:left:2`,
    /// `slip:left`, …
    pub warnings: Vec<String>,
    /// Active faults, as instructors set them (labels, see [`fault_label`]); neither a fault
    /// drill's hidden fault nor a silent fault (`"silent": true` on injection) is listed.
    pub faults: Vec<ActiveFault>,
    /// The scenario or exercise id the session runs.
    pub scenario: String,
    /// The exercise attempt's progress (`null` in free play).
    pub exercise: Option<seaarms_core::exercise::Status>,
    /// The panel's moving parts (`null` without a panel).
    pub panel: Option<PanelFrame>,
    /// The water's current `{speed_m_s, heading_deg}` (heading: the direction it flows
    /// towards, degrees from +x towards +y) in a subsea session; `null` in air.
    pub current: Option<seaarms_core::sim::Current>,
    /// The water's visibility the instructor set (m), or `null`: each page's own choice.
    pub visibility_m: Option<f64>,
}

/// Left and right arm frames.
#[derive(Debug, Clone, Serialize)]
pub struct ArmsFrame {
    /// Left arm.
    pub left: ArmFrame,
    /// Right arm.
    pub right: ArmFrame,
}

/// Everything the server sends.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// Once, first.
    Hello(Box<Hello>),
    /// At the frame rate.
    State(Box<StateFrame>),
    /// A message was refused or adjusted; the session keeps running.
    Error {
        /// What was wrong.
        message: String,
    },
    /// An instructor's message to the trainee.
    Message {
        /// Who sent it.
        from: String,
        /// Text.
        text: String,
    },
    /// The session switched scenario or exercise (e.g. set by the instructor): what to draw
    /// and the new settings; state frames of the new scenario follow.
    Scenario {
        /// Scenario or exercise id.
        scenario: String,
        /// The exercise file, or `null`.
        exercise: Option<Arc<ExerciseSpec>>,
        /// What to draw.
        scene: Box<SceneOut>,
        /// Settings now in force.
        settings: Settings,
    },
    /// The replay socket's playback status, after every command and every frame played.
    Replay {
        /// Replay time (s since the attempt's start).
        t: f64,
        /// Playing or paused.
        playing: bool,
        /// Playback speed.
        speed: f64,
        /// The attempt's length (s).
        duration_s: f64,
    },
    /// Answer to a ping.
    Pong {
        /// The ping's timestamp.
        t: f64,
    },
    /// The session has ended; the close frame follows. Reconnecting cannot resume it.
    Ended {
        /// Why, as a code.
        reason: EndReason,
        /// Why, as text (the record's `end_reason`).
        text: String,
    },
}

impl ServerMessage {
    /// The `ended` message for `reason`.
    pub fn ended(reason: EndReason) -> Self {
        ServerMessage::Ended {
            reason,
            text: reason.text(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use seaarms_core::hydraulics::FaultKind;

    /// The `ended` message as web/connection.js reads it (`type`, `reason` code, `text`);
    /// the texts are the record strings tests/sessions.rs and tests/admission_and_security.rs
    /// read back as `end_reason`.
    #[test]
    fn ended_message_wire_shape() {
        let v = serde_json::to_value(ServerMessage::ended(EndReason::Instructor)).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"type": "ended", "reason": "instructor", "text": "ended by instructor"})
        );
        let v = serde_json::to_value(ServerMessage::ended(EndReason::NoTraineeJoined)).unwrap();
        assert_eq!(v["reason"], "no_trainee_joined");
        assert_eq!(v["text"], "no trainee joined");
        assert_eq!(EndReason::ServerShutdown.text(), "server shutdown");
        let v = serde_json::to_value(ServerMessage::ended(EndReason::Abandoned { grace_s: 30 }))
            .unwrap();
        assert_eq!(
            v,
            serde_json::json!({"type": "ended", "reason": "abandoned",
                "text": "the trainee left: no connection for 30 s"})
        );
    }

    /// The wire strings the page and the instructor dashboard rely on (README "Protocol",
    /// web/instructor.js) are unchanged by the typed faults and grasp states.
    #[test]
    fn wire_strings_of_faults_and_grasp_states() {
        let label = |arm, kind, joint, value| {
            fault_label(&ActiveFault {
                arm,
                fault: Fault::new(kind, joint, value).unwrap(),
                silent: false,
                persistent: false,
            })
        };
        assert_eq!(
            label(Arm::Left, FaultKind::SupplyDrop, None, 3.0e6),
            "supply_drop:left:3000000Pa"
        );
        assert_eq!(
            label(Arm::Right, FaultKind::StuckValve, Some(2), 0.5),
            "stuck_valve:right:2:0.5"
        );
        assert_eq!(
            label(Arm::Left, FaultKind::Leak, Some(1), 5e-10),
            "leak:left:1:5e-10"
        );
        assert_eq!(
            label(Arm::Right, FaultKind::Air, None, 0.3),
            "air:right:0.3"
        );
        let f = ActiveFault {
            arm: Arm::Left,
            fault: Fault::new(FaultKind::Air, None, 0.3).unwrap(),
            silent: true,
            persistent: false,
        };
        assert_eq!(serde_json::to_value(f).unwrap(), "air:left:0.3");
        for kind in FaultKind::ALL {
            assert_eq!(FaultKind::parse(kind.name()), Some(kind));
        }
        for arm in Arm::BOTH {
            assert_eq!(parse_arm(arm_name(arm)), Some(arm));
        }
        // The core's own snake-case names (CSV) agree with the wire names.
        for g in [
            GraspState::Free,
            GraspState::OneOnSurface,
            GraspState::OneLifted,
            GraspState::OneHoldingOtherContact,
            GraspState::BothHolding,
        ] {
            assert_eq!(grasp_name(g), g.as_str());
        }
    }
}
