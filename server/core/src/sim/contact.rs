//! The contact stage: the arms' links and jaws against the seabed, the box, the panel, the
//! vehicle and each other (geometry and narrow phase in [`crate::collision`]).
//!
//! # Contact law
//! Each contact point is a compliant spring–damper along the normal with Coulomb friction
//! across it ([`ContactParams`]): F_n = k·δ − c·v_n (δ the penetration, v_n the separation
//! speed; never pulling), and a tangential force −c_t·v_t while that stays within μ·F_n
//! (sticking), else a damper −(μ·F_n/|v_t|)·v_t of magnitude μ·F_n against the sliding
//! (kinetic), both implicit.
//!
//! # Integration (stable at the 1 ms step)
//! The stiff terms are linearly implicit, like the joint end stops (`sim` module docs): with
//! J_p the 3×6 linear Jacobian of the arm's contact point, the arm's H̃ gains
//! h·C·J_pᵀnnᵀJ_p (C = c + h·k; and h·c_f·J_pᵀ(I − nnᵀ)J_p for the friction's damper c_f)
//! and its right-hand side J_pᵀ·n·(k·δ − C·v_n) (and −c_f·J_pᵀv_t): one term in the arm's implicit system,
//! unconditionally stable for any stiffness against a fixed partner (seabed, panel, vehicle).
//! A moving partner (the box, the other arm) is integrated in its own step, its velocity held
//! in the arm's: two bodies that each close the whole gap as if the other stood still would
//! together overshoot it (twice, for two light wrists: an oscillation that grows). So each
//! side takes its share: with w_a, w_b the two bodies' mobilities along n at the contact
//! (nᵀJ_pH̃⁻¹J_pᵀn for an arm, gᵀM̃⁻¹g for the box, g = [n; r × n]), the exact implicit
//! force of the pair is f = (k·δ − C·v_n)/(1 + h·C·(w_a + w_b)), and an arm that scales its
//! k·δ and C by 1/(1 + h·C·w_b) and then solves alone reproduces it; the box's rows
//! ([`box_acceleration`]) add the arm's h·w_a to their compliance, the same thing. Together
//! the two corrections of the gap sum to h·C·(w_a + w_b)/(1 + h·C·(w_a + w_b)) < 1: stable.
//! Geometry (points, normals, depths, Jacobians, mobilities) is evaluated once per 1 ms
//! step, like every configuration-dependent term.
//!
//! # Exclusions (grasps are not collisions)
//! A jaw holding the box skips the box and its handles; a jaw (wrist plate and fingers) whose
//! tool point is within the capture radius of a handle's bar, widened by the fingers' reach
//! past the tool point (they close on the bar from there), skips that handle (its bar and a
//! T-handle's post), aligned with the bar or not; a jaw holding the valve or the stab, or within that radius of its grip, skips it; an
//! arm's first two links skip its own pedestal.
//! Links of the same arm do not collide with each other.

use nalgebra::{
    Isometry3, Matrix3, Matrix3x6, Matrix6, Point3, SMatrix, SVector, Vector3, Vector6,
};

use super::arm::ArmTerms;
use super::object::ObjectTerms;
use super::{Arm, Event, Simulation};
use crate::collision::{
    ArmPart, ArmShapes, CollisionSpec, Epa, Exclusions, Item, Partner, Posed, Touch, World,
    WorldGeometry, arm_touches, world_touches,
};
use crate::grasp::Posts;
use crate::linalg::Ldlt;

