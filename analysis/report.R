#!/usr/bin/env Rscript
# From curvlab databases (or an export directory) to an HTML report:
#   Rscript analysis/report.R --db results/demo.sqlite --out results/demo/report
#   Rscript analysis/report.R --db lab1.sqlite lab2.sqlite --out study/report
#   Rscript analysis/report.R --db results/ --out study/report
#   Rscript analysis/report.R --export results/demo/export --out results/demo/report
# Prints the path of report.html. Exit codes: 0 done, 2 bad input (missing
# file, not a curvlab database, bad option), 1 anything else.

usage <- paste(
  "usage: Rscript analysis/report.R (--db FILE... | --export DIR) --out DIR [options]",
  "  --db FILE...              curvlab SQLite data files or folders of them (pooled by session UUID)",
  "  --export DIR              a directory written by `curvlab export` (trials.csv)",
  "  --out DIR                 where report.html, the PNG figures and CSV tables go",
  "  --positive VALUE          response counted as positive in fits and models (default convex)",
  "  --lapse free|none         fit a lapse rate by maximum likelihood, or a plain probit GLM (default free)",
  "  --lapse-max X             upper bound of the fitted lapse rate (default 0.1)",
  "  --discard-reversals N     reversals left out of staircase thresholds (default 2)",
  "  --quiet                   print only the report path",
  sep = "\n")

fail_usage <- function(msg) {
  cat("error: ", msg, "\n", usage, "\n", sep = "", file = stderr())
  quit(status = 2)
}

parse_args <- function(args) {
  opts <- list(db = NULL, export = NULL, out = NULL, positive = "convex", lapse = "free",
               lapse_max = 0.1, discard_reversals = 2L, quiet = FALSE)
  i <- 1
  while (i <= length(args)) {
    a <- args[i]
    if (a %in% c("-h", "--help")) { cat(usage, "\n"); quit(status = 0) }
    if (a == "--quiet") { opts$quiet <- TRUE; i <- i + 1; next }
    key <- sub("^--", "", a)
    if (!startsWith(a, "--") || !gsub("-", "_", key) %in% names(opts))
      fail_usage(paste0("unknown argument '", a, "'"))
    if (i == length(args)) fail_usage(paste0(a, " needs a value"))
    if (a == "--db") {
      # Every following argument up to the next option is a database.
      n <- 0
      while (i + n + 1 <= length(args) && !startsWith(args[i + n + 1], "--")) n <- n + 1
      if (n == 0) fail_usage("--db needs a value")
      opts$db <- c(opts$db, args[i + seq_len(n)])
      i <- i + n + 1
      next
    }
    opts[[gsub("-", "_", key)]] <- args[i + 1]
    i <- i + 2
  }
  if (is.null(opts$db) == is.null(opts$export)) fail_usage("give exactly one of --db FILE... or --export DIR")
  if (is.null(opts$out)) fail_usage("--out DIR is required")
  if (!opts$lapse %in% c("free", "none")) fail_usage(paste0("--lapse must be free or none, not '", opts$lapse, "'"))
  opts$lapse_max <- suppressWarnings(as.numeric(opts$lapse_max))
  if (is.na(opts$lapse_max) || opts$lapse_max <= 0 || opts$lapse_max >= 1)
    fail_usage("--lapse-max must be a number in (0, 1)")
  opts$discard_reversals <- suppressWarnings(as.integer(opts$discard_reversals))
  if (is.na(opts$discard_reversals) || opts$discard_reversals < 0)
    fail_usage("--discard-reversals must be a whole number >= 0")
  opts
}

script_dir <- function() {
  file_arg <- grep("^--file=", commandArgs(FALSE), value = TRUE)
  dirname(normalizePath(sub("^--file=", "", file_arg[1])))
}

main <- function() {
  opts <- parse_args(commandArgs(TRUE))
  root <- script_dir()
  analysis_root <<- function() root
  for (f in sort(list.files(file.path(root, "R"), pattern = "\\.R$", full.names = TRUE))) source(f)
  suppressPackageStartupMessages({
    for (p in c("DBI", "RSQLite", "jsonlite", "ggplot2", "lme4", "brglm2", "blme", "emmeans", "lpSolve"))
      if (!requireNamespace(p, quietly = TRUE)) {
        cat("error: R package '", p, "' is not installed (Debian: apt-get install --no-install-recommends r-cran-",
            tolower(p), ")\n", sep = "", file = stderr())
        quit(status = 1)
      }
  })
  if (!is.null(opts$export) && file.exists(opts$export) && !dir.exists(opts$export))
    fail_usage(paste0(opts$export, ": is a file; use --db FILE"))
  data <- tryCatch(if (!is.null(opts$db)) read_curvlab_databases(opts$db) else read_curvlab(opts$export),
                   curvlab_input_error = function(e) {
                     cat("error: ", conditionMessage(e), "\n", sep = "", file = stderr())
                     quit(status = 2)
                   })
  if (!opts$quiet)
    cat(sprintf("read %s: %d trials (%d completed), %d session(s)\n", data$source, nrow(data$trials),
                sum(data$trials$status == "completed"), nrow(data$sessions)))
  result <- build_report(data, opts$out, positive = opts$positive, lapse = opts$lapse,
                         lapse_max = opts$lapse_max, discard_reversals = opts$discard_reversals)
  if (!opts$quiet) {
    cat(sprintf("figures: %s\n", paste(basename(result$figures), collapse = ", ")))
    if (nrow(result$designs))
      cat(sprintf("design: block %s %s (%d trials)\n", result$designs$block, result$designs$design,
                  result$designs$trials), sep = "")
    for (m in result$hierarchical) {
      if (isTRUE(m$separation$separated))
        cat(sprintf("separation (psychometric model, %s): %s\n", m$judged, separation_words(m$separation)))
      for (n in m$notes) cat(sprintf("note (psychometric model, %s): %s\n", m$judged, n))
      p <- m$pse
      if (nrow(p))
        cat(sprintf("PSE %s (%s): %s\n", p$condition, m$judged,
                    ifelse(is.na(p$pse_m), paste("not estimated;", p$note),
                           sprintf("%+.2f mm [%+.2f, %+.2f], slope %.0f /m", 1000 * p$pse_m, 1000 * p$pse_ci_low_m,
                                   1000 * p$pse_ci_high_m, p$slope_per_m))), sep = "")
    }
    for (m in result$models) {
      if (isTRUE(m$separation$separated))
        cat(sprintf("separation (%s, %s): %s\n", m$outcome, m$judged, separation_words(m$separation)))
      for (n in m$notes) cat(sprintf("note (%s, %s): %s\n", m$outcome, m$judged, n))
    }
    cat(sprintf("models: %s\n", result$models_csv))
  }
  cat(normalizePath(result$report), "\n", sep = "")
}

tryCatch(main(), error = function(e) {
  cat("error: ", conditionMessage(e), "\n", sep = "", file = stderr())
  quit(status = 1)
})
