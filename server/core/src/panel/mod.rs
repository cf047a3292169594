//! A subsea intervention panel: a vertical plate standing on the seabed with a quarter-turn
//! T-bar valve, a hot-stab receptacle and a holster holding the hot stab (issue 15's
//! `valve-turn` and `hot-stab` exercises).
//!
//! # What is modelled
//! * **Valve** ([`ValveParams`], [`valve_step`]): one revolute degree of freedom about the
//!   stem axis, quarter turn 0–90° between rigid end stops, rotor inertia, breakaway (static)
//!   and running (Coulomb) friction torque and a small viscous term. Stick–slip: a stuck valve
//!   stays put while the torque about its axis is at most the breakaway torque; once moving
//!   it runs against the running torque until its rate would change sign (then it sticks
//!   again) or it reaches a stop.
//! * **Hot stab** ([`StabParams`]): a rigid cylinder with a handle, parked in a holster on the
//!   panel. Held, it moves with the jaw; at the receptacle mouth it enters only when its tip
//!   is within the position tolerance of the receptacle axis and its axis within the angle
//!   tolerance, otherwise the panel face blocks it (a stiff penalty spring on the tip). Inside,
//!   two lateral bearing springs (tip and mouth) keep it on the receptacle axis, with a play
//!   that the entry chamfer narrows to zero over its length; the larger of the two bearing
//!   forces is the side load. Axial motion meets the insertion (seal) friction; at full depth
//!   a latch spring, and pushing it with the seating force latches the stab (seated) where it
//!   is, its tip at full depth. A seated stab stays when released; held, its side load is the
//!   jaw's force across the axis (bearing compliance), and pulling it out with more than the
//!   seating force unlatches it. A side load rising above the limit counts one fault.
//! * **Coupling to the jaw** (`contact.rs`): the held item's reaction is a wrench at the tool
//!   point, added to the arm's joint torques as Jᵀ·F (Lim eq. 3.38's external-force term
//!   JᵀF, as the grasp constraint's contact wrenches enter it). The jaw is coupled to a held
//!   valve or seated stab by a stiff 6-D spring–damper, and a held free stab is rigid in the
//!   jaw with its mass lumped at the tool point. All stiff terms are linearly implicit in the
//!   arm's H̃ (like the joint end stops, see `sim`'s module docs) and the valve's own update is
//!   backward Euler in its coupling spring, so the 1 ms step stays stable
//!   (`tests/panel.rs`).
//!
//! # Simplifications
//! * The jaw holds the item rigidly (no slip), like the box handles; the clamp force is the
//!   jaw's (Lim Table 1-1: 150 kgf) but does not limit the transmitted wrench.
//! * The held stab's mass is a point mass at the tool point (its rotational inertia and the
//!   centripetal term m·J̇q̇ are neglected: 3 kg at arm speeds below 0.2 m/s).
//! * Taking the stab out of the holster meets no resistance (a loose parking sleeve); a stab
//!   whose tip enters the holster mouth aligned (same tolerances) is back in its sleeve and,
//!   released there, holstered; released anywhere else outside the receptacle it drops to
//!   the seabed ([`StabPhase::Dropped`]) where it can be picked up again.
//! * Links and jaws collide with the plate, the valve and the stab as fixed shapes
//!   (`sim`'s contacts, [`crate::collision`]): a link pushing the T-bar does not turn it.
//!
//! # Sources
//! Lim 2005 (seeds: `lim2005-dual-hydraulic-manipulator-simulator.txt`): Table 1-1 (jaw
//! opening 7.5 cm, clamp force 150 kg, rotate 150°/s, reach 1.5 m) and eq. 3.38 (the JᵀF term).
//! The wrist rotate motor is sized for 150 N·m (`hydraulics::sizing::MAGNUM_TORQUE_FLOOR_NM`),
//! which bounds what the valve may need. API TR 17TR15 (2016, "API 17H Hydraulic Interfaces
//! for Hot Stabs": hot stabs are pressure-balanced connections, three categories by profile
//! and diameter, bores 0.25–3.5 in) and the Wikipedia article "Hot stab" (receptacles are
//! concentric cylinder and cone sections that guide the stab; O-ring seal lands along the
//! body) fix the kind of object; ISO 13628-8 / API 17H define the ROV-operated low-torque
//! (manipulator) handle and the rotary torque classes, but their tables are not public: every
//! number below that comes from them is marked as recalled, not verified, and each value's
//! doc says where it comes from.

