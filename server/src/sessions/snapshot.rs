//! State frames: what the page draws, computed once per frame per session (never per client):
//! joint frames, end-effector poses, translational manipulability ellipsoids and measures
//! per arm and dual (Lim eqs 3.62, 3.68; Hong eq. 4.1), JLM (Jun eq. 16), forces, warnings.

use seaarms_core::manipulability::Measures;
use seaarms_core::sim::measures::measures;
use seaarms_core::sim::{Arm, ArmContacts, ArmPart, ORIENTATION_LOST_RAD};

use super::Live;
use crate::protocol::PoseOut;
use crate::protocol::{
    ArmFrame, ArmsFrame, DualFrame, EllipsoidFrame, MeasuresFrame, ObjectFrame, StateFrame,
    TouchOut, arm_name,
};

fn ellipsoid(m: &Measures) -> EllipsoidFrame {
    let mut radii = [0.0; 3];
    let mut axes = [[0.0; 3]; 3];
    for i in 0..3 {
        radii[i] = m.singular_values.get(i).copied().unwrap_or(0.0);
        if i < m.axes.ncols() && m.axes.nrows() >= 3 {
            let a = m.axes.column(i);
            axes[i] = [a[0], a[1], a[2]];
        }
    }
    EllipsoidFrame { radii, axes }
}

fn measures_frame(m: &Measures, jlm: Option<f64>) -> MeasuresFrame {
    MeasuresFrame {
        yoshikawa: m.yoshikawa,
        isotropy: m.isotropy,
        hong: m.hong,
        condition_number: m.condition_number,
        jlm,
    }
}

/// One arm's warnings: near a singularity and joints near a limit (the core's measures,
/// [`seaarms_core::sim::measures`], with its thresholds), relief valves open, the jaw's bar
/// slipping (`slip:left`), the jaw's orientation not held in a Cartesian translation
/// (`orientation_lost:left`: a limit or a singularity, [`ORIENTATION_LOST_RAD`]). The one
/// rule behind the frames' and the summaries' `warnings`.
fn arm_warnings(live: &Live, arm: Arm, warnings: &mut Vec<String>) {
    let name = arm_name(arm);
    let state = live.sim.arm(arm);
    let m = &live.measures.arms[arm.index()];
    if m.near_singularity {
        warnings.push(format!("near_singularity:{name}"));
    }
    for (i, near) in m.near_limits.iter().enumerate() {
        if *near {
            warnings.push(format!("near_joint_limit:{name}:{i}"));
        }
    }
    for (i, open) in state.relief_open.iter().enumerate() {
        if *open {
            warnings.push(format!("relief:{name}:{i}"));
        }
    }
    if state.grip.slipping {
        warnings.push(format!("slip:{name}"));
    }
    if live.operator.orientation_error_rad(arm) > ORIENTATION_LOST_RAD {
        warnings.push(format!("orientation_lost:{name}"));
    }
}

/// The warnings the last published frame carried (`near_singularity:left`,
/// `near_joint_limit:right:3`, `relief:left:2`, …; measures as published, valves and grips
/// as now), without building a frame.
pub fn warnings(live: &Live) -> Vec<String> {
    let mut warnings = Vec::new();
    for arm in Arm::BOTH {
        arm_warnings(live, arm, &mut warnings);
    }
    warnings
}

