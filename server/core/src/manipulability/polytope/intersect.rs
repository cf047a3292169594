//! The intersection of two convex polytopes by clipping one with the facet planes of the
//! other (Sutherland–Hodgman per face plus a cap per plane), then hulled.

use nalgebra::Vector3;

use super::hull::{HULL_TOL, quickhull};
use super::{Polytope, polytope_from_mesh};
use crate::Error;

/// P₁ ∩ P₂ by clipping P₁ with every facet plane of P₂ (halfspace n·x ≤ d, unit outward n).
///
/// P₁ is kept as polygon faces; each plane clips every face (Sutherland–Hodgman) and closes
/// the cut with a cap polygon. Every new corner lies on an edge of the current polytope, so the
/// result never leaves P₁, and it is within the hull tolerance of every plane of P₂. Planes
/// that cut nothing (every corner within the tolerance) are skipped: P ∩ P = P exactly.
pub(super) fn intersect(p1: &Polytope, p2: &Polytope) -> Result<Polytope, Error> {
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
