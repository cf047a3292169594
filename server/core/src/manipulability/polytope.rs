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

use nalgebra::{DMatrix, Vector3};

use crate::Error;

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

/// Relative tolerance of the hull: points closer than this times the largest absolute
/// coordinate to a facet plane count as on it.
const HULL_TOL: f64 = 1e-12;
/// Relative distance below which two points are one (duplicates are merged before hulling).
const MERGE_TOL: f64 = 1e-10;
/// Relative tolerance for generators: a generator shorter than this times the longest one is
/// dropped; two generators whose sine of angle is below it are parallel; a generator whose
/// out-of-plane component is below it times its length lies in that plane.
const GEN_TOL: f64 = 1e-9;

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
    intersect(&p1, &p2)
}

// ---------------------------------------------------------------------------------------
// Generators and zonotope vertices
// ---------------------------------------------------------------------------------------

/// Validates `j` and `qdot_max` and returns the generators qᵢmax·jᵢ (as 3-vectors, z = 0 for
/// m = 2), with zero ones dropped and parallel ones merged (two parallel segments sum to one
/// segment of the summed length).
fn generators(j: &DMatrix<f64>, qdot_max: &[f64]) -> Result<Vec<Vector3<f64>>, Error> {
    let (m, n) = j.shape();
    if m != 2 && m != 3 {
        return Err(Error::InvalidRows {
            reason: format!("a velocity polytope needs 2 or 3 rows, got {m}"),
        });
    }
    if qdot_max.len() != n {
        return Err(Error::SizeMismatch {
            what: "qdot_max",
            input: qdot_max.len(),
            required: n,
        });
    }
    if let Some(i) = j.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "jacobian",
            index: i,
        });
    }
    if let Some(i) = qdot_max.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "qdot_max",
            index: i,
        });
    }
    if let Some(i) = qdot_max.iter().position(|&v| v < 0.0) {
        return Err(Error::InvalidParameter {
            what: "qdot_max",
            reason: format!("entry {i} is negative ({})", qdot_max[i]),
        });
    }
    let raw: Vec<Vector3<f64>> = (0..n)
        .map(|k| {
            let z = if m == 3 { j[(2, k)] } else { 0.0 };
            Vector3::new(j[(0, k)], j[(1, k)], z) * qdot_max[k]
        })
        .collect();
    let longest = raw.iter().map(|g| g.norm()).fold(0.0, f64::max);
    let mut merged: Vec<Vector3<f64>> = Vec::with_capacity(n);
    for g in raw {
        let len = g.norm();
        if len <= GEN_TOL * longest || len == 0.0 {
            continue;
        }
        match merged
            .iter_mut()
            .find(|h| g.cross(h).norm() <= GEN_TOL * len * h.norm())
        {
            Some(h) => {
                let s = if g.dot(h) >= 0.0 { 1.0 } else { -1.0 };
                *h += s * g;
            }
            None => merged.push(g),
        }
    }
    let dim = span_dimension(&merged);
    if dim < m {
        return Err(Error::Degenerate {
            what: "velocity polytope",
            dimension: dim,
        });
    }
    Ok(merged)
}

/// Dimension spanned by merged (nonzero, pairwise non-parallel) generators: 0, 1, 2 or 3.
fn span_dimension(gens: &[Vector3<f64>]) -> usize {
    match gens.len() {
        0 => 0,
        1 => 1,
        _ => {
            let mut best = (0.0, Vector3::zeros());
            for (a, ga) in gens.iter().enumerate() {
                for gb in &gens[a + 1..] {
                    let c = ga.cross(gb);
                    let s = c.norm() / (ga.norm() * gb.norm());
                    if s > best.0 {
                        best = (s, c);
                    }
                }
            }
            let nrm = best.1.normalize();
            let flat = gens.iter().all(|g| nrm.dot(g).abs() <= GEN_TOL * g.norm());
            if flat { 2 } else { 3 }
        }
    }
}

