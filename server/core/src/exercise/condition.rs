//! Step completion conditions: when a step is done, how far along it is, and the readout the
//! trainee sees for it. Each condition reads only the simulation's state and the attempt's
//! own facts (the answer given, whether the drill's fault is in), so the same state always
//! gives the same verdict.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::spec::{ArmName, ArmSel, Scene};
use crate::sim::{Arm, Graspable, Simulation, StabPhase};

/// What can be held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Item {
    /// The 50 kg box (by its handles).
    Box,
    /// The panel valve's T-bar (scene `panel`).
    Valve,
    /// The hot stab (scene `panel`).
    Stab,
}

/// A step's completion condition (`"kind"` names the variant in the file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Condition {
    /// Joint `joint` (0-based) of `arm` within `tolerance_deg` of `angle_deg`.
    JointAt {
        /// Arm.
        arm: ArmName,
        /// Joint index (0–5).
        joint: usize,
        /// Target angle (degrees).
        angle_deg: f64,
        /// Tolerance (degrees).
        tolerance_deg: f64,
    },
    /// The tool point of `arm` (either: any arm) within the target's radius.
    ToolAt {
        /// Arm(s).
        arm: ArmSel,
        /// Target id.
        target: String,
    },
    /// `arm` holds `item` (both: both arms do).
    Holding {
        /// Arm(s).
        arm: ArmSel,
        /// Item.
        item: Item,
    },
    /// The box's centre of mass `height_m` ± `tolerance_m` above where it rests at the start.
    ObjectHeight {
        /// Lift (m).
        height_m: f64,
        /// Tolerance (m).
        tolerance_m: f64,
    },
    /// The box resting on the seabed with its centre inside the zone and tilted no more than
    /// `max_tilt_deg`.
    ObjectInZone {
        /// Zone id.
        zone: String,
        /// Largest tilt of its vertical axis (degrees).
        max_tilt_deg: f64,
    },
    /// The panel valve within `tolerance_deg` of `angle_deg` (0 closed, 90 open).
    ValveAngle {
        /// Target angle (degrees).
        angle_deg: f64,
        /// Tolerance (degrees).
        tolerance_deg: f64,
    },
    /// The hot stab latched in its receptacle.
    StabSeated,
    /// No jaw holds anything.
    Released,
    /// The box rests on the seabed (the seabed carries at least half its weight).
    ObjectResting,
    /// Internal force magnitude below `force_n` (N) (zero unless both jaws hold).
    InternalForceBelow {
        /// Limit (N).
        force_n: f64,
    },
    /// Closed-loop cooperative control active (method closed and both jaws holding).
    ClosedLoop,
    /// Every joint of both arms slower than `max_joint_speed_rad_s`.
    ArmsStill {
        /// Limit (rad/s).
        max_joint_speed_rad_s: f64,
    },
    /// The fault drill's window has ended (its fault is in: it comes inside the window). Not
    /// "the fault is in", whose moment a step ticking over would tell the trainee (issue 29).
    FaultWindowOver,
    /// The trainee has named a fault.
    Diagnosed,
    /// Every one of `of`.
    All {
        /// Conditions.
        of: Vec<Condition>,
    },
    /// At least one of `of` (its progress: the furthest along).
    Any {
        /// Conditions.
        of: Vec<Condition>,
    },
}

/// A live readout for the task panel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Readout {
    /// What it is.
    pub label: String,
    /// Current value.
    pub value: f64,
    /// Target value.
    pub target: f64,
    /// Unit of both.
    pub unit: &'static str,
}

/// What a condition says about the current state.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Met now.
    pub met: bool,
    /// How far along, in [0, 1] (1 when met).
    pub fraction: f64,
}

/// What conditions may read besides the simulation.
#[derive(Debug, Clone, Copy)]
pub struct Facts<'a> {
    /// The scene (targets, zones).
    pub scene: &'a Scene,
    /// The box's centre-of-mass height at rest at the start (m, world z).
    pub rest_z_m: f64,
    /// The drill's fault window has ended (the fault is in).
    pub fault_window_over: bool,
    /// The trainee's answer, once given.
    pub answer: Option<&'a str>,
}

fn arm_of(i: usize) -> Arm {
    Arm::BOTH[i.min(1)]
}

fn tool_distance(sim: &Simulation, arm: usize, p: [f64; 3]) -> f64 {
    (sim.end_effector(arm_of(arm)).translation.vector - Vector3::from(p)).norm()
}

