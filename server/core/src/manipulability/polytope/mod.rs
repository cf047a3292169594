//! Velocity polytopes (Kilic §3.2): single-arm zonotopes, convex hull, dual-arm intersection.
//!
//! With joint-rate bounds |q̇ᵢ| ≤ q̇ᵢmax the reachable task velocities of a Jacobian J (m×n,
//! m = 3 or 2) form P = {J q̇} = Σᵢ [−gᵢ, gᵢ] with generators gᵢ = q̇ᵢmax·jᵢ (Kilic eq. 1.50):
//! a zonotope, the Minkowski sum of n segments.
//!
//! # Mechanism
//! * [`convex_hull`]: 3-D quickhull with a scale-relative tolerance. Points within the
//!   tolerance of the hull count as on it, so coplanar and duplicate points are absorbed;
//!   inputs spanning fewer than 3 dimensions give [`Error::Degenerate`].
//! * [`velocity_polytope`]: the zonotope's candidate vertices from its facets (one facet pair
//!   per plane spanned by two generators, each the 2-D zonogon of the generators in that
//!   plane shifted by the signs of the others), then their hull. This produces the vertices
//!   Kilic's Minkowski-sum pseudo-code (§3.2.1) would keep after removing interior vertices,
//!   without enumerating 2ⁿ sums.
//! * [`dual_velocity_polytope`]: the intersection of two arms' polytopes as a halfspace
//!   intersection: one polytope is clipped by every facet plane of the other (polygon faces,
//!   Sutherland–Hodgman per face plus a cap per plane), then the corners are hulled.
//!
//! Every result is a [`Polytope`]: vertices, outward triangles (three.js order), volume and
//! Kilic's cone-cell index w_p.
//!
//! # Layout
//! * `hull`: the quickhull behind [`convex_hull`] and every other result.
//! * `zonotope`: generators and zonotope corners for [`velocity_polytope`].
//! * `intersect`: the clipping behind [`dual_velocity_polytope`].

mod hull;
mod intersect;
mod zonotope;

use nalgebra::{DMatrix, Vector3};

use crate::Error;
use hull::quickhull;
use zonotope::{generators, zonogon_polytope, zonotope_candidates};

/// A convex polytope as a closed triangle mesh, ready to draw.
///
/// For 3-D inputs the vertices are the hull's corners (m/s for velocity polytopes, in the
/// Jacobian's frame) and the facets are triangles wound counter-clockwise seen from outside
/// (right-hand normal points outward), as three.js expects. For 2-D inputs (m = 2) the
/// vertices are the polygon's corners with z = 0 in counter-clockwise order and the facets
/// are a fan triangulation of it (normal +z).
#[derive(Debug, Clone, PartialEq)]
pub struct Polytope {
    /// Corners, each [x, y, z].
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as index triples into `vertices`, outward-oriented (counter-clockwise seen
    /// from outside).
    pub facets: Vec<[usize; 3]>,
    /// Volume (m³/s³ for a translational velocity polytope); area for m = 2.
    pub volume: f64,
    /// Kilic's cone-cell index w_p = Σₖ Sₖ (eqs 1.51–1.55). Each hull facet (an edge for
    /// m = 2) is the bottom plane of one cone cell with apex at the origin, and
    /// Sₖ = |det[V_k1 … V_km]| / d_m. The paper never defines d_m; we choose d_m = m!
    /// (6 in 3-D, 2 in 2-D), so Sₖ is the cell's simplex volume and w_p equals `volume`
    /// whenever the origin lies inside the polytope (always so for velocity polytopes,
    /// which are symmetric about it). Computed from its own formula, not copied.
    pub w_p: f64,
}

/// Convex hull of 3-D points (quickhull).
///
/// With s the largest absolute coordinate: points closer than 10⁻¹⁰·s to each other are one
/// (the first in x order is kept), points within 10⁻¹²·s of the hull count as on it, and
/// points inside an edge or a face of the hull are not corners; duplicate, collinear and
/// coplanar points are therefore harmless. Every corner of the result is one of the inputs.
/// The volume is exact up to about (surface area)·10⁻¹²·s, which matters only for hulls
/// thinner than about 10⁻⁸·s. The result is checked: if rounding left any point more than
/// 10⁻⁹·s outside a facet plane (points scattered about a plane by about the tolerance can
/// do that), the hull is recomputed with the tolerance raised to 10⁻⁹·s and then 10⁻⁷·s, and
/// accepted when every point is within 1000× the tolerance used of it (at worst 10⁻⁴·s, for
/// such noisy near-degenerate clouds only; velocity polytopes pass at the first tolerance). `volume` is the signed-tetrahedron sum (divergence
/// theorem) and `w_p` the cone-cell index about the origin (see [`Polytope::w_p`]).
///
/// # Errors
/// [`Error::NonFinite`] for a NaN or infinite coordinate, [`Error::Degenerate`] when the
/// points span fewer than 3 dimensions (none, one point, a segment or a flat set; the hull
/// then has zero volume), [`Error::Numerical`] if no tolerance gives a valid hull (not seen in
/// testing).
pub fn convex_hull(points: &[[f64; 3]]) -> Result<Polytope, Error> {
    for (i, p) in points.iter().enumerate() {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "points",
                index: i,
            });
        }
    }
    let pts: Vec<Vector3<f64>> = points
        .iter()
        .map(|p| Vector3::new(p[0], p[1], p[2]))
        .collect();
    let (verts, facets) = quickhull(&pts)?;
    Ok(polytope_from_mesh(verts, facets))
}

