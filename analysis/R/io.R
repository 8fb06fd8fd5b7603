# Reading curvlab data into plain data frames.
#
# Two sources give the same trial table:
#   - a curvlab SQLite file (schema version 8, data_schema/schema.sql), read
#     read-only with RSQLite; conditions/stimulus JSON are expanded into
#     cond_<name> / stim_<name> columns exactly as `curvlab export --format csv`
#     names them, and staircase steps are joined on trial_id;
#   - an export directory holding trials.csv (`curvlab export --format csv`).
# The database also gives full session provenance, observer ground truth and
# tracking samples; an export directory gives what trials.csv carries.
#
# Input problems raise a condition of class "curvlab_input_error" whose message
# names the file and what was expected; report.R turns it into exit code 2.

curvlab_application_id <- 1129729090  # PRAGMA application_id "CVLB"
curvlab_schema_version <- 9L

input_error <- function(...) {
  stop(structure(class = c("curvlab_input_error", "error", "condition"),
                 list(message = paste0(...), call = NULL)))
}

# Reads a database file or an export directory; returns a list with
#   source (path), kind ("database" | "export"), trials, sessions,
#   staircase (steps), tracking (may be empty), events (observer rows).
# The psi method's posterior summaries (its `posterior` event's keys; the
# trial CSV's columns, entropy_nats there as posterior_entropy).
posterior_fields <- c("pse_mean", "pse_sd", "slope_mean", "slope_sd", "lapse_mean", "lapse_sd", "entropy_nats")

read_curvlab <- function(path, max_tracking_per_device = 20000L) {
  if (!nzchar(path)) input_error("no input given (expected --db FILE or --export DIR)")
  if (!file.exists(path))
    input_error(path, ": no such file or directory (expected a curvlab SQLite database ",
                "or a directory written by `curvlab export`)")
  if (dir.exists(path)) read_export_dir(path) else read_database(path, max_tracking_per_device)
}

# ---------------------------------------------------------------------------
# SQLite

# Damaged and foreign files get the same messages as the curvlab command
# (harness/src/data/database.cpp, docs/data.md "Damaged or foreign files"):
# whether the file can be read at all, and how to recover committed data.
shell_quote <- function(path)
  if (grepl("^[A-Za-z0-9/._+,:@%=-]+$", path)) path else paste0("'", gsub("'", "'\\''", path, fixed = TRUE), "'")
recover_command <- function(path) paste0("sqlite3 ", shell_quote(path), " .recover | sqlite3 recovered.sqlite")
corrupt_error <- function(path, ...) {
  input_error(path, ": damaged curvlab data file: ", ..., ", so only part of it can be read. ",
              "Recover the committed data into a new file with the SQLite shell: ", recover_command(path),
              "; then use recovered.sqlite (", path,
              " is left as it is; docs/data.md shows how without .recover)")
}

# Checks the file itself before SQLite reads it: the header's magic string,
# then its length against the page size and page count the header records
# (sqlite.org/fileformat.html, "The Database Header").
check_database_file <- function(path) {
  size <- file.info(path)$size
  header <- tryCatch(readBin(path, "raw", 100L), error = function(e) raw(0))
  magic <- c(charToRaw("SQLite format 3"), as.raw(0))
  n <- min(length(header), 16L)
  if (n == 0L || !identical(header[seq_len(n)], magic[seq_len(n)]))
    input_error(path, ": not an SQLite database (it does not begin with \"SQLite format 3\"), so it ",
                "cannot be read at all and is not a curvlab data file. If it should hold curvlab data it ",
                "was overwritten: use a backup, or save whatever SQLite pages remain with the SQLite shell: ",
                recover_command(path))
  bytes <- function(n) format(n, scientific = FALSE, trim = TRUE)
  if (length(header) < 100L)
    corrupt_error(path, "truncated to ", bytes(size), " bytes, shorter than the 100-byte SQLite header")
  be <- function(b) sum(as.numeric(as.integer(b)) * 256^(rev(seq_along(b)) - 1))
  page_size <- be(header[17:18])
  if (page_size == 1) page_size <- 65536
  if (page_size < 512 || page_size > 65536 || bitwAnd(page_size, page_size - 1) != 0)
    corrupt_error(path, "its header is damaged (page size ", page_size, ")")
  # A pending write-ahead log is reconciled by SQLite on open, unless its
  # header is damaged: then SQLite would silently read the file without it.
  wal <- paste0(path, "-wal")
  check_wal_header(path, wal)
  if (file.exists(wal) && isTRUE(file.info(wal)$size > 0)) return(invisible(TRUE))
  pages <- be(header[29:32])
  if (pages > 0 && be(header[25:28]) == be(header[93:96]) && size < pages * page_size)
    corrupt_error(path, "truncated to ", bytes(size), " bytes where its header records ",
                  bytes(pages * page_size), " (", bytes(pages), " pages of ", bytes(page_size), " bytes)")
  invisible(TRUE)
}

