//! The jaw's finite grip on a handle bar: what friction from the clamp force lets one jaw
//! transmit, and the wrench it transmits while the bar slips.
//!
//! # Contact model
//! The jaw is two flat finger pads closing along the tool frame's **y** axis (the page draws
//! the jaw so: z along the jaw, y across the opening) on a flat-sided handle bar of section
//! s × s (s = [`ObjectParams::handle_width_m`], 4 cm; the flat "fishtail" section of ROV grab
//! handles, assumed). The wrench is written in the **bar frame** of the grasp
//! ([`super::Handle::bar_frame`]): x the bar's axis a (from the handle, not the jaw), y the
//! closing axis n made normal to it, z = a × n the direction across the bar in the pads'
//! plane, d (for an aligned jaw within 45° of its depth axis). Each pad presses one flat with
//! the clamp force N (Lim Table 1-1: 150 kgf = 1 471 N at full command) over a w × s patch (w
//! the pad width along the bar, [`GripParams::pad_width_m`]). A contact wrench [f; m] splits
//! into
//!
//! * the **geometry-carried** force along n (one pad pushes the bar; the hydraulically held
//!   fingers do not yield), rigid whatever its size (assumed);
//! * two **pry** moments, each carried by the pads' pressure moving across a pad up to the
//!   moment that tips the bar onto a pad's edge and pries the pads apart (friction plays no
//!   part; the same limit static and sliding): the **roll** about the bar axis a, the pressure
//!   resultant of each pad moving to the flat's edge, s/2 from the axis, M_a = N·s; and the
//!   moment about d, which turns the bar in the plane of a and n, pressing its two ends into
//!   opposite pads: each pad's resultant moves to the pad's end, w/2 along the bar, so
//!   M_d = N·w;
//! * **friction-carried** components, with Coulomb friction μ at both pads:
//!   - the tangential force f_t = |(f_a, f_d)| (sliding along the bar or out of the jaw):
//!     at most F = 2 μ N (two pads);
//!   - the torsion about n (the bar turning in the pads' plane): a uniform pressure N/(w s)
//!     over the patch gives at most μ N ρ̄ per pad, M_n = 2 μ N ρ̄, with ρ̄ the patch's mean
//!     distance from its centre ([`mean_radius`]).
//!
//! The four are combined by the ellipsoidal approximation of the limit surface (Howe &
//! Cutkosky 1996, "Practical force-motion models for sliding manipulation", IJRR 15(6),
//! §4: the set of friction wrenches a planar contact patch can transmit is convex and well
//! approximated by an ellipsoid with the pure-force and pure-moment limits as semi-axes;
//! Goyal, Ruina & Papadopoulos 1991 for the limit surface itself; for a soft finger the
//! same ellipse in (f_t, m_n), Xydas & Kao 1999, "Modeling of contact mechanics and friction
//! limit surfaces for soft fingers in robotics", IJRR 18(9)): the **load fraction**
//!
//! > λ = √((f_t/F)² + (m_n/M_n)² + (m_a/M_a)² + (m_d/M_d)²)
//!
//! is ≤ 1 while the grip holds. The two pry moments enter the same ellipsoid (assumed: a pry
//! moment moves the pads' pressure towards their edges and leaves less of the patch to
//! friction; the ellipsoid is the simplest convex surface through the four pure limits).
//! Beyond it the bar slips and the pads transmit the kinetic wrench: the limited components
//! scaled radially onto the kinetic ellipsoid (μ_k in place of μ_s), in the direction of the
//! wrench the rigid grasp required (which contains the constraint's velocity damping, so it
//! opposes the sliding).
//!
//! # Compliance in torsion
//! Between sticking and sliding the pads are not rigid about the closing axis n: steel wear
//! plates on a bonded elastomer layer ([`GripParams::pad_shear_modulus_pa`],
//! [`GripParams::pad_layer_m`]) twist by τ_n/k, k = [`GripParams::torsion_stiffness`]
//! (1.90·10³ N·m/rad), with damping from the elastomer's loss factor. The grasp constraint
//! carries that direction as a spring-damper (`sim/constraint.rs`, `PadTorsion`); the other
//! five stay rigid. Without it, a jaw on a box still seated on the seabed (≈2·10⁵ N·m/rad
//! about a horizontal axis) turned every 0.1 mrad of the stalled wrist's attitude into
//! ≈14 N·m of torsion, and a one-arm lift by the lifting point slipped at lift-off.

use nalgebra::{Rotation3, Vector3, Vector6};

use super::{Alignment, ObjectParams};

