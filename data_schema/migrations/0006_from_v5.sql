-- Migration from schema version 5 to 6:
--   lsl_streams, lsl_samples, lsl_clock: the Lab Streaming Layer streams a
--     session sent (its outlets) and recorded (other instruments' streams,
--     `curvlab run --lsl-record`), each recorded sample on the session clock
--     with its LSL time stamp, and the measured mapping between the session
--     clock and the LSL clock (docs/lsl.md). Files of version 5 streamed
--     nothing: the tables start empty.
-- The definitions are schema.sql's, so a migrated file and a new file have the
-- same sqlite_master entries.

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

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (6, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'lsl_streams, lsl_samples, lsl_clock');

PRAGMA user_version = 6;
