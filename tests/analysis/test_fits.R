# Unit tests of the fits and models on synthetic data (no runner needed).
#   Rscript tests/analysis/test_fits.R SOURCE_ROOT
# Tolerances: a fitted PSE or slope must lie within 3 of its own standard
# errors of the truth (the SEs' calibration is itself checked: 95 % Wald
# intervals must cover the truth in 90-99 % of 200 replicates). Null: of 100
# simulated null data sets the space x view likelihood-ratio test may reject
# at alpha = .05 at most 10 times (P(more than 10 | true rate 5 %) = 1.1 %).
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))
cores <- as.integer(Sys.getenv("CURVLAB_TEST_CORES", "2"))

cat("Wilson intervals against published values\n")
w <- wilson_ci(c(0, 5), c(10, 10))
check(abs(w$upper[1] - 0.2775) < 1e-4 && abs(w$lower[1]) < 1e-9, "0/10: [0, 0.2775]")
check(abs(w$lower[2] - 0.2366) < 1e-4 && abs(w$upper[2] - 0.7634) < 1e-4, "5/10: [0.2366, 0.7634]")

cat("Psychometric fit on a large sample\n")
set.seed(11)
x <- rep(seq(-0.03, 0.03, by = 0.01), each = 400)
p_true <- psychometric_p(x, 0.005, 120, 0.04, 2)
y <- stats::rbinom(length(x), 1, p_true)
f <- fit_psychometric(x, y, 2, "free")
check(abs(f$pse_m - 0.005) < 3 * f$pse_se_m, sprintf("PSE %.5f (SE %.5f), truth 0.005", f$pse_m, f$pse_se_m))
check(abs(f$slope_per_m - 120) < 3 * f$slope_se_per_m, sprintf("slope %.1f (SE %.1f), truth 120", f$slope_per_m, f$slope_se_per_m))
check(abs(f$lapse - 0.04) < 3 * f$lapse_se, sprintf("lapse %.4f (SE %.4f), truth 0.04", f$lapse, f$lapse_se))
g <- fit_psychometric(x, stats::rbinom(length(x), 1, stats::pnorm(80 * (x + 0.01))), 2, "none")
check(abs(g$pse_m + 0.01) < 3 * g$pse_se_m && abs(g$slope_per_m - 80) < 3 * g$slope_se_per_m,
      sprintf("probit GLM: PSE %.5f (SE %.5f) slope %.1f (SE %.1f), truth -0.01, 80", g$pse_m, g$pse_se_m,
              g$slope_per_m, g$slope_se_per_m))

cat("Standard errors are calibrated (200 replicates of 7 levels x 30 trials)\n")
cover <- do.call(rbind, parallel::mclapply(1:200, function(r) {
  set.seed(100 + r)
  x <- rep(seq(-0.03, 0.03, by = 0.01), each = 30)
  y <- stats::rbinom(length(x), 1, psychometric_p(x, -0.004, 100, 0.02, 2))
  f <- fit_psychometric(x, y, 2, "free")
  c(pse = abs(f$pse_m + 0.004) < 1.96 * f$pse_se_m, slope = abs(f$slope_per_m - 100) < 1.96 * f$slope_se_per_m)
}, mc.cores = cores))
rate <- colMeans(cover, na.rm = TRUE)
check(rate["pse"] >= 0.90 && rate["pse"] <= 0.99, sprintf("PSE 95%% interval coverage %.3f", rate["pse"]))
check(rate["slope"] >= 0.90 && rate["slope"] <= 0.99, sprintf("slope 95%% interval coverage %.3f", rate["slope"]))

cat("Recovery from a synthetic curvlab database (constant stimuli, E3 tourist)\n")
truth <- data.frame(participant = c("P01", "P02", "P03", "P04"), bias_m = c(-0.012, 0, 0.006, 0.015),
                    slope_per_m = c(80, 150, 120, 200), lapse = c(0.02, 0, 0.04, 0.02))
db <- scratch("recovery.sqlite")
simulate_curvlab_db(db, truth, levels_m = seq(-0.03, 0.03, by = 0.01), repetitions = 30, seed = 21)
data <- read_curvlab(db)
check(nrow(data$trials) == 4 * 7 * 30, "all trials read back")
ot <- observer_truth(data)
check(isTRUE(all.equal(ot$bias_m, truth$bias_m)), "observer ground truth read from the events table")
fits <- merge(psychometric_fits(data$trials), ot, by = "participant", suffixes = c("", ".true"))
for (i in seq_len(nrow(fits))) {
  fi <- fits[i, ]
  check(abs(fi$pse_m + fi$bias_m) < 3 * fi$pse_se_m,
        sprintf("%s PSE %+.4f m (SE %.4f), truth %+.4f", fi$participant, fi$pse_m, fi$pse_se_m, -fi$bias_m))
  check(abs(fi$slope_per_m - fi$slope_per_m.true) < 3 * fi$slope_se_per_m,
        sprintf("%s slope %.0f /m (SE %.0f), truth %.0f", fi$participant, fi$slope_per_m, fi$slope_se_per_m, fi$slope_per_m.true))
}

