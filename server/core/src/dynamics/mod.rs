//! Rigid-body dynamics of one serial arm (Lim eq. 3.38): H(q)q̈ + C(q,q̇)q̇ + G(q) = T − JᵀF_c.
//!
//! * [`Inertials`]: mass, centre of mass and inertia of every link (Model side).
//! * [`DynData`]: preallocated scratch and results (Data side).
//! * [`rnea`]: recursive Newton–Euler inverse dynamics, τ = H q̈ + C q̇ + G (Featherstone 2008,
//!   ch. 5, here in the base frame with moments about each joint origin).
//! * [`crba`]: composite-rigid-body mass matrix H (Featherstone ch. 6), computed independently
//!   of [`rnea`] from composite inertias, so the two can be checked against each other.
//! * [`tool_bias_acceleration`]: J̇q̇ of the tool point, from the RNEA forward pass.
//! * [`step_terms`]: H, C q̇ + G and J̇q̇ together in one pass over the links, on the stack —
//!   what the 1 kHz step needs; the same formulas as [`rnea`] and [`crba`], which stay the
//!   readable reference implementations it is tested against.
//!
//! All functions use the joint frames of a [`KinData`] already filled by
//! [`crate::kinematics::forward_kinematics`] (or `jacobian`) for the same q, and allocate nothing.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};

use crate::Error;
use crate::kinematics::KinData;
use crate::model::{JointKind, Model};

/// Inertial parameters of one link (the body moved by a joint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkInertia {
    /// Mass (kg), > 0.
    pub mass_kg: f64,
    /// Centre of mass in the joint's moving frame (m).
    pub com_m: Vector3<f64>,
    /// Inertia tensor about the centre of mass, joint frame axes (kg·m²), symmetric PSD.
    pub inertia_kgm2: Matrix3<f64>,
    /// Volume displaced in water (m³), for optional buoyancy; 0 when unknown.
    pub volume_m3: f64,
}

impl LinkInertia {
    /// This link with a point mass `mass_kg` added at `point_m` (joint frame), e.g. a payload
    /// held in the jaw: combined mass, COM and inertia (parallel-axis theorem).
    pub fn with_point_mass(&self, point_m: &Vector3<f64>, mass_kg: f64) -> LinkInertia {
        let m = self.mass_kg + mass_kg;
        let c = (self.com_m * self.mass_kg + point_m * mass_kg) / m;
        let d1 = self.com_m - c;
        let d2 = point_m - c;
        let pa = |d: &Vector3<f64>, mm: f64| {
            (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * mm
        };
        LinkInertia {
            mass_kg: m,
            com_m: c,
            inertia_kgm2: self.inertia_kgm2 + pa(&d1, self.mass_kg) + pa(&d2, mass_kg),
            volume_m3: self.volume_m3,
        }
    }
}

/// Inertial parameters of every link of a model, base to tip.
#[derive(Debug, Clone, PartialEq)]
pub struct Inertials {
    /// One per joint: link `i` is moved by joint `i`.
    pub links: Vec<LinkInertia>,
    /// Where the numbers come from.
    pub source: &'static str,
}

/// Mass of each Magnum link (kg), base to tip: swing housing, upper arm, forearm, pitch
/// housing, yaw housing, rotate + jaw. Sum = 71 kg = "weight in air, 71 kg (nominal)" of
/// Lim Table 1-1. The split is an engineering guess (no masses are published): the two
/// long links carry the two big cylinders and most of the structure; the wrist and the jaw
/// are compact castings.
pub const MAGNUM_LINK_MASSES_KG: [f64; 6] = [12.0, 22.0, 18.0, 7.0, 5.0, 7.0];

/// Mean density of a Magnum link (kg/m³) for buoyancy: titanium/aluminium structure with
/// oil-filled cylinders ≈ 4 000 kg/m³ (assumed), so the arm weighs about 75 % of its air
/// weight in sea water.
pub const MAGNUM_LINK_DENSITY_KGM3: f64 = 4000.0;

impl Inertials {
    /// Plausible Magnum inertials (Lim gives none): masses [`MAGNUM_LINK_MASSES_KG`]; each
    /// link is a solid cylinder of radius 0.06 m from its joint to the next joint (the
    /// DH link vector), COM at its middle; the last link reaches the tool point and its
    /// COM is placed 60 % of the way to it (jaw mass forward).
    pub fn magnum(model: &Model) -> Result<Inertials, Error> {
        if model.dof() != MAGNUM_LINK_MASSES_KG.len() {
            return Err(Error::InvalidModel {
                reason: "Magnum inertials need a 6-joint model".into(),
            });
        }
        Ok(Self::rods(
            model,
            &MAGNUM_LINK_MASSES_KG,
            0.06,
            MAGNUM_LINK_DENSITY_KGM3,
            "Lim Table 1-1 total mass 71 kg; split, COM and rod inertia assumed (see MAGNUM_LINK_MASSES_KG)",
        ))
    }

