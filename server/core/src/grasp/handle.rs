//! The box's handle bars and when a jaw is aligned with one.
//!
//! # Handles
//! A handle is a straight bar of square section s × s (the flat "fishtail" section of ROV grab
//! handles, s = [`super::ObjectParams::handle_width_m`]) between two posts: its centre, its
//! axis a and the normal f of one pair of its flats (the other pair faces a × f), all in the
//! object frame. The case-study box has three ([`super::ObjectParams::case_study_box`]): one
//! on each side of the top face, 0.15 m off the centre of mass, where Lim's two arms take it,
//! and a **lifting point** — a T-handle on a post over the centre of mass, as recovery baskets
//! and ROV tools carry — by which one jaw can lift the box without twisting it.
//!
//! # Alignment
//! The jaw's two flat pads close along the tool frame's y axis n, with z its depth axis (the
//! fingers) and x across the fingers. A jaw takes a bar only when three angles are within the
//! tolerances of [`super::GripParams`]:
//!
//! * **skew** ψ = asin|n·a|, the closing axis off the plane normal to the bar: the pads, of
//!   width w along the bar, first meet a skewed bar at two diagonally opposite edges, at an
//!   opening o(ψ) = w·tan ψ + s/cos ψ; at ψ = 30° that is 7.5 cm, the jaw's full opening (Lim
//!   Table 1-1), so the bar no longer fits between the pads at all. Below that the clamp must
//!   turn the bar (and the box) by ψ before the flats seat — a squeeze grasp's
//!   self-alignment (Goldberg 1993, "Orienting polygonal parts without sensors", Algorithmica
//!   10; Brost 1988, "Automatic grasp planning in the presence of uncertainty", IJRR 7(1)),
//!   which friction at the edges and the box's own resistance can stop. The tolerance is
//!   half the geometric limit, 15° (assumed; o(15°) = 5.5 cm, 1.5 cm over the bar);
//! * **roll** ρ, the pads' normal off the nearest pair of flats, about the bar (a square bar
//!   seats every 90°): the pads first meet the bar's edges at an opening s·(cos ρ + sin ρ),
//!   and seat only by rolling the bar (and the box) about its axis; at 45° they meet it on
//!   its diagonal and could turn it either way. The tolerance is half that, 22.5° (assumed,
//!   the same margin as the skew's);
//! * **cross** φ, the bar off the jaw's x axis within the pads' plane: the bar must lie
//!   across the fingers, not along them (a bar along the fingers is another grasp, not
//!   modelled; the pad patch w × s of [`super::GripCapacity`] assumes the bar crosses it).
//!   Tolerance 45°: the bar is nearer across than along.
//!
//! A jaw that is not aligned closes past the bar without taking it (the jaw–bar collision is
//! not modelled here). Once held, the bar may turn in the jaw as it slips; the grasp is lost
//! only when it has slid out of the pads (the slip stage in [`crate::sim`]): a test of the
//! alignment while holding also dropped bars that had crept (in steps each under the slip
//! notice) past a tolerance without a slip ever being reported, so it was left out.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// A handle bar on the object (object frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handle {
    /// Centre of the bar (m, object frame): its grasp point.
    pub centre_m: Vector3<f64>,
    /// The bar's axis a (unit, object frame).
    pub axis: Vector3<f64>,
    /// Normal of one pair of the bar's flats (unit, perpendicular to the axis, object frame);
    /// the other pair faces axis × flat_normal.
    pub flat_normal: Vector3<f64>,
    /// Length of the bar between its posts (m).
    pub length_m: f64,
    /// How the bar stands on the object.
    pub posts: Posts,
}

/// How a handle bar stands on the object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Posts {
    /// A grab handle: thin posts at both ends of the bar (not collision shapes; the jaw
    /// takes the bar between them).
    Ends,
    /// A T-handle: one post under the bar's centre, down the object's −z axis to its top
    /// face (a collision shape, [`crate::collision::WorldGeometry::post_radius_m`]).
    Centre,
}

/// How a jaw lies on a bar: the three angles of the module docs (rad, each ≥ 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// ψ: the closing axis off the plane normal to the bar, in [0, π/2].
    pub skew_rad: f64,
    /// ρ: the pads' normal off the nearest pair of flats, about the bar, in [0, π/4].
    pub roll_rad: f64,
    /// φ: the bar off the jaw's x axis in the pads' plane, in [0, π/2].
    pub cross_rad: f64,
}

