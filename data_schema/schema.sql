-- curvlab data schema, version 8 (current). The program embeds this file at
-- build time and executes it verbatim to create a new database; the codebook
-- (codebook.md) gives every column its meaning and unit. Times: *_ns are
-- nanoseconds of the session's monotonic clock, *_utc are ISO 8601 UTC text.
-- Adding or changing anything here means a new version, a migration in
-- migrations/, and a codebook entry: no column is ever added at run time.
PRAGMA user_version = 9;

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
  session_uuid TEXT CHECK (session_uuid IS NULL OR (length(session_uuid) = 36 AND
    session_uuid GLOB '[0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f][0-9a-f]-*')),
  UNIQUE (participant_id, session_number)
) STRICT;

-- A session's identity across files and machines (RFC 9562 UUID, lower case).
CREATE UNIQUE INDEX sessions_by_uuid ON sessions (session_uuid);

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
  end_reason TEXT,
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
  triangles INTEGER NOT NULL,
  eye_width_px INTEGER CHECK (eye_width_px IS NULL OR eye_width_px > 0),
  eye_height_px INTEGER CHECK (eye_height_px IS NULL OR eye_height_px > 0),
  eye_views BLOB CHECK (eye_views IS NULL OR length(eye_views) = 256),
  display_period_ns INTEGER CHECK (display_period_ns IS NULL OR display_period_ns > 0),
  late INTEGER NOT NULL DEFAULT 0 CHECK (late IN (0, 1))
) STRICT;

CREATE INDEX frames_by_session_frame ON frames (session_id, frame_index);
-- The frames that record eye geometry (the first of each run, then each change).
CREATE INDEX frames_with_eye_views ON frames (session_id, frame_index) WHERE eye_views IS NOT NULL;

CREATE TABLE events (
  event_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER,
  t_ns INTEGER NOT NULL,
  kind TEXT NOT NULL,
  detail TEXT NOT NULL DEFAULT '{}' CHECK (json_valid(detail))
) STRICT;

-- Lab Streaming Layer (docs/lsl.md): the streams a session sent and recorded,
-- recorded samples on the session clock, the session clock ↔ LSL clock mapping.
CREATE TABLE lsl_streams (
  lsl_stream_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  role TEXT NOT NULL CHECK (role IN ('outlet', 'recorded')),
  name TEXT NOT NULL,
  type TEXT NOT NULL,
  source_id TEXT NOT NULL,
  channel_count INTEGER NOT NULL CHECK (channel_count > 0),
  nominal_srate_hz REAL NOT NULL CHECK (nominal_srate_hz >= 0),
  channel_format TEXT NOT NULL,
  info_xml TEXT NOT NULL,
  UNIQUE (session_id, role, source_id, name, type)
) STRICT;

CREATE TABLE lsl_samples (
  lsl_sample_id INTEGER PRIMARY KEY,
  lsl_stream_id INTEGER NOT NULL REFERENCES lsl_streams(lsl_stream_id),
  t_ns INTEGER NOT NULL,
  lsl_time_s REAL NOT NULL,
  lsl_offset_s REAL NOT NULL,
  received_ns INTEGER NOT NULL,
  value TEXT NOT NULL CHECK (json_valid(value))
) STRICT;

CREATE INDEX lsl_samples_by_stream_time ON lsl_samples (lsl_stream_id, t_ns);

CREATE TABLE lsl_clock (
  lsl_clock_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  t_ns INTEGER NOT NULL,
  lsl_time_s REAL NOT NULL,
  uncertainty_ns INTEGER NOT NULL CHECK (uncertainty_ns >= 0)
) STRICT;

CREATE INDEX lsl_clock_by_session_time ON lsl_clock (session_id, t_ns);

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

CREATE TABLE questionnaire_answers (
  answer_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER NOT NULL REFERENCES trials(trial_id),
  instrument TEXT NOT NULL,
  item_index INTEGER NOT NULL CHECK (item_index >= 0),
  item_id TEXT NOT NULL,
  item_text TEXT NOT NULL,
  value INTEGER NOT NULL,
  label TEXT NOT NULL,
  shown_ns INTEGER NOT NULL,
  t_ns INTEGER NOT NULL,
  rt_ms REAL NOT NULL CHECK (rt_ms >= 0),
  device TEXT NOT NULL,
  UNIQUE (trial_id, item_index)
) STRICT;

CREATE TABLE questionnaire_scores (
  score_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_id INTEGER NOT NULL REFERENCES trials(trial_id),
  instrument TEXT NOT NULL,
  subscale_index INTEGER NOT NULL CHECK (subscale_index >= 0),
  subscale TEXT NOT NULL,
  rule TEXT NOT NULL CHECK (rule IN ('sum', 'mean')),
  weight REAL NOT NULL,
  items INTEGER NOT NULL CHECK (items >= 0),
  answered INTEGER NOT NULL CHECK (answered >= 0),
  raw REAL,
  score REAL,
  UNIQUE (trial_id, subscale_index)
) STRICT;

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
