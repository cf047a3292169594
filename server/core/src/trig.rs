//! sin and cos together for the 1 kHz step, where they are called a dozen times per step on
//! joint angles of a few radians.
//!
//! The C library's `sincos` handles every double (Payne–Hanek reduction for huge
//! arguments) behind a call. [`sin_cos`] handles |x| < 2¹⁹·π/2 inline: a two-constant
//! Cody–Waite reduction to r ∈ [−π/4, π/4] and the minimax polynomials of fdlibm's kernels
//! (`k_sin.c`, `k_cos.c`, Sun Microsystems 1993; coefficients and error bound < 1 ulp on
//! [−π/4, π/4] from there). Other arguments (and NaN, ±∞) go to the library. Plain
//! arithmetic only (no fused multiply–add), so the result is the same on every x86-64 and
//! the simulation stays deterministic.

// The constants are written with the digits fdlibm publishes (more than an f64 holds), so
// they can be checked against the source.
#![allow(clippy::excessive_precision)]

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// π/2 split as `PIO2_HI + PIO2_LO` with `PIO2_HI` holding the first 33 bits, so that
/// k·`PIO2_HI` is exact for |k| < 2²⁰ (fdlibm `pio2_1`, `pio2_1t`).
const PIO2_HI: f64 = 1.570_796_326_734_125_614_17e+00;
const PIO2_LO: f64 = 6.077_100_506_506_192_249_32e-11;
/// Largest |x| handled inline: the quadrant k stays below 2¹⁹, where k·`PIO2_HI` is exact and
/// the reduction error k·|π/2 − `PIO2_HI` − `PIO2_LO`| (< 2¹⁹·2⁻⁹⁹) is far below an ulp of r.
const INLINE_LIMIT: f64 = 823_549.6;
/// 1.5·2⁵²: adding and subtracting it rounds a double of magnitude < 2⁵¹ to the nearest
/// integer (ties to even) in the current rounding mode, without a library call.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