# The write-ahead log's 32-byte header: magic, version 3007000 and the
# checksum of its first 24 bytes (sqlite.org/fileformat.html, "WAL File
# Format", "Checksum Algorithm"); the same check and words as the curvlab
# command. A log without frames holds nothing to lose.
check_wal_header <- function(path, wal) {
  size <- if (file.exists(wal)) file.info(wal)$size else 0
  if (is.na(size) || size <= 32) return(invisible(TRUE))
  h <- as.numeric(as.integer(readBin(wal, "raw", 32L)))
  word <- function(i, big) {
    b <- h[i + 1:4]
    if (!big) b <- rev(b)
    sum(b * 256^(3:0))
  }
  magic <- word(0, TRUE)
  wal_magic <- 931071618  # 0x377f0682; the low bit says the checksums' byte order
  big <- magic %% 2 == 1
  problem <- if (magic - magic %% 2 != wal_magic) "does not begin with the WAL magic number"
             else if (word(4, TRUE) != 3007000) "records an unknown format version"
             else {
               m <- 2^32
               s0 <- 0
               s1 <- 0
               for (i in c(0, 8, 16)) {
                 s0 <- (s0 + word(i, big) + s1) %% m
                 s1 <- (s1 + word(i + 4, big) + s0) %% m
               }
               if (s0 != word(24, TRUE) || s1 != word(28, TRUE)) "has a header whose checksum does not match"
               else ""
             }
  if (!nzchar(problem)) return(invisible(TRUE))
  input_error(path, ": damaged curvlab data file: its write-ahead log ", wal, " (",
              format(size, scientific = FALSE), " bytes of transactions not yet copied into the file) ", problem,
              ", so SQLite would discard those transactions on the next open. Nothing was changed. Before any ",
              "program opens the file, copy ", shell_quote(path), " and ", shell_quote(wal), " aside together; docs/data.md ",
              "(\"A damaged write-ahead log\") shows how to repair the header and recover the committed rows")
}

# The tables and columns of the current schema (data_schema/schema.sql, when
# this checkout has it), to tell a damaged schema from a readable one.
expected_columns <- function() {
  # report.R defines analysis_root(); the schema sits beside analysis/.
  candidates <- c(if (exists("analysis_root", mode = "function"))
                    file.path(analysis_root(), "..", "data_schema", "schema.sql"),
                  file.path(getwd(), "data_schema", "schema.sql"))
  schema <- Filter(function(f) nzchar(f) && file.exists(f), candidates)
  if (!length(schema)) return(character(0))
  con <- DBI::dbConnect(RSQLite::SQLite(), ":memory:")
  on.exit(DBI::dbDisconnect(con))
  sql <- paste(readLines(schema[[1]], warn = FALSE), collapse = "\n")
  for (stmt in strsplit(sql, ";\\s*\n")[[1]]) if (nzchar(trimws(gsub("--[^\n]*", "", stmt)))) DBI::dbExecute(con, stmt)
  table_columns(function(q) DBI::dbGetQuery(con, q))
}

table_columns <- function(q) {
  cols <- q(paste("SELECT m.name || '.' || p.name AS col FROM sqlite_master AS m, pragma_table_info(m.name) AS p",
                  "WHERE m.type = 'table' AND m.name NOT LIKE 'sqlite_%'"))$col
  sort(cols, method = "radix")  # byte order, as the curvlab command lists them
}

schema_damage <- function(path, what)
  corrupt_error(path, "its schema is damaged (", what, "); nothing was changed")

# SQLite's own words for a damaged file, as raised by RSQLite.
is_corruption_message <- function(msg)
  grepl("malformed|not a database|disk image|database corrupt", msg, ignore.case = TRUE)