/// The contact law and the world's extra geometry (each default in its doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Contacts act (true) or the arms pass through everything (false, the thesis's
    /// simulator without collision response).
    pub enabled: bool,
    /// Normal stiffness (N/m): 5·10⁶. Chosen so the hardest push the arm can make stays well
    /// inside the 1 cm acceptance: the shoulder at its 5 kN·m stall (`StepParams`) on a link
    /// 0.3 m from the axis is 17 kN, 3.3 mm of penetration; at the jaw (Table 1-1's 295 kg
    /// lift, 2.9 kN) 0.6 mm. Far softer than steel on steel (10⁸–10⁹ N/m) — a penalty
    /// contact's compromise — and stable at any value because it is treated implicitly.
    pub stiffness_n_m: f64,
    /// Normal damping (N·s/m): 2·10⁴, as the box's seabed corners (`ObjectParams`): damping
    /// ratio ≈ 0.6 for 50 kg on 5·10⁶ N/m, so a strike at 0.2 m/s rebounds at a fraction of
    /// its speed, as metal on metal under water does.
    pub damping_n_s_m: f64,
    /// Coulomb friction coefficient, arm on steel (box, panel, vehicle, other arm): 0.3
    /// (assumed: steel on steel, wet; Engineering ToolBox lists 0.5–0.8 clean and dry,
    /// 0.16 greasy).
    pub friction: f64,
    /// Coulomb friction coefficient, arm on the seabed: 0.5, the box's (`ObjectParams`).
    pub seabed_friction: f64,
    /// Tangential damping while sticking (N·s/m): 2·10⁴, the regularization of static
    /// friction (creep below μ·F_n/c_t: 7.5 mm/s at 500 N on steel).
    pub stick_damping_n_s_m: f64,
    /// Impact speed from which a new contact counts as a strike (m/s): 0.02 (a tenth of the
    /// jaw's nominal speed; slower touches are placements, not strikes).
    pub strike_speed_m_s: f64,
    /// The world's extra shapes (handles, valve, vehicle, pedestals).
    pub geometry: WorldGeometry,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            enabled: true,
            stiffness_n_m: 5.0e6,
            damping_n_s_m: 2.0e4,
            friction: 0.3,
            seabed_friction: 0.5,
            stick_damping_n_s_m: 2.0e4,
            strike_speed_m_s: 0.02,
            geometry: WorldGeometry::standard(),
        }
    }
}

/// A strike's peak force is taken over at most this long after its first contact (s): the
/// impact transient of the 5·10⁶ N/m contact on the arm's effective mass (tens of kg) lasts a
/// few milliseconds; after 0.2 s the contact is a press, not a strike.
pub const STRIKE_WINDOW_S: f64 = 0.2;

/// Contact points per arm held over a step (the deepest are kept).
const MAX_POINTS: usize = 8;
/// Arm–box contact points the box's implicit solve takes (the deepest are kept).
const MAX_BOX_POINTS: usize = 4;
/// Rows of the box's implicit solve: normal and two tangents per point.
const BOX_ROWS: usize = 3 * MAX_BOX_POINTS;

/// One contact point of an arm, held over the step.
#[derive(Debug, Clone, Copy)]
struct Point {
    touch: Touch,
    /// Linear Jacobian of the arm's contact point (world).
    jv: Matrix3x6<f64>,
    /// Velocity of the partner's contact point at the start of the step (held).
    v_partner: Vector3<f64>,
    /// Velocity of the arm's contact point at the start of the step.
    v_arm: Vector3<f64>,
    /// Friction coefficient.
    mu: f64,
    /// The normal force acts this step (not separating at the start).
    pressing: bool,
    /// Normal force at the start of the step (N), the sliding friction's magnitude.
    fn0: f64,
    /// Friction branch: sticking (c_t·|v_t| within μ·F_n) or sliding.
    stick: bool,
    /// The friction's implicit damping coefficient for this arm (N·s/m): its share of c_t
    /// while sticking, μ·F_n/|v_t| while sliding (so the force is at most μ·F_n and, being
    /// implicit, never reverses the sliding; an explicit μ·F_n on the light wrist rotate
    /// overshot and grew).
    c_fric: f64,
    /// Share of the normal law this arm takes, 1/(1 + h·(c + h·k)·w) with w the partner's
    /// mobility at the contact (0 for the seabed, panel and vehicle; see the module docs).
    share_n: f64,
    /// The same for the sticking friction, 1/(1 + h·c_t·w).
    share_t: f64,
}

/// One arm's contact points of this step.
#[derive(Debug, Clone, Copy)]
struct ArmPoints {
    points: [Option<Point>; MAX_POINTS],
}

impl ArmPoints {
    fn iter(&self) -> impl Iterator<Item = &Point> {
        self.points.iter().flatten()
    }