mod contact;

pub(crate) use contact::{ToolLoad, item_torque_about, tool_load};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::Error;
use crate::sim::{Arm, OBJECT_XY_M, SEABED_Z_M};

/// The valve: a quarter-turn ball valve with a T-bar handle for the manipulator jaw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValveParams {
    /// Where the stem axis meets the panel face, panel frame (m): (0, 0, 0.225) in
    /// [`PanelParams::standard`] — world z = +0.15, the top of the three items.
    pub axis_point_m: Vector3<f64>,
    /// Stem length from the face to the T-bar grip point on the axis (m): 0.10 (assumed; puts
    /// the grip at world x = 1.36, inside both arms' common reach, see [`PanelParams`]).
    pub stem_length_m: f64,
    /// T-bar cross-bar length (m): 0.15 (assumed; a hand-size T-bar of the kind ISO 13628-8
    /// shows for manipulator-operated low-torque valves). Drawing only.
    pub bar_length_m: f64,
    /// Grip width the jaw closes on (m): 0.04 (the hub of the T-bar; < the 7.5 cm jaw
    /// opening of Lim Table 1-1, same as the box handles).
    pub grip_width_m: f64,
    /// Travel (rad): π/2, a quarter turn from closed (0) to open, with rigid stops at both ends.
    pub travel_rad: f64,
    /// Rotor inertia about the stem (kg·m²): 0.02 (assumed: T-bar, stem and ball of a 1-in
    /// ball valve; a steel T-bar of 1 kg and 0.15 m alone has m·l²/12 ≈ 0.002).
    pub inertia_kg_m2: f64,
    /// Breakaway (static) torque (N·m): 40. Assumed within ISO 13628-8 / API 17H torque
    /// class 1 (recalled as ≤ 67 N·m, 50 ft·lbf, for the smallest rotary interface; not
    /// verified) and well under the Magnum rotate motor's 150 N·m, so one arm can turn it.
    pub breakaway_torque_nm: f64,
    /// Running (Coulomb) torque (N·m): 25 (assumed: about 60 % of breakaway, the usual
    /// static-to-dynamic ratio of a seated ball valve).
    pub running_torque_nm: f64,
    /// Viscous torque coefficient (N·m·s/rad): 1.0 (assumed; 2.6 N·m at the rotate joint's
    /// nominal 150°/s — small against the running torque).
    pub viscous_nm_s_rad: f64,
}