/// The box's tilt: angle between its z axis and the world vertical (rad).
pub fn object_tilt_rad(sim: &Simulation) -> f64 {
    let z = sim.object().pose.rotation * Vector3::z();
    z.z.clamp(-1.0, 1.0).acos()
}

/// Whether the box rests on the seabed (the seabed carries at least half its weight).
pub fn object_resting(sim: &Simulation) -> bool {
    let p = sim.params();
    sim.object().seabed_force_n > 0.5 * p.object.mass_kg * p.step.gravity.norm()
}

fn fraction_towards(error: f64, tolerance: f64, scale: f64) -> f64 {
    if error <= tolerance {
        1.0
    } else {
        (1.0 - (error - tolerance) / scale.max(1e-9)).clamp(0.0, 0.99)
    }
}

impl Condition {
    /// Whether it holds now and how far along it is.
    pub fn evaluate(&self, sim: &Simulation, facts: &Facts<'_>) -> Verdict {
        let yes = |met: bool| Verdict {
            met,
            fraction: if met { 1.0 } else { 0.0 },
        };
        match self {
            Condition::JointAt {
                arm,
                joint,
                angle_deg,
                tolerance_deg,
            } => {
                let q = sim.arm(arm_of(arm.index())).q[(*joint).min(5)].to_degrees();
                let e = (q - angle_deg).abs();
                Verdict {
                    met: e <= *tolerance_deg,
                    fraction: fraction_towards(e, *tolerance_deg, 90.0),
                }
            }
            Condition::ToolAt { arm, target } => {
                let Some(t) = facts.scene.targets.iter().find(|t| &t.id == target) else {
                    return yes(false);
                };
                let d = arm
                    .indices()
                    .iter()
                    .map(|&i| tool_distance(sim, i, t.position_m))
                    .fold(f64::INFINITY, f64::min);
                Verdict {
                    met: d <= t.radius_m,
                    fraction: fraction_towards(d, t.radius_m, 1.0),
                }
            }
            Condition::Holding { arm, item } => {
                let holds = |i: usize| match item {
                    Item::Box => sim.arm(arm_of(i)).holding,
                    Item::Valve => panel_holds(sim, i, Graspable::Valve),
                    Item::Stab => panel_holds(sim, i, Graspable::Stab),
                };
                let n = arm.indices().iter().filter(|&&i| holds(i)).count();
                match arm {
                    ArmSel::Both => Verdict {
                        met: n == 2,
                        fraction: n as f64 / 2.0,
                    },
                    _ => yes(n > 0),
                }
            }
            Condition::ObjectHeight {
                height_m,
                tolerance_m,
            } => {
                let h = sim.object().pose.translation.z - facts.rest_z_m;
                let e = (h - height_m).abs();
                Verdict {
                    met: e <= *tolerance_m,
                    fraction: fraction_towards(e, *tolerance_m, height_m.abs().max(0.05)),
                }
            }
            Condition::ObjectInZone { zone, max_tilt_deg } => {
                let Some(z) = facts.scene.zones.iter().find(|z| &z.id == zone) else {
                    return yes(false);
                };
                let c = sim.object().pose.translation.vector;
                let (dx, dy) = ((c.x - z.center_m[0]).abs(), (c.y - z.center_m[1]).abs());
                let inside = dx <= z.half_size_m[0] && dy <= z.half_size_m[1];
                let level = object_tilt_rad(sim).to_degrees() <= *max_tilt_deg;
                let d = ((dx - z.half_size_m[0]).max(0.0)).hypot((dy - z.half_size_m[1]).max(0.0));
                let met = inside && level && object_resting(sim);
                Verdict {
                    met,
                    fraction: if met {
                        1.0
                    } else {
                        fraction_towards(d, 0.0, 1.0).min(0.9)
                    },
                }
            }
            Condition::ValveAngle {
                angle_deg,
                tolerance_deg,
            } => {
                let Some(p) = sim.panel() else {
                    return yes(false);
                };
                let e = (p.valve_angle_rad.to_degrees() - angle_deg).abs();
                Verdict {
                    met: e <= *tolerance_deg,
                    fraction: fraction_towards(e, *tolerance_deg, 90.0),
                }
            }
            Condition::StabSeated => {
                let Some(p) = sim.panel() else {
                    return yes(false);
                };
                let met = p.stab_phase == StabPhase::Seated;
                let full = sim
                    .params()
                    .panel
                    .map_or(1.0, |pp| pp.stab.insertion_depth_m);
                Verdict {
                    met,
                    fraction: if met {
                        1.0
                    } else {
                        (p.stab_depth_m / full).clamp(0.0, 0.9)
                    },
                }
            }
            Condition::Released => yes(Arm::BOTH.iter().all(|&a| {
                !sim.arm(a).holding
                    && !panel_holds(sim, a.index(), Graspable::Valve)
                    && !panel_holds(sim, a.index(), Graspable::Stab)
            })),
            Condition::ObjectResting => yes(object_resting(sim)),
            Condition::InternalForceBelow { force_n } => {
                let w = sim.internal_wrench();
                yes(Vector3::new(w[0], w[1], w[2]).norm() < *force_n)
            }
            Condition::ClosedLoop => yes(sim.closed_loop_active()),
            Condition::ArmsStill {
                max_joint_speed_rad_s,
            } => yes(Arm::BOTH.iter().all(|&a| {
                sim.arm(a)
                    .qd
                    .iter()
                    .all(|v| v.abs() < *max_joint_speed_rad_s)
            })),
            // Its progress is never shown: a step's progress bar that moved at the injection
            // would tell the trainee when the hidden fault came (issue 29).
            Condition::FaultWindowOver => Verdict {
                met: facts.fault_window_over,
                fraction: 0.0,
            },
            Condition::Diagnosed => yes(facts.answer.is_some()),
            Condition::All { of } => {
                let v: Vec<Verdict> = of.iter().map(|c| c.evaluate(sim, facts)).collect();
                Verdict {
                    met: v.iter().all(|v| v.met),
                    fraction: if v.is_empty() {
                        1.0
                    } else {
                        v.iter().map(|v| v.fraction).sum::<f64>() / v.len() as f64
                    },
                }
            }
            Condition::Any { of } => {
                let v: Vec<Verdict> = of.iter().map(|c| c.evaluate(sim, facts)).collect();
                Verdict {
                    met: v.iter().any(|v| v.met),
                    fraction: v.iter().map(|v| v.fraction).fold(0.0, f64::max),
                }
            }
        }
    }

