//! Cylinder-to-joint geometry (Lim eq. 3.53): the actuator coordinate x(q) and its lever
//! Ĵ(q) = dx/dq.

/// How an actuator drives its joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Linkage {
    /// A linear cylinder pinned to the parent link at distance `r_a_m` from the joint axis and
    /// to the child link at `r_b_m`, both in the plane normal to the axis. The angle between
    /// the two pin radii is φ = `phi0_rad` + q, so the cylinder length is
    /// L(q) = √(r_a² + r_b² − 2 r_a r_b cos φ) and Ĵ(q) = dL/dq = r_a r_b sin φ / L: extending
    /// the cylinder increases q. φ stays in (0, π) over the joint range.
    Linear {
        /// Parent-side pin radius (m).
        r_a_m: f64,
        /// Child-side pin radius (m).
        r_b_m: f64,
        /// φ at q = 0 (rad).
        phi0_rad: f64,
    },
    /// A rotary actuator (vane, rack-and-pinion or motor): x = q, Ĵ = 1; "area" is the
    /// volumetric displacement (m³/rad).
    Rotary,
}

impl Linkage {
    /// Actuator coordinate x (m or rad) and Ĵ = dx/dq (m/rad or 1) at joint angle `q`.
    pub fn coordinate(&self, q: f64) -> (f64, f64) {
        match *self {
            Linkage::Linear {
                r_a_m,
                r_b_m,
                phi0_rad,
            } => {
                let (s, c) = (phi0_rad + q).sin_cos();
                let l = (r_a_m * r_a_m + r_b_m * r_b_m - 2.0 * r_a_m * r_b_m * c)
                    .max(1e-12)
                    .sqrt();
                (l, r_a_m * r_b_m * s / l)
            }
            Linkage::Rotary => (q, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ĵ against a central difference of x(q) (an independent check of the closed-form
    /// derivative), and L against the law of cosines at φ = 90° (Pythagoras).
    #[test]
    fn lever_is_the_derivative_of_the_length() {
        let link = Linkage::Linear {
            r_a_m: 0.35,
            r_b_m: 0.10,
            phi0_rad: 1.9,
        };
        for k in 0..200 {
            let q = -1.5 + 0.01 * k as f64;
            let step = 1e-6;
            let (x, jh) = link.coordinate(q);
            let fd = (link.coordinate(q + step).0 - link.coordinate(q - step).0) / (2.0 * step);
            assert!((jh - fd).abs() < 1e-8, "q {q}: {jh} vs {fd}");
            assert!(x > 0.0);
        }
        let (x, jh) = link.coordinate(std::f64::consts::FRAC_PI_2 - 1.9);
        assert!((x - (0.35f64.powi(2) + 0.10f64.powi(2)).sqrt()).abs() < 1e-15);
        assert!((jh - 0.35 * 0.10 / x).abs() < 1e-15);
        assert_eq!(Linkage::Rotary.coordinate(0.7), (0.7, 1.0));
    }
}
