# Figures (ggplot2, PNG). Each function returns a ggplot object or NULL when
# the data hold nothing to draw; save_figure() writes it.

theme_curvlab <- function() {
  ggplot2::theme_bw(base_size = 11) +
    ggplot2::theme(legend.position = "bottom", strip.background = ggplot2::element_rect(fill = "grey92"),
                   panel.grid.minor = ggplot2::element_blank())
}

response_palette <- function(responses) {
  known <- c(convex = "#d95f02", straight = "#7570b3", concave = "#1b9e77")
  extra <- setdiff(responses, names(known))
  c(known[intersect(names(known), responses)],
    stats::setNames(grDevices::hcl.colors(max(1, length(extra)), "Dark 3")[seq_along(extra)], extra))
}

# Proportion of each judgement by space × view (pooled over participants),
# Wilson 95 % intervals, participants' own proportions as small points.
figure_proportions <- function(trials) {
  d <- analysed_trials(trials)
  if (!nrow(d)) return(NULL)
  for (col in c("cond_space", "cond_view", "cond_judged"))
    if (!col %in% names(d)) d[[col]] <- "all"
  pooled <- response_proportions(d, c("cond_space", "cond_view", "cond_judged"))
  per_p <- response_proportions(d, c("participant", "cond_space", "cond_view", "cond_judged"))
  pal <- response_palette(unique(pooled$response))
  dodge <- ggplot2::position_dodge(width = 0.8)
  facets <- if (length(unique(d$cond_judged)) > 1) ggplot2::facet_grid(cond_judged ~ cond_space, labeller = ggplot2::label_both)
            else ggplot2::facet_grid(. ~ cond_space)
  ggplot2::ggplot(pooled, ggplot2::aes(x = cond_view, y = p, fill = response)) +
    ggplot2::geom_col(position = dodge, width = 0.75, alpha = 0.85) +
    ggplot2::geom_errorbar(ggplot2::aes(ymin = lower, ymax = upper), position = dodge, width = 0.25) +
    ggplot2::geom_point(data = per_p, ggplot2::aes(group = response), colour = "grey15", size = 0.9,
                        alpha = 0.6, position = ggplot2::position_jitterdodge(jitter.width = 0.15, dodge.width = 0.8,
                                                                               seed = 1)) +
    facets + ggplot2::scale_fill_manual(values = pal) +
    ggplot2::scale_y_continuous(limits = c(0, 1), labels = function(v) paste0(100 * v, "%")) +
    ggplot2::labs(x = "view", y = "proportion of trials", fill = "judgement",
                  title = "Judgements by space and view",
                  subtitle = "bars: all participants, 95% Wilson intervals; points: single participants") +
    theme_curvlab()
}

# Psychometric curves: binned proportions (point area = trials) and the
# fitted function per participant, one panel per condition.
figure_psychometric <- function(trials, fits, positive = "convex") {
  bins <- psychometric_bins(trials, positive)
  if (is.null(bins) || !nrow(bins) || !nrow(fits)) return(NULL)
  d <- analysed_trials(trials)
  k_options <- max(option_count(d))
  x_range <- range(bins$x_m)
  grid <- seq(x_range[1], x_range[2], length.out = 200)
  curves <- do.call(rbind, lapply(seq_len(nrow(fits)), function(i) {
    f <- fits[i, ]
    if (is.na(f$pse_m) || is.na(f$slope_per_m)) return(NULL)
    data.frame(participant = f$participant, condition = f$condition, x_m = grid,
               p = psychometric_p(grid, f$pse_m, f$slope_per_m, f$lapse, k_options))
  }))
  pse <- fits[!is.na(fits$pse_m) & fits$pse_m >= x_range[1] & fits$pse_m <= x_range[2], ]
  ggplot2::ggplot(bins, ggplot2::aes(x = 1000 * x_m, y = p, colour = participant)) +
    ggplot2::geom_hline(yintercept = 0.5, colour = "grey70", linetype = "dashed") +
    ggplot2::geom_vline(xintercept = 0, colour = "grey70") +
    ggplot2::geom_point(ggplot2::aes(size = n), alpha = 0.7) +
    ggplot2::geom_line(data = curves, linewidth = 0.8) +
    ggplot2::geom_point(data = pse, ggplot2::aes(x = 1000 * pse_m, y = 0.5), shape = 4, size = 3,
                        stroke = 1.2, inherit.aes = FALSE) +
    ggplot2::facet_wrap(~ condition) +
    ggplot2::scale_size_area(max_size = 4, breaks = integer_breaks) +
    ggplot2::scale_y_continuous(limits = c(0, 1)) +
    ggplot2::labs(x = "shown sagitta (mm, + toward the viewer)", y = paste0("P(", positive, ")"),
                  title = "Psychometric functions", size = "trials",
                  subtitle = "points: proportion per shown level; lines: probit fits with lapse; x: PSE") +
    theme_curvlab()
}

