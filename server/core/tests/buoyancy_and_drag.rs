//! Buoyancy of the links (issue criterion 1): each uniform link weighs (1 − ρ_water/ρ_link) of
//! its air weight, so RNEA gravity torques scale by exactly that factor. Drag, added mass and
//! the current: tests/water.rs.

mod common;

use nalgebra::Vector3;
use seaarms_core::dynamics::{DynData, Inertials, MAGNUM_LINK_DENSITY_KGM3, rnea};
use seaarms_core::kinematics::{KinData, forward_kinematics};

#[test]
fn buoyancy_scales_gravity_torques() {
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    let q = [0.1, 0.4, -0.9, 0.3, -0.2, 0.5];
    forward_kinematics(&m, &mut kin, &q);
    let g = Vector3::new(0.0, 0.0, -9.81);
    let (mut air, mut water) = ([0.0; 6], [0.0; 6]);
    rnea(
        &m, &inr, &kin, &[0.0; 6], &[0.0; 6], &g, 0.0, &mut air, &mut d,
    );
    rnea(
        &m, &inr, &kin, &[0.0; 6], &[0.0; 6], &g, 1025.0, &mut water, &mut d,
    );
    let k = 1.0 - 1025.0 / MAGNUM_LINK_DENSITY_KGM3;
    for j in 0..6 {
        assert!(
            (water[j] - k * air[j]).abs() < 1e-9 * (1.0 + air[j].abs()),
            "joint {j}"
        );
    }
}
