//! The object: a 50 kg box with two handles (Lim §4.2.2) and a lifting point, its mass
//! properties and corners.

use nalgebra::{Isometry3, Matrix3, Vector3};

use super::{Handle, Posts};

/// Number of handles on the box: the two side handles and the lifting point.
pub const N_HANDLES: usize = 3;

/// The object and its environment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectParams {
    /// Mass (kg): 50 (Lim §4.2.2, "an object which is 50 kg").
    pub mass_kg: f64,
    /// Box size x, y, z (m): 0.30 × 0.40 × 0.20 (assumed; mean density ≈ 2 080 kg/m³).
    pub size_m: Vector3<f64>,
    /// The handle bars ([`Handle`], object frame; assumed): 0 and 1 the side handles Lim's
    /// two arms take (0: left arm's at y = +0.15, 1: right arm's at y = −0.15), bars 0.12 m
    /// long along the box's x axis 3 cm above its top face; 2 the lifting point, a T-handle
    /// bar of the same section along x on a post 0.04 m above the top face, over the centre of
    /// mass. Flats face up and sideways. Any jaw may take any handle.
    pub handles: [Handle; N_HANDLES],
    /// Handle bar thickness the jaw closes on (m): 0.04 (< 7.5 cm jaw opening).
    pub handle_width_m: f64,
    /// Contact (capture) radius (m) around a handle bar's axis within which the tool point
    /// touches it: 0.04. Stands in for the thesis's collision detection of jaw and object
    /// meshes; an aligned jaw ([`super::handle`]) closing there takes the bar.
    pub capture_radius_m: f64,
    /// Seabed height (m, base frame z).
    pub seabed_z_m: f64,
    /// Initial pose of the object frame (at its centre of mass), resting on the seabed.
    pub initial_pose: Isometry3<f64>,
    /// Seabed contact stiffness per bottom corner (N/m): 2·10⁶ (stiff sediment-free rock/
    /// steel plate; settles 0.06 mm under 50 kg).
    pub contact_stiffness_n_m: f64,
    /// Seabed contact damping per corner (N·s/m): 2·10⁴ (about critical for 50 kg on 4 corners).
    pub contact_damping_n_s_m: f64,
    /// Seabed Coulomb friction coefficient: 0.5.
    pub friction: f64,
    /// Friction regularization speed (m/s): 0.01 (μN·v/√(v²+ε²)).
    pub friction_speed_m_s: f64,
}

/// Height of the lifting point's bar above the box's top face (m): 0.04 (assumed: it stands
/// clear of the side handles, 3 cm up; at 0.10 m the links reaching over the box to the panel
/// struck it, docs/physics.md "Handles, alignment and the lifting point").
pub const LIFTING_POINT_RISE_M: f64 = 0.04;

/// Index of the lifting point in [`ObjectParams::handles`].
pub const LIFTING_POINT: usize = 2;

/// A 0.12 m bar along the box's x axis centred at `centre`, flats facing up and sideways,
/// standing on `posts`.
fn bar(centre: Vector3<f64>, posts: Posts) -> Handle {
    Handle {
        centre_m: centre,
        axis: Vector3::x(),
        flat_normal: Vector3::z(),
        length_m: 0.12,
        posts,
    }
}

impl ObjectParams {
    /// The case-study object: 50 kg box centred at (x, y), resting on the seabed at `seabed_z`.
    pub fn case_study_box(x: f64, y: f64, seabed_z: f64) -> ObjectParams {
        let size = Vector3::new(0.30, 0.40, 0.20);
        ObjectParams {
            mass_kg: 50.0,
            size_m: size,
            handles: [
                bar(Vector3::new(0.0, 0.15, 0.5 * size.z + 0.03), Posts::Ends),
                bar(Vector3::new(0.0, -0.15, 0.5 * size.z + 0.03), Posts::Ends),
                bar(
                    Vector3::new(0.0, 0.0, 0.5 * size.z + LIFTING_POINT_RISE_M),
                    Posts::Centre,
                ),
            ],
            handle_width_m: 0.04,
            capture_radius_m: 0.04,
            seabed_z_m: seabed_z,
            initial_pose: Isometry3::translation(x, y, seabed_z + 0.5 * size.z),
            contact_stiffness_n_m: 2.0e6,
            contact_damping_n_s_m: 2.0e4,
            friction: 0.5,
            friction_speed_m_s: 0.01,
        }
    }

    /// Inertia about the centre of mass, object axes (kg·m²): solid box.
    pub fn inertia_body(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&self.principal_inertia())
    }

    /// The principal moments of inertia about the centre of mass (kg·m²), along the object
    /// axes: the diagonal of [`Self::inertia_body`] (a box's axes are its principal axes).
    pub fn principal_inertia(&self) -> Vector3<f64> {
        let (x, y, z) = (self.size_m.x, self.size_m.y, self.size_m.z);
        let k = self.mass_kg / 12.0;
        Vector3::new(
            k * (y * y + z * z),
            k * (x * x + z * z),
            k * (x * x + y * y),
        )
    }

    /// The eight box corners in the object frame.
    pub fn corners(&self) -> [Vector3<f64>; 8] {
        let h = self.size_m * 0.5;
        let mut out = [Vector3::zeros(); 8];
        for (k, c) in out.iter_mut().enumerate() {
            *c = Vector3::new(
                if k & 1 == 0 { -h.x } else { h.x },
                if k & 2 == 0 { -h.y } else { h.y },
                if k & 4 == 0 { -h.z } else { h.z },
            );
        }
        out
    }
}
