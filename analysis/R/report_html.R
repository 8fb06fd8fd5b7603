# The analysis report: one self-contained HTML file (figures embedded as
# base64 PNG, no external files, no pandoc), plus the figures and tables as
# separate PNG and CSV files next to it for reuse in papers.

html_escape <- function(x) {
  x <- gsub("&", "&amp;", as.character(x), fixed = TRUE)
  x <- gsub("<", "&lt;", x, fixed = TRUE)
  x <- gsub(">", "&gt;", x, fixed = TRUE)
  gsub("\"", "&quot;", x, fixed = TRUE)
}

format_cell <- function(v, digits = 4) {
  if (is.numeric(v)) {
    # Fixed notation, except for magnitudes below 1e-4 (e.g. a difference
    # of 1e-16 that is zero up to rounding), which get an exponent.
    small <- !is.na(v) & v != 0 & abs(v) < 1e-4
    out <- ifelse(is.na(v), "NA", ifelse(small, formatC(v, format = "g", digits = digits),
                                         formatC(signif(v, digits), format = "fg", digits = digits, flag = "#")))
    out <- sub("\\.$", "", out)
    ifelse(!is.na(v) & v == round(v) & abs(v) < 1e9, format(round(v), scientific = FALSE, trim = TRUE), out)
  } else ifelse(is.na(v), "NA", as.character(v))
}

# A table in a horizontally scrolling box, so a wide one never widens the
# page. `titles`: optional data frame of the same shape whose non-NA cells
# become the cells' title attributes (the full value of a shortened one).
# `wrap`: names of columns whose long values may break anywhere (hardware
# names, commits, seeds); header names may break after an underscore.
html_table <- function(df, caption = NULL, digits = 4, titles = NULL, class = NULL, wrap = character(0)) {
  if (is.null(df) || !nrow(df)) return("<p class=\"empty\">(nothing to show)</p>")
  head <- paste0("<tr>", paste0("<th>", gsub("_", "_<wbr>", html_escape(names(df)), fixed = TRUE), "</th>",
                                collapse = ""), "</tr>")
  cells <- vapply(df, function(col) html_escape(format_cell(col, digits)), character(nrow(df)))
  if (is.null(dim(cells))) cells <- matrix(cells, nrow = nrow(df))
  attrs <- matrix("", nrow(df), ncol(df))
  attrs[, names(df) %in% wrap] <- " class=\"wrap\""
  if (!is.null(titles))
    for (j in seq_len(ncol(df))) {
      t <- titles[[j]]
      attrs[!is.na(t), j] <- paste0(attrs[!is.na(t), j], " title=\"", html_escape(t[!is.na(t)]), "\"")
    }
  open <- matrix(paste0("<td", attrs, ">"), nrow(df))
  body <- paste0("<tr>", vapply(seq_len(nrow(df)), function(i) paste0(open[i, ], cells[i, ], "</td>", collapse = ""), ""),
                 "</tr>", collapse = "\n")
  paste0("<div class=\"scroll\"><table", if (!is.null(class)) paste0(" class=\"", class, "\""), ">",
         if (!is.null(caption)) paste0("<caption>", html_escape(caption), "</caption>"),
         "<thead>", head, "</thead><tbody>", body, "</tbody></table></div>")
}

# First 12 hex digits of a hash (the full value goes in the cell's title).
short_hash <- function(x) ifelse(is.na(x), NA_character_, substr(x, 1, 12))

html_figure <- function(file, caption) {
  if (is.null(file) || !file.exists(file)) return("")
  data <- jsonlite::base64_enc(readBin(file, "raw", file.info(file)$size))
  paste0("<figure><img alt=\"", html_escape(caption), "\" src=\"data:image/png;base64,", data,
         "\"><figcaption>", html_escape(caption), "</figcaption></figure>")
}