/// The corners of the zonogon Σ[−hᵢ, hᵢ] of coplanar, pairwise non-parallel generators, in
/// order around it. `u`, `v` span their plane. Orienting every generator into the upper
/// half-plane and sorting by angle, the lower chain runs from −Σh to +Σh adding 2h in angle
/// order and the upper chain returns subtracting them in the same order.
fn zonogon_corners(hs: &[Vector3<f64>], u: &Vector3<f64>, v: &Vector3<f64>) -> Vec<Vector3<f64>> {
    let mut oriented: Vec<(f64, Vector3<f64>)> = hs
        .iter()
        .map(|h| {
            let (x, y) = (h.dot(u), h.dot(v));
            let h = if y < 0.0 || (y == 0.0 && x < 0.0) {
                -h
            } else {
                *h
            };
            (h.dot(v).atan2(h.dot(u)), h)
        })
        .collect();
    oriented.sort_by(|a, b| a.0.total_cmp(&b.0));
    let sum: Vector3<f64> = oriented.iter().map(|(_, h)| h).sum();
    let mut out = Vec::with_capacity(2 * oriented.len());
    let mut w = -sum;
    for (_, h) in &oriented {
        out.push(w);
        w += 2.0 * h;
    }
    for (_, h) in &oriented {
        out.push(w);
        w -= 2.0 * h;
    }
    out
}

