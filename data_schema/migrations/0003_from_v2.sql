-- Migration from schema version 2 to 3: the eye geometry each frame was drawn
-- with (frames.eye_width_px, eye_height_px, eye_views). Frames of version 2
-- recorded none and keep NULL there; replay then assumes what version 2's
-- replay assumed (the protocol's IPD and resolution, a 90° field of view).
-- The column definitions are schema.sql's, so a migrated file and a new file
-- have the same sqlite_master entries.

ALTER TABLE frames ADD COLUMN eye_width_px INTEGER CHECK (eye_width_px IS NULL OR eye_width_px > 0);
ALTER TABLE frames ADD COLUMN eye_height_px INTEGER CHECK (eye_height_px IS NULL OR eye_height_px > 0);
ALTER TABLE frames ADD COLUMN eye_views BLOB CHECK (eye_views IS NULL OR length(eye_views) = 256);

-- The frames that record eye geometry (the first of each run, then each change).
CREATE INDEX frames_with_eye_views ON frames (session_id, frame_index) WHERE eye_views IS NOT NULL;

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (3, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'frames: eye geometry (eye_width_px, eye_height_px, eye_views)');

PRAGMA user_version = 3;
