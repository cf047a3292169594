//! The zonotope of a Jacobian's scaled columns: its generators (validated, zero ones
//! dropped, parallel ones merged), the candidate corners of the 3-D zonotope from its facet
//! zonogons, and the 2-D zonogon as a polygon.

use nalgebra::{DMatrix, Vector3};

use super::Polytope;
use crate::Error;

/// Relative tolerance for generators: a generator shorter than this times the longest one is
/// dropped; two generators whose sine of angle is below it are parallel; a generator whose
/// out-of-plane component is below it times its length lies in that plane.
const GEN_TOL: f64 = 1e-9;

/// Validates `j` and `qdot_max` and returns the generators qᵢmax·jᵢ (as 3-vectors, z = 0 for
/// m = 2), with zero ones dropped and parallel ones merged (two parallel segments sum to one
/// segment of the summed length).
pub(super) fn generators(j: &DMatrix<f64>, qdot_max: &[f64]) -> Result<Vec<Vector3<f64>>, Error> {
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
pub(super) fn zonotope_candidates(gens: &[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, Error> {
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
pub(super) fn zonogon_polytope(gens: &[Vector3<f64>]) -> Result<Polytope, Error> {
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