/// Candidate corners of the 3-D zonotope Σ[−gᵢ, gᵢ]: for every plane spanned by two
/// generators (visited once, from its lowest index pair), the generators in it form the
/// facet's zonogon, and the others are pushed to the sign of their normal component; the
/// facet is c + zonogon and its opposite −(c + zonogon). Every zonotope corner lies on a facet,
/// so these contain all corners (with repeats, which the hull absorbs).
fn zonotope_candidates(gens: &[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, Error> {
    let r = gens.len();
    let mut out = Vec::with_capacity(4 * r * r);
    let mut in_plane: Vec<usize> = Vec::with_capacity(r);
    let mut hs: Vec<Vector3<f64>> = Vec::with_capacity(r);
    for a in 0..r {
        for b in a + 1..r {
            let nrm = gens[a].cross(&gens[b]);
            let len = nrm.norm();
            if len.is_nan() || len <= 0.0 {
                return Err(Error::Numerical {
                    what: "zonotope",
                    reason: "parallel generators".into(),
                });
            }
            let nrm = nrm / len;
            in_plane.clear();
            let mut c = Vector3::zeros();
            for (k, g) in gens.iter().enumerate() {
                let s = nrm.dot(g);
                if k == a || k == b || s.abs() <= GEN_TOL * g.norm() {
                    in_plane.push(k);
                } else if s > 0.0 {
                    c += g;
                } else {
                    c -= g;
                }
            }
            // Visit each plane once: from its two lowest generator indices.
            if in_plane[0] != a || in_plane[1] != b {
                continue;
            }
            hs.clear();
            hs.extend(in_plane.iter().map(|&k| gens[k]));
            let u = gens[a].normalize();
            let v = nrm.cross(&u);
            for w in zonogon_corners(&hs, &u, &v) {
                out.push(c + w);
                out.push(-(c + w));
            }
        }
    }
    Ok(out)
}

/// The 2-D velocity polygon as a [`Polytope`]: corners counter-clockwise (z = 0), fan
/// triangles, area, and w_p = Σ over edges |det[V₁ V₂]| / 2!.
fn zonogon_polytope(gens: &[Vector3<f64>]) -> Result<Polytope, Error> {
    let corners = zonogon_corners(gens, &Vector3::x(), &Vector3::y());
    let vertices: Vec<[f64; 3]> = corners.iter().map(|w| [w.x, w.y, 0.0]).collect();
    let k = vertices.len();
    let facets: Vec<[usize; 3]> = (1..k.saturating_sub(1)).map(|i| [0, i, i + 1]).collect();
    let mut area = 0.0;
    let mut w_p = 0.0;
    let o = corners[0];
    let det2 = |a: Vector3<f64>, b: Vector3<f64>| a.x * b.y - a.y * b.x;
    for i in 0..k {
        let (p, q) = (corners[i], corners[(i + 1) % k]);
        area += det2(p - o, q - o) / 2.0;
        w_p += det2(p, q).abs() / 2.0;
    }
    Ok(Polytope {
        vertices,
        facets,
        volume: area,
        w_p,
    })
}

// ---------------------------------------------------------------------------------------
// Intersection by clipping
// ---------------------------------------------------------------------------------------

/// P₁ ∩ P₂ by clipping P₁ with every facet plane of P₂ (halfspace n·x ≤ d, unit outward n).
///
/// P₁ is kept as polygon faces; each plane clips every face (Sutherland–Hodgman) and closes
/// the cut with a cap polygon. Every new corner lies on an edge of the current polytope, so the
/// result never leaves P₁, and it is within the hull tolerance of every plane of P₂. Planes
/// that cut nothing (every corner within the tolerance) are skipped: P ∩ P = P exactly.
fn intersect(p1: &Polytope, p2: &Polytope) -> Result<Polytope, Error> {
    let v1: Vec<Vector3<f64>> = p1.vertices.iter().map(|v| Vector3::from(*v)).collect();
    let v2: Vec<Vector3<f64>> = p2.vertices.iter().map(|v| Vector3::from(*v)).collect();
    let scale = v1.iter().chain(&v2).map(|v| v.amax()).fold(0.0, f64::max);
    let eps = HULL_TOL * scale;
    let mut faces: Vec<Vec<Vector3<f64>>> = p1
        .facets
        .iter()
        .map(|f| vec![v1[f[0]], v1[f[1]], v1[f[2]]])
        .collect();
    let mut next: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(faces.len() + 8);
    let mut cap: Vec<Vector3<f64>> = Vec::new();
    let mut ds: Vec<f64> = Vec::new();
    for f in &p2.facets {
        let (a, b, c) = (v2[f[0]], v2[f[1]], v2[f[2]]);
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        let n = n / len;
        let d = n.dot(&a);
        let dist = |x: &Vector3<f64>| n.dot(x) - d;
        if faces.iter().flatten().all(|x| dist(x) <= eps) {
            continue;
        }
        next.clear();
        cap.clear();
        for face in faces.drain(..) {
            ds.clear();
            ds.extend(face.iter().map(dist));
            if ds.iter().all(|&d| d <= eps) {
                // Untouched face; its corners on the plane belong to the cap.
                let on = face.iter().zip(&ds).filter(|(_, d)| d.abs() <= eps);
                cap.extend(on.map(|(x, _)| *x));
                next.push(face);
                continue;
            }
            let mut out: Vec<Vector3<f64>> = Vec::with_capacity(face.len() + 1);
            let (mut prev, mut prev_d) = (face[face.len() - 1], ds[ds.len() - 1]);
            for (&cur, &cur_d) in face.iter().zip(&ds) {
                match (prev_d <= eps, cur_d <= eps) {
                    (true, true) => out.push(cur),
                    (true, false) => out.push(cut(prev, prev_d, cur, cur_d)),
                    (false, true) => {
                        out.push(cut(cur, cur_d, prev, prev_d));
                        out.push(cur);
                    }
                    (false, false) => {}
                }
                prev = cur;
                prev_d = cur_d;
            }
            cap.extend(out.iter().filter(|x| dist(x).abs() <= eps));
            if out.len() >= 3 {
                next.push(out);
            }
        }
        let cap_face = order_around(&cap, &n, eps);
        if cap_face.len() >= 3 {
            next.push(cap_face);
        }
        std::mem::swap(&mut faces, &mut next);
        if faces.is_empty() {
            return Err(Error::Degenerate {
                what: "polytope intersection",
                dimension: 0,
            });
        }
    }
    let corners: Vec<Vector3<f64>> = faces.into_iter().flatten().collect();
    let (verts, facets) = quickhull(&corners)?;
    Ok(polytope_from_mesh(verts, facets))
}

/// The point where segment `inside` → `outside` crosses the plane, from their signed distances
/// (`di` ≤ tolerance < `dout`); always computed from the inside end, so the two faces sharing
/// the edge get the same point.
fn cut(inside: Vector3<f64>, di: f64, outside: Vector3<f64>, dout: f64) -> Vector3<f64> {
    let t = (di / (di - dout)).clamp(0.0, 1.0);
    inside + (outside - inside) * t
}

/// Distinct points of a planar convex set, ordered counter-clockwise about `n` (seen from
/// the side `n` points to).
fn order_around(pts: &[Vector3<f64>], n: &Vector3<f64>, eps: f64) -> Vec<Vector3<f64>> {
    let mut uniq: Vec<Vector3<f64>> = Vec::with_capacity(pts.len());
    for p in pts {
        if !uniq.iter().any(|q| (p - q).norm() <= eps) {
            uniq.push(*p);
        }
    }
    if uniq.len() < 3 {
        return uniq;
    }
    let centre: Vector3<f64> = uniq.iter().sum::<Vector3<f64>>() / uniq.len() as f64;
    let u = if n.x.abs() < 0.9 {
        n.cross(&Vector3::x())
    } else {
        n.cross(&Vector3::y())
    }
    .normalize();
    let v = n.cross(&u);
    let mut keyed: Vec<(f64, Vector3<f64>)> = uniq
        .into_iter()
        .map(|p| {
            let r = p - centre;
            (r.dot(&v).atan2(r.dot(&u)), p)
        })
        .collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    keyed.into_iter().map(|(_, p)| p).collect()
}

// ---------------------------------------------------------------------------------------
// Volume and cone-cell index
// ---------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------
// Quickhull
// ---------------------------------------------------------------------------------------

const NONE: usize = usize::MAX;

/// One triangle of the hull under construction.
#[derive(Debug, Clone)]
struct Face {
    /// Corners (point indices), counter-clockwise seen from outside.
    v: [usize; 3],
    /// `nb[k]`: the face across edge v[k] → v[(k+1) % 3].
    nb: [usize; 3],
    /// Unit outward normal.
    n: Vector3<f64>,
    /// Plane offset: n·x = d on the face.
    d: f64,
    /// False once replaced.
    alive: bool,
    /// Points above this face, not yet on the hull.
    outside: Vec<usize>,
    /// Visit stamp for the visibility search.
    stamp: u32,
}

/// One representative of every cluster of points closer than `delta` to each other (the first
/// in x order), so that near-duplicates (e.g. one corner computed from several planes) never
/// form tiny, ill-conditioned facets.
fn distinct(pts: &[Vector3<f64>], delta: f64) -> Vec<Vector3<f64>> {
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| pts[a].x.total_cmp(&pts[b].x));
    let mut kept: Vec<Vector3<f64>> = Vec::with_capacity(pts.len());
    for i in order {
        let p = pts[i];
        let near = kept
            .iter()
            .rev()
            .take_while(|q| q.x >= p.x - delta)
            .any(|q| (p - q).norm() <= delta);
        if !near {
            kept.push(p);
        }
    }
    kept
}

/// A hull as corners and outward triangles indexing them.
type Mesh = (Vec<Vector3<f64>>, Vec<[usize; 3]>);

/// Quickhull of `pts` without spurious corners: returns the corners (a subset of `pts`) and
/// outward triangles indexing them.
///
/// Near-duplicates are merged first ([`distinct`]). Quickhull adds the farthest outside point
/// at each step, which can end up on an edge or in a face of the final hull (e.g. a zonotope's
/// edge midpoint); such points are no corners: they are dropped ([`corner_flags`]) and the rest
/// hulled again. Points scattered about a plane by about the tolerance can make the
/// tolerance-based visibility inconsistent; the result is therefore checked (every point on
/// or below every facet plane, to 1000× the tolerance) and, failing that, recomputed with a
/// 1000× and then a 10⁵× larger tolerance.
fn quickhull(pts: &[Vector3<f64>]) -> Result<Mesh, Error> {
    let scale = pts.iter().map(|p| p.amax()).fold(0.0, f64::max);
    let pts = distinct(pts, MERGE_TOL * scale);
    let mut failure = Error::Numerical {
        what: "convex hull",
        reason: "no attempt".into(),
    };
    for tol in [HULL_TOL, 1e3 * HULL_TOL, 1e5 * HULL_TOL] {
        let eps = tol * scale;
        match hull_without_spurious_corners(&pts, eps) {
            Ok(mesh) => {
                let worst = max_violation(&mesh, &pts);
                if worst <= 1e3 * eps {
                    return Ok(mesh);
                }
                failure = Error::Numerical {
                    what: "convex hull",
                    reason: format!("a point is {worst:e} outside a facet"),
                };
            }
            Err(e @ Error::Degenerate { .. }) => return Err(e),
            Err(e) => failure = e,
        }
    }
    Err(failure)
}

/// [`quickhull_raw`] at tolerance `eps` (a length), then non-corners dropped and the rest
/// hulled again (rarely more than once).
fn hull_without_spurious_corners(pts: &[Vector3<f64>], eps: f64) -> Result<Mesh, Error> {
    let (mut verts, mut facets) = quickhull_raw(pts, eps)?;
    for _ in 0..4 {
        let keep = corner_flags(&verts, &facets, eps);
        if keep.iter().all(|&k| k) {
            break;
        }
        let corners: Vec<Vector3<f64>> = verts
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(v, _)| *v)
            .collect();
        (verts, facets) = quickhull_raw(&corners, eps)?;
    }
    Ok((verts, facets))
}

