//! The parameters of the case studies (Lim §4.3) and their defaults.

/// §4.3.1.1 / §4.3.2.1: for each Z level, X from `start` towards the boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepX {
    /// Z levels (m, default [0, 0.2, 0.4, 0.5]).
    pub z_levels: Vec<f64>,
    /// First X (m, default 0.9).
    pub start: f64,
    /// X step (m, default 0.01).
    pub step: f64,
    /// Last X tried if no boundary is met first (m, default 2.0).
    pub end: f64,
}

impl Default for SweepX {
    fn default() -> Self {
        SweepX {
            z_levels: vec![0.0, 0.2, 0.4, 0.5],
            start: 0.9,
            step: 0.01,
            end: 2.0,
        }
    }
}

/// §4.3.1.2: for each X level, Z from `start` upwards to the boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepZ {
    /// X levels (m, default [0.9, 1.0, 1.1, 1.2, 1.3, 1.4]).
    pub x_levels: Vec<f64>,
    /// First Z (m, default 0.0).
    pub start: f64,
    /// Z step (m, default 0.01).
    pub step: f64,
    /// Last Z tried if no boundary is met first (m, default 1.5).
    pub end: f64,
}

impl Default for SweepZ {
    fn default() -> Self {
        SweepZ {
            x_levels: vec![0.9, 1.0, 1.1, 1.2, 1.3, 1.4],
            start: 0.0,
            step: 0.01,
            end: 1.5,
        }
    }
}

/// §4.3.1.3 / §4.3.2.2: pitch and yaw changed at named points.
#[derive(Debug, Clone, PartialEq)]
pub struct PitchYaw {
    /// Named points (base frame, m). Default: Fig. 4-51's points are not printed; we use
    /// A (1.1, 0, 0.2), B (1.2, 0, 0.2), C (1.3, 0, 0.2), D (1.1, 0, 0.3), E (1.2, 0, 0.3),
    /// F (1.3, 0, 0.3): inside the case-study workspace, where the 90°/90° start pose and at
    /// least 10 of the 13 pitch rows are reachable (docs/physics.md, "Link lengths").
    pub points: Vec<(String, [f64; 3])>,
    /// Pitch range (deg, default [75, 135], the thesis's range), yaw held at 90°.
    pub pitch_deg: [f64; 2],
    /// Yaw range (deg, default [60, 120]; not printed in the thesis), pitch held at 90°.
    pub yaw_deg: [f64; 2],
    /// Angle step (deg, default 5).
    pub step_deg: f64,
}

impl Default for PitchYaw {
    fn default() -> Self {
        let p = |n: &str, x: f64, z: f64| (n.to_string(), [x, 0.0, z]);
        PitchYaw {
            points: vec![
                p("A", 1.1, 0.2),
                p("B", 1.2, 0.2),
                p("C", 1.3, 0.2),
                p("D", 1.1, 0.3),
                p("E", 1.2, 0.3),
                p("F", 1.3, 0.3),
            ],
            pitch_deg: [75.0, 135.0],
            yaw_deg: [60.0, 120.0],
            step_deg: 5.0,
        }
    }
}

/// §4.3.2.3 (Fig. 4-75): both end-effectors at X, then link 1 swung by ±δ.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceSweep {
    /// X levels (m, default [1.0, 1.2, 1.4]).
    pub x_levels: Vec<f64>,
    /// Z of both end-effectors (m, default 0.3; not printed in the thesis; inside the
    /// case-study workspace Z 0–0.5 m).
    pub z: f64,
    /// Largest swing δ (deg, default 25 = the Magnum swing limit). The right arm swings by +δ
    /// (towards the left arm), the left by −δ; δ runs from −max to +max, so the distance first
    /// grows, then equals the base spacing (parallel arms, δ = 0), then shrinks.
    pub swing_max_deg: f64,
    /// δ step (deg, default 1).
    pub step_deg: f64,
}

impl Default for DistanceSweep {
    fn default() -> Self {
        DistanceSweep {
            x_levels: vec![1.0, 1.2, 1.4],
            z: 0.3,
            swing_max_deg: 25.0,
            step_deg: 1.0,
        }
    }
}

/// Placement of the second arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualSetup {
    /// Y of the left arm's base in the world frame (m, default 1.0, Lim §4.3.2.2).
    pub left_base_y_m: f64,
}

impl Default for DualSetup {
    fn default() -> Self {
        DualSetup { left_base_y_m: 1.0 }
    }
}
