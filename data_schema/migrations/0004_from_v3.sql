-- Migration from schema version 3 to 4:
--   sessions.session_uuid: a session's identity across files and machines,
--     so that files from several lab PCs pool without clashes. Sessions
--     stored before version 4 get a random (version 4) UUID here.
--   trials.end_reason: why a trial ended without an answer (skipped or
--     aborted); NULL for trials of version 3, whose reason is in the events.
--   frames.display_period_ns and frames.late: the runtime's display period
--     and whether the frame missed its display time; NULL and 0 for frames
--     of version 3, which recorded neither.
-- sessions and trials are rebuilt (their new columns precede the tables'
-- UNIQUE constraints, where ALTER TABLE cannot put them); the definitions are
-- schema.sql's, so a migrated file and a new file have the same
-- sqlite_master entries. legacy_alter_table keeps the other tables'
-- REFERENCES clauses naming sessions and trials while the old tables are
-- renamed aside (foreign keys are off during a migration, database.cpp).

PRAGMA legacy_alter_table = ON;
ALTER TABLE sessions RENAME TO v3_sessions;
ALTER TABLE trials RENAME TO v3_trials;

CREATE TABLE sessions (
  session_id INTEGER PRIMARY KEY,
  protocol_id INTEGER NOT NULL REFERENCES protocols(protocol_id),
  participant_id INTEGER NOT NULL REFERENCES participants(participant_id),
  session_number INTEGER NOT NULL CHECK (session_number >= 1),
  software_version TEXT NOT NULL,
  software_commit TEXT NOT NULL,
  backend TEXT NOT NULL CHECK (backend IN ('headless', 'desktop', 'xr', 'unknown')),
  renderer_device TEXT NOT NULL,
  renderer_driver TEXT NOT NULL,
  display_refresh_hz REAL CHECK (display_refresh_hz IS NULL OR display_refresh_hz > 0),
  seed INTEGER NOT NULL,
  table_calibration TEXT CHECK (table_calibration IS NULL OR json_valid(table_calibration)),
  status TEXT NOT NULL
    CHECK (status IN ('running', 'paused', 'completed', 'aborted', 'interrupted')),
  started_utc TEXT NOT NULL,
  ended_utc TEXT,
  session_uuid TEXT CHECK (session_uuid IS NULL OR (length(session_uuid) = 36 AND
    session_uuid GLOB '[0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f]-*')),
  UNIQUE (participant_id, session_number)
) STRICT;

-- A session's identity across files and machines (RFC 9562 UUID, lower case).
CREATE UNIQUE INDEX sessions_by_uuid ON sessions (session_uuid);

CREATE TABLE trials (
  trial_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  block_id INTEGER NOT NULL REFERENCES blocks(block_id),
  trial_index INTEGER NOT NULL CHECK (trial_index >= 0),
  trial_in_block INTEGER NOT NULL CHECK (trial_in_block >= 0),
  conditions TEXT NOT NULL CHECK (json_valid(conditions)),
  stimulus TEXT NOT NULL DEFAULT '{}' CHECK (json_valid(stimulus)),
  status TEXT NOT NULL DEFAULT 'pending'
    CHECK (status IN ('pending', 'running', 'completed', 'skipped', 'aborted')),
  attempt INTEGER NOT NULL DEFAULT 0 CHECK (attempt >= 0),
  onset_ns INTEGER,
  response_ns INTEGER,
  response TEXT,
  rt_ns INTEGER,
  response_device TEXT,
  completed_utc TEXT,
  end_reason TEXT,
  UNIQUE (session_id, trial_index)
) STRICT;

-- RFC 9562 §5.4: 122 random bits, version nibble 4, variant bits 10.
INSERT INTO sessions (session_id, protocol_id, participant_id, session_number, software_version, software_commit, backend, renderer_device, renderer_driver, display_refresh_hz, seed, table_calibration, status, started_utc, ended_utc, session_uuid)
  SELECT session_id, protocol_id, participant_id, session_number, software_version, software_commit, backend, renderer_device, renderer_driver, display_refresh_hz, seed, table_calibration, status, started_utc, ended_utc,
    lower(hex(randomblob(4))) || '-' || lower(hex(randomblob(2))) || '-4' ||
    substr(lower(hex(randomblob(2))), 2) || '-' || substr('89ab', 1 + (abs(random()) % 4), 1) ||
    substr(lower(hex(randomblob(2))), 2) || '-' || lower(hex(randomblob(6)))
  FROM v3_sessions;

INSERT INTO trials (trial_id, session_id, block_id, trial_index, trial_in_block, conditions, stimulus, status, attempt, onset_ns, response_ns, response, rt_ns, response_device, completed_utc)
  SELECT trial_id, session_id, block_id, trial_index, trial_in_block, conditions, stimulus, status, attempt, onset_ns, response_ns, response, rt_ns, response_device, completed_utc FROM v3_trials;

DROP TABLE v3_trials;
DROP TABLE v3_sessions;
PRAGMA legacy_alter_table = OFF;

ALTER TABLE frames ADD COLUMN display_period_ns INTEGER CHECK (display_period_ns IS NULL OR display_period_ns > 0);
ALTER TABLE frames ADD COLUMN late INTEGER NOT NULL DEFAULT 0 CHECK (late IN (0, 1));

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (4, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'),
          'sessions.session_uuid; trials.end_reason; frames.display_period_ns and late');

PRAGMA user_version = 4;
