# Parameter recovery of the per-space view contrasts on data that separate.
#
# Generating model: each trial's answer is convex with probability p(space,
# view), independently, the same for every participant (no participant
# variation, so the pooled bias-reduced GLM is the true model):
#   strong:  E3: 0.5 in every view; H3: tourist 0.5, monocular 0.6,
#            native 0.98 (the paper's H3-native prediction; with 48 trials
#            in the cell every answer is convex in 0.98^48 = 38 % of data sets);
#   null:    E3 0.5, H3 0.7 in every view (space matters, view does not).
# The truth of a contrast "a - b" within a space is logit p(a) - logit p(b).

recovery_probabilities <- function(kind = c("strong", "null")) {
  kind <- match.arg(kind)
  cells <- expand.grid(space = c("E3", "H3"), view = c("monocular", "native", "tourist"), stringsAsFactors = FALSE)
  cells$p <- if (kind == "strong")
    ifelse(cells$space == "E3", 0.5, c(monocular = 0.6, native = 0.98, tourist = 0.5)[cells$view])
  else ifelse(cells$space == "E3", 0.5, 0.7)
  cells
}

# One simulated data set and its contrasts with the truth next to them.
recovery_replicate <- function(kind, participants = 6L, repetitions = 8L) {
  cells <- recovery_probabilities(kind)
  d <- cells[rep(seq_len(nrow(cells)), each = participants * repetitions), ]
  d$participant <- rep(sprintf("P%02d", seq_len(participants)), times = nrow(cells) * repetitions)
  d$y <- stats::rbinom(nrow(d), 1, d$p)
  d$space <- factor(d$space); d$view <- factor(d$view)
  br <- fit_bias_reduced(y ~ space * view, d, profiles = FALSE)
  ctr <- view_contrasts(br)
  logit <- stats::setNames(stats::qlogis(cells$p), paste(cells$space, cells$view))
  pair <- strsplit(ctr$contrast, " - ", fixed = TRUE)
  ctr$truth <- vapply(seq_len(nrow(ctr)), function(i)
    logit[[paste(ctr$space[i], pair[[i]][1])]] - logit[[paste(ctr$space[i], pair[[i]][2])]], 0)
  ctr$separated <- isTRUE(detect_separation(stats::model.matrix(y ~ space * view, d), d$y)$separated)
  ctr
}

# Replicates of both kinds; returns one row per contrast and replicate.
recovery_study <- function(replicates, seed = 1L, participants = 6L, repetitions = 8L) {
  set.seed(seed)
  rows <- lapply(c("strong", "null"), function(kind) {
    r <- lapply(seq_len(replicates), function(i)
      cbind(kind = kind, replicate = i, recovery_replicate(kind, participants, repetitions)))
    do.call(rbind, r)
  })
  out <- do.call(rbind, rows)
  out$covered <- out$ci_low <= out$truth & out$truth <= out$ci_high
  out$finite <- is.finite(out$estimate) & is.finite(out$ci_low) & is.finite(out$ci_high) & out$se < 50
  out
}

# Summary: coverage over all contrasts of the strong data sets (and of the
# one whose cell reaches 0.98), the false-positive rate over the contrasts of
# the null data sets, and how often the data were separated.
recovery_summary <- function(rows) {
  strong <- rows[rows$kind == "strong", ]
  null <- rows[rows$kind == "null", ]
  extreme <- strong[strong$space == "H3" & grepl("native", strong$contrast), ]
  data.frame(
    replicates = length(unique(strong$replicate)),
    separated = mean(tapply(strong$separated, strong$replicate, any)),
    all_finite = all(rows$finite),
    max_se = max(rows$se),
    coverage_all = mean(strong$covered),
    coverage_h3_native = mean(extreme$covered),
    fpr = mean(null$p < 0.05),
    null_coverage = mean(null$covered))
}