    /// Adds `p`, replacing the shallowest point when full and `p` is deeper.
    fn push(&mut self, p: Point) {
        if let Some(slot) = self.points.iter_mut().find(|s| s.is_none()) {
            *slot = Some(p);
            return;
        }
        let (k, d) = self
            .points
            .iter()
            .enumerate()
            .map(|(k, s)| (k, s.map_or(0.0, |q| q.touch.depth_m)))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        if p.touch.depth_m > d {
            self.points[k] = Some(p);
        }
    }
}

/// The arm's implicit contact terms: H̃ += `matrix`, right-hand side += `torque`.
#[derive(Debug, Clone, Copy)]
pub(super) struct ArmLoad {
    pub(super) matrix: Matrix6<f64>,
    pub(super) torque: Vector6<f64>,
}

/// One row of the box's implicit solve: a force on the box along a direction d at a lever
/// r from its COM, f = e − C·s⁺ with s the box point's velocity along d relative to the
/// arm's point, the arm's own response included through its mobility w_arm along d.
#[derive(Debug, Clone, Copy)]
struct BoxRow {
    /// Unit wrench [d; r × d].
    w: Vector6<f64>,
    /// M̃⁻¹·w.
    mw: Vector6<f64>,
    /// The arm point's velocity along d (held).
    v_arm: f64,
    /// e/C (m/s): k·δ/(c + h·k) on a normal row, 0 on a tangent.
    e_over_c: f64,
    /// 1/C + h·w_arm (s/kg).
    compliance: f64,
}

/// Everything the contacts need over the step's sub-steps and for the report.
#[derive(Debug, Clone, Copy)]
pub(super) struct ContactTerms {
    arms: [ArmPoints; 2],
    /// The box's rows.
    box_rows: [Option<BoxRow>; BOX_ROWS],
    /// Anything set since the last clear.
    dirty: bool,
}

impl ContactTerms {
    /// No contacts.
    fn none() -> ContactTerms {
        ContactTerms {
            arms: [ArmPoints {
                points: [None; MAX_POINTS],
            }; 2],
            box_rows: [None; BOX_ROWS],
            dirty: false,
        }
    }

    fn clear(&mut self) {
        if self.dirty {
            *self = ContactTerms::none();
        }
    }
}

/// The contact stage's workspace, kept in the simulation (boxed, so the step moves a
/// pointer, not the ~10 kB of points): the narrow phase's kept EPA, the touches found and
/// the terms formed from them.
#[derive(Debug, Clone)]
pub(super) struct ContactWork {
    epa: Epa,
    /// Each arm's shapes (meaningful for an arm with a collision spec).
    shapes: [ArmShapes; 2],
    /// The world's obstacles.
    world: World,
    touches: [[Option<Touch>; MAX_POINTS]; 2],
    /// The terms of the current step.
    pub(super) terms: ContactTerms,
}

impl ContactWork {
    /// A workspace with a warm EPA and nothing found.
    pub(super) fn new() -> ContactWork {
        ContactWork {
            epa: Epa::warm(),
            shapes: [ArmShapes::empty(); 2],
            world: World::new(0.0),
            touches: [[None; MAX_POINTS]; 2],
            terms: ContactTerms::none(),
        }
    }
}

/// One arm's strongest contact of the last step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmContact {
    /// What it touches.
    pub partner: Partner,
    /// Which part of the arm.
    pub part: ArmPart,
    /// Contact point on the arm (world, m).
    pub point_m: [f64; 3],
    /// Normal force (N).
    pub normal_force_n: f64,
    /// Friction force (N).
    pub friction_force_n: f64,
    /// Penetration (m).
    pub depth_m: f64,
    /// Approach speed at the start of the step (m/s, ≥ 0).
    pub approach_speed_m_s: f64,
}

/// A strike: a contact with a partner that began at an approach speed of at least
/// [`ContactParams::strike_speed_m_s`]. It is pushed to the step's events
/// ([`super::Event::Strike`]) once its peak force is known: when the contact ends, or
/// [`STRIKE_WINDOW_S`] after it began (the impact's peak; a contact that lasts is a press).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strike {
    /// What was struck.
    pub partner: Partner,
    /// The arm's part that struck first.
    pub part: ArmPart,
    /// Where (world, m).
    pub point_m: [f64; 3],
    /// Approach speed at first contact (m/s).
    pub impact_speed_m_s: f64,
    /// Largest total normal force on the arm from this partner while the contact lasts (N).
    pub peak_force_n: f64,
    /// Simulated time of the first contact (s).
    pub time_s: f64,
    /// The contact still lasts (the peak may still grow).
    pub ongoing: bool,
}

