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
    /// A cylinder driving the joint through a four-bar ("dog-bone") linkage, as excavator
    /// buckets and heavy-duty manipulator wrists use to turn a joint through 120°–180° with a
    /// nearly constant lever: a rocker pivoted on the parent link at `rocker_pivot_m` (length
    /// `rocker_m`), a dog-bone link (`dogbone_m`) from the rocker's tip P to a crank pin on the
    /// child link at radius `crank_m`, angle `crank_angle_rad` + q, and the cylinder from the
    /// parent pin `cylinder_pin_m` to P. Coordinates are in the plane normal to the joint axis,
    /// fixed to the parent link, origin on the axis (m). P is the intersection of the circle of
    /// radius `rocker_m` about the pivot with the circle of radius `dogbone_m` about the crank
    /// pin, on the side `branch` (±1) of the pivot-to-pin line. x = |P − C|, and Ĵ = dx/dq in
    /// closed form by differentiating both circle constraints:
    /// Ṗ = λ·(P − R)^⊥ with λ = ((P − B)·Ḃ) / ((P − B)·(P − R)^⊥), Ḃ = B^⊥, Ĵ = (P − C)·Ṗ / x.
    /// The designs in [`crate::hydraulics::HydraulicParams::magnum`] keep both transmission
    /// angles away from the toggle positions over the joint range, so the solve is regular
    /// there; outside it (an end stop's few mrad) the circle intersection is clamped, never NaN.
    FourBar {
        /// Crank radius on the child link (m).
        crank_m: f64,
        /// Angle of the crank pin at q = 0 in the parent frame (rad).
        crank_angle_rad: f64,
        /// Rocker pivot on the parent link (m).
        rocker_pivot_m: [f64; 2],
        /// Rocker length, pivot to P (m).
        rocker_m: f64,
        /// Dog-bone length, P to the crank pin (m).
        dogbone_m: f64,
        /// Cylinder's parent-side pin (m).
        cylinder_pin_m: [f64; 2],
        /// Which intersection of the two circles P is (±1).
        branch: f64,
    },
    /// A rotary actuator (vane, rack-and-pinion or motor): x = q, Ĵ = 1; "area" is the
    /// volumetric displacement (m³/rad).
    Rotary,
}