    /// The readouts that show the trainee how close the state is (empty for yes/no conditions).
    pub fn readouts(&self, sim: &Simulation, facts: &Facts<'_>, out: &mut Vec<Readout>) {
        match self {
            Condition::JointAt {
                arm,
                joint,
                angle_deg,
                ..
            } => out.push(Readout {
                label: format!(
                    "{} joint {}",
                    if *arm == ArmName::Left {
                        "Left"
                    } else {
                        "Right"
                    },
                    joint + 1
                ),
                value: sim.arm(arm_of(arm.index())).q[(*joint).min(5)].to_degrees(),
                target: *angle_deg,
                unit: "°",
            }),
            Condition::ToolAt { arm, target } => {
                if let Some(t) = facts.scene.targets.iter().find(|t| &t.id == target) {
                    let d = arm
                        .indices()
                        .iter()
                        .map(|&i| tool_distance(sim, i, t.position_m))
                        .fold(f64::INFINITY, f64::min);
                    out.push(Readout {
                        label: format!("Distance to {}", t.id),
                        value: d * 100.0,
                        target: t.radius_m * 100.0,
                        unit: "cm",
                    });
                }
            }
            Condition::ObjectHeight { height_m, .. } => out.push(Readout {
                label: "Box lift".into(),
                value: (sim.object().pose.translation.z - facts.rest_z_m) * 100.0,
                target: height_m * 100.0,
                unit: "cm",
            }),
            Condition::ObjectInZone { zone, max_tilt_deg } => {
                if let Some(z) = facts.scene.zones.iter().find(|z| &z.id == zone) {
                    let c = sim.object().pose.translation.vector;
                    out.push(Readout {
                        label: format!("Box to {} centre", z.id),
                        value: (c.x - z.center_m[0]).hypot(c.y - z.center_m[1]) * 100.0,
                        target: z.half_size_m[0].min(z.half_size_m[1]) * 100.0,
                        unit: "cm",
                    });
                }
                out.push(Readout {
                    label: "Box tilt".into(),
                    value: object_tilt_rad(sim).to_degrees(),
                    target: *max_tilt_deg,
                    unit: "°",
                });
            }
            Condition::InternalForceBelow { force_n } => {
                let w = sim.internal_wrench();
                out.push(Readout {
                    label: "Internal force".into(),
                    value: Vector3::new(w[0], w[1], w[2]).norm(),
                    target: *force_n,
                    unit: "N",
                });
            }
            Condition::ValveAngle { angle_deg, .. } => {
                if let Some(p) = sim.panel() {
                    out.push(Readout {
                        label: "Valve angle".into(),
                        value: p.valve_angle_rad.to_degrees(),
                        target: *angle_deg,
                        unit: "°",
                    });
                }
            }
            Condition::StabSeated => {
                if let (Some(p), Some(pp)) = (sim.panel(), sim.params().panel) {
                    out.push(Readout {
                        label: "Stab depth".into(),
                        value: p.stab_depth_m * 1000.0,
                        target: pp.stab.insertion_depth_m * 1000.0,
                        unit: "mm",
                    });
                    out.push(Readout {
                        label: "Side load".into(),
                        value: p.side_load_n,
                        target: pp.stab.side_load_limit_n,
                        unit: "N",
                    });
                }
            }
            Condition::All { of } | Condition::Any { of } => {
                for c in of {
                    c.readouts(sim, facts, out);
                }
            }
            Condition::Holding { .. }
            | Condition::Released
            | Condition::ObjectResting
            | Condition::ClosedLoop
            | Condition::ArmsStill { .. }
            | Condition::FaultWindowOver
            | Condition::Diagnosed => {}
        }
    }

