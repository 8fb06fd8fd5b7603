# The report command end to end on synthetic curvlab databases: exit codes,
# figures that exist and are not blank, provenance in the HTML, the export
# directory path (through the real `curvlab export`) and the Python summary.
#   Rscript tests/analysis/test_report.R SOURCE_ROOT [CURVLAB_BINARY]
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))

truth <- data.frame(participant = c("P01", "P02", "P03"), bias_m = c(-0.01, 0, 0.01),
                    slope_per_m = c(100, 150, 200), lapse = 0.02)
db <- scratch("report.sqlite")
simulate_curvlab_db(db, truth, spaces = c("E3", "H3"), views = c("tourist", "native"), repetitions = 6, seed = 31)
stair <- scratch("report_staircase.sqlite")
simulate_curvlab_db(stair, truth[1:2, ], spaces = "H3", views = c("tourist", "native"), judgement = "staircase",
                    staircase_trials = 30, seed = 32)

cat("Report from a database\n")
out <- scratch("report_db")
r <- run(rscript, c(report_r, "--db", db, "--out", out))
check(r$status == 0, paste("exit 0:", paste(utils::tail(r$out, 3), collapse = " | ")))
check(utils::tail(r$out, 1) == normalizePath(file.path(out, "report.html")), "prints the report path last")
html <- paste(readLines(file.path(out, "report.html"), warn = FALSE), collapse = "\n")
figs <- file.path(out, c("proportions.png", "psychometric.png", "trajectories.png", "rt.png"))
check(all(file.exists(figs)), "proportions, psychometric, trajectories and RT figures written")
check(!file.exists(file.path(out, "vergence.png")) && !grepl("Eye tracking", html),
      "no vergence figure or section without eye tracking")
check(lengths(regmatches(html, gregexpr("data:image/png;base64,", html))) == 4, "all four figures embedded in the HTML")
p <- png_ok(figs)
check(p$status == 0, paste("figures are not blank:", paste(p$out, collapse = " | ")))
check(grepl("synthetic-constant", html) && grepl(strrep("1f", 32), html) && grepl("31001", html) &&
        grepl("synthetic data (analysis/R/simulate.R)", html, fixed = TRUE) && grepl("168 / 168", html),
      "provenance: protocol name, sha256, seed, renderer, trials completed/planned")
check(grepl("y ~ x_std + space * view + (1 | participant)", html, fixed = TRUE), "mixed model formula shown")
check(grepl("Simulated observers", html), "observer ground truth section")
fits <- utils::read.csv(file.path(out, "psychometric_fits.csv"))
check(nrow(fits) == 12, "one psychometric fit per participant x space x view")

cat("Report from staircases\n")
out2 <- scratch("report_staircase")
r <- run(rscript, c(report_r, "--db", stair, "--out", out2, "--quiet"))
check(r$status == 0 && length(r$out) == 1, "exit 0, --quiet prints one line")
check(file.exists(file.path(out2, "staircases.png")) && png_ok(file.path(out2, "staircases.png"))$status == 0,
      "staircase track figure written and not blank")
check(file.exists(file.path(out2, "staircase_thresholds.csv")), "staircase thresholds table written")
sm <- utils::read.csv(file.path(out2, "models.csv"))
check(nrow(sm) == 0, "staircase data: no space x view choice model (adaptive blocks)")
pm <- utils::read.csv(file.path(out2, "psychometric_model.csv"))
check(sum(pm$part == "PSE") == 2 && all(is.finite(pm$ci_low) & is.finite(pm$ci_high)) && all(grepl("glmer", pm$method)),
      paste("staircase data: a hierarchical psychometric model with finite CIs, by", paste(unique(pm$method), collapse = " / ")))

cat("models.csv: every estimate with a finite CI and a method\n")
mc <- utils::read.csv(file.path(out, "models.csv"))
check(identical(names(mc), c("model", "term", "estimate", "se", "ci_low", "ci_high", "p", "method", "note")),
      "models.csv columns")
check(nrow(mc) > 0 && all(is.finite(mc$ci_low) & is.finite(mc$ci_high) & mc$se < 50) && all(nzchar(mc$method)),
      sprintf("%d rows, all CIs finite, largest SE %.2f", nrow(mc), max(mc$se)))
check(any(grepl("view contrasts", mc$model)) && any(grepl("E3: native - tourist|E3: tourist - native", mc$term)),
      "per-space view contrasts")

