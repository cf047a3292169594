-- Practice attempts (issue 30 item 5, "take over from here"): an attempt started from another
-- attempt's replayed state records that attempt and the time (s since its start). Such an
-- attempt is practice: the learning curves, proficiency, benchmarks, the logbook's counts and
-- the xAPI outbox leave it out. NULL for every other attempt. Portable SQL, as 0001.

ALTER TABLE attempts ADD COLUMN taken_over_from TEXT;
ALTER TABLE attempts ADD COLUMN taken_over_t DOUBLE PRECISION;
