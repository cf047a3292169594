//! The closed kinematic chain while jaws hold the object: the grasp constraint system of one
//! step ([`Constraint::new`]) and, per sub-step, the contact wrenches that keep each holding
//! tool on its grasp point ([`Constraint::apply`]): an exact acceleration-level solve with
//! Baumgarte position/velocity stabilization (critically damped, k_p = ω², k_d = 2ω).
//!
//! # Finite grip
//! Lim's assumption (i) (§3.5.2.1: "the object is held rigidly by the grippers … slipping
//! … is not considered") is kept while each jaw's share of the solve lies within its limits
//! ([`crate::grasp::GripCapacity`], written in the bar frame of the handle it holds,
//! [`crate::grasp::Handle::bar_frame`]); a jaw whose required wrench leaves them slips: it
//! transmits only the kinetic wrench in its limited directions (the geometry-carried force
//! along the closing axis stays as solved), so the object and the jaw accelerate apart there.
//! After the sub-steps, [`slip_stage`] moves the slipping jaw's grasp frame with the bar in
//! those directions (so the Baumgarte terms do not pull the bar back) and lets go when the
//! bar has slid [`crate::grasp::GripParams::slip_travel_m`] out of the pads. The closing-axis direction of a slipping jaw is
//! solved together with the full rigid system and corrected by the Baumgarte terms in the
//! next step. About the closing axis the finite grip's pads are compliant: that row is a
//! spring-damper ([`PadTorsion`]), and a slipping jaw's grasp frame keeps the pads' elastic
//! twist. [`SimParams::rigid_grasp`] restores the rigid grasp, all six rows rigid (the load
//! fraction is still reported).

use nalgebra::{
    Isometry3, Matrix6, Point3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6,
};

use super::arm::ArmTerms;
use super::object::ObjectTerms;
use super::{Arm, ArmState, Event, ObjectState, SimParams, StepParams};
use crate::control::rotation_error;
use crate::grasp::{self, GripCapacity};
use crate::hydraulics::N_ACT;
use crate::linalg::{BlockLdlt, Ldlt, gram_lower};

/// Factor of the constraint matrix: one 6×6 block per arm holding the object. Lives on the
/// stack for one step, so the variants' different sizes cost nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
enum Factor {
    /// Only this arm holds.
    One(usize, Ldlt<6>),
    /// Both arms hold: the 12×12 system in 6×6 blocks.
    Both(BlockLdlt<6>),
}

/// The grasp constraint system of one step, held over its sub-steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct Constraint {
    /// Factor of Σ blocks Wⁱᵀ·M̃⁻¹·Wᵏ + Z_iᵀZ_i + εI; `None` when no arm holds (or the
    /// system is not positive definite).
    factor: Option<Factor>,
    /// Arm i holds the object and its H̃ factored: it enters the solve.
    pub(super) active: [bool; 2],
    /// Grasp points relative to the object COM (m, world).
    r: [Vector3<f64>; 2],
    /// Per active arm: −J̇q̇ + centripetal term − k_p·(position, orientation error).
    c_const: [Vector6<f64>; 2],
    /// Velocity gain k_d = 2ω (1/s).
    kd: f64,
    /// Per active arm: the jaw's grip limits (`None` for a rigid grasp).
    grip: [Option<JawGrip>; 2],
    /// Per active arm with compliant pads: the closing axis n (world) and the velocity gain
    /// of its torsion row (1/h in place of k_d; [`PadTorsion`]).
    soft: [Option<(Vector3<f64>, f64)>; 2],
}

/// The pads' torsional compliance about the closing axis n (finite grip only): a
/// spring-damper (k, c) between jaw and bar in place of the rigid torsion row, integrated
/// implicitly as a soft constraint (the constraint-force-mixing form of Smith's ODE manual,
/// §3.8, "Soft constraint and constraint force mixing", and Catto's "Soft constraints", GDC
/// 2011): with the sub-step h, the torsion at the end of the sub-step
/// τ = k·(θ + h·ω⁺) + c·ω⁺ (θ, ω the jaw's twist and twist rate on the bar, ω⁺ = ω + h·α)
/// is the row α = γ·τ − γ·k·θ − ω/h with γ = 1/(h·(k·h + c)): γ on the row's diagonal,
/// γ·k in place of the position gain k_p and 1/h in place of k_d. Unconditionally stable
/// (backward Euler on the spring), the rigid row as k → ∞.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PadTorsion {
    /// Closing axis n (world).
    pub(super) n: Vector3<f64>,
    /// Stiffness k (N·m/rad).
    pub(super) k: f64,
    /// Damping c (N·m·s/rad).
    pub(super) c: f64,
}