const S1: f64 = -1.666_666_666_666_663_243_48e-01;
const S2: f64 = 8.333_333_333_322_489_461_24e-03;
const S3: f64 = -1.984_126_982_985_794_931_34e-04;
const S4: f64 = 2.755_731_370_707_006_767_89e-06;
const S5: f64 = -2.505_076_025_340_686_341_95e-08;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-02;
const C2: f64 = -1.388_888_888_887_410_957_49e-03;
const C3: f64 = 2.480_158_728_947_672_941_78e-05;
const C4: f64 = -2.755_731_435_139_066_330_35e-07;
const C5: f64 = 2.087_572_321_298_174_827_90e-09;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// (sin x, cos x), within 1 ulp of the exact values for |x| < 823 549 (about 2¹⁹·π/2);
/// larger, infinite and NaN arguments go to the standard library.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    // NaN fails `<` and goes to the library too.
    let inline = x.abs() < INLINE_LIMIT;
    if !inline {
        return x.sin_cos();
    }
    if x == 0.0 {
        // ±0: keeps the sign of zero, as the library does.
        return (x, 1.0);
    }
    // Nearest multiple k of π/2, and r = x − k·π/2 in two exact-product steps.
    let k = (x * core::f64::consts::FRAC_2_PI + ROUND_MAGIC) - ROUND_MAGIC;
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let (s, c) = kernel(r);
    match (k as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// The unit quaternion of the rotation by |v| about v/|v| (the exponential map, as
/// nalgebra's `UnitQuaternion::from_scaled_axis`: (cos ½|v|, sin ½|v|·v/|v|)), with
/// [`sin_cos`]; the identity for v = 0.
#[inline]
pub fn quaternion_from_scaled_axis(v: &Vector3<f64>) -> UnitQuaternion<f64> {
    let half = v * 0.5;
    let n = half.norm();
    if n == 0.0 {
        return UnitQuaternion::identity();
    }
    let (s, c) = sin_cos(n);
    UnitQuaternion::new_unchecked(Quaternion::from_parts(c, half * (s / n)))
}

/// fdlibm `s_atan.c` odd/even coefficients aT[0..=10] of atan(x) = x − x·(s₁ + s₂) for
/// |x| < 7/16 (error < 1 ulp there).
const AT: [f64; 11] = [
    3.333_333_333_333_293_180_27e-01,
    -1.999_999_999_987_648_324_76e-01,
    1.428_571_427_250_346_637_11e-01,
    -1.111_111_040_546_235_578_80e-01,
    9.090_887_133_436_506_561_96e-02,
    -7.691_876_205_044_829_994_95e-02,
    6.661_073_137_387_531_206_69e-02,
    -5.833_570_133_790_573_486_45e-02,
    4.976_877_994_615_932_360_17e-02,
    -3.653_157_274_421_691_552_70e-02,
    1.628_582_011_536_578_236_23e-02,
];

/// atan2(y, x) for y ≥ 0, x > 0 (the first quadrant), as the angle of a rotation error:
/// there y ≪ x, and t = y/x < 7/16 takes fdlibm's atan polynomial inline (at most 1 ulp from
/// atan(t), plus the half ulp of the quotient). Other arguments go to the library.
#[inline]
pub fn atan2_first_quadrant(y: f64, x: f64) -> f64 {
    // NaN fails the comparison and goes to the library too.
    if !(y >= 0.0 && x > 0.0 && y <= 0.4375 * x && x < f64::INFINITY) {
        return y.atan2(x);
    }
    let t = y / x;
    let z = t * t;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    t - t * (s1 + s2)
}

/// sin and cos of r ∈ [−π/4, π/4] (fdlibm `__kernel_sin`, `__kernel_cos` with no tail).
#[inline(always)]
fn kernel(r: f64) -> (f64, f64) {
    let z = r * r;
    let v = z * r;
    let ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let sin = r + v * (S1 + z * ps);
    let pc = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    // 1 − z/2 + z·pc, summed so that the rounding of 1 − z/2 is recovered (fdlibm).
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cos = w + (((1.0 - w) - hz) + z * pc);
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reproducible uniform numbers in [0, 1) from `seed` (a 64-bit LCG).
    fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Units in the last place between `a` and the reference `b`.
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let ulp = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
        (a - b).abs() / ulp
    }

    /// Against the C library's correctly rounded-in-practice `sin`/`cos` (glibc, < 1 ulp)
    /// over joint-angle ranges, quadrant boundaries and large arguments: at most 1 ulp apart
    /// (each within 1 ulp of the exact value, fdlibm's bound), and the identity
    /// sin² + cos² = 1 to 2 ulp.
    #[test]
    fn agrees_with_the_library() {
        let mut uniform = lcg(12_345);
        let mut xs: Vec<f64> = (0..200_000).map(|_| (uniform() - 0.5) * 40.0).collect();
        xs.extend((0..20_000).map(|_| (uniform() - 0.5) * 2.0e6));
        xs.extend((0..20_000).map(|_| (uniform() - 0.5) * 1e-6));
        for k in -40..=40 {
            let c = k as f64 * core::f64::consts::FRAC_PI_2;
            for d in [-1e-9, -1e-15, 0.0, 1e-15, 1e-9, 0.785, -0.785] {
                xs.push(c + d);
            }
        }
        xs.extend([
            0.0,
            -0.0,
            1e-300,
            f64::MIN_POSITIVE,
            INLINE_LIMIT,
            -INLINE_LIMIT,
        ]);
        let mut worst: f64 = 0.0;
        for &x in &xs {
            let (s, c) = sin_cos(x);
            let (s_ref, c_ref) = x.sin_cos();
            // Near a zero of sin or cos, compare against the size of the other (absolute).
            let es = ulps(s, s_ref).min((s - s_ref).abs() / f64::EPSILON);
            let ec = ulps(c, c_ref).min((c - c_ref).abs() / f64::EPSILON);
            worst = worst.max(es).max(ec);
            assert!(
                es <= 1.0 && ec <= 1.0,
                "x = {x:e}: ({s:e}, {c:e}) vs ({s_ref:e}, {c_ref:e})"
            );
            assert!(
                (s * s + c * c - 1.0).abs() <= 2.0 * f64::EPSILON,
                "x = {x:e}"
            );
        }
        assert!(worst > 0.0, "the comparison measured something");
    }

    /// The quaternion equals nalgebra's exponential map to round-off, from tiny to large
    /// rotation vectors, and is the identity at zero.
    #[test]
    fn quaternion_matches_nalgebra() {
        assert_eq!(
            quaternion_from_scaled_axis(&Vector3::zeros()),
            UnitQuaternion::identity()
        );
        for k in 0..2000 {
            let t = k as f64 * 0.37;
            let scale = 10f64.powi(k % 12 - 9);
            let v = Vector3::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin() - 0.2) * scale;
            let ours = quaternion_from_scaled_axis(&v);
            let theirs = UnitQuaternion::from_scaled_axis(v);
            assert!(
                (ours.coords - theirs.coords).norm() < 4.0 * f64::EPSILON,
                "{v}"
            );
            assert!((ours.norm() - 1.0).abs() < 4.0 * f64::EPSILON);
        }
    }

    /// atan2 in the first quadrant against the C library's (glibc, < 1 ulp): at most 2 ulp
    /// apart over ratios y/x from 10⁻¹² to 1 (across the 7/16 switch), and the library's own
    /// value for the special cases (10⁻³⁰⁰, subnormal-sized, zero, infinite, NaN, y < 0).
    #[test]
    fn atan2_agrees_with_the_library() {
        let mut uniform = lcg(777);
        let mut worst: f64 = 0.0;
        let mut inline = 0;
        for k in 0..200_000 {
            let x = 1e-3 + uniform() * 10.0;
            // Ratios spread over many decades, and uniformly over [0, 1].
            let ratio = if k % 2 == 0 {
                10f64.powf(-12.0 * uniform())
            } else {
                uniform()
            };
            let y = x * ratio;
            let ours = atan2_first_quadrant(y, x);
            let e = ulps(ours, y.atan2(x));
            worst = worst.max(e);
            inline += usize::from(y <= 0.4375 * x);
            assert!(e <= 2.0, "atan2({y:e}, {x:e}) = {ours:e}, {e} ulp");
        }
        assert!(
            inline > 100_000 && worst > 0.0,
            "the inline branch was measured"
        );
        for (y, x) in [
            (0.0, 1.0),
            (1e-300, 1.0),
            (f64::MIN_POSITIVE, 3.0),
            (1.0, 0.0),
            (0.0, 0.0),
            (1.0, f64::INFINITY),
            (f64::NAN, 1.0),
            (-1.0, 2.0),
        ] {
            let (ours, lib) = (atan2_first_quadrant(y, x), y.atan2(x));
            assert!(ours == lib || (ours.is_nan() && lib.is_nan()), "({y}, {x})");
        }
    }

    /// Special values go to the library: NaN stays NaN, ±∞ give NaN, signs of zero kept.
    #[test]
    fn special_values() {
        assert!(sin_cos(f64::NAN).0.is_nan());
        assert!(sin_cos(f64::INFINITY).1.is_nan());
        assert!(sin_cos(f64::NEG_INFINITY).0.is_nan());
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert!(sin_cos(-0.0).0.is_sign_negative());
        assert_eq!(sin_cos(1e30), 1e30f64.sin_cos());
    }
}