    /// Each link as a solid cylinder of `radius_m` along its link vector (from the joint
    /// origin to the next joint's origin, or to the tool point for the last link), with
    /// the given masses and mean density (for the displaced volume).
    pub fn rods(
        model: &Model,
        masses_kg: &[f64],
        radius_m: f64,
        density_kgm3: f64,
        source: &'static str,
    ) -> Inertials {
        let n = model.dof();
        let links = (0..n)
            .map(|i| {
                let (seg, frac) = if i + 1 < n {
                    (model.joints[i + 1].origin.translation.vector, 0.5)
                } else {
                    (model.flange.transform_point(&model.tool.into()).coords, 0.6)
                };
                let m = masses_kg.get(i).copied().unwrap_or(1.0);
                let len = seg.norm();
                let com = seg * frac;
                // Solid cylinder about its own axis (u) and about the transverse axes.
                let ia = 0.5 * m * radius_m * radius_m;
                let it = m * (3.0 * radius_m * radius_m + len * len) / 12.0;
                let inertia = if len > 1e-9 {
                    let u = seg / len;
                    Matrix3::identity() * it + u * u.transpose() * (ia - it)
                } else {
                    Matrix3::identity() * ia
                };
                LinkInertia {
                    mass_kg: m,
                    com_m: com,
                    inertia_kgm2: inertia,
                    volume_m3: m / density_kgm3,
                }
            })
            .collect();
        Inertials { links, source }
    }