/// Largest signed distance of any of `pts` above any facet plane of `mesh` (≤ 0 when all
/// are inside), or +∞ for a facet without a normal.
fn max_violation(mesh: &Mesh, pts: &[Vector3<f64>]) -> f64 {
    let (verts, facets) = mesh;
    let mut worst = f64::NEG_INFINITY;
    for f in facets {
        let Ok((n, d)) = plane_of(verts, *f) else {
            return f64::INFINITY;
        };
        for p in pts {
            worst = worst.max(n.dot(p) - d);
        }
    }
    worst
}

/// For each vertex of a closed convex mesh: whether it is a true corner. A vertex is not
/// one when, within `eps` (a length), it lies in the plane of all its neighbours (inside a
/// flat face) or strictly between two of its neighbours on their segment (inside an edge).
fn corner_flags(verts: &[Vector3<f64>], facets: &[[usize; 3]], eps: f64) -> Vec<bool> {
    let mut star: Vec<Vec<usize>> = vec![Vec::new(); verts.len()];
    for f in facets {
        for k in 0..3 {
            let (v, w) = (f[k], f[(k + 1) % 3]);
            if !star[v].contains(&w) {
                star[v].push(w);
            }
            if !star[w].contains(&v) {
                star[w].push(v);
            }
        }
    }
    star.iter()
        .enumerate()
        .map(|(i, nbrs)| {
            let v = verts[i];
            // Inside a face: every neighbour in the plane of v and its first two neighbours.
            if let [a, b, ..] = nbrs[..] {
                let n = (verts[a] - v).cross(&(verts[b] - v));
                let len = n.norm();
                if len > 0.0
                    && nbrs
                        .iter()
                        .all(|&w| (n.dot(&(verts[w] - v)) / len).abs() <= eps)
                {
                    return false;
                }
            }
            // Inside an edge: on the segment between two neighbours.
            for (x, &a) in nbrs.iter().enumerate() {
                for &b in &nbrs[x + 1..] {
                    let ab = verts[b] - verts[a];
                    let av = v - verts[a];
                    let l2 = ab.norm_squared();
                    let t = av.dot(&ab);
                    if t > 0.0 && t < l2 && av.cross(&ab).norm() <= eps * l2.sqrt() {
                        return false;
                    }
                }
            }
            true
        })
        .collect()
}