/// One arm's contact report.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmContacts {
    /// The strongest contact (largest normal force) of the last step.
    pub strongest: Option<ArmContact>,
    /// Contact points in the last step.
    pub points: usize,
    /// Deepest penetration in the last step (m).
    pub max_depth_m: f64,
    /// Sum of the normal forces in the last step (N).
    pub total_normal_force_n: f64,
    /// Strikes since reset, per partner ([`Partner::index`]).
    pub strikes: [u64; 5],
    /// The latest strike (`ongoing` until it is pushed to the events).
    pub last_strike: Option<Strike>,
    /// Partners touched in the last step (indexed by [`Partner::index`]).
    touching: [bool; 5],
}

/// The contacts of both arms, per step ([`Simulation::contacts`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Contacts {
    /// Left (0) and right (1) arm.
    pub arms: [ArmContacts; 2],
    /// Total force of the arms on the box (N, world) in the last step.
    pub box_force_n: [f64; 3],
}

/// Linear Jacobian (world) of a point `p` moved by joints `0..=last` of an arm whose joint
/// frames (after motion; z the axis) are `frames`.
fn point_jacobian(
    frames: &[nalgebra::IsometryMatrix3<f64>],
    last: usize,
    p: &Vector3<f64>,
) -> Matrix3x6<f64> {
    let mut j = Matrix3x6::zeros();
    for (k, f) in frames.iter().enumerate().take(last + 1) {
        let z = f.rotation.matrix().column(2).into_owned();
        j.set_column(k, &z.cross(&(p - f.translation.vector)));
    }
    j
}

/// An arm's mobility along `d` at a point with linear Jacobian `jv`: dᵀJ_p·H̃⁻¹·J_pᵀd (1/kg;
/// 0 if its H̃ did not factor: then it does not move).
fn arm_mobility(t: &ArmTerms, jv: &Matrix3x6<f64>, d: &Vector3<f64>) -> f64 {
    let b = jv.transpose() * d;
    t.factor.as_ref().map_or(0.0, |f| b.dot(&f.solve(&b)))
}

/// The unit wrench [d; r × d] of a force along `d` at lever `r`.
fn unit_wrench(d: &Vector3<f64>, r: &Vector3<f64>) -> Vector6<f64> {
    let m = r.cross(d);
    Vector6::new(d.x, d.y, d.z, m.x, m.y, m.z)
}

fn part_link(part: ArmPart) -> usize {
    match part {
        ArmPart::Link(i) => i,
        ArmPart::Wrist | ArmPart::Finger(_) => 5,
    }
}

/// Two unit vectors completing `n` to an orthonormal basis.
fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = n.cross(&a).normalize();
    (t1, n.cross(&t1))
}