read_database <- function(path, max_tracking_per_device = 20000L) {
  check_database_file(path)
  con <- tryCatch(
    suppressWarnings(
      DBI::dbConnect(RSQLite::SQLite(), path, flags = RSQLite::SQLITE_RO, bigint = "numeric")),
    error = function(e) {
      if (is_corruption_message(conditionMessage(e)))
        corrupt_error(path, "SQLite reports \"", conditionMessage(e), "\"")
      input_error(path, ": cannot open read-only: ", conditionMessage(e))
    })
  on.exit(DBI::dbDisconnect(con), add = TRUE)
  q <- function(sql, params = NULL) {
    tryCatch(DBI::dbGetQuery(con, sql, params = params), error = function(e) {
      if (is_corruption_message(conditionMessage(e)))
        corrupt_error(path, "SQLite reports \"", conditionMessage(e), "\"")
      stop(e)
    })
  }

  app_id <- q("PRAGMA application_id")[[1]]
  version <- q("PRAGMA user_version")[[1]]
  if (app_id != curvlab_application_id)
    input_error(path, ": not a curvlab data file: a readable SQLite database written by another ",
                "program (application_id ", app_id, "; curvlab writes ", curvlab_application_id,
                ", \"CVLB\"). It was not modified and there is nothing to recover; give the file ",
                "curvlab run wrote (by default results/<protocol name>.sqlite)")
  # The whole file is about to be read: check every page's structure first, so
  # damage is reported as such rather than as a failed query half-way.
  checked <- q("PRAGMA quick_check")[[1]]
  if (!identical(checked, "ok"))
    corrupt_error(path, "SQLite's quick_check reports \"", checked[1], "\"")
  if (version < 1)
    schema_damage(path, paste0("it records schema version ", version, ", which no curvlab writes"))
  if (version != curvlab_schema_version)
    input_error(path, ": schema version ", version, ", expected ", curvlab_schema_version,
                if (version < curvlab_schema_version)
                  " (upgrade it once in place with `curvlab upgrade --db FILE`)"
                else " (written by a newer curvlab; update the analysis scripts)")
  tables <- q("SELECT name FROM sqlite_master WHERE type = 'table'")$name
  needed <- c("protocols", "participants", "sessions", "blocks", "trials",
              "staircase_steps", "tracking_samples", "events")
  missing <- setdiff(needed, tables)
  expected <- expected_columns()
  if (length(expected)) missing <- setdiff(expected, table_columns(q))
  if (length(missing)) {
    listed <- paste(head(missing, 4), collapse = ", ")
    if (length(missing) > 4) listed <- paste0(listed, " and ", length(missing) - 4, " more")
    schema_damage(path, paste0("schema version ", curvlab_schema_version, " lacks ", listed))
  }

  # A Bayesian adaptive (psi) method stores its posterior after each answer
  # as a `posterior` event of the trial (docs/data.md); its summaries travel
  # with the trial as posterior_* columns (the last event of a trial).
  posterior_sql <- paste(
    "LEFT JOIN (SELECT trial_id,",
    paste0("json_extract(detail, '$.", posterior_fields, "') AS posterior_", posterior_fields, collapse = ", "),
    "FROM events WHERE event_id IN (SELECT max(event_id) FROM events WHERE kind = 'posterior'",
    "GROUP BY trial_id)) po ON po.trial_id = t.trial_id")
  raw_trials <- q(paste(
    "SELECT t.trial_id, t.session_id, se.session_uuid, p.pseudonym AS participant, se.session_number,",
    "pr.sha256 AS protocol_sha256, b.block_index, b.name AS block_name, b.is_practice,",
    "t.trial_index, t.trial_in_block, t.status, t.attempt, t.onset_ns, t.response_ns,",
    "t.rt_ns, t.response, t.response_device, t.completed_utc, t.conditions, t.stimulus,",
    "st.staircase, st.step_index, st.intensity, st.is_reversal, st.response_correct, st.next_intensity,",
    paste0(paste0("po.posterior_", posterior_fields, collapse = ", "), ","),
    "tf.lost_ms AS tracking_lost_ms,",
    # Eye tracking, as the trial CSV summarises it (docs/data.md, "Eye
    # tracking"): the model's vergence demand from the onset's percept, and
    # the gaze samples during the stimulus with their mean vergence.
    "json_extract(op.detail, '$.percept.vergence_demand_arcmin') AS vergence_demand_arcmin,",
    "CASE WHEN gs.session_id IS NULL THEN NULL ELSE COALESCE(gz.n, 0) END AS gaze_samples,",
    "CASE WHEN gs.session_id IS NULL THEN NULL ELSE COALESCE(gz.valid, 0) END AS gaze_valid_samples,",
    "gz.vergence_rad * 10800.0 / 3.141592653589793 AS gaze_vergence_arcmin",
    "FROM trials t",
    "JOIN sessions se ON se.session_id = t.session_id",
    "JOIN participants p ON p.participant_id = se.participant_id",
    "JOIN protocols pr ON pr.protocol_id = se.protocol_id",
    "JOIN blocks b ON b.block_id = t.block_id",
    "LEFT JOIN staircase_steps st ON st.trial_id = t.trial_id",
    posterior_sql,
    "LEFT JOIN (SELECT trial_id, sum(json_extract(detail, '$.lost_ms')) AS lost_ms FROM events",
    "   WHERE kind = 'tracking_flagged' GROUP BY trial_id) tf ON tf.trial_id = t.trial_id",
    "LEFT JOIN (SELECT trial_id, detail FROM events WHERE kind = 'onset') op ON op.trial_id = t.trial_id",
    "   AND json_extract(op.detail, '$.predicted_display_ns') = t.onset_ns",
    "LEFT JOIN (SELECT DISTINCT session_id FROM gaze_samples) gs ON gs.session_id = t.session_id",
    "LEFT JOIN (SELECT g.trial_id, count(*) AS n,",
    "   sum(CASE WHEN g.left_valid IS NOT NULL THEN g.vergence_rad IS NOT NULL ELSE g.combined_valid = 1 END) AS valid,",
    "   avg(g.vergence_rad) AS vergence_rad FROM gaze_samples g JOIN trials gt ON gt.trial_id = g.trial_id",
    "   LEFT JOIN (SELECT trial_id, json_extract(detail, '$.predicted_display_ns') AS at_ns,",
    "     json_extract(detail, '$.stimulus_ms') AS ms FROM events WHERE kind = 'onset') oe",
    "     ON oe.trial_id = gt.trial_id AND oe.at_ns = gt.onset_ns",
    "   WHERE g.t_ns >= gt.onset_ns AND g.t_ns < coalesce(gt.onset_ns + oe.ms * 1000000, gt.response_ns)",
    "   GROUP BY g.trial_id) gz ON gz.trial_id = t.trial_id",
    # A play or questionnaire block's one trial stands for the block: it is
    # not a judgement.
    "WHERE NOT EXISTS (SELECT 1 FROM shots sh WHERE sh.trial_id = t.trial_id)",
    "  AND NOT EXISTS (SELECT 1 FROM events pe WHERE pe.trial_id = t.trial_id",
    "                  AND pe.kind IN ('play_summary', 'questionnaire_start'))",
    "ORDER BY t.session_id, t.trial_index"))
  cond <- expand_json_column(raw_trials$conditions, "cond_", path, "trials.conditions")
  stim <- expand_json_column(raw_trials$stimulus, "stim_", path, "trials.stimulus")
  trials <- cbind(raw_trials[setdiff(names(raw_trials), c("conditions", "stimulus"))], cond, stim)
  trials <- normalise_trials(trials)

  sessions <- q(paste(
    "SELECT s.session_id, s.session_uuid, p.pseudonym AS participant, s.session_number,",
    "pr.name AS protocol_name, pr.sha256 AS protocol_sha256, s.software_version,",
    "s.software_commit, s.backend, s.renderer_device, s.renderer_driver,",
    "s.display_refresh_hz, printf('%llu', s.seed) AS seed, s.table_calibration, s.status,",
    "s.started_utc, s.ended_utc,",
    "(SELECT count(*) FROM trials t WHERE t.session_id = s.session_id) AS trials_planned,",
    "(SELECT count(*) FROM trials t WHERE t.session_id = s.session_id",
    "   AND t.status = 'completed') AS trials_completed,",
    "(SELECT e.detail FROM events e WHERE e.session_id = s.session_id",
    "   AND e.kind = 'observer' ORDER BY e.event_id LIMIT 1) AS observer,",
    "(SELECT json_extract(e.detail, '$.warnings') FROM events e WHERE e.session_id = s.session_id",
    "   AND e.kind = 'session_start' ORDER BY e.event_id LIMIT 1) AS protocol_warnings",
    "FROM sessions s JOIN participants p ON p.participant_id = s.participant_id",
    "JOIN protocols pr ON pr.protocol_id = s.protocol_id ORDER BY s.session_id"))

  staircase <- q(paste(
    "SELECT st.session_id, p.pseudonym AS participant, st.staircase, st.step_index,",
    "st.trial_id, st.intensity, st.response_correct, st.is_reversal, st.next_intensity",
    "FROM staircase_steps st JOIN sessions s ON s.session_id = st.session_id",
    "JOIN participants p ON p.participant_id = s.participant_id",
    "ORDER BY st.session_id, st.staircase, st.step_index"))

  events <- q("SELECT session_id, trial_id, t_ns, kind, detail FROM events WHERE kind = 'observer'")
  # Play blocks' figures (docs/billiards.md) and where they sat in the run.
  play <- q(paste(
    "SELECT e.session_id, se.session_uuid, p.pseudonym AS participant, b.block_index,",
    "json_extract(e.detail, '$.block') AS block, json_extract(t.conditions, '$.space') AS space,",
    "json_extract(e.detail, '$.shots') AS shots, json_extract(e.detail, '$.pocketed') AS pocketed,",
    "json_extract(e.detail, '$.time_s') AS time_s, json_extract(e.detail, '$.walked_m') AS walked_m,",
    "json_extract(e.detail, '$.laps_physical') AS laps_physical,",
    "json_extract(e.detail, '$.laps_virtual') AS laps_virtual,",
    "json_extract(e.detail, '$.hand_error_m') AS hand_error_m, json_extract(e.detail, '$.ended') AS ended,",
    # A shared game (docs/shared_play.md): its id, this station's role, and
    # who struck which shots and pocketed how many balls on them.
    "(SELECT json_extract(g.detail, '$.game_uuid') FROM events g WHERE g.trial_id = e.trial_id",
    "   AND g.kind = 'shared_game' ORDER BY g.event_id LIMIT 1) AS game_uuid,",
    "(SELECT json_extract(g.detail, '$.role') FROM events g WHERE g.trial_id = e.trial_id",
    "   AND g.kind = 'shared_game' ORDER BY g.event_id LIMIT 1) AS role,",
    paste0("(SELECT count(DISTINCT json_extract(ss.detail, '$.shot_index')) FROM events ss WHERE ss.trial_id = e.trial_id",
           " AND ss.kind = 'shared_shot' AND json_extract(ss.detail, '$.shooter') = '", c("host", "join"), "') AS ",
           c("host", "join"), "_shots,", collapse = " "),
    paste0("(SELECT coalesce(sum(json_array_length(sh.pocketed)), 0) FROM shots sh WHERE sh.trial_id = e.trial_id",
           " AND sh.shot_index IN (SELECT json_extract(ss.detail, '$.shot_index') FROM events ss",
           " WHERE ss.trial_id = e.trial_id AND ss.kind = 'shared_shot'",
           " AND json_extract(ss.detail, '$.shooter') = '", c("host", "join"), "')) AS ", c("host", "join"), "_pocketed,",
           collapse = " "),
    # The two players' heads apart in the virtual space, as this station
    # drew the partner (partner_samples).
    "(SELECT avg(x.distance_m) FROM partner_samples x WHERE x.trial_id = e.trial_id AND x.device = 'head')",
    "   AS partner_distance_m,",
    "(SELECT min(x.distance_m) FROM partner_samples x WHERE x.trial_id = e.trial_id AND x.device = 'head')",
    "   AS partner_closest_m",
    "FROM events e JOIN sessions se ON se.session_id = e.session_id",
    "JOIN participants p ON p.participant_id = se.participant_id",
    "JOIN trials t ON t.trial_id = e.trial_id JOIN blocks b ON b.block_id = t.block_id",
    "WHERE e.kind = 'play_summary' ORDER BY e.session_id, b.block_index"))

  # Questionnaire blocks' scores (docs/questionnaires.md), one row per block
  # and subscale, in the columns questionnaire_scores.csv has.
  questionnaires <- q(paste(
    "SELECT x.session_id, se.session_uuid, p.pseudonym AS participant, se.session_number,",
    "b.name AS block, b.block_index, x.instrument, x.subscale, x.rule, x.weight, x.items, x.answered,",
    "x.raw, x.score FROM questionnaire_scores x JOIN sessions se ON se.session_id = x.session_id",
    "JOIN participants p ON p.participant_id = se.participant_id",
    "JOIN trials t ON t.trial_id = x.trial_id JOIN blocks b ON b.block_id = t.block_id",
    "ORDER BY x.session_id, b.block_index, x.subscale_index"))

  # Thin long recordings evenly per session and device so figures stay light:
  # a 1 kHz hour would otherwise be millions of points on a top-view plot.
  counts <- q(paste("SELECT session_id, device, count(*) AS n FROM tracking_samples",
                    "WHERE position_valid = 1 GROUP BY session_id, device"))
  stride <- max(1, ceiling(max(c(0, counts$n)) / max_tracking_per_device))
  tracking <- q(paste(
    "SELECT * FROM (SELECT session_id, trial_id, device, t_ns, lab_px_m, lab_py_m, lab_pz_m,",
    "coherence_error_m, ROW_NUMBER() OVER (PARTITION BY session_id, device ORDER BY t_ns) AS rn",
    "FROM tracking_samples WHERE position_valid = 1) WHERE (rn - 1) % ? = 0"),
    params = list(stride))
  tracking$rn <- NULL

  list(source = normalizePath(path), kind = "database", trials = trials,
       sessions = sessions, staircase = staircase, tracking = tracking, events = events,
       play = play, questionnaires = questionnaires, tracking_stride = stride)
}

