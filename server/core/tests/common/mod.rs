//! Shared test helpers: load the built-in models.
#![allow(dead_code)]

use seaarms_core::{Model, ModelSpec, robots};

/// Parses and builds a built-in model.
pub(crate) fn builtin(name: &str) -> Model {
    let text = robots::builtin_text(name).expect("built-in model");
    let spec: ModelSpec = serde_json::from_str(text).expect("model JSON parses");
    Model::from_spec(&spec).expect("model builds")
}

/// Every built-in model.
pub(crate) fn all_builtin() -> Vec<Model> {
    robots::BUILTIN.iter().map(|(n, _)| builtin(n)).collect()
}

pub(crate) mod panel_util;
pub(crate) mod rng;
pub(crate) mod scenario_util;
