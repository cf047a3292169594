//! Progression (issue 30 item 4): an exercise may require proficiency in earlier ones
//! ([`ExerciseSpec::requires`]).
//!
//! * [`check_requires`]: the set of exercise files as a whole — every required id names an
//!   exercise of the set, and no exercise requires itself through a chain (a cycle would lock
//!   every exercise on it for ever).
//! * [`missing`]: what still locks an exercise for one trainee, from their state on each
//!   required exercise.
//!
//! A required exercise counts once the trainee *has been* proficient in it:
//! [`ProficiencyState::Proficient`] or [`ProficiencyState::Relapsed`]. A relapse is a signal
//! for the instructor and for practice on that exercise; it does not re-lock the later
//! exercises the trainee already opened (docs/exercises.md "Progression").

use std::collections::BTreeMap;

use serde::Serialize;

use super::ExerciseSpec;
use super::proficiency::ProficiencyState;
use crate::Error;

/// Whether a trainee in state `s` on a required exercise has met the requirement: they are,
/// or were, proficient in it.
pub fn meets(s: ProficiencyState) -> bool {
    matches!(s, ProficiencyState::Proficient | ProficiencyState::Relapsed)
}

/// One requirement a trainee has not met yet.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Missing {
    /// The required exercise's id.
    pub exercise: String,
    /// The trainee's state in it.
    pub state: ProficiencyState,
}

/// The requirements of `spec` that a trainee has not met, in the file's order; empty when the
/// exercise is open to them. `state_of` gives the trainee's state on an exercise by id.
pub fn missing(spec: &ExerciseSpec, state_of: impl Fn(&str) -> ProficiencyState) -> Vec<Missing> {
    spec.requires
        .iter()
        .map(|id| Missing {
            exercise: id.clone(),
            state: state_of(id),
        })
        .filter(|m| !meets(m.state))
        .collect()
}

/// Checks the requirements of a whole set of exercises: each required id is an exercise of
/// the set, listed once, and the requirements form no cycle (the error names it, e.g.
/// `a → b → a`).
pub fn check_requires<'a>(specs: impl IntoIterator<Item = &'a ExerciseSpec>) -> Result<(), Error> {
    let by_id: BTreeMap<&str, &ExerciseSpec> =
        specs.into_iter().map(|s| (s.id.as_str(), s)).collect();
    let bad = |id: &str, reason: String| {
        Err(Error::InvalidParameter {
            what: "exercise",
            reason: format!("{id}: {reason}"),
        })
    };
    for (id, spec) in &by_id {
        for (i, r) in spec.requires.iter().enumerate() {
            if !by_id.contains_key(r.as_str()) {
                return bad(id, format!("requires unknown exercise `{r}`"));
            }
            if spec.requires[..i].contains(r) {
                return bad(id, format!("requires `{r}` twice"));
            }
        }
    }
    // Depth-first search with the path on a stack: an edge back into the path is a cycle.
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        OnPath,
        Done,
    }
    let mut mark: BTreeMap<&str, Mark> = by_id.keys().map(|id| (*id, Mark::New)).collect();
    for start in by_id.keys() {
        if mark[start] != Mark::New {
            continue;
        }
        // (exercise, index of the next requirement to follow)
        let mut path: Vec<(&str, usize)> = vec![(start, 0)];
        mark.insert(start, Mark::OnPath);
        while let Some((id, next)) = path.last().copied() {
            let requires = &by_id[id].requires;
            if let Some(r) = requires.get(next) {
                if let Some(top) = path.last_mut() {
                    top.1 += 1;
                }
                match mark[r.as_str()] {
                    Mark::New => {
                        mark.insert(r.as_str(), Mark::OnPath);
                        path.push((r.as_str(), 0));
                    }
                    Mark::OnPath => {
                        let from = path.iter().position(|(p, _)| *p == r.as_str()).unwrap_or(0);
                        let mut cycle: Vec<&str> = path[from..].iter().map(|(p, _)| *p).collect();
                        cycle.push(r.as_str());
                        return bad(
                            cycle[0],
                            format!("`requires` makes a cycle: {}", cycle.join(" → ")),
                        );
                    }
                    Mark::Done => {}
                }
            } else {
                mark.insert(id, Mark::Done);
                path.pop();
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(id: &str, requires: &[&str]) -> ExerciseSpec {
        let mut s: ExerciseSpec = serde_json::from_str(
            r#"{"id":"x","version":1,"title":"t","goal":"g","skills":[],
            "control":{"mode":"joint","arm":"left"},
            "steps":[{"id":"a","text":"a","done_when":{"kind":"released"}}],
            "time_limit_s":100,"pass":{"min_score":50,"limits":[]},
            "scoring":[],"autopilot":[]}"#,
        )
        .expect("spec");
        s.id = id.to_string();
        s.requires = requires.iter().map(|r| r.to_string()).collect();
        s
    }

    fn reason(r: Result<(), Error>) -> String {
        match r {
            Err(Error::InvalidParameter { reason, .. }) => reason,
            other => panic!("expected a rejection, got {other:?}"),
        }
    }

    /// A file without `requires` requires nothing (the field's default).
    #[test]
    fn requires_defaults_to_nothing() {
        assert!(spec("a", &[]).requires.is_empty());
    }

    /// A chain and a diamond (b and c both require a; d requires both) are accepted.
    #[test]
    fn chains_and_diamonds_pass() {
        let set = [
            spec("a", &[]),
            spec("b", &["a"]),
            spec("c", &["a"]),
            spec("d", &["b", "c"]),
        ];
        assert_eq!(check_requires(&set), Ok(()));
    }

    /// An id that names no exercise is rejected, naming both.
    #[test]
    fn unknown_ids_are_rejected() {
        let set = [spec("a", &[]), spec("b", &["a", "nope"])];
        assert_eq!(
            reason(check_requires(&set)),
            "b: requires unknown exercise `nope`"
        );
    }

    /// A requirement listed twice is rejected.
    #[test]
    fn duplicates_are_rejected() {
        let set = [spec("a", &[]), spec("b", &["a", "a"])];
        assert_eq!(reason(check_requires(&set)), "b: requires `a` twice");
    }

    /// Cycles are rejected, naming the cycle: through three exercises, and of one exercise
    /// on itself.
    #[test]
    fn cycles_are_rejected() {
        let set = [
            spec("a", &["c"]),
            spec("b", &["a"]),
            spec("c", &["b"]),
            spec("d", &[]),
        ];
        assert_eq!(
            reason(check_requires(&set)),
            "a: `requires` makes a cycle: a → c → b → a"
        );
        let set = [spec("a", &["a"])];
        assert_eq!(
            reason(check_requires(&set)),
            "a: `requires` makes a cycle: a → a"
        );
    }

    /// What locks an exercise: the requirements not proficient and never were; a relapse
    /// keeps it open.
    #[test]
    fn missing_lists_unmet_requirements() {
        let d = spec("d", &["a", "b", "c"]);
        let state = |id: &str| match id {
            "a" => ProficiencyState::Proficient,
            "b" => ProficiencyState::Relapsed,
            "c" => ProficiencyState::Practising,
            _ => ProficiencyState::NotStarted,
        };
        assert_eq!(
            missing(&d, state),
            vec![Missing {
                exercise: "c".into(),
                state: ProficiencyState::Practising
            }]
        );
        assert!(missing(&spec("a", &[]), |_| ProficiencyState::NotStarted).is_empty());
    }
}
