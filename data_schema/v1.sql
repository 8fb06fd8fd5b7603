-- curvlab data schema, version 1 (the first released layout, kept so that
-- files written by it can be migrated and the migration can be tested).
-- Do not edit: a released schema version is frozen.
PRAGMA user_version = 1;

CREATE TABLE protocols (
  protocol_id INTEGER PRIMARY KEY,
  sha256 TEXT NOT NULL UNIQUE,
  text TEXT NOT NULL
) STRICT;

CREATE TABLE participants (
  participant_id INTEGER PRIMARY KEY,
  pseudonym TEXT NOT NULL UNIQUE
) STRICT;

CREATE TABLE sessions (
  session_id INTEGER PRIMARY KEY,
  protocol_id INTEGER NOT NULL REFERENCES protocols(protocol_id),
  participant_id INTEGER NOT NULL REFERENCES participants(participant_id),
  seed INTEGER NOT NULL,
  status TEXT NOT NULL,
  started_utc TEXT NOT NULL
) STRICT;

CREATE TABLE trials (
  trial_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  trial_index INTEGER NOT NULL,
  conditions TEXT NOT NULL,
  response TEXT,
  rt_ms REAL,
  status TEXT NOT NULL,
  UNIQUE (session_id, trial_index)
) STRICT;

CREATE TABLE events (
  event_id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(session_id),
  t_ns INTEGER NOT NULL,
  kind TEXT NOT NULL,
  detail TEXT
) STRICT;
