# report.R on damaged and foreign databases: random bytes, a curvlab file cut
# off mid-way, another program's SQLite file and a curvlab file whose pages
# were overwritten each exit 2 with one message that says whether the file can
# be read and how to recover it — the same message `curvlab export` gives.
#   Rscript tests/analysis/test_corrupt_input.R SOURCE_ROOT [CURVLAB_BINARY]
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))

whole <- scratch("corrupt_whole.sqlite")
simulate_curvlab_db(whole, data.frame(participant = "P01", bias_m = 0, slope_per_m = 150, lapse = 0.02),
                    spaces = "E3", views = c("tourist", "native"), repetitions = 4, seed = 5)
bytes <- readBin(whole, "raw", file.info(whole)$size)
check(length(bytes) > 16 * 4096, "the synthetic database spans many pages")

random_file <- scratch("corrupt_random.sqlite")
set.seed(20261124)
writeBin(as.raw(sample.int(256L, 65536L, replace = TRUE) - 1L), random_file)
truncated <- scratch("corrupt_truncated.sqlite")
writeBin(bytes[seq_len(length(bytes) %/% 2 + 1000)], truncated)
foreign <- scratch("corrupt_foreign.sqlite")
if (file.exists(foreign)) file.remove(foreign)
con <- DBI::dbConnect(RSQLite::SQLite(), foreign)
invisible(DBI::dbExecute(con, "CREATE TABLE photos (id INTEGER PRIMARY KEY, path TEXT)"))
DBI::dbDisconnect(con)
# The size is right and page 1 is intact; the b-tree pages after it are not.
overwritten <- scratch("corrupt_overwritten.sqlite")
damaged <- bytes
for (page in seq(4096L, length(bytes) - 16L, by = 4096L)) damaged[page + 1:16] <- as.raw(0xff)
writeBin(damaged, overwritten)

cases <- list(
  list(file = random_file, says = "cannot be read at all", recover = TRUE),
  list(file = truncated, says = "only part of it can be read", recover = TRUE),
  list(file = foreign, says = "a readable SQLite database written by another program", recover = FALSE),
  list(file = overwritten, says = "only part of it can be read", recover = TRUE))

for (case in cases) {
  name <- basename(case$file)
  before <- tools::md5sum(case$file)
  r <- run(rscript, c(report_r, "--db", case$file, "--out", scratch("corrupt_out"), "--quiet"))
  errors <- grep("^error: ", r$out, value = TRUE)
  check(r$status == 2, paste(name, ": exit 2, got", r$status))
  check(length(errors) == 1 && length(r$out) == 1, paste(name, ": one message, got:", paste(r$out, collapse = " | ")))
  check(any(startsWith(errors, paste0("error: ", case$file, ": "))), paste(name, ": names the file"))
  check(any(grepl(case$says, errors, fixed = TRUE)), paste(name, ": says", case$says))
  check(any(grepl(" .recover | sqlite3 recovered.sqlite", errors, fixed = TRUE)) == case$recover,
        paste(name, if (case$recover) ": shows the .recover command" else ": nothing to recover"))
  check(unname(tools::md5sum(case$file) == before), paste(name, ": left unmodified"))
  # The header-level checks give the very words of the curvlab command.
  if (nzchar(curvlab) && file.exists(curvlab) && !identical(case$file, overwritten)) {
    cli <- run(curvlab, c("export", "--db", case$file, "--out", scratch("corrupt_export")))
    same <- length(cli$out) == 1 && length(errors) == 1 &&
      sub("^curvlab: error: ", "", cli$out) == sub("^error: ", "", errors)
    check(cli$status == 2 && isTRUE(same),
          paste(name, ": the same message as curvlab export:", paste(cli$out, collapse = " | ")))
  }
}

# Damaged schemas and a damaged write-ahead log: exit 2, one message, the
# file unchanged, and the words of `curvlab export`.
damaged_copy <- function(name, sql) {
  file <- scratch(name)
  for (f in paste0(file, c("", "-wal", "-shm"))) if (file.exists(f)) file.remove(f)
  file.copy(whole, file)
  con <- DBI::dbConnect(RSQLite::SQLite(), file)
  for (stmt in sql) invisible(DBI::dbExecute(con, stmt))
  DBI::dbDisconnect(con)
  file
}
# A copy taken while a writer's transactions are still in its log, the
# log's header checksum then hit (docs/data.md, "A damaged write-ahead log").
wal_copy <- function(name) {
  file <- scratch(name)
  for (f in paste0(file, c("", "-wal", "-shm"))) if (file.exists(f)) file.remove(f)
  source_db <- scratch("wal_source.sqlite")
  for (f in paste0(source_db, c("", "-wal", "-shm"))) if (file.exists(f)) file.remove(f)
  file.copy(whole, source_db)
  con <- DBI::dbConnect(RSQLite::SQLite(), source_db)
  invisible(DBI::dbGetQuery(con, "PRAGMA journal_mode = WAL"))
  invisible(DBI::dbExecute(con, "PRAGMA wal_autocheckpoint = 0"))
  DBI::dbBegin(con)
  invisible(DBI::dbExecute(con, "INSERT INTO schema_migrations (version, applied_utc, note) VALUES (99, 'now', 'x')"))
  DBI::dbCommit(con)
  file.copy(source_db, file)
  file.copy(paste0(source_db, "-wal"), paste0(file, "-wal"))
  DBI::dbDisconnect(con)
  wal <- readBin(paste0(file, "-wal"), "raw", file.info(paste0(file, "-wal"))$size)
  check(length(wal) > 32, "the copied log holds frames")
  wal[25] <- xor(wal[25], as.raw(0x5a))
  writeBin(wal, paste0(file, "-wal"))
  file
}
damaged <- list(
  list(file = damaged_copy("schema_dropped.sqlite", "DROP TABLE staircase_steps"), says = "its schema is damaged"),
  list(file = damaged_copy("schema_version0.sqlite", "PRAGMA user_version = 0"), says = "its schema is damaged"),
  list(file = damaged_copy("schema_column.sqlite", "ALTER TABLE frames DROP COLUMN late"), says = "lacks frames.late"),
  list(file = wal_copy("damaged_wal.sqlite"), says = "write-ahead log"))
for (case in damaged) {
  name <- basename(case$file)
  before <- tools::md5sum(c(case$file, if (file.exists(paste0(case$file, "-wal"))) paste0(case$file, "-wal")))
  r <- run(rscript, c(report_r, "--db", case$file, "--out", scratch("corrupt_out"), "--quiet"))
  check(r$status == 2, paste(name, ": exit 2, got", r$status, paste(r$out, collapse = " | ")))
  check(length(r$out) == 1 && grepl(case$says, r$out[1], fixed = TRUE),
        paste(name, ": one message saying", case$says, "got:", paste(r$out, collapse = " | ")))
  check(all(tools::md5sum(names(before)) == before), paste(name, ": left unmodified"))
  if (nzchar(curvlab) && file.exists(curvlab)) {
    cli <- run(curvlab, c("export", "--db", case$file, "--out", scratch("corrupt_export")))
    same <- length(cli$out) == 1 && length(r$out) == 1 &&
      sub("^curvlab: error: ", "", cli$out) == sub("^error: ", "", r$out)
    check(cli$status == 2 && isTRUE(same),
          paste(name, ": the same message as curvlab export:", paste(cli$out, "||", r$out, collapse = " | ")))
  }
}

finish()
