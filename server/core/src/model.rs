//! Robot models: a serial chain of joints, each a fixed transform plus a joint axis.
//!
//! Every convention the source documents use loads into this one representation:
//!
//! * standard DH (Lim eq. 2.1): `A_i = Rz(θ_i + q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)`;
//! * the thesis's variant for Magnum link 5 (Lim eq. 3.1): the twist is `Ry(α_i)` instead of `Rx(α_i)`;
//! * modified DH (Craig / Khalil–Kleinfinger, RX90 report): `A_i = Rx(α_i)·Tx(a_i)·Rz(θ_i + q_i)·Tz(d_i)`.
//!
//! A [`Joint`] moves about (or along) `axis` of its own frame, which sits at `origin` in the
//! frame of the previous joint (after that joint's motion). Standard DH puts the motion first
//! and the fixed part after it, so joint `i`'s fixed part becomes joint `i+1`'s `origin`, and
//! the last one becomes the model's `flange`.

use nalgebra::{Isometry3, IsometryMatrix3, Matrix3, Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::Error;

/// Revolute (angle, rad) or prismatic (displacement, m) joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Rotation about the joint axis; q in rad, q̇ in rad/s.
    Revolute,
    /// Translation along the joint axis; q in m, q̇ in m/s.
    Prismatic,
}

/// One joint of a serial chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Name shown to users (e.g. "shoulder").
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Fixed transform from the previous joint's moving frame (or the base) to this joint's frame
    /// (rotation stored as a matrix: forward kinematics multiplies matrices).
    pub origin: IsometryMatrix3<f64>,
    /// `origin`'s rotation in the form forward kinematics applies it.
    pub origin_rotation: FixedRotation,
    /// Motion axis, unit, in this joint's frame (z for every DH convention).
    pub axis: Unit<Vector3<f64>>,
    /// Added to q before the motion: DH θ for revolute joints, DH d for prismatic ones.
    pub offset: f64,
    /// Position limits [lo, hi] (rad or m); ±∞ when the joint is unlimited.
    pub limits: [f64; 2],
    /// Velocity limit (rad/s or m/s), > 0.
    pub max_velocity: f64,
}

/// `r`·R_z(v) given s = sin v, c = cos v: only the first two columns change, to
/// c·r₀ + s·r₁ and c·r₁ − s·r₀.
pub(crate) fn turn_about_z(r: &Matrix3<f64>, s: f64, c: f64) -> Matrix3<f64> {
    let (c0, c1) = (r.column(0).into_owned(), r.column(1).into_owned());
    let mut out = *r;
    out.set_column(0, &(c0 * c + c1 * s));
    out.set_column(1, &(c1 * c - c0 * s));
    out
}

impl Joint {
    /// `r`·R(axis, q + offset): a frame's rotation followed by this revolute joint's motion.
    /// For the z axis of every DH convention only two columns change (c·r₀ + s·r₁,
    /// −s·r₀ + c·r₁), which is what forward kinematics spends its time on.
    pub fn rotate_frame(&self, r: &Matrix3<f64>, q: f64) -> Matrix3<f64> {
        let v = q + self.offset;
        let a = self.axis.into_inner();
        if a.x == 0.0 && a.y == 0.0 {
            // ±z: the frame turned by ±v.
            let (s, c) = (v * a.z.signum()).sin_cos();
            turn_about_z(r, s, c)
        } else {
            // Not produced by any DH convention.
            r * Rotation3::from_axis_angle(&self.axis, v).matrix()
        }
    }

    /// True when both limits are finite.
    pub fn is_limited(&self) -> bool {
        self.limits[0].is_finite() && self.limits[1].is_finite()
    }
}