# JSON objects (one per row) → data frame of prefixed columns, keys in order of
# first appearance (the CSV exporter's order). Strings stay text, numbers
# become numeric where every present value is a number, booleans TRUE/FALSE.
expand_json_column <- function(texts, prefix, path, field) {
  n <- length(texts)
  if (n == 0) return(data.frame(row.names = integer(0)))
  parsed <- tryCatch(
    jsonlite::fromJSON(paste0("[", paste(ifelse(is.na(texts), "{}", texts), collapse = ","), "]"),
                       simplifyVector = FALSE),
    error = function(e) input_error(path, ": ", field, " holds invalid JSON (", conditionMessage(e), ")"))
  keys <- unique(unlist(lapply(parsed, names), use.names = FALSE))
  out <- lapply(keys, function(k) {
    vals <- lapply(parsed, function(o) if (is.null(o[[k]])) NA else o[[k]])
    if (all(vapply(vals, function(v) length(v) == 1 && (is.na(v) || is.numeric(v)), TRUE)))
      as.numeric(unlist(vals))
    else vapply(vals, function(v) if (length(v) == 1 && !is.na(v)) {
      if (is.logical(v)) (if (v) "TRUE" else "FALSE") else as.character(v)
    } else NA_character_, "")
  })
  names(out) <- paste0(prefix, keys)
  as.data.frame(out, stringsAsFactors = FALSE, check.names = FALSE)
}

