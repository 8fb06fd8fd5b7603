# Synthetic curvlab data files, written with the real schema
# (data_schema/schema.sql executed verbatim), for power analyses and for tests
# of the analysis that must not depend on the session runner.
#
# The response model is the simulated observer's (DESIGN.md §5): perceived
# signed sagitta s = physical sagitta + effect(space, view); latent
# L = s + bias_m + N(0, 1/slope_per_m^2);
#   2 options: the positive option when L > 0, with probability `lapse` a
#              uniformly random option instead;
#   3 options: convex if L > criterion_m, concave if L < -criterion_m, else
#              straight, with the same lapse rule.
# So with 2 options P(convex) = lapse/2 + (1 - lapse) * pnorm(slope * (s + bias)).

default_schema_path <- function() {
  here <- analysis_root()
  file.path(dirname(here), "data_schema", "schema.sql")
}

create_curvlab_db <- function(path, schema_sql = default_schema_path()) {
  if (file.exists(path)) file.remove(path)
  con <- DBI::dbConnect(RSQLite::SQLite(), path)
  sql <- readLines(schema_sql, warn = FALSE)
  sql <- sub("--.*$", "", sql)
  statements <- strsplit(paste(sql, collapse = "\n"), ";", fixed = TRUE)[[1]]
  for (s in statements) if (nzchar(trimws(s))) DBI::dbExecute(con, s)
  DBI::dbExecute(con, paste("PRAGMA application_id =", curvlab_application_id))
  DBI::dbExecute(con, "INSERT INTO schema_migrations VALUES (2, '2024-01-01T00:00:00.000Z', 'created by curvlab')")
  con
}

# observers: data frame with participant, bias_m, slope_per_m, lapse and
#   optionally criterion_m (3 options) and model ("perception" by default).
# effect_m: function(space, view) giving the perceived-minus-physical sagitta
#   (0 everywhere = a null simulation).
# judgement: "constant" (levels_m × repetitions per cell) or "staircase"
#   (two 1-up/1-down staircases per cell, from +start_m and -start_m).
simulate_curvlab_db <- function(path, observers,
                                spaces = "E3", views = "tourist",
                                levels_m = seq(-0.03, 0.03, by = 0.01), repetitions = 10L,
                                options = c("convex", "concave"),
                                effect_m = function(space, view) 0,
                                judgement = c("constant", "staircase"),
                                staircase_trials = 40L, start_m = 0.06,
                                step_sizes_m = c(0.016, 0.008, 0.004, 0.002),
                                tracking = TRUE, seed = 1L,
                                schema_sql = default_schema_path()) {
  judgement <- match.arg(judgement)
  set.seed(seed)
  con <- create_curvlab_db(path, schema_sql)
  on.exit(DBI::dbDisconnect(con), add = TRUE)
  protocol_text <- paste0("# synthetic protocol\n[protocol]\nname = \"synthetic-", judgement, "\"\n")
  sha <- paste(rep(sprintf("%02x", seed %% 256), 32), collapse = "")
  DBI::dbExecute(con, "INSERT INTO protocols VALUES (1, ?, ?, ?, NULL)",
                 params = list(paste0("synthetic-", judgement), sha, protocol_text))
  if (is.null(observers$criterion_m)) observers$criterion_m <- 0.005
  if (is.null(observers$model)) observers$model <- "perception"
  trial_id <- 0L
  step_id <- 0L
  for (i in seq_len(nrow(observers))) {
    ob <- observers[i, ]
    DBI::dbExecute(con, "INSERT INTO participants VALUES (?, ?, NULL, 'right', '2024-01-01T00:00:00.000Z')",
                   params = list(i, ob$participant))
    calibration <- '{"centre_x_m":0,"centre_z_m":-0.9,"yaw_rad":0.2,"edge_m":0.9,"height_m":0.75}'
    DBI::dbExecute(con, paste(
      "INSERT INTO sessions VALUES (?, 1, ?, 1, 'synthetic', 'none', 'headless',",
      "'synthetic data (analysis/R/simulate.R)', 'none', NULL, ?, ?, 'completed', ?, ?)"),
      params = list(i, i, seed * 1000L + i, calibration,
                    sprintf("2024-01-01T%02d:00:00.000Z", i %% 24), sprintf("2024-01-01T%02d:30:00.000Z", i %% 24)))
    DBI::dbExecute(con, "INSERT INTO blocks VALUES (?, ?, 0, 'main', 0, '{}')", params = list(i, i))
    DBI::dbExecute(con, "INSERT INTO events (session_id, trial_id, t_ns, kind, detail) VALUES (?, NULL, 0, 'observer', ?)",
                   params = list(i, as.character(jsonlite::toJSON(list(
                     model = ob$model, bias_m = ob$bias_m, slope_per_m = ob$slope_per_m,
                     lapse = ob$lapse, criterion_m = ob$criterion_m, seed = seed), auto_unbox = TRUE, digits = NA))))

    cells <- expand.grid(space = spaces, view = views, stringsAsFactors = FALSE)
    respond <- function(x, cell) {
      s <- x + effect_m(cell$space, cell$view)
      latent <- s + ob$bias_m + stats::rnorm(1, 0, 1 / ob$slope_per_m)
      answer <- if (length(options) == 2) {
        if (latent > 0) options[1] else options[2]
      } else {
        if (latent > ob$criterion_m) "convex" else if (latent < -ob$criterion_m) "concave" else "straight"
      }
      if (stats::runif(1) < ob$lapse) answer <- sample(options, 1)
      answer
    }
    rows <- list()
    steps <- list()
    if (judgement == "constant") {
      plan <- do.call(rbind, lapply(seq_len(nrow(cells)), function(k)
        expand.grid(space = cells$space[k], view = cells$view[k], x = levels_m,
                    rep = seq_len(repetitions), stringsAsFactors = FALSE)))
      plan <- plan[sample.int(nrow(plan)), ]
      plan$staircase <- NA_character_
      plan$response <- vapply(seq_len(nrow(plan)), function(k) respond(plan$x[k], plan[k, ]), "")
    } else {
      plan <- NULL
      for (k in seq_len(nrow(cells))) for (name in c("from-convex", "from-concave")) {
        x <- if (name == "from-convex") start_m else -start_m
        last_dir <- 0; reversals <- 0L
        for (step in seq_len(staircase_trials)) {
          answer <- respond(x, cells[k, ])
          positive <- answer == options[1]
          dir <- if (positive) -1 else 1        # 1-up/1-down toward the 50 % point
          is_rev <- last_dir != 0 && dir != last_dir
          if (is_rev) reversals <- reversals + 1L
          size <- step_sizes_m[min(reversals + 1L, length(step_sizes_m))]
          nxt <- min(0.15, max(-0.15, x + dir * size))
          plan <- rbind(plan, data.frame(space = cells$space[k], view = cells$view[k], x = x, rep = step,
                                         staircase = name, response = answer, step = step - 1L,
                                         is_reversal = as.integer(is_rev), next_x = nxt,
                                         correct = as.integer(positive), stringsAsFactors = FALSE))
          last_dir <- dir; x <- nxt
        }
      }
      plan <- plan[sample.int(nrow(plan)), ]  # interleaved
    }
    t0 <- 0
    for (k in seq_len(nrow(plan))) {
      trial_id <- trial_id + 1L
      p <- plan[k, ]
      projection <- if (p$view == "tourist") "tourist" else "native"
      eyes <- if (p$view == "monocular") "dominant" else "both"
      cond <- list(space = p$space, view = p$view, space = p$space, view = p$view,
                   projection = projection, eyes = eyes, judged = "stick")
      cond <- cond[!duplicated(names(cond))]
      if (judgement == "constant") cond <- c(list(sagitta = format(p$x)), cond)
      else cond$staircase <- p$staircase
      stim <- list(stick_sagitta_m = p$x, table_sagitta_m = 0, stick_distance_m = 1, radius_m = 1,
                   tracking = "table-anchored")
      onset <- t0 + 0.5e9
      rt <- round(stats::rlnorm(1, log(0.6), 0.35) * 1e9)
      DBI::dbExecute(con, paste(
        "INSERT INTO trials VALUES (?, ?, ?, ?, ?, ?, ?, 'completed', 1, ?, ?, ?, ?, 'observer', ?)"),
        params = list(trial_id, i, i, k - 1L, k - 1L,
                      as.character(jsonlite::toJSON(cond, auto_unbox = TRUE)),
                      as.character(jsonlite::toJSON(stim, auto_unbox = TRUE, digits = NA)),
                      onset, onset + rt, p$response, rt, "2024-01-01T00:00:00.000Z"))
      if (judgement == "staircase") {
        step_id <- step_id + 1L
        DBI::dbExecute(con, "INSERT INTO staircase_steps VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                       params = list(step_id, i, paste(p$space, p$view, p$staircase), p$step, trial_id,
                                     p$x, p$correct, p$is_reversal, p$next_x))
        DBI::dbExecute(con, "UPDATE trials SET conditions = json_set(conditions, '$.staircase', ?) WHERE trial_id = ?",
                       params = list(paste(p$space, p$view, p$staircase), trial_id))
      }
      t0 <- onset + rt + 0.3e9
    }
    if (tracking) write_synthetic_tracking(con, i, t0)
  }
  invisible(path)
}

