//! Optimal deploy posture (Jun 2008 §3) at the server edge (`POST /api/optimal-posture`,
//! `seaarms optimal-posture`): the request, parsed once into the core's
//! [`PostureOptions`](optimize::PostureOptions) and checked against [`crate::limits`], and the
//! answer. A target outside the workspace is [`seaarms_core::Error::Unreachable`] (→ 422).

use serde::ser::SerializeStruct;
use serde::{Deserialize, Serialize, Serializer};
use serde_json::Value;

use seaarms_core::{Model, optimize};

use crate::error::ApiError;
use crate::limits::{self, MAX_POSITION_M, MAX_POSTURE_START_JOINTS};

/// Body of `POST /api/optimal-posture` (the command line builds the same).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PostureRequest {
    /// Built-in name or inline model.
    pub robot: Value,
    /// Tool-point target, base frame (m).
    pub target_position: [f64; 3],
    /// Weight α ∈ [0, 1] of TOMM in f = −α·TOMM − (1 − α)·JLM (Jun eq. 17).
    pub alpha: f64,
    /// TOMM task rows (0..6: vx vy vz wx wy wz; default translational 0, 1, 2).
    #[serde(default)]
    pub rows: Option<Vec<usize>>,
    /// Initial candidates, 1..=64 (default 8); starts × joints ≤ [`MAX_POSTURE_START_JOINTS`].
    #[serde(default)]
    pub starts: Option<usize>,
}

impl PostureRequest {
    /// The core's options for `model`, after the checks the core does not make: the target
    /// within ±[`MAX_POSITION_M`] and starts × joints ≤ [`MAX_POSTURE_START_JOINTS`] (α, rows
    /// and the start count are the core's to check).
    pub fn options(&self, model: &Model) -> Result<optimize::PostureOptions, ApiError> {
        for (i, &v) in self.target_position.iter().enumerate() {
            limits::within(
                "max_position_m",
                MAX_POSITION_M,
                &format!("target_position[{i}]"),
                v,
            )?;
        }
        let defaults = optimize::PostureOptions::default();
        let starts = self.starts.unwrap_or(defaults.starts);
        let work = starts.saturating_mul(model.dof());
        if work > MAX_POSTURE_START_JOINTS {
            return Err(limits::exceeded(
                "max_posture_start_joints",
                MAX_POSTURE_START_JOINTS,
                work,
                &format!("starts × joints ({starts} × {})", model.dof()),
            ));
        }
        Ok(optimize::PostureOptions {
            alpha: self.alpha,
            rows: self.rows.clone().unwrap_or(defaults.rows.clone()),
            starts,
            ..defaults
        })
    }
}

/// Answer of an optimal-posture request: the core's result without its per-start detail —
/// `q` (rad or m), `tomm`, `jlm` (Jun eq. 16), `objective` (f = −α·TOMM − (1 − α)·JLM),
/// `iterations` (objective evaluations of the winning SQP run), `constraint_violation_m`
/// (≤ 1e-6 m) and `start` (index of the winning candidate).
#[derive(Debug, Clone, PartialEq)]
pub struct PostureAnswer(pub optimize::PostureResult);

impl Serialize for PostureAnswer {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let r = &self.0;
        let mut s = serializer.serialize_struct("PostureAnswer", 7)?;
        s.serialize_field("q", &r.q)?;
        s.serialize_field("tomm", &r.tomm)?;
        s.serialize_field("jlm", &r.jlm)?;
        s.serialize_field("objective", &r.objective)?;
        s.serialize_field("iterations", &r.iterations)?;
        s.serialize_field("constraint_violation_m", &r.constraint_violation_m)?;
        s.serialize_field("start", &r.start)?;
        s.end()
    }
}

/// Optimal posture of `model` for `req` (checked as [`PostureRequest::options`] says).
pub fn optimal_posture(model: &Model, req: &PostureRequest) -> Result<PostureAnswer, ApiError> {
    let opts = req.options(model)?;
    Ok(PostureAnswer(optimize::optimal_posture(
        model,
        &req.target_position,
        &opts,
    )?))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::robots::Robots;
    use serde_json::json;

    #[test]
    fn optimal_posture_round_trips_and_validates() {
        let robots = Robots::load().unwrap();
        let orion = robots.get("orion").unwrap();
        let req: PostureRequest = serde_json::from_value(
            json!({"robot": "orion", "target_position": [0.9, 0.1, 0.1], "alpha": 0.5, "starts": 4}),
        )
        .expect("parses");
        let r = optimal_posture(&orion, &req).expect("reachable");
        assert!(r.0.constraint_violation_m <= 1e-6);
        let v = serde_json::to_value(&r).expect("serialises");
        let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(
            keys,
            [
                "constraint_violation_m",
                "iterations",
                "jlm",
                "objective",
                "q",
                "start",
                "tomm"
            ]
        );
        let far = PostureRequest {
            target_position: [5.0, 0.0, 0.0],
            ..req.clone()
        };
        assert_eq!(optimal_posture(&orion, &far).unwrap_err().status, 422);
        for bad in [
            PostureRequest {
                alpha: -0.1,
                ..req.clone()
            },
            PostureRequest {
                starts: Some(0),
                ..req.clone()
            },
            PostureRequest {
                starts: Some(65),
                ..req.clone()
            },
            PostureRequest {
                rows: Some(vec![7]),
                ..req.clone()
            },
            PostureRequest {
                target_position: [f64::INFINITY, 0.0, 0.0],
                ..req.clone()
            },
            PostureRequest {
                target_position: [2e3, 0.0, 0.0],
                ..req.clone()
            },
        ] {
            assert_eq!(
                optimal_posture(&orion, &bad).unwrap_err().status,
                400,
                "{bad:?}"
            );
        }
    }

    /// Starts × joints: 64 starts of the 6-joint ORION (384) pass, 64 of a 9-joint arm (576)
    /// do not; the 400 names the limit.
    #[test]
    fn starts_times_joints_is_limited() {
        let robots = Robots::load().unwrap();
        let orion = robots.get("orion").unwrap();
        let req = PostureRequest {
            robot: json!("orion"),
            target_position: [0.9, 0.1, 0.1],
            alpha: 0.5,
            rows: None,
            starts: Some(64),
        };
        assert!(req.options(&orion).is_ok());
        let joint = json!({"type": "revolute", "a": 0.1, "alpha": std::f64::consts::FRAC_PI_2, "limits": [-3, 3], "max_velocity": 1});
        let nine = robots
            .resolve(&json!({"name": "nine", "dh": "standard", "joints": vec![joint; 9]}))
            .unwrap();
        let e = req.options(&nine).unwrap_err();
        assert_eq!(e.status, 400);
        assert_eq!(e.detail.unwrap()["limit"], "max_posture_start_joints");
        let huge = PostureRequest {
            starts: Some(usize::MAX),
            ..req.clone()
        };
        assert_eq!(huge.options(&orion).unwrap_err().status, 400);
    }
}