/// Friction and pad geometry of the jaw on a handle (each default in its doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripParams {
    /// Static friction coefficient, pad on handle, wet: 0.30. Hardened steel on steel is
    /// 0.78 dry and 0.23 with a thin film of light mineral oil (Kirk-Othmer, Encyclopedia of
    /// Chemical Technology, "Friction"; also the Engineering ToolBox / Machinery's Handbook
    /// tables: iron on iron lubricated 0.15–0.20); sea water is a poorer boundary lubricant
    /// than oil, so the figure is taken just above the oiled one.
    pub mu_static: f64,
    /// Kinetic friction coefficient, wet: 0.20 (same sources: dry 0.42 → oiled 0.10 for hard
    /// steel; the static/kinetic ratio of 1.5 kept).
    pub mu_kinetic: f64,
    /// Pad width along the bar, the line contact length w (m): 0.05 (assumed: a jaw of the
    /// Table 1-1 7.5 cm opening class has pads of about that width).
    pub pad_width_m: f64,
    /// Slip across the bar in the pads' plane (the bar frame's z, for an aligned jaw within
    /// 45° of its depth axis) after which the bar has left the pads and the grasp is lost
    /// (m): 0.03 (assumed: pads 6 cm deep, the bar taken at their middle).
    pub slip_travel_m: f64,
    /// Largest skew of the closing axis off the plane normal to the bar at which a jaw takes
    /// the bar or keeps it (rad): 15° (half the 30° at which the bar no longer fits between
    /// the fully open pads; [`super::handle`] module docs).
    pub max_skew_rad: f64,
    /// Largest roll of the pads off the bar's flats, about the bar (rad): 22.5° (half the 45°
    /// at which the pads meet the square bar on its diagonal and could turn it either way).
    pub max_roll_rad: f64,
    /// Largest angle of the bar off the jaw's x axis in the pads' plane (rad): 45° (across
    /// the fingers, not along them).
    pub max_cross_rad: f64,
    /// Shear modulus G of the pads' elastomer layer (Pa): 6.95·10⁶, a 90 Shore A polyurethane
    /// (Gent 1958, "On the relation between indentation hardness and Young's modulus", Trans.
    /// IRI 34: E = 0.0981(56 + 7.62336 S)/(0.137505(254 − 2.54 S)) MPa = 20.8 MPa at S = 90,
    /// G = E/3 for a rubber-like solid). The pads are steel wear plates (the friction above)
    /// bonded on this layer, as jaw liners are (assumed).
    pub pad_shear_modulus_pa: f64,
    /// Thickness t of the pads' elastomer layer (m): 0.005 (assumed).
    pub pad_layer_m: f64,
    /// Loss factor η of the pads' elastomer (tan δ): 0.1 (assumed; polyurethane elastomers
    /// above their glass transition are 0.05–0.2 at room temperature, the figure in the middle
    /// of that range).
    pub pad_loss_factor: f64,
}

impl Default for GripParams {
    fn default() -> Self {
        GripParams {
            mu_static: 0.30,
            mu_kinetic: 0.20,
            pad_width_m: 0.05,
            slip_travel_m: 0.03,
            max_skew_rad: 15f64.to_radians(),
            max_roll_rad: 22.5f64.to_radians(),
            max_cross_rad: 45f64.to_radians(),
            pad_shear_modulus_pa: 6.95e6,
            pad_layer_m: 0.005,
            pad_loss_factor: 0.1,
        }
    }
}

impl GripParams {
    /// Whether a jaw lying on a bar with alignment `al` takes it (or keeps it): every angle
    /// within its tolerance.
    pub fn accepts(&self, al: &Alignment) -> bool {
        al.skew_rad <= self.max_skew_rad
            && al.roll_rad <= self.max_roll_rad
            && al.cross_rad <= self.max_cross_rad
    }

    /// Torsional stiffness of the two pads about the closing axis on a bar of side
    /// `bar_side_m` (N·m/rad): each w × s elastomer layer of thickness t sheared by a twist θ
    /// carries G·J·θ/t (J = w·s·(w² + s²)/12, the patch's polar moment of area; shear strain
    /// r·θ/t at radius r), the two pads side by side between jaw and bar: k = 2·G·J/t
    /// (1.90·10³ N·m/rad for 5 × 4 cm pads, 5 mm of 90 Shore A polyurethane).
    pub fn torsion_stiffness(&self, bar_side_m: f64) -> f64 {
        let (w, s) = (self.pad_width_m, bar_side_m);
        let j = w * s * (w * w + s * s) / 12.0;
        2.0 * self.pad_shear_modulus_pa * j / self.pad_layer_m
    }
}

/// The friction-carried limits of one jaw on its handle: the semi-axes of the limit ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripCapacity {
    /// Tangential force limit F = 2 μ N (N).
    pub force_n: f64,
    /// Torsion limit about the closing axis, M_n = 2 μ N ρ̄ (N·m).
    pub torsion_nm: f64,
    /// Roll limit about the bar axis, M_a = N s (N·m).
    pub roll_nm: f64,
    /// Pry limit about the bar frame's z axis (across the bar in the pads' plane),
    /// M_d = N w (N·m).
    pub pry_nm: f64,
}

