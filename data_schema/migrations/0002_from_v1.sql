-- Migration from schema version 1 to 2. Runs inside one transaction with
-- foreign keys off (the program checks PRAGMA foreign_key_check before it
-- commits). Every v1 table is renamed, the v2 tables are created with exactly
-- the DDL of schema.sql at version 2 (so a migrated file and a new file have
-- identical sqlite_master entries), the rows are copied, and the v1 tables are
-- dropped. Values v1 did not record become 'unknown' or NULL, never invented.

ALTER TABLE trials RENAME TO v1_trials;
ALTER TABLE events RENAME TO v1_events;
ALTER TABLE sessions RENAME TO v1_sessions;
ALTER TABLE participants RENAME TO v1_participants;
ALTER TABLE protocols RENAME TO v1_protocols;

CREATE TABLE schema_migrations (
  version INTEGER PRIMARY KEY,
  applied_utc TEXT NOT NULL,
  note TEXT NOT NULL
) STRICT;

CREATE TABLE protocols (
  protocol_id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  sha256 TEXT NOT NULL UNIQUE CHECK (length(sha256) = 64),
  text TEXT NOT NULL,
  source_path TEXT
) STRICT;

CREATE TABLE participants (
  participant_id INTEGER PRIMARY KEY,
  pseudonym TEXT NOT NULL UNIQUE CHECK (length(pseudonym) > 0),
  ipd_m REAL CHECK (ipd_m IS NULL OR (ipd_m > 0.04 AND ipd_m < 0.09)),
  dominant_eye TEXT NOT NULL DEFAULT 'unknown'
    CHECK (dominant_eye IN ('left', 'right', 'unknown')),
  created_utc TEXT NOT NULL
) STRICT;

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
  UNIQUE (participant_id, session_number)
) STRICT;

CREATE TABLE blocks (
  block_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  block_index INTEGER NOT NULL CHECK (block_index >= 0),
  name TEXT NOT NULL,
  is_practice INTEGER NOT NULL DEFAULT 0 CHECK (is_practice IN (0, 1)),
  settings TEXT NOT NULL DEFAULT '{}' CHECK (json_valid(settings)),
  UNIQUE (session_id, block_index)
) STRICT;

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
  UNIQUE (session_id, trial_index)
) STRICT;

CREATE TABLE staircase_steps (
  step_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  staircase TEXT NOT NULL,
  step_index INTEGER NOT NULL CHECK (step_index >= 0),
  trial_id INTEGER REFERENCES trials(trial_id),
  intensity REAL NOT NULL,
  response_correct INTEGER CHECK (response_correct IS NULL OR response_correct IN (0, 1)),
  is_reversal INTEGER NOT NULL DEFAULT 0 CHECK (is_reversal IN (0, 1)),
  next_intensity REAL,
  UNIQUE (session_id, staircase, step_index)
) STRICT;

CREATE TABLE tracking_samples (
  sample_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  frame_index INTEGER NOT NULL,
  device TEXT NOT NULL CHECK (device IN ('head', 'left_hand', 'right_hand', 'other')),
  t_ns INTEGER NOT NULL,
  lab_px_m REAL NOT NULL,
  lab_py_m REAL NOT NULL,
  lab_pz_m REAL NOT NULL,
  lab_qx REAL NOT NULL,
  lab_qy REAL NOT NULL,
  lab_qz REAL NOT NULL,
  lab_qw REAL NOT NULL,
  position_valid INTEGER NOT NULL CHECK (position_valid IN (0, 1)),
  orientation_valid INTEGER NOT NULL CHECK (orientation_valid IN (0, 1)),
  virtual_pose BLOB CHECK (virtual_pose IS NULL OR length(virtual_pose) = 128),
  physical_edge INTEGER,
  virtual_edge INTEGER,
  laps REAL,
  anchor_fraction REAL,
  coherence_error_m REAL,
  coherence_error_rad REAL
) STRICT;

CREATE INDEX tracking_samples_by_session_time ON tracking_samples (session_id, t_ns);

