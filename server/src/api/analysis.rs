//! `POST /api/analysis` (one arm) and `POST /api/analysis/dual` (two arms, Lim eq. 3.68).

use std::sync::Arc;

use axum::Json;
use axum::extract::State;
use nalgebra::{DMatrix, Matrix3};
use seaarms_core::analysis::{TRANSLATIONAL_ROWS, analyze};
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::polytope::{self, Polytope};
use seaarms_core::manipulability::{dual_measures, measures};
use seaarms_core::model::Model;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::wire::{MeasuresOut, PoseOut, columns, rows};
use crate::app::AppState;
use crate::compute::ComputeError;
use crate::error::ApiError;
use crate::json::ApiJson;
use crate::limits::{MAX_ABS_Q, MAX_POSITION_M};

/// Body of `POST /api/analysis`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisRequest {
    /// Built-in name or inline model.
    pub robot: Value,
    /// Joint values (rad / m), one per joint.
    pub q: Vec<f64>,
    /// Task rows of the 6×n Jacobian (0..6: vx vy vz wx wy wz), for Jun's TOMM.
    #[serde(default)]
    pub rows: Option<Vec<usize>>,
    /// Also compute the translational velocity polytope: over the requested `rows` when
    /// they are two or three of vx, vy, vz (two rows: a planar task, the 2-D zonogon of
    /// Kilic Fig. 4.2), else over vx vy vz.
    #[serde(default)]
    pub polytope: bool,
    /// The polytope's joint-rate bounds: `limits` (each joint's `max_velocity`, default) or
    /// `unit` (|q̇ᵢ| ≤ 1, the constraint the unit-norm ellipsoid is drawn for, so Kilic's
    /// "polytope vs ellipsoid" comparison is on the same joint rates).
    #[serde(default)]
    pub polytope_rates: PolytopeRates,
}

/// Joint-rate bounds of a velocity polytope.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PolytopeRates {
    /// Each joint's `max_velocity`.
    #[default]
    Limits,
    /// |q̇ᵢ| ≤ 1 for every joint.
    Unit,
}

/// The rows a polytope is built over: the requested translational rows (2 or 3 of them),
/// else vx vy vz.
fn polytope_rows(rows: Option<&[usize]>) -> Vec<usize> {
    match rows {
        Some(r)
            if (2..=3).contains(&r.len()) && r.iter().all(|i| TRANSLATIONAL_ROWS.contains(i)) =>
        {
            r.to_vec()
        }
        _ => TRANSLATIONAL_ROWS.to_vec(),
    }
}

/// Measures of every row selection.
#[derive(Debug, Serialize)]
pub struct MeasureSet {
    /// All six rows.
    pub full: MeasuresOut,
    /// vx vy vz (Lim eq. 3.62).
    pub translational: MeasuresOut,
    /// wx wy wz (Lim eq. 3.63).
    pub rotational: MeasuresOut,
    /// The requested task rows (Jun eq. 4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub task: Option<MeasuresOut>,
}

/// Response of `POST /api/analysis`.
#[derive(Debug, Serialize)]
pub struct AnalysisResponse {
    /// Model name.
    pub robot: String,
    /// End-effector pose (tool point; flange orientation), base frame.
    pub pose: PoseOut,
    /// Joint frames after their motion (z = joint axis), base frame.
    pub joint_frames: Vec<PoseOut>,
    /// 6×n, base frame, rows vx vy vz wx wy wz, reference point = tool point.
    pub jacobian: Vec<Vec<f64>>,
    /// 6×n, end-effector frame.
    pub jacobian_end_effector: Vec<Vec<f64>>,
    /// Measures.
    pub measures: MeasureSet,
    /// Joint-limit measure (Jun eq. 16).
    pub jlm: f64,
    /// ∂JLM/∂q.
    pub jlm_gradient: Vec<f64>,
    /// Orthonormal basis of the null space of the full Jacobian.
    pub null_space: Vec<Vec<f64>>,
    /// The other SVD subspaces (RX90 report part VI).
    pub subspaces: SubspacesOut,
    /// Translational velocity polytope, when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polytope: Option<PolytopeOut>,
}

/// SVD subspaces.
#[derive(Debug, Serialize)]
pub struct SubspacesOut {
    /// Rank used.
    pub rank: usize,
    /// Joint velocities that generate end-effector motion.
    pub generating: Vec<Vec<f64>>,
    /// Achievable end-effector velocities.
    pub range: Vec<Vec<f64>>,
    /// End-effector velocities that cannot be generated.
    pub unreachable: Vec<Vec<f64>>,
}