/// The hot stab, its holster and the receptacle (both on the panel face, axes along the panel
/// normal into the panel).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabParams {
    /// Mass in air (kg): 3 (assumed: a stainless single-port hot stab with handle, e.g. a
    /// 1/2-in-bore API 17H stab is a few kg).
    pub mass_kg: f64,
    /// Body length from the handle grip point to the tip (m): 0.14 (assumed; shortened from
    /// real stabs' 0.2–0.3 m so the whole insertion stays inside the two arms' common reach).
    pub length_m: f64,
    /// Body diameter (m): 0.035 (assumed, drawing and clearance only).
    pub diameter_m: f64,
    /// Handle width the jaw closes on (m): 0.04 (assumed, like the box handles).
    pub handle_width_m: f64,
    /// Holster mouth on the panel face, panel frame (m): (0, 0, −0.075) — world z = −0.15.
    pub holster_m: Vector3<f64>,
    /// How deep the tip sits in the holster (m): 0.03.
    pub holster_depth_m: f64,
    /// Receptacle mouth on the panel face, panel frame (m): (0, 0, 0.075) — world z = 0.
    pub receptacle_m: Vector3<f64>,
    /// Full insertion depth of the tip past the mouth (m): 0.05 (assumed; see `length_m`).
    pub insertion_depth_m: f64,
    /// Position tolerance (m): 0.010 — the tip must be within this distance of the receptacle
    /// axis to enter (the entry cone's capture; assumed, about the Magnum's ±12.7 mm accuracy
    /// of Table 1-1).
    pub position_tolerance_m: f64,
    /// Angle tolerance (rad): 5° between the stab and receptacle axes (assumed).
    pub angle_tolerance_rad: f64,
    /// Seating force (N): 300 — the push on the full-depth stop that latches the stab
    /// (assumed: seal friction plus latch of a single-port stab; well within the arm's
    /// 295 kg lift of Table 1-1).
    pub seating_force_n: f64,
    /// Side-load limit (N): 400 (assumed); a side load rising above it counts one fault
    /// (re-armed once it falls below 90 % of the limit).
    pub side_load_limit_n: f64,
    /// Insertion (seal) friction (N): 40 plus `friction_coefficient` × side load (assumed).
    pub insertion_friction_n: f64,
    /// Friction coefficient of the bearing (side) load in the bore: 0.2 (steel on steel,
    /// wet; assumed).
    pub friction_coefficient: f64,
    /// Lateral bearing stiffness at the tip and at the mouth, and across the axis of a seated
    /// stab held by the jaw (N/m): 2·10⁴ (the bore, stab and the jaw's grip on the handle —
    /// the "float" a hot stab needs; assumed: the 400 N limit at 20 mm of misfit, so the
    /// millimetre errors of a hydraulic arm's position control do not count as faults).
    pub bearing_stiffness_n_m: f64,
    /// Length of the receptacle's entry chamfer (m): 0.01 (assumed). The radial play the
    /// bearings allow shrinks linearly from the position tolerance at the mouth to 0 at this
    /// depth — the entry cone that guides the stab in (Wikipedia "Hot stab": "guided into the
    /// port by the port geometry ... cone sections").
    pub chamfer_length_m: f64,
    /// Lateral bearing damping (N·s/m): 1·10³ (assumed; about critical for the 3 kg stab on
    /// the bearing spring).
    pub bearing_damping_n_s_m: f64,
    /// Stiffness of the panel face against the stab's tip (N/m): 5·10⁶ (assumed: a steel
    /// plate; the arm stalled on it at 5 kN sinks 1 mm — a hydraulic arm pushes up to its
    /// relief pressure, so a softer face would let a misaligned stab through).
    pub face_stiffness_n_m: f64,
    /// Damping of the face and the latch (N·s/m): 2·10⁴ (assumed).
    pub face_damping_n_s_m: f64,
    /// Stiffness of the latch at full depth (N/m): 5·10⁴ (assumed). Pushed past full depth the
    /// stab compresses the latch spring; the latch engages when its force reaches the seating
    /// force (6 mm with the standard values).
    pub latch_stiffness_n_m: f64,
}

/// Stiffness and damping of the jaw–item coupling (a held valve or seated stab): the
/// jaw's grip and the item's mounting, as a 6-D spring–damper between the tool frame and
/// where the grasp puts it. Treated implicitly (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingParams {
    /// Translational stiffness (N/m): 5·10⁴ (assumed; 250 N at 5 mm).
    pub stiffness_n_m: f64,
    /// Translational damping (N·s/m): 2·10³ (assumed).
    pub damping_n_s_m: f64,
    /// Rotational stiffness (N·m/rad): 3·10³ (assumed; the 40 N·m breakaway winds it up 0.8°).
    pub stiffness_nm_rad: f64,
    /// Rotational damping (N·m·s/rad): 30 (assumed; ≈ 2·√(k·I) with I ≈ 0.05 kg·m² for the
    /// valve rotor plus the wrist rotate link).
    pub damping_nm_s_rad: f64,
}

/// The panel: plate pose and size, its items and the capture radius.
///
/// World coordinates of [`PanelParams::standard`] (arm bases at y = 0 and 1, facing +x): the
/// face is the plane x = 1.46 m, y 0.25…0.75, z from the seabed (−0.45) to +0.30; the valve
/// grip point is at (1.36, 0.50, 0.15), the receptacle mouth at (1.46, 0.50, 0.00), the
/// holster mouth at (1.46, 0.50, −0.15), all axes along +x. The 50 kg box (x ≤ 1.15) is
/// 0.31 m clear. With the jaw pointing along +x both Magnums reach tool points from
/// x ≈ 1.24 to 1.39 m on the midplane y = 0.5 at z = −0.15…0.15 (Magnum closed-form IK; the
/// swing joint's ±25° of Table 1-1 binds at the near end, the reach at the far end;
/// `tests/panel.rs` checks the grip, pre-insert and seated points for both arms).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PanelParams {
    /// Pose of the panel frame in the world: origin at the centre of the face, x along the
    /// face normal into the panel (the insertion direction), z up.
    pub pose: Isometry3<f64>,
    /// Plate size (m): thickness (x), width (y), height (z) = 0.04 × 0.50 × 0.75; the face is
    /// centred on the frame origin and its bottom edge stands on the seabed.
    pub size_m: Vector3<f64>,
    /// The valve.
    pub valve: ValveParams,
    /// The hot stab, holster and receptacle.
    pub stab: StabParams,
    /// The jaw–item coupling.
    pub coupling: CouplingParams,
    /// Capture radius (m): 0.04, as the box handles' (`grasp::ObjectParams`).
    pub capture_radius_m: f64,
}