# A participant walking slowly round the table's near half while the hands
# reach toward its edge: enough structure for the trajectory figure.
write_synthetic_tracking <- function(con, session_id, duration_ns, rate_hz = 30) {
  n <- max(2L, as.integer(duration_ns / 1e9 * rate_hz))
  t <- round(seq(0, duration_ns, length.out = n))
  a <- seq(-0.6, 0.6, length.out = n) + 0.05 * sin(seq(0, 6 * pi, length.out = n))
  head <- cbind(0 + 1.0 * sin(a), 1.65 + 0.01 * sin(seq_len(n) / 3), -0.9 + 1.0 * cos(a))
  reach <- 0.5 + 0.1 * sin(seq(0, 10 * pi, length.out = n))
  left <- cbind(head[, 1] - 0.2 * cos(a) - reach * sin(a), 1.0, head[, 3] + 0.2 * sin(a) - reach * cos(a))
  right <- cbind(head[, 1] + 0.2 * cos(a) - reach * sin(a), 1.0, head[, 3] - 0.2 * sin(a) - reach * cos(a))
  rows <- do.call(rbind, lapply(list(head = head, left_hand = left, right_hand = right), function(m) m))
  df <- data.frame(session_id = session_id, trial_id = NA_integer_,
                   frame_index = rep(seq_len(n) - 1L, 3), device = rep(c("head", "left_hand", "right_hand"), each = n),
                   t_ns = rep(t, 3), lab_px_m = rows[, 1], lab_py_m = rows[, 2], lab_pz_m = rows[, 3],
                   lab_qx = 0, lab_qy = 0, lab_qz = 0, lab_qw = 1, position_valid = 1L, orientation_valid = 1L,
                   coherence_error_m = abs(stats::rnorm(3 * n, 0, 0.002)))
  DBI::dbWriteTable(con, "tracking_samples", df, append = TRUE)
}