/// One arm's frame from the simulation and the published measures, with its warnings.
fn arm_frame(live: &Live, arm: Arm, warnings: &mut Vec<String>) -> ArmFrame {
    let sim = &live.sim;
    let state = sim.arm(arm);
    let m = &live.measures.arms[arm.index()];
    arm_warnings(live, arm, warnings);
    let joint_frames = sim.joint_frames(arm).iter().map(PoseOut::from).collect();
    let w = state.contact_wrench;
    ArmFrame {
        q: state.q,
        qd: state.qd,
        p_in: state.p_in,
        p_out: state.p_out,
        jaw_opening_m: state.jaw_opening_m,
        holding: state.holding,
        contact: state.contact,
        pose: (&sim.end_effector(arm)).into(),
        joint_frames,
        ellipsoid: ellipsoid(&m.translational),
        measures: measures_frame(&m.translational, Some(m.jlm)),
        contact_force_n: [w[0], w[1], w[2]],
        contact_torque_nm: [w[3], w[4], w[5]],
        relief_open: state.relief_open,
        grip_load: state.grip.load_fraction,
        slipping: state.grip.slipping,
        capture: if state.holding {
            None
        } else {
            sim.in_capture_range(arm).map(|g| g.as_str())
        },
        touch: touch_out(&sim.contacts().arms[arm.index()]),
        strikes: sim.contacts().arms[arm.index()].strikes.iter().sum(),
    }
}

/// The strongest contact of an arm's report, for the frame.
fn touch_out(c: &ArmContacts) -> Option<TouchOut> {
    let s = c.strongest.filter(|s| s.normal_force_n > 0.0)?;
    Some(TouchOut {
        partner: s.partner.as_str(),
        part: part_name(s.part),
        point_m: s.point_m,
        force_n: s.normal_force_n,
        total_force_n: c.total_normal_force_n,
        depth_m: s.depth_m,
    })
}

/// `link-0` … `link-5`, `wrist`, `finger-0`, `finger-1`.
pub fn part_name(p: ArmPart) -> String {
    match p {
        ArmPart::Link(i) => format!("link-{i}"),
        ArmPart::Wrist => "wrist".into(),
        ArmPart::Finger(i) => format!("finger-{i}"),
    }
}

/// Builds the frame for a live state (a session's, or a replay's).
/// The measures are computed here, once per frame ([`seaarms_core::sim::measures::measures`]),
/// and kept as the session's published ones ([`Live::measures`]).
pub fn build_frame(live: &mut Live) -> StateFrame {
    live.measures = measures(&live.sim);
    let mut warnings = Vec::new();
    let left = arm_frame(live, Arm::Left, &mut warnings);
    let right = arm_frame(live, Arm::Right, &mut warnings);
    let sim = &live.sim;
    let dual = live.measures.dual.as_ref().map(|m| DualFrame {
        ellipsoid: ellipsoid(m),
        measures: measures_frame(m, None),
    });
    let object = sim.object();
    let v = object.velocity;
    let internal = sim.internal_wrench();
    StateFrame {
        t: sim.time_s(),
        seq: live.frame_seq,
        input_seq: live.input_seq,
        paused: live.paused(),
        awaiting_ready: live.awaiting_ready(),
        practice: live
            .practice
            .as_ref()
            .map(|f| crate::protocol::PracticeOut {
                attempt: f.attempt.clone(),
                t: f.t_s(),
            }),
        paused_by: live.paused_by(),
        settings: live.settings(),
        arms: ArmsFrame { left, right },
        dual,
        object: ObjectFrame {
            pose: (&object.pose).into(),
            velocity: [v.x, v.y, v.z],
        },
        grasp: sim.grasp_state(),
        internal_force_n: [internal[0], internal[1], internal[2]],
        internal_torque_nm: [internal[3], internal[4], internal[5]],
        relief_events: sim.relief_events(),
        warnings,
        // Frames go to every client: a silent fault must not be in them at all.
        faults: live.faults.iter().filter(|f| !f.silent).copied().collect(),
        scenario: live.scenario.name().to_string(),
        exercise: live.exercise.as_ref().map(|run| run.status(sim)),
        panel: sim.panel().map(|p| crate::protocol::PanelFrame {
            valve_angle_deg: p.valve_angle_rad.to_degrees(),
            stab_phase: p.stab_phase.as_str(),
            stab_pose: (&p.stab_pose).into(),
            stab_depth_m: p.stab_depth_m,
            side_load_n: p.side_load_n,
        }),
        current: sim.environment().water().map(|w| w.current),
        visibility_m: live.visibility_m,
    }
}
