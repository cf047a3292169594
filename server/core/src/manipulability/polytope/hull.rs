//! Convex hull of 3-D points: quickhull with a scale-relative tolerance, near-duplicates
//! merged first, spurious corners (points on an edge or in a face) dropped, and the result
//! checked against every input point, with a larger tolerance on failure.

use nalgebra::Vector3;

use crate::Error;

/// Relative tolerance of the hull: points closer than this times the largest absolute
/// coordinate to a facet plane count as on it.
pub(super) const HULL_TOL: f64 = 1e-12;
/// Relative distance below which two points are one (duplicates are merged before hulling).
const MERGE_TOL: f64 = 1e-10;

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
/// A hull as corners and outward triangles indexing them.
pub(super) type Mesh = (Vec<Vector3<f64>>, Vec<[usize; 3]>);

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
pub(super) fn quickhull(pts: &[Vector3<f64>]) -> Result<Mesh, Error> {
    let scale = pts.iter().map(|p| p.amax()).fold(0.0, f64::max);
    let pts = distinct(pts, MERGE_TOL * scale);
    let mut failure = hull_error("no attempt");
    for tol in [HULL_TOL, 1e3 * HULL_TOL, 1e5 * HULL_TOL] {
        let eps = tol * scale;
        match hull_without_spurious_corners(&pts, eps) {
            Ok(mesh) => {
                let worst = max_violation(&mesh, &pts);
                if worst <= 1e3 * eps {
                    return Ok(mesh);
                }
                failure = hull_error(&format!("a point is {worst:e} outside a facet"));
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
    let mut hull = Hull::new(pts, eps)?;
    let mut pending: Vec<usize> = (0..4).collect();
    let max_steps = 4 * pts.len() + 16;
    let mut steps = 0;
    while let Some(f0) = pending.pop() {
        if !hull.faces[f0].alive || hull.faces[f0].outside.is_empty() {
            continue;
        }
        steps += 1;
        if steps > max_steps {
            return Err(hull_error("too many steps"));
        }
        let new_faces = hull.add_farthest_point(f0)?;
        pending.extend(new_faces);
    }
    Ok(hull.into_mesh())
}

/// [`Error::Numerical`] of the convex hull with `reason`.
fn hull_error(reason: &str) -> Error {
    Error::Numerical {
        what: "convex hull",
        reason: reason.into(),
    }
}

/// The state of [`quickhull_raw`]: the faces so far (retired ones included, `alive` false)
/// and the scratch lists of one step, kept to reuse their storage.
struct Hull<'a> {
    /// The input points.
    pts: &'a [Vector3<f64>],
    /// Tolerance (a length).
    eps: f64,
    /// Every face made so far.
    faces: Vec<Face>,
    /// The stamp of the current visibility search.
    stamp: u32,
    /// Faces the current eye point sees.
    visible: Vec<usize>,
    /// Search stack of the visibility search.
    stack: Vec<usize>,
    /// Horizon edges (a, b, face across) of the visible region.
    horizon: Vec<(usize, usize, usize)>,
    /// `start_of[a]`: the new face whose horizon edge starts at point a (`NONE` otherwise).
    start_of: Vec<usize>,
    /// Outside points of the retired faces, to be handed on.
    orphans: Vec<usize>,
}

impl<'a> Hull<'a> {
    /// The initial tetrahedron of [`initial_simplex`], outward, its adjacency, and every
    /// other point given to the first face it is above.
    fn new(pts: &'a [Vector3<f64>], eps: f64) -> Result<Hull<'a>, Error> {
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
            faces.push(Face::new(pts, t, [NONE; 3])?);
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
        Ok(Hull {
            pts,
            eps,
            faces,
            stamp: 0,
            visible: Vec::new(),
            stack: Vec::new(),
            horizon: Vec::new(),
            start_of: vec![NONE; pts.len()],
            orphans: Vec::new(),
        })
    }

    /// One quickhull step on face `f0` (alive, with outside points): its farthest outside
    /// point (the eye) joins the hull. The faces it sees are retired, a cone of new faces
    /// joins it to their horizon, and their outside points go to the new faces. Returns the
    /// new faces' indices.
    fn add_farthest_point(&mut self, f0: usize) -> Result<std::ops::Range<usize>, Error> {
        // Farthest outside point of this face.
        let (n0, d0) = (self.faces[f0].n, self.faces[f0].d);
        let mut eye = self.faces[f0].outside[0];
        let mut far = f64::NEG_INFINITY;
        for &i in &self.faces[f0].outside {
            let h = n0.dot(&self.pts[i]) - d0;
            if h > far {
                far = h;
                eye = i;
            }
        }
        self.find_visible(f0, eye)?;
        let new_faces = self.add_cone(eye)?;
        self.hand_on_points(eye, new_faces.start);
        Ok(new_faces)
    }

    /// The faces the point `eye` sees (a connected search from `f0`, which it sees) into
    /// `visible`, stamped, and the horizon: their edges whose neighbour it does not see.
    fn find_visible(&mut self, f0: usize, eye: usize) -> Result<(), Error> {
        let (faces, p) = (&mut self.faces, self.pts[eye]);
        self.stamp = self.stamp.wrapping_add(1);
        let stamp = self.stamp;
        self.visible.clear();
        self.stack.clear();
        self.stack.push(f0);
        faces[f0].stamp = stamp;
        while let Some(f) = self.stack.pop() {
            self.visible.push(f);
            for k in 0..3 {
                let g = faces[f].nb[k];
                if g == NONE {
                    return Err(hull_error("open mesh"));
                }
                if faces[g].stamp != stamp && faces[g].n.dot(&p) - faces[g].d > self.eps {
                    faces[g].stamp = stamp;
                    self.stack.push(g);
                }
            }
        }
        // Horizon: edges of visible faces whose neighbour is not visible.
        self.horizon.clear();
        for &f in &self.visible {
            for k in 0..3 {
                let g = faces[f].nb[k];
                if faces[g].stamp != stamp {
                    self.horizon
                        .push((faces[f].v[k], faces[f].v[(k + 1) % 3], g));
                }
            }
        }
        Ok(())
    }

    /// New faces (a, b, eye), one per horizon edge, linked to the faces across the horizon
    /// and to each other. Returns their indices.
    fn add_cone(&mut self, eye: usize) -> Result<std::ops::Range<usize>, Error> {
        let first_new = self.faces.len();
        let result = self.link_cone(eye, first_new);
        // Clear the `start_of` entries set for the horizon, also after a failure.
        for &(a, _, _) in &self.horizon {
            self.start_of[a] = NONE;
        }
        result.map(|()| first_new..self.faces.len())
    }

    /// [`Hull::add_cone`] but for clearing `start_of`.
    fn link_cone(&mut self, eye: usize, first_new: usize) -> Result<(), Error> {
        let faces = &mut self.faces;
        for &(a, b, g) in &self.horizon {
            if self.start_of[a] != NONE {
                return Err(hull_error("the visible region is not a disc"));
            }
            let f = faces.len();
            faces.push(Face::new(self.pts, [a, b, eye], [g, NONE, NONE])?);
            self.start_of[a] = f;
            match edge_index(&faces[g], b, a) {
                Some(k) => faces[g].nb[k] = f,
                None => return Err(hull_error("broken adjacency")),
            }
        }
        for f in first_new..faces.len() {
            let b = faces[f].v[1];
            let g = self.start_of[b];
            if g == NONE {
                return Err(hull_error("open horizon"));
            }
            faces[f].nb[1] = g;
            faces[g].nb[2] = f;
        }
        Ok(())
    }

    /// Retires the visible faces and hands their outside points (but `eye`) to the first new
    /// face (from `first_new` on) they are above.
    fn hand_on_points(&mut self, eye: usize, first_new: usize) {
        let faces = &mut self.faces;
        self.orphans.clear();
        for &f in &self.visible {
            faces[f].alive = false;
            self.orphans.append(&mut faces[f].outside);
        }
        for &i in &self.orphans {
            if i == eye {
                continue;
            }
            let q = self.pts[i];
            if let Some(f) =
                (first_new..faces.len()).find(|&f| faces[f].n.dot(&q) - faces[f].d > self.eps)
            {
                faces[f].outside.push(i);
            }
        }
    }

    /// The live faces as a [`Mesh`] of the corners they use.
    fn into_mesh(self) -> Mesh {
        let mut map = vec![NONE; self.pts.len()];
        let mut verts = Vec::new();
        let mut out = Vec::new();
        for f in self.faces.iter().filter(|f| f.alive) {
            let mut t = [0; 3];
            for (slot, &i) in t.iter_mut().zip(&f.v) {
                if map[i] == NONE {
                    map[i] = verts.len();
                    verts.push(self.pts[i]);
                }
                *slot = map[i];
            }
            out.push(t);
        }
        (verts, out)
    }
}

impl Face {
    /// The live face with corners `v` (outward order) and neighbours `nb`, no outside points.
    fn new(pts: &[Vector3<f64>], v: [usize; 3], nb: [usize; 3]) -> Result<Face, Error> {
        let (n, d) = plane_of(pts, v)?;
        Ok(Face {
            v,
            nb,
            n,
            d,
            alive: true,
            outside: Vec::new(),
            stamp: 0,
        })
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
        return Err(hull_error("zero-area facet"));
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
    let degenerate = |dimension| Error::Degenerate {
        what: "convex hull",
        dimension,
    };
    if span.is_nan() || span <= eps {
        return Err(degenerate(0));
    }
    // Farthest from the line i0–i1, then from the plane through the three.
    let dir = (pts[i1] - pts[i0]) / span;
    let i2 = farthest_beyond(pts, eps, |r| (r - dir * r.dot(&dir)).norm(), pts[i0])
        .ok_or_else(|| degenerate(1))?;
    let n = (pts[i1] - pts[i0]).cross(&(pts[i2] - pts[i0])).normalize();
    let i3 =
        farthest_beyond(pts, eps, |r| n.dot(&r).abs(), pts[i0]).ok_or_else(|| degenerate(2))?;
    Ok([i0, i1, i2, i3])
}

/// The index of the point p of `pts` farthest by `dist(p − origin)` (the first of equals),
/// if that distance exceeds `eps`.
fn farthest_beyond(
    pts: &[Vector3<f64>],
    eps: f64,
    dist: impl Fn(Vector3<f64>) -> f64,
    origin: Vector3<f64>,
) -> Option<usize> {
    let (mut far, mut best) = (0.0, NONE);
    for (i, p) in pts.iter().enumerate() {
        let d = dist(p - origin);
        if d > far {
            far = d;
            best = i;
        }
    }
    (far > eps && best != NONE).then_some(best)
}