/// A velocity polytope.
#[derive(Debug, Serialize)]
pub struct PolytopeOut {
    /// Hull vertices (m/s).
    pub vertices: Vec<[f64; 3]>,
    /// Outward triangles, indices into `vertices`.
    pub facets: Vec<[usize; 3]>,
    /// Volume (m³/s³).
    pub volume: f64,
    /// Kilic's cone-cell index (eq. 1.55, d_n = n!).
    pub w_p: f64,
}

fn check_q(model: &Model, q: &[f64]) -> Result<(), ApiError> {
    model.check_q(q)?;
    if let Some(i) = q.iter().position(|v| v.abs() > MAX_ABS_Q) {
        return Err(ApiError::bad_request(format!(
            "q[{i}] = {} is out of range (|q| ≤ {MAX_ABS_Q}, limit max_abs_q)",
            q[i]
        ))
        .with_detail(serde_json::json!({"limit": "max_abs_q", "value": MAX_ABS_Q})));
    }
    Ok(())
}

impl From<Polytope> for PolytopeOut {
    fn from(p: Polytope) -> PolytopeOut {
        PolytopeOut {
            vertices: p.vertices,
            facets: p.facets,
            volume: p.volume,
            w_p: p.w_p,
        }
    }
}

fn analysis_response(model: &Model, req: &AnalysisRequest) -> Result<AnalysisResponse, ApiError> {
    let a = analyze(model, &req.q, req.rows.as_deref())?;
    let polytope = if req.polytope {
        let jt = a.jacobian.select_rows(&polytope_rows(req.rows.as_deref()));
        let rates = match req.polytope_rates {
            PolytopeRates::Limits => model.max_velocities(),
            PolytopeRates::Unit => vec![1.0; model.dof()],
        };
        Some(polytope::velocity_polytope(&jt, &rates)?.into())
    } else {
        None
    };
    Ok(AnalysisResponse {
        robot: model.name.clone(),
        pose: (&a.pose).into(),
        joint_frames: a.joint_frames.iter().map(PoseOut::from).collect(),
        jacobian: rows(&a.jacobian),
        jacobian_end_effector: rows(&a.jacobian_end_effector),
        measures: MeasureSet {
            full: (&a.full).into(),
            translational: (&a.translational).into(),
            rotational: (&a.rotational).into(),
            task: a.task.as_ref().map(MeasuresOut::from),
        },
        jlm: a.jlm,
        jlm_gradient: a.jlm_gradient,
        null_space: columns(&a.subspaces.null_space),
        subspaces: SubspacesOut {
            rank: a.subspaces.rank,
            generating: columns(&a.subspaces.generating),
            range: columns(&a.subspaces.range),
            unreachable: columns(&a.subspaces.unreachable),
        },
        polytope,
    })
}

/// Handler of `POST /api/analysis`: answered at once, or on the compute pool when a polytope
/// is asked for (a 32-joint arm's polytope takes milliseconds).
pub async fn single(
    State(state): State<AppState>,
    ApiJson(req): ApiJson<AnalysisRequest>,
) -> Result<Json<AnalysisResponse>, ComputeError> {
    let model = state.robots.resolve(&req.robot)?;
    check_q(&model, &req.q)?;
    if !req.polytope {
        return Ok(Json(analysis_response(&model, &req)?));
    }
    let answer = state
        .compute
        .run(move |_| Ok(analysis_response(&model, &req)?))
        .await?;
    Ok(Json(answer))
}

/// Where an arm's base sits in the common (world) frame.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseIn {
    /// [x, y, z] (m).
    pub position: [f64; 3],
    /// Row-major 3×3 rotation matrix (identity when omitted).
    #[serde(default)]
    pub rotation: Option<[[f64; 3]; 3]>,
}

/// One arm of a dual request.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmIn {
    /// Built-in name or inline model.
    pub robot: Value,
    /// Joint values.
    pub q: Vec<f64>,
    /// Base pose in the common frame (identity when omitted).
    #[serde(default)]
    pub base: Option<BaseIn>,
}

/// Body of `POST /api/analysis/dual`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DualRequest {
    /// Exactly two arms.
    pub arms: Vec<ArmIn>,
    /// Also compute the dual velocity polytope.
    #[serde(default)]
    pub polytope: bool,
}

/// Response of `POST /api/analysis/dual`.
#[derive(Debug, Serialize)]
pub struct DualResponse {
    /// Dual-arm translational ellipsoid ẋᵀ[(J₁J₁ᵀ)⁻¹ + (J₂J₂ᵀ)⁻¹]ẋ = 1 (Lim eq. 3.68), common frame.
    pub translational: MeasuresOut,
    /// Each arm's translational measures, common frame.
    pub arms: Vec<DualArmOut>,
    /// Intersection of the two arms' translational velocity polytopes, when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polytope: Option<PolytopeOut>,
}

