//! [`step_terms`](super::step_terms) for the simulation's two arms in lockstep.
//!
//! Both arms run the same recursions over their links (Featherstone 2008 ch. 5–6, as in
//! [`super::step_terms`]), so each number of the one-arm algorithm becomes a pair — left arm
//! in lane 0, right arm in lane 1 — and every operation acts on both lanes at once. The
//! compiler turns a pair operation into one packed SSE2 instruction, where the one-arm code
//! spends shuffles packing the x, y, z of a single vector. Each lane performs exactly the
//! one-arm operations (no lane mixes with the other), so the results match
//! [`super::step_terms`] for each arm to round-off (the tests check it).
//!
//! The lockstep needs both arms' joints to be of the same kinds, joint by joint (two Magnum
//! arms are); [`step_terms_pair`] returns `None` otherwise and the caller uses the one-arm
//! function per arm.

// Per-link and per-entry loops index several arrays by the same counter, as in the one-arm
// function.
#![allow(clippy::needless_range_loop)]

use std::ops::{Add, AddAssign, Neg, Sub};

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::{Inertials, StepTerms};
use crate::kinematics::KinData;
use crate::linalg::Pair as P;
use crate::model::{JointKind, Model};

/// A 3-vector of pairs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct V([P; 3]);

impl V {
    #[inline(always)]
    fn from_arms(a: &Vector3<f64>, b: &Vector3<f64>) -> V {
        V([P([a.x, b.x]), P([a.y, b.y]), P([a.z, b.z])])
    }
    #[inline(always)]
    fn arm(&self, k: usize) -> Vector3<f64> {
        Vector3::new(self.0[0].0[k], self.0[1].0[k], self.0[2].0[k])
    }
    #[inline(always)]
    fn scale(self, s: P) -> V {
        V([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
    #[inline(always)]
    fn cross(self, o: V) -> V {
        let (a, b) = (self.0, o.0);
        V([
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ])
    }
    #[inline(always)]
    fn dot(self, o: V) -> P {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
}

impl Add for V {
    type Output = V;
    #[inline(always)]
    fn add(self, o: V) -> V {
        V([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}
impl Sub for V {
    type Output = V;
    #[inline(always)]
    fn sub(self, o: V) -> V {
        V([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V([-self.0[0], -self.0[1], -self.0[2]])
    }
}
impl AddAssign for V {
    #[inline(always)]
    fn add_assign(&mut self, o: V) {
        *self = *self + o;
    }
}

/// A 3×3 matrix of pairs, row-major.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct M([[P; 3]; 3]);

impl M {
    #[inline(always)]
    fn from_arms(a: &Matrix3<f64>, b: &Matrix3<f64>) -> M {
        let mut m = M::default();
        for r in 0..3 {
            for c in 0..3 {
                m.0[r][c] = P([a[(r, c)], b[(r, c)]]);
            }
        }
        m
    }
    #[inline(always)]
    fn mul_v(&self, v: V) -> V {
        let row = |r: &[P; 3]| r[0] * v.0[0] + r[1] * v.0[1] + r[2] * v.0[2];
        V([row(&self.0[0]), row(&self.0[1]), row(&self.0[2])])
    }
    /// Adds x·xᵀ (or subtracts it when `minus`).
    #[inline(always)]
    fn add_outer(&mut self, x: V, minus: bool) {
        for r in 0..3 {
            for c in 0..=r {
                let e = x.0[r] * x.0[c];
                let e = if minus { -e } else { e };
                self.0[r][c] += e;
                if c != r {
                    self.0[c][r] += e;
                }
            }
        }
    }
    #[inline(always)]
    fn add(&self, b: &M) -> M {
        let mut m = *self;
        for r in 0..3 {
            for c in 0..3 {
                m.0[r][c] += b.0[r][c];
            }
        }
        m
    }
}

/// Both arms' constant link data in lanes, paired once when the simulation is built, so
/// that a step pairs only what changes (the joint frames).
///
/// Each link inertia about its COM is kept in spectral form with its middle eigenvalue
/// taken out: I = s·1 + u·uᵀ − v·vᵀ with u = √(λ_max − s)·e_max, v = √(s − λ_min)·e_min
/// (e the unit eigenvectors). Then R·I·Rᵀ = s·1 + (Ru)(Ru)ᵀ − (Rv)(Rv)ᵀ: two matrix–vector
/// products instead of two matrix products. A rod-like link (two equal eigenvalues, as the
/// Magnum's [`Inertials::magnum`]) has one of u, v zero, and the step skips that term when it
/// is zero in both lanes. Eigenvalue gaps below 10⁻¹² of the largest are taken as zero,
/// a change of the inertia by at most that fraction.
#[derive(Debug, Clone, PartialEq)]
pub struct PairLinks<const N: usize> {
    revolute: [bool; N],
    /// Joint axis in the joint frame.
    axis: [V; N],
    com: [V; N],
    mass: [P; N],
    volume: [P; N],
    iso: [P; N],
    u: [V; N],
    v: [V; N],
    /// u (resp. v) is non-zero in at least one lane.
    has_u: [bool; N],
    has_v: [bool; N],
}

impl<const N: usize> PairLinks<N> {
    /// The links of `models[k]` with `inertials[k]` for arm k, or `None` when the arms'
    /// joints differ in kind (then use the one-arm [`super::step_terms`]) or a model has
    /// fewer than N joints or links.
    pub fn new(models: [&Model; 2], inertials: [&Inertials; 2]) -> Option<Self> {
        if (0..2).any(|k| models[k].joints.len() < N || inertials[k].links.len() < N) {
            return None;
        }
        let joints = [&models[0].joints[..N], &models[1].joints[..N]];
        if (0..N).any(|i| joints[0][i].kind != joints[1][i].kind) {
            return None;
        }
        let links = [&inertials[0].links[..N], &inertials[1].links[..N]];
        let pair = |f: &dyn Fn(usize) -> f64| P([f(0), f(1)]);
        let mut out = PairLinks {
            revolute: [false; N],
            axis: [V::default(); N],
            com: [V::default(); N],
            mass: [P::default(); N],
            volume: [P::default(); N],
            iso: [P::default(); N],
            u: [V::default(); N],
            v: [V::default(); N],
            has_u: [false; N],
            has_v: [false; N],
        };
        for i in 0..N {
            out.revolute[i] = joints[0][i].kind == JointKind::Revolute;
            out.axis[i] = V::from_arms(
                &joints[0][i].axis.into_inner(),
                &joints[1][i].axis.into_inner(),
            );
            out.com[i] = V::from_arms(&links[0][i].com_m, &links[1][i].com_m);
            out.mass[i] = pair(&|k| links[k][i].mass_kg);
            out.volume[i] = pair(&|k| links[k][i].volume_m3);
            let spectral = [
                spectral_form(&links[0][i].inertia_kgm2),
                spectral_form(&links[1][i].inertia_kgm2),
            ];
            out.iso[i] = pair(&|k| spectral[k].0);
            out.u[i] = V::from_arms(&spectral[0].1, &spectral[1].1);
            out.v[i] = V::from_arms(&spectral[0].2, &spectral[1].2);
            out.has_u[i] = spectral.iter().any(|s| s.1 != Vector3::zeros());
            out.has_v[i] = spectral.iter().any(|s| s.2 != Vector3::zeros());
        }
        Some(out)
    }
}

/// (s, u, v) with I = s·1 + u·uᵀ − v·vᵀ (see [`PairLinks`]).
fn spectral_form(inertia: &Matrix3<f64>) -> (f64, Vector3<f64>, Vector3<f64>) {
    let sym = (inertia + inertia.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let [lo, mid, hi] = order.map(|k| eig.eigenvalues[k]);
    let tiny = 1e-12 * hi.abs().max(lo.abs());
    let gap = |g: f64| if g > tiny { g.sqrt() } else { 0.0 };
    (
        mid,
        eig.eigenvectors.column(order[2]) * gap(hi - mid),
        eig.eigenvectors.column(order[0]) * gap(mid - lo),
    )
}

/// [`super::step_terms`] of two arms at once: `links` (from [`PairLinks::new`]), `kin[k]`
/// (frames for arm k's q) and `qd[k]` describe arm k; gravity and buoyancy density are
/// shared. Returns the arms' terms in order.
pub fn step_terms_pair<const N: usize>(
    links: &PairLinks<N>,
    kin: [&KinData; 2],
    qd: [&[f64; N]; 2],
    gravity: &Vector3<f64>,
    buoyancy_density_kgm3: f64,
) -> [StepTerms<N>; 2] {
    let frames = [&kin[0].joint_frames[..N], &kin[1].joint_frames[..N]];
    let revolute = &links.revolute;
    let mut z = [V::default(); N];
    let mut p = [V::default(); N];
    let mut c = [V::default(); N];
    let mut ic = [M::default(); N];
    let g = V::from_arms(gravity, gravity);
    let rho = P::splat(buoyancy_density_kgm3);
    for i in 0..N {
        let r = M::from_arms(
            frames[0][i].rotation.matrix(),
            frames[1][i].rotation.matrix(),
        );
        z[i] = r.mul_v(links.axis[i]);
        p[i] = V::from_arms(
            &frames[0][i].translation.vector,
            &frames[1][i].translation.vector,
        );
        c[i] = r.mul_v(links.com[i]);
        // R·I·Rᵀ = s·1 + (Ru)(Ru)ᵀ − (Rv)(Rv)ᵀ (see `PairLinks`).
        let mut m = M::default();
        for d in 0..3 {
            m.0[d][d] = links.iso[i];
        }
        if links.has_u[i] {
            m.add_outer(r.mul_v(links.u[i]), false);
        }
        if links.has_v[i] {
            m.add_outer(r.mul_v(links.v[i]), true);
        }
        ic[i] = m;
    }
    let mut rate = [P::default(); N];
    for i in 0..N {
        rate[i] = P([qd[0][i], qd[1][i]]);
    }
    // Forward pass with q̈ = 0 and gravity as a fictitious base acceleration.
    let mut w_of = [V::default(); N];
    let mut wd_of = [V::default(); N];
    let mut a_of = [V::default(); N];
    let (mut w, mut wd, mut a) = (V::default(), V::default(), -g);
    let mut p_prev = V::default();
    for i in 0..N {
        let d = p[i] - p_prev;
        let mut ai = a + wd.cross(d) + w.cross(w.cross(d));
        let zq = z[i].scale(rate[i]);
        if revolute[i] {
            wd += w.cross(zq);
            w += zq;
        } else {
            ai += w.cross(zq).scale(P::splat(2.0));
        }
        a = ai;
        p_prev = p[i];
        w_of[i] = w;
        wd_of[i] = wd;
        a_of[i] = a;
    }
    // Backward pass: link forces and moments (RNEA) and composite bodies (CRBA).
    let mut bias = [P::default(); N];
    let (mut f_next, mut n_next, mut p_next) = (V::default(), V::default(), p[N - 1]);
    let (mut m_acc, mut h_acc, mut i_acc) = (P::default(), V::default(), M::default());
    let (mut comp_m, mut comp_h, mut comp_i) =
        ([P::default(); N], [V::default(); N], [M::default(); N]);
    for i in (0..N).rev() {
        let mass = links.mass[i];
        let (w, wd, ci) = (w_of[i], wd_of[i], c[i]);
        let ac = a_of[i] + wd.cross(ci) + w.cross(w.cross(ci));
        // Buoyancy −g·ρV of the link (zero without water).
        let fb = (-g).scale(rho * links.volume[i]);
        let fi = ac.scale(mass) - fb;
        let f = fi + f_next;
        let iw = ic[i].mul_v(w);
        let m =
            ic[i].mul_v(wd) + w.cross(iw) + ci.cross(fi) + n_next + (p_next - p[i]).cross(f_next);
        bias[i] = if revolute[i] {
            z[i].dot(m)
        } else {
            z[i].dot(f)
        };
        (f_next, n_next, p_next) = (f, m, p[i]);
        // Composite inertia about the base origin; parallel axis I_O = I_c + m(|x|²1 − x xᵀ).
        let x = p[i] + ci;
        m_acc += mass;
        h_acc += x.scale(mass);
        let x2 = x.dot(x);
        let mut parallel = M::default();
        for r in 0..3 {
            for col in 0..3 {
                let diag = if r == col { x2 } else { P::default() };
                parallel.0[r][col] = (diag - x.0[r] * x.0[col]) * mass;
            }
        }
        i_acc = i_acc.add(&ic[i].add(&parallel));
        (comp_m[i], comp_h[i], comp_i[i]) = (m_acc, h_acc, i_acc);
    }
    // Mass matrix columns from the axis moments μᵢ = zᵢ × pᵢ (see `super::step_terms`).
    let mut mu = [V::default(); N];
    for i in 0..N {
        mu[i] = z[i].cross(p[i]);
    }
    let mut h = [[P::default(); N]; N];
    for j in 0..N {
        let (m, hj, io) = (comp_m[j], comp_h[j], &comp_i[j]);
        let zj = z[j];
        let (f, n0) = if revolute[j] {
            (zj.cross(hj - p[j].scale(m)), io.mul_v(zj) - hj.cross(mu[j]))
        } else {
            (zj.scale(m), hj.cross(zj))
        };
        for i in 0..=j {
            let hij = if revolute[i] {
                z[i].dot(n0) - mu[i].dot(f)
            } else {
                z[i].dot(f)
            };
            h[i][j] = hij;
            h[j][i] = hij;
        }
    }
    let tool = V::from_arms(&kin[0].tool_point, &kin[1].tool_point);
    let r = tool - p[N - 1];
    let (w, wd) = (w_of[N - 1], wd_of[N - 1]);
    let acc = a_of[N - 1] + g + wd.cross(r) + w.cross(w.cross(r));
    let mut out = [StepTerms {
        mass_matrix: SMatrix::zeros(),
        bias: SVector::zeros(),
        tool_bias: [0.0; 6],
    }; 2];
    for (k, t) in out.iter_mut().enumerate() {
        for i in 0..N {
            for j in 0..N {
                t.mass_matrix[(i, j)] = h[i][j].0[k];
            }
            t.bias[i] = bias[i].0[k];
        }
        let (acc, wd) = (acc.arm(k), wd.arm(k));
        t.tool_bias = [acc.x, acc.y, acc.z, wd.x, wd.y, wd.z];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ModelSpec, robots};

    fn magnum() -> Model {
        let spec: ModelSpec =
            serde_json::from_str(robots::builtin_text("magnum").expect("built-in")).expect("json");
        Model::from_spec(&spec).expect("model")
    }

    /// The Magnum's rod inertias, and the same links with a point mass off every axis (a
    /// general inertia, with three distinct eigenvalues, so both spectral terms are used).
    fn inertial_sets(m: &Model) -> [Inertials; 2] {
        let rods = Inertials::magnum(m).expect("inertials");
        let mut general = rods.clone();
        for (i, l) in general.links.iter_mut().enumerate() {
            let at = Vector3::new(0.05, -0.03 * i as f64, 0.02 + 0.01 * i as f64);
            *l = l.with_point_mass(&at, 1.5);
        }
        [rods, general]
    }

    /// The spectral form reproduces the inertia (closed form: s·1 + u·uᵀ − v·vᵀ = I) and, for
    /// a rod, has a single term.
    #[test]
    fn spectral_form_reproduces_the_inertia() {
        let m = magnum();
        for set in inertial_sets(&m) {
            for l in &set.links {
                let (s, u, v) = spectral_form(&l.inertia_kgm2);
                let back = Matrix3::identity() * s + u * u.transpose() - v * v.transpose();
                let scale = l.inertia_kgm2.norm();
                assert!(
                    (back - l.inertia_kgm2).norm() < 1e-14 * scale,
                    "{back} vs {l:?}"
                );
            }
        }
        let rods = &inertial_sets(&m)[0];
        for l in &rods.links {
            let (_, u, v) = spectral_form(&l.inertia_kgm2);
            assert!(
                u == Vector3::zeros() || v == Vector3::zeros(),
                "rod: one term"
            );
        }
    }

    /// Each lane equals the one-arm `step_terms` (the reference, itself tested against RNEA
    /// and CRBA) for two arms at different postures and rates, with and without buoyancy,
    /// for rod and general link inertias.
    #[test]
    fn each_lane_matches_the_one_arm_terms() {
        let m = magnum();
        let right = m.based_at(&nalgebra::Isometry3::translation(0.0, -1.0, 0.1));
        let postures = [
            (
                [0.1, 0.5, -1.0, 0.3, -0.2, 0.7],
                [0.2, -0.1, 0.3, 0.5, -0.4, 1.5],
            ),
            ([-0.3, 1.2, -2.0, -0.8, 0.9, -3.0], [0.0; 6]),
        ];
        let g = Vector3::new(0.0, 0.0, -9.81);
        let sets = inertial_sets(&m);
        // Rods on both arms, general on both, and one of each (lanes with and without the
        // second spectral term).
        for (li, ri) in [(0, 0), (1, 1), (0, 1)] {
            let (inl, inr) = (&sets[li], &sets[ri]);
            let links = PairLinks::<6>::new([&m, &right], [inl, inr]).expect("same joint kinds");
            for (k, (q0, qd0)) in postures.iter().enumerate() {
                let (q1, qd1) = &postures[1 - k];
                let mut kin0 = KinData::new(&m);
                let mut kin1 = KinData::new(&right);
                crate::kinematics::jacobian(&m, &mut kin0, q0);
                crate::kinematics::jacobian(&right, &mut kin1, q1);
                for rho in [0.0, 1025.0] {
                    let pair = step_terms_pair::<6>(&links, [&kin0, &kin1], [qd0, qd1], &g, rho);
                    let one = [
                        super::super::step_terms::<6>(&m, inl, &kin0, qd0, &g, rho),
                        super::super::step_terms::<6>(&right, inr, &kin1, qd1, &g, rho),
                    ];
                    for a in 0..2 {
                        let scale = one[a].mass_matrix.norm();
                        assert!((pair[a].mass_matrix - one[a].mass_matrix).norm() < 1e-13 * scale);
                        let bscale = one[a].bias.norm().max(1.0);
                        assert!((pair[a].bias - one[a].bias).norm() < 1e-12 * bscale);
                        for i in 0..6 {
                            let t = one[a].tool_bias[i];
                            assert!((pair[a].tool_bias[i] - t).abs() < 1e-12 * t.abs().max(1.0));
                        }
                    }
                }
            }
        }
    }

    /// Arms whose joints differ in kind are refused (the caller falls back).
    #[test]
    fn refuses_different_joint_kinds() {
        let m = magnum();
        let mut other = m.clone();
        other.joints[2].kind = JointKind::Prismatic;
        let inertials = Inertials::magnum(&m).expect("inertials");
        assert!(PairLinks::<6>::new([&m, &other], [&inertials, &inertials]).is_none());
        assert!(PairLinks::<7>::new([&m, &m], [&inertials, &inertials]).is_none());
    }
}