const DEG: f64 = std::f64::consts::PI / 180.0;
/// Face plane of the standard panel (world x, m).
const FACE_X_M: f64 = 1.46;

impl PanelParams {
    /// The documented standard panel (see the type docs for its world coordinates).
    pub fn standard() -> PanelParams {
        let height = 0.75;
        let centre_z = SEABED_Z_M + 0.5 * height;
        PanelParams {
            pose: Isometry3::translation(FACE_X_M, OBJECT_XY_M[1], centre_z),
            size_m: Vector3::new(0.04, 0.50, height),
            valve: ValveParams {
                axis_point_m: Vector3::new(0.0, 0.0, 0.15 - centre_z),
                stem_length_m: 0.10,
                bar_length_m: 0.15,
                grip_width_m: 0.04,
                travel_rad: 90.0 * DEG,
                inertia_kg_m2: 0.02,
                breakaway_torque_nm: 40.0,
                running_torque_nm: 25.0,
                viscous_nm_s_rad: 1.0,
            },
            stab: StabParams {
                mass_kg: 3.0,
                length_m: 0.14,
                diameter_m: 0.035,
                handle_width_m: 0.04,
                holster_m: Vector3::new(0.0, 0.0, -0.15 - centre_z),
                holster_depth_m: 0.03,
                receptacle_m: Vector3::new(0.0, 0.0, -centre_z),
                insertion_depth_m: 0.05,
                position_tolerance_m: 0.010,
                angle_tolerance_rad: 5.0 * DEG,
                seating_force_n: 300.0,
                side_load_limit_n: 400.0,
                insertion_friction_n: 40.0,
                friction_coefficient: 0.2,
                bearing_stiffness_n_m: 2.0e4,
                chamfer_length_m: 0.01,
                bearing_damping_n_s_m: 1.0e3,
                face_stiffness_n_m: 5.0e6,
                face_damping_n_s_m: 2.0e4,
                latch_stiffness_n_m: 5.0e4,
            },
            coupling: CouplingParams {
                stiffness_n_m: 5.0e4,
                damping_n_s_m: 2.0e3,
                stiffness_nm_rad: 3.0e3,
                damping_nm_s_rad: 30.0,
            },
            capture_radius_m: 0.04,
        }
    }