/// Translational velocity polytope P = {J q̇ : |q̇ᵢ| ≤ q̇ᵢmax} (Kilic eq. 1.50, §3.2.1).
///
/// `j` is m×n with m = 3 (rows vx vy vz of a geometric Jacobian, any frame) or m = 2 (a
/// planar task, rows x y); `qdot_max` holds n joint-rate bounds (each joint's
/// `max_velocity`, rad/s or m/s), each ≥ 0. The result is in the frame of `j`'s rows;
/// zero columns and zero bounds contribute nothing. Relative tolerance 10⁻⁹: a generator
/// shorter than that times the longest is zero, two within that angle (sine) are parallel and
/// merge, and generators within it of a common plane make the polytope flat.
///
/// # Errors
/// [`Error::InvalidRows`] unless m is 2 or 3; [`Error::SizeMismatch`] when `qdot_max` does
/// not have n entries; [`Error::NonFinite`] for a NaN or infinite entry;
/// [`Error::InvalidParameter`] for a negative bound; [`Error::Degenerate`] when the
/// generators span fewer than m dimensions (a singular posture: the polytope is flat and has
/// zero volume); [`Error::Numerical`] if rounding breaks the hull.
pub fn velocity_polytope(j: &DMatrix<f64>, qdot_max: &[f64]) -> Result<Polytope, Error> {
    let gens = generators(j, qdot_max)?;
    match j.nrows() {
        2 => zonogon_polytope(&gens),
        _ => {
            let cands = zonotope_candidates(&gens)?;
            let (verts, facets) = quickhull(&cands)?;
            Ok(polytope_from_mesh(verts, facets))
        }
    }
}

/// Dual-arm velocity polytope: the intersection P₁ ∩ P₂ of two arms' velocity polytopes,
/// the task velocities both arms can produce (each arm's q̇ within its bounds).
///
/// `j1` (3×n₁) and `j2` (3×n₂) are translational Jacobian rows already expressed in one
/// common frame (rotate them first); `qmax1`, `qmax2` their joint-rate bounds, as for
/// [`velocity_polytope`]. Both polytopes are symmetric about the origin, so the origin is
/// inside the intersection. The intersection is computed by clipping arm 1's polytope with
/// every facet plane of arm 2's (a halfspace intersection), and then hulled; its corners are
/// within 10⁻¹² × (largest coordinate) of both polytopes.
///
/// # Errors
/// As [`velocity_polytope`] for either arm (m must be 3 for both). A flat arm polytope
/// (singular posture) makes the intersection flat: [`Error::Degenerate`] with the flat arm's
/// dimension.
pub fn dual_velocity_polytope(
    j1: &DMatrix<f64>,
    qmax1: &[f64],
    j2: &DMatrix<f64>,
    qmax2: &[f64],
) -> Result<Polytope, Error> {
    for j in [j1, j2] {
        if j.nrows() != 3 {
            return Err(Error::InvalidRows {
                reason: format!("the dual velocity polytope needs 3 rows, got {}", j.nrows()),
            });
        }
    }
    let p1 = velocity_polytope(j1, qmax1)?;
    let p2 = velocity_polytope(j2, qmax2)?;
    intersect::intersect(&p1, &p2)
}

/// Builds the [`Polytope`] of a closed outward mesh: volume by the divergence theorem (signed
/// tetrahedra from the first corner), w_p by Kilic eq. 1.54–1.55 with d₃ = 3! (cone cells from
/// the origin).
fn polytope_from_mesh(verts: Vec<Vector3<f64>>, facets: Vec<[usize; 3]>) -> Polytope {
    let o = verts.first().copied().unwrap_or_else(Vector3::zeros);
    let mut volume = 0.0;
    let mut w_p = 0.0;
    for f in &facets {
        let (a, b, c) = (verts[f[0]], verts[f[1]], verts[f[2]]);
        volume += (a - o).dot(&(b - o).cross(&(c - o))) / 6.0;
        w_p += a.dot(&b.cross(&c)).abs() / 6.0;
    }
    Polytope {
        vertices: verts.iter().map(|v| [v.x, v.y, v.z]).collect(),
        facets,
        volume,
        w_p,
    }
}