CREATE TABLE frames (
  frame_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  frame_index INTEGER NOT NULL,
  t_ns INTEGER NOT NULL,
  predicted_display_ns INTEGER,
  cpu_time_ns INTEGER NOT NULL,
  gpu_time_ns INTEGER,
  dropped_frames INTEGER NOT NULL DEFAULT 0 CHECK (dropped_frames >= 0),
  views INTEGER NOT NULL,
  passes INTEGER NOT NULL,
  draws INTEGER NOT NULL,
  triangles INTEGER NOT NULL
) STRICT;

CREATE INDEX frames_by_session_frame ON frames (session_id, frame_index);

CREATE TABLE events (
  event_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  t_ns INTEGER NOT NULL,
  kind TEXT NOT NULL,
  detail TEXT NOT NULL DEFAULT '{}' CHECK (json_valid(detail))
) STRICT;

INSERT INTO protocols (protocol_id, name, sha256, text, source_path)
SELECT protocol_id, 'unnamed', lower(sha256), text, NULL FROM v1_protocols;

INSERT INTO participants (participant_id, pseudonym, ipd_m, dominant_eye, created_utc)
SELECT p.participant_id, p.pseudonym, NULL, 'unknown',
       coalesce((SELECT min(s.started_utc) FROM v1_sessions s
                 WHERE s.participant_id = p.participant_id),
                strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))
FROM v1_participants p;

INSERT INTO sessions (session_id, protocol_id, participant_id, session_number,
                      software_version, software_commit, backend, renderer_device,
                      renderer_driver, display_refresh_hz, seed, table_calibration,
                      status, started_utc, ended_utc)
SELECT session_id, protocol_id, participant_id,
       row_number() OVER (PARTITION BY participant_id ORDER BY session_id),
       'unknown', 'unknown', 'unknown', 'unknown', 'unknown', NULL, seed, NULL,
       CASE WHEN status IN ('running', 'paused', 'completed', 'aborted') THEN status
            ELSE 'interrupted' END,
       started_utc, NULL
FROM v1_sessions;

-- v1 had no blocks: each session gets one block holding all its trials.
INSERT INTO blocks (session_id, block_index, name, is_practice, settings)
SELECT session_id, 0, 'main', 0, '{}' FROM v1_sessions;

INSERT INTO trials (trial_id, session_id, block_id, trial_index, trial_in_block,
                    conditions, stimulus, status, attempt, onset_ns, response_ns,
                    response, rt_ns, response_device, completed_utc)
SELECT t.trial_id, t.session_id,
       (SELECT b.block_id FROM blocks b WHERE b.session_id = t.session_id AND b.block_index = 0),
       t.trial_index, t.trial_index,
       CASE WHEN json_valid(t.conditions) THEN t.conditions
            ELSE json_object('v1_conditions', t.conditions) END,
       '{}',
       CASE WHEN t.status IN ('pending', 'running', 'completed', 'skipped', 'aborted') THEN t.status
            ELSE 'pending' END,
       CASE WHEN t.status = 'completed' THEN 1 ELSE 0 END,
       NULL, NULL, t.response,
       CASE WHEN t.rt_ms IS NULL THEN NULL ELSE CAST(round(t.rt_ms * 1000000.0) AS INTEGER) END,
       NULL, NULL
FROM v1_trials t;

INSERT INTO events (event_id, session_id, trial_id, t_ns, kind, detail)
SELECT event_id, session_id, NULL, t_ns, kind,
       CASE WHEN detail IS NULL THEN '{}'
            WHEN json_valid(detail) THEN detail
            ELSE json_object('text', detail) END
FROM v1_events;

DROP TABLE v1_trials;
DROP TABLE v1_events;
DROP TABLE v1_sessions;
DROP TABLE v1_participants;
DROP TABLE v1_protocols;

INSERT INTO schema_migrations (version, applied_utc, note)
VALUES (1, 'unknown', 'created by a curvlab release with schema version 1');
INSERT INTO schema_migrations (version, applied_utc, note)
VALUES (2, strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), 'migrated from version 1');

PRAGMA user_version = 2;