    /// Total mass (kg).
    pub fn total_mass_kg(&self) -> f64 {
        self.links.iter().map(|l| l.mass_kg).sum()
    }
}

/// Preallocated results and scratch for one model.
#[derive(Debug, Clone)]
pub struct DynData {
    /// Angular velocity of each link, base frame (rad/s).
    pub omega: Vec<Vector3<f64>>,
    /// Angular acceleration of each link, base frame (rad/s²).
    pub omega_dot: Vec<Vector3<f64>>,
    /// Linear acceleration of each joint origin, base frame (m/s²), gravity included as a
    /// fictitious base acceleration in [`rnea`].
    pub acc: Vec<Vector3<f64>>,
    /// Force transmitted to each link from its parent, base frame (N).
    pub force: Vec<Vector3<f64>>,
    /// Moment transmitted to each link about its joint origin, base frame (N·m).
    pub moment: Vec<Vector3<f64>>,
    /// Composite mass of links i..n (kg) (CRBA).
    pub comp_mass: Vec<f64>,
    /// Composite first moment Σ m·c of links i..n, base frame (kg·m) (CRBA).
    pub comp_first: Vec<Vector3<f64>>,
    /// Composite inertia of links i..n about the base origin, base frame (kg·m²) (CRBA).
    pub comp_inertia: Vec<Matrix3<f64>>,
    /// Joint axes, base frame (CRBA scratch).
    pub axes: Vec<Vector3<f64>>,
    /// Joint origins, base frame (CRBA scratch).
    pub origins: Vec<Vector3<f64>>,
    /// Joint-space mass matrix H, n×n (kg·m² / kg), filled by [`crba`].
    pub mass_matrix: DMatrix<f64>,
}

impl DynData {
    /// Allocates scratch for `model`.
    pub fn new(model: &Model) -> DynData {
        let n = model.dof();
        DynData {
            omega: vec![Vector3::zeros(); n],
            omega_dot: vec![Vector3::zeros(); n],
            acc: vec![Vector3::zeros(); n],
            force: vec![Vector3::zeros(); n],
            moment: vec![Vector3::zeros(); n],
            comp_mass: vec![0.0; n],
            comp_first: vec![Vector3::zeros(); n],
            comp_inertia: vec![Matrix3::zeros(); n],
            axes: vec![Vector3::zeros(); n],
            origins: vec![Vector3::zeros(); n],
            mass_matrix: DMatrix::zeros(n, n),
        }
    }
}

/// Skew-symmetric cross-product matrix \[v\]×.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

fn joint_axis(model: &Model, kin: &KinData, i: usize) -> Vector3<f64> {
    kin.joint_frames[i].rotation * model.joints[i].axis.into_inner()
}

/// Forward pass shared by [`rnea`] and [`tool_bias_acceleration`]: link angular velocity and
/// acceleration and joint-origin acceleration (base acceleration `a0`).
fn forward_pass(
    model: &Model,
    kin: &KinData,
    qd: &[f64],
    qdd: &[f64],
    a0: Vector3<f64>,
    data: &mut DynData,
) {
    let mut w = Vector3::zeros();
    let mut wd = Vector3::zeros();
    let mut a = a0;
    let mut p_prev = Vector3::zeros();
    for i in 0..model.dof() {
        let z = joint_axis(model, kin, i);
        let p = kin.joint_frames[i].translation.vector;
        let d = p - p_prev;
        // Acceleration of this joint's origin, a point of the parent link (revolute), or
        // of the parent plus the sliding motion (prismatic).
        let mut ai = a + wd.cross(&d) + w.cross(&w.cross(&d));
        match model.joints[i].kind {
            JointKind::Revolute => {
                let wn = w + z * qd[i];
                wd += z * qdd[i] + w.cross(&(z * qd[i]));
                w = wn;
            }
            JointKind::Prismatic => {
                ai += z * qdd[i] + 2.0 * w.cross(&(z * qd[i]));
            }
        }
        a = ai;
        p_prev = p;
        data.omega[i] = w;
        data.omega_dot[i] = wd;
        data.acc[i] = a;
    }
}

/// Recursive Newton–Euler inverse dynamics: fills `tau` (n) with H(q)q̈ + C(q,q̇)q̇ + G(q) for
/// gravity `gravity` (m/s², base frame, e.g. (0, 0, −9.81)). `kin` must hold the frames for q.
/// With `buoyancy_density_kgm3` > 0 each link is pushed up by ρ·V·g at its COM (uniform
/// links), i.e. its weight becomes (m − ρV)·g.
#[allow(clippy::too_many_arguments)]
pub fn rnea(
    model: &Model,
    inertials: &Inertials,
    kin: &KinData,
    qd: &[f64],
    qdd: &[f64],
    gravity: &Vector3<f64>,
    buoyancy_density_kgm3: f64,
    tau: &mut [f64],
    data: &mut DynData,
) {
    let n = model.dof();
    // Gravity as a fictitious upward base acceleration; buoyancy as a per-link correction.
    forward_pass(model, kin, qd, qdd, -gravity, data);
    let mut f_next = Vector3::zeros();
    let mut n_next = Vector3::zeros();
    let mut p_next = Vector3::zeros();
    for i in (0..n).rev() {
        let frame = &kin.joint_frames[i];
        let link = &inertials.links[i];
        let p = frame.translation.vector;
        let r = frame.rotation * link.com_m;
        let w = data.omega[i];
        let wd = data.omega_dot[i];
        let ac = data.acc[i] + wd.cross(&r) + w.cross(&w.cross(&r));
        let rot = frame.rotation.matrix();
        let ic = rot * link.inertia_kgm2 * rot.transpose();
        // Net force on the link, less the buoyant force (which acts upward, against gravity).
        let fb = -gravity * (buoyancy_density_kgm3 * link.volume_m3);
        let fi = ac * link.mass_kg - fb;
        let f = fi + f_next;
        let m = ic * wd + w.cross(&(ic * w)) + r.cross(&fi) + n_next + (p_next - p).cross(&f_next);
        data.force[i] = f;
        data.moment[i] = m;
        let z = joint_axis(model, kin, i);
        tau[i] = match model.joints[i].kind {
            JointKind::Revolute => z.dot(&m),
            JointKind::Prismatic => z.dot(&f),
        };
        f_next = f;
        n_next = m;
        p_next = p;
    }
}

/// Composite-rigid-body algorithm: fills `data.mass_matrix` with H(q) (n×n, symmetric
/// positive definite). Column j is the generalized force that a unit acceleration of joint j
/// (all velocities zero) needs: the composite body j..n moves rigidly about/along axis j.
pub fn crba(model: &Model, inertials: &Inertials, kin: &KinData, data: &mut DynData) {
    let n = model.dof();
    // Composite mass, first moment and inertia about the base origin, tip to base.
    let mut m_acc = 0.0;
    let mut h_acc = Vector3::zeros();
    let mut i_acc = Matrix3::zeros();
    for i in (0..n).rev() {
        let frame = &kin.joint_frames[i];
        data.axes[i] = joint_axis(model, kin, i);
        data.origins[i] = frame.translation.vector;
        let link = &inertials.links[i];
        let c = frame.transform_point(&link.com_m.into()).coords;
        let rot = frame.rotation.matrix();
        let ic = rot * link.inertia_kgm2 * rot.transpose();
        // Parallel axis: I_O = I_c + m([c]ᵀ[c]).
        let sc = skew(&c);
        m_acc += link.mass_kg;
        h_acc += c * link.mass_kg;
        i_acc += ic - sc * sc * link.mass_kg;
        data.comp_mass[i] = m_acc;
        data.comp_first[i] = h_acc;
        data.comp_inertia[i] = i_acc;
    }
    for j in 0..n {
        let zj = data.axes[j];
        let pj = data.origins[j];
        let (m, h, io) = (data.comp_mass[j], data.comp_first[j], data.comp_inertia[j]);
        // Rate of momentum of the composite body: force f, moment about the base origin n0.
        let (f, n0) = match model.joints[j].kind {
            JointKind::Revolute => {
                // Velocity field v(x) = z×(x − p); ω = z.
                let f = zj.cross(&(h - pj * m));
                // Angular momentum about the origin: L_O = Σ m x × (z × (x − p))
                // = I_O z − h × (z × p), with h = Σ m x.
                let n0 = io * zj - h.cross(&zj.cross(&pj));
                (f, n0)
            }
            JointKind::Prismatic => (zj * m, h.cross(&zj)),
        };
        for i in 0..=j {
            let zi = data.axes[i];
            let pi = data.origins[i];
            let hij = match model.joints[i].kind {
                JointKind::Revolute => zi.dot(&(n0 - pi.cross(&f))),
                JointKind::Prismatic => zi.dot(&f),
            };
            data.mass_matrix[(i, j)] = hij;
            data.mass_matrix[(j, i)] = hij;
        }
    }
}

/// The same J̇q̇ read from the forward pass of a preceding [`rnea`] call made with q̈ = 0 and
/// gravity `gravity` (saves a second forward pass inside the step): linear accelerations there
/// include the fictitious base acceleration −g, which is removed here.
pub fn tool_bias_from_rnea(
    model: &Model,
    kin: &KinData,
    gravity: &Vector3<f64>,
    data: &DynData,
) -> [f64; 6] {
    let n = model.dof();
    let p = kin.joint_frames[n - 1].translation.vector;
    let r = kin.tool_point - p;
    let w = data.omega[n - 1];
    let wd = data.omega_dot[n - 1];
    let a = data.acc[n - 1] + gravity + wd.cross(&r) + w.cross(&w.cross(&r));
    [a.x, a.y, a.z, wd.x, wd.y, wd.z]
}

/// Tool-point bias acceleration J̇(q,q̇)q̇ (6: linear, angular; base frame): the tool's
/// acceleration when q̈ = 0, without gravity. Overwrites the forward-pass fields of `data`.
pub fn tool_bias_acceleration(
    model: &Model,
    kin: &KinData,
    qd: &[f64],
    zero: &[f64],
    data: &mut DynData,
) -> [f64; 6] {
    let n = model.dof();
    forward_pass(model, kin, qd, zero, Vector3::zeros(), data);
    let p = kin.joint_frames[n - 1].translation.vector;
    let r = kin.tool_point - p;
    let w = data.omega[n - 1];
    let wd = data.omega_dot[n - 1];
    let a = data.acc[n - 1] + wd.cross(&r) + w.cross(&w.cross(&r));
    [a.x, a.y, a.z, wd.x, wd.y, wd.z]
}

/// Everything the simulation step needs from the rigid-body model at one (q, q̇) (Lim eq. 3.38).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepTerms<const N: usize> {
    /// Joint-space mass matrix H(q) (CRBA).
    pub mass_matrix: SMatrix<f64, N, N>,
    /// C(q, q̇)q̇ + G(q), buoyancy included: the RNEA torques at q̈ = 0.
    pub bias: SVector<f64, N>,
    /// Tool-point J̇q̇ (linear; angular), base frame, without gravity.
    pub tool_bias: [f64; 6],
}

