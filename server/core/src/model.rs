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
    /// Motion axis, unit, in this joint's frame (z for every DH convention).
    pub axis: Unit<Vector3<f64>>,
    /// Added to q before the motion: DH θ for revolute joints, DH d for prismatic ones.
    pub offset: f64,
    /// Position limits [lo, hi] (rad or m); ±∞ when the joint is unlimited.
    pub limits: [f64; 2],
    /// Velocity limit (rad/s or m/s), > 0.
    pub max_velocity: f64,
}

impl Joint {
    /// `r`·R(axis, q + offset): a frame's rotation followed by this revolute joint's motion.
    /// For the z axis of every DH convention only two columns change (c·r₀ + s·r₁,
    /// −s·r₀ + c·r₁), which is what forward kinematics spends its time on.
    #[inline]
    pub fn rotate_frame(&self, r: &Matrix3<f64>, q: f64) -> Matrix3<f64> {
        let v = q + self.offset;
        let a = self.axis.into_inner();
        if a.x == 0.0 && a.y == 0.0 {
            let (s, c) = (v * a.z.signum()).sin_cos();
            let (c0, c1) = (r.column(0).into_owned(), r.column(1).into_owned());
            let mut out = *r;
            out.set_column(0, &(c0 * c + c1 * s));
            out.set_column(1, &(c1 * c - c0 * s));
            out
        } else {
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
            joints.push(Joint {
                name,
                kind: js.kind,
                origin: as_matrix_isometry(&origin),
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
        Ok(Model {
            name: spec.name.clone(),
            source: spec.source.clone().unwrap_or_default(),
            joints,
            flange: as_matrix_isometry(&pending),
            tool,
            spec: spec.clone(),
        })
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
