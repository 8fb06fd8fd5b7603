# Parameter recovery and a null check through the real headless runner.
#   Rscript tests/analysis/test_runner_recovery.R SOURCE_ROOT CURVLAB_BINARY
# Skipped (exit 77) while the binary has no `run` command.
#
# Recovery: 4 simulated observers with known bias_m, slope_per_m and lapse
# run tests/analysis/recovery_constant.toml (E3 tourist, 7 bends x 24
# repetitions, 2 options) into one database; the report's fits must give
# |PSE - (-bias_m)| < 3 SE and |slope - slope_per_m| < 3 SE for every
# observer (SEs from the observed information; their calibration is checked
# in test_fits.R). Expected false-failure rate: 8 checks at 3 SE, about 2 %.
#
# Null: 4 "physical" observers (answering from the physical bend only) run
# tests/analysis/null_space_view.toml (E3/H3 x tourist/native); the space x
# view likelihood-ratio test must give p > 0.01 (false failure 1 %).
# Many null replicates are in test_fits.R (synthetic, same model code).
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))
curvlab <- commandArgs(TRUE)[2]
here <- file.path(source_root, "tests", "analysis")
run <- function(args) {
  out <- suppressWarnings(system2(curvlab, args, stdout = TRUE, stderr = TRUE))
  list(status = if (is.null(attr(out, "status"))) 0L else attr(out, "status"), out = out)
}
has_run <- function() !is.na(curvlab) && file.exists(curvlab) && any(grepl("^\\s+run\\s", run("--help")$out))
if (!has_run()) {
  cat("curvlab has no `run` command yet: runner recovery skipped\n")
  quit(status = 77)
}
simulate_session <- function(protocol, db, participant, model, bias, slope, lapse) {
  r <- run(c("run", protocol, "--participant", participant, "--db", db, "--observer", model,
             "--observer-bias-m", format(bias), "--observer-slope-per-m", format(slope),
             "--observer-lapse", format(lapse), "--render", "none", "--quiet"))
  check(r$status == 0, sprintf("curvlab run %s participant %s (exit %d%s)", basename(protocol), participant,
                               r$status, if (r$status != 0) paste(":", paste(utils::tail(r$out, 3), collapse = " | ")) else ""))
}

cat("Recovery through the runner\n")
truth <- data.frame(participant = sprintf("R%02d", 1:4), bias_m = c(-0.01, 0, 0.008, 0.015),
                    slope_per_m = c(80, 150, 120, 200), lapse = c(0.02, 0, 0.03, 0.02))
db <- scratch("runner_recovery.sqlite")
unlink(paste0(db, c("", "-wal", "-shm")))
for (i in seq_len(nrow(truth)))
  simulate_session(file.path(here, "recovery_constant.toml"), db, truth$participant[i], "perception",
                   truth$bias_m[i], truth$slope_per_m[i], truth$lapse[i])
data <- read_curvlab(db)
check(nrow(data$sessions) == 4 && all(data$sessions$trials_completed == 168), "4 sessions of 168 completed trials")
ot <- observer_truth(data)
check(!is.null(ot) && nrow(ot) == 4, "observer parameters logged per session")
fits <- merge(psychometric_fits(data$trials), ot[c("session_id", "participant", "bias_m", "slope_per_m")],
              by = "participant", suffixes = c("", ".true"))
check(nrow(fits) == 4, "one fit per participant")
for (i in seq_len(nrow(fits))) {
  f <- fits[i, ]
  check(abs(f$pse_m + f$bias_m) < 3 * f$pse_se_m,
        sprintf("participant %s: PSE %+.4f m (SE %.4f), truth %+.4f", f$participant, f$pse_m, f$pse_se_m, -f$bias_m))
  check(abs(f$slope_per_m - f$slope_per_m.true) < 3 * f$slope_se_per_m,
        sprintf("participant %s: slope %.0f /m (SE %.0f), truth %.0f", f$participant, f$slope_per_m,
                f$slope_se_per_m, f$slope_per_m.true))
}
out <- scratch("runner_report")
r <- suppressWarnings(system2(file.path(R.home("bin"), "Rscript"),
                              c(file.path(source_root, "analysis/report.R"), "--db", db, "--out", out, "--quiet"),
                              stdout = TRUE, stderr = TRUE))
check(is.null(attr(r, "status")) && file.exists(file.path(out, "report.html")), "report from the runner's database")

cat("Null check through the runner (physical observer)\n")
db0 <- scratch("runner_null.sqlite")
unlink(paste0(db0, c("", "-wal", "-shm")))
for (p in 1:4) simulate_session(file.path(here, "null_space_view.toml"), db0, sprintf("N%02d", p), "physical",
                                c(-0.004, 0, 0.003, 0.006)[p], 150, 0.02)
d0 <- read_curvlab(db0)
m <- space_view_models(d0$trials)[[1]]
check(nrow(m$tests) >= 1 && m$tests$p[1] > 0.01,
      sprintf("space x view: chi2 = %.2f, df = %d, p = %.3f (must be > 0.01)", m$tests$chisq[1], m$tests$df[1], m$tests$p[1]))
finish()