report_css <- paste(
  "body{font-family:system-ui,-apple-system,'DejaVu Sans',sans-serif;max-width:1200px;margin:2em auto;",
  "padding:0 1em;color:#222;line-height:1.45}",
  "h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}",
  "table{border-collapse:collapse;margin:.8em 0;font-size:.85em}",
  "th,td{border:1px solid #ddd;padding:.25em .5em;text-align:right}",
  "th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}",
  "caption{caption-side:top;text-align:left;font-weight:600;padding:.3em 0}",
  "figure{margin:1em 0}img{max-width:100%;border:1px solid #eee}figcaption{font-size:.9em;color:#555}",
  ".note{background:#fff8e1;border-left:4px solid #f9a825;padding:.4em .8em;margin:.5em 0}",
  ".empty{color:#888}code{background:#f4f4f4;padding:0 .2em}",
  ".scroll{max-width:100%;overflow-x:auto}",
  "table.provenance{font-size:.8em}table.provenance td,table.provenance th{text-align:left;padding:.2em .35em}",
  "table.provenance td.wrap{min-width:5em;max-width:9em;overflow-wrap:anywhere}",
  ".method{background:#eef5fb;border-left:4px solid #4a90c2;padding:.4em .8em;margin:.5em 0}",
  "ol.fit-notes{font-size:.85em;color:#444;max-width:60em}",
  ".warning{background:#fdecea;border-left:4px solid #c62828;padding:.4em .8em;margin:.5em 0}")