/// One arm in a dual response.
#[derive(Debug, Serialize)]
pub struct DualArmOut {
    /// Model name.
    pub robot: String,
    /// End-effector pose in the common frame.
    pub pose: PoseOut,
    /// Translational measures in the common frame.
    pub translational: MeasuresOut,
}

fn base_rotation(base: &Option<BaseIn>, arm: usize) -> Result<(Matrix3<f64>, [f64; 3]), ApiError> {
    let Some(b) = base else {
        return Ok((Matrix3::identity(), [0.0; 3]));
    };
    let bad = |what: &str| ApiError::bad_request(format!("arms[{arm}].base: {what}"));
    if b.position
        .iter()
        .any(|v| !v.is_finite() || v.abs() > MAX_POSITION_M)
    {
        return Err(bad(&format!(
            "position must be finite and within ±{MAX_POSITION_M} m (limit max_position_m)"
        )));
    }
    let r = match b.rotation {
        Some(rr) => Matrix3::from_fn(|i, j| rr[i][j]),
        None => Matrix3::identity(),
    };
    if r.iter().any(|v| !v.is_finite()) {
        return Err(bad("rotation must be finite"));
    }
    if (r.transpose() * r - Matrix3::identity()).abs().max() > 1e-6
        || (r.determinant() - 1.0).abs() > 1e-6
    {
        return Err(bad(
            "rotation must be a proper rotation matrix (RᵀR = I, det R = 1, to 1e-6)",
        ));
    }
    Ok((r, b.position))
}

/// One arm of a dual request, checked: model, joint values, base rotation and position.
struct DualArm {
    model: Arc<Model>,
    q: Vec<f64>,
    rotation: Matrix3<f64>,
    position: [f64; 3],
}

fn dual_response(arms: &[DualArm], polytope: bool) -> Result<DualResponse, ApiError> {
    let mut world_j = Vec::with_capacity(2);
    let mut out = Vec::with_capacity(2);
    for arm in arms {
        let (model, r, p) = (&arm.model, arm.rotation, arm.position);
        let jt = jacobian_at(model, &arm.q).select_rows(&TRANSLATIONAL_ROWS);
        let rd = DMatrix::from_column_slice(3, 3, r.as_slice());
        let jw = &rd * jt;
        let local = seaarms_core::kinematics::end_effector_pose(model, &arm.q);
        let base = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(p[0], p[1], p[2]),
            nalgebra::UnitQuaternion::from_matrix(&r),
        );
        out.push(DualArmOut {
            robot: model.name.clone(),
            pose: (&(base * local)).into(),
            translational: (&measures(&jw)?).into(),
        });
        world_j.push(jw);
    }
    let dual = dual_measures(&world_j[0], &world_j[1])?;
    let polytope = if polytope {
        let p = polytope::dual_velocity_polytope(
            &world_j[0],
            &arms[0].model.max_velocities(),
            &world_j[1],
            &arms[1].model.max_velocities(),
        )?;
        Some(p.into())
    } else {
        None
    };
    Ok(DualResponse {
        translational: (&dual).into(),
        arms: out,
        polytope,
    })
}

/// Handler of `POST /api/analysis/dual`: answered at once, or on the compute pool when the
/// dual polytope is asked for (2 × 32 joints: ~40 ms).
pub async fn dual(
    State(state): State<AppState>,
    ApiJson(req): ApiJson<DualRequest>,
) -> Result<Json<DualResponse>, ComputeError> {
    if req.arms.len() != 2 {
        return Err(ApiError::bad_request(format!(
            "`arms` must hold exactly 2 arms, got {}",
            req.arms.len()
        ))
        .into());
    }
    let mut arms = Vec::with_capacity(2);
    for (i, arm) in req.arms.into_iter().enumerate() {
        let model = state.robots.resolve(&arm.robot)?;
        check_q(&model, &arm.q).map_err(|e| ApiError {
            error: format!("arms[{i}]: {}", e.error),
            ..e
        })?;
        let (rotation, position) = base_rotation(&arm.base, i)?;
        arms.push(DualArm {
            model,
            q: arm.q,
            rotation,
            position,
        });
    }
    if !req.polytope {
        return Ok(Json(dual_response(&arms, false)?));
    }
    let answer = state
        .compute
        .run(move |_| Ok(dual_response(&arms, true)?))
        .await?;
    Ok(Json(answer))
}
