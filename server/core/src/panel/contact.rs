//! The held item's load on the jaw: a wrench at the tool point with its stiffness and damping
//! (for the linearly implicit treatment in the arm's H̃) and the lumped mass of a held stab;
//! plus the side load and axial forces the stab's phase logic reads.

use nalgebra::{Isometry3, Matrix3, Matrix3x6, Matrix6, Point3, Vector3, Vector6};

use super::{Graspable, PanelParams, PanelState, StabPhase};
use crate::control::rotation_error;
use crate::sim::Arm;

/// Regularization speed of the stab's axial (seal) friction (m/s): 0.005, μN·v/√(v²+ε²) as the
/// seabed friction's regularization (`grasp::ObjectParams::friction_speed_m_s`).
const FRICTION_SPEED_M_S: f64 = 0.005;

/// A held item's load on the jaw for one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ToolLoad {
    /// Wrench on the tool (N, N·m; world; moment about the tool point), the item's weight
    /// included.
    pub(crate) wrench: Vector6<f64>,
    /// −∂wrench/∂(tool displacement, rotation) (N/m, N·m/rad; world), symmetric ≥ 0.
    pub(crate) stiffness: Matrix6<f64>,
    /// −∂wrench/∂(tool twist), symmetric ≥ 0.
    pub(crate) damping: Matrix6<f64>,
    /// Mass lumped at the tool point (kg): a held free stab's.
    pub(crate) mass_kg: f64,
    /// The larger lateral bearing force on the receptacle (N): the side load.
    pub(crate) side_load_n: f64,
    /// Spring force of the full-depth latch pushed by the stab (N, ≥ 0).
    pub(crate) stop_push_n: f64,
    /// Force of the panel face on a blocked stab's tip (N, ≥ 0).
    pub(crate) face_n: f64,
    /// Pull of the jaw on a seated stab out of the receptacle (N; negative: pushing in).
    pub(crate) pull_n: f64,
}

impl ToolLoad {
    fn zero(mass_kg: f64) -> ToolLoad {
        ToolLoad {
            wrench: Vector6::zeros(),
            stiffness: Matrix6::zeros(),
            damping: Matrix6::zeros(),
            mass_kg,
            side_load_n: 0.0,
            stop_push_n: 0.0,
            face_n: 0.0,
            pull_n: 0.0,
        }
    }

    /// Adds a force `f` at the point `r` from the tool point with point stiffness `k` and
    /// damping `c` (3×3): wrench [f; r×f], and Gᵀ·k·G, Gᵀ·c·G with G = [I, −[r]×] (the point's
    /// velocity v + ω×r from the tool twist).
    fn add_point(
        &mut self,
        r: &Vector3<f64>,
        f: &Vector3<f64>,
        k: &Matrix3<f64>,
        c: &Matrix3<f64>,
    ) {
        let m = r.cross(f);
        self.wrench += Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
        let mut g = Matrix3x6::zeros();
        g.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        g.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(-r.cross_matrix()));
        self.stiffness += g.transpose() * k * g;
        self.damping += g.transpose() * c * g;
    }
}

/// Velocity of the point `r` from the tool point, for the tool twist [v; ω].
fn point_velocity(twist: &Vector6<f64>, r: &Vector3<f64>) -> Vector3<f64> {
    let v = Vector3::new(twist[0], twist[1], twist[2]);
    let w = Vector3::new(twist[3], twist[4], twist[5]);
    v + w.cross(r)
}

