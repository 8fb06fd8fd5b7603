# Recovery on separated data, short version of bench/separation_recovery.R
# (analysis/R/recovery.R states the generating model): 40 strong-effect data
# sets (P(convex) = 0.98 in H3 native, every answer convex in about a third
# of them) and 40 null ones. Bounds, each with a small chance of a false
# failure when the method is right (nominal 95 % coverage, 5 % FPR):
#   - every estimate and interval finite, every SE below 50;
#   - coverage over the 240 contrast intervals of the strong sets in
#     [0.88, 1): not too low, and not trivially everything;
#   - coverage of the 80 intervals involving H3 native >= 0.85;
#   - false-positive rate over the 240 null contrasts in (0, 0.10].
source(file.path(commandArgs(TRUE)[1], "tests/analysis/helpers.R"))
rows <- recovery_study(40, seed = 7)
s <- recovery_summary(rows)
print(s, row.names = FALSE)
check(s$all_finite && s$max_se < 50, sprintf("all estimates and CIs finite, largest SE %.2f", s$max_se))
check(s$separated > 0.15, sprintf("separated data sets: %.0f%% (the case this is about)", 100 * s$separated))
check(s$coverage_all >= 0.88 && s$coverage_all < 1, sprintf("coverage %.3f in [0.88, 1)", s$coverage_all))
check(s$coverage_h3_native >= 0.85, sprintf("coverage of the H3-native contrasts %.3f >= 0.85", s$coverage_h3_native))
check(s$fpr > 0 && s$fpr <= 0.10, sprintf("false-positive rate %.3f in (0, 0.10]", s$fpr))
finish()