impl Simulation {
    /// The world's obstacles at the current state.
    fn collision_world(&self) -> World {
        let g = &self.params.contact.geometry;
        let op = &self.params.object;
        let mut w = World::new(op.seabed_z_m);
        let o = &self.state.object.pose;
        w.push(Item::BoxBody, Posed::cuboid(&(op.size_m * 0.5), o));
        for (k, h) in op.handles.iter().enumerate() {
            let c = (o * Point3::from(h.centre_m)).coords;
            let ax = o.rotation * h.axis * (0.5 * h.length_m);
            w.push(
                Item::Handle(k),
                Posed::capsule(&(c - ax), &(c + ax), g.handle_radius_m),
            );
            if h.posts == Posts::Centre {
                let foot = o * Point3::new(h.centre_m.x, h.centre_m.y, 0.5 * op.size_m.z);
                w.push(
                    Item::Handle(k),
                    Posed::capsule(&foot.coords, &c, g.post_radius_m),
                );
            }
        }
        if let (Some(p), Some(ps)) = (&self.params.panel, &self.state.panel) {
            let plate = p.pose * Isometry3::translation(0.5 * p.size_m.x, 0.0, 0.0);
            w.push(Item::Plate, Posed::cuboid(&(p.size_m * 0.5), &plate));
            let grip = p.valve_grip_m();
            let face = grip + p.normal() * p.valve.stem_length_m;
            w.push(
                Item::Valve,
                Posed::capsule(&grip, &face, g.valve_stem_radius_m),
            );
            let bar = p.valve_frame(ps.valve_angle_rad).rotation
                * Vector3::y()
                * (0.5 * p.valve.bar_length_m);
            w.push(
                Item::Valve,
                Posed::capsule(&(grip - bar), &(grip + bar), g.valve_bar_radius_m),
            );
            w.push(
                Item::Stab,
                Posed::capsule(
                    &ps.stab_handle_m(),
                    &ps.stab_tip_m(p),
                    0.5 * p.stab.diameter_m,
                ),
            );
        }
        let vehicle = Isometry3::translation(
            g.vehicle_centre_m.x,
            g.vehicle_centre_m.y,
            g.vehicle_centre_m.z,
        );
        w.push(
            Item::Vehicle,
            Posed::cuboid(&g.vehicle_half_extents_m, &vehicle),
        );
        for (k, a) in self.params.arms.iter().enumerate() {
            let b = a.base.translation.vector;
            let (top, bottom) = (g.pedestal_span_m[0], g.pedestal_span_m[1]);
            w.push(
                Item::Pedestal(k),
                Posed::capsule(
                    &(b - Vector3::z() * top),
                    &(b - Vector3::z() * bottom),
                    g.pedestal_radius_m,
                ),
            );
        }
        w
    }

    /// Arm `i`'s collision shapes (of `spec`) at the current state.
    fn arm_shapes(&self, i: usize, spec: &CollisionSpec) -> ArmShapes {
        let w = &self.work[i];
        let origins = core::array::from_fn(|k| w.kin.joint_frames[k].translation.vector);
        ArmShapes::new(spec, &origins, &w.tool, self.state.arms[i].jaw_opening_m)
    }

    /// What arm `i`'s jaw skips (see the module docs).
    fn exclusions(&self, i: usize) -> Exclusions {
        let a = &self.state.arms[i];
        let tool = self.work[i].tool.translation.vector;
        let op = &self.params.object;
        let o = &self.state.object.pose;
        let near = |p: &Vector3<f64>, r: f64| (tool - p).norm() <= r;
        // The jaw closes on a bar from as far as its fingers reach past the capture sphere.
        let reach = self.models[i]
            .spec
            .collision
            .as_ref()
            .map_or(0.0, |c| c.finger_half_extents_m[2]);
        let tool_o = o.inverse_transform_point(&Point3::from(tool)).coords;
        let jaw_handle = core::array::from_fn(|k| {
            op.handles[k].distance_m(&tool_o) <= op.capture_radius_m + reach
        });
        let (mut jaw_valve, mut jaw_stab) = (false, false);
        if let (Some(p), Some(ps)) = (&self.params.panel, &self.state.panel) {
            let arm = super::Arm::BOTH[i];
            let r = p.capture_radius_m + reach;
            jaw_valve = ps.valve_holder == Some(arm) || near(&p.valve_grip_m(), r);
            jaw_stab = ps.stab_holder == Some(arm) || near(&ps.stab_handle_m(), r);
        }
        Exclusions {
            arm: i,
            jaw_box: a.holding,
            jaw_handle,
            jaw_valve,
            jaw_stab,
        }
    }

