# Analysis per design: adaptive blocks (staircase, psi) are told from
# constant-stimulus blocks by their data, and get psychometric functions per
# participant and condition plus a hierarchical probit model instead of the
# choice GLM; separated data are reported as such with no absurd number.
#   Rscript tests/analysis/test_adaptive.R SOURCE_ROOT [CURVLAB_BINARY]
# Tolerances: population PSEs and their differences within 3 of their own
# SEs of the truth (the mean of the simulated observers' -bias, minus the
# condition's perceived bend), slopes within 3 SE; about 1 % chance of a
# false failure over the 12 checks.
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))
read_html <- function(dir) paste(readLines(file.path(dir, "report.html"), warn = FALSE), collapse = "\n")
# Every number in the HTML tables' odds_ratio column, and any infinite cell.
odds_ratios <- function(html) {
  tables <- regmatches(html, gregexpr("<table.*?</table>", html))[[1]]
  unlist(lapply(tables, function(t) {
    rows <- regmatches(t, gregexpr("<tr>.*?</tr>", t))[[1]]
    cells <- lapply(rows, function(r) gsub("<[^>]*>", "", regmatches(r, gregexpr("<t([hd])[^>]*>.*?</t\\1>", r, perl = TRUE))[[1]]))
    header <- gsub("_<wbr>|<wbr>", "_", cells[[1]])
    j <- which(gsub("_", "", header) == "oddsratio")
    if (!length(j)) return(numeric(0))
    suppressWarnings(as.numeric(vapply(cells[-1], `[`, "", j)))
  }))
}
infinite_cells <- function(html) grepl("<td[^>]*>-?Inf</td>", html)
mm <- function(v) sprintf("%+.2f mm", 1000 * v)

cat("Design of each block, from the data\n")
const <- simulate_trials(data.frame(participant = "C01", bias_m = 0, slope_per_m = 150, lapse = 0), repetitions = 4)
const$session_id <- 1L; const$block_index <- 0L
stair <- const; stair$block_index <- 1L
stair$staircase <- "main:cell0:up"; stair$intensity <- stair$x_m
psi <- const; psi$block_index <- 2L
psi$staircase <- "main:cell0:track"; psi$intensity <- psi$x_m
mixed <- bind_rows_fill(list(const, stair, psi))
mixed$posterior_pse_m <- ifelse(mixed$block_index == 2L, 0.001, NA)
# One step row without a posterior value still makes the whole block psi.
mixed$posterior_pse_m[which(mixed$block_index == 2L)[1]] <- NA
got <- tapply(trial_design(mixed), mixed$block_index, unique)
check(identical(as.vector(unlist(got)), c("constant", "staircase", "psi")),
      paste("blocks 0, 1, 2 of one session: constant, staircase, psi; got", paste(unlist(got), collapse = ", ")))

cat("Hierarchical model recovers PSEs, differences and slopes (6 observers, 2 staircases x 4 conditions)\n")
set.seed(3)
obs <- data.frame(participant = sprintf("S%02d", 1:6), bias_m = stats::rnorm(6, 0, 0.004), slope_per_m = 300,
                  lapse = 0.03)
bend <- function(space, view) if (space == "H3" && view == "native") 0.03 else 0
db <- scratch("adaptive.sqlite")
simulate_curvlab_db(db, obs, spaces = c("E3", "H3"), views = c("tourist", "native"), judgement = "staircase",
                    staircase_trials = 40, effect_m = bend, tracking = FALSE, seed = 5)
data <- read_curvlab(db)
check(all(data$trials$design == "staircase"), "every trial of the simulated staircase file: design staircase")
h <- psychometric_hierarchical(data$trials)
check(length(h) == 1 && nrow(h[[1]]$pse) == 4, "one model, a PSE per condition")
pse <- h[[1]]$pse
truth <- mean(-obs$bias_m) - ifelse(pse$condition == "H3 / native", 0.03, 0)
for (i in seq_len(nrow(pse)))
  check(abs(pse$pse_m[i] - truth[i]) < 3 * pse$pse_se_m[i],
        sprintf("%s: PSE %s [%s, %s], truth %s", pse$condition[i], mm(pse$pse_m[i]), mm(pse$pse_ci_low_m[i]),
                mm(pse$pse_ci_high_m[i]), mm(truth[i])))
