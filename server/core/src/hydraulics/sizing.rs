//! Magnum actuator sizing from Lim Table 1-1 ([`HydraulicParams::magnum`]) and the
//! constants it uses.

use super::{ActuatorParams, HydraulicParams, JawParams, Linkage, N_ACT};
use crate::Error;
use crate::dynamics::{DynData, Inertials, rnea};
use crate::kinematics::{KinData, jacobian};
use crate::model::Model;

/// Payload at the jaw for the holding requirement, Lim Table 1-1 "lift 295 kg at full extension".
pub const MAGNUM_LIFT_KG: f64 = 295.0;
/// Margin of the holding side over the 295 kg requirement at supply pressure: 1.15.
pub const HOLD_MARGIN: f64 = 1.15;
/// Rod-side to bore-side area ratio of the linear cylinders (typical single-rod cylinder): 0.8.
pub const AREA_RATIO: f64 = 0.8;
/// Nominal joint speeds, Lim Table 1-1 (°/s): 20, 20, 30, 30, 30, 150.
pub const MAGNUM_SPEEDS_DEG_S: [f64; N_ACT] = [20.0, 20.0, 30.0, 30.0, 30.0, 150.0];

/// Floor on the design torque of each joint (N·m), for joints the full-extension load does
/// not exercise: swing 2 000 (lateral loads of the order of the elbow's), shoulder/elbow/
/// pitch 0 (sized by the load), yaw 600, rotate 150 (typical wrist torques of 7-function
/// subsea arms; assumed).
pub const MAGNUM_TORQUE_FLOOR_NM: [f64; N_ACT] = [2000.0, 0.0, 0.0, 0.0, 600.0, 150.0];

/// Dimensionless four-bar designs ([`Linkage::FourBar`], crank radius 1) for the shoulder (90°),
/// elbow (130°) and pitch (115°) cylinders: [crank angle at the joint's lower limit (rad),
/// rocker pivot x, y, rocker, dog-bone, cylinder pin x, y, branch]. Found by a random search
/// and hill climb (`tests/four_bar_design.rs`, ignored test `search_four_bar_designs`)
/// minimizing Ĵ_max/Ĵ_min over the range ± 0.05 rad subject to both transmission angles ≥ 20.5°
/// (|sin| ≥ 0.35) and an extended cylinder ≤ 1.75 × its retracted length (a cylinder's dead
/// length makes longer strokes impractical). Ĵ_max/Ĵ_min = 1.025/1.042/1.024.
pub const FOUR_BAR_DESIGNS: [[f64; 8]; 3] = [
    [2.0149, 1.4008, 0.1452, 2.7022, 1.8401, -1.9127, 1.7397, 1.0],
    [
        2.8196, 0.0588, 1.2709, 2.7916, 1.6933, -5.0698, -5.0849, 1.0,
    ],
    [2.9106, 0.0604, 1.2165, 2.7854, 1.698, -5.1526, -5.1035, 1.0],
];

/// Mean lever Ĵ of the shoulder, elbow and pitch linkages over their ranges (m): 0.096, 0.086,
/// 0.058 — the mid-range levers of the slider-cranks these linkages replace (pins 0.35/0.10,
/// 0.30/0.09, 0.25/0.06 m at 90°), so cylinder bores and pressures stay as before.
pub const MEAN_LEVER_M: [f64; 3] = [0.096, 0.086, 0.058];

/// The four-bar linkage of cylinder `k` (0 shoulder, 1 elbow, 2 pitch) for a joint whose
/// lower limit is `q_lo` (rad): [`FOUR_BAR_DESIGNS`]`[k]` scaled to mean lever
/// [`MEAN_LEVER_M`]`[k]` over `[q_lo, q_hi]`.
pub fn magnum_four_bar(k: usize, q_lo: f64, q_hi: f64) -> Linkage {
    let at = |scale: f64| {
        let d = FOUR_BAR_DESIGNS[k];
        Linkage::FourBar {
            crank_m: scale,
            crank_angle_rad: d[0] - q_lo,
            rocker_pivot_m: [scale * d[1], scale * d[2]],
            rocker_m: scale * d[3],
            dogbone_m: scale * d[4],
            cylinder_pin_m: [scale * d[5], scale * d[6]],
            branch: d[7],
        }
    };
    // Ĵ scales with the linkage: the mean over the range at unit scale sets the scale.
    let unit = at(1.0);
    const N: usize = 64;
    let mean = (0..=N)
        .map(|i| {
            unit.coordinate(q_lo + (q_hi - q_lo) * i as f64 / N as f64)
                .1
        })
        .sum::<f64>()
        / (N + 1) as f64;
    at(MEAN_LEVER_M[k] / mean)
}

/// The "full extension" posture of the Magnum model used for sizing and for the holding test:
/// all joints at 0 — upper arm, forearm and wrist in line and horizontal, 1.51 m from the
/// shoulder pivot to the jaw centre (Table 1-1: reach 1.5 m).
pub const MAGNUM_FULL_EXTENSION: [f64; N_ACT] = [0.0; N_ACT];