# Staircase tracks: shown intensity against step, reversals marked.
figure_staircases <- function(trials) {
  d <- analysed_trials(trials)
  d <- d[!is.na(d$staircase) & !is.na(d$intensity), , drop = FALSE]
  if (!nrow(d)) return(NULL)
  d$condition <- condition_label(d)
  d$step <- if (all(is.na(d$step_index))) stats::ave(d$trial_index, d$participant, d$staircase, FUN = rank)
            else d$step_index
  d$track <- sub(".*[ :]", "", d$staircase)  # the protocol's staircase name, without the cell
  d$reversal <- !is.na(d$is_reversal) & d$is_reversal == 1
  ggplot2::ggplot(d, ggplot2::aes(x = step, y = 1000 * intensity,
                                  group = interaction(participant, staircase), colour = track)) +
    ggplot2::geom_hline(yintercept = 0, colour = "grey70") +
    ggplot2::geom_step(alpha = 0.8) +
    ggplot2::geom_point(data = d[d$reversal, ], shape = 21, fill = "white", size = 1.8, stroke = 0.9) +
    ggplot2::facet_grid(participant ~ condition) +
    ggplot2::labs(x = "step", y = "shown sagitta (mm)", colour = "staircase",
                  title = "Staircase tracks", subtitle = "open circles: reversals") +
    theme_curvlab()
}

# Legend breaks for counts of trials: whole numbers only (a bin holds 4 or 5
# trials, never 4.25).
integer_breaks <- function(limits) {
  b <- unique(round(pretty(limits, n = 4)))
  b[b >= max(1, ceiling(limits[1])) & b <= floor(limits[2])]
}

# Table outline (lab x–z corners) for a session: its calibration JSON when
# present (every session stores one: the calibration, else the protocol's
# [table] at the lab origin), otherwise a 1.0 m table, the protocols' default.
table_outline <- function(calibration_json) {
  t <- list(centre_x_m = 0, centre_z_m = 0, yaw_rad = 0, edge_m = 1.0)
  if (!is.null(calibration_json) && !is.na(calibration_json)) {
    cal <- tryCatch(jsonlite::fromJSON(calibration_json), error = function(e) list())
    for (k in names(t)) if (!is.null(cal[[k]])) t[[k]] <- as.numeric(cal[[k]])
  }
  h <- t$edge_m / 2
  local <- rbind(c(-h, -h), c(h, -h), c(h, h), c(-h, h), c(-h, -h))
  c_ <- cos(t$yaw_rad); s_ <- sin(t$yaw_rad)
  # The tracking library's rotate_y: x' = c x + s z, z' = -s x + c z.
  data.frame(x = t$centre_x_m + c_ * local[, 1] + s_ * local[, 2],
             z = t$centre_z_m - s_ * local[, 1] + c_ * local[, 2],
             calibrated = !is.null(calibration_json) && !is.na(calibration_json), edge_m = t$edge_m)
}

# Head and hand paths seen from above (lab x right, z toward the
# participant's back, so the table is drawn as the experimenter sees the room
# plan), with the physical table outline.
figure_trajectories <- function(tracking, sessions) {
  if (is.null(tracking) || !nrow(tracking)) return(NULL)
  if (!"participant" %in% names(tracking))
    tracking$participant <- sessions$participant[match(tracking$session_id, sessions$session_id)]
  tracking$panel <- paste0(tracking$participant, " (session ", tracking$session_id, ")")
  tables <- do.call(rbind, lapply(unique(tracking$session_id), function(s) {
    cal <- if ("table_calibration" %in% names(sessions)) sessions$table_calibration[sessions$session_id == s][1] else NA
    cbind(table_outline(cal), panel = tracking$panel[tracking$session_id == s][1])
  }))
  tracking <- tracking[order(tracking$session_id, tracking$device, tracking$t_ns), ]
  starts <- tracking[!duplicated(paste(tracking$session_id, tracking$device)), ]
  ggplot2::ggplot(tracking, ggplot2::aes(x = lab_px_m, y = lab_pz_m, colour = device)) +
    ggplot2::geom_polygon(data = tables, ggplot2::aes(x = x, y = z), inherit.aes = FALSE,
                          fill = "#2e7d32", alpha = 0.25, colour = "#1b5e20") +
    ggplot2::geom_path(alpha = 0.75, linewidth = 0.5) +
    ggplot2::geom_point(data = starts, shape = 17, size = 2.5) +
    ggplot2::facet_wrap(~ panel) + ggplot2::coord_equal() +
    ggplot2::scale_colour_manual(values = c(head = "#333333", left_hand = "#1f78b4", right_hand = "#e31a1c",
                                            other = "#999999")) +
    ggplot2::scale_y_reverse() +
    ggplot2::labs(x = "lab x (m, right)", y = "lab z (m; up the page = forward, -z)", colour = "device",
                  title = "Head and hand paths over the table (top view)",
                  subtitle = paste0("green: the physical table as each session stored it (its calibration, else the protocol's [table] at the lab origin; edge ",
                                    paste(sprintf("%.2f m", sort(unique(tables$edge_m))), collapse = ", "), "); triangles: start")) +
    theme_curvlab()
}