check(all(abs(pse$slope_per_m - 300) < 3 * pse$slope_se_per_m),
      paste("slopes within 3 SE of 300 /m:", paste(sprintf("%.0f (SE %.0f)", pse$slope_per_m, pse$slope_se_per_m), collapse = ", ")))
dif <- h[[1]]$differences
hv <- dif[dif$contrast == "H3 / tourist - H3 / native", ]
ev <- dif[dif$contrast == "E3 / tourist - E3 / native", ]
check(nrow(hv) == 1 && abs(hv$difference_m - 0.03) < 3 * hv$se_m,
      sprintf("H3 tourist - native: %s (SE %.2f mm), truth +30 mm", mm(hv$difference_m), 1000 * hv$se_m))
check(nrow(ev) == 1 && abs(ev$difference_m) < 3 * ev$se_m,
      sprintf("E3 tourist - native: %s (SE %.2f mm), truth 0", mm(ev$difference_m), 1000 * ev$se_m))
check(!isTRUE(h[[1]]$separation$separated) && grepl("glmer", h[[1]]$method) && grepl("lapse", h[[1]]$method),
      paste("glmer with a profiled lapse:", h[[1]]$method))
check(grepl("(1 + z | participant)", h[[1]]$formula, fixed = TRUE) || any(grepl("simpler random effects", h[[1]]$notes)),
      paste("random intercept and slope per participant:", h[[1]]$formula))
fits <- psychometric_fits(data$trials)
check(nrow(fits) == 24 && all(fits$design == "staircase") && all(fits$pse_ci_low_m < fits$pse_m & fits$pse_m < fits$pse_ci_high_m, na.rm = TRUE),
      "per participant x condition fits with PSE intervals")
th <- staircase_thresholds(data$trials)
check(nrow(th) == 48 && all(th$method == "staircase") && all(!is.na(th$final_m)), "48 tracks with reversal means and final steps")

cat("The choice GLM on these data blows up, and is flagged\n")
blow_db <- scratch("blowup.sqlite")
simulate_curvlab_db(blow_db, data.frame(participant = sprintf("B%02d", 1:4), bias_m = 0, slope_per_m = 400, lapse = 0.02),
                    spaces = c("E3", "H3"), views = c("tourist", "native"), judgement = "staircase", staircase_trials = 30,
                    effect_m = function(space, view) if (view == "native") (if (space == "H3") 0.045 else -0.115) else 0,
                    tracking = FALSE, seed = 6)
bt <- analysed_trials(read_curvlab(blow_db)$trials)
check(!isTRUE(detect_separation(stats::model.matrix(~ x_m + cond_space * cond_view, bt),
                                as.integer(bt$response == "convex"))$separated),
      "no exact separation (the linear programme finds none)")
m <- space_view_model(bt, "P(convex)", function(r) as.integer(r == "convex"))
check(isTRUE(m$separation$separated) && length(m$separation$diverging) > 0,
      paste("flagged:", separation_words(m$separation)))
shown <- rbind(m$fixed[c("estimate", "ci_low", "ci_high")], m$contrasts[c("estimate", "ci_low", "ci_high")],
               m$coefficients[c("estimate", "ci_low", "ci_high")])
check(all(is.na(shown) | (is.finite(as.matrix(shown)) & abs(as.matrix(shown)) <= max_abs_logit + 5)),
      sprintf("no estimate or bound beyond the sane range is left (largest |value| %.3g)", max(abs(as.matrix(shown)), na.rm = TRUE)))
mt <- models_table(list(c(m, judged = "stick")))
check(all(is.na(mt$estimate) | abs(mt$estimate) <= max_abs_logit) && any(grepl("diverges", mt$note)),
      "models.csv rows of diverging terms carry no number and say why")

cat("Separated adaptive data: a noiseless observer\n")
sharp_db <- scratch("sharp.sqlite")
simulate_curvlab_db(sharp_db, data.frame(participant = c("D01", "D02", "D03"), bias_m = 0, slope_per_m = 1e7, lapse = 0),
                    judgement = "staircase", staircase_trials = 24, tracking = FALSE, seed = 8)
sharp <- read_curvlab(sharp_db)
hs <- psychometric_hierarchical(sharp$trials)[[1]]
check(isTRUE(hs$separation$separated) && any(grepl("threshold on the intensity", separation_words(hs$separation))),
      paste("hierarchical model separated:", separation_words(hs$separation)))