/// One holding jaw's grip for the step: its bar frame and limits.
#[derive(Debug, Clone, Copy)]
pub(super) struct JawGrip {
    /// The bar frame of the grasp ([`crate::grasp::Handle::bar_frame`]), world.
    rot: Rotation3<f64>,
    /// Static limits (λ is reported against these; a sticking jaw starts slipping beyond them).
    stat: GripCapacity,
    /// Kinetic limits (a slipping jaw transmits at most these).
    kinetic: GripCapacity,
    /// The jaw was slipping at the end of the last step.
    slipping: bool,
    /// Rigid grasp: report λ, never slip.
    rigid: bool,
    /// The jaw is opening (no clamp force): it lets go by the release gap of
    /// [`super::arm::update_jaw`], held rigidly until then, neither loaded nor slipping.
    releasing: bool,
    /// The pads' torsional compliance (`None` for a rigid grasp).
    pub(super) torsion: Option<PadTorsion>,
}

impl JawGrip {
    /// The grip of arm state `a` (its clamp force, handle and slip state) with tool pose
    /// `tool` on the object at `object` (world).
    pub(super) fn new(
        p: &SimParams,
        a: &ArmState,
        tool: &Isometry3<f64>,
        object: &Isometry3<f64>,
    ) -> JawGrip {
        let (gp, op) = (&p.grip, &p.object);
        let handle = &op.handles[a.grip.handle.min(op.handles.len() - 1)];
        let jaw = (object.rotation.inverse() * tool.rotation).to_rotation_matrix();
        let rot = object.rotation.to_rotation_matrix() * handle.bar_frame(&jaw);
        JawGrip {
            rot,
            torsion: (!p.rigid_grasp).then(|| pad_torsion(p, &rot, a, object)),
            stat: GripCapacity::of(gp, op, a.clamp_force_n, false),
            kinetic: GripCapacity::of(gp, op, a.clamp_force_n, true),
            slipping: a.grip.sliding,
            rigid: p.rigid_grasp,
            releasing: a.clamp_force_n <= 0.0,
        }
    }

    /// The wrench this jaw transmits when the rigid solve needs `f` (world), with the load
    /// fraction λ of `f` against the static limits and whether the jaw slips.
    fn limit(&self, f: &Vector6<f64>) -> (Vector6<f64>, GripOut) {
        if self.releasing {
            return (*f, GripOut::default());
        }
        let jaw = grasp::to_jaw(&self.rot, f);
        let lambda = self.stat.load_fraction(&jaw);
        let beyond = if self.slipping {
            self.kinetic.load_fraction(&jaw) > 1.0
        } else {
            lambda > 1.0
        };
        let out = GripOut {
            load_fraction: crate::finite_or(lambda, f64::MAX),
            slipping: beyond && !self.rigid,
        };
        if out.slipping {
            let k = grasp::kinetic_wrench(&self.kinetic, &jaw);
            (grasp::from_jaw(&self.rot, &k), out)
        } else {
            (*f, out)
        }
    }
}

/// The pads' torsion about the closing axis n = `rot`'s y (world) of arm state `a` holding
/// the object at `object`: k from [`crate::grasp::GripParams::torsion_stiffness`]; c = η·k/ω,
/// the elastomer's loss factor η at the frequency ω = √(k/I_n) of the box twisting on the
/// pads (I_n its inertia about n through the grasp point; viscous damping equivalent to the
/// loss factor at that mode).
fn pad_torsion(
    p: &SimParams,
    rot: &Rotation3<f64>,
    a: &ArmState,
    object: &Isometry3<f64>,
) -> PadTorsion {
    let (gp, op) = (&p.grip, &p.object);
    let n = rot * Vector3::y();
    let k = gp.torsion_stiffness(op.handle_width_m);
    let r = object.rotation * a.grasp_rel.translation.vector;
    let nb = object.rotation.inverse_transform_vector(&n);
    let i_n = nb.dot(&(op.inertia_body() * nb)) + op.mass_kg * r.cross(&n).norm_squared();
    let c = gp.pad_loss_factor * (k * i_n).sqrt();
    PadTorsion { n, k, c }
}

