-- Migration from schema version 4 to 5:
--   gaze_samples: the participant's gaze where the headset tracks the eyes
--     (XR_EXT_eye_gaze_interaction, XR_FB_eye_tracking_social), one row per
--     frame at its predicted display time, with the vergence of the two
--     eyes. Files of version 4 recorded no gaze: the table starts empty.
-- The definition is schema.sql's, so a migrated file and a new file have the
-- same sqlite_master entries.

CREATE TABLE gaze_samples (
  gaze_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  frame_index INTEGER NOT NULL,
  t_ns INTEGER NOT NULL,
  combined_valid INTEGER CHECK (combined_valid IS NULL OR combined_valid IN (0, 1)),
  combined_ox_m REAL,
  combined_oy_m REAL,
  combined_oz_m REAL,
  combined_dx REAL,
  combined_dy REAL,
  combined_dz REAL,
  left_valid INTEGER CHECK (left_valid IS NULL OR left_valid IN (0, 1)),
  left_confidence REAL CHECK (left_confidence IS NULL OR (left_confidence >= 0 AND left_confidence <= 1)),
  left_ox_m REAL,
  left_oy_m REAL,
  left_oz_m REAL,
  left_dx REAL,
  left_dy REAL,
  left_dz REAL,
  right_valid INTEGER CHECK (right_valid IS NULL OR right_valid IN (0, 1)),
  right_confidence REAL CHECK (right_confidence IS NULL OR (right_confidence >= 0 AND right_confidence <= 1)),
  right_ox_m REAL,
  right_oy_m REAL,
  right_oz_m REAL,
  right_dx REAL,
  right_dy REAL,
  right_dz REAL,
  vergence_rad REAL,
  vergence_distance_m REAL CHECK (vergence_distance_m IS NULL OR vergence_distance_m > 0)
) STRICT;

CREATE INDEX gaze_samples_by_session_time ON gaze_samples (session_id, t_ns);

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (5, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'gaze_samples');

PRAGMA user_version = 5;