check(grepl("bglmer|Jeffreys|prior", hs$method) && nrow(hs$pse) == 1, paste("finite method:", hs$method))
check(nrow(hs$pse) == 1 && all(is.na(hs$pse$pse_m) | (is.finite(hs$pse$pse_ci_low_m) & is.finite(hs$pse$pse_ci_high_m) &
                                 abs(hs$pse$pse_m) < 0.2)),
      paste("PSE finite with a finite interval, or not estimated:", paste(mm(hs$pse$pse_m), hs$pse$note, collapse = "; ")))
fs <- psychometric_fits(sharp$trials)
check(all(grepl("separation: every answer", fs$note)), paste("per-participant fits name the threshold:", fs$note[1]))

cat("Report on separated constant-stimulus data: says so, no odds ratio above exp(10)\n")
sep_db <- scratch("separated.sqlite")
simulate_curvlab_db(sep_db, data.frame(participant = c("Q01", "Q02", "Q03"), bias_m = 0, slope_per_m = 150, lapse = 0),
                    spaces = c("E3", "H3"), views = c("tourist", "native"), levels_m = c(-0.01, 0, 0.01), repetitions = 4,
                    effect_m = function(space, view) if (view == "native") (if (space == "H3") 0.3 else -0.3) else 0,
                    tracking = FALSE, seed = 9)
out <- scratch("report_separated")
r <- run(rscript, c(report_r, "--db", sep_db, "--out", out))
check(r$status == 0 && any(grepl("^separation \\(P\\(convex\\)", r$out)),
      paste("exit 0, separation printed:", paste(grep("separation", r$out, value = TRUE), collapse = " | ")))
html <- read_html(out)
check(grepl("Separation detected", html) && grepl("every answer the same in", html), "the HTML says separated, and where")
or <- odds_ratios(html)
check(length(or) > 0 && all(is.na(or) | or <= exp(max_abs_logit)) && all(is.na(or) | or >= exp(-max_abs_logit)),
      sprintf("%d odds ratios shown, largest %.4g (bound %.4g)", length(or), max(c(0, or), na.rm = TRUE), exp(max_abs_logit)))
check(!infinite_cells(html), "no infinite estimate or bound in any table")
mc <- utils::read.csv(file.path(out, "models.csv"))
check(all(grepl("^separation:", mc$note)) && all(is.na(mc$ci_low) | is.finite(mc$ci_low)) &&
        all(is.na(mc$ci_high) | is.finite(mc$ci_high)), "models.csv: every row notes the separation, no infinite bound")

cat("Report on staircase data: psychometric sections instead of the choice GLM\n")
out2 <- scratch("report_adaptive")
r <- run(rscript, c(report_r, "--db", db, "--out", out2))
check(r$status == 0 && any(grepl("^design: block main staircase", r$out)) && sum(grepl("^PSE ", r$out)) == 4,
      paste("exit 0, design and four PSEs printed:", paste(grep("^PSE |^design", r$out, value = TRUE), collapse = " | ")))
html2 <- read_html(out2)
check(file.exists(file.path(out2, "psychometric_adaptive.png")) && png_ok(file.path(out2, "psychometric_adaptive.png"))$status == 0 &&
        grepl("Adaptive blocks: proportion of", html2, fixed = TRUE), "adaptive psychometric figure written, not blank, embedded")
check(grepl("Adaptive blocks: psychometric functions", html2) && grepl("Population PSE", html2) &&
        grepl("PSE differences", html2), "PSE, difference and participant tables in the HTML")
check(!grepl("odds_(<wbr>)?ratio", html2) && !infinite_cells(html2) && !file.exists(file.path(out2, "proportions.png")),
      "no odds ratio, no infinite cell, no proportions figure")
check(nrow(utils::read.csv(file.path(out2, "models.csv"))) == 0, "no choice model on adaptive blocks")
pm <- utils::read.csv(file.path(out2, "psychometric_model.csv"))
check(sum(pm$part == "PSE") == 4 && all(is.finite(pm$ci_low) & is.finite(pm$ci_high)), "psychometric_model.csv: 4 PSEs, finite intervals")
ae <- utils::read.csv(file.path(out2, "adaptive_estimates.csv"))
check(nrow(ae) == 24 && all(abs(ae$fitted_pse_m - ae$reversal_mean_m) < 0.01, na.rm = TRUE),
      sprintf("fitted PSE and reversal mean agree within 10 mm (largest gap %.2f mm)", 1000 * max(abs(ae$fitted_pse_m - ae$reversal_mean_m), na.rm = TRUE)))