/// One jaw's grip in a sub-step: the load fraction λ of the wrench the rigid grasp required
/// (against the static limits) and whether the jaw slipped.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct GripOut {
    /// λ (finite; 0 when not holding).
    pub(super) load_fraction: f64,
    /// The jaw transmitted only the kinetic friction wrench.
    pub(super) slipping: bool,
}

/// A sliding episode becomes a reported slip once the bar has slid this far in the jaw (m):
/// 0.002 (assumed: about what a camera view of the jaw shows).
pub const SLIP_NOTICE_M: f64 = 0.002;
/// … or turned this far (rad): 2°.
pub const SLIP_NOTICE_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// One jaw's grip on its handle (plain data): which handle, how hard it is loaded, whether it
/// slips, how far the bar has slid, and the counts since reset. Zeros while not holding (the
/// counts and the handle excepted).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GripState {
    /// The handle ([`crate::grasp::ObjectParams::handles`]) the jaw holds, or last held.
    pub handle: usize,
    /// Load fraction λ in the last step against the static limits (1 = at the limit;
    /// [`crate::grasp::GripCapacity::load_fraction`]): of the wrench the rigid grasp needed
    /// while the jaw sticks (and always with the rigid grasp, where it may exceed 1), and 1
    /// while the bar slides (the jaw transmits what its limits allow, no more).
    pub load_fraction: f64,
    /// The bar is slipping in the jaw: it slid in the last step and has slid at least
    /// [`SLIP_NOTICE_M`] or turned [`SLIP_NOTICE_RAD`] since it started to (a slip the
    /// operator sees; shorter episodes are creep, modelled but not reported).
    pub slipping: bool,
    /// The bar slid in the jaw in the last step (the kinetic limits applied).
    pub sliding: bool,
    /// Slide (m) and turn (rad) of the bar in the jaw since the current sliding began.
    pub episode: [f64; 2],
    /// Slip of the bar across itself in the pads' plane since the grasp (m, signed, along the
    /// bar frame's z: out of the jaw for an aligned jaw).
    pub depth_slip_m: f64,
    /// Slip onsets since reset.
    pub slips: u64,
    /// Grasps lost by slipping since reset (the bar slid out of the pads; not the
    /// assessment's *drop*, see [`Event::SlidOut`]).
    pub slid_out: u64,
    /// The grasp was lost by slipping and the jaw has not opened since: it cannot take the
    /// handle again until it opens past it.
    pub lost: bool,
    /// The handle's grasp point in the jaw frame at the grasp (m).
    handle0: Vector3<f64>,
}

impl GripState {
    /// A new grasp of handle `handle`: the slip measure restarts from its centre at
    /// `handle_jaw` (jaw frame).
    pub(super) fn grasped(&mut self, handle: usize, handle_jaw: Vector3<f64>) {
        self.handle = handle;
        self.load_fraction = 0.0;
        self.slipping = false;
        self.sliding = false;
        self.episode = [0.0; 2];
        self.depth_slip_m = 0.0;
        self.handle0 = handle_jaw;
    }
}