cat("Aborted and tracking-flagged trials are counted in the provenance\n")
marked <- scratch("report_marked.sqlite")
invisible(file.copy(db, marked, overwrite = TRUE))
con <- DBI::dbConnect(RSQLite::SQLite(), marked)
first <- DBI::dbGetQuery(con, paste("SELECT trial_id, session_id FROM trials WHERE status = 'completed'",
                                    "AND session_id = 1 ORDER BY trial_id LIMIT 2"))
invisible(DBI::dbExecute(con, paste("UPDATE trials SET status = 'aborted', response = NULL, response_ns = NULL,",
                                    "rt_ns = NULL, response_device = NULL, completed_utc = NULL",
                                    "WHERE trial_id = ?"), params = list(first$trial_id[1])))
invisible(DBI::dbExecute(con, paste("INSERT INTO events (session_id, trial_id, t_ns, kind, detail)",
                                    "VALUES (1, ?, 0, 'tracking_flagged', ?)"),
                         params = list(first$trial_id[2], '{"lost_ms": 480, "spells": 1, "attempt": 1}')))
DBI::dbDisconnect(con)
out3 <- scratch("report_marked")
r <- run(rscript, c(report_r, "--db", marked, "--out", out3, "--quiet"))
check(r$status == 0, paste("exit 0:", paste(utils::tail(r$out, 3), collapse = " | ")))
html3 <- paste(readLines(file.path(out3, "report.html"), warn = FALSE), collapse = "\n")
rows <- regmatches(html3, gregexpr("<tr>.*?</tr>", html3))[[1]]
header <- rows[grepl("tracking_(<wbr>)?flagged", rows)][1]
cells <- function(row) gsub("<[^>]*>", "", regmatches(row, gregexpr("<t([hd])[^>]*>.*?</t\\1>", row, perl = TRUE))[[1]])
session1 <- rows[which(rows == header) + 1]
got <- stats::setNames(cells(session1), cells(header))
check(!is.na(header) && got[["completed"]] == "167 / 168" && got[["aborted"]] == "1" &&
        got[["tracking_flagged"]] == "1",
      paste("session 1: 167 / 168 completed, 1 aborted, 1 flagged; got", paste(names(got), got, collapse = ", ")))

cat("The blank-figure check can fail\n")
blank <- scratch("blank.png")
grDevices::png(blank, 800, 600); graphics::plot.new(); invisible(grDevices::dev.off())
check(png_ok(blank)$status == 1, "an empty page is rejected")

cat("Bad input: exit 2 with the file named\n")
r <- run(rscript, c(report_r, "--db", scratch("missing.sqlite"), "--out", scratch("x")))
check(r$status == 2 && any(grepl("missing.sqlite: no such file", r$out)), "missing database")
text_file <- scratch("notes.txt"); writeLines("not a database", text_file)
r <- run(rscript, c(report_r, "--db", text_file, "--out", scratch("x")))
check(r$status == 2 && any(grepl("notes.txt: not an SQLite database", r$out)), "text file")
other <- scratch("other.sqlite"); if (file.exists(other)) file.remove(other)
con <- DBI::dbConnect(RSQLite::SQLite(), other); invisible(DBI::dbExecute(con, "CREATE TABLE t (a)")); DBI::dbDisconnect(con)
r <- run(rscript, c(report_r, "--db", other, "--out", scratch("x")))
check(r$status == 2 && any(grepl("other.sqlite: not a curvlab data file", r$out)), "SQLite file of another program")
empty_dir <- scratch("empty_export"); dir.create(empty_dir, showWarnings = FALSE)
r <- run(rscript, c(report_r, "--export", empty_dir, "--out", scratch("x")))
check(r$status == 2 && any(grepl("no trials.csv", r$out)), "export directory without trials.csv")
r <- run(rscript, c(report_r, "--db", db, "--out", scratch("x"), "--lapse", "maybe"))
check(r$status == 2 && any(grepl("--lapse must be", r$out)), "bad option value")