cat("Recovery from staircases (two 1-up/1-down staircases per cell)\n")
db2 <- scratch("staircase.sqlite")
simulate_curvlab_db(db2, truth[1:3, ], spaces = "E3", views = c("tourist", "native"), judgement = "staircase",
                    staircase_trials = 50, seed = 22)
d2 <- read_curvlab(db2)
f2 <- merge(psychometric_fits(d2$trials), observer_truth(d2)[c("participant", "bias_m")], by = "participant")
check(nrow(f2) == 6 && all(f2$design == "staircase"), "one staircase fit per participant x view")
check(all(abs(f2$pse_m + f2$bias_m) < 3 * f2$pse_se_m),
      sprintf("staircase PSEs within 3 SE of -bias (max |error|/SE %.2f)", max(abs(f2$pse_m + f2$bias_m) / f2$pse_se_m)))
th <- staircase_thresholds(d2$trials)
check(nrow(th) == 12 && all(th$reversals >= 3), "reversal thresholds for all 12 staircases")

cat("Null simulation: space x view has no effect (100 replicates, 8 participants, 3 options)\n")
null_p <- unlist(parallel::mclapply(1:100, function(r) {
  set.seed(5000 + r)
  obs <- data.frame(participant = sprintf("N%02d", 1:8), bias_m = stats::rnorm(8, 0, 0.004),
                    slope_per_m = 150, lapse = 0.02, criterion_m = 0.006)
  tr <- simulate_trials(obs, spaces = c("E3", "H3"), views = c("tourist", "native"), repetitions = 15)
  m <- space_view_model(tr, "P(convex)", function(r) as.integer(r == "convex"), interaction_test = FALSE)
  if (nrow(m$tests)) m$tests$p[1] else NA_real_
}, mc.cores = cores))
rejections <- sum(null_p < 0.05, na.rm = TRUE)
check(sum(is.na(null_p)) == 0, "every null replicate produced a test")
check(rejections <= 10, sprintf("false positives at alpha = .05: %d of 100 (allowed <= 10)", rejections))

cat("Power: a 1 cm perceived bend in H3 native is detected\n")
set.seed(77)
obs <- data.frame(participant = sprintf("E%02d", 1:8), bias_m = stats::rnorm(8, 0, 0.004), slope_per_m = 150,
                  lapse = 0.02, criterion_m = 0.006)
tr <- simulate_trials(obs, spaces = c("E3", "H3"), views = c("tourist", "native"), repetitions = 15,
                      effect_m = function(space, view) if (space == "H3" && view == "native") 0.01 else 0)
m <- space_view_model(tr, "P(convex)", function(r) as.integer(r == "convex"))
check(m$tests$p[1] < 0.001 && m$tests$p[2] < 0.001, sprintf("omnibus p = %.2g, interaction p = %.2g", m$tests$p[1], m$tests$p[2]))

cat("Degenerate designs give notes, not errors\n")
one <- simulate_trials(obs[1:3, ], repetitions = 20)
m1 <- space_view_model(one, "P(convex)", function(r) as.integer(r == "convex"))
check(!grepl("space|view", m1$formula) && any(grepl("dropped", m1$notes)), paste("one-level factors dropped:", m1$formula))
solo <- simulate_trials(obs[1, ], spaces = c("E3", "H3"), repetitions = 20)
m2 <- space_view_model(solo, "P(convex)", function(r) as.integer(r == "convex"))
check(!grepl("participant", m2$formula) && nrow(m2$coefficients) == 2, paste("one participant, GLM:", m2$formula))
flat <- one; flat$response <- "straight"
m3 <- space_view_model(flat, "P(convex)", function(r) as.integer(r == "convex"))
check(any(grepl("does not vary", m3$notes)), "constant outcome reported")
sep <- fit_psychometric(c(-1, -1, 1, 1), c(0, 0, 1, 1), 2, "none")
check(grepl("separation", sep$note), paste("perfect separation noted:", sep$note))
finish()