/// Mean distance from the centre of a uniformly loaded `a` × `b` rectangle (m): with
/// half-sides p, q and d = √(p² + q²),
/// ρ̄ = [2pqd + p³·ln((q + d)/p) + q³·ln((p + d)/q)] / (6pq) (the integral of r over a
/// quarter, divided by its area); 0 for a degenerate patch.
pub fn mean_radius(a: f64, b: f64) -> f64 {
    let (p, q) = (0.5 * a, 0.5 * b);
    if !(p > 0.0 && q > 0.0) {
        return 0.0;
    }
    let d = p.hypot(q);
    (2.0 * p * q * d + p.powi(3) * ((q + d) / p).ln() + q.powi(3) * ((p + d) / q).ln())
        / (6.0 * p * q)
}

impl GripCapacity {
    /// The limits for friction coefficient `mu`, clamp force `clamp_n` (N) per pad, pad width
    /// `pad_width_m` and bar side `bar_side_m` (see the module docs).
    pub fn new(mu: f64, clamp_n: f64, pad_width_m: f64, bar_side_m: f64) -> GripCapacity {
        let n = clamp_n.max(0.0);
        GripCapacity {
            force_n: 2.0 * mu * n,
            torsion_nm: 2.0 * mu * n * mean_radius(pad_width_m, bar_side_m),
            roll_nm: n * bar_side_m,
            pry_nm: n * pad_width_m,
        }
    }

    /// The static (`kinetic` false) or kinetic limits of a jaw clamping `clamp_n` on one of
    /// `object`'s handles.
    pub fn of(gp: &GripParams, op: &ObjectParams, clamp_n: f64, kinetic: bool) -> GripCapacity {
        let mu = if kinetic { gp.mu_kinetic } else { gp.mu_static };
        GripCapacity::new(mu, clamp_n, gp.pad_width_m, op.handle_width_m)
    }

    /// The load fraction λ of a wrench given in the bar frame (`jaw`: [f; m], N and N·m,
    /// axes x bar, y closing, z across the bar in the pads' plane): 0 for no limited load,
    /// ∞ for any limited load on a jaw that does not clamp.
    pub fn load_fraction(&self, jaw: &Vector6<f64>) -> f64 {
        let part = |x: f64, limit: f64| {
            if x == 0.0 {
                0.0
            } else if limit > 0.0 {
                x / limit
            } else {
                f64::INFINITY
            }
        };
        let ft = part(jaw[0].hypot(jaw[2]), self.force_n);
        let mn = part(jaw[4], self.torsion_nm);
        let ma = part(jaw[3], self.roll_nm);
        let md = part(jaw[5], self.pry_nm);
        (ft * ft + mn * mn + ma * ma + md * md).sqrt()
    }
}

/// A world-frame contact wrench [f; m] in the frame whose orientation (world) is `r` (the
/// bar frame of a grasp).
pub fn to_jaw(r: &Rotation3<f64>, w: &Vector6<f64>) -> Vector6<f64> {
    let f = r.inverse_transform_vector(&Vector3::new(w[0], w[1], w[2]));
    let m = r.inverse_transform_vector(&Vector3::new(w[3], w[4], w[5]));
    Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z)
}

/// A bar-frame wrench back in the world frame (the inverse of [`to_jaw`]).
pub fn from_jaw(r: &Rotation3<f64>, w: &Vector6<f64>) -> Vector6<f64> {
    let f = r * Vector3::new(w[0], w[1], w[2]);
    let m = r * Vector3::new(w[3], w[4], w[5]);
    Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z)
}