# ---------------------------------------------------------------------------
# Export directory

read_export_dir <- function(dir) {
  csv <- file.path(dir, "trials.csv")
  if (!file.exists(csv))
    input_error(dir, ": no trials.csv in this directory (expected the output of ",
                "`curvlab export --db FILE --format csv --out DIR`)")
  trials <- tryCatch(
    utils::read.csv(csv, colClasses = "character", na.strings = "NA", check.names = FALSE),
    error = function(e) input_error(csv, ": cannot read as CSV (", conditionMessage(e), ")"))
  required <- c("session_id", "participant", "status", "response", "trial_index")
  missing <- setdiff(required, names(trials))
  if (length(missing))
    input_error(csv, ": missing column(s) ", paste(missing, collapse = ", "),
                " (expected the curvlab trial CSV, see docs/data.md)")
  # The export names the step's index staircase_step, and the psi method's
  # posterior summaries without the posterior_ prefix.
  if ("staircase_step" %in% names(trials) && !"step_index" %in% names(trials))
    names(trials)[names(trials) == "staircase_step"] <- "step_index"
  for (f in posterior_fields) {
    exported <- if (f == "entropy_nats") "posterior_entropy" else f
    if (exported %in% names(trials)) names(trials)[names(trials) == exported] <- paste0("posterior_", f)
  }
  for (col in c(grep("^stim_", names(trials), value = TRUE), grep("^posterior_", names(trials), value = TRUE))) {
    v <- suppressWarnings(as.numeric(trials[[col]]))
    if (all(is.na(v) == is.na(trials[[col]]))) trials[[col]] <- v
  }
  # A questionnaire block's one trial stands for the block (its blocks are
  # those of questionnaire_scores.csv): it is not a judgement.
  questionnaires <- read_questionnaire_scores_csv(dir)
  if (nrow(questionnaires) && all(c("session_uuid", "block_name") %in% names(trials)) &&
      "session_uuid" %in% names(questionnaires)) {
    asked <- paste(questionnaires$session_uuid, questionnaires$block)
    trials <- trials[!paste(trials$session_uuid, trials$block_name) %in% asked, , drop = FALSE]
  }
  trials <- normalise_trials(trials)

  sessions <- unique(trials[c("session_id", "participant", "session_number", "protocol_sha256")])
  sessions <- sessions[order(sessions$session_id), , drop = FALSE]
  sessions$trials_planned <- as.vector(table(factor(trials$session_id, sessions$session_id)))
  sessions$trials_completed <- as.vector(table(factor(trials$session_id[trials$status == "completed"],
                                                      sessions$session_id)))
  for (col in c("protocol_name", "software_version", "software_commit", "backend",
                "renderer_device", "renderer_driver", "seed", "table_calibration",
                "status", "started_utc", "observer"))
    sessions[[col]] <- NA_character_
  # trials.csv has no session table: the first completion time stands in for the start.
  sessions$started_utc <- vapply(sessions$session_id, function(s) {
    t <- trials$completed_utc[trials$session_id == s & !is.na(trials$completed_utc)]
    if (length(t)) min(t) else NA_character_
  }, "")

  staircase <- trials[!is.na(trials$intensity),
                      intersect(c("session_id", "participant", "staircase", "step_index",
                                  "trial_index", "intensity", "is_reversal"), names(trials)),
                      drop = FALSE]
  list(source = normalizePath(dir), kind = "export", trials = trials, sessions = sessions,
       staircase = staircase, tracking = read_bids_motion(dir), events = data.frame(),
       questionnaires = questionnaires, tracking_stride = 1)
}