    /// The contact stage at the start of a step (kinematics current): finds every contact and
    /// forms each arm's implicit terms and the box's rows, for sub-steps of length `h`.
    /// Returns each arm's implicit terms (`None`: no contact); the rest goes into `work`.
    pub(super) fn contact_terms(
        &self,
        h: f64,
        object: &ObjectTerms,
        arms: &[ArmTerms; 2],
        work: &mut ContactWork,
    ) -> [Option<ArmLoad>; 2] {
        let mut load = [None; 2];
        work.terms.clear();
        let cp = &self.params.contact;
        if !cp.enabled {
            return load;
        }
        let specs = [
            self.models[0].spec.collision.as_ref(),
            self.models[1].spec.collision.as_ref(),
        ];
        let ContactWork {
            epa,
            touches,
            terms: out,
            shapes,
            world,
        } = work;
        // Written in place (each arm's shapes and the world are ~2 kB).
        for (i, (sh, sp)) in shapes.iter_mut().zip(specs).enumerate() {
            if let Some(sp) = sp {
                *sh = self.arm_shapes(i, sp);
            }
        }
        *world = self.collision_world();
        if touches.iter().flatten().any(Option::is_some) {
            *touches = [[None; MAX_POINTS]; 2];
        }
        let keep = |list: &mut [Option<Touch>; MAX_POINTS], t: Touch| {
            if let Some(s) = list.iter_mut().find(|s| s.is_none()) {
                *s = Some(t);
            } else if let Some(s) = list
                .iter_mut()
                .min_by(|a, b| {
                    let da = a.map_or(0.0, |t| t.depth_m);
                    let db = b.map_or(0.0, |t| t.depth_m);
                    da.total_cmp(&db)
                })
                .filter(|s| s.is_some_and(|q| q.depth_m < t.depth_m))
            {
                *s = Some(t);
            }
        };
        for i in 0..2 {
            if specs[i].is_some() {
                let ex = self.exclusions(i);
                world_touches(&shapes[i], world, &ex, epa, |t| keep(&mut touches[i], t));
            }
        }
        if let ([a, b], true) = (&*shapes, specs.iter().all(Option::is_some)) {
            let [t0, t1] = touches;
            arm_touches(a, b, epa, |ta, tb| {
                keep(t0, ta);
                keep(t1, tb);
            });
        }
        if touches.iter().all(|l| l.iter().all(Option::is_none)) {
            return load;
        }
        out.dirty = true;
        let o = &self.state.object;
        let com = o.pose.translation.vector;
        let box_velocity = |p: &Vector3<f64>| o.velocity + o.angular_velocity.cross(&(p - com));
        let (k, c, ct) = (cp.stiffness_n_m, cp.damping_n_s_m, cp.stick_damping_n_s_m);
        let mut box_points: [Option<(usize, Point)>; MAX_BOX_POINTS] = [None; MAX_BOX_POINTS];
        for i in 0..2 {
            let frames = &self.work[i].kin.joint_frames;
            let qd = Vector6::from(self.state.arms[i].qd);
            let other = 1 - i;
            let mut matrix = Matrix6::zeros();
            let mut torque = Vector6::zeros();
            for t in touches[i].iter().flatten() {
                let jv = point_jacobian(frames, part_link(t.part), &t.point_arm);
                let v_arm = jv * qd;
                let n = t.normal;
                // The partner's point velocity (held over the step) and its mobility along n.
                let (v_partner, w_partner) = match t.partner {
                    Partner::Object => {
                        let g = unit_wrench(&-n, &(t.point_other - com));
                        (
                            box_velocity(&t.point_other),
                            g.dot(&object.mobility_times(&g)),
                        )
                    }
                    Partner::OtherArm => {
                        let f = &self.work[other].kin.joint_frames;
                        let link = t.other_part.map_or(5, part_link);
                        let jo = point_jacobian(f, link, &t.point_other);
                        let v = jo * Vector6::from(self.state.arms[other].qd);
                        (v, arm_mobility(&arms[other], &jo, &n))
                    }
                    _ => (Vector3::zeros(), 0.0),
                };
                let vrel = v_arm - v_partner;
                let vn = n.dot(&vrel);
                let cn = c + h * k;
                let share_n = 1.0 / (1.0 + h * cn * w_partner);
                let share_t = 1.0 / (1.0 + h * ct * w_partner);
                let fn0 = share_n * (k * t.depth_m - c * vn);
                let mu = if t.partner == Partner::Seabed {
                    cp.seabed_friction
                } else {
                    cp.friction
                };
                let mut p = Point {
                    touch: *t,
                    jv,
                    v_partner,
                    v_arm,
                    mu,
                    pressing: fn0 > 0.0,
                    fn0: fn0.max(0.0),
                    stick: true,
                    c_fric: 0.0,
                    share_n,
                    share_t,
                };
                if p.pressing {
                    let jn = jv.transpose() * n;
                    matrix += jn * jn.transpose() * (h * cn * share_n);
                    torque += jn * (share_n * (k * t.depth_m - cn * vn));
                    // Coulomb friction as an implicit damper capped at μ·F_n.
                    let vt = vrel - n * vn;
                    let ctt = ct * share_t;
                    p.stick = ctt * vt.norm() <= mu * p.fn0;
                    p.c_fric = if p.stick { ctt } else { mu * p.fn0 / vt.norm() };
                    let pt = Matrix3::identity() - n * n.transpose();
                    matrix += jv.transpose() * pt * jv * (h * p.c_fric);
                    torque -= jv.transpose() * vt * p.c_fric;
                }
                if t.partner == Partner::Object && p.pressing {
                    push_deepest(&mut box_points, (i, p));
                }
                out.arms[i].push(p);
            }
            if out.arms[i].iter().next().is_some() {
                load[i] = Some(ArmLoad { matrix, torque });
            }
        }
        // The box's rows: normal and (sticking) tangents, forces on the box = − the arm's.
        let mut r = 0;
        for (i, p) in box_points.iter().flatten() {
            let t = &p.touch;
            let lever = t.point_other - com;
            let n = -t.normal;
            let mut row = |d: Vector3<f64>, e: f64, cc: f64| {
                let w = unit_wrench(&d, &lever);
                out.box_rows[r] = Some(BoxRow {
                    w,
                    mw: object.mobility_times(&w),
                    v_arm: d.dot(&p.v_arm),
                    e_over_c: e / cc,
                    compliance: 1.0 / cc + h * arm_mobility(&arms[*i], &p.jv, &d),
                });
                r += 1;
            };
            row(n, k * t.depth_m, c + h * k);
            // The friction's damper, undoing the arm's share (the rows add the arm's own
            // mobility instead).
            let cf = p.c_fric / p.share_t;
            if cf > 0.0 {
                let (t1, t2) = tangents(&n);
                row(t1, 0.0, cf);
                row(t2, 0.0, cf);
            }
        }
        load
    }