cat("A psi method's posterior PSE is read from its posterior events\n")
psi_db <- scratch("psi.sqlite")
invisible(file.copy(db, psi_db, overwrite = TRUE))
con <- DBI::dbConnect(RSQLite::SQLite(), psi_db)
# As the session store writes them (docs/data.md): one `posterior` event per
# answered step, in the step's trial.
invisible(DBI::dbExecute(con, paste(
  "INSERT INTO events (session_id, trial_id, t_ns, kind, detail)",
  "SELECT session_id, trial_id, 0, 'posterior', json_object('staircase', staircase, 'step_index', step_index,",
  "'pse_mean', intensity / 2 + step_index * 1e-5, 'pse_sd', 0.001, 'slope_mean', 300, 'slope_sd', 10,",
  "'lapse_mean', NULL, 'lapse_sd', NULL, 'entropy_nats', 1.5) FROM staircase_steps")))
DBI::dbDisconnect(con)
pd <- read_curvlab(psi_db)
check(all(pd$trials$design == "psi"), "design psi")
pth <- staircase_thresholds(pd$trials)
last <- do.call(rbind, lapply(split(pd$trials, paste(pd$trials$participant, pd$trials$staircase)), function(s)
  s[which.max(s$step_index), c("participant", "staircase", "posterior_pse_mean")]))
mg <- merge(pth, last, by = c("participant", "staircase"))
check(nrow(mg) == 48 && all(abs(mg$posterior_pse_m - mg$posterior_pse_mean) < 1e-12) && all(pth$method == "psi"),
      "each track's posterior PSE is its last step's")
r <- run(rscript, c(report_r, "--db", psi_db, "--out", scratch("report_psi"), "--quiet"))
check(r$status == 0, "report on psi data: exit 0")

if (nzchar(curvlab) && file.exists(curvlab)) {
  cat("The staircase protocol through `curvlab run` (3 simulated participants)\n")
  st_db <- scratch("stick_pse_staircase.sqlite")
  if (file.exists(st_db)) file.remove(st_db)
  ok <- TRUE
  for (p in c("P01", "P02", "P03")) {
    r <- run(curvlab, c("run", file.path(source_root, "protocols/stick_pse_staircase.toml"), "--participant", p,
                        "--db", st_db, "--render", "none", "--quiet"))
    ok <- ok && r$status == 0
  }
  check(ok, "curvlab run protocols/stick_pse_staircase.toml, three participants")
  out3 <- scratch("report_stick_pse_staircase")
  r <- run(rscript, c(report_r, "--db", st_db, "--out", out3))
  cat(paste0("    ", grep("^PSE |^design", r$out, value = TRUE), collapse = "\n"), "\n")
  html3 <- read_html(out3)
  check(r$status == 0 && sum(grepl("^PSE ", r$out)) == 4 && !grepl("odds_(<wbr>)?ratio", html3) && !infinite_cells(html3),
        "four population PSEs, no odds ratio, no infinite cell")
  # What the simulated observer perceives depends on the runner's perception
  # model, so only the analysis' own promises are checked: each PSE is
  # either estimated, with a finite interval inside the levels' range, or
  # said not to be.
  pm3 <- utils::read.csv(file.path(out3, "psychometric_model.csv"))
  p3 <- pm3[pm3$part == "PSE", ]
  check(nrow(p3) == 4 && all(ifelse(is.na(p3$estimate), grepl("not estimated", p3$note),
                                    is.finite(p3$ci_low) & is.finite(p3$ci_high) & abs(p3$estimate) < 0.15)),
        "psychometric_model.csv: every PSE estimated with a finite interval, or said not to be")
  ae3 <- utils::read.csv(file.path(out3, "adaptive_estimates.csv"))
  check(nrow(ae3) == 12 && all(!is.na(ae3$reversal_mean_m)), "reversal means for all 12 participant x condition cells")
} else cat("(no curvlab binary given: the protocol run is not tested)\n")
finish()
