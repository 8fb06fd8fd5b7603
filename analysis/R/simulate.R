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

# A version-4 (random) RFC 9562 UUID that depends only on the seed and the
# session, so a simulated study split over files pools the same way twice.
synthetic_uuid <- function(seed, session) {
  sprintf("%08x-0000-4000-8000-%012x", as.integer(seed %% 2^31), as.integer(session))
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
      "'synthetic data (analysis/R/simulate.R)', 'none', NULL, ?, ?, 'completed', ?, ?, ?)"),
      params = list(i, i, seed * 1000L + i, calibration,
                    sprintf("2024-01-01T%02d:00:00.000Z", i %% 24), sprintf("2024-01-01T%02d:30:00.000Z", i %% 24),
                    synthetic_uuid(seed, i)))
    DBI::dbExecute(con, "INSERT INTO blocks VALUES (?, ?, 0, 'main', 0, '{}')", params = list(i, i))
    DBI::dbExecute(con, "INSERT INTO events (session_id, trial_id, t_ns, kind, detail) VALUES (?, NULL, 0, 'observer', ?)",
                   params = list(i, as.character(jsonlite::toJSON(list(
                     model = ob$model, bias_m = ob$bias_m, slope_per_m = ob$slope_per_m,
                     lapse = ob$lapse, criterion_m = ob$criterion_m, seed = seed), auto_unbox = TRUE, digits = NA))))

    cells <- expand.grid(space = spaces, view = views, stringsAsFactors = FALSE)
    if (judgement == "constant") {
      plan <- simulate_constant_plan(ob, cells, levels_m, repetitions, options, effect_m)
    } else {
      plan <- NULL
      for (k in seq_len(nrow(cells))) for (name in c("from-convex", "from-concave")) {
        x <- if (name == "from-convex") start_m else -start_m
        last_dir <- 0; reversals <- 0L
        for (step in seq_len(staircase_trials)) {
          answer <- observer_response(x + effect_m(cells$space[k], cells$view[k]), ob, options)
          positive <- answer == options[1]
          dir <- if (positive) -1 else 1        # 1-up/1-down toward the 50 % point
          is_rev <- last_dir != 0 && dir != last_dir
          if (is_rev) reversals <- reversals + 1L
          size <- step_sizes_m[min(reversals + 1L, length(step_sizes_m))]
          nxt <- min(0.15, max(-0.15, x + dir * size))
          plan <- rbind(plan, data.frame(space = cells$space[k], view = cells$view[k], x = x,
                                         staircase = paste(cells$space[k], cells$view[k], name),
                                         response = answer, step = step - 1L,
                                         is_reversal = as.integer(is_rev), next_x = nxt,
                                         correct = as.integer(positive), stringsAsFactors = FALSE))
          last_dir <- dir; x <- nxt
        }
      }
      plan <- plan[sample.int(nrow(plan)), ]  # interleaved
    }
    n <- nrow(plan)
    ids <- trial_id + seq_len(n)
    trial_id <- trial_id + n
    rt <- round(stats::rlnorm(n, log(0.6), 0.35) * 1e9)
    gap <- 0.5e9 + 0.3e9
    onset <- cumsum(c(0.5e9, utils::head(rt, -1) + gap))
    cond <- vapply(seq_len(n), function(k) {
      c_ <- list(space = plan$space[k], view = plan$view[k],
                 projection = if (plan$view[k] == "tourist") "tourist" else "native",
                 eyes = if (plan$view[k] == "monocular") "dominant" else "both", judged = "stick")
      if (judgement == "constant") c_ <- c(list(sagitta = format(plan$x[k])), c_)
      else c_$staircase <- plan$staircase[k]
      as.character(jsonlite::toJSON(c_, auto_unbox = TRUE))
    }, "")
    stim <- vapply(plan$x, function(x) as.character(jsonlite::toJSON(list(
      stick_sagitta_m = x, table_sagitta_m = 0, stick_distance_m = 1, radius_m = 1,
      tracking = "table-anchored"), auto_unbox = TRUE, digits = NA)), "")
    DBI::dbWriteTable(con, "trials", data.frame(
      trial_id = ids, session_id = i, block_id = i, trial_index = seq_len(n) - 1L,
      trial_in_block = seq_len(n) - 1L, conditions = cond, stimulus = stim, status = "completed",
      attempt = 1L, onset_ns = onset, response_ns = onset + rt, response = plan$response, rt_ns = rt,
      response_device = "observer", completed_utc = "2024-01-01T00:00:00.000Z"), append = TRUE)
    if (judgement == "staircase") {
      DBI::dbWriteTable(con, "staircase_steps", data.frame(
        step_id = step_id + seq_len(n), session_id = i, staircase = plan$staircase, step_index = plan$step,
        trial_id = ids, intensity = plan$x, response_correct = plan$correct,
        is_reversal = plan$is_reversal, next_intensity = plan$next_x), append = TRUE)
      step_id <- step_id + n
    }
    t0 <- onset[n] + rt[n] + gap
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

# One simulated observer's answer to each shown (perceived) sagitta x.
observer_response <- function(x, ob, options = c("convex", "concave")) {
  latent <- x + ob$bias_m + stats::rnorm(length(x), 0, 1 / ob$slope_per_m)
  answer <- if (length(options) == 2) ifelse(latent > 0, options[1], options[2])
            else ifelse(latent > ob$criterion_m, "convex", ifelse(latent < -ob$criterion_m, "concave", "straight"))
  lapsed <- stats::runif(length(x)) < ob$lapse
  answer[lapsed] <- sample(options, sum(lapsed), replace = TRUE)
  answer
}

simulate_constant_plan <- function(ob, cells, levels_m, repetitions, options, effect_m) {
  plan <- do.call(rbind, lapply(seq_len(nrow(cells)), function(k)
    expand.grid(space = cells$space[k], view = cells$view[k], x = levels_m,
                rep = seq_len(repetitions), stringsAsFactors = FALSE)))
  plan <- plan[sample.int(nrow(plan)), ]
  shift <- mapply(effect_m, plan$space, plan$view)
  plan$response <- observer_response(plan$x + shift, ob, options)
  plan
}

# Trials in memory with the columns the analysis uses (no database): fast
# enough for the many replicates of a null simulation.
simulate_trials <- function(observers, spaces = "E3", views = "tourist", levels_m = 0,
                            repetitions = 10L, options = c("convex", "straight", "concave"),
                            effect_m = function(space, view) 0) {
  if (is.null(observers$criterion_m)) observers$criterion_m <- 0.005
  cells <- expand.grid(space = spaces, view = views, stringsAsFactors = FALSE)
  do.call(rbind, lapply(seq_len(nrow(observers)), function(i) {
    plan <- simulate_constant_plan(observers[i, ], cells, levels_m, repetitions, options, effect_m)
    data.frame(participant = observers$participant[i], status = "completed", is_practice = 0L,
               protocol_sha256 = "synthetic", block_name = "main", response = plan$response,
               cond_space = plan$space, cond_view = plan$view, cond_judged = "stick",
               x_m = plan$x, staircase = NA_character_, intensity = NA_real_, stringsAsFactors = FALSE)
  }))
}