    /// What [`crate::sim::Simulation::new`] requires of a panel: finite values, positive
    /// sizes, masses, inertia, stiffnesses and tolerances, running ≤ breakaway torque, travel
    /// in (0, 2π), jaw widths within (0, `jaw_max_m`].
    pub fn check(&self, jaw_max_m: f64) -> Result<(), Error> {
        let bad = |reason: &str| {
            Err(Error::InvalidParameter {
                what: "panel",
                reason: reason.into(),
            })
        };
        let v = &self.valve;
        let s = &self.stab;
        let c = &self.coupling;
        let positive = [
            self.size_m.x,
            self.size_m.y,
            self.size_m.z,
            self.capture_radius_m,
            v.stem_length_m,
            v.bar_length_m,
            v.inertia_kg_m2,
            v.breakaway_torque_nm,
            s.mass_kg,
            s.length_m,
            s.diameter_m,
            s.holster_depth_m,
            s.insertion_depth_m,
            s.position_tolerance_m,
            s.angle_tolerance_rad,
            s.seating_force_n,
            s.side_load_limit_n,
            s.bearing_stiffness_n_m,
            s.chamfer_length_m,
            s.face_stiffness_n_m,
            s.latch_stiffness_n_m,
            c.stiffness_n_m,
            c.stiffness_nm_rad,
        ];
        if positive.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return bad(
                "sizes, masses, inertia, torques, forces, stiffnesses and tolerances must be finite and > 0",
            );
        }
        let non_negative = [
            v.running_torque_nm,
            v.viscous_nm_s_rad,
            s.insertion_friction_n,
            s.friction_coefficient,
            s.bearing_damping_n_s_m,
            s.face_damping_n_s_m,
            c.damping_n_s_m,
            c.damping_nm_s_rad,
        ];
        if non_negative.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return bad("friction and damping must be finite and ≥ 0");
        }
        let points = [v.axis_point_m, s.holster_m, s.receptacle_m];
        let pose_ok = self.pose.translation.vector.iter().all(|x| x.is_finite())
            && self.pose.rotation.coords.iter().all(|x| x.is_finite());
        if !pose_ok || points.iter().any(|p| p.iter().any(|x| !x.is_finite())) {
            return bad("poses and points must be finite");
        }
        if v.running_torque_nm > v.breakaway_torque_nm {
            return bad("running torque must not exceed the breakaway torque");
        }
        if !(v.travel_rad > 0.0 && v.travel_rad < 2.0 * std::f64::consts::PI) {
            return bad("valve travel must be in (0, 2π)");
        }
        for w in [v.grip_width_m, s.handle_width_m] {
            if !(w > 0.0 && w <= jaw_max_m) {
                return bad("grip widths must be in (0, jaw opening]");
            }
        }
        if s.holster_depth_m >= s.length_m || s.insertion_depth_m >= s.length_m {
            return bad("the stab must be longer than the holster and insertion depths");
        }
        Ok(())
    }

    /// Unit normal of the face into the panel (world): the receptacle and holster axes.
    pub fn normal(&self) -> Vector3<f64> {
        self.pose.rotation * Vector3::x()
    }

    /// World point of a panel-frame point.
    fn world(&self, p: &Vector3<f64>) -> Vector3<f64> {
        (self.pose * Point3::from(*p)).coords
    }

    /// The valve's T-bar grip point (world, m): on the stem axis, `stem_length_m` in front of
    /// the face.
    pub fn valve_grip_m(&self) -> Vector3<f64> {
        self.world(&self.valve.axis_point_m) - self.normal() * self.valve.stem_length_m
    }

    /// The valve's rotation axis (world unit vector): out of the panel, towards the arms; a
    /// positive angle turns counter-clockwise seen from the arms.
    pub fn valve_axis(&self) -> Vector3<f64> {
        -self.normal()
    }

    /// Pose of the valve's T-bar frame (world) at `angle` (rad): origin at the grip point, the
    /// panel's axes rotated by `angle` about [`Self::valve_axis`]; its y axis is along the bar
    /// (vertical at 0).
    pub fn valve_frame(&self, angle: f64) -> Isometry3<f64> {
        let turn = UnitQuaternion::from_scaled_axis(self.valve_axis() * angle);
        Isometry3::from_parts(
            Translation3::from(self.valve_grip_m()),
            turn * self.pose.rotation,
        )
    }

    /// The receptacle mouth (world, m).
    pub fn receptacle_mouth_m(&self) -> Vector3<f64> {
        self.world(&self.stab.receptacle_m)
    }

    /// The holster mouth (world, m).
    pub fn holster_mouth_m(&self) -> Vector3<f64> {
        self.world(&self.stab.holster_m)
    }

    /// Pose of the stab frame (world) with its tip `depth_m` past the mouth `mouth` and its axis
    /// along the panel normal: origin at the handle grip point, x axis towards the tip.
    fn stab_in_port(&self, mouth: &Vector3<f64>, depth_m: f64) -> Isometry3<f64> {
        let n = self.normal();
        let grip = mouth + n * (depth_m - self.stab.length_m);
        Isometry3::from_parts(Translation3::from(grip), self.pose.rotation)
    }

    /// The stab frame when holstered.
    pub fn holstered_stab(&self) -> Isometry3<f64> {
        self.stab_in_port(&self.holster_mouth_m(), self.stab.holster_depth_m)
    }

    /// The stab frame when seated on the receptacle axis (a latched stab keeps the small
    /// lateral and angular offset it was latched with).
    pub fn seated_stab(&self) -> Isometry3<f64> {
        self.stab_in_port(&self.receptacle_mouth_m(), self.stab.insertion_depth_m)
    }

    /// The seabed height under the panel (world z, m): the bottom edge of the plate.
    pub fn seabed_z_m(&self) -> f64 {
        self.pose.translation.vector.z - 0.5 * self.size_m.z
    }
}