# questionnaire_scores.csv of an export directory, when present (sessions
# numbered as trials.csv numbers them: by session_uuid).
read_questionnaire_scores_csv <- function(dir) {
  csv <- file.path(dir, "questionnaire_scores.csv")
  if (!file.exists(csv)) return(data.frame())
  d <- tryCatch(utils::read.csv(csv, colClasses = "character", na.strings = c("", "NA"), check.names = FALSE),
                error = function(e) input_error(csv, ": cannot read as CSV (", conditionMessage(e), ")"))
  missing <- setdiff(c("participant", "block", "block_index", "instrument", "subscale", "score"), names(d))
  if (length(missing))
    input_error(csv, ": missing column(s) ", paste(missing, collapse = ", "),
                " (expected the output of `curvlab export --format csv`)")
  d$session_id <- as.integer(factor(if ("session_uuid" %in% names(d)) d$session_uuid else d$participant))
  d
}

# Lab positions from a BIDS-motion export (DIR/bids/sub-*/ses-*/motion), when
# present: one *_motion.tsv per device with columns named by *_channels.tsv.
read_bids_motion <- function(dir) {
  files <- list.files(file.path(dir, "bids"), pattern = "_motion\\.tsv$", recursive = TRUE,
                      full.names = TRUE)
  empty <- data.frame(session_id = integer(0), trial_id = integer(0), device = character(0),
                      t_ns = numeric(0), lab_px_m = numeric(0), lab_py_m = numeric(0),
                      lab_pz_m = numeric(0), coherence_error_m = numeric(0))
  if (!length(files)) return(empty)
  rows <- lapply(files, function(f) {
    channels_file <- sub("_motion\\.tsv$", "_channels.tsv", f)
    if (!file.exists(channels_file)) return(NULL)
    ch <- utils::read.delim(channels_file, colClasses = "character")
    m <- utils::read.delim(f, header = FALSE, colClasses = "numeric", na.strings = c("n/a", "NA"))
    if (ncol(m) != nrow(ch)) return(NULL)
    names(m) <- ch$name
    pos <- ch$name[ch$type == "POS"]
    if (length(pos) != 3) return(NULL)
    base <- basename(f)
    data.frame(session_id = as.integer(sub(".*_ses-([0-9]+)_.*", "\\1", base)),
               participant = sub("^sub-([^_]+)_.*", "\\1", base),
               trial_id = NA_integer_,
               device = sub(".*_tracksys-([^_]+)_motion\\.tsv$", "\\1", base),
               t_ns = m[[ch$name[ch$type == "LATENCY"][1]]] * 1e9,
               lab_px_m = m[[pos[1]]], lab_py_m = m[[pos[2]]], lab_pz_m = m[[pos[3]]],
               coherence_error_m = NA_real_)
  })
  rows <- rows[!vapply(rows, is.null, TRUE)]
  if (!length(rows)) return(empty)
  do.call(rbind, rows)
}