/// The rotation of `v` by +90° in its plane.
fn perp(v: [f64; 2]) -> [f64; 2] {
    [-v[1], v[0]]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// Smallest |denominator| of the four-bar's rate solve (m²), a guard against division by zero
/// at a toggle position (never reached inside a design's range).
const TOGGLE_GUARD_M2: f64 = 1e-12;

/// The moving points of a [`Linkage::FourBar`] at one joint angle, with its fixed pins (m).
struct FourBarPoints {
    /// Crank pin B on the child link.
    b: [f64; 2],
    /// Rocker tip P (cylinder rod pin).
    p: [f64; 2],
    /// Rocker pivot R.
    pivot: [f64; 2],
    /// Cylinder's parent pin C.
    cylinder_pin: [f64; 2],
}

/// The points of `link` at joint angle `q` if it is a [`Linkage::FourBar`]: B on its circle
/// about the axis, P where the rocker's and dog-bone's circles meet (law of cosines at the
/// pivot, clamped so a pose just outside the linkage's reach stays finite).
fn four_bar_points(link: &Linkage, q: f64) -> Option<FourBarPoints> {
    let Linkage::FourBar {
        crank_m,
        crank_angle_rad,
        rocker_pivot_m: pivot,
        rocker_m,
        dogbone_m,
        cylinder_pin_m,
        branch,
    } = *link
    else {
        return None;
    };
    let (s, c) = (crank_angle_rad + q).sin_cos();
    let b = [crank_m * c, crank_m * s];
    let rb = sub(b, pivot);
    let d = dot(rb, rb).sqrt().max(1e-12);
    let cos_delta = ((rocker_m * rocker_m + d * d - dogbone_m * dogbone_m) / (2.0 * rocker_m * d))
        .clamp(-1.0, 1.0);
    let theta = rb[1].atan2(rb[0]) + branch.signum() * cos_delta.acos();
    let p = [
        pivot[0] + rocker_m * theta.cos(),
        pivot[1] + rocker_m * theta.sin(),
    ];
    Some(FourBarPoints {
        b,
        p,
        pivot,
        cylinder_pin: cylinder_pin_m,
    })
}

/// Rocker-side and crank-side transmission quality of a [`Linkage::FourBar`] at `q`: |sin|
/// of the angle between the dog-bone and the rocker, and between the dog-bone and the crank
/// (1 = ideal, 0 = toggle); `None` for other linkages. Used by the design checks.
pub fn four_bar_transmission(link: &Linkage, q: f64) -> Option<(f64, f64)> {
    let pts = four_bar_points(link, q)?;
    let (bp, rp) = (sub(pts.p, pts.b), sub(pts.p, pts.pivot));
    let sin_between = |u: [f64; 2], v: [f64; 2]| {
        (u[0] * v[1] - u[1] * v[0]).abs() / (dot(u, u) * dot(v, v)).sqrt().max(1e-24)
    };
    Some((sin_between(bp, rp), sin_between(bp, pts.b)))
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
            Linkage::FourBar { .. } => {
                let Some(FourBarPoints {
                    b,
                    p,
                    pivot,
                    cylinder_pin,
                }) = four_bar_points(self, q)
                else {
                    return (0.0, 0.0);
                };
                let (pb, pr) = (sub(p, b), perp(sub(p, pivot)));
                let den = dot(pb, pr);
                let den = if den.abs() < TOGGLE_GUARD_M2 {
                    TOGGLE_GUARD_M2.copysign(den)
                } else {
                    den
                };
                let lambda = dot(pb, perp(b)) / den;
                let pdot = [lambda * pr[0], lambda * pr[1]];
                let pc = sub(p, cylinder_pin);
                let x = dot(pc, pc).sqrt().max(1e-12);
                (x, dot(pc, pdot) / x)
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

    /// The Magnum four-bar linkages: P satisfies both circle constraints (rocker and dog-bone
    /// lengths), Ĵ equals a central difference of x(q) over the range ± 0.05 rad (the closed
    /// form differentiates the constraints; this checks it independently), Ĵ > 0 (extending
    /// the cylinder raises q), Ĵ_max/Ĵ_min ≤ 1.05 and both transmission |sin| ≥ 0.35.
    #[test]
    fn four_bar_lever_is_the_derivative_of_the_length() {
        use crate::hydraulics::{FOUR_BAR_DESIGNS, magnum_four_bar};
        let spans_deg = [90.0f64, 130.0, 115.0];
        for (k, span) in spans_deg.iter().enumerate() {
            let (lo, hi) = (-0.3, -0.3 + span.to_radians());
            let link = magnum_four_bar(k, lo, hi);
            let Linkage::FourBar {
                crank_angle_rad,
                rocker_m,
                dogbone_m,
                ..
            } = link
            else {
                panic!("four-bar expected");
            };
            let (mut jmin, mut jmax) = (f64::INFINITY, 0.0f64);
            for i in 0..=200 {
                let q = lo - 0.05 + (hi - lo + 0.1) * i as f64 / 200.0;
                let pts = four_bar_points(&link, q).expect("four-bar");
                let (b, p, rocker_pivot_m) = (pts.b, pts.p, pts.pivot);
                let dist = |u: [f64; 2], v: [f64; 2]| dot(sub(u, v), sub(u, v)).sqrt();
                assert!((dist(p, rocker_pivot_m) - rocker_m).abs() < 1e-12);
                assert!((dist(p, b) - dogbone_m).abs() < 1e-12, "{k} {q}");
                let step = 1e-6;
                let (x, jh) = link.coordinate(q);
                let fd = (link.coordinate(q + step).0 - link.coordinate(q - step).0) / (2.0 * step);
                assert!((jh - fd).abs() < 1e-8, "{k} q {q}: {jh} vs {fd}");
                assert!(x > 0.0 && jh > 0.0);
                let (t1, t2) = four_bar_transmission(&link, q).expect("four-bar");
                assert!(t1 >= 0.35 && t2 >= 0.35, "{k} q {q}: {t1} {t2}");
                jmin = jmin.min(jh);
                jmax = jmax.max(jh);
            }
            assert!(jmax / jmin <= 1.05, "{k}: {jmin}..{jmax}");
            assert!((FOUR_BAR_DESIGNS[k][0] - (crank_angle_rad + lo)).abs() < 1e-12);
        }
    }
}