/// Plain quickhull of `pts` at tolerance `eps` (a length: points within it of a facet plane
/// are on it): corners (a subset of `pts`, possibly with points on edges or faces of the
/// hull) and outward triangles indexing them.
fn quickhull_raw(pts: &[Vector3<f64>], eps: f64) -> Result<Mesh, Error> {
    if pts.is_empty() {
        return Err(Error::Degenerate {
            what: "convex hull",
            dimension: 0,
        });
    }
    let simplex = initial_simplex(pts, eps)?;
    let mut faces: Vec<Face> = Vec::with_capacity(8 * pts.len().min(1024));
    let [i0, i1, i2, i3] = simplex;
    // Orient so that i3 is below the face (i0, i1, i2).
    let below = plane_of(pts, [i0, i1, i2])?.0.dot(&(pts[i3] - pts[i0])) < 0.0;
    let tris = if below {
        [[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]]
    } else {
        [[i0, i2, i1], [i0, i1, i3], [i1, i2, i3], [i2, i0, i3]]
    };
    for t in tris {
        let (n, d) = plane_of(pts, t)?;
        faces.push(Face {
            v: t,
            nb: [NONE; 3],
            n,
            d,
            alive: true,
            outside: Vec::new(),
            stamp: 0,
        });
    }
    for f in 0..4 {
        for k in 0..3 {
            let (a, b) = (faces[f].v[k], faces[f].v[(k + 1) % 3]);
            faces[f].nb[k] = (0..4)
                .find(|&g| g != f && edge_index(&faces[g], b, a).is_some())
                .unwrap_or(NONE);
        }
    }
    for (i, p) in pts.iter().enumerate() {
        if simplex.contains(&i) {
            continue;
        }
        if let Some(f) = (0..4).find(|&f| faces[f].n.dot(p) - faces[f].d > eps) {
            faces[f].outside.push(i);
        }
    }

    let mut stamp = 0u32;
    let mut visible: Vec<usize> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut horizon: Vec<(usize, usize, usize)> = Vec::new();
    let mut start_of: Vec<usize> = vec![NONE; pts.len()];
    let mut orphans: Vec<usize> = Vec::new();
    let mut pending: Vec<usize> = (0..4).collect();
    let max_steps = 4 * pts.len() + 16;
    let mut steps = 0;
    while let Some(f0) = pending.pop() {
        if !faces[f0].alive || faces[f0].outside.is_empty() {
            continue;
        }
        steps += 1;
        if steps > max_steps {
            return Err(Error::Numerical {
                what: "convex hull",
                reason: "too many steps".into(),
            });
        }
        // Farthest outside point of this face.
        let (n0, d0) = (faces[f0].n, faces[f0].d);
        let mut eye = faces[f0].outside[0];
        let mut far = f64::NEG_INFINITY;
        for &i in &faces[f0].outside {
            let h = n0.dot(&pts[i]) - d0;
            if h > far {
                far = h;
                eye = i;
            }
        }
        let p = pts[eye];
        // Visible faces: connected search from f0.
        stamp = stamp.wrapping_add(1);
        visible.clear();
        stack.clear();
        stack.push(f0);
        faces[f0].stamp = stamp;
        while let Some(f) = stack.pop() {
            visible.push(f);
            for k in 0..3 {
                let g = faces[f].nb[k];
                if g == NONE {
                    return Err(Error::Numerical {
                        what: "convex hull",
                        reason: "open mesh".into(),
                    });
                }
                if faces[g].stamp != stamp && faces[g].n.dot(&p) - faces[g].d > eps {
                    faces[g].stamp = stamp;
                    stack.push(g);
                }
            }
        }
        // Horizon: edges of visible faces whose neighbour is not visible.
        horizon.clear();
        for &f in &visible {
            for k in 0..3 {
                let g = faces[f].nb[k];
                if faces[g].stamp != stamp {
                    horizon.push((faces[f].v[k], faces[f].v[(k + 1) % 3], g));
                }
            }
        }
        // New faces (a, b, eye), one per horizon edge.
        let first_new = faces.len();
        for &(a, b, g) in &horizon {
            if start_of[a] != NONE {
                reset(&mut start_of, &horizon);
                return Err(Error::Numerical {
                    what: "convex hull",
                    reason: "the visible region is not a disc".into(),
                });
            }
            let (n, d) = plane_of(pts, [a, b, eye])?;
            let f = faces.len();
            faces.push(Face {
                v: [a, b, eye],
                nb: [g, NONE, NONE],
                n,
                d,
                alive: true,
                outside: Vec::new(),
                stamp: 0,
            });
            start_of[a] = f;
            match edge_index(&faces[g], b, a) {
                Some(k) => faces[g].nb[k] = f,
                None => {
                    reset(&mut start_of, &horizon);
                    return Err(Error::Numerical {
                        what: "convex hull",
                        reason: "broken adjacency".into(),
                    });
                }
            }
        }
        for f in first_new..faces.len() {
            let b = faces[f].v[1];
            let g = start_of[b];
            if g == NONE {
                reset(&mut start_of, &horizon);
                return Err(Error::Numerical {
                    what: "convex hull",
                    reason: "open horizon".into(),
                });
            }
            faces[f].nb[1] = g;
            faces[g].nb[2] = f;
        }
        reset(&mut start_of, &horizon);
        // Retire the visible faces and hand their points to the new ones.
        orphans.clear();
        for &f in &visible {
            faces[f].alive = false;
            orphans.append(&mut faces[f].outside);
        }
        for &i in &orphans {
            if i == eye {
                continue;
            }
            let q = pts[i];
            if let Some(f) =
                (first_new..faces.len()).find(|&f| faces[f].n.dot(&q) - faces[f].d > eps)
            {
                faces[f].outside.push(i);
            }
        }
        pending.extend(first_new..faces.len());
    }

    // Compact: keep used corners only.
    let mut map = vec![NONE; pts.len()];
    let mut verts = Vec::new();
    let mut out = Vec::new();
    for f in faces.iter().filter(|f| f.alive) {
        let mut t = [0; 3];
        for (slot, &i) in t.iter_mut().zip(&f.v) {
            if map[i] == NONE {
                map[i] = verts.len();
                verts.push(pts[i]);
            }
            *slot = map[i];
        }
        out.push(t);
    }
    Ok((verts, out))
}