/// A serial robot: joints from base to tip, the flange transform and an optional tool point.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Short name, e.g. "magnum".
    pub name: String,
    /// Where the numbers come from.
    pub source: String,
    /// Joints from base to tip.
    pub joints: Vec<Joint>,
    /// Fixed transform from the last joint's moving frame to the last link frame.
    pub flange: IsometryMatrix3<f64>,
    /// `flange`'s rotation in the form forward kinematics applies it.
    pub flange_rotation: FixedRotation,
    /// Tool point in the last link frame (m); zero when the reference point is the flange origin.
    pub tool: Vector3<f64>,
    /// The specification this model was built from (returned by the API).
    pub spec: ModelSpec,
}

impl Model {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Checks that `q` has one finite value per joint.
    pub fn check_q(&self, q: &[f64]) -> Result<(), Error> {
        if q.len() != self.dof() {
            return Err(Error::SizeMismatch {
                what: "q",
                input: q.len(),
                required: self.dof(),
            });
        }
        if let Some(index) = q.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite { what: "q", index });
        }
        Ok(())
    }

    /// The same robot with its base frame placed at `base`: forward kinematics, Jacobians and
    /// the dynamics then come out in the frame `base` is given in (e.g. the world of a
    /// two-arm simulation) with no transformation afterwards.
    pub fn based_at(&self, base: &Isometry3<f64>) -> Model {
        let mut m = self.clone();
        if let Some(first) = m.joints.first_mut() {
            let (origin, form) = FixedRotation::of(&(as_matrix_isometry(base) * first.origin));
            first.origin = origin;
            first.origin_rotation = form;
        }
        m
    }

    /// Lower and upper position limits as two vectors.
    pub fn limits(&self) -> (Vec<f64>, Vec<f64>) {
        self.joints
            .iter()
            .map(|j| (j.limits[0], j.limits[1]))
            .unzip()
    }

    /// Velocity limits, one per joint.
    pub fn max_velocities(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.max_velocity).collect()
    }

    /// Builds a model from its specification, validating every number.
    pub fn from_spec(spec: &ModelSpec) -> Result<Model, Error> {
        if spec.joints.is_empty() {
            return Err(Error::InvalidModel {
                reason: "a model needs at least one joint".into(),
            });
        }
        if spec.joints.len() > MAX_JOINTS {
            return Err(Error::InvalidModel {
                reason: format!("at most {MAX_JOINTS} joints are supported"),
            });
        }
        let mut joints = Vec::with_capacity(spec.joints.len());
        // Standard DH: the fixed part of joint i is the origin of joint i+1.
        let mut pending = Isometry3::identity();
        for (i, js) in spec.joints.iter().enumerate() {
            js.validate(i)?;
            let (lo, hi) = match js.limits {
                Some([lo, hi]) => (lo, hi),
                None => (f64::NEG_INFINITY, f64::INFINITY),
            };
            let max_velocity = js.max_velocity.unwrap_or(1.0);
            let name = js
                .name
                .clone()
                .unwrap_or_else(|| format!("joint {}", i + 1));
            let z = Vector3::z_axis();
            let (origin, offset, post) = match spec.dh {
                DhConvention::Standard => {
                    let twist = twist(js.twist_axis, js.alpha);
                    match js.kind {
                        // Rz(θ+q)·Tz(d)·Tx(a)·R(α): motion first, fixed part after.
                        JointKind::Revolute => (pending, js.theta, tz(js.d) * tx(js.a) * twist),
                        // Rz(θ)·Tz(d+q)·Tx(a)·R(α) = Tz(d+q)·Rz(θ)·Tx(a)·R(α).
                        JointKind::Prismatic => (pending, js.d, rz(js.theta) * tx(js.a) * twist),
                    }
                }
                DhConvention::Modified => {
                    if js.twist_axis != TwistAxis::X {
                        return Err(Error::InvalidModel {
                            reason: format!(
                                "joint {}: twist_axis \"y\" is only defined for standard DH (Lim eq. 3.1)",
                                i + 1
                            ),
                        });
                    }
                    let base = pending * rx(js.alpha) * tx(js.a);
                    match js.kind {
                        // Rx(α)·Tx(a)·Rz(θ+q)·Tz(d) = Rx(α)·Tx(a)·Tz(d)·Rz(θ)·Rz(q).
                        JointKind::Revolute => {
                            (base * tz(js.d) * rz(js.theta), 0.0, Isometry3::identity())
                        }
                        // Rx(α)·Tx(a)·Rz(θ)·Tz(d+q).
                        JointKind::Prismatic => (base * rz(js.theta), js.d, Isometry3::identity()),
                    }
                }
            };
            let (origin, origin_rotation) = FixedRotation::of(&as_matrix_isometry(&origin));
            joints.push(Joint {
                name,
                kind: js.kind,
                origin,
                origin_rotation,
                axis: z,
                offset,
                limits: [lo, hi],
                max_velocity,
            });
            pending = post;
        }
        let tool = match spec.tool {
            Some(t) => {
                if t.iter().any(|v| !v.is_finite() || v.abs() > MAX_LENGTH_M) {
                    return Err(Error::InvalidModel {
                        reason: format!("tool must be finite and within ±{MAX_LENGTH_M} m"),
                    });
                }
                Vector3::new(t[0], t[1], t[2])
            }
            None => Vector3::zeros(),
        };
        if let Some(c) = &spec.collision {
            c.check(spec.joints.len())?;
        }
        let (flange, flange_rotation) = FixedRotation::of(&as_matrix_isometry(&pending));
        Ok(Model {
            name: spec.name.clone(),
            source: spec.source.clone().unwrap_or_default(),
            joints,
            flange,
            flange_rotation,
            tool,
            spec: spec.clone(),
        })
    }
}