# Writes report.html (and the PNG/CSV files) into out_dir; returns its path.
build_report <- function(data, out_dir, positive = "convex", lapse = "free", lapse_max = 0.1,
                         discard_reversals = 2L) {
  dir.create(out_dir, recursive = TRUE, showWarnings = FALSE)
  if (!dir.exists(out_dir) || file.access(out_dir, 2) != 0)
    stop(paste0(out_dir, ": cannot write the report here (expected a writable folder)"))
  trials <- data$trials
  trials$design <- trial_design(trials)
  analysed <- analysed_trials(trials)
  cond_cols <- condition_columns(trials)
  fac <- intersect(c("cond_space", "cond_view", "cond_judged"), names(trials))

  # Each block is analysed by its design (design.R): proportions and the
  # space × view choice models for constant stimuli only; psychometric
  # functions for every design, and the hierarchical psychometric model for
  # adaptive blocks, where proportions depend on the answers themselves.
  designs <- design_summary(trials)
  constant <- trials[trials$design == "constant", , drop = FALSE]
  adaptive_n <- sum(is_adaptive(analysed$design))
  props <- response_proportions(constant, c("participant", cond_cols))
  props_pooled <- response_proportions(constant, fac)
  fits <- psychometric_fits(trials, positive, lapse, lapse_max)
  thresholds <- staircase_thresholds(trials, discard_reversals)
  models <- space_view_models(constant, positive)
  hierarchical <- psychometric_hierarchical(trials, positive, lapse, lapse_max)
  estimates <- adaptive_estimates(fits, thresholds)
  truth <- observer_truth(data)

  fig <- function(name) file.path(out_dir, name)
  n_panels <- function(k) max(1, ceiling(sqrt(k)))
  figures <- list(
    list(save_figure(figure_proportions(constant), fig("proportions.png"), 10, 5.5),
         "Proportion of each judgement by space (panels) and view (x axis), pooled over participants with 95% Wilson intervals; points are single participants."),
    list(save_figure(figure_psychometric(trials, fits, positive), fig("psychometric.png"), 10,
                     2.5 + 3 * n_panels(length(unique(fits$condition)))),
         paste0("Psychometric functions: proportion of '", positive, "' per shown sagitta (point area = trials) with the fitted probit-with-lapse curve per participant; crosses mark the PSEs.")),
    list(save_figure(figure_adaptive(trials, fits, hierarchical, positive), fig("psychometric_adaptive.png"), 10,
                     2.5 + 3 * n_panels(length(unique(condition_label(analysed[is_adaptive(analysed$design), , drop = FALSE]))))),
         paste0("Adaptive blocks: proportion of '", positive, "' in equal-count bins of the shown sagitta (all participants; point area = trials), ",
                "each participant's fit (thin lines), the hierarchical model's population curve (thick) and its PSE with the 95% interval (red).")),
    list(save_figure(figure_staircases(trials), fig("staircases.png"), 10,
                     2 + 1.6 * length(unique(stats::na.omit(analysed$participant[!is.na(analysed$staircase)])))),
         "Staircase tracks: shown sagitta against step for every staircase; open circles are reversals."),
    list(save_figure(figure_trajectories(data$tracking, data$sessions), fig("trajectories.png"), 10, 7),
         paste0("Head and hand positions over the physical table, seen from above (lab x right, forward up the page)",
                if (isTRUE(data$tracking_stride > 1)) sprintf("; every %d-th sample drawn", data$tracking_stride) else "", ".")),
    list(save_figure(figure_rt(trials), fig("rt.png"), 10, 6),
         "Response-time distributions per space (columns) and view (rows), stacked by judgement; dashed lines are medians."),
    list(save_figure(figure_vergence(trials), fig("vergence.png"), 9, 6),
         paste("Vergence per trial and condition: measured by the headset's eye tracker, mean over the trial's stimulus (dots),",
               "and the vergence the perception model says the stimulus demands (the onset's percept; open diamonds), the bar",
               "between them their difference. Positive: converging; negative: diverging beyond parallel."))
  )
  figures <- figures[!vapply(figures, function(f) is.null(f[[1]]), TRUE)]

  utils::write.csv(props, fig("proportions.csv"), row.names = FALSE)
  utils::write.csv(fits, fig("psychometric_fits.csv"), row.names = FALSE)
  if (nrow(thresholds)) utils::write.csv(thresholds, fig("staircase_thresholds.csv"), row.names = FALSE)
  hier_table <- hierarchical_table(hierarchical)
  if (nrow(hier_table)) utils::write.csv(hier_table, fig("psychometric_model.csv"), row.names = FALSE)
  if (nrow(estimates)) utils::write.csv(estimates, fig("adaptive_estimates.csv"), row.names = FALSE)

  s <- data$sessions
  provenance <- provenance_html(s, trials)
  model_html <- vapply(models, model_section_html, "")
  utils::write.csv(models_table(models), fig("models.csv"), row.names = FALSE)

  truth_html <- if (!is.null(truth) && nrow(truth)) {
    cmp <- truth
    cmp$true_pse_m <- -cmp$bias_m
    if (nrow(fits) && any(stats::complete.cases(fits[c("pse_m", "slope_per_m")]))) {
      agg <- stats::aggregate(cbind(pse_m, slope_per_m) ~ participant, fits, mean)
      cmp <- merge(cmp, agg, by = "participant", all.x = TRUE)
      names(cmp)[names(cmp) == "pse_m"] <- "mean_fitted_pse_m"
      names(cmp)[names(cmp) == "slope_per_m"] <- "mean_fitted_slope_per_m"
    }
    paste0("<h2>Simulated observers</h2><p>These sessions were answered by curvlab's simulated observer; ",
           "its parameters are the ground truth for the fits (for a 2-option judgement in E3 the PSE is -bias_m ",
           "and the probit slope is slope_per_m; in curved spaces the perception model adds the perceived bend).</p>",
           html_table(cmp, "Observer parameters and fits averaged over conditions"))
  } else ""

  body <- c(
    "<h1>curvlab analysis report</h1>",
    paste0("<p>Source: <code>", html_escape(data$source), "</code> (", data$kind, "); generated ",
           format(Sys.time(), "%Y-%m-%d %H:%M:%S %Z"), " with R ", html_escape(getRversion()), ", lme4 ",
           html_escape(utils::packageVersion("lme4")), ". ", nrow(analysed), " completed non-practice trials of ",
           nrow(trials), " planned, ", length(unique(analysed$participant)), " participant(s), ",
           nrow(s), " session(s).</p>"),
    protocol_warnings_html(s),
    if (data$kind == "export") "<p class=\"note\">Read from an export directory: trials.csv carries no protocol name, software, renderer or seed; run the report on the database for full provenance.</p>" else "",
    "<h2>Sessions and provenance</h2>", provenance,
    "<h2>Designs</h2>",
    "<p class=\"method\">The design of each judgement block is read from the data: <strong>adaptive</strong> (staircase, psi) when its trials have staircase steps, the shown intensity then depending on the previous answers; <strong>constant stimuli</strong> otherwise. Proportions of answers and the space &times; view choice models describe constant-stimulus blocks only; adaptive blocks are analysed by psychometric functions of the shown intensity, per participant and condition and in a hierarchical model across participants.</p>",
    html_table(designs, "Judgement blocks by design (completed, answered, non-practice trials)"),
    "<h2>Judgements</h2>",
    if (adaptive_n) sprintf("<p class=\"note\">%d trials of adaptive blocks are left out of the proportions: under an adaptive method the share of an answer depends on the answers themselves (a staircase converges on 50%%). Their analysis is under <em>Adaptive blocks</em>.</p>", adaptive_n) else "",
    vapply(figures[grepl("proportions", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
    if (nrow(constant) && nrow(props)) c(html_table(props_pooled, "Proportions pooled over participants (95% Wilson intervals)"),
                                         html_table(props, "Proportions per participant and condition (also in proportions.csv)"))
    else "<p class=\"empty\">(no constant-stimulus blocks)</p>",
    "<h2>Psychometric fits</h2>",
    paste0("<p>Model: P(", html_escape(positive), ") = &lambda;/K + (1 &minus; &lambda;) &Phi;(&beta;(x &minus; PSE)), x the shown signed sagitta in metres, ",
           "K the number of answer options, &lambda; the lapse rate (", if (lapse == "free") sprintf("fitted by maximum likelihood in [0, %g]", lapse_max) else "fixed at 0: probit GLM",
           "). Standard errors from the observed information. Fitted wherever the shown sagitta takes three or more values in a participant &times; condition cell (constant-stimulus levels or staircase steps pooled).</p>"),
    vapply(figures[grepl("psychometric", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
    fits_table_html(fits, "PSE (m) and slope (1/m) per participant and condition, 95% Wald intervals"),
    if (length(hierarchical)) adaptive_section_html(hierarchical, estimates, figures) else "",
    if (nrow(thresholds)) c("<h2>Staircases</h2>",
                            vapply(figures[grepl("staircases", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
                            html_table(thresholds, sprintf(paste0("Per track: reversal-mean threshold (first %d reversals discarded; SE = SD/sqrt(n)), ",
                                                                  "the intensity the track ended on, and the posterior PSE where the method stores one"),
                                                           discard_reversals))) else "",
    "<h2>Models: space &times; view</h2>",
    if (length(models)) c(models_intro_html(models), model_html)
    else if (adaptive_n) "<p class=\"empty\">(no constant-stimulus blocks: the adaptive blocks' conditions are compared by their PSEs under <em>Adaptive blocks</em>, not by a choice model, whose odds ratios would depend on where the adaptive method placed the trials)</p>"
    else "<p class=\"empty\">(no model: no completed trials)</p>",
    truth_html,
    play_section_html(data$play, analysed, positive),
    questionnaire_section_html(data$questionnaires),
    "<h2>Tracking</h2>",
    vapply(figures[grepl("trajectories", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
    if (!any(grepl("trajectories", vapply(figures, `[[`, "", 1)))) "<p class=\"empty\">(no tracking samples in this source)</p>" else "",
    if (any(grepl("vergence\\.png", vapply(figures, `[[`, "", 1)))) {
      v <- vergence_trials(trials)
      agg <- stats::aggregate(cbind(vergence_demand_arcmin, gaze_vergence_arcmin, gaze_valid_samples) ~ condition, v, mean)
      agg$trials <- as.vector(table(factor(v$condition, agg$condition)))
      utils::write.csv(agg, fig("vergence.csv"), row.names = FALSE)
      c("<h2>Eye tracking: vergence</h2>",
        vapply(figures[grepl("vergence\\.png", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
        html_table(agg, "Mean predicted and measured vergence (arcmin) and valid samples per condition (also in vergence.csv)"))
    } else "",
    "<h2>Response times</h2>",
    vapply(figures[grepl("rt\\.png", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""))
  html <- paste0("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>curvlab report</title><style>",
                 report_css, "</style></head><body>\n", paste(body, collapse = "\n"), "\n</body></html>\n")
  out <- file.path(out_dir, "report.html")
  writeLines(html, out, useBytes = TRUE)
  invisible(list(report = out, models_csv = fig("models.csv"), figures = vapply(figures, `[[`, "", 1), fits = fits, models = models,
                 proportions = props, thresholds = thresholds, hierarchical = hierarchical, designs = designs,
                 estimates = estimates))
}

# The adaptive blocks' section: the hierarchical model's PSE and slope per
# condition, PSE differences, participant variation, the figure, and the
# per-participant PSE beside the staircase's own estimates.
adaptive_section_html <- function(hierarchical, estimates, figures) {
  parts <- vapply(hierarchical, function(m) {
    sep <- if (isTRUE(m$separation$separated))
      paste0("<p class=\"note\"><strong>Separation detected</strong>: ", html_escape(separation_words(m$separation)), ".</p>")
    else "<p>No separation: the maximum-likelihood estimates exist.</p>"
    paste0("<h3>", html_escape(m$outcome), " — judged: ", html_escape(m$judged), "</h3>",
           "<p>Model: &Phi;<sup>&minus;1</sup>(P) = a<sub>c</sub> + b<sub>c</sub>&middot;z, an intercept a and a slope b ",
           "for each condition c (probit), with z = (x &minus; ", sprintf("%.4g", m$centre_m),
           " m) / ", sprintf("%.4g", m$scale_m), " m the shown sagitta standardised; ", m$n, " trials, ",
           m$participants, " participant(s). <details><summary>as R writes it</summary><code>",
           html_escape(m$formula), "</code></details></p>",
           sep,
           paste0("<p class=\"method\">", html_escape(c(m$method, m$methods)), "</p>", collapse = ""),
           paste0("<p class=\"note\">", html_escape(m$notes), "</p>", collapse = ""),
           html_table(m$pse, "Population PSE (m) and slope (1/m) per condition, 95% delta-method intervals"),
           html_table(m$differences, "PSE differences between conditions that differ in one factor (m), delta method"),
           html_table(m$random, "Participant variation (standard deviations; slope in 1/m)"))
  }, "")
  c("<h2>Adaptive blocks: psychometric functions</h2>",
    paste0("<p class=\"method\">Each participant &times; condition is fitted by the psychometric function above (all tracks of the condition pooled; ",
           "the lapse rate bounded). Across participants, a hierarchical probit model (lme4::glmer) has one intercept and one slope per condition, ",
           "and per participant a random intercept and a random slope on the shown intensity, with a common lapse rate chosen by profile likelihood; ",
           "the population PSE of a condition is where its curve crosses the midpoint, with a delta-method interval. The staircase reversal means ",
           "(and a psi method's posterior PSE) are a second, model-free estimate.</p>"),
    vapply(figures[grepl("psychometric_adaptive", vapply(figures, `[[`, "", 1))], function(f) html_figure(f[[1]], f[[2]]), ""),
    parts,
    if (nrow(estimates) && any(estimates$tracks_agree %in% FALSE))
      paste0("<p class=\"note\"><strong>Tracks disagree</strong> in ", sum(estimates$tracks_agree %in% FALSE), " of ",
             nrow(estimates), " participant &times; condition cells: their staircases settled on intensities further apart ",
             "than 4 SE of the difference, so the judgement is not one increasing function of the intensity there (two ",
             "crossing points, or a drift), and a single PSE does not describe the cell. Read the tracks (Staircases) ",
             "before the fits.</p>") else "",
    html_table(estimates, "Per participant and condition: fitted PSE (95% interval) beside the mean over tracks of the reversal-mean threshold, the final intensity and the posterior PSE (also in adaptive_estimates.csv)"))
}

# Fitted PSE per participant × condition beside the adaptive method's own
# estimates averaged over the condition's tracks.
adaptive_estimates <- function(fits, thresholds) {
  if (!nrow(thresholds) || !nrow(fits)) return(data.frame())
  mean_or_na <- function(v) if (all(is.na(v))) NA_real_ else mean(v, na.rm = TRUE)
  keys <- unique(thresholds[c("participant", "condition")])
  rows <- lapply(seq_len(nrow(keys)), function(i) {
    th <- thresholds[thresholds$participant == keys$participant[i] & thresholds$condition == keys$condition[i], ]
    f <- fits[fits$participant == keys$participant[i] & fits$condition == keys$condition[i], ]
    # Tracks of one condition that settle on clearly different intensities
    # (reversal means further apart than 4 SE of their difference) mean the
    # judgement is not one monotone function of the intensity there (or it
    # drifted): one PSE does not describe that condition.
    ok <- !is.na(th$threshold_m) & !is.na(th$threshold_se_m)
    disagree <- if (sum(ok) >= 2) {
      r <- th[ok, ]
      lo <- which.min(r$threshold_m); hi <- which.max(r$threshold_m)
      (r$threshold_m[hi] - r$threshold_m[lo]) > 4 * sqrt(r$threshold_se_m[hi]^2 + r$threshold_se_m[lo]^2)
    } else NA
    data.frame(participant = keys$participant[i], condition = keys$condition[i], method = th$method[1],
               tracks = nrow(th), tracks_agree = !disagree,
               fitted_pse_m = if (nrow(f)) f$pse_m[1] else NA_real_,
               fitted_pse_ci_low_m = if (nrow(f)) f$pse_ci_low_m[1] else NA_real_,
               fitted_pse_ci_high_m = if (nrow(f)) f$pse_ci_high_m[1] else NA_real_,
               reversal_mean_m = mean_or_na(th$threshold_m), final_m = mean_or_na(th$final_m),
               posterior_pse_m = mean_or_na(th$posterior_pse_m), stringsAsFactors = FALSE)
  })
  out <- do.call(rbind, rows)
  out <- out[order(out$participant, out$condition), , drop = FALSE]
  rownames(out) <- NULL
  out
}

# Provenance per session, sized for a laptop screen: hashes and commits
# shortened to 12 hex digits (the full value in the cell's title, shown on
# hover), long cells wrapped, and the whole table scrolling sideways in its
# box if it is still too wide.
provenance_html <- function(s, trials) {
  count <- function(ok) vapply(s$session_id, function(id) sum(trials$session_id == id & ok), 0L)
  uuid <- if (is.null(s$session_uuid)) rep(NA_character_, nrow(s)) else s$session_uuid
  table <- data.frame(
    session = ifelse(is.na(uuid), as.character(s$session_id), substr(uuid, 1, 8)),
    participant = s$participant, protocol = s$protocol_name,
    protocol_sha256 = short_hash(s$protocol_sha256),
    software = paste(s$software_version, short_hash(s$software_commit)),
    backend = s$backend, renderer = paste(s$renderer_device, s$renderer_driver, sep = " / "),
    seed = s$seed, started_utc = s$started_utc, status = s$status,
    completed = paste0(s$trials_completed, " / ", s$trials_planned),
    no_answer = count(trials$status == "completed" & no_answer(trials)),
    # Given up after tracking loss or max_attempts (tracking.on_loss, docs/protocols.md).
    aborted = count(trials$status == "aborted"),
    # Completed with the head lost for longer than tracking.loss_ms (on_loss = "flag").
    tracking_flagged = count(trials$status == "completed" & !is.na(trials$tracking_lost_ms)))
  titles <- as.data.frame(lapply(table, function(col) rep(NA_character_, nrow(table))))
  titles$session <- uuid
  titles$protocol_sha256 <- s$protocol_sha256
  titles$software <- paste(s$software_version, s$software_commit)
  html_table(table, titles = titles, class = "provenance", wrap = c("software", "renderer", "seed", "started_utc"))
}

models_intro_html <- function(models) {
  separated <- vapply(models, function(m) isTRUE(m$separation$separated), TRUE)
  flag <- if (any(separated))
    paste0("<p class=\"note\"><strong>Separation</strong> in ", sum(separated), " of ", length(models),
           " model(s): in some condition every answer is the same, so maximum-likelihood estimates are infinite ",
           "and their Wald statistics meaningless. These models are reported with the finite methods below.</p>")
  else ""
  paste0(flag, "<p class=\"method\">Every model is checked for separation with a linear programme (Konis 2007). ",
         "Each is fitted as a <strong>bias-reduced logistic GLM</strong> (brglm2, mean bias reduction, which for ",
         "the logit link maximises the Jeffreys-penalised likelihood and always gives finite estimates; Firth 1993, ",
         "Kosmidis &amp; Firth 2021) pooling participants, with <strong>profile penalised-likelihood</strong> 95% ",
         "intervals and tests (Heinze &amp; Schemper 2002); the per-space view contrasts (emmeans) are log odds ",
         "ratios from this fit. The <strong>mixed model</strong> (random intercept per participant) is fitted by ",
         "maximum likelihood (glmer) when the data are not separated, and with weakly informative priors ",
         "(blme::bglmer, N(0, 2.5&sup2;) on each effect, N(0, 10&sup2;) on the intercept, logit scale) when they ",
         "are or when glmer fails. All estimates, intervals and the method of each row are in models.csv.</p>")
}

model_section_html <- function(m) {
  sep <- if (isTRUE(m$separation$separated))
    paste0("<p class=\"note\"><strong>Separation detected</strong>: ", html_escape(separation_words(m$separation)), ".</p>")
  else "<p>No separation: the maximum-likelihood estimates exist.</p>"
  # Odds ratios only of estimates that do not diverge (mask_diverging has
  # already removed those numbers); a diverging row says so instead.
  show <- function(t) {
    if (!nrow(t)) return(t)
    if (!is.null(t$diverges)) {
      t$note <- ifelse(t$diverges, "diverges: not estimable (separation)", "")
      t$diverges <- NULL
    }
    t
  }
  contrasts <- m$contrasts
  if (nrow(contrasts))
    contrasts$odds_ratio <- ifelse(is.finite(contrasts$estimate) & abs(contrasts$estimate) <= max_abs_logit,
                                   exp(contrasts$estimate), NA_real_)
  contrasts <- show(contrasts)
  m$fixed <- show(m$fixed)
  m$coefficients <- show(m$coefficients)
  paste0("<h3>", html_escape(m$outcome), " — judged: ", html_escape(m$judged), "</h3>",
         "<p><code>", html_escape(m$formula), "</code>, ", html_escape(m$family), "; ",
         m$n, " trials, ", m$participants, " participant(s)",
         if (!is.na(m$random_sd)) sprintf("; participant SD (logit units) %.3g", m$random_sd) else "", ".</p>",
         sep,
         paste0("<p class=\"method\">", html_escape(m$methods), "</p>", collapse = ""),
         paste0("<p class=\"note\">", html_escape(m$notes), "</p>", collapse = ""),
         html_table(contrasts, paste("Per-space view contrasts: log odds ratios (and odds ratios) with profile",
                                     "penalised-likelihood 95% CIs, bias-reduced GLM")),
         html_table(m$fixed, "Bias-reduced logistic GLM (participants pooled): coefficients, logit units, profile 95% CIs"),
         if (isTRUE(m$mixed_is_fixed)) "<p>One participant: no mixed model; the bias-reduced GLM above is the model.</p>"
         else html_table(m$coefficients, paste0("Mixed model: ", if (is.null(m$mixed_method)) "none" else m$mixed_method)),
         html_table(m$tests, "Tests against the model without these terms"))
}

# The warnings curvlab gave the protocol when its sessions started (the human
# observer model's range of validity: stored with each session_start event),
# repeated before any result, once each.
protocol_warnings_html <- function(sessions) {
  if (is.null(sessions$protocol_warnings)) return("")
  texts <- unlist(lapply(stats::na.omit(sessions$protocol_warnings), function(j) {
    w <- tryCatch(jsonlite::fromJSON(j), error = function(e) character())
    as.character(w)
  }))
  texts <- unique(texts)
  if (!length(texts)) return("")
  paste0("<div class=\"warning\"><p><strong>Warnings about the protocol</strong> (given by curvlab when the sessions ",
         "started; simulated participants answered with the model these concern):</p><ul>",
         paste0("<li>", html_escape(texts), "</li>", collapse = ""), "</ul></div>")
}

# The per-participant fits with their notes below the table, numbered, so
# that a long note neither makes its row hundreds of pixels tall nor pushes
# the table off the page's right edge.
fits_table_html <- function(fits, caption) {
  if (!nrow(fits) || !"note" %in% names(fits)) return(html_table(fits, caption))
  has <- !is.na(fits$note) & nzchar(fits$note)
  shown <- fits
  shown$note <- ifelse(has, paste0("note ", cumsum(has)), "")
  notes <- paste0("<li>", html_escape(paste0(fits$participant[has], ", ", fits$condition[has], ": ", fits$note[has])),
                  "</li>", collapse = "")
  paste0(html_table(shown, caption), if (any(has)) paste0("<ol class=\"fit-notes\">", notes, "</ol>") else "")
}