# Response-time distributions by space × view and judgement.
figure_rt <- function(trials) {
  d <- analysed_trials(trials)
  d <- d[!is.na(d$rt_ms) & d$rt_ms > 0, , drop = FALSE]
  if (!nrow(d)) return(NULL)
  for (col in c("cond_space", "cond_view")) if (!col %in% names(d)) d[[col]] <- "all"
  med <- stats::aggregate(rt_ms ~ cond_space + cond_view, d, stats::median)
  ggplot2::ggplot(d, ggplot2::aes(x = rt_ms, fill = response)) +
    ggplot2::geom_histogram(bins = 30, alpha = 0.85, position = "stack") +
    ggplot2::geom_vline(data = med, ggplot2::aes(xintercept = rt_ms), linetype = "dashed") +
    ggplot2::facet_grid(cond_view ~ cond_space) +
    ggplot2::scale_x_log10() +
    ggplot2::scale_fill_manual(values = response_palette(unique(d$response))) +
    ggplot2::labs(x = "response time (ms, log scale)", y = "trials", fill = "judgement",
                  title = "Response times", subtitle = "dashed: median per space and view") +
    theme_curvlab()
}

# Measured against predicted vergence (docs/xr.md, "Eye tracking"), per
# space × view condition: each trial's mean vergence measured by the eye
# tracker during the stimulus (dot) and the vergence demand the perception
# model computed for its stimulus (the onset's percept; open diamond), joined
# by a bar, the difference. Positive converging, negative diverging beyond
# parallel (S3 beyond a quarter circumference). NULL without measured and
# predicted vergence.
figure_vergence <- function(trials) {
  d <- vergence_trials(trials)
  if (!nrow(d)) return(NULL)
  # Trials side by side within their condition's slot, centred on it.
  k <- stats::ave(seq_len(nrow(d)), d$condition, FUN = seq_along)
  n <- stats::ave(seq_len(nrow(d)), d$condition, FUN = length)
  d$x <- as.numeric(factor(d$condition)) + 0.6 * (k - (n + 1) / 2) / n
  ggplot2::ggplot(d, ggplot2::aes(x = x, colour = condition)) +
    ggplot2::geom_hline(yintercept = 0, colour = "grey60") +
    ggplot2::geom_segment(ggplot2::aes(xend = x, y = vergence_demand_arcmin, yend = gaze_vergence_arcmin),
                          linewidth = 2.5, alpha = 0.45) +
    ggplot2::geom_point(ggplot2::aes(y = vergence_demand_arcmin, shape = "predicted (model)"), size = 4, stroke = 1.3) +
    ggplot2::geom_point(ggplot2::aes(y = gaze_vergence_arcmin, shape = "measured (eye tracker)"), size = 3) +
    ggplot2::scale_shape_manual(values = c(`predicted (model)` = 5, `measured (eye tracker)` = 16)) +
    ggplot2::scale_x_continuous(breaks = seq_along(levels(factor(d$condition))), labels = levels(factor(d$condition))) +
    ggplot2::labs(x = "space and view", y = "vergence (arcmin)", colour = "condition", shape = NULL,
                  title = "Vergence: measured against predicted",
                  subtitle = "per trial; positive converging, negative diverging beyond parallel") +
    theme_curvlab()
}

# Completed trials with both a measured and a predicted vergence, labelled
# by their space × view condition.
vergence_trials <- function(trials) {
  if (!all(c("gaze_vergence_arcmin", "vergence_demand_arcmin") %in% names(trials))) return(trials[0, , drop = FALSE])
  d <- trials[trials$status == "completed" & !is.na(trials$gaze_vergence_arcmin) &
                !is.na(trials$vergence_demand_arcmin), , drop = FALSE]
  if (!nrow(d)) return(d)
  cols <- intersect(c("cond_space", "cond_view"), names(d))
  d$condition <- if (length(cols)) do.call(paste, c(unname(as.list(d[cols])), sep = " ")) else "all"
  d
}

save_figure <- function(plot, file, width_in = 9, height_in = 6) {
  if (is.null(plot)) return(NULL)
  grDevices::png(file, width = width_in, height = height_in, units = "in", res = 110, type = "cairo")
  on.exit(grDevices::dev.off())
  print(plot)
  file
}