/// A fixed rotation of the chain (a joint's origin, the flange) in the form forward kinematics
/// applies it. DH twists of 0 and ±90° — most of them — only permute and negate the columns
/// of the frame they follow: R·M is then a shuffle of R's columns instead of a 3×3 product.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FixedRotation {
    /// M = I.
    Identity,
    /// Column k of R·M is `sign[k]` × column `col[k]` of R (M a signed permutation).
    Permutation {
        /// Source column of R for each column of the product.
        col: [usize; 3],
        /// ±1.
        sign: [f64; 3],
    },
    /// Any other rotation M.
    General(Matrix3<f64>),
}

impl FixedRotation {
    /// Entries this close to 0 or ±1 are taken as exact: a 90° twist built through a
    /// quaternion comes out with round-off of ~1e-16 in its zero entries.
    pub const SNAP: f64 = 1e-12;

    /// Classifies the rotation of `t`; returns `t` with that rotation snapped to exact 0/±1
    /// entries when it is a signed permutation (a change below [`Self::SNAP`]), and the form.
    pub fn of(t: &IsometryMatrix3<f64>) -> (IsometryMatrix3<f64>, FixedRotation) {
        let m = t.rotation.matrix();
        let mut col = [0; 3];
        let mut sign = [0.0; 3];
        let mut exact = Matrix3::zeros();
        for k in 0..3 {
            // Column k of M must be ±e_c for one c.
            let unit: Vec<usize> = (0..3)
                .filter(|&r| (m[(r, k)].abs() - 1.0).abs() < Self::SNAP)
                .collect();
            let zeros = (0..3).filter(|&r| m[(r, k)].abs() < Self::SNAP).count();
            if unit.len() != 1 || zeros != 2 {
                return (*t, FixedRotation::General(*m));
            }
            col[k] = unit[0];
            sign[k] = m[(unit[0], k)].signum();
            exact[(unit[0], k)] = sign[k];
        }
        let snapped =
            IsometryMatrix3::from_parts(t.translation, Rotation3::from_matrix_unchecked(exact));
        let form = if exact == Matrix3::identity() {
            FixedRotation::Identity
        } else {
            FixedRotation::Permutation { col, sign }
        };
        (snapped, form)
    }