if (nzchar(curvlab) && file.exists(curvlab)) {
  cat("Report from `curvlab export` output, and the Python summary\n")
  exp_dir <- scratch("export")
  unlink(exp_dir, recursive = TRUE)
  r <- run(curvlab, c("export", "--db", db, "--format", "csv", "--out", exp_dir))
  check(r$status == 0, "curvlab export --format csv")
  out3 <- scratch("report_export")
  r <- run(rscript, c(report_r, "--export", exp_dir, "--out", out3, "--quiet"))
  check(r$status == 0, "report from the export directory")
  fits_csv <- utils::read.csv(file.path(out3, "psychometric_fits.csv"))
  key <- function(f) f[order(f$participant, f$condition), c("pse_m", "slope_per_m")]
  check(isTRUE(all.equal(key(fits_csv), key(fits), tolerance = 1e-6, check.attributes = FALSE)),
        "same fits from the CSV export as from the database")
  r <- run(python, c(file.path(source_root, "analysis/python/describe.py"), exp_dir, "--figure", scratch("describe.png")))
  check(r$status == 0 && any(grepl("^Constant-stimulus blocks .*proportion of each judgement", r$out)) &&
          !any(grepl("^Adaptive blocks", r$out)), "describe.py prints proportions of the constant-stimulus design")
  stair_exp <- scratch("export_staircase")
  unlink(stair_exp, recursive = TRUE)
  r <- run(curvlab, c("export", "--db", stair, "--format", "csv", "--out", stair_exp))
  r <- run(python, c(file.path(source_root, "analysis/python/describe.py"), stair_exp, "--figure", scratch("describe_st.png")))
  check(r$status == 0 && any(grepl("^Adaptive blocks \\(staircase", r$out)) && !any(grepl("proportion of each", r$out)) &&
          sum(grepl("from-convex|from-concave", r$out)) == 8,
        "describe.py on staircases: thresholds of the 8 tracks, no proportions")
  th_py <- r$out[grepl("from-convex|from-concave", r$out)]
  th_r <- staircase_thresholds(read_curvlab(stair)$trials)
  first <- th_r[order(th_r$participant, th_r$staircase), ][1, ]
  check(grepl(sprintf("%.5f", first$threshold_m), th_py[1], fixed = TRUE) && grepl(sprintf("%.5f", first$final_m), th_py[1], fixed = TRUE),
        sprintf("describe.py and report.R agree on a track's reversal mean %.5f and final step %.5f", first$threshold_m, first$final_m))
  check(png_ok(scratch("describe.png"))$status == 0, "describe.py figure is not blank")
  r <- run(python, c(file.path(source_root, "analysis/python/describe.py"), empty_dir))
  check(r$status == 2, "describe.py: exit 2 without trials.csv")
  cat("The demo session: separation flagged, every printed estimate finite\n")
  demo_db <- scratch("demo.sqlite")
  if (file.exists(demo_db)) file.remove(demo_db)
  r <- run(curvlab, c("run", file.path(source_root, "protocols/demo.toml"), "--participant", "P01", "--db", demo_db))
  check(r$status == 0, "curvlab run protocols/demo.toml")
  demo_out <- scratch("report_demo")
  r <- run(rscript, c(report_r, "--db", demo_db, "--out", demo_out, "--quiet"))
  check(r$status == 0, "report on the demo database")
  dm <- utils::read.csv(file.path(demo_out, "models.csv"))
  demo_html <- paste(readLines(file.path(demo_out, "report.html"), warn = FALSE), collapse = "\n")
  check(grepl("Separation detected", demo_html) && all(grepl("^separation:", dm$note)), "separation flagged")
  check(nrow(dm) > 0 && all(is.finite(dm$estimate) & is.finite(dm$ci_low) & is.finite(dm$ci_high)) && max(dm$se) < 50,
        sprintf("demo: %d estimates, all CIs finite, largest SE %.2f", nrow(dm), max(dm$se)))
  check(!grepl("Wald", paste(dm$method, collapse = " ")), "demo: no Wald statistic of a separated fit")
  check(!grepl("Warnings about the protocol", demo_html, fixed = TRUE), "demo: no warning about its protocol")
  cat("The stick PSE protocol: the report repeats the model-range warning\n")
  pse_db <- scratch("pse.sqlite")
  if (file.exists(pse_db)) file.remove(pse_db)
  r <- run(curvlab, c("run", file.path(source_root, "protocols/stick_pse_staircase.toml"), "--participant", "P01",
                      "--db", pse_db, "--render", "none", "--quiet"))
  check(r$status == 0, "curvlab run protocols/stick_pse_staircase.toml --render none")
  pse_out <- scratch("report_pse")
  r <- run(rscript, c(report_r, "--db", pse_db, "--out", pse_out, "--quiet"))
  pse_html <- paste(readLines(file.path(pse_out, "report.html"), warn = FALSE), collapse = "\n")
  check(r$status == 0 && grepl("Warnings about the protocol", pse_html, fixed = TRUE) &&
          grepl("block main: in 4 of its 4 binocular conditions the human observer model&#39;s predictions lie outside its range of validity|block main: in 4 of its 4 binocular conditions the human observer model's predictions lie outside its range of validity", pse_html),
        "the report repeats the model-range warning curvlab gave when the session started")
} else cat("(no curvlab binary given: export path not tested)\n")
finish()