# Adaptive blocks (staircase, psi): per condition panel, the answers pooled
# over participants in equal-count bins of the shown intensity (point area =
# trials), each participant's fitted curve (thin), the hierarchical model's
# population curve (thick) and its PSE with the 95 % interval (bar at 50 %).
figure_adaptive <- function(trials, fits, hierarchical, positive = "convex", bins = 10L) {
  d <- analysed_trials(trials)
  d <- d[is_adaptive(trial_design(d)) & !is.na(d$x_m), , drop = FALSE]
  if (!nrow(d)) return(NULL)
  d$condition <- condition_label(d)
  d$y <- as.integer(d$response == positive)
  k_options <- max(option_count(d))
  binned <- do.call(rbind, lapply(split(d, d$condition), function(s) {
    b <- if (length(unique(s$x_m)) <= bins) match(s$x_m, sort(unique(s$x_m)))
         else as.integer(cut(rank(s$x_m, ties.method = "first"), bins))
    do.call(rbind, lapply(split(s, b), function(g)
      data.frame(condition = g$condition[1], x_m = mean(g$x_m), n = nrow(g), p = mean(g$y))))
  }))
  grid_for <- function(cond) {
    r <- range(d$x_m[d$condition == cond])
    seq(r[1], r[2], length.out = 200)
  }
  fits <- if (nrow(fits)) fits[fits$condition %in% unique(d$condition) & !is.na(fits$pse_m) & !is.na(fits$slope_per_m), ]
          else fits
  own <- do.call(rbind, lapply(seq_len(nrow(fits)), function(i) {
    f <- fits[i, ]
    x <- grid_for(f$condition)
    data.frame(participant = f$participant, condition = f$condition, x_m = x,
               p = psychometric_p(x, f$pse_m, f$slope_per_m, f$lapse, k_options))
  }))
  pop <- NULL; pse <- NULL
  for (m in hierarchical) {
    p <- m$pse
    if (!nrow(p)) next
    p <- p[!is.na(p$pse_m), , drop = FALSE]
    lambda <- if (is.null(m$lapse)) 0 else m$lapse
    pop <- rbind(pop, do.call(rbind, lapply(seq_len(nrow(p)), function(i) {
      x <- grid_for(p$condition[i])
      data.frame(condition = p$condition[i], x_m = x,
                 p = psychometric_p(x, p$pse_m[i], p$slope_per_m[i], lambda, k_options))
    })))
    pse <- rbind(pse, p[c("condition", "pse_m", "pse_ci_low_m", "pse_ci_high_m")])
  }
  plot <- ggplot2::ggplot(binned, ggplot2::aes(x = 1000 * x_m, y = p)) +
    ggplot2::geom_hline(yintercept = 0.5, colour = "grey70", linetype = "dashed") +
    ggplot2::geom_vline(xintercept = 0, colour = "grey70")
  if (!is.null(own) && nrow(own))
    plot <- plot + ggplot2::geom_line(data = own, ggplot2::aes(group = participant, colour = participant),
                                      linewidth = 0.4, alpha = 0.7)
  plot <- plot + ggplot2::geom_point(ggplot2::aes(size = n), shape = 21, fill = "grey35", colour = "black", alpha = 0.8)
  if (!is.null(pop) && nrow(pop))
    plot <- plot + ggplot2::geom_line(data = pop, linewidth = 1.2, colour = "black")
  if (!is.null(pse) && nrow(pse))
    plot <- plot +
      ggplot2::geom_errorbarh(data = pse, ggplot2::aes(y = 0.5, xmin = 1000 * pse_ci_low_m, xmax = 1000 * pse_ci_high_m),
                              inherit.aes = FALSE, height = 0.06, colour = "#c62828", linewidth = 0.9) +
      ggplot2::geom_point(data = pse, ggplot2::aes(x = 1000 * pse_m, y = 0.5), inherit.aes = FALSE,
                          shape = 23, size = 2.6, fill = "#c62828", colour = "black")
  plot + ggplot2::facet_wrap(~ condition, scales = "free_x") +
    ggplot2::scale_size_area(max_size = 5, breaks = integer_breaks) +
    ggplot2::scale_y_continuous(limits = c(0, 1)) +
    ggplot2::labs(x = "shown sagitta (mm, + toward the viewer)", y = paste0("P(", positive, ")"),
                  title = "Psychometric functions of the adaptive blocks", size = "trials per bin", colour = "participant",
                  subtitle = paste0("points: all participants' answers in equal-count bins; thin lines: each participant's fit;\n",
                                    "thick line: hierarchical model; red: population PSE with 95% interval")) +
    theme_curvlab()
}
