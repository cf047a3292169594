//! Velocity polytopes (Kilic §3.2): hull invariants, zonotope volume closed form, cone-cell
//! index, dual-arm intersection, degenerate inputs, and real robots.

#![allow(clippy::unwrap_used)] // Tests may unwrap (STYLE: `unwrap_used` outside tests).

mod common;

use nalgebra::{DMatrix, Matrix3, Vector3};
use proptest::prelude::*;
use seaarms_core::Error;
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::{
    Polytope, convex_hull, dual_velocity_polytope, select_rows, velocity_polytope,
};

// ----------------------------------------------------------------------------------------
// Independent references
// ----------------------------------------------------------------------------------------

/// Generators gᵢ = q̇ᵢmax·jᵢ (Kilic eq. 1.50) as 3-vectors.
fn generators(j: &DMatrix<f64>, qmax: &[f64]) -> Vec<Vector3<f64>> {
    (0..j.ncols())
        .map(|k| Vector3::new(j[(0, k)], j[(1, k)], j[(2, k)]) * qmax[k])
        .collect()
}

/// Zonotope volume closed form (McMullen / Shephard; e.g. Gover & Krikorian, "Determinants
/// and the volumes of parallelotopes and zonotopes", Linear Algebra Appl. 2010):
/// vol Σᵢ[−gᵢ, gᵢ] = 2^m Σ over m-subsets |det(g_i, g_j, g_k)|, here m = 3.
fn zonotope_volume(g: &[Vector3<f64>]) -> f64 {
    let mut sum = 0.0;
    for a in 0..g.len() {
        for b in a + 1..g.len() {
            for c in b + 1..g.len() {
                sum += Matrix3::from_columns(&[g[a], g[b], g[c]])
                    .determinant()
                    .abs();
            }
        }
    }
    8.0 * sum
}

/// Kilic §3.2.1 pseudo-code without the pruning: all 2ⁿ sums ±g₁ ± … ± gₙ.
fn all_sign_sums(g: &[Vector3<f64>]) -> Vec<[f64; 3]> {
    (0..1usize << g.len())
        .map(|mask| {
            let v: Vector3<f64> = g
                .iter()
                .enumerate()
                .map(|(i, gi)| if mask >> i & 1 == 1 { *gi } else { -gi })
                .sum();
            [v.x, v.y, v.z]
        })
        .collect()
}

fn v3(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// Facet planes (unit outward normal n, offset d: n·x ≤ d inside).
fn planes(p: &Polytope) -> Vec<(Vector3<f64>, f64)> {
    p.facets
        .iter()
        .map(|f| {
            let (a, b, c) = (
                v3(&p.vertices[f[0]]),
                v3(&p.vertices[f[1]]),
                v3(&p.vertices[f[2]]),
            );
            let n = (b - a).cross(&(c - a)).normalize();
            (n, n.dot(&a))
        })
        .collect()
}

fn scale_of(p: &Polytope) -> f64 {
    p.vertices
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()))
}

fn inside(p: &Polytope, x: &Vector3<f64>, tol: f64) -> bool {
    planes(p).iter().all(|(n, d)| n.dot(x) <= d + tol)
}

/// Closed-mesh invariants: outward facets, every directed edge matched by its reverse,
/// Euler V − E + F = 2, convexity (all corners on or below every facet plane).
fn check_mesh(p: &Polytope) {
    check_mesh_tol(p, 1e-9 * scale_of(p));
}

