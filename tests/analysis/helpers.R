# Shared by the analysis tests: loads the analysis scripts and gives a tiny
# check() that records failures and a finish() that sets the exit status,
# the programs the tests run (the curvlab binary when given as the second
# argument, Rscript, Debian's python3, the report) and run() for them.
args <- commandArgs(TRUE)
source_root <- normalizePath(if (length(args) >= 1) args[1] else ".")
analysis_root <- function() file.path(source_root, "analysis")
for (f in sort(list.files(file.path(source_root, "analysis", "R"), pattern = "\\.R$", full.names = TRUE)))
  source(f)
failures <- 0L
check <- function(ok, what) {
  ok <- isTRUE(ok)
  cat(if (ok) "  ok   " else "  FAIL ", what, "\n", sep = "")
  if (!ok) failures <<- failures + 1L
  invisible(ok)
}
finish <- function() {
  if (failures > 0) { cat(failures, "check(s) failed\n"); quit(status = 1) }
  cat("all checks passed\n")
  quit(status = 0)
}
scratch <- function(name) {
  dir <- file.path(tempdir(), "curvlab-analysis-test")
  dir.create(dir, showWarnings = FALSE, recursive = TRUE)
  file.path(dir, name)
}
curvlab <- if (length(args) >= 2) args[2] else ""
rscript <- file.path(R.home("bin"), "Rscript")
python <- "/usr/bin/python3"
report_r <- file.path(source_root, "analysis", "report.R")
run <- function(cmd, args) {
  out <- suppressWarnings(system2(cmd, args, stdout = TRUE, stderr = TRUE))
  list(status = if (is.null(attr(out, "status"))) 0L else attr(out, "status"), out = out)
}
png_ok <- function(files) run(python, c(file.path(source_root, "tests/analysis/check_png.py"), files))
