//! Which ended records to delete: older than the retention age, then the oldest ended ones
//! until the records fit the size cap. Live sessions are never chosen, whatever their size.

use std::collections::HashSet;

use crate::db::SessionRecord;

/// Retention limits (0 turns a limit off).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Retention {
    /// Records of sessions that ended longer ago than this are deleted (days; 0 = kept).
    pub max_age_days: f64,
    /// The records (CSV + database rows of every session, live ones included) are kept below
    /// this many bytes by deleting the oldest ended ones (0 = no cap).
    pub max_bytes: u64,
}

/// When a record ended (interrupted ones: when they were created), for ordering and age.
fn ended_at(r: &SessionRecord) -> f64 {
    r.ended_unix.unwrap_or(r.created_unix)
}

/// The ids to delete, oldest first. `records` with their on-disk sizes (bytes); `live` are
/// ids the server is recording now; `now_unix` in seconds.
pub(super) fn select(
    records: &[(SessionRecord, u64)],
    live: &HashSet<String>,
    limits: Retention,
    now_unix: f64,
) -> Vec<String> {
    let mut ended: Vec<&(SessionRecord, u64)> = records
        .iter()
        .filter(|(r, _)| !live.contains(&r.id))
        .collect();
    ended.sort_by(|a, b| ended_at(&a.0).total_cmp(&ended_at(&b.0)));
    let mut total: u64 = records.iter().map(|(_, size)| size).sum();
    let mut out = Vec::new();
    for (r, size) in ended {
        let too_old =
            limits.max_age_days > 0.0 && now_unix - ended_at(r) > limits.max_age_days * 86_400.0;
        let too_big = limits.max_bytes > 0 && total > limits.max_bytes;
        if !(too_old || too_big) {
            // Sorted oldest first: a younger record is not too old either, and the total
            // already fits.
            break;
        }
        total = total.saturating_sub(*size);
        out.push(r.id.clone());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(id: &str, created: f64, ended: Option<f64>) -> SessionRecord {
        SessionRecord {
            id: id.into(),
            trainee: String::new(),
            group: String::new(),
            scenario: "training".into(),
            created_unix: created,
            ended_unix: ended,
            end_reason: None,
            sim_seconds: 0.0,
            overloads: 0,
            recording_failed: false,
        }
    }

    const DAY: f64 = 86_400.0;

    #[test]
    fn age_limit_deletes_only_old_ended_records() {
        let now = 100.0 * DAY;
        let records = vec![
            (rec("old", 10.0 * DAY, Some(10.0 * DAY + 60.0)), 10),
            (rec("interrupted-old", 20.0 * DAY, None), 10),
            (rec("recent", 95.0 * DAY, Some(95.0 * DAY)), 10),
            (rec("live-old", 1.0 * DAY, None), 10),
        ];
        let live: HashSet<String> = ["live-old".to_string()].into();
        let limits = Retention {
            max_age_days: 30.0,
            max_bytes: 0,
        };
        assert_eq!(
            select(&records, &live, limits, now),
            vec!["old".to_string(), "interrupted-old".to_string()]
        );
    }

    #[test]
    fn size_cap_deletes_oldest_ended_first_and_never_live() {
        let records = vec![
            (rec("b", 2.0, Some(20.0)), 300),
            (rec("a", 1.0, Some(10.0)), 300),
            (rec("live", 0.0, None), 5000),
            (rec("c", 3.0, Some(30.0)), 300),
        ];
        let live: HashSet<String> = ["live".to_string()].into();
        // 5900 bytes against a 5400 cap: the two oldest ended go (5900 → 5600 → 5300).
        let cap = Retention {
            max_age_days: 0.0,
            max_bytes: 5400,
        };
        assert_eq!(select(&records, &live, cap, 0.0), vec!["a", "b"]);
        // A cap below the live record alone: every ended record goes, the live one stays.
        let tiny = Retention {
            max_age_days: 0.0,
            max_bytes: 100,
        };
        assert_eq!(select(&records, &live, tiny, 0.0), vec!["a", "b", "c"]);
        // No limits: nothing.
        let none = Retention {
            max_age_days: 0.0,
            max_bytes: 0,
        };
        assert!(select(&records, &live, none, 1e12).is_empty());
    }
}