impl HydraulicParams {
    /// Magnum hydraulics sized from Lim Table 1-1 by these rules:
    ///
    /// * Shoulder, elbow, pitch: linear cylinders (geometry below); swing, yaw: rotary
    ///   actuators; rotate: continuous hydraulic motor.
    /// * Design torque of joint j = max(1.15 × |G_j| at [`MAGNUM_FULL_EXTENSION`] with 295 kg at
    ///   the jaw (in air), [`MAGNUM_TORQUE_FLOOR_NM`]). The side of the actuator that holds
    ///   that load gets area = design torque / (Ĵ · supply); the other side is 0.8× (or
    ///   1/0.8×) for cylinders, equal for rotary actuators. So 295 kg is held below supply
    ///   pressure, and 590 kg needs ≈ 1.7× the relief setting: it cannot be held.
    /// * Flow gain so that full command moves the unloaded joint at its Table 1-1 speed at
    ///   mid-range: extend and retract speeds of a cylinder with area ratio α differ by √α,
    ///   so the gain puts their geometric mean on the nominal speed.
    /// * Cylinder linkages (shoulder, elbow, pitch): four-bar "dog-bone" linkages
    ///   ([`FOUR_BAR_DESIGNS`], scaled so the mean lever is [`MEAN_LEVER_M`]) whose lever Ĵ
    ///   varies by 2.5/4.2/2.4 % over the 90/130/115° ranges, so the full-command speed is
    ///   nearly constant over the whole range (issue 17; a plain slider-crank's lever falls to
    ///   sin 25° ≈ 0.42 of its peak at the ends of a 130° range). Assumed; Lim prints none.
    /// * Dead volume 0.15 L per side (≈ 3 m of 3/8" hose); damping 5·10⁴ N·s/m for cylinders
    ///   (README range 10³–10⁵; the upper half, because a closed-centre valve adds no damping and
    ///   the cooperative loop needs the oil-column resonance damped), 200/50/5 N·m·s/rad for
    ///   swing/yaw/rotate.
    pub fn magnum(model: &Model, inertials: &Inertials) -> Result<HydraulicParams, Error> {
        if model.dof() != N_ACT {
            return Err(Error::InvalidModel {
                reason: "Magnum hydraulics need a 6-joint model".into(),
            });
        }
        let supply = 6.89e6;
        // Holding torques at full extension with the payload.
        let q = MAGNUM_FULL_EXTENSION;
        let mut kin = KinData::new(model);
        jacobian(model, &mut kin, &q);
        let mut dd = DynData::new(model);
        let mut g = [0.0; N_ACT];
        let g_vec = nalgebra::Vector3::new(0.0, 0.0, -9.81);
        rnea(
            model,
            inertials,
            &kin,
            &[0.0; N_ACT],
            &[0.0; N_ACT],
            &g_vec,
            0.0,
            &mut g,
            &mut dd,
        );
        // Payload weight at the tool: τ = −J_vᵀ·(m·g).
        for (j, gj) in g.iter_mut().enumerate() {
            let col = kin.jacobian.column(j);
            *gj -= col[2] * (-9.81 * MAGNUM_LIFT_KG);
        }
        // Cylinder joints and their four-bar designs (shoulder, elbow, pitch); the rest rotary.
        let cylinders: [Option<usize>; N_ACT] = [None, Some(0), Some(1), Some(2), None, None];
        let damping = [200.0, 5.0e4, 5.0e4, 5.0e4, 50.0, 5.0];
        let mut actuators = [ActuatorParams {
            linkage: Linkage::Rotary,
            area_in: 0.0,
            area_out: 0.0,
            x_min: 0.0,
            stroke: 0.0,
            dead_volume_in_m3: 1.5e-4,
            dead_volume_out_m3: 1.5e-4,
            flow_gain: 0.0,
            damping: 0.0,
            continuous: false,
            nominal_speed_rad_s: 0.0,
            design_torque_nm: 0.0,
        }; N_ACT];
        for j in 0..N_ACT {
            let joint = &model.joints[j];
            let (lo, hi) = if joint.is_limited() {
                (joint.limits[0], joint.limits[1])
            } else {
                (-std::f64::consts::PI, std::f64::consts::PI)
            };
            let mid = 0.5 * (lo + hi);
            let omega = MAGNUM_SPEEDS_DEG_S[j].to_radians();
            let torque = (HOLD_MARGIN * g[j].abs()).max(MAGNUM_TORQUE_FLOOR_NM[j]);
            let a = &mut actuators[j];
            a.damping = damping[j];
            a.nominal_speed_rad_s = omega;
            a.design_torque_nm = torque;
            match cylinders[j] {
                Some(k) => {
                    let link = magnum_four_bar(k, lo, hi);
                    let (x_lo, _) = link.coordinate(lo);
                    let (x_hi, _) = link.coordinate(hi);
                    let (_, jh_q) = link.coordinate(q[j]);
                    let (_, jh_mid) = link.coordinate(mid);
                    let hold_area = torque / (jh_q * supply);
                    // τ_act = G holds the arm; G > 0 with Ĵ > 0 needs an extending force (inlet side).
                    let (ai, ao) = if g[j] >= 0.0 {
                        (hold_area, hold_area * AREA_RATIO)
                    } else {
                        (hold_area / AREA_RATIO, hold_area)
                    };
                    a.linkage = link;
                    a.area_in = ai;
                    a.area_out = ao;
                    a.x_min = x_lo;
                    a.stroke = x_hi - x_lo;
                    let alpha = ao / ai;
                    a.flow_gain = omega * jh_mid * ai * (1.0 + alpha.powi(3)).sqrt()
                        / (supply.sqrt() * alpha.powf(0.25));
                }
                None => {
                    let d = torque / supply;
                    a.linkage = Linkage::Rotary;
                    a.area_in = d;
                    a.area_out = d;
                    a.x_min = lo;
                    a.stroke = hi - lo;
                    a.continuous = !joint.is_limited();
                    a.flow_gain = omega * d * 2.0f64.sqrt() / supply.sqrt();
                }
            }
        }
        Ok(HydraulicParams {
            supply_pa: supply,
            return_pa: 0.0,
            relief_pa: 1.10 * supply,
            relief_gain: 1.0e-8,
            bulk_modulus_pa: 1.0e9,
            laminar_pa: 2.0e4,
            actuators,
            jaw: JawParams::default(),
        })
    }
}
