# A study over several files: report.R given two lab machines' databases,
# the folder holding them, and one file with both machines' sessions (a
# merge) writes identical tables; a session given twice counts once; the
# same session UUID with different trials is refused with exit 2.
#   Rscript tests/analysis/test_pooling.R SOURCE_ROOT [CURVLAB_BINARY]
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

# The merged file: machine A's file with machine B's rows appended, ids
# shifted and protocol / participant references re-pointed (what a merge
# of two files produces).
merge_files <- function(out, first, second) {
  invisible(file.copy(first, out, overwrite = TRUE))
  con <- DBI::dbConnect(RSQLite::SQLite(), out)
  on.exit(DBI::dbDisconnect(con))
  DBI::dbExecute(con, "ATTACH ? AS src", params = list(second))
  top <- function(table, id) DBI::dbGetQuery(con, sprintf("SELECT coalesce(max(%s), 0) FROM main.%s", id, table))[[1]]
  shift <- c(session_id = top("sessions", "session_id"), block_id = top("blocks", "block_id"),
             trial_id = top("trials", "trial_id"), step_id = top("staircase_steps", "step_id"),
             sample_id = top("tracking_samples", "sample_id"), event_id = top("events", "event_id"))
  copy <- function(table, extra = character(0)) {
    cols <- DBI::dbGetQuery(con, sprintf("PRAGMA src.table_info(%s)", table))$name
    expr <- ifelse(cols %in% names(shift), paste0(cols, " + ", shift[cols]), cols)
    expr[match(names(extra), cols)] <- extra
    DBI::dbExecute(con, sprintf("INSERT INTO main.%s (%s) SELECT %s FROM src.%s s", table,
                                paste(cols, collapse = ", "), paste(expr, collapse = ", "), table))
  }
  DBI::dbExecute(con, paste("INSERT INTO main.protocols (name, sha256, text, source_path) SELECT name, sha256,",
                            "text, source_path FROM src.protocols WHERE sha256 NOT IN (SELECT sha256 FROM main.protocols)"))
  DBI::dbExecute(con, paste("INSERT INTO main.participants (pseudonym, ipd_m, dominant_eye, created_utc)",
                            "SELECT pseudonym, ipd_m, dominant_eye, created_utc FROM src.participants"))
  copy("sessions", c(
    protocol_id = paste("(SELECT m.protocol_id FROM main.protocols m JOIN src.protocols p ON p.sha256 = m.sha256",
                        "WHERE p.protocol_id = s.protocol_id)"),
    participant_id = paste("(SELECT m.participant_id FROM main.participants m JOIN src.participants p",
                           "ON p.pseudonym = m.pseudonym WHERE p.participant_id = s.participant_id)")))
  for (table in c("blocks", "trials", "staircase_steps", "tracking_samples", "events")) copy(table)
  out
}
# Machine B first: the merged file numbers sessions and trials differently
# from the two files read in name order.
merged <- merge_files(scratch("study.sqlite"), b, a)

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
