-- Instructor sign-off (issue 30 item 7; docs/operations.md "The logbook"): an assessor's
-- signature that a trainee, by name and group as the records keep them, is competent at an
-- exercise, with an optional note. One per trainee and exercise: signing again replaces it,
-- revoking deletes it. Portable SQL, as 0001.

CREATE TABLE signoffs (
    name TEXT NOT NULL,
    grp TEXT NOT NULL,
    exercise TEXT NOT NULL,
    signed_unix DOUBLE PRECISION NOT NULL,
    assessor TEXT NOT NULL,
    note TEXT NOT NULL,
    PRIMARY KEY (name, grp, exercise)
);
