//! Velocity polytopes (Kilic §3.2). Filled in by the polytope work.
