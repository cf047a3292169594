//! HTTP API handlers, one module per concern; wire types live beside their handlers and are
//! never the core's internal structs.

pub mod analysis;
pub mod attempts;
pub mod ghosts;
pub mod logbook;
pub mod openapi;
pub mod optimize;
pub mod progress;
pub mod results;
pub mod robots;
pub mod scenarios;
pub mod session_ws;
pub mod sessions;
pub mod signin;
pub mod unlocks;
pub mod wire;
