-- Migration from schema version 7 to 8:
--   questionnaire_answers: one row per item answered in a questionnaire
--     block (docs/questionnaires.md), with the item as shown, the value and
--     label chosen and when.
--   questionnaire_scores: one row per subscale of a questionnaire block,
--     scored when the block ends (the SSQ's weighted scores, a custom
--     instrument's sums or means).
-- Files of version 7 had no questionnaire blocks: both tables start empty.
-- The definitions are schema.sql's, so a migrated file and a new file have
-- the same sqlite_master entries.

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

INSERT INTO schema_migrations (version, applied_utc, note)
  VALUES (8, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'questionnaires');

PRAGMA user_version = 8;
