//! Cartesian teleoperation: the operator's end-effector speed command (stick deflections,
//! world frame) to a joint-velocity reference for the joint servo
//! ([`crate::sim::ArmInput::joint_velocity_ref`]), by task-oriented redundancy resolution
//! (Jun eq. 21, [`Redundancy::step`]).

use nalgebra::{UnitQuaternion, Vector3};

use crate::hydraulics::N_ACT;
use crate::model::Model;
use crate::redundancy::Redundancy;

/// End-effector linear speed at full stick (m/s): 0.2.
pub const MAX_LINEAR_SPEED_M_S: f64 = 0.2;
/// End-effector angular speed at full stick (rad/s): 0.5.
pub const MAX_ANGULAR_SPEED_RAD_S: f64 = 0.5;

/// Joint velocities (rad/s) that move arm `model` (in its own base frame, whose orientation in
/// the world is `base_rotation`) at joint angles `q` with the end-effector twist
/// `command` ∘ (max speeds): `command` is [vx vy vz wx wy wz] in the world frame as fractions
/// of [`MAX_LINEAR_SPEED_M_S`] and [`MAX_ANGULAR_SPEED_RAD_S`].
///
/// Translational rows only when the angular command is zero and `keep_orientation` is false,
/// so the three spare DOF keep the arm away from joint limits and singularities
/// (P = α·TOMM + (1−α)·JLM rises in the null space); all six rows otherwise. Set
/// `keep_orientation` while both jaws hold the object: in that closed chain the tool's
/// orientation is not spare — each arm's null-space motion would turn its own jaw against
/// the other through the box (docs/physics.md, "Moving the pair in Cartesian mode") — so a
/// translational command holds it (zero angular rate on rows 4–6). Damped near singularities
/// and scaled to the joints' velocity limits by `resolver`'s settings. The null-space gain is
/// `resolver`'s ε times the stick's largest deflection (≤ 1): the spare-DOF motion scales with
/// the command like the task motion. Zero for a zero command, and for a command the
/// resolver refuses (e.g. non-finite numbers); non-finite results become 0. `dt_s` is the
/// control period (s) the resolver's q + q̇·dt refers to.
pub fn cartesian_to_joint_velocity(
    resolver: &mut Redundancy,
    model: &Model,
    base_rotation: &UnitQuaternion<f64>,
    q: &[f64; N_ACT],
    command: &[f64; 6],
    keep_orientation: bool,
    dt_s: f64,
) -> [f64; N_ACT] {
    if command.iter().all(|v| *v == 0.0) {
        return [0.0; N_ACT];
    }
    // World → arm base frame (velocities rotate only).
    let r = base_rotation.inverse();
    let c = command;
    let lin = r * Vector3::new(c[0], c[1], c[2]) * MAX_LINEAR_SPEED_M_S;
    let ang = r * Vector3::new(c[3], c[4], c[5]) * MAX_ANGULAR_SPEED_RAD_S;
    let full = [lin.x, lin.y, lin.z, ang.x, ang.y, ang.z];
    let (rows, rdot): (&[usize], &[f64]) = if ang.norm() == 0.0 && !keep_orientation {
        (&[0, 1, 2], &full[..3])
    } else {
        (&[0, 1, 2, 3, 4, 5], &full[..])
    };
    // The null-space motion scales with the stick: ε·s with s the largest deflection (fraction
    // of full stick, ≤ 1), so a stick barely off zero barely moves the arm's spare DOF (a
    // 10⁻⁶ stick had turned the arm by 18° in 4 s at the full ε), and full stick gets the
    // resolver's own ε.
    let deflection = command.iter().fold(0.0_f64, |m, v| m.max(v.abs())).min(1.0);
    let epsilon = resolver.params.epsilon;
    resolver.params.epsilon = epsilon * deflection;
    let mut out = [0.0; N_ACT];
    if let Ok(qd) = resolver.step(model, q, rdot, rows, dt_s) {
        for (o, v) in out.iter_mut().zip(qd) {
            *o = if v.is_finite() { *v } else { 0.0 };
        }
    }
    resolver.params.epsilon = epsilon;
    out
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3};

    use super::*;
    use crate::kinematics::end_effector_pose;
    use crate::redundancy::RedundancyParams;
    use crate::{ModelSpec, robots};

    fn magnum() -> Model {
        let spec: ModelSpec =
            serde_json::from_str(robots::builtin_text("magnum").expect("built-in")).expect("json");
        Model::from_spec(&spec).expect("model")
    }

    /// The end-effector twist that the joint velocities produce, in the world frame, by
    /// central finite differences of forward kinematics of the arm placed at `base`
    /// (independent of the Jacobian the resolver uses): position change and rotation vector
    /// of R(q + q̇δ)·R(q − q̇δ)⁻¹, over 2δ.
    fn twist_by_finite_differences(
        model: &Model,
        base: &Isometry3<f64>,
        q: &[f64; N_ACT],
        qd: &[f64; N_ACT],
    ) -> [f64; 6] {
        let placed = model.based_at(base);
        let delta = 1e-6;
        let at = |s: f64| {
            let qs: Vec<f64> = q.iter().zip(qd).map(|(a, b)| a + s * delta * b).collect();
            end_effector_pose(&placed, &qs)
        };
        let (plus, minus) = (at(1.0), at(-1.0));
        let v = (plus.translation.vector - minus.translation.vector) / (2.0 * delta);
        let w = (plus.rotation * minus.rotation.inverse()).scaled_axis() / (2.0 * delta);
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// Away from singularities and below the velocity limits, the joint velocities reproduce
    /// the commanded world twist (finite differences of FK, with the base rotated so that the
    /// world→base conversion matters): all six components for a full command, the three
    /// linear ones for a translational command.
    #[test]
    fn joint_velocities_reproduce_the_commanded_twist() {
        let m = magnum();
        let base = Isometry3::from_parts(
            Translation3::new(0.3, 1.0, -0.1),
            UnitQuaternion::from_euler_angles(0.2, -0.1, 1.3),
        );
        let q = crate::sim::INITIAL_Q;
        let params = RedundancyParams {
            // The plain solution: no null-space motion, so the check is exact to round-off.
            epsilon: 0.0,
            ..RedundancyParams::default()
        };
        let commands = [
            [0.1, -0.05, 0.08, 0.0, 0.0, 0.0],
            [0.05, 0.02, -0.04, 0.06, -0.03, 0.05],
        ];
        for command in commands {
            let mut resolver = Redundancy::new(&m, params);
            let qd = cartesian_to_joint_velocity(
                &mut resolver,
                &m,
                &base.rotation,
                &q,
                &command,
                false,
                1e-3,
            );
            assert!(qd.iter().any(|v| *v != 0.0));
            let twist = twist_by_finite_differences(&m, &base, &q, &qd);
            let rows = if command[3..].iter().all(|v| *v == 0.0) {
                3
            } else {
                6
            };
            for k in 0..rows {
                let max = if k < 3 {
                    MAX_LINEAR_SPEED_M_S
                } else {
                    MAX_ANGULAR_SPEED_RAD_S
                };
                let want = command[k] * max;
                assert!(
                    (twist[k] - want).abs() < 1e-6,
                    "{command:?} row {k}: {} vs {want}",
                    twist[k]
                );
            }
        }
    }

    /// A zero command gives zero, and a non-finite one no motion (refused, never NaN).
    #[test]
    fn zero_and_non_finite_commands_give_no_motion() {
        let m = magnum();
        let mut resolver = Redundancy::new(&m, RedundancyParams::default());
        let rot = UnitQuaternion::identity();
        let q = crate::sim::INITIAL_Q;
        let zero = cartesian_to_joint_velocity(&mut resolver, &m, &rot, &q, &[0.0; 6], false, 1e-3);
        assert_eq!(zero, [0.0; N_ACT]);
        let bad = [f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0];
        let out = cartesian_to_joint_velocity(&mut resolver, &m, &rot, &q, &bad, false, 1e-3);
        assert!(out.iter().all(|v| v.is_finite()), "{out:?}");
    }
}
