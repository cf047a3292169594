//! `GET /api/robots` and `GET /api/robots/{name}`.

use axum::Json;
use axum::extract::{Path, State};
use serde::Serialize;

use crate::app::AppState;
use crate::error::ApiError;

/// One entry of the robot list.
#[derive(Debug, Serialize)]
pub struct RobotSummary {
    /// Name to use in requests.
    pub name: String,
    /// Number of joints.
    pub dof: usize,
    /// Where the model comes from.
    pub source: String,
}

/// Lists the built-in models.
pub async fn list(State(state): State<AppState>) -> Json<Vec<RobotSummary>> {
    Json(
        state
            .robots
            .all()
            .iter()
            .map(|m| RobotSummary {
                name: m.name.clone(),
                dof: m.dof(),
                source: m.source.clone(),
            })
            .collect(),
    )
}

/// One model in the inline-model schema (joints, limits, velocity limits, source, notes).
pub async fn get(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Json<seaarms_core::ModelSpec>, ApiError> {
    let model = state.robots.resolve(&serde_json::Value::String(name))?;
    Ok(Json(model.spec.clone()))
}