impl Handle {
    /// The point of the bar's axis nearest to `p` (object frame, m).
    pub fn nearest_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let t = (p - self.centre_m)
            .dot(&self.axis)
            .clamp(-0.5 * self.length_m, 0.5 * self.length_m);
        self.centre_m + self.axis * t
    }

    /// Distance (m) from `p` (object frame) to the bar's axis segment.
    pub fn distance_m(&self, p: &Vector3<f64>) -> f64 {
        (p - self.nearest_point(p)).norm()
    }

    /// The alignment of a jaw whose orientation in the object frame is `jaw` (columns: the
    /// tool's x, closing axis n = y, depth axis z).
    pub fn alignment(&self, jaw: &Rotation3<f64>) -> Alignment {
        let m = jaw.matrix();
        let (x, n, z) = (
            m.column(0).into_owned(),
            m.column(1).into_owned(),
            m.column(2).into_owned(),
        );
        let a = self.axis;
        let skew_rad = n.dot(&a).abs().min(1.0).asin();
        // Roll: n's direction in the plane normal to the bar, against the flats f, a × f.
        let f = self.flat_normal;
        let g = a.cross(&f);
        let theta = n.dot(&g).atan2(n.dot(&f));
        let quarter = std::f64::consts::FRAC_PI_2;
        let roll_rad = (theta - (theta / quarter).round() * quarter).abs();
        // Cross: the bar's direction in the pads' plane (x, z), against ±x.
        let cross_rad = a.dot(&z).abs().atan2(a.dot(&x).abs());
        Alignment {
            skew_rad,
            roll_rad,
            cross_rad,
        }
    }

    /// The bar frame of a jaw with orientation `jaw` (object frame) on this bar, as a rotation
    /// in the object frame: columns the bar axis a (signed to point along the jaw's +x side),
    /// the closing axis n made normal to a, and d = a × n, the direction in the pads' plane
    /// across the bar (along which the bar slides out of the pads). The grip's limit surface
    /// is written in it ([`super::GripCapacity::load_fraction`]). A closing axis along the bar
    /// (never the case while aligned) falls back to the jaw's own frame.
    pub fn bar_frame(&self, jaw: &Rotation3<f64>) -> Rotation3<f64> {
        let m = jaw.matrix();
        let (x, n) = (m.column(0).into_owned(), m.column(1).into_owned());
        let a = if self.axis.dot(&x) >= 0.0 {
            self.axis
        } else {
            -self.axis
        };
        let np = n - a * n.dot(&a);
        let norm = np.norm();
        if norm.is_nan() || norm <= 1e-9 {
            return *jaw;
        }
        let np = np / norm;
        Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[a, np, a.cross(&np)]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bar_x() -> Handle {
        Handle {
            centre_m: Vector3::new(0.0, 0.0, 0.2),
            axis: Vector3::x(),
            flat_normal: Vector3::z(),
            length_m: 0.12,
            posts: Posts::Ends,
        }
    }

    #[test]
    fn angles_of_simple_attitudes() {
        let h = bar_x();
        // Jaw pointing down (z = −Z), closing along Y, x = −X: aligned.
        let down = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
        let al = h.alignment(&down);
        assert!(al.skew_rad < 1e-12 && al.roll_rad < 1e-12 && al.cross_rad < 1e-12);
        // Turned 30° about its depth axis: skew 30°, nothing else.
        let r = down * Rotation3::from_axis_angle(&Vector3::z_axis(), 30f64.to_radians());
        let al = h.alignment(&r);
        assert!((al.skew_rad - 30f64.to_radians()).abs() < 1e-12, "{al:?}");
        // Turned 20° about the closing axis: the bar lies 20° across the pads.
        let r = down * Rotation3::from_axis_angle(&Vector3::y_axis(), 20f64.to_radians());
        let al = h.alignment(&r);
        assert!(al.skew_rad < 1e-12 && (al.cross_rad - 20f64.to_radians()).abs() < 1e-12);
        // Rolled 100° about the bar: 10° off the next pair of flats.
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), 100f64.to_radians()) * down;
        let al = h.alignment(&r);
        assert!((al.roll_rad - 10f64.to_radians()).abs() < 1e-12, "{al:?}");
    }

    #[test]
    fn bar_frame_is_right_handed_and_follows_the_bar() {
        let h = bar_x();
        let r = Rotation3::from_euler_angles(0.1, 2.8, -0.2);
        let b = h.bar_frame(&r);
        let m = b.matrix();
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((m * m.transpose() - Matrix3::identity()).norm() < 1e-12);
        assert!((m.column(0).into_owned().cross(&Vector3::x())).norm() < 1e-12);
        assert!(m.column(1).dot(&r.matrix().column(1)) > 0.9);
    }

    #[test]
    fn nearest_point_stays_on_the_segment() {
        let h = bar_x();
        let p = Vector3::new(0.5, 0.03, 0.2);
        assert!((h.nearest_point(&p) - Vector3::new(0.06, 0.0, 0.2)).norm() < 1e-15);
        assert!((h.distance_m(&Vector3::new(0.01, 0.0, 0.23)) - 0.03).abs() < 1e-15);
    }
}