/// [`check_mesh`] with convexity to within `tol`.
fn check_mesh_tol(p: &Polytope, tol: f64) {
    let nv = p.vertices.len();
    assert!(nv >= 4, "{} vertices", nv);
    let centroid: Vector3<f64> = p.vertices.iter().map(v3).sum::<Vector3<f64>>() / nv as f64;
    for (f, (n, d)) in p.facets.iter().zip(planes(p)) {
        let a = v3(&p.vertices[f[0]]);
        assert!(n.dot(&(a - centroid)) > 0.0, "facet {f:?} points inward");
        for v in &p.vertices {
            assert!(
                n.dot(&v3(v)) <= d + tol,
                "hull is not convex at facet {f:?}: {} > {tol:e}",
                n.dot(&v3(v)) - d
            );
        }
    }
    let mut edges = std::collections::HashSet::new();
    for f in &p.facets {
        for k in 0..3 {
            assert!(
                edges.insert((f[k], f[(k + 1) % 3])),
                "edge repeated in {f:?}"
            );
        }
    }
    for &(a, b) in &edges {
        assert!(edges.contains(&(b, a)), "edge {a}-{b} has one facet");
    }
    let e = edges.len() / 2;
    assert_eq!(
        nv as i64 - e as i64 + p.facets.len() as i64,
        2,
        "Euler V − E + F"
    );
    let used: std::collections::HashSet<usize> = p.facets.iter().flatten().copied().collect();
    assert_eq!(used.len(), nv, "unused vertex");
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

fn matrix(m: usize, n: usize, v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_row_slice(m, n, v)
}

/// Kilic §4.2 PA10 posture ("extrusion of an improper hexagon").
const PA10_Q: [f64; 7] = [
    0.0,
    std::f64::consts::FRAC_PI_4,
    0.0,
    std::f64::consts::FRAC_PI_4,
    0.0,
    std::f64::consts::FRAC_PI_4,
    0.0,
];

fn translational(model: &seaarms_core::Model, q: &[f64]) -> DMatrix<f64> {
    select_rows(&jacobian_at(model, q), &[0, 1, 2]).expect("rows 0..3")
}

// ----------------------------------------------------------------------------------------
// Closed forms and small cases
// ----------------------------------------------------------------------------------------

/// Unit cube: J = I, q̇max = 1 gives [−1, 1]³ (Kilic eq. 1.50 with three unit columns):
/// 8 corners, 12 triangles, volume 8, w_p 8.
#[test]
fn unit_cube_has_8_vertices_12_triangles_volume_8() {
    let p = velocity_polytope(&DMatrix::identity(3, 3), &[1.0; 3]).unwrap();
    assert_eq!(p.vertices.len(), 8);
    assert_eq!(p.facets.len(), 12);
    assert!(close(p.volume, 8.0, 1e-12), "volume {}", p.volume);
    assert!(close(p.w_p, 8.0, 1e-12), "w_p {}", p.w_p);
    for v in &p.vertices {
        assert!(v.iter().all(|x| (x.abs() - 1.0).abs() < 1e-12), "{v:?}");
    }
    check_mesh(&p);
}

/// Parallelepiped: three generators span a parallelepiped of volume 2³·|det J| (linear map of
/// the cube [−1, 1]³).
#[test]
fn parallelepiped_volume_is_8_abs_det() {
    let j = matrix(3, 3, &[0.3, -1.2, 0.5, 0.9, 0.4, -0.7, -0.2, 0.8, 1.1]);
    let qmax = [0.7, 1.3, 2.0];
    let p = velocity_polytope(&j, &qmax).unwrap();
    let det =
        (&j * DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&qmax))).determinant();
    assert_eq!(p.vertices.len(), 8);
    assert_eq!(p.facets.len(), 12);
    assert!(
        close(p.volume, 8.0 * det.abs(), 1e-12),
        "{} vs {}",
        p.volume,
        8.0 * det.abs()
    );
    check_mesh(&p);
}