# ---------------------------------------------------------------------------
# Common column types and derived columns

normalise_trials <- function(trials) {
  int_cols <- c("session_id", "session_number", "block_index", "is_practice", "trial_index",
                "trial_in_block", "attempt", "step_index", "is_reversal", "trial_id")
  num_cols <- c("onset_ns", "response_ns", "rt_ns", "intensity", "next_intensity", "tracking_lost_ms",
                "vergence_demand_arcmin", "gaze_samples", "gaze_valid_samples", "gaze_vergence_arcmin")
  for (col in intersect(int_cols, names(trials))) trials[[col]] <- as.integer(trials[[col]])
  for (col in intersect(num_cols, names(trials))) trials[[col]] <- as.numeric(trials[[col]])
  for (col in grep("^cond_", names(trials), value = TRUE))
    trials[[col]] <- as.character(trials[[col]])
  for (col in c("staircase", "step_index", "intensity", "next_intensity", "is_reversal", "tracking_lost_ms",
                "vergence_demand_arcmin", "gaze_samples", "gaze_valid_samples", "gaze_vergence_arcmin"))
    if (!col %in% names(trials)) trials[[col]] <- NA
  if (!"is_practice" %in% names(trials)) trials$is_practice <- 0L
  if (!"cond_judged" %in% names(trials)) trials$cond_judged <- rep("stick", nrow(trials))
  # The staircase name is also a condition value; the step row is authoritative.
  if ("cond_staircase" %in% names(trials))
    trials$staircase <- ifelse(is.na(trials$staircase), trials$cond_staircase, trials$staircase)
  trials$rt_ms <- trials$rt_ns / 1e6
  trials$participant <- as.character(trials$participant)
  trials$x_m <- stimulus_intensity(trials)
  trials$design <- trial_design(trials)
  trials
}

# The intensity a trial showed, in metres of signed sagitta: the staircase
# step's intensity where there is one, otherwise the judged object's sagitta.
# (Sessions store a staircase's value in its stim_ column as well; files of
# earlier versions hold the protocol's value there, so the step comes first.)
stimulus_intensity <- function(trials) {
  n <- nrow(trials)
  pick <- function(col) if (col %in% names(trials)) as.numeric(trials[[col]]) else rep(NA_real_, n)
  judged <- ifelse(is.na(trials$cond_judged), "stick", trials$cond_judged)
  x <- ifelse(judged == "table", pick("stim_table_sagitta_m"), pick("stim_stick_sagitta_m"))
  ifelse(is.na(trials$intensity), x, trials$intensity)
}

# Observer ground truth (events kind "observer") per session, as columns.
observer_truth <- function(data) {
  s <- data$sessions
  if (!nrow(s) || all(is.na(s$observer))) return(NULL)
  rows <- lapply(seq_len(nrow(s)), function(i) {
    if (is.na(s$observer[i])) return(NULL)
    d <- jsonlite::fromJSON(s$observer[i])
    data.frame(session_id = s$session_id[i], participant = s$participant[i],
               model = if (is.null(d$model)) NA else d$model,
               bias_m = num_or_na(d$bias_m), slope_per_m = num_or_na(d$slope_per_m),
               lapse = num_or_na(d$lapse), criterion_m = num_or_na(d$criterion_m))
  })
  do.call(rbind, rows[!vapply(rows, is.null, TRUE)])
}

num_or_na <- function(v) if (is.null(v)) NA_real_ else as.numeric(v)

# ---------------------------------------------------------------------------
# Several files: one study

# Database files named by `paths`: files as given, folders expanded to the
# SQLite files in them (*.sqlite, *.sqlite3, *.db), in name order.
database_files <- function(paths) {
  files <- unlist(lapply(paths, function(p) {
    if (!file.exists(p))
      input_error(p, ": no such file or directory (expected a curvlab SQLite database or a folder of them)")
    if (!dir.exists(p)) return(p)
    found <- sort(list.files(p, pattern = "\\.(sqlite3?|db)$", full.names = TRUE))
    if (!length(found))
      input_error(p, ": a folder without curvlab data files (expected *.sqlite, *.sqlite3 or *.db files, ",
                  "or use --export DIR for a `curvlab export` folder)")
    found
  }))
  unique(normalizePath(files))
}

