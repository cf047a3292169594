//! How `hydraulics::FOUR_BAR_DESIGNS` were found (issue 17 item 1, docs/physics.md): a random
//! search and hill climb over four-bar ("dog-bone") geometries with crank radius 1, minimizing
//! the lever's spread Ĵ_max/Ĵ_min over the joint's range ± 0.05 rad subject to
//! * the two circles (rocker about its pivot, dog-bone about the crank pin) intersecting with
//!   1 mm to spare, i.e. the linkage assembles everywhere;
//! * both transmission angles ≥ 20.5° (|sin| ≥ 0.35), away from the toggle positions;
//! * Ĵ > 0 (extending the cylinder raises the joint, as `HydraulicParams::magnum` assumes);
//! * extended cylinder ≤ 1.75 × retracted (a cylinder's dead length makes longer strokes
//!   impractical).
//!
//! The search is deterministic (seeded) and slow in a debug build, so it is ignored:
//! `cargo test --release -p seaarms-core --test four_bar_design -- --ignored --nocapture`
//! prints, for each range, the best design of three seeds; the committed designs are seed 1
//! (shoulder, 90°: seed 3 spreads 0.3 % less, but its lever is only 0.37 crank radii, so its
//! links would be 2.7× larger) and seed 2 (elbow 130°, pitch 115°: the least spread), rounded
//! to 4 decimals. The always-run
//! test checks that the committed designs meet the constraints with these figures.

use seaarms_core::hydraulics::{FOUR_BAR_DESIGNS, Linkage, four_bar_transmission};

/// Least transmission |sin|.
const MIN_TRANSMISSION: f64 = 0.35;
/// Largest extended/retracted cylinder length.
const MAX_LENGTH_RATIO: f64 = 1.75;
/// Margin past each end of the range (rad).
const MARGIN_RAD: f64 = 0.05;

/// A design vector: crank angle at the lower limit, rocker pivot x y, rocker, dog-bone,
/// cylinder pin x y, branch sign (as `FOUR_BAR_DESIGNS`), crank radius 1.
type Design = [f64; 8];

fn linkage(v: &Design) -> Linkage {
    Linkage::FourBar {
        crank_m: 1.0,
        crank_angle_rad: v[0],
        rocker_pivot_m: [v[1], v[2]],
        rocker_m: v[3],
        dogbone_m: v[4],
        cylinder_pin_m: [v[5], v[6]],
        branch: if v[7] > 0.0 { 1.0 } else { -1.0 },
    }
}

/// Ĵ_max/Ĵ_min over [−margin, span + margin] (q from the lower limit), or ∞ if a constraint
/// fails; with the least Ĵ and the cylinder length range.
fn spread(v: &Design, span_rad: f64) -> (f64, f64, f64, f64) {
    let link = linkage(v);
    const N: usize = 60;
    let fail = (f64::INFINITY, 0.0, 0.0, 0.0);
    let (mut jmin, mut jmax, mut xmin, mut xmax) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, 0.0f64);
    for i in 0..=N {
        let q = -MARGIN_RAD + (span_rad + 2.0 * MARGIN_RAD) * i as f64 / N as f64;
        let b = [(v[0] + q).cos(), (v[0] + q).sin()];
        let d = ((b[0] - v[1]).powi(2) + (b[1] - v[2]).powi(2)).sqrt();
        if d > v[3] + v[4] - 1e-3 || d < (v[3] - v[4]).abs() + 1e-3 {
            return fail;
        }
        let (x, j) = link.coordinate(q);
        let (t1, t2) = four_bar_transmission(&link, q).expect("four-bar");
        if t1.min(t2) < MIN_TRANSMISSION {
            return fail;
        }
        jmin = jmin.min(j);
        jmax = jmax.max(j);
        xmin = xmin.min(x);
        xmax = xmax.max(x);
    }
    if jmin <= 0.0 || xmax > MAX_LENGTH_RATIO * xmin {
        return fail;
    }
    (jmax / jmin, jmin, xmin, xmax)
}

/// The committed designs meet the constraints: spread ≤ 1.05 (so the joint speed varies by
/// less than ±2.5 % from the lever), with the figures docs/physics.md quotes.
#[test]
fn committed_designs_meet_the_constraints() {
    for (design, span) in FOUR_BAR_DESIGNS.iter().zip([90.0f64, 130.0, 115.0]) {
        let (ratio, jmin, xmin, xmax) = spread(design, span.to_radians());
        println!(
            "{span}°: Ĵ max/min {ratio:.4}, Ĵ min {jmin:.3}, x {xmin:.3}..{xmax:.3} (crank 1)"
        );
        assert!(ratio <= 1.05, "{span}°: {ratio}");
    }
}

/// A reproducible uniform number in [0, 1).
fn uniform(s: &mut u64) -> f64 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*s >> 11) as f64 / (1u64 << 53) as f64
}

fn search(span_rad: f64, mut seed: u64) -> (Design, f64) {
    let pi = std::f64::consts::PI;
    let mut best = ([0.0; 8], f64::INFINITY);
    for _ in 0..400_000 {
        let mut u = || uniform(&mut seed);
        let v = [
            (2.0 * u() - 1.0) * pi,
            (2.0 * u() - 1.0) * 3.0,
            (2.0 * u() - 1.0) * 3.0,
            0.3 + 2.5 * u(),
            0.3 + 3.0 * u(),
            (2.0 * u() - 1.0) * 6.0,
            (2.0 * u() - 1.0) * 6.0,
            2.0 * u() - 1.0,
        ];
        let c = spread(&v, span_rad).0;
        if c < best.1 {
            best = (v, c);
        }
    }
    // Hill climb: one coordinate at a time (not the branch), the step shrinking by 0.6 every
    // 20 000 tries.
    let mut step = 0.2;
    for it in 0..200_000 {
        let mut v = best.0;
        let k = (uniform(&mut seed) * 7.0) as usize;
        v[k] += (2.0 * uniform(&mut seed) - 1.0) * step;
        let c = spread(&v, span_rad).0;
        if c < best.1 {
            best = (v, c);
        }
        if it % 20_000 == 19_999 {
            step *= 0.6;
        }
    }
    best
}

#[test]
#[ignore = "the design search: slow in debug builds; run with --release --ignored"]
fn search_four_bar_designs() {
    for span in [90.0f64, 115.0, 130.0] {
        for seed in [1u64, 2, 3] {
            let (v, c) = search(span.to_radians(), seed);
            println!(
                "{span}° seed {seed}: Ĵ max/min {c:.4}, design {:?}",
                v.map(|x| (x * 1e4).round() / 1e4)
            );
        }
    }
}
