-- Instructor unlocks (issue 30 item 4; docs/exercises.md "Progression"): an exercise opened
-- for a trainee, by name and group as the records keep them, whatever its `requires`. One per
-- trainee and exercise; locking again deletes it. Portable SQL, as 0001.

CREATE TABLE unlocks (
    name TEXT NOT NULL,
    grp TEXT NOT NULL,
    exercise TEXT NOT NULL,
    unlocked_unix DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (name, grp, exercise)
);