# Reads several curvlab databases (or one) and pools them into one data set.
# Sessions are identified by sessions.session_uuid, so a session found in two
# files (a merged study file next to one of its sources) counts once; the
# same UUID with different trials is refused. Session and trial ids are
# renumbered in the order (start time, UUID), the same however the sessions
# are split over files, so separate files and their merge give equal tables.
read_curvlab_databases <- function(paths, max_tracking_per_device = 20000L) {
  files <- database_files(paths)
  parts <- lapply(files, read_database, max_tracking_per_device = max_tracking_per_device)
  pooled <- pool_parts(parts)
  pooled$source <- paste(files, collapse = ", ")
  pooled$files <- files
  pooled
}

session_fingerprint <- function(trials) {
  t <- trials[order(trials$trial_index), c("trial_index", "status", "response", "rt_ns"), drop = FALSE]
  paste(do.call(paste, c(unname(as.list(t)), sep = "|")), collapse = "\n")
}

pool_parts <- function(parts) {
  sessions <- bind_rows_fill(lapply(seq_along(parts), function(i)
    cbind(parts[[i]]$sessions, .part = rep(i, nrow(parts[[i]]$sessions)))))
  sessions$session_uuid <- ifelse(is.na(sessions$session_uuid),
                                  paste0("file", sessions$.part, "-session", sessions$session_id),
                                  sessions$session_uuid)
  part_trials <- function(i, id) { t <- parts[[i]]$trials; t[t$session_id == id, , drop = FALSE] }
  keep <- !duplicated(sessions$session_uuid)
  for (k in which(!keep)) {
    first <- which(sessions$session_uuid == sessions$session_uuid[k])[1]
    if (!identical(session_fingerprint(part_trials(sessions$.part[first], sessions$session_id[first])),
                   session_fingerprint(part_trials(sessions$.part[k], sessions$session_id[k]))))
      input_error(parts[[sessions$.part[k]]]$source, ": session ", sessions$session_uuid[k],
                  " is also in ", parts[[sessions$.part[first]]]$source,
                  " with different trials; give only one of the two files (or merge them with `curvlab merge`, ",
                  "which reports the conflict)")
  }
  sessions <- sessions[keep, , drop = FALSE]
  sessions <- sessions[order(sessions$started_utc, sessions$session_uuid), , drop = FALSE]
  sessions$new_id <- seq_len(nrow(sessions))
  remap <- function(table, i) {
    if (is.null(table) || !nrow(table)) return(table)
    m <- sessions[sessions$.part == i, ]
    table <- table[table$session_id %in% m$session_id, , drop = FALSE]
    table$session_id <- m$new_id[match(table$session_id, m$session_id)]
    table
  }
  pick <- function(name) lapply(seq_along(parts), function(i) remap(parts[[i]][[name]], i))
  trials <- bind_rows_fill(pick("trials"))
  trial_key <- function(session_id, trial_id) paste(session_id, trial_id)
  trials <- trials[order(trials$session_id, trials$trial_index), , drop = FALSE]
  new_trial_id <- stats::setNames(seq_len(nrow(trials)), trial_key(trials$session_id, trials$trial_id))
  renumber_trials <- function(table) {
    if (is.null(table) || !nrow(table) || !"trial_id" %in% names(table)) return(table)
    table$trial_id <- unname(new_trial_id[trial_key(table$session_id, table$trial_id)])
    table
  }
  staircase <- renumber_trials(bind_rows_fill(pick("staircase")))
  tracking <- renumber_trials(bind_rows_fill(pick("tracking")))
  events <- renumber_trials(bind_rows_fill(pick("events")))
  play <- bind_rows_fill(pick("play"))
  questionnaires <- bind_rows_fill(pick("questionnaires"))
  trials$trial_id <- seq_len(nrow(trials))
  rownames(trials) <- NULL
  sessions$session_id <- sessions$new_id
  sessions$new_id <- NULL; sessions$.part <- NULL
  rownames(sessions) <- NULL
  order_by <- function(t, cols) if (is.null(t) || !nrow(t)) t else t[do.call(order, unname(as.list(t[cols]))), , drop = FALSE]
  list(source = parts[[1]]$source, kind = "database", trials = trials, sessions = sessions,
       staircase = order_by(staircase, c("session_id", "staircase", "step_index")),
       tracking = order_by(tracking, c("session_id", "device", "t_ns")),
       events = order_by(events, c("session_id", "t_ns")),
       play = play, questionnaires = questionnaires,
       tracking_stride = max(vapply(parts, function(p) p$tracking_stride, 1)))
}

# rbind of data frames whose columns differ (cond_* and stim_* columns depend
# on the protocol): missing columns are NA.
bind_rows_fill <- function(frames) {
  frames <- frames[!vapply(frames, is.null, TRUE)]
  if (!length(frames)) return(data.frame())
  cols <- unique(unlist(lapply(frames, names)))
  filled <- lapply(frames, function(f) {
    for (c in setdiff(cols, names(f))) f[[c]] <- rep(NA, nrow(f))
    f[cols]
  })
  do.call(rbind, filled)
}
