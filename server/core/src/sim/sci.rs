//! Scientific notation with seven significant digits for the scenario CSV — the same text
//! as `format!("{x:.6e}")` (e.g. `-1.234568e-5`), several times faster: the standard
//! formatter's exact mode (Grisu with a Dragon4 fallback) dominated the runner's time when a
//! row of ~90 values is written every 10 ms of simulated time.
//!
//! Method: x = m·10^(e−6) with m = round(|x|/10^(e−6)) ∈ [10⁶, 10⁷). For |e − 6| ≤ 22 the
//! power of ten is exact in f64, so the scaled value carries one rounding (relative error
//! ≤ 2⁻⁵³, i.e. < 10⁻⁹ absolute at 10⁷); when it lies within 10⁻⁶ of a rounding tie the
//! decision is left to the standard formatter, as are non-finite values and magnitudes
//! outside 10⁻¹⁶ … 10²⁸. Zeros (±0) are written directly as the standard text.

/// 10⁰ … 10²², all exact in f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// |x| / 10^(e−6), or `None` when 10^|e−6| is not exact in f64.
fn scaled(a: f64, e: i32) -> Option<f64> {
    let k = e - 6;
    let p = *POW10.get(k.unsigned_abs() as usize)?;
    Some(if k >= 0 { a / p } else { a * p })
}

/// "00", "01", … "99": two digits per table lookup.
const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Appends `x` as `format!("{x:.6e}")` would, as UTF-8 bytes.
pub fn push_sci6(out: &mut Vec<u8>, x: f64) {
    push(out, x, false);
}

/// Appends `,` and then `x` as [`push_sci6`]: one CSV field.
pub fn push_sci6_field(out: &mut Vec<u8>, x: f64) {
    push(out, x, true);
}

#[inline(always)]
fn push(out: &mut Vec<u8>, x: f64, comma: bool) {
    // ",-d.dddddde-ddd" at most (15 bytes): assembled on the stack.
    let mut buf = [0u8; 16];
    let mut n = 0;
    if comma {
        buf[0] = b',';
        n = 1;
    }
    let Some((negative, m, e)) = digits(x) else {
        // Zeros (common in the CSV: forces while not holding, idle inputs) are written as the
        // standard text directly; the rest goes to the standard formatter.
        out.extend_from_slice(&buf[..n]);
        if x == 0.0 {
            let text: &[u8] = if x.is_sign_negative() {
                b"-0.000000e0"
            } else {
                b"0.000000e0"
            };
            out.extend_from_slice(text);
        } else {
            use std::io::Write;
            let _ = write!(out, "{x:.6e}");
        }
        return;
    };
    if negative {
        buf[n] = b'-';
        n += 1;
    }
    // d.dddddd: the leading digit, then three pairs.
    let m = m as usize;
    let (lead, rest) = (m / 1_000_000, m % 1_000_000);
    buf[n] = b'0' + lead as u8;
    buf[n + 1] = b'.';
    for (k, pair) in [rest / 10_000, rest / 100 % 100, rest % 100]
        .into_iter()
        .enumerate()
    {
        buf[n + 2 + 2 * k..n + 4 + 2 * k].copy_from_slice(&PAIRS[2 * pair..2 * pair + 2]);
    }
    buf[n + 8] = b'e';
    n += 9;
    if e < 0 {
        buf[n] = b'-';
        n += 1;
    }
    let a = e.unsigned_abs() as usize;
    if a >= 100 {
        buf[n] = b'0' + (a / 100) as u8;
        n += 1;
    }
    if a >= 10 {
        buf[n..n + 2].copy_from_slice(&PAIRS[2 * (a % 100)..2 * (a % 100) + 2]);
        n += 2;
    } else {
        buf[n] = b'0' + a as u8;
        n += 1;
    }
    // All 16 bytes (a fixed-size copy, no call), then the unused tail cut off.
    let len = out.len();
    out.extend_from_slice(&buf);
    out.truncate(len + n);
}

/// (sign, 7-digit mantissa, exponent), or `None` where the standard formatter decides.
fn digits(x: f64) -> Option<(bool, u64, i32)> {
    if x == 0.0 || !x.is_finite() {
        return None;
    }
    let a = x.abs();
    // ⌊log₁₀ a⌋ from the binary exponent (within one; corrected below). Subnormals are
    // below the exact-power range anyway.
    let e2 = ((a.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    // ⌊e2·log₁₀2⌋ in integers (78913/2¹⁸ ≈ log₁₀2, as in Ryū; an arithmetic shift floors).
    let mut e = (e2 * 78_913) >> 18;
    let mut s = scaled(a, e)?;
    // log10 can be off by one next to a power of ten.
    if s < 1e6 {
        e -= 1;
        s = scaled(a, e)?;
    } else if s >= 1e7 {
        e += 1;
        s = scaled(a, e)?;
    }
    if !(1e6..1e7).contains(&s) {
        return None;
    }
    // s ∈ [10⁶, 10⁷): truncation is ⌊s⌋ and s + 0.5 is exact (ulp(s) ≤ 2⁻²⁹), so these are
    // floor and round-half-up without library calls.
    // In i64 (s < 10⁷ fits): one conversion instruction each way, where u64 conversions
    // take branchy sequences for values ≥ 2⁶³.
    let whole = s as i64;
    if (s - whole as f64 - 0.5).abs() < 1e-6 {
        return None;
    }
    let mut m = (s + 0.5) as i64 as u64;
    if m == 10_000_000 {
        m = 1_000_000;
        e += 1;
    }
    Some((x < 0.0, m, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ours(x: f64) -> String {
        let mut s = Vec::new();
        push_sci6(&mut s, x);
        String::from_utf8(s).expect("ASCII")
    }

    /// Identical text to the standard library's `{:.6e}` (the reference) over random values
    /// of every magnitude and sign, exact ties, powers of ten and the special values.
    #[test]
    fn matches_the_standard_formatter() {
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..200_000 {
            let bits = next();
            // Uniform mantissa, exponent spread over 10⁻³⁰⁰ … 10³⁰⁰.
            let mant = (bits >> 12) as f64 / (1u64 << 52) as f64 + 1.0;
            let exp = ((next() % 2000) as i32 - 1000) as f64 * 0.3;
            let x = mant * 2f64.powf(exp) * if bits & 1 == 0 { 1.0 } else { -1.0 };
            assert_eq!(ours(x), format!("{x:.6e}"), "{x:e}");
        }
        for x in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-5,
            9.9999995,
            9.9999994999,
            1.0000005,
            1234567.5,
            0.1,
            0.3,
            6.89e6,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            f64::MAX,
            5e-324,
        ] {
            assert_eq!(ours(x), format!("{x:.6e}"), "{x:e}");
        }
        for k in -30..30 {
            let x = 10f64.powi(k);
            assert_eq!(ours(x), format!("{x:.6e}"), "10^{k}");
            assert_eq!(ours(-x * 1.5), format!("{:.6e}", -x * 1.5), "1.5·10^{k}");
        }
    }
}