    /// R·M.
    pub fn after(&self, r: &Matrix3<f64>) -> Matrix3<f64> {
        match self {
            FixedRotation::Identity => *r,
            FixedRotation::Permutation { col, sign } => Matrix3::from_columns(&[
                r.column(col[0]) * sign[0],
                r.column(col[1]) * sign[1],
                r.column(col[2]) * sign[2],
            ]),
            FixedRotation::General(m) => r * m,
        }
    }
}

/// Largest number of joints a model may have.
pub const MAX_JOINTS: usize = 32;
/// Largest link length or offset accepted (m).
pub const MAX_LENGTH_M: f64 = 1.0e3;

/// The same rigid transform with its rotation as a matrix.
pub fn as_matrix_isometry(t: &Isometry3<f64>) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(t.translation, t.rotation.to_rotation_matrix())
}

fn rz(t: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::z() * t)
}
fn rx(t: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * t)
}
fn ry(t: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::y() * t)
}
fn tx(a: f64) -> Isometry3<f64> {
    Isometry3::translation(a, 0.0, 0.0)
}
fn tz(d: f64) -> Isometry3<f64> {
    Isometry3::translation(0.0, 0.0, d)
}
fn twist(axis: TwistAxis, alpha: f64) -> Isometry3<f64> {
    match axis {
        TwistAxis::X => rx(alpha),
        TwistAxis::Y => ry(alpha),
    }
}

/// Which DH convention a specification's joint parameters follow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DhConvention {
    /// `Rz(θ+q)·Tz(d)·Tx(a)·Rx(α)` (Lim eq. 2.1).
    Standard,
    /// `Rx(α)·Tx(a)·Rz(θ+q)·Tz(d)` (Craig; Khalil–Kleinfinger).
    Modified,
}

/// Axis of the DH twist rotation: x (usual) or y (Lim eq. 3.1, Magnum link 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TwistAxis {
    /// `Rx(α)`.
    #[default]
    X,
    /// `Ry(α)`.
    Y,
}

fn is_default_twist(t: &TwistAxis) -> bool {
    *t == TwistAxis::X
}

/// The inline-model schema of the HTTP API; built-in models are stored in it too.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Short name.
    pub name: String,
    /// Where the numbers come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// DH convention of the joint parameters.
    pub dh: DhConvention,
    /// Joints from base to tip.
    pub joints: Vec<JointSpec>,
    /// Tool point in the last link frame (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<[f64; 3]>,
    /// Free-form notes (how values were chosen).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub notes: Option<String>,
    /// Collision shapes of the links and the jaw ([`crate::collision`]); a model without them
    /// collides with nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collision: Option<crate::collision::CollisionSpec>,
}

/// One row of a DH table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Optional name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Revolute or prismatic.
    #[serde(rename = "type")]
    pub kind: JointKind,
    /// Link length a (m).
    #[serde(default)]
    pub a: f64,
    /// Link twist α (rad).
    #[serde(default)]
    pub alpha: f64,
    /// Link offset d (m).
    #[serde(default)]
    pub d: f64,
    /// Joint angle offset θ (rad).
    #[serde(default)]
    pub theta: f64,
    /// Axis of the twist rotation (standard DH only; "y" for Lim eq. 3.1).
    #[serde(default, skip_serializing_if = "is_default_twist")]
    pub twist_axis: TwistAxis,
    /// Position limits [lo, hi] (rad or m); unlimited when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<[f64; 2]>,
    /// Velocity limit (rad/s or m/s); 1 when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity: Option<f64>,
}