    /// After the sub-steps: each arm's contact forces at the new velocities, the report and
    /// the strike records.
    pub(super) fn contact_report(&mut self, terms: &ContactTerms, h: f64) {
        let cp = self.params.contact;
        let time = self.state.time_s;
        let mut box_force = Vector3::zeros();
        for i in 0..2 {
            let qd = Vector6::from(self.state.arms[i].qd);
            let rep = &mut self.contacts.arms[i];
            let mut strongest: Option<ArmContact> = None;
            let (mut n_points, mut max_depth, mut total) = (0, 0.0_f64, 0.0);
            let mut per_partner = [0.0_f64; 5];
            let mut onset: [Option<(f64, &Point)>; 5] = [None; 5];
            for p in terms.arms[i].iter() {
                let t = &p.touch;
                let n = t.normal;
                let vrel = p.jv * qd - p.v_partner;
                let vn = n.dot(&vrel);
                let (fnorm, ffric) = if p.pressing {
                    let f = (p.share_n
                        * (cp.stiffness_n_m * t.depth_m
                            - (cp.damping_n_s_m + h * cp.stiffness_n_m) * vn))
                        .max(0.0);
                    let ff = (p.c_fric * (vrel - n * vn).norm()).min(p.mu * f);
                    (f, ff)
                } else {
                    (0.0, 0.0)
                };
                n_points += 1;
                max_depth = max_depth.max(t.depth_m);
                total += fnorm;
                let k = t.partner.index();
                per_partner[k] += fnorm;
                let approach = (-n.dot(&(p.v_arm - p.v_partner))).max(0.0);
                if onset[k].is_none_or(|(s, _)| approach > s) {
                    onset[k] = Some((approach, p));
                }
                if t.partner == Partner::Object {
                    box_force -= n * fnorm;
                }
                if strongest.is_none_or(|s| fnorm > s.normal_force_n) {
                    strongest = Some(ArmContact {
                        partner: t.partner,
                        part: t.part,
                        point_m: t.point_arm.into(),
                        normal_force_n: fnorm,
                        friction_force_n: ffric,
                        depth_m: t.depth_m,
                        approach_speed_m_s: approach,
                    });
                }
            }
            let mut touching = [false; 5];
            for k in 0..5 {
                touching[k] = onset[k].is_some();
                if let Some((speed, p)) = onset[k]
                    && !rep.touching[k]
                    && speed >= cp.strike_speed_m_s
                {
                    // A new strike; one still open on another partner is reported first.
                    if let Some(s) = rep.last_strike.as_mut().filter(|s| s.ongoing) {
                        s.ongoing = false;
                        self.events.push(Event::Strike {
                            arm: Arm::BOTH[i],
                            strike: *s,
                        });
                    }
                    rep.strikes[k] += 1;
                    rep.last_strike = Some(Strike {
                        partner: p.touch.partner,
                        part: p.touch.part,
                        point_m: p.touch.point_arm.into(),
                        impact_speed_m_s: speed,
                        peak_force_n: per_partner[k],
                        time_s: time,
                        ongoing: true,
                    });
                } else if let Some(s) = &mut rep.last_strike
                    && s.ongoing
                    && s.partner.index() == k
                {
                    s.peak_force_n = s.peak_force_n.max(per_partner[k]);
                    // (1 ns of slack: the step's time is a running sum, so 200 steps of 1 ms
                    // after t ≈ 1.2 s measure 0.19999999999998 s and the window closed a step
                    // late.)
                    if !touching[k] || time - s.time_s >= STRIKE_WINDOW_S - 1.0e-9 {
                        s.ongoing = false;
                        self.events.push(Event::Strike {
                            arm: Arm::BOTH[i],
                            strike: *s,
                        });
                    }
                }
            }
            rep.touching = touching;
            rep.strongest = strongest;
            rep.points = n_points;
            rep.max_depth_m = max_depth;
            rep.total_normal_force_n = total;
        }
        self.contacts.box_force_n = box_force.into();
    }
}

