//! Random ids, tokens and seeds (session, attempt and run ids; control tokens; attempt
//! seeds), from the operating system's entropy source.

use std::time::{SystemTime, UNIX_EPOCH};

/// A random hex string of `bytes` bytes (ids and tokens).
pub fn random_hex(bytes: usize) -> String {
    let mut buf = vec![0u8; bytes];
    // getrandom only fails when the OS has no entropy source at all; fall back to the clock
    // mixed with the address of the buffer so ids stay unique in that case.
    if getrandom::fill(&mut buf).is_err() {
        let seed = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        for (i, b) in buf.iter_mut().enumerate() {
            *b = (seed >> ((i % 16) * 8)) as u8 ^ (i as u8).wrapping_mul(151);
        }
    }
    buf.iter().map(|b| format!("{b:02x}")).collect()
}

/// A random seed for a session's attempts, below 2⁵³ so the page's JavaScript numbers hold
/// it exactly.
pub fn random_seed() -> u64 {
    u64::from_str_radix(&random_hex(8), 16).unwrap_or(0) >> 11
}
