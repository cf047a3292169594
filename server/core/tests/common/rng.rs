//! A tiny deterministic xorshift generator for random test inputs.
#![allow(dead_code)]

/// xorshift64.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    /// Uniform in [0, 1).
    pub(crate) fn next(&mut self) -> f64 {
        let mut s = self.0;
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        self.0 = s;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [−a, a).
    pub(crate) fn sym(&mut self, a: f64) -> f64 {
        (2.0 * self.next() - 1.0) * a
    }
}
