-- Several replicas sharing one database (issue 18; docs/api.md "Replicas"). Portable SQL, as
-- 0001. A replica writes its own row and its own sessions' rows every heartbeat; any replica
-- declares one whose heartbeat is older than the timeout lost (lost_unix), marks its sessions
-- and running attempts interrupted and deletes its directory rows; a replica that stops
-- gracefully sets its own lost_unix (gone) and deletes its rows. In single-machine (SQLite)
-- mode both tables stay empty.

CREATE TABLE replicas (
    name TEXT PRIMARY KEY,
    started_unix DOUBLE PRECISION NOT NULL,
    heartbeat_unix DOUBLE PRECISION NOT NULL,
    live_sessions BIGINT NOT NULL,
    max_sessions BIGINT NOT NULL,
    draining BIGINT NOT NULL,
    lost_unix DOUBLE PRECISION
);

CREATE TABLE session_directory (
    id TEXT PRIMARY KEY,
    replica TEXT NOT NULL,
    updated_unix DOUBLE PRECISION NOT NULL,
    summary TEXT NOT NULL
);
CREATE INDEX session_directory_by_replica ON session_directory (replica);
