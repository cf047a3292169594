-- The xAPI outbox (issue 30 item 6; docs/xapi.md). Portable SQL, as 0001. When
-- `--xapi-endpoint` is set, the recorder adds a row here in the same transaction that stores a
-- finished exercise attempt (outcome passed or failed) of a named trainee, so only stored
-- results are sent and none is lost while the Learning Record Store is down. The sender
-- builds the attempt's statements from the stored rows, claims a due row (next_unix moved
-- forward: another replica does not take it meanwhile), posts them and deletes the row; a
-- failed try moves next_unix by the back-off; a statement the LRS refuses for good keeps its
-- row with rejected set (not retried).

CREATE TABLE xapi_outbox (
    attempt_id TEXT PRIMARY KEY,
    queued_unix DOUBLE PRECISION NOT NULL,
    tries BIGINT NOT NULL,
    next_unix DOUBLE PRECISION NOT NULL,
    last_error TEXT,
    rejected BIGINT NOT NULL
);
CREATE INDEX xapi_outbox_due ON xapi_outbox (rejected, next_unix);
