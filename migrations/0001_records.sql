-- Training records (issue 16). Portable SQL for SQLite and PostgreSQL: TEXT, BIGINT,
-- DOUBLE PRECISION, BYTEA (SQLite accepts any type name). Ids are the server's hex ids.
-- Times are Unix seconds; JSON is stored as TEXT.

CREATE TABLE trainees (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    grp TEXT NOT NULL,
    created_unix DOUBLE PRECISION NOT NULL,
    UNIQUE (name, grp)
);

CREATE TABLE sessions (
    id TEXT PRIMARY KEY,
    trainee_id TEXT,
    label TEXT NOT NULL,
    grp TEXT NOT NULL,
    scenario TEXT NOT NULL,
    created_unix DOUBLE PRECISION NOT NULL,
    ended_unix DOUBLE PRECISION,
    end_reason TEXT,
    sim_seconds DOUBLE PRECISION NOT NULL,
    overloads BIGINT NOT NULL,
    recording TEXT NOT NULL,
    token_sha256 TEXT NOT NULL
);
CREATE INDEX sessions_by_trainee ON sessions (trainee_id);
CREATE INDEX sessions_by_name ON sessions (label, grp);
CREATE INDEX sessions_by_created ON sessions (created_unix);

CREATE TABLE attempts (
    id TEXT PRIMARY KEY,
    session_id TEXT NOT NULL,
    scenario TEXT NOT NULL,
    exercise TEXT,
    exercise_version TEXT,
    sim_version TEXT NOT NULL,
    started_unix DOUBLE PRECISION NOT NULL,
    ended_unix DOUBLE PRECISION,
    sim_seconds DOUBLE PRECISION NOT NULL,
    outcome TEXT,
    score DOUBLE PRECISION,
    assessment TEXT,
    init TEXT NOT NULL
);
CREATE INDEX attempts_by_session ON attempts (session_id, started_unix);
CREATE INDEX attempts_by_exercise ON attempts (exercise, started_unix);
CREATE INDEX attempts_by_started ON attempts (started_unix);

CREATE TABLE attempt_inputs (
    attempt_id TEXT NOT NULL,
    seq BIGINT NOT NULL,
    data BYTEA NOT NULL,
    PRIMARY KEY (attempt_id, seq)
);

CREATE TABLE events (
    session_id TEXT NOT NULL,
    seq BIGINT NOT NULL,
    attempt_id TEXT,
    t DOUBLE PRECISION NOT NULL,
    unix DOUBLE PRECISION NOT NULL,
    kind TEXT NOT NULL,
    actor TEXT,
    detail TEXT NOT NULL,
    PRIMARY KEY (session_id, seq)
);
CREATE INDEX events_by_attempt ON events (attempt_id, t);