/// The wrench a slipping jaw transmits (bar frame) when the rigid grasp would need `jaw`: the
/// limited components (f_a, f_d, m_a, m_n, m_d) scaled by 1/λ onto the `kinetic` limit
/// ellipsoid, the geometry-carried f_n unchanged. `jaw` itself when it lies inside the
/// ellipsoid (then the jaw sticks).
pub fn kinetic_wrench(kinetic: &GripCapacity, jaw: &Vector6<f64>) -> Vector6<f64> {
    let lambda = kinetic.load_fraction(jaw);
    if lambda <= 1.0 {
        return *jaw;
    }
    let s = if lambda.is_finite() {
        1.0 / lambda
    } else {
        0.0
    };
    Vector6::new(
        jaw[0] * s,
        jaw[1],
        jaw[2] * s,
        jaw[3] * s,
        jaw[4] * s,
        jaw[5] * s,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacity_closed_forms() {
        // Two pads, Coulomb: F = 2μN; torsion 2μNρ̄; roll N·s. A square patch of side a has
        // ρ̄ = a(√2 + ln(1 + √2))/6 (the classical mean distance, ≈ 0.3826a)
        // (the rectangle's closed form is checked by a midpoint sum in tests/grasp_slip.rs).
        let sq = 0.05 * (2f64.sqrt() + (1.0 + 2f64.sqrt()).ln()) / 6.0;
        assert!((mean_radius(0.05, 0.05) - sq).abs() < 1e-15);
        let rho = mean_radius(0.05, 0.04);
        let c = GripCapacity::new(0.3, 1000.0, 0.05, 0.04);
        assert!((c.force_n - 600.0).abs() < 1e-9);
        assert!((c.torsion_nm - 600.0 * rho).abs() < 1e-9);
        assert!((c.roll_nm - 40.0).abs() < 1e-9);
        assert!((c.pry_nm - 50.0).abs() < 1e-9);
        let c = GripCapacity {
            force_n: 600.0,
            torsion_nm: 7.5,
            roll_nm: 12.0,
            pry_nm: 20.0,
        };
        // A pure tangential load at the limit, in any in-plane direction, is λ = 1; the
        // closing-axis force does not count.
        let at = |w: [f64; 6]| c.load_fraction(&Vector6::from(w));
        assert!((at([600.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        let d = 600.0 / 2f64.sqrt();
        assert!((at([d, 5e4, -d, 0.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((at([0.0, 0.0, 0.0, 12.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((at([0.0, 0.0, 0.0, 0.0, -7.5, 0.0]) - 1.0).abs() < 1e-12);
        assert!((at([0.0, 0.0, 0.0, 0.0, 0.0, 20.0]) - 1.0).abs() < 1e-12);
        // Half of each limit at once: √(4/4).
        assert!((at([300.0, 0.0, 0.0, 6.0, 3.75, 10.0]) - 1.0).abs() < 1e-12);
        // No clamp: any limited load is beyond it, the closing-axis force alone is not.
        let none = GripCapacity::new(0.3, 0.0, 0.05, 0.04);
        assert_eq!(
            none.load_fraction(&Vector6::new(0.0, 5.0, 0.0, 0.0, 0.0, 0.0)),
            0.0
        );
        assert!(
            none.load_fraction(&Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0))
                .is_infinite()
        );
        assert!(
            none.load_fraction(&Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0))
                .is_infinite()
        );
    }

    #[test]
    fn pad_torsion_stiffness_is_two_g_j_over_t() {
        // Each pad: a thin bonded layer twisted by θ shears by r·θ/t at radius r, so its
        // torque is G·θ/t·∫r² dA. The polar moment ∫r² dA by a midpoint sum over the 5 × 4 cm
        // patch (independent of the closed form w·s·(w² + s²)/12 in the code).
        let gp = GripParams::default();
        let (w, s, m) = (0.05, 0.04, 400);
        let (dx, dy) = (w / m as f64, s / m as f64);
        let mut j = 0.0;
        for a in 0..m {
            for b in 0..m {
                let x = -0.5 * w + (a as f64 + 0.5) * dx;
                let y = -0.5 * s + (b as f64 + 0.5) * dy;
                j += (x * x + y * y) * dx * dy;
            }
        }
        let k = 2.0 * gp.pad_shear_modulus_pa * j / gp.pad_layer_m;
        let got = gp.torsion_stiffness(s);
        assert!((got - k).abs() < 1e-5 * k, "{got} vs {k}");
        // Gent's hardness relation at 90 Shore A: E = 20.8 MPa, G = E/3.
        let e = 0.0981 * (56.0 + 7.62336 * 90.0) / (0.137505 * (254.0 - 2.54 * 90.0));
        assert!(
            (gp.pad_shear_modulus_pa - e / 3.0 * 1e6).abs() < 0.01e6,
            "E = {e} MPa"
        );
        assert!((got - 1899.6).abs() < 0.1, "{got}");
    }

    #[test]
    fn kinetic_wrench_lies_on_the_ellipsoid() {
        let k = GripCapacity::new(0.2, 1471.0, 0.05, 0.04);
        let need = Vector6::new(400.0, -900.0, 700.0, 10.0, -3.0, 55.0);
        let got = kinetic_wrench(&k, &need);
        assert!((k.load_fraction(&got) - 1.0).abs() < 1e-12);
        // The geometry-carried component untouched; the others keep their direction.
        assert_eq!(got[1], need[1]);
        let s = got[0] / need[0];
        for i in [2, 3, 4, 5] {
            assert!((got[i] / need[i] - s).abs() < 1e-12);
        }
        // Inside: unchanged.
        let small = need * 0.01;
        assert_eq!(kinetic_wrench(&k, &small), small);
        // World ↔ jaw frame round trip.
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let back = from_jaw(&r, &to_jaw(&r, &need));
        assert!((back - need).norm() < 1e-9);
    }
}
