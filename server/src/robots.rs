//! The robot registry: built-in models parsed once at start-up, and resolution of the API's
//! `"robot"` field (a built-in name or an inline model in the same schema).

use std::sync::Arc;

use seaarms_core::{Model, ModelSpec, robots::BUILTIN};
use serde_json::Value;

use crate::error::ApiError;

/// Built-in models by name, in the order of [`BUILTIN`].
#[derive(Debug)]
pub struct Robots {
    models: Vec<Arc<Model>>,
}

impl Robots {
    /// Parses every built-in model file; an error here is a bug in a shipped data file.
    pub fn load() -> anyhow::Result<Robots> {
        let mut models = Vec::new();
        for (name, text) in BUILTIN {
            let spec: ModelSpec = serde_json::from_str(text)
                .map_err(|e| anyhow::anyhow!("built-in model {name}: {e}"))?;
            models.push(Arc::new(
                Model::from_spec(&spec)
                    .map_err(|e| anyhow::anyhow!("built-in model {name}: {e}"))?,
            ));
        }
        Ok(Robots { models })
    }

    /// All built-in models.
    pub fn all(&self) -> &[Arc<Model>] {
        &self.models
    }

    /// A built-in model by name.
    pub fn get(&self, name: &str) -> Option<Arc<Model>> {
        self.models.iter().find(|m| m.name == name).cloned()
    }

    /// Resolves a request's `"robot"` value: a string names a built-in model (404 when
    /// unknown); an object is an inline model (400 with the schema error when invalid).
    pub fn resolve(&self, robot: &Value) -> Result<Arc<Model>, ApiError> {
        match robot {
            Value::String(name) => self.get(name).ok_or_else(|| {
                let known: Vec<&str> = self.models.iter().map(|m| m.name.as_str()).collect();
                ApiError::not_found(format!("unknown robot `{name}`"))
                    .with_detail(serde_json::json!({ "known": known }))
            }),
            Value::Object(_) => {
                let spec: ModelSpec = serde_path_to_error::deserialize(robot).map_err(|e| {
                    ApiError::bad_request(format!(
                        "invalid inline robot at `robot.{}`: {}",
                        e.path(),
                        e.inner()
                    ))
                })?;
                Ok(Arc::new(Model::from_spec(&spec)?))
            }
            _ => Err(ApiError::bad_request(
                "`robot` must be a built-in robot name or an inline model object",
            )),
        }
    }
}
