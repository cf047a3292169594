//! State frames: what the page draws, computed once per frame per session (never per client):
//! joint frames, end-effector poses, translational manipulability ellipsoids and measures
//! per arm and dual (Lim eqs 3.62, 3.68; Hong eq. 4.1), JLM (Jun eq. 16), forces, warnings.

use nalgebra::{DMatrix, Isometry3, Matrix6, Vector6};
use seaarms_core::kinematics::forward_kinematics;
use seaarms_core::manipulability::{Measures, dual_measures, jlm, measures};
use seaarms_core::sim::{LEFT, RIGHT};

use super::{Live, Session};
use crate::api::wire::PoseOut;
use crate::protocol::{
    ArmFrame, ArmsFrame, DualFrame, EllipsoidFrame, MeasuresFrame, ObjectFrame, StateFrame,
};

/// Isotropy below which an arm is reported near a singularity.
pub const NEAR_SINGULAR_ISOTROPY: f64 = 0.05;
/// A joint within this fraction of its range from a limit is reported near the limit.
pub const NEAR_LIMIT_FRACTION: f64 = 0.05;
/// Cartesian mode: end-effector linear speed at full stick (m/s).
pub const CARTESIAN_MAX_LINEAR_M_S: f64 = 0.2;
/// Cartesian mode: end-effector angular speed at full stick (rad/s).
pub const CARTESIAN_MAX_ANGULAR_RAD_S: f64 = 0.5;

