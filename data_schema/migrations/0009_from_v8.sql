-- Migration from schema version 8 to 9:
--   partner_samples: in a shared game (docs/shared_play.md), the partner's
--     head, hands and cue as this station drew them, one row per device
--     and frame, on this station's session clock, with the distance
--     between the two players' heads in the virtual space.
-- Files of version 8 stored no partner poses: the table starts empty.
-- The definitions are schema.sql's, so a migrated file and a new file have
-- the same sqlite_master entries.

CREATE TABLE partner_samples (
  sample_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  frame_index INTEGER NOT NULL,
  device TEXT NOT NULL CHECK (device IN ('head', 'left_hand', 'right_hand', 'cue')),
  t_ns INTEGER NOT NULL,
  virtual_pose BLOB NOT NULL CHECK (length(virtual_pose) = 128),
  tracked INTEGER NOT NULL CHECK (tracked IN (0, 1)),
  extrapolated INTEGER NOT NULL CHECK (extrapolated IN (0, 1)),
  sample_age_ns INTEGER NOT NULL,
  distance_m REAL
) STRICT;

CREATE INDEX partner_samples_by_session_time ON partner_samples (session_id, t_ns);

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (9, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'partner samples');

PRAGMA user_version = 9;