fn push_deepest(list: &mut [Option<(usize, Point)>; MAX_BOX_POINTS], p: (usize, Point)) {
    if let Some(s) = list.iter_mut().find(|s| s.is_none()) {
        *s = Some(p);
        return;
    }
    if let Some(s) = list
        .iter_mut()
        .min_by(|a, b| {
            let da = a.map_or(0.0, |q| q.1.touch.depth_m);
            let db = b.map_or(0.0, |q| q.1.touch.depth_m);
            da.total_cmp(&db)
        })
        .filter(|s| s.is_some_and(|q| q.1.touch.depth_m < p.1.touch.depth_m))
    {
        *s = Some(p);
    }
}

/// Sub-step: the box's acceleration `acc` (its free acceleration on entry) with the arms'
/// contact forces, linearly implicit in the box's velocity (`twist`, at the sub-step's
/// start): with rows f_r = e_r − C_r·s_r⁺ and s⁺ = s + h·Wᵀ·acc (+ the arm's own response
/// h·w_arm·f along the row), (C⁻¹ + h·w_arm + h·WᵀM̃⁻¹W)·f = C⁻¹e − s − h·Wᵀ·acc_free (SPD),
/// then acc += M̃⁻¹W·f.
pub(super) fn box_acceleration(
    terms: &ContactTerms,
    twist: &Vector6<f64>,
    acc: &mut Vector6<f64>,
    h: f64,
) {
    if terms.box_rows[0].is_none() {
        return;
    }
    let mut a = SMatrix::<f64, BOX_ROWS, BOX_ROWS>::identity();
    let mut b = SVector::<f64, BOX_ROWS>::zeros();
    for (r, row) in terms.box_rows.iter().enumerate() {
        let Some(x) = row else { continue };
        for (q, col) in terms.box_rows.iter().enumerate().take(r + 1) {
            let Some(y) = col else { continue };
            a[(r, q)] = h * x.w.dot(&y.mw);
        }
        a[(r, r)] += x.compliance;
        let s = x.w.dot(twist) - x.v_arm;
        b[r] = x.e_over_c - s - h * x.w.dot(acc);
    }
    let Some(f) = Ldlt::factor(&a) else { return };
    let f = f.solve(&b);
    for (r, row) in terms.box_rows.iter().enumerate() {
        if let Some(x) = row {
            *acc += x.mw * f[r];
        }
    }
}