/// Where the hot stab is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StabPhase {
    /// In its holster on the panel (possibly gripped, not yet pulled).
    Holstered,
    /// Held by this arm's jaw, outside the receptacle.
    Held(Arm),
    /// In the receptacle, not latched (held or left there).
    Inserting,
    /// Latched at full depth (held or released).
    Seated,
    /// Released outside the holster and receptacle: lying on the seabed.
    Dropped,
}

impl StabPhase {
    /// Wire name: "holstered", "held", "inserting", "seated", "dropped".
    pub fn as_str(self) -> &'static str {
        match self {
            StabPhase::Holstered => "holstered",
            StabPhase::Held(_) => "held",
            StabPhase::Inserting => "inserting",
            StabPhase::Seated => "seated",
            StabPhase::Dropped => "dropped",
        }
    }
}

/// An item a jaw can take ([`crate::sim::Simulation::in_capture_range`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Graspable {
    /// A handle of the box (its index).
    BoxHandle(usize),
    /// The valve's T-bar.
    Valve,
    /// The hot stab's handle.
    Stab,
}

impl Graspable {
    /// Wire name: "handle-0", "handle-1", "handle-2" (the lifting point), "valve", "stab".
    pub fn as_str(self) -> &'static str {
        match self {
            Graspable::BoxHandle(0) => "handle-0",
            Graspable::BoxHandle(1) => "handle-1",
            Graspable::BoxHandle(_) => "handle-2",
            Graspable::Valve => "valve",
            Graspable::Stab => "stab",
        }
    }
}

/// State of the panel (plain data, `Copy`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PanelState {
    /// Valve angle (rad), 0 (closed) … travel.
    pub valve_angle_rad: f64,
    /// Valve rate (rad/s).
    pub valve_rate_rad_s: f64,
    /// Torque of the jaw on the valve about its axis at the last step (N·m).
    pub valve_torque_nm: f64,
    /// The arm holding the valve's T-bar.
    pub valve_holder: Option<Arm>,
    /// Where the stab is.
    pub stab_phase: StabPhase,
    /// The arm holding the stab (in any phase).
    pub stab_holder: Option<Arm>,
    /// Pose of the stab frame (world): origin at the handle grip point, x towards the tip.
    pub stab_pose: Isometry3<f64>,
    /// Insertion depth of the tip past the receptacle mouth (m); 0 outside the receptacle.
    pub stab_depth_m: f64,
    /// Force of the full-depth stop on the stab's tip (N): what latches it at the seating
    /// force.
    pub stop_force_n: f64,
    /// Force of the panel face on the stab's tip when it is blocked (N).
    pub face_force_n: f64,
    /// Current side (lateral bearing) load on the receptacle (N).
    pub side_load_n: f64,
    /// Peak side load since reset (N).
    pub peak_side_load_n: f64,
    /// Rising edges of the side load above the limit, since reset.
    pub side_load_faults: u64,
    /// Times the stab latched (seated), since reset.
    pub seatings: u64,
    /// Tool frame in the valve's T-bar frame, fixed while the valve is held.
    pub(crate) valve_grasp: Isometry3<f64>,
    /// Stab frame in the tool frame, fixed while the stab is held.
    pub(crate) stab_grasp: Isometry3<f64>,
    /// The stab's tip is still in the holster bore (grasped there, not yet pulled clear).
    pub(crate) in_holster_bore: bool,
    /// A side-load fault was counted and the load has not yet fallen back below the re-arm
    /// level.
    pub(crate) side_over: bool,
}

