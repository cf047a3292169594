-- Reference operators (issue 30 item 1; docs/exercises.md "Benchmarks"): the trainees, by
-- name and group as the records keep them, whose finished attempts make each exercise's
-- benchmark. The instructor marks and unmarks them. Portable SQL, as 0001.

CREATE TABLE reference_operators (
    name TEXT NOT NULL,
    grp TEXT NOT NULL,
    marked_unix DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (name, grp)
);