/// Planar case (m = 2): J = I gives the square [−1, 1]², area 4; a planar 2R arm's polygon
/// area equals 2²·|det(g₁, g₂)| (zonotope closed form, m = 2).
#[test]
fn planar_polygon_area_matches_closed_form() {
    let sq = velocity_polytope(&DMatrix::identity(2, 2), &[1.0, 1.0]).unwrap();
    assert_eq!(sq.vertices.len(), 4);
    assert_eq!(sq.facets.len(), 2);
    assert!(close(sq.volume, 4.0, 1e-12) && close(sq.w_p, 4.0, 1e-12));

    let model = common::builtin("planar2r");
    let j = select_rows(&jacobian_at(&model, &[0.3, 1.1]), &[0, 1]).unwrap();
    let qmax = model.max_velocities();
    let p = velocity_polytope(&j, &qmax).unwrap();
    let det = (j[(0, 0)] * j[(1, 1)] - j[(1, 0)] * j[(0, 1)]) * qmax[0] * qmax[1];
    assert!(
        close(p.volume, 4.0 * det.abs(), 1e-12),
        "{} vs {}",
        p.volume,
        4.0 * det.abs()
    );
    assert!(close(p.w_p, p.volume, 1e-12));

    // Three planar generators: a hexagon, area 4·Σ|det| over pairs.
    let j = matrix(2, 3, &[1.0, 0.2, -0.5, 0.1, 0.9, 0.6]);
    let p = velocity_polytope(&j, &[1.0, 0.5, 2.0]).unwrap();
    assert_eq!(p.vertices.len(), 6);
    let g: Vec<(f64, f64)> = (0..3)
        .map(|k| {
            (
                j[(0, k)] * [1.0, 0.5, 2.0][k],
                j[(1, k)] * [1.0, 0.5, 2.0][k],
            )
        })
        .collect();
    let mut area = 0.0;
    for a in 0..3 {
        for b in a + 1..3 {
            area += 4.0 * (g[a].0 * g[b].1 - g[a].1 * g[b].0).abs();
        }
    }
    assert!(close(p.volume, area, 1e-12), "{} vs {area}", p.volume);
    for w in p.vertices.windows(2) {
        assert_eq!(w[0][2], 0.0);
    }
}

/// Kilic §4.2: PA10 at q = [0, π/4, 0, π/4, 0, π/4, 0], translational rows, joint-rate
/// bounds from the model; the volume matches the zonotope closed form, w_p equals it (origin
/// inside, d₃ = 3!), and the hull equals the hull of all 2⁷ sign sums (Kilic's pseudo-code).
#[test]
fn pa10_kilic_posture_matches_zonotope_formula() {
    let model = common::builtin("pa10");
    let j = translational(&model, &PA10_Q);
    let qmax = model.max_velocities();
    let p = velocity_polytope(&j, &qmax).unwrap();
    let g = generators(&j, &qmax);
    let expected = zonotope_volume(&g);
    assert!(
        close(p.volume, expected, 1e-9),
        "{} vs {expected}",
        p.volume
    );
    assert!(close(p.w_p, p.volume, 1e-9));
    check_mesh(&p);
    let brute = convex_hull(&all_sign_sums(&g)).unwrap();
    assert!(close(brute.volume, p.volume, 1e-9));
    assert_eq!(brute.vertices.len(), p.vertices.len());
    // Joints 1, 3, 5 move the tool along y, joints 2, 4, 6 in the xz plane, joint 7 not at
    // all: a hexagon in xz extruded along y, 12 corners, 2·4 + 6·2 = 20 triangles.
    assert_eq!(p.vertices.len(), 12);
    assert_eq!(p.facets.len(), 20);
}

// ----------------------------------------------------------------------------------------
// Property tests
// ----------------------------------------------------------------------------------------