impl PanelState {
    /// The reset state: valve closed and at rest, stab holstered, counters cleared.
    pub fn initial(p: &PanelParams) -> PanelState {
        PanelState {
            valve_angle_rad: 0.0,
            valve_rate_rad_s: 0.0,
            valve_torque_nm: 0.0,
            valve_holder: None,
            stab_phase: StabPhase::Holstered,
            stab_holder: None,
            stab_pose: p.holstered_stab(),
            stab_depth_m: 0.0,
            stop_force_n: 0.0,
            face_force_n: 0.0,
            side_load_n: 0.0,
            peak_side_load_n: 0.0,
            side_load_faults: 0,
            seatings: 0,
            valve_grasp: Isometry3::identity(),
            stab_grasp: Isometry3::identity(),
            in_holster_bore: true,
            side_over: false,
        }
    }

    /// The stab's handle grip point (world, m).
    pub fn stab_handle_m(&self) -> Vector3<f64> {
        self.stab_pose.translation.vector
    }

    /// The stab's tip (world, m).
    pub fn stab_tip_m(&self, p: &PanelParams) -> Vector3<f64> {
        (self.stab_pose * Point3::new(p.stab.length_m, 0.0, 0.0)).coords
    }

    /// Whether any arm holds `item` (valve or stab) — and which.
    pub fn holder(&self, item: Graspable) -> Option<Arm> {
        match item {
            Graspable::Valve => self.valve_holder,
            Graspable::Stab => self.stab_holder,
            Graspable::BoxHandle(_) => None,
        }
    }

    /// The panel item arm `arm` holds, if any.
    pub fn held_by(&self, arm: Arm) -> Option<Graspable> {
        if self.valve_holder == Some(arm) {
            Some(Graspable::Valve)
        } else if self.stab_holder == Some(arm) {
            Some(Graspable::Stab)
        } else {
            None
        }
    }

    /// Every value finite (for the simulation's rollback safety net).
    pub(crate) fn is_finite(&self) -> bool {
        let t = self.stab_pose.translation.vector;
        [
            self.valve_angle_rad,
            self.valve_rate_rad_s,
            self.valve_torque_nm,
            self.stab_depth_m,
            self.side_load_n,
            t.x,
            t.y,
            t.z,
        ]
        .iter()
        .chain(self.stab_pose.rotation.coords.iter())
        .all(|x| x.is_finite())
    }
}

/// One step of the valve's 1-DOF dynamics, I·θ̈ = τ − τ_f − b·θ̇, with stick–slip friction and
/// rigid end stops; backward Euler in the coupling terms. The torque about the axis is
/// linearized in the step's end state: τ(θ⁺, θ̇⁺) = `tau_nm` − `k`·(θ⁺ − θ) − `c`·(θ̇⁺ − θ̇),
/// `k` ≥ 0 and `c` ≥ 0 the coupling's stiffness and damping about the axis (0 and 0 for a
/// plain applied torque). Stuck (θ̇ = 0): stays while |τ| ≤ breakaway, or while τ pushes
/// into an end stop it rests on. Moving (or breaking away): τ_f = running torque in the
/// direction of motion; if θ̇ would change sign the valve sticks (θ̇ = 0). `angle`, `rate`:
/// θ (rad), θ̇ (rad/s), updated in place; `h`: step (s).
pub fn valve_step(
    v: &ValveParams,
    angle: &mut f64,
    rate: &mut f64,
    tau_nm: f64,
    k: f64,
    c: f64,
    h: f64,
) {
    let at_low = *angle <= 0.0 && tau_nm <= 0.0;
    let at_high = *angle >= v.travel_rad && tau_nm >= 0.0;
    if *rate == 0.0 && (tau_nm.abs() <= v.breakaway_torque_nm || at_low || at_high) {
        return;
    }
    let dir = if *rate != 0.0 {
        rate.signum()
    } else {
        tau_nm.signum()
    };
    let num = v.inertia_kg_m2 * *rate + h * (tau_nm + c * *rate - v.running_torque_nm * dir);
    let den = v.inertia_kg_m2 + h * h * k + h * c + h * v.viscous_nm_s_rad;
    let mut next = num / den;
    if next * dir < 0.0 {
        next = 0.0;
    }
    *angle += h * next;
    *rate = next;
    if *angle <= 0.0 {
        *angle = 0.0;
        *rate = 0.0;
    } else if *angle >= v.travel_rad {
        *angle = v.travel_rad;
        *rate = 0.0;
    }
}
