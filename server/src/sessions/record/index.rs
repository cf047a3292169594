//! The session index (`DATA/sessions.jsonl`): its line types and how lines fold into one
//! record per session (the last line of a session wins).

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use serde::{Deserialize, Serialize};

/// One session of the index, folded over its lines.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SessionRecord {
    /// Id.
    pub id: String,
    /// Trainee label.
    #[serde(default)]
    pub label: String,
    /// Scenario.
    #[serde(default)]
    pub scenario: String,
    /// Unix seconds.
    #[serde(default)]
    pub created_unix: f64,
    /// Unix seconds, when ended.
    #[serde(default)]
    pub ended_unix: Option<f64>,
    /// Simulated seconds: at the end, or of the last row written while it ran.
    #[serde(default)]
    pub sim_seconds: Option<f64>,
    /// Why it ended.
    #[serde(default)]
    pub end_reason: Option<String>,
    /// Relief events over the session (so far, while it runs).
    #[serde(default)]
    pub overloads: Option<u64>,
    /// Part of the record could not be written.
    #[serde(default)]
    pub recording_failed: bool,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub(super) enum IndexLine {
    Created {
        id: String,
        label: String,
        scenario: String,
        created_unix: f64,
    },
    Progress {
        id: String,
        sim_seconds: f64,
        overloads: u64,
        #[serde(default)]
        recording_failed: bool,
    },
    Ended {
        id: String,
        ended_unix: f64,
        sim_seconds: f64,
        reason: String,
        overloads: u64,
        #[serde(default)]
        recording_failed: bool,
    },
    /// A whole folded record (written by compaction).
    Record(SessionRecord),
}

/// Reads and folds an index file (the last line of a session wins); unparsable lines (a
/// line cut by a crash) are skipped.
pub fn read_index(path: &Path) -> Vec<SessionRecord> {
    let Ok(file) = File::open(path) else {
        return Vec::new();
    };
    let mut order: Vec<String> = Vec::new();
    let mut by_id: HashMap<String, SessionRecord> = HashMap::new();
    for line in BufReader::new(file).lines().map_while(Result::ok) {
        let Ok(line) = serde_json::from_str::<IndexLine>(&line) else {
            continue;
        };
        match line {
            IndexLine::Created {
                id,
                label,
                scenario,
                created_unix,
            } => {
                if !by_id.contains_key(&id) {
                    order.push(id.clone());
                }
                by_id.insert(
                    id.clone(),
                    SessionRecord {
                        id,
                        label,
                        scenario,
                        created_unix,
                        ended_unix: None,
                        sim_seconds: None,
                        end_reason: None,
                        overloads: None,
                        recording_failed: false,
                    },
                );
            }
            IndexLine::Record(r) => {
                if !by_id.contains_key(&r.id) {
                    order.push(r.id.clone());
                }
                by_id.insert(r.id.clone(), r);
            }
            IndexLine::Progress {
                id,
                sim_seconds,
                overloads,
                recording_failed,
            } => {
                if let Some(r) = by_id.get_mut(&id) {
                    r.sim_seconds = Some(sim_seconds);
                    r.overloads = Some(overloads);
                    r.recording_failed |= recording_failed;
                }
            }
            IndexLine::Ended {
                id,
                ended_unix,
                sim_seconds,
                reason,
                overloads,
                recording_failed,
            } => {
                if let Some(r) = by_id.get_mut(&id) {
                    r.ended_unix = Some(ended_unix);
                    r.sim_seconds = Some(sim_seconds);
                    r.end_reason = Some(reason);
                    r.overloads = Some(overloads);
                    r.recording_failed |= recording_failed;
                }
            }
        }
    }
    order
        .into_iter()
        .filter_map(|id| by_id.remove(&id))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_index_line_of_a_session_wins() {
        let dir =
            std::env::temp_dir().join(format!("seaarms-index-{}", crate::sessions::random_hex(6)));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("sessions.jsonl");
        let lines = [
            r#"{"event":"created","id":"a","label":"x","scenario":"training","created_unix":1.0}"#,
            r#"{"event":"progress","id":"a","sim_seconds":3.5,"overloads":2}"#,
            r#"{"event":"progress","id":"a","sim_seconds":4.25,"overloads":3,"recording_failed":true}"#,
            r#"{"event":"created","id":"b","label":"","scenario":"training","created_unix":2.0}"#,
            r#"{"event":"ended","id":"b","ended_unix":9.0,"sim_seconds":7.0,"reason":"r","overloads":1}"#,
            r#"{"event":"progress","id":"b","sim_sec"#,
        ];
        std::fs::write(&path, lines.join("\n")).expect("write");
        let v = read_index(&path);
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].sim_seconds, Some(4.25));
        assert_eq!(v[0].overloads, Some(3));
        assert!(v[0].recording_failed);
        assert_eq!(v[0].ended_unix, None);
        assert_eq!(v[1].sim_seconds, Some(7.0));
        assert!(!v[1].recording_failed);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
