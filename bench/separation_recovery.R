#!/usr/bin/env Rscript
# Parameter recovery of the report's per-space view contrasts on data that
# separate (analysis/R/recovery.R states the generating model): coverage of
# the profile penalised-likelihood 95 % intervals over strong-effect data
# sets (P(convex) = 0.98 in H3 native), the false-positive rate over null
# data sets, and the run time. Prints one table.
#   Rscript bench/separation_recovery.R [REPLICATES (default 200)] [SEED (default 1)]
args <- commandArgs(TRUE)
replicates <- if (length(args) >= 1) as.integer(args[1]) else 200L
seed <- if (length(args) >= 2) as.integer(args[2]) else 1L
if (is.na(replicates) || replicates < 1) stop("REPLICATES must be a whole number >= 1")
file_arg <- grep("^--file=", commandArgs(FALSE), value = TRUE)
root <- dirname(dirname(normalizePath(sub("^--file=", "", file_arg[1]))))
analysis_root <- function() file.path(root, "analysis")
for (f in sort(list.files(file.path(root, "analysis", "R"), pattern = "\\.R$", full.names = TRUE))) source(f)

started <- Sys.time()
rows <- recovery_study(replicates, seed = seed)
seconds <- as.numeric(difftime(Sys.time(), started, units = "secs"))
s <- recovery_summary(rows)
cat(sprintf("separation recovery: %d strong + %d null data sets (6 participants x 8 trials per cell, 2 spaces x 3 views), seed %d\n",
            replicates, replicates, seed))
cat(sprintf("%-10s %-10s %-10s %-7s %-13s %-19s %-6s %-14s %-9s\n", "replicates", "separated", "all_finite",
            "max_se", "coverage_all", "coverage_h3_native", "fpr", "null_coverage", "runtime_s"))
cat(sprintf("%-10d %-10.2f %-10s %-7.2f %-13.3f %-19.3f %-6.3f %-14.3f %-9.1f\n", s$replicates, s$separated,
            s$all_finite, s$max_se, s$coverage_all, s$coverage_h3_native, s$fpr, s$null_coverage, seconds))
