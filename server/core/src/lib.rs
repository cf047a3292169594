//! seaarms-core: the pure simulation core of the seaarms training simulator.
//!
//! No I/O, no clock, no async: kinematics, manipulability, dynamics, hydraulics, grasp and
//! control, as free functions over a fixed [`model::Model`] and preallocated data.
//!
//! # Layout
//! * [`analysis`]: one-call analysis of a posture (what the HTTP API returns).
//! * [`model`]: robots as data — a joint is a fixed transform plus an axis; DH loaders.
//! * [`robots`]: the built-in model files (JSON text; parsed by the caller).
//! * [`kinematics`]: forward kinematics of every frame, geometric Jacobian.
//! * [`ik`]: Magnum closed-form IK (Lim eqs 3.10–3.19) and damped-least-squares IK.
//! * [`manipulability`]: ellipsoid measures, JLM, dual-arm ellipsoid, velocity polytopes.
//! * [`dynamics`]: link inertials, RNEA, CRBA, tool bias acceleration (Lim eq. 3.38).
//! * [`linalg`]: fixed-size LDLᵀ factorization for the step's small SPD systems.
//! * [`hydraulics`]: valves, cylinders, relief, linkage Ĵ(q), Magnum sizing (Lim eqs 3.48–3.56).
//! * [`grasp`]: the object, seabed contact, grasp matrices W, W⁺, V, grasp state (Lim eqs 3.39–3.47).
//! * [`control`]: open loop, joint-velocity servo, closed-loop cooperative control.
//! * [`sim`]: the whole-system [`sim::Simulation`] stepped at 1 ms, and scripted scenarios.
//! * [`collision`]: collision shapes of the arms and the world, narrow phase (parry3d-f64).
//! * [`panel`]: the intervention panel: T-bar valve (stick–slip, end stops) and hot stab
//!   (holster, aligned insertion, seating, side load).
//! * [`optimize`]: TOMM/JLM objective and gradients; optimal posture by multi-start SLSQP (Jun §3).
//! * [`redundancy`]: task-oriented redundancy resolution, task priority, damping, velocity
//!   limits, feedback form (Jun eqs 19–24, Kilic eqs 0.2–0.10); allocation-free steps.
//! * [`exercise`]: training exercises: steps, conditions, assessment and score, the autopilot.
//! * [`studies`]: Lim §4.3 manipulability case studies (single and dual arm) as rows, and a
//!   workspace map of translational measures.

pub mod analysis;
pub mod collision;
pub mod error;
pub mod exercise;
pub mod ik;

pub mod control;
pub mod dynamics;
pub mod grasp;
pub mod hydraulics;
pub mod sim;

pub mod kinematics;
pub mod linalg;
pub mod manipulability;
pub mod model;
pub mod optimize;
pub mod panel;
pub mod redundancy;
pub mod robots;
pub mod studies;

pub use error::Error;
pub use model::{Joint, JointKind, Model, ModelSpec};

/// `x` if it is finite, else `default`: the validation rule for numbers from outside (inputs,
/// fault settings) that must not reach the physics as NaN or ±∞.
pub(crate) fn finite_or(x: f64, default: f64) -> f64 {
    if x.is_finite() { x } else { default }
}
