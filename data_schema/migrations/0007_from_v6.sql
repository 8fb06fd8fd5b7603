-- Migration from schema version 6 to 7:
--   shots: one row per billiards shot of a play block, with its inputs, the
--     events it caused and the balls' rest state. Files of version 6 had no
--     play blocks: the table starts empty.
-- The definition is schema.sql's, so a migrated file and a new file have the
-- same sqlite_master entries.

CREATE TABLE shots (
  shot_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER NOT NULL REFERENCES trials(trial_id),
  shot_index INTEGER NOT NULL CHECK (shot_index >= 0),
  t_ns INTEGER NOT NULL,
  rest_ns INTEGER NOT NULL,
  player TEXT NOT NULL CHECK (player IN ('participant', 'simulated')),
  ball TEXT NOT NULL,
  aim_x REAL NOT NULL,
  aim_z REAL NOT NULL,
  speed_m_s REAL NOT NULL CHECK (speed_m_s >= 0),
  cue_speed_m_s REAL,
  tip_side REAL,
  tip_height REAL,
  miscue INTEGER NOT NULL DEFAULT 0 CHECK (miscue IN (0, 1)),
  cue_pose TEXT CHECK (cue_pose IS NULL OR json_valid(cue_pose)),
  table_settings TEXT NOT NULL CHECK (json_valid(table_settings)),
  before_state TEXT NOT NULL CHECK (json_valid(before_state)),
  shot TEXT NOT NULL CHECK (json_valid(shot)),
  events TEXT NOT NULL CHECK (json_valid(events)),
  rest_state TEXT NOT NULL CHECK (json_valid(rest_state)),
  pocketed TEXT NOT NULL CHECK (json_valid(pocketed)),
  event_count INTEGER NOT NULL CHECK (event_count >= 0),
  UNIQUE (trial_id, shot_index)
) STRICT;

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (7, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'shots');

PRAGMA user_version = 7;