impl Constraint {
    /// Stage 6: the constraint matrix — diagonal blocks Wⁱᵀ·M̃⁻¹·Wⁱ + ZᵢᵀZᵢ + εI and the
    /// coupling W¹ᵀ·M̃⁻¹·W⁰ — factored, and the Baumgarte terms of each holding arm
    /// (`tools`: world tool poses; `r`: grasp points from the COM).
    pub(super) fn new(
        arms: [(&ArmState, &ArmTerms); 2],
        object: (&ObjectState, &ObjectTerms),
        tools: [&Isometry3<f64>; 2],
        r: &[Vector3<f64>; 2],
        sp: &StepParams,
        grip: [Option<JawGrip>; 2],
    ) -> Constraint {
        let (o, ot) = object;
        let active = [0, 1].map(|i| arms[i].0.holding && arms[i].1.factor.is_some());
        let h = sp.dt_s / sp.substeps.max(1) as f64;
        let kp = sp.constraint_omega * sp.constraint_omega;
        let kd = 2.0 * sp.constraint_omega;
        // Compliant pads: γ = 1/(h(kh + c)) and the torsion row's position gain γk.
        let pads = grip.map(|g| {
            g.and_then(|g| g.torsion).map(|t| {
                let gamma = 1.0 / (h * (t.k * h + t.c));
                (t.n, gamma, gamma * t.k)
            })
        });
        // The factorizations read lower triangles only.
        let diag = |i: usize| {
            let mut d = ot.grasp_mobility_diag(&r[i])
                + gram_lower(&arms[i].1.z)
                + Matrix6::identity() * sp.constraint_compliance;
            if let Some((n, gamma, _)) = pads[i] {
                let mut b = d.fixed_view_mut::<3, 3>(3, 3);
                b += n * n.transpose() * gamma;
            }
            d
        };
        let factor = match active {
            [true, true] => BlockLdlt::factor(&diag(0), &ot.grasp_mobility(&r[1], &r[0]), &diag(1))
                .map(Factor::Both),
            [true, false] => Ldlt::factor(&diag(0)).map(|f| Factor::One(0, f)),
            [false, true] => Ldlt::factor(&diag(1)).map(|f| Factor::One(1, f)),
            [false, false] => None,
        };
        let mut c_const = [Vector6::zeros(); 2];
        for i in 0..2 {
            if !active[i] {
                continue;
            }
            let desired = o.pose * arms[i].0.grasp_rel;
            let t = tools[i];
            let ep = t.translation.vector - desired.translation.vector;
            let mut er = rotation_error(&t.rotation, &desired.rotation);
            if let Some((n, _, kp_n)) = pads[i] {
                // The twist about n enters with the spring's gain γk, not k_p.
                er += n * (n.dot(&er) * (kp_n / kp - 1.0));
            }
            let w = o.angular_velocity;
            let cen = w.cross(&w.cross(&r[i]));
            c_const[i] = -arms[i].1.jdqd
                + Vector6::new(
                    cen.x - kp * ep.x,
                    cen.y - kp * ep.y,
                    cen.z - kp * ep.z,
                    -kp * er.x,
                    -kp * er.y,
                    -kp * er.z,
                );
        }
        Constraint {
            factor,
            active,
            r: *r,
            c_const,
            kd,
            grip,
            soft: pads.map(|p| p.map(|(n, _, _)| (n, 1.0 / h))),
        }
    }

    /// Sub-step: the contact wrenches f (on the object, at the grasp points, world) that
    /// make each active arm's tool acceleration match its grasp point's, with the arms' free
    /// accelerations `qdd` and the object's free acceleration `acc_o`; adds their effect to
    /// both (q̈ −= H̃⁻¹Jᵀf, a_o += M̃⁻¹Wf). `jw`, `qd`: the arms' world Jacobians and joint
    /// rates; `vo`: the object's twist. Zero for an arm not holding. A jaw with a finite grip
    /// transmits at most its friction limits ([`JawGrip`]); its [`GripOut`] says how it fared.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply(
        &self,
        arms: [&ArmTerms; 2],
        object: &ObjectTerms,
        jw: [&Matrix6<f64>; 2],
        qd: [&[f64; N_ACT]; 2],
        vo: &Vector6<f64>,
        qdd: &mut [Vector6<f64>; 2],
        acc_o: &mut Vector6<f64>,
    ) -> ([Vector6<f64>; 2], [GripOut; 2]) {
        let mut grip = [GripOut::default(); 2];
        let Some(factor) = &self.factor else {
            return ([Vector6::zeros(); 2], grip);
        };
        let mut b = [Vector6::zeros(); 2];
        for i in 0..2 {
            if self.active[i] {
                let r = &self.r[i];
                let ev = jw[i] * Vector6::from(*qd[i]) - grasp::grasp_point_twist(r, vo);
                let mut ci = self.c_const[i] - ev * self.kd;
                if let Some((n, kd_n)) = &self.soft[i] {
                    // The torsion row's twist rate enters with 1/h, not k_d.
                    let w = n * (n.dot(&ev.fixed_rows::<3>(3)) * (kd_n - self.kd));
                    ci -= Vector6::new(0.0, 0.0, 0.0, w.x, w.y, w.z);
                }
                b[i] = jw[i] * qdd[i] - grasp::grasp_point_twist(r, acc_o) - ci;
            }
        }
        let mut f = match factor {
            Factor::One(i, f) => {
                let mut out = [Vector6::zeros(); 2];
                out[*i] = f.solve(&b[*i]);
                out
            }
            Factor::Both(f) => {
                let (f0, f1) = f.solve(&b[0], &b[1]);
                [f0, f1]
            }
        };
        for i in 0..2 {
            if let (true, Some(g)) = (self.active[i], &self.grip[i]) {
                (f[i], grip[i]) = g.limit(&f[i]);
            }
        }
        for i in 0..2 {
            if self.active[i] {
                if let Some(h) = &arms[i].factor {
                    qdd[i] -= h.backward(&(arms[i].z * f[i]));
                }
                *acc_o += object.mobility_times(&grasp::wrench_at_com(&self.r[i], &f[i]));
            }
        }
        (f, grip)
    }

    /// The internal wrench F_int (eq. 3.41) of contact wrenches `fc` while both arms hold;
    /// zero otherwise.
    pub(super) fn internal_wrench(&self, fc: &[Vector6<f64>; 2]) -> Vector6<f64> {
        if self.active[0] && self.active[1] {
            grasp::internal_wrench(&self.r, fc)
        } else {
            Vector6::zeros()
        }
    }
}