/// Clears the `start_of` entries set for `horizon`.
fn reset(start_of: &mut [usize], horizon: &[(usize, usize, usize)]) {
    for &(a, _, _) in horizon {
        start_of[a] = NONE;
    }
}

/// Index k of edge a → b in `face`, if it has it.
fn edge_index(face: &Face, a: usize, b: usize) -> Option<usize> {
    (0..3).find(|&k| face.v[k] == a && face.v[(k + 1) % 3] == b)
}

/// Unit normal (right-hand rule over t) and offset of the plane through three points.
fn plane_of(pts: &[Vector3<f64>], t: [usize; 3]) -> Result<(Vector3<f64>, f64), Error> {
    let (a, b, c) = (pts[t[0]], pts[t[1]], pts[t[2]]);
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return Err(Error::Numerical {
            what: "convex hull",
            reason: "zero-area facet".into(),
        });
    }
    let n = n / len;
    Ok((n, n.dot(&a)))
}

/// Four affinely independent points (beyond `eps`), or the dimension the points span.
fn initial_simplex(pts: &[Vector3<f64>], eps: f64) -> Result<[usize; 4], Error> {
    // Extreme points along the axes; the farthest pair among them.
    let mut ext = [0usize; 6];
    for (i, p) in pts.iter().enumerate() {
        for ax in 0..3 {
            if p[ax] < pts[ext[2 * ax]][ax] {
                ext[2 * ax] = i;
            }
            if p[ax] > pts[ext[2 * ax + 1]][ax] {
                ext[2 * ax + 1] = i;
            }
        }
    }
    let mut best = (0.0, 0, 0);
    for &a in &ext {
        for &b in &ext {
            let d = (pts[a] - pts[b]).norm();
            if d > best.0 {
                best = (d, a, b);
            }
        }
    }
    let (span, i0, i1) = best;
    if span.is_nan() || span <= eps {
        return Err(Error::Degenerate {
            what: "convex hull",
            dimension: 0,
        });
    }
    let dir = (pts[i1] - pts[i0]) / span;
    let (mut far, mut i2) = (0.0, NONE);
    for (i, p) in pts.iter().enumerate() {
        let r = p - pts[i0];
        let d = (r - dir * r.dot(&dir)).norm();
        if d > far {
            far = d;
            i2 = i;
        }
    }
    if far <= eps || i2 == NONE {
        return Err(Error::Degenerate {
            what: "convex hull",
            dimension: 1,
        });
    }
    let n = (pts[i1] - pts[i0]).cross(&(pts[i2] - pts[i0])).normalize();
    let (mut far, mut i3) = (0.0, NONE);
    for (i, p) in pts.iter().enumerate() {
        let d = n.dot(&(p - pts[i0])).abs();
        if d > far {
            far = d;
            i3 = i;
        }
    }
    if far <= eps || i3 == NONE {
        return Err(Error::Degenerate {
            what: "convex hull",
            dimension: 2,
        });
    }
    Ok([i0, i1, i2, i3])
}