fn jacobian_and_bounds() -> impl Strategy<Value = (DMatrix<f64>, Vec<f64>)> {
    (3usize..=8).prop_flat_map(|n| {
        (
            prop::collection::vec(-2.0f64..2.0, 3 * n),
            prop::collection::vec(0.05f64..3.0, n),
        )
            .prop_map(move |(v, q)| (DMatrix::from_row_slice(3, n, &v), q))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Zonotope closed form (2³·Σ|det| over column triples, see `zonotope_volume`) equals the
    /// hull volume; Kilic eq. 1.54–1.55 with d₃ = 3! gives w_p = volume (origin inside).
    #[test]
    fn volume_matches_zonotope_closed_form((j, qmax) in jacobian_and_bounds()) {
        let p = velocity_polytope(&j, &qmax).unwrap();
        let expected = zonotope_volume(&generators(&j, &qmax));
        prop_assert!(close(p.volume, expected, 1e-9), "{} vs {}", p.volume, expected);
        prop_assert!(close(p.w_p, p.volume, 1e-9), "w_p {} vs volume {}", p.w_p, p.volume);
        check_mesh(&p);
    }

    /// The pruned candidates give the same polytope as Kilic's unpruned 2ⁿ Minkowski sums:
    /// every sign sum lies inside, and every corner is a sign sum.
    #[test]
    fn corners_are_sign_sums_and_contain_all_of_them((j, qmax) in jacobian_and_bounds()) {
        let p = velocity_polytope(&j, &qmax).unwrap();
        let sums = all_sign_sums(&generators(&j, &qmax));
        let tol = 1e-9 * scale_of(&p);
        for s in &sums {
            prop_assert!(inside(&p, &v3(s), tol), "sign sum {:?} outside", s);
        }
        for v in &p.vertices {
            prop_assert!(sums.iter().any(|s| (v3(s) - v3(v)).norm() <= tol), "corner {:?} is not a sign sum", v);
        }
    }

    /// Definition of the convex hull, on random points with exact duplicates mixed in: every
    /// input is inside or on every facet plane, every corner is an input, facets point
    /// outward, every edge has two facets, V − E + F = 2 (Euler, convex polyhedron).
    #[test]
    fn hull_contains_inputs_and_corners_are_inputs(
        pts in prop::collection::vec(prop::array::uniform3(-5.0f64..5.0), 4..120),
        dup in 0usize..4,
    ) {
        let mut pts = pts;
        let extra: Vec<[f64; 3]> = pts.iter().take(dup * 3).copied().collect();
        pts.extend(extra);
        match convex_hull(&pts) {
            Ok(p) => {
                check_mesh(&p);
                let tol = 1e-9 * scale_of(&p);
                for q in &pts {
                    prop_assert!(inside(&p, &v3(q), tol), "{:?} outside", q);
                }
                for v in &p.vertices {
                    prop_assert!(pts.contains(v), "corner {:?} is not an input", v);
                }
                prop_assert!(p.volume > 0.0 && p.volume.is_finite());
            }
            Err(e) => prop_assert!(matches!(e, Error::Degenerate { .. }), "{e}"),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Integer generators in {−1, 0, 1}³ (many zero, repeated, parallel and coplanar columns,
    /// the hard cases for facet enumeration): the volume still matches the zonotope closed
    /// form, or the input is reported flat; never a panic or a numerical failure.
    #[test]
    fn lattice_generators_match_closed_form(
        v in prop::collection::vec(-1i8..=1, 9..=27),
        q in prop::collection::vec(prop::sample::select(vec![0.0, 0.5, 1.0, 2.0]), 9),
    ) {
        let n = v.len() / 3;
        let j = DMatrix::from_fn(3, n, |r, c| f64::from(v[3 * c + r]));
        let qmax = &q[..n];
        let expected = zonotope_volume(&generators(&j, qmax));
        match velocity_polytope(&j, qmax) {
            Ok(p) => {
                prop_assert!(close(p.volume, expected, 1e-9), "{} vs {}", p.volume, expected);
                check_mesh(&p);
            }
            Err(e) => {
                prop_assert!(matches!(e, Error::Degenerate { .. }), "{e}");
                prop_assert!(expected == 0.0, "flat reported but closed form is {expected}");
            }
        }
    }

    /// Nearly flat arms (third row scaled by 10⁻⁷…10⁻⁵): a valid thin hull with the closed-
    /// form volume (to the hull tolerance), and the dual polytope
    /// with a full arm no larger; or, if the arm is flat to the generator tolerance (10⁻⁹
    /// relative out-of-plane), a `Degenerate` error.
    #[test]
    fn nearly_flat_polytopes_stay_valid((j, qmax) in jacobian_and_bounds(), t in 1e-7f64..1e-5) {
        let mut j = j;
        j.row_mut(2).scale_mut(t);
        let g = generators(&j, &qmax);
        let expected = zonotope_volume(&g);
        let size: f64 = g.iter().map(|g| g.norm()).sum();
        match velocity_polytope(&j, &qmax) {
            Ok(p) => {
                // Points within 10⁻¹²·scale of the hull are dropped: the volume error is at
                // most about surface × that, tiny against size³ but not against a thin volume.
                let err = (p.volume - expected).abs();
                prop_assert!(
                    err <= 1e-6 * expected || err <= 1e-10 * size.powi(3),
                    "{} vs {}", p.volume, expected
                );
                check_mesh(&p);
                let both =
                    dual_velocity_polytope(&j, &qmax, &DMatrix::identity(3, 3), &[1.0; 3]).unwrap();
                prop_assert!(both.volume <= p.volume * (1.0 + 1e-6));
            }
            Err(e) => {
                prop_assert!(matches!(e, Error::Degenerate { .. }), "{e}");
                prop_assert!(expected <= 1e-6 * size.powi(3), "flat reported, volume {expected}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Kilic eqs 1.51–1.55 with d₃ = 3!: when the origin is inside, the cone cells from the
    /// origin to the facets tile the polytope, so w_p equals the volume — here for
    /// asymmetric hulls of random points around a small cube containing the origin.
    #[test]
    fn w_p_equals_volume_when_origin_inside(
        pts in prop::collection::vec(prop::array::uniform3(-4.0f64..6.0), 0..60),
    ) {
        let mut pts = pts;
        for i in 0..8 {
            let c = |b: usize| if i >> b & 1 == 1 { 0.1 } else { -0.1 };
            pts.push([c(0), c(1), c(2)]);
        }
        let p = convex_hull(&pts).unwrap();
        prop_assert!(inside(&p, &Vector3::zeros(), 0.0));
        prop_assert!(close(p.w_p, p.volume, 1e-9), "w_p {} vs volume {}", p.w_p, p.volume);
    }

    /// Scaling J by s scales every corner by s and the volume by s³ (homogeneity of
    /// P = {J q̇}), from 10⁻⁶ to 10⁶: the tolerances are relative.
    #[test]
    fn velocity_polytope_is_scale_invariant((j, qmax) in jacobian_and_bounds(), e in -6i32..=6) {
        let s = 10f64.powi(e);
        let p = velocity_polytope(&j, &qmax).unwrap();
        let ps = velocity_polytope(&(&j * s), &qmax).unwrap();
        prop_assert_eq!(p.vertices.len(), ps.vertices.len());
        prop_assert!(close(ps.volume, p.volume * s.powi(3), 1e-9));
        let q = dual_velocity_polytope(&(&j * s), &qmax, &(&j * s), &qmax).unwrap();
        prop_assert!(close(q.volume, ps.volume, 1e-9));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Near-degenerate clouds (a 4×4×4 grid, cube-face points and near-duplicates, all jittered
    /// by 10⁻¹⁶…10⁻⁸): the hull is a closed outward mesh, convex and containing every input
    /// to the documented worst case (10⁻⁴ × the largest coordinate, reached only when the
    /// jitter is near a hull tolerance), with the grid cube's volume.
    #[test]
    fn hull_of_jittered_grids_is_valid(
        jitter in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 64 + 48),
        e in -16i32..=-8,
        offset in prop::array::uniform3(-10.0f64..10.0),
    ) {
        let amp = 10f64.powi(e);
        let mut pts: Vec<[f64; 3]> = (0..64)
            .map(|i| [(i % 4) as f64 / 3.0, (i / 4 % 4) as f64 / 3.0, (i / 16) as f64 / 3.0])
            .collect();
        // Face-centre points and near-duplicates of corners.
        for i in 0..48 {
            pts.push(if i % 2 == 0 { [0.5, 0.5, (i % 4 / 2) as f64] } else { pts[(i * 7) % 64] });
        }
        for (p, j) in pts.iter_mut().zip(&jitter) {
            for k in 0..3 {
                p[k] += offset[k] + amp * j[k];
            }
        }
        let h = convex_hull(&pts).unwrap();
        let tol = 1e-4 * scale_of(&h);
        check_mesh_tol(&h, tol);
        for q in &pts {
            prop_assert!(inside(&h, &v3(q), tol), "{:?} outside", q);
        }
        prop_assert!((h.volume - 1.0).abs() <= 1e-6, "volume {}", h.volume);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Intersection properties: P ∩ P = P; P ∩ sP = P for s ≥ 1; vol(P₁ ∩ P₂) ≤ min; points
    /// inside both are inside the result and the result's corners are inside both.
    #[test]
    fn dual_polytope_is_the_intersection(
        (j1, q1) in jacobian_and_bounds(),
        (j2, q2) in jacobian_and_bounds(),
        s in 1.0f64..3.0,
        probes in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 200),
    ) {
        let p1 = velocity_polytope(&j1, &q1).unwrap();
        let p2 = velocity_polytope(&j2, &q2).unwrap();

        let same = dual_velocity_polytope(&j1, &q1, &j1, &q1).unwrap();
        prop_assert!(close(same.volume, p1.volume, 1e-9), "{} vs {}", same.volume, p1.volume);
        let qs: Vec<f64> = q1.iter().map(|q| q * s).collect();
        let scaled = dual_velocity_polytope(&j1, &qs, &j1, &q1).unwrap();
        prop_assert!(close(scaled.volume, p1.volume, 1e-9), "{} vs {}", scaled.volume, p1.volume);

        let both = dual_velocity_polytope(&j1, &q1, &j2, &q2).unwrap();
        check_mesh(&both);
        let tol = 1e-9 * scale_of(&p1).max(scale_of(&p2));
        prop_assert!(both.volume <= p1.volume.min(p2.volume) * (1.0 + 1e-9));
        prop_assert!(close(both.w_p, both.volume, 1e-9));
        for v in &both.vertices {
            prop_assert!(inside(&p1, &v3(v), tol) && inside(&p2, &v3(v), tol), "corner {:?} outside", v);
        }
        // Probes over the bounding box of the smaller polytope.
        let r = scale_of(&p1).min(scale_of(&p2));
        for q in &probes {
            let x = v3(q) * r;
            if inside(&p1, &x, -tol) && inside(&p2, &x, -tol) {
                prop_assert!(inside(&both, &x, tol), "{:?} inside both but not the result", x);
            }
        }
    }
}

// ----------------------------------------------------------------------------------------
// Degenerate and invalid inputs
// ----------------------------------------------------------------------------------------

/// Rank-2 J (third row a combination of the others): the polytope is flat, a documented
/// `Degenerate` error, no panic, no NaN.
#[test]
fn degenerate_inputs_give_errors_not_panics() {
    let j = matrix(
        3,
        4,
        &[1.0, 0.0, 0.5, 0.2, 0.0, 1.0, 0.3, -0.4, 1.0, 1.0, 0.8, -0.2],
    );
    assert_eq!(
        velocity_polytope(&j, &[1.0; 4]),
        Err(Error::Degenerate {
            what: "velocity polytope",
            dimension: 2
        })
    );
    // All columns parallel: a segment.
    let j = matrix(3, 3, &[1.0, 2.0, -1.0, 1.0, 2.0, -1.0, 0.0, 0.0, 0.0]);
    assert!(matches!(
        velocity_polytope(&j, &[1.0; 3]),
        Err(Error::Degenerate { dimension: 1, .. })
    ));
    // Zero matrix and zero bounds: a point.
    assert!(matches!(
        velocity_polytope(&DMatrix::zeros(3, 5), &[1.0; 5]),
        Err(Error::Degenerate { dimension: 0, .. })
    ));
    assert!(matches!(
        velocity_polytope(&DMatrix::identity(3, 3), &[0.0; 3]),
        Err(Error::Degenerate { dimension: 0, .. })
    ));
    // NaN and infinity.
    let mut j = DMatrix::identity(3, 3);
    j[(1, 2)] = f64::NAN;
    assert!(matches!(
        velocity_polytope(&j, &[1.0; 3]),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        velocity_polytope(&DMatrix::identity(3, 3), &[1.0, f64::INFINITY, 1.0]),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        convex_hull(&[[0.0, 0.0, f64::NAN]; 5]),
        Err(Error::NonFinite { .. })
    ));
    // Sizes and signs.
    assert!(matches!(
        velocity_polytope(&DMatrix::identity(3, 3), &[1.0; 2]),
        Err(Error::SizeMismatch { .. })
    ));
    assert!(matches!(
        velocity_polytope(&DMatrix::identity(6, 6), &[1.0; 6]),
        Err(Error::InvalidRows { .. })
    ));
    assert!(matches!(
        velocity_polytope(&DMatrix::identity(3, 3), &[1.0, -1.0, 1.0]),
        Err(Error::InvalidParameter { .. })
    ));
    // Hull of too few, collinear or coplanar points.
    assert!(matches!(
        convex_hull(&[]),
        Err(Error::Degenerate { dimension: 0, .. })
    ));
    assert!(matches!(
        convex_hull(&[[1.0, 2.0, 3.0]; 7]),
        Err(Error::Degenerate { dimension: 0, .. })
    ));
    let line: Vec<[f64; 3]> = (0..9)
        .map(|i| [i as f64, 2.0 * i as f64, -(i as f64)])
        .collect();
    assert!(matches!(
        convex_hull(&line),
        Err(Error::Degenerate { dimension: 1, .. })
    ));
    let flat: Vec<[f64; 3]> = (0..30)
        .map(|i| [(i % 5) as f64, (i / 5) as f64, 1.0])
        .collect();
    assert!(matches!(
        convex_hull(&flat),
        Err(Error::Degenerate { dimension: 2, .. })
    ));
    // Planar: parallel columns give a segment; a dual polytope needs 3 rows.
    assert!(matches!(
        velocity_polytope(&matrix(2, 3, &[1.0, 2.0, 0.0, 2.0, 4.0, 0.0]), &[1.0; 3]),
        Err(Error::Degenerate { dimension: 1, .. })
    ));
    assert!(matches!(
        dual_velocity_polytope(
            &DMatrix::identity(2, 2),
            &[1.0; 2],
            &DMatrix::identity(2, 2),
            &[1.0; 2]
        ),
        Err(Error::InvalidRows { .. })
    ));
    // Magnitudes whose products overflow or underflow f64: an error or a finite result.
    for s in [1e200, 1e-200, f64::MAX, f64::MIN_POSITIVE] {
        let j = matrix(
            3,
            4,
            &[1.0, 0.2, 0.0, 0.5, 0.0, 1.0, 0.3, -0.5, 0.1, 0.0, 1.0, 0.5],
        ) * s;
        let results = [
            velocity_polytope(&j, &[1.0; 4]),
            dual_velocity_polytope(&j, &[1.0; 4], &j, &[1.0; 4]),
        ];
        for p in results.into_iter().flatten() {
            assert!(p.volume.is_finite() && p.w_p.is_finite());
            assert!(p.vertices.iter().flatten().all(|x| x.is_finite()));
        }
    }
    // A flat arm makes the dual polytope flat.
    let flat_j = matrix(3, 3, &[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    assert!(matches!(
        dual_velocity_polytope(&DMatrix::identity(3, 3), &[1.0; 3], &flat_j, &[1.0; 3]),
        Err(Error::Degenerate { dimension: 2, .. })
    ));
}

/// A zero column or a zero bound contributes nothing (the generator is the zero segment);
/// repeated and parallel columns merge into one longer segment (Minkowski sum of parallel
/// segments), checked against the zonotope closed form.
#[test]
fn zero_and_parallel_columns_are_handled() {
    let j = matrix(
        3,
        4,
        &[1.0, 0.0, 0.2, 0.0, 0.0, 1.0, 0.1, 0.0, 0.3, 0.0, 1.0, 0.0],
    );
    let with_zero = velocity_polytope(&j, &[1.0; 4]).unwrap();
    let without = velocity_polytope(&j.columns(0, 3).into_owned(), &[1.0; 3]).unwrap();
    assert!(close(with_zero.volume, without.volume, 1e-12));
    assert_eq!(with_zero.vertices.len(), without.vertices.len());

    let j = matrix(
        3,
        5,
        &[
            1.0, 0.0, 0.2, -2.0, 1.0, 0.0, 1.0, 0.1, 0.0, 0.0, 0.3, 0.0, 1.0, -0.6, 0.3,
        ],
    );
    let qmax = [1.0, 0.5, 0.8, 0.3, 1.5];
    let p = velocity_polytope(&j, &qmax).unwrap();
    let expected = zonotope_volume(&generators(&j, &qmax));
    assert!(
        close(p.volume, expected, 1e-12),
        "{} vs {expected}",
        p.volume
    );
    check_mesh(&p);
}

/// Coplanar generators (several joint columns in one plane, as PA10's hexagon) give hexagonal
/// and larger zonogon facets; the cube-like grid hull has volume 1 and eight corners.
#[test]
fn coplanar_generators_and_grids() {
    // Four generators in the xy plane plus z: an extruded octagon, 16 corners.
    let j = matrix(
        3,
        5,
        &[
            1.0, 0.0, 0.6, -0.6, 0.0, 0.0, 1.0, 0.6, 0.6, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ],
    );
    let p = velocity_polytope(&j, &[1.0; 5]).unwrap();
    assert_eq!(p.vertices.len(), 16);
    let expected = zonotope_volume(&generators(&j, &[1.0; 5]));
    assert!(close(p.volume, expected, 1e-12));
    check_mesh(&p);

    // A 5×5×5 grid in the unit cube: only the 8 corners remain.
    let grid: Vec<[f64; 3]> = (0..125)
        .map(|i| {
            [
                (i % 5) as f64 / 4.0,
                (i / 5 % 5) as f64 / 4.0,
                (i / 25) as f64 / 4.0,
            ]
        })
        .collect();
    let h = convex_hull(&grid).unwrap();
    assert_eq!(h.vertices.len(), 8);
    assert!(close(h.volume, 1.0, 1e-12));
    check_mesh(&h);
}

/// Cone-cell index with the origin outside: w_p counts the cells' absolute volumes, so it
/// exceeds the volume (Kilic eq. 1.52 cells overlap when the origin is not inside).
#[test]
fn w_p_exceeds_volume_when_origin_outside() {
    let cube: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                2.0 + (i & 1) as f64,
                (i >> 1 & 1) as f64,
                (i >> 2 & 1) as f64,
            ]
        })
        .collect();
    let h = convex_hull(&cube).unwrap();
    assert!(close(h.volume, 1.0, 1e-12));
    assert!(h.w_p > h.volume + 1.0);
}

/// Two Magnum arms in one frame (the simulator's dual-arm case): the intersection is a
/// nonempty polytope no larger than either arm's, and contains the origin.
#[test]
fn magnum_dual_polytope_is_inside_both_arms() {
    let model = common::builtin("magnum");
    let qmax = model.max_velocities();
    let n = model.dof();
    let q1: Vec<f64> = (0..n).map(|i| 0.3 + 0.2 * i as f64).collect();
    let q2: Vec<f64> = (0..n).map(|i| -0.4 + 0.15 * i as f64).collect();
    let j1 = translational(&model, &q1);
    let j2 = translational(&model, &q2);
    let p1 = velocity_polytope(&j1, &qmax).unwrap();
    let p2 = velocity_polytope(&j2, &qmax).unwrap();
    let both = dual_velocity_polytope(&j1, &qmax, &j2, &qmax).unwrap();
    check_mesh(&both);
    assert!(both.volume > 0.0 && both.volume <= p1.volume.min(p2.volume));
    assert!(inside(&both, &Vector3::zeros(), 0.0));
    let tol = 1e-9 * scale_of(&p1);
    for v in &both.vertices {
        assert!(inside(&p1, &v3(v), tol) && inside(&p2, &v3(v), tol));
    }
}
