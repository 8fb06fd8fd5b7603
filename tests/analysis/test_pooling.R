# A study over several files: report.R given two lab machines' databases,
# the folder holding them, and the file `curvlab merge` makes of them writes
# identical tables; a session given twice counts once; the
# same session UUID with different trials is refused with exit 2.
#   Rscript tests/analysis/test_pooling.R SOURCE_ROOT CURVLAB_BINARY
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))
rscript <- file.path(R.home("bin"), "Rscript")
report_r <- file.path(source_root, "analysis", "report.R")
run <- function(args) {
  out <- suppressWarnings(system2(rscript, c(report_r, args), stdout = TRUE, stderr = TRUE))
  list(status = if (is.null(attr(out, "status"))) 0L else attr(out, "status"), out = out)
}

# Two lab machines with two participants each; the H3 native cell is
# answered "convex" almost always (separation in the pooled models too).
lab <- function(name, participants, seed) {
  path <- scratch(paste0(name, ".sqlite"))
  simulate_curvlab_db(path, data.frame(participant = participants, bias_m = 0, slope_per_m = 150, lapse = 0.02),
                      spaces = c("E3", "H3"), views = c("tourist", "native"), levels_m = c(-0.01, 0, 0.01),
                      repetitions = 4, effect_m = function(space, view) if (space == "H3" && view == "native") 0.1 else 0,
                      tracking = FALSE, seed = seed)
  path
}
folder <- scratch("labs")
unlink(folder, recursive = TRUE); dir.create(folder)
a <- lab("labs/machine_a", c("A01", "A02"), 41)
b <- lab("labs/machine_b", c("B01", "B02"), 42)

# The merged file, by `curvlab merge`, machine B first: it numbers sessions
# and trials differently from the two files read in name order. The two
# machines' protocols share a name but not a hash (their seeds differ).
curvlab <- if (length(commandArgs(TRUE)) >= 2) commandArgs(TRUE)[2] else ""
if (!nzchar(curvlab) || !file.exists(curvlab)) { cat("FAIL: give the curvlab binary (for curvlab merge)\n"); quit(status = 1) }
merged <- scratch("study.sqlite")
if (file.exists(merged)) file.remove(merged)
m <- suppressWarnings(system2(curvlab, c("merge", "--out", merged, "--allow-protocol-versions", b, a),
                              stdout = TRUE, stderr = TRUE))
check(is.null(attr(m, "status")) && file.exists(merged), paste("curvlab merge:", paste(utils::tail(m, 3), collapse = " | ")))

tables <- c("proportions.csv", "psychometric_fits.csv", "models.csv")
read_tables <- function(dir) lapply(stats::setNames(tables, tables), function(t) readLines(file.path(dir, t)))

cat("Separate files, their folder and the merged file\n")
r_sep <- run(c("--db", a, b, "--out", scratch("pool_separate"), "--quiet"))
check(r_sep$status == 0, paste("two files: exit 0", paste(utils::tail(r_sep$out, 2), collapse = " | ")))
r_dir <- run(c("--db", folder, "--out", scratch("pool_folder"), "--quiet"))
check(r_dir$status == 0, "a folder of files: exit 0")
r_mrg <- run(c("--db", merged, "--out", scratch("pool_merged"), "--quiet"))
check(r_mrg$status == 0, "the merged file: exit 0")
separate <- read_tables(scratch("pool_separate"))
for (t in tables) {
  check(identical(separate[[t]], read_tables(scratch("pool_folder"))[[t]]), paste(t, ": folder = separate files"))
  check(identical(separate[[t]], read_tables(scratch("pool_merged"))[[t]]), paste(t, ": merged file = separate files"))
}
fits <- utils::read.csv(file.path(scratch("pool_merged"), "psychometric_fits.csv"))
check(setequal(fits$participant, c("A01", "A02", "B01", "B02")), "all four participants fitted")
html <- paste(readLines(file.path(scratch("pool_merged"), "report.html")), collapse = "\n")
check(grepl("4 session(s)", html, fixed = TRUE), "four sessions in the report")
check(grepl("Separation detected", html, fixed = TRUE), "separation flagged in the pooled report")

cat("A session given twice counts once\n")
r_twice <- run(c("--db", merged, a, "--out", scratch("pool_twice"), "--quiet"))
check(r_twice$status == 0, "merged file plus one of its sources: exit 0")
for (t in tables)
  check(identical(separate[[t]], read_tables(scratch("pool_twice"))[[t]]), paste(t, ": unchanged by the duplicate"))

cat("The same UUID with different trials is refused\n")
conflict <- scratch("conflict.sqlite")
invisible(file.copy(a, conflict, overwrite = TRUE))
con <- DBI::dbConnect(RSQLite::SQLite(), conflict)
invisible(DBI::dbExecute(con, paste("UPDATE trials SET response = CASE response WHEN 'convex' THEN 'concave' ELSE 'convex' END",
                                    "WHERE trial_id = (SELECT min(trial_id) FROM trials)")))
uuid <- DBI::dbGetQuery(con, "SELECT session_uuid FROM sessions WHERE session_id = 1")[[1]]
DBI::dbDisconnect(con)
r <- run(c("--db", a, conflict, "--out", scratch("pool_conflict")))
check(r$status == 2 && any(grepl(uuid, r$out, fixed = TRUE)) && any(grepl("different trials", r$out)),
      paste("exit 2 naming the session UUID:", paste(r$out, collapse = " | ")))
r <- run(c("--db", scratch("no_such_folder"), "--out", scratch("x")))
check(r$status == 2 && any(grepl("no_such_folder: no such file", r$out)), "a missing folder: exit 2")
empty <- scratch("empty_folder"); dir.create(empty, showWarnings = FALSE)
r <- run(c("--db", empty, "--out", scratch("x")))
check(r$status == 2 && any(grepl("without curvlab data files", r$out)), "a folder without databases: exit 2")
finish()