fn ellipsoid(m: &Measures) -> EllipsoidFrame {
    let mut radii = [0.0; 3];
    let mut axes = [[0.0; 3]; 3];
    for i in 0..3 {
        radii[i] = m.singular_values.get(i).copied().unwrap_or(0.0);
        if let Some(a) = m.ellipsoid.axes.get(i) {
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

fn translational(j: &Matrix6<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(3, 6, |r, c| j[(r, c)])
}

/// Builds the frame for the session's current state.
pub fn build_frame(session: &Session, live: &mut Live) -> StateFrame {
    let sim = &live.sim;
    let mut warnings = Vec::new();
    let mut jt = [DMatrix::zeros(3, 6), DMatrix::zeros(3, 6)];
    let mut arms = Vec::with_capacity(2);
    for (arm, name) in [(LEFT, "left"), (RIGHT, "right")] {
        let model = &session.models[arm];
        let state = sim.arm(arm);
        jt[arm] = translational(sim.jacobian_world(arm));
        let m = measures(&jt[arm]).unwrap_or_else(|_| zero_measures());
        let p_jlm = jlm(model, &state.q);
        if m.isotropy < NEAR_SINGULAR_ISOTROPY {
            warnings.push(format!("near_singularity:{name}"));
        }
        for (i, (q, joint)) in state.q.iter().zip(&model.joints).enumerate() {
            if joint.is_limited() {
                let span = joint.limits[1] - joint.limits[0];
                if q - joint.limits[0] < NEAR_LIMIT_FRACTION * span
                    || joint.limits[1] - q < NEAR_LIMIT_FRACTION * span
                {
                    warnings.push(format!("near_joint_limit:{name}:{i}"));
                }
            }
        }
        for (i, open) in state.relief_open.iter().enumerate() {
            if *open {
                warnings.push(format!("relief:{name}:{i}"));
            }
        }
        let base: Isometry3<f64> = sim.params().arms[arm].base;
        forward_kinematics(model, &mut live.kin[arm], &state.q);
        let joint_frames = live.kin[arm]
            .joint_frames
            .iter()
            .map(|f| PoseOut::from(&(base * f)))
            .collect();
        let w = state.contact_wrench;
        arms.push(ArmFrame {
            q: state.q,
            qd: state.qd,
            p_in: state.p_in,
            p_out: state.p_out,
            jaw_opening_m: state.jaw_opening_m,
            holding: state.holding,
            contact: state.contact,
            pose: (&sim.end_effector(arm)).into(),
            joint_frames,
            ellipsoid: ellipsoid(&m),
            measures: measures_frame(&m, Some(p_jlm)),
            contact_force_n: [w[0], w[1], w[2]],
            contact_torque_nm: [w[3], w[4], w[5]],
            relief_open: state.relief_open,
        });
    }
    let both = sim.arm(LEFT).holding && sim.arm(RIGHT).holding;
    let dual = if both {
        dual_measures(&jt[LEFT], &jt[RIGHT])
            .ok()
            .map(|m| DualFrame {
                ellipsoid: ellipsoid(&m),
                measures: measures_frame(&m, None),
            })
    } else {
        None
    };
    let right = arms.pop().unwrap_or_else(|| unreachable_arm());
    let left = arms.pop().unwrap_or_else(|| unreachable_arm());
    let object = sim.object();
    let v = object.velocity;
    let internal = sim.internal_wrench();
    StateFrame {
        t: sim.time_s(),
        seq: live.frame_seq,
        input_seq: live.input_seq,
        paused: live.paused,
        settings: live.settings,
        arms: ArmsFrame { left, right },
        dual,
        object: ObjectFrame {
            pose: (&object.pose).into(),
            velocity: [v.x, v.y, v.z],
        },
        grasp: sim.grasp_state().as_str(),
        internal_force_n: [internal[0], internal[1], internal[2]],
        internal_torque_nm: [internal[3], internal[4], internal[5]],
        relief_events: sim.relief_events(),
        warnings,
        faults: live.faults.clone(),
    }
}

fn zero_measures() -> Measures {
    Measures::from_spectrum(&[0.0; 3], &DMatrix::identity(3, 3), 0.0)
}

fn unreachable_arm() -> ArmFrame {
    // Both arms are always pushed above; this keeps the code free of panics regardless.
    ArmFrame {
        q: [0.0; 6],
        qd: [0.0; 6],
        p_in: [0.0; 6],
        p_out: [0.0; 6],
        jaw_opening_m: 0.0,
        holding: false,
        contact: false,
        pose: (&Isometry3::identity()).into(),
        joint_frames: Vec::new(),
        ellipsoid: EllipsoidFrame {
            radii: [0.0; 3],
            axes: [[0.0; 3]; 3],
        },
        measures: MeasuresFrame {
            yoshikawa: 0.0,
            isotropy: 0.0,
            hong: 0.0,
            condition_number: None,
            jlm: None,
        },
        contact_force_n: [0.0; 3],
        contact_torque_nm: [0.0; 3],
        relief_open: [false; 6],
    }
}

/// Cartesian mode: the stick command (fractions of the maximum end-effector speeds, world
/// frame) to a joint-velocity reference by damped least squares on the world Jacobian,
/// q̇ = Jᵀ(JJᵀ + λ²I)⁻¹ẋ (Nakamura; Kilic eq. 0.2 with a damped pseudo-inverse), with λ = 0.05
/// so the reference stays bounded near singularities.
pub fn cartesian_to_joint_velocity(live: &Live, arm: usize) -> [f64; 6] {
    let cmd = live.cartesian[arm];
    let xdot = Vector6::new(
        cmd[0] * CARTESIAN_MAX_LINEAR_M_S,
        cmd[1] * CARTESIAN_MAX_LINEAR_M_S,
        cmd[2] * CARTESIAN_MAX_LINEAR_M_S,
        cmd[3] * CARTESIAN_MAX_ANGULAR_RAD_S,
        cmd[4] * CARTESIAN_MAX_ANGULAR_RAD_S,
        cmd[5] * CARTESIAN_MAX_ANGULAR_RAD_S,
    );
    if xdot.iter().all(|v| *v == 0.0) {
        return [0.0; 6];
    }
    let j = live.sim.jacobian_world(arm);
    let lambda2 = 0.05 * 0.05;
    let a = j * j.transpose() + Matrix6::identity() * lambda2;
    match a.cholesky() {
        Some(ch) => {
            let qd = j.transpose() * ch.solve(&xdot);
            let mut out = [0.0; 6];
            for (o, v) in out.iter_mut().zip(qd.iter()) {
                *o = if v.is_finite() { *v } else { 0.0 };
            }
            out
        }
        None => [0.0; 6],
    }
}