/// The slip stage (after the sub-steps, per holding arm with `out` from the last sub-step):
/// records the load fraction (1 while the bar slides); while the jaw slips, moves its grasp
/// frame with the bar in the limited directions (translation along the bar and across it in
/// the pads' plane, every rotation; the closing-axis translation keeps its constraint error
/// for the Baumgarte terms), measures the slip across the bar from where the handle's centre
/// was at the grasp, and lets go when it exceeds the travel; an episode is reported ([`GripState::slipping`], counted in `slips`)
/// once it has slid [`SLIP_NOTICE_M`] or turned [`SLIP_NOTICE_RAD`]. `tool`, `object`: world
/// poses after the step. The onset ([`Event::Slip`]) and the slide-out
/// ([`Event::SlidOut`]) of `arm`'s jaw go to `events`.
pub(super) fn slip_stage(
    arm: Arm,
    a: &mut ArmState,
    out: &GripOut,
    p: &SimParams,
    tool: &Isometry3<f64>,
    object: &Isometry3<f64>,
    events: &mut Vec<Event>,
) {
    let (gp, op) = (&p.grip, &p.object);
    a.grip.sliding = a.holding && out.slipping;
    a.grip.load_fraction = match (a.holding, a.grip.sliding) {
        (false, _) => 0.0,
        (true, true) => out.load_fraction.min(1.0),
        (true, false) => out.load_fraction,
    };
    if !a.grip.sliding {
        a.grip.slipping = false;
        a.grip.episode = [0.0; 2];
        return;
    }
    let handle = &op.handles[a.grip.handle.min(op.handles.len() - 1)];
    // The bar frame in the grasp (desired tool) frame, and δ: the tool's pose in the grasp
    // frame, in bar-frame coordinates.
    let jaw = a.grasp_rel.rotation.to_rotation_matrix();
    let bar = jaw.inverse() * handle.bar_frame(&jaw);
    let delta = a.grasp_rel.inverse() * (object.inverse() * tool);
    let t = bar.inverse() * delta.translation.vector;
    let mut rv = delta.rotation.scaled_axis();
    if !p.rigid_grasp {
        // Compliant pads: the bar turns in the pads by the twist beyond the pads' elastic
        // one, τ_n/k (τ_n the torsion they transmit, about n).
        let n_world = object.rotation * (a.grasp_rel.rotation * (bar * Vector3::y()));
        let tau = Vector3::new(
            a.contact_wrench[3],
            a.contact_wrench[4],
            a.contact_wrench[5],
        );
        let elastic = tau.dot(&n_world) / gp.torsion_stiffness(op.handle_width_m);
        rv -= bar * Vector3::y() * crate::finite_or(elastic, 0.0);
    }
    let slide = Isometry3::from_parts(
        Translation3::from(bar * Vector3::new(t.x, 0.0, t.z)),
        UnitQuaternion::from_scaled_axis(rv),
    );
    a.grasp_rel *= slide;
    a.grip.episode[0] += t.x.hypot(t.z);
    a.grip.episode[1] += rv.norm();
    if !a.grip.slipping
        && (a.grip.episode[0] >= SLIP_NOTICE_M || a.grip.episode[1] >= SLIP_NOTICE_RAD)
    {
        a.grip.slipping = true;
        a.grip.slips += 1;
        events.push(Event::Slip {
            arm,
            load_fraction: a.grip.load_fraction,
        });
    }
    let handle_jaw = a.grasp_rel.inverse() * Point3::from(handle.centre_m);
    let across = bar * Vector3::z();
    a.grip.depth_slip_m = (handle_jaw.coords - a.grip.handle0).dot(&across);
    if a.grip.depth_slip_m.abs() > gp.slip_travel_m {
        a.holding = false;
        a.contact_wrench = [0.0; 6];
        a.grip.slipping = false;
        a.grip.sliding = false;
        a.grip.lost = true;
        a.grip.slid_out += 1;
        events.push(Event::SlidOut { arm });
    }
}