impl JointSpec {
    fn validate(&self, i: usize) -> Result<(), Error> {
        let bad = |reason: String| {
            Err(Error::InvalidModel {
                reason: format!("joint {}: {reason}", i + 1),
            })
        };
        for (name, v, max) in [
            ("a", self.a, MAX_LENGTH_M),
            ("d", self.d, MAX_LENGTH_M),
            ("alpha", self.alpha, 1.0e3),
            ("theta", self.theta, 1.0e3),
        ] {
            if !v.is_finite() || v.abs() > max {
                return bad(format!("{name} must be finite and within ±{max}"));
            }
        }
        if let Some([lo, hi]) = self.limits {
            if lo.is_nan() || hi.is_nan() || lo >= hi {
                return bad("limits must be [lo, hi] with lo < hi".into());
            }
        }
        if let Some(v) = self.max_velocity {
            if !v.is_finite() || v <= 0.0 || v > 1.0e6 {
                return bad("max_velocity must be finite and > 0".into());
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R·M through [`FixedRotation::after`] equals the matrix product for twists of 0, ±90°,
    /// 180° about x and y (signed permutations) and for a general angle; the snapped matrix
    /// differs from the quaternion-built one by round-off only.
    #[test]
    fn fixed_rotation_matches_the_matrix_product() {
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let cases = [
            (rx(0.0), "identity"),
            (rx(std::f64::consts::FRAC_PI_2), "perm"),
            (rx(-std::f64::consts::FRAC_PI_2), "perm"),
            (ry(std::f64::consts::FRAC_PI_2), "perm"),
            (rx(std::f64::consts::PI), "perm"),
            (rx(0.7), "general"),
            (rz(0.2) * rx(std::f64::consts::FRAC_PI_2), "general"),
        ];
        for (t, expect) in cases {
            let m = as_matrix_isometry(&t);
            let (snapped, form) = FixedRotation::of(&m);
            let kind = match form {
                FixedRotation::Identity => "identity",
                FixedRotation::Permutation { .. } => "perm",
                FixedRotation::General(_) => "general",
            };
            assert_eq!(kind, expect, "{t:?}");
            let exact = r * m.rotation.matrix();
            assert!((form.after(&r) - exact).norm() < 1e-15);
            assert!((snapped.rotation.matrix() - m.rotation.matrix()).norm() < 1e-15);
            assert_eq!(snapped.translation, m.translation);
        }
    }

    /// A model placed at a base gives the base-frame results composed with the base:
    /// tool pose T_world = B·T and Jacobian blockdiag(R_B, R_B)·J (Magnum, Lim Table 3-1).
    #[test]
    fn based_at_composes_the_base() {
        let spec: ModelSpec =
            serde_json::from_str(crate::robots::builtin_text("magnum").unwrap()).expect("parses");
        let m = Model::from_spec(&spec).expect("builds");
        let base = Isometry3::from_parts(
            nalgebra::Translation3::new(0.3, 1.0, -0.2),
            nalgebra::UnitQuaternion::from_euler_angles(0.1, -0.4, 0.9),
        );
        let placed = m.based_at(&base);
        let q = [0.2, 0.7, -1.2, 0.3, -0.5, 1.0];
        let t = crate::kinematics::end_effector_pose(&m, &q);
        let tw = crate::kinematics::end_effector_pose(&placed, &q);
        let expect = base * t;
        assert!((tw.translation.vector - expect.translation.vector).norm() < 1e-14);
        assert!(tw.rotation.angle_to(&expect.rotation) < 1e-12);
        let j = crate::kinematics::jacobian_at(&m, &q);
        let jw = crate::kinematics::jacobian_at(&placed, &q);
        let rb = base.rotation.to_rotation_matrix().into_inner();
        for k in 0..6 {
            let lin: Vector3<f64> = rb * j.fixed_view::<3, 1>(0, k);
            let ang: Vector3<f64> = rb * j.fixed_view::<3, 1>(3, k);
            assert!((jw.fixed_view::<3, 1>(0, k) - lin).norm() < 1e-14);
            assert!((jw.fixed_view::<3, 1>(3, k) - ang).norm() < 1e-14);
        }
    }
}