/// The 6-D coupling spring–damper pulling the tool (pose `tool`, twist `twist`) to `desired`
/// moving with the twist `desired_twist` (both world, at the tool point), with translational
/// stiffness and damping matrices `kt`, `ct` (world) and the rotational ones of
/// [`super::CouplingParams`].
fn coupling(
    p: &PanelParams,
    tool: &Isometry3<f64>,
    twist: &Vector6<f64>,
    desired: &Isometry3<f64>,
    desired_twist: &Vector6<f64>,
    (kt, ct): (Matrix3<f64>, Matrix3<f64>),
) -> ToolLoad {
    let c = &p.coupling;
    let ep = tool.translation.vector - desired.translation.vector;
    let er = rotation_error(&tool.rotation, &desired.rotation);
    let ev = twist - desired_twist;
    let f = -(kt * ep) - ct * Vector3::new(ev[0], ev[1], ev[2]);
    let m = -er * c.stiffness_nm_rad - Vector3::new(ev[3], ev[4], ev[5]) * c.damping_nm_s_rad;
    let mut load = ToolLoad::zero(0.0);
    load.wrench = Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
    load.stiffness.fixed_view_mut::<3, 3>(0, 0).copy_from(&kt);
    load.damping.fixed_view_mut::<3, 3>(0, 0).copy_from(&ct);
    let rot = Matrix3::identity();
    load.stiffness
        .fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(rot * c.stiffness_nm_rad));
    load.damping
        .fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(rot * c.damping_nm_s_rad));
    load
}

/// The load on arm `arm`'s jaw from the panel item it holds (`None` if it holds none), at the
/// tool pose `tool` and twist `twist` (world, at the tool point). `gravity`: world (m/s²);
/// `water_density`: for the stab's buoyancy (0 in air).
pub(crate) fn tool_load(
    p: &PanelParams,
    s: &PanelState,
    arm: Arm,
    tool: &Isometry3<f64>,
    twist: &Vector6<f64>,
    gravity: &Vector3<f64>,
    water_density: f64,
) -> Option<ToolLoad> {
    match s.held_by(arm)? {
        Graspable::Valve => {
            let u = p.valve_axis();
            let frame = p.valve_frame(s.valve_angle_rad);
            let desired = frame * s.valve_grasp;
            let w = u * s.valve_rate_rad_s;
            let vd = w.cross(&(desired.translation.vector - frame.translation.vector));
            let dt = Vector6::new(vd.x, vd.y, vd.z, w.x, w.y, w.z);
            let c = &p.coupling;
            let i = Matrix3::identity();
            let kc = (i * c.stiffness_n_m, i * c.damping_n_s_m);
            Some(coupling(p, tool, twist, &desired, &dt, kc))
        }
        Graspable::BoxHandle(_) => None,
        Graspable::Stab => Some(match s.stab_phase {
            StabPhase::Seated => {
                let desired = s.stab_pose * s.stab_grasp.inverse();
                // Along the axis the latch and the grip's coupling; across it the bore's and
                // grip's bearing compliance, as while inserting.
                let n = p.normal();
                let (along, across) = (n * n.transpose(), Matrix3::identity() - n * n.transpose());
                let (c, sp) = (&p.coupling, &p.stab);
                let kc = (
                    along * c.stiffness_n_m + across * sp.bearing_stiffness_n_m,
                    along * c.damping_n_s_m + across * sp.bearing_damping_n_s_m,
                );
                let mut load = coupling(p, tool, twist, &desired, &Vector6::zeros(), kc);
                let f = Vector3::new(load.wrench[0], load.wrench[1], load.wrench[2]);
                // The receptacle takes what the jaw pushes: −f on the stab.
                load.side_load_n = (f - n * f.dot(&n)).norm();
                load.pull_n = f.dot(&n);
                load
            }
            _ => held_stab(p, s, tool, twist, gravity, water_density),
        }),
    }
}

