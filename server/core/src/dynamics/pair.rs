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

use std::ops::{Add, AddAssign, Mul, Neg, Sub};

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::{Inertials, StepTerms};
use crate::kinematics::KinData;
use crate::model::{JointKind, Model};

/// One number for each arm.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct P([f64; 2]);

impl P {
    #[inline(always)]
    fn splat(x: f64) -> P {
        P([x, x])
    }
}

impl Add for P {
    type Output = P;
    #[inline(always)]
    fn add(self, o: P) -> P {
        P([self.0[0] + o.0[0], self.0[1] + o.0[1]])
    }
}
impl Sub for P {
    type Output = P;
    #[inline(always)]
    fn sub(self, o: P) -> P {
        P([self.0[0] - o.0[0], self.0[1] - o.0[1]])
    }
}
impl Mul for P {
    type Output = P;
    #[inline(always)]
    fn mul(self, o: P) -> P {
        P([self.0[0] * o.0[0], self.0[1] * o.0[1]])
    }
}
impl Neg for P {
    type Output = P;
    #[inline(always)]
    fn neg(self) -> P {
        P([-self.0[0], -self.0[1]])
    }
}
impl AddAssign for P {
    #[inline(always)]
    fn add_assign(&mut self, o: P) {
        *self = *self + o;
    }
}

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
    /// A·B.
    #[inline(always)]
    fn mul_m(&self, b: &M) -> M {
        let mut m = M::default();
        for r in 0..3 {
            for c in 0..3 {
                let a = &self.0[r];
                m.0[r][c] = a[0] * b.0[0][c] + a[1] * b.0[1][c] + a[2] * b.0[2][c];
            }
        }
        m
    }
    /// A·Bᵀ.
    #[inline(always)]
    fn mul_mt(&self, b: &M) -> M {
        let mut m = M::default();
        for r in 0..3 {
            for c in 0..3 {
                let (a, bc) = (&self.0[r], &b.0[c]);
                m.0[r][c] = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
            }
        }
        m
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

/// [`super::step_terms`] of two arms at once: `models[k]`, `inertials[k]`, `kin[k]` (frames
/// for the arm's q) and `qd[k]` describe arm k; gravity and buoyancy density are shared.
/// Returns the arms' terms in order, or `None` when the arms' joints differ in kind (then use
/// the one-arm function). The models must have at least N joints (as for the one-arm one).
pub fn step_terms_pair<const N: usize>(
    models: [&Model; 2],
    inertials: [&Inertials; 2],
    kin: [&KinData; 2],
    qd: [&[f64; N]; 2],
    gravity: &Vector3<f64>,
    buoyancy_density_kgm3: f64,
) -> Option<[StepTerms<N>; 2]> {
    let joints = [&models[0].joints[..N], &models[1].joints[..N]];
    if (0..N).any(|i| joints[0][i].kind != joints[1][i].kind) {
        return None;
    }
    let links = [&inertials[0].links[..N], &inertials[1].links[..N]];
    let frames = [&kin[0].joint_frames[..N], &kin[1].joint_frames[..N]];
    let mut revolute = [false; N];
    for i in 0..N {
        revolute[i] = joints[0][i].kind == JointKind::Revolute;
    }
    let mut z = [V::default(); N];
    let mut p = [V::default(); N];
    let mut c = [V::default(); N];
    let mut ic = [M::default(); N];
    let mut mass = [P::default(); N];
    let mut fb = [V::default(); N];
    let g = V::from_arms(gravity, gravity);
    for i in 0..N {
        let r = M::from_arms(
            frames[0][i].rotation.matrix(),
            frames[1][i].rotation.matrix(),
        );
        z[i] = r.mul_v(V::from_arms(
            &joints[0][i].axis.into_inner(),
            &joints[1][i].axis.into_inner(),
        ));
        p[i] = V::from_arms(
            &frames[0][i].translation.vector,
            &frames[1][i].translation.vector,
        );
        c[i] = r.mul_v(V::from_arms(&links[0][i].com_m, &links[1][i].com_m));
        let inertia = M::from_arms(&links[0][i].inertia_kgm2, &links[1][i].inertia_kgm2);
        ic[i] = r.mul_m(&inertia).mul_mt(&r);
        mass[i] = P([links[0][i].mass_kg, links[1][i].mass_kg]);
        // Buoyancy −g·ρV of each link (zero without water).
        fb[i] = (-g).scale(P([
            buoyancy_density_kgm3 * links[0][i].volume_m3,
            buoyancy_density_kgm3 * links[1][i].volume_m3,
        ]));
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
        let (w, wd, ci) = (w_of[i], wd_of[i], c[i]);
        let ac = a_of[i] + wd.cross(ci) + w.cross(w.cross(ci));
        let fi = ac.scale(mass[i]) - fb[i];
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
        m_acc += mass[i];
        h_acc += x.scale(mass[i]);
        let x2 = x.dot(x);
        let mut parallel = M::default();
        for r in 0..3 {
            for col in 0..3 {
                let diag = if r == col { x2 } else { P::default() };
                parallel.0[r][col] = (diag - x.0[r] * x.0[col]) * mass[i];
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
    Some(out)
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

    /// Each lane equals the one-arm `step_terms` (the reference, itself tested against RNEA
    /// and CRBA) for two arms at different postures and rates, with and without buoyancy.
    #[test]
    fn each_lane_matches_the_one_arm_terms() {
        let m = magnum();
        let right = m.based_at(&nalgebra::Isometry3::translation(0.0, -1.0, 0.1));
        let inertials = Inertials::magnum(&m).expect("inertials");
        let postures = [
            (
                [0.1, 0.5, -1.0, 0.3, -0.2, 0.7],
                [0.2, -0.1, 0.3, 0.5, -0.4, 1.5],
            ),
            ([-0.3, 1.2, -2.0, -0.8, 0.9, -3.0], [0.0; 6]),
        ];
        let g = Vector3::new(0.0, 0.0, -9.81);
        for (k, (q0, qd0)) in postures.iter().enumerate() {
            let (q1, qd1) = &postures[1 - k];
            let mut kin0 = KinData::new(&m);
            let mut kin1 = KinData::new(&right);
            crate::kinematics::jacobian(&m, &mut kin0, q0);
            crate::kinematics::jacobian(&right, &mut kin1, q1);
            for rho in [0.0, 1025.0] {
                let pair = step_terms_pair::<6>(
                    [&m, &right],
                    [&inertials, &inertials],
                    [&kin0, &kin1],
                    [qd0, qd1],
                    &g,
                    rho,
                )
                .expect("same joint kinds");
                let one = [
                    super::super::step_terms::<6>(&m, &inertials, &kin0, qd0, &g, rho),
                    super::super::step_terms::<6>(&right, &inertials, &kin1, qd1, &g, rho),
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

    /// Arms whose joints differ in kind are refused (the caller falls back).
    #[test]
    fn refuses_different_joint_kinds() {
        let m = magnum();
        let mut other = m.clone();
        other.joints[2].kind = JointKind::Prismatic;
        let inertials = Inertials::magnum(&m).expect("inertials");
        let kin = KinData::new(&m);
        let qd = [0.0; 6];
        let g = Vector3::new(0.0, 0.0, -9.81);
        assert!(
            step_terms_pair::<6>(
                [&m, &other],
                [&inertials, &inertials],
                [&kin, &kin],
                [&qd, &qd],
                &g,
                0.0
            )
            .is_none()
        );
    }
}