    /// Checks references and numbers against the scene.
    pub fn check(&self, scene: &Scene) -> Result<(), String> {
        let finite = |x: f64, what: &str| {
            if x.is_finite() {
                Ok(())
            } else {
                Err(format!("{what} must be finite"))
            }
        };
        match self {
            Condition::JointAt {
                joint,
                angle_deg,
                tolerance_deg,
                ..
            } => {
                if *joint > 5 {
                    return Err(format!("joint {joint} is not in 0..=5"));
                }
                finite(*angle_deg, "angle_deg")?;
                finite(*tolerance_deg, "tolerance_deg")
            }
            Condition::ToolAt { target, .. } => {
                if scene.targets.iter().any(|t| &t.id == target) {
                    Ok(())
                } else {
                    Err(format!("unknown target `{target}`"))
                }
            }
            Condition::ObjectInZone { zone, max_tilt_deg } => {
                finite(*max_tilt_deg, "max_tilt_deg")?;
                if scene.zones.iter().any(|z| &z.id == zone) {
                    Ok(())
                } else {
                    Err(format!("unknown zone `{zone}`"))
                }
            }
            Condition::ObjectHeight {
                height_m,
                tolerance_m,
            } => {
                finite(*height_m, "height_m")?;
                finite(*tolerance_m, "tolerance_m")
            }
            Condition::InternalForceBelow { force_n } => finite(*force_n, "force_n"),
            Condition::ArmsStill {
                max_joint_speed_rad_s,
            } => finite(*max_joint_speed_rad_s, "max_joint_speed_rad_s"),
            Condition::ValveAngle {
                angle_deg,
                tolerance_deg,
            } => {
                finite(*angle_deg, "angle_deg")?;
                finite(*tolerance_deg, "tolerance_deg")?;
                if scene.panel {
                    Ok(())
                } else {
                    Err("valve_angle needs the scene's panel".into())
                }
            }
            Condition::StabSeated if !scene.panel => {
                Err("stab_seated needs the scene's panel".into())
            }
            Condition::Holding {
                item: Item::Valve | Item::Stab,
                ..
            } if !scene.panel => Err("holding the valve or stab needs the scene's panel".into()),
            Condition::All { of } | Condition::Any { of } => {
                of.iter().try_for_each(|c| c.check(scene))
            }
            Condition::StabSeated
            | Condition::Holding { .. }
            | Condition::Released
            | Condition::ObjectResting
            | Condition::ClosedLoop
            | Condition::FaultWindowOver
            | Condition::Diagnosed => Ok(()),
        }
    }
}

/// Arm `i` holds the panel item `item` (false without a panel).
fn panel_holds(sim: &Simulation, i: usize, item: Graspable) -> bool {
    sim.panel()
        .is_some_and(|p| p.held_by(arm_of(i)) == Some(item))
}