/// A stab rigid in the jaw: its weight, and its contact with the receptacle (inside: bearing
/// springs at the tip and the mouth beyond the chamfer's play, seal friction, the latch at
/// full depth) or the panel face (outside, tip past the face plane and not in the holster
/// bore: a penalty spring on the tip).
fn held_stab(
    p: &PanelParams,
    s: &PanelState,
    tool: &Isometry3<f64>,
    twist: &Vector6<f64>,
    gravity: &Vector3<f64>,
    water_density: f64,
) -> ToolLoad {
    let sp = &p.stab;
    let radius = 0.5 * sp.diameter_m;
    let volume = std::f64::consts::PI * radius * radius * sp.length_m;
    let mut load = ToolLoad::zero(sp.mass_kg);
    let weight = gravity * (sp.mass_kg - water_density * volume);
    load.wrench += Vector6::new(weight.x, weight.y, weight.z, 0.0, 0.0, 0.0);
    let stab = tool * s.stab_grasp;
    let tip = (stab * Point3::new(sp.length_m, 0.0, 0.0)).coords;
    let axis = stab.rotation * Vector3::x();
    let n = p.normal();
    let lateral = Matrix3::identity() - n * n.transpose();
    let along = n * n.transpose();
    let p0 = tool.translation.vector;
    let mouth = p.receptacle_mouth_m();
    let depth = (tip - mouth).dot(&n);
    let r_tip = tip - p0;
    let v_tip = point_velocity(twist, &r_tip);
    let v_ax = v_tip.dot(&n);
    match s.stab_phase {
        StabPhase::Inserting => {
            // Bearings at the tip and at the stab's point in the mouth plane.
            let mouth_point = tip - axis * (depth / axis.dot(&n).max(0.5));
            let (kb, cb) = (sp.bearing_stiffness_n_m, sp.bearing_damping_n_s_m);
            let play = sp.position_tolerance_m * (1.0 - depth / sp.chamfer_length_m).max(0.0);
            let mut bearing = [0.0; 2];
            for (k, pt) in [tip, mouth_point].iter().enumerate() {
                let r = pt - p0;
                let e = lateral * (pt - mouth);
                let interference = (e.norm() - play).max(0.0);
                let spring = if interference > 0.0 {
                    e * (kb * interference / e.norm())
                } else {
                    Vector3::zeros()
                };
                let f = -spring - lateral * point_velocity(twist, &r) * cb;
                bearing[k] = f.norm();
                load.add_point(&r, &f, &(lateral * kb), &(lateral * cb));
            }
            load.side_load_n = bearing[0].max(bearing[1]);
            // Seal friction, regularized Coulomb; its slope at v = 0 treated implicitly.
            let fric =
                sp.insertion_friction_n + sp.friction_coefficient * (bearing[0] + bearing[1]);
            let eps = FRICTION_SPEED_M_S;
            let f = -n * (fric * v_ax / (v_ax * v_ax + eps * eps).sqrt());
            load.add_point(&r_tip, &f, &Matrix3::zeros(), &(along * (fric / eps)));
            let pen = depth - sp.insertion_depth_m;
            if pen > 0.0 {
                let push = sp.latch_stiffness_n_m * pen + sp.face_damping_n_s_m * v_ax;
                if push > 0.0 {
                    load.stop_push_n = sp.latch_stiffness_n_m * pen;
                    let (k, c) = (
                        along * sp.latch_stiffness_n_m,
                        along * sp.face_damping_n_s_m,
                    );
                    load.add_point(&r_tip, &(-n * push), &k, &c);
                }
            }
        }
        _ if !s.in_holster_bore && depth > 0.0 && on_plate(p, &tip) => {
            let push = sp.face_stiffness_n_m * depth + sp.face_damping_n_s_m * v_ax;
            load.face_n = push.max(0.0);
            if push > 0.0 {
                let (k, c) = (along * sp.face_stiffness_n_m, along * sp.face_damping_n_s_m);
                load.add_point(&r_tip, &(-n * push), &k, &c);
            }
        }
        _ => {}
    }
    load
}

/// The point `x` (world) lies within the plate's face rectangle (ignoring depth).
fn on_plate(p: &PanelParams, x: &Vector3<f64>) -> bool {
    let local = p.pose.inverse() * Point3::from(*x);
    local.y.abs() <= 0.5 * p.size_m.y && local.z.abs() <= 0.5 * p.size_m.z
}

/// Torque about the axis through `point` along the unit vector `axis` that the jaw exerts on
/// the item, from the wrench `load` on the tool (at `tool_point`): the reaction −F at the tool
/// point and −M, i.e. −axis·(M + (tool_point − point) × F).
pub(crate) fn item_torque_about(
    load: &ToolLoad,
    tool_point: &Vector3<f64>,
    point: &Vector3<f64>,
    axis: &Vector3<f64>,
) -> f64 {
    let f = Vector3::new(load.wrench[0], load.wrench[1], load.wrench[2]);
    let m = Vector3::new(load.wrench[3], load.wrench[4], load.wrench[5]);
    -axis.dot(&(m + (tool_point - point).cross(&f)))
}