/// [`rnea`] at q̈ = 0, [`crba`] and [`tool_bias_from_rnea`] fused: every link's rotation
/// matrix, axis, COM offset and world inertia R·I·Rᵀ is formed once and shared by the
/// forward pass, the backward (force) pass and the composite-inertia accumulation, with all
/// scratch in fixed-size arrays (Featherstone 2008 ch. 5–6). `kin` must hold the frames for
/// q; `qd` the joint rates.
///
/// # Panics
/// If the model, its inertials or `kin` have fewer than `N` joints (the simulation checks the
/// model's size when it is built).
pub fn step_terms<const N: usize>(
    model: &Model,
    inertials: &Inertials,
    kin: &KinData,
    qd: &[f64; N],
    gravity: &Vector3<f64>,
    buoyancy_density_kgm3: f64,
) -> StepTerms<N> {
    let joints = &model.joints[..N];
    let links = &inertials.links[..N];
    let frames = &kin.joint_frames[..N];
    let mut z = [Vector3::zeros(); N];
    let mut p = [Vector3::zeros(); N];
    let mut c = [Vector3::zeros(); N];
    let mut ic = [Matrix3::zeros(); N];
    let mut revolute = [true; N];
    for i in 0..N {
        let r = frames[i].rotation.matrix();
        z[i] = r * joints[i].axis.into_inner();
        p[i] = frames[i].translation.vector;
        c[i] = r * links[i].com_m;
        ic[i] = r * links[i].inertia_kgm2 * r.transpose();
        revolute[i] = joints[i].kind == JointKind::Revolute;
    }
    // Forward pass with q̈ = 0 and gravity as a fictitious base acceleration (see `rnea`).
    let mut w_of = [Vector3::zeros(); N];
    let mut wd_of = [Vector3::zeros(); N];
    let mut a_of = [Vector3::zeros(); N];
    let (mut w, mut wd, mut a) = (Vector3::zeros(), Vector3::zeros(), -gravity);
    let mut p_prev = Vector3::zeros();
    for i in 0..N {
        let d = p[i] - p_prev;
        let mut ai = a + wd.cross(&d) + w.cross(&w.cross(&d));
        let zq = z[i] * qd[i];
        if revolute[i] {
            wd += w.cross(&zq);
            w += zq;
        } else {
            ai += 2.0 * w.cross(&zq);
        }
        a = ai;
        p_prev = p[i];
        w_of[i] = w;
        wd_of[i] = wd;
        a_of[i] = a;
    }
    // Backward pass: link forces and moments (RNEA) and composite bodies (CRBA).
    let mut bias = SVector::<f64, N>::zeros();
    let (mut f_next, mut n_next, mut p_next) = (Vector3::zeros(), Vector3::zeros(), p[N - 1]);
    let (mut m_acc, mut h_acc, mut i_acc) = (0.0, Vector3::zeros(), Matrix3::zeros());
    let mut comp = [(0.0, Vector3::zeros(), Matrix3::zeros()); N];
    for i in (0..N).rev() {
        let link = &links[i];
        let (w, wd, ci) = (w_of[i], wd_of[i], c[i]);
        let ac = a_of[i] + wd.cross(&ci) + w.cross(&w.cross(&ci));
        let fb = -gravity * (buoyancy_density_kgm3 * link.volume_m3);
        let fi = ac * link.mass_kg - fb;
        let f = fi + f_next;
        let iw = ic[i] * w;
        let m = ic[i] * wd + w.cross(&iw) + ci.cross(&fi) + n_next + (p_next - p[i]).cross(&f_next);
        bias[i] = if revolute[i] {
            z[i].dot(&m)
        } else {
            z[i].dot(&f)
        };
        (f_next, n_next, p_next) = (f, m, p[i]);
        // Composite inertia about the base origin; parallel axis I_O = I_c + m(|x|²1 − x xᵀ).
        let x = p[i] + ci;
        m_acc += link.mass_kg;
        h_acc += x * link.mass_kg;
        i_acc +=
            ic[i] + (Matrix3::identity() * x.norm_squared() - x * x.transpose()) * link.mass_kg;
        comp[i] = (m_acc, h_acc, i_acc);
    }
    // Mass matrix columns, as in `crba`. With the axis moment μᵢ = zᵢ × pᵢ (Plücker
    // coordinates of the axis), zᵢ·(n₀ − pᵢ × f) = zᵢ·n₀ − μᵢ·f: two dot products per entry.
    let mut mu = [Vector3::zeros(); N];
    for i in 0..N {
        mu[i] = z[i].cross(&p[i]);
    }
    let mut h = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let (m, hj, io) = comp[j];
        let zj = z[j];
        let (f, n0) = if revolute[j] {
            (zj.cross(&(hj - p[j] * m)), io * zj - hj.cross(&mu[j]))
        } else {
            (zj * m, hj.cross(&zj))
        };
        for i in 0..=j {
            let hij = if revolute[i] {
                z[i].dot(&n0) - mu[i].dot(&f)
            } else {
                z[i].dot(&f)
            };
            h[(i, j)] = hij;
            h[(j, i)] = hij;
        }
    }
    let r = kin.tool_point - p[N - 1];
    let (w, wd) = (w_of[N - 1], wd_of[N - 1]);
    let acc = a_of[N - 1] + gravity + wd.cross(&r) + w.cross(&w.cross(&r));
    StepTerms {
        mass_matrix: h,
        bias,
        tool_bias: [acc.x, acc.y, acc.z, wd.x, wd.y, wd.z],
    }
}
