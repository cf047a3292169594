//! The benchmark pass lines live attempts start with (issue 30 item 1): for each exercise
//! whose pass marks are `benchmark` (`pass.marks` in its file), the reference operators'
//! lines as the database last gave them ([`crate::api::progress::refresh_pass_board`], every
//! [`REFRESH_INTERVAL`] and at once when the reference operators change). An attempt copies
//! its exercise's lines at its start into its record ([`crate::replay::Init`]), so its verdict
//! and its replay's never depend on a later benchmark.

use std::collections::HashMap;
use std::sync::RwLock;
use std::time::Duration;

use seaarms_core::exercise::proficiency::PassLines;

/// How often the lines are read again from the database (a reference operator's new attempt
/// moves the benchmark within this long).
pub const REFRESH_INTERVAL: Duration = Duration::from_secs(10);

/// Each benchmarked exercise's current pass lines (absent: the benchmark does not apply yet,
/// or the exercise's marks are fixed).
#[derive(Debug, Default)]
pub struct PassBoard {
    lines: RwLock<HashMap<String, PassLines>>,
}

impl PassBoard {
    /// `exercise`'s lines now.
    pub fn get(&self, exercise: &str) -> Option<PassLines> {
        let map = self.lines.read().unwrap_or_else(|e| e.into_inner());
        map.get(exercise).cloned()
    }

    /// Sets (or, with None, clears) `exercise`'s lines.
    pub fn set(&self, exercise: &str, lines: Option<PassLines>) {
        let mut map = self.lines.write().unwrap_or_else(|e| e.into_inner());
        match lines {
            Some(l) => map.insert(exercise.to_string(), l),
            None => map.remove(exercise),
        };
    }
}
