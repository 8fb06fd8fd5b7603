# Proportions of each judgement and psychometric fits.
#
# Psychometric model (the simulated observer's, DESIGN.md §5): with K answer
# options and a lapse rate lambda (a lapse gives a uniformly random option),
#   P(positive | x) = lambda/K + (1 - lambda) * pnorm(beta * (x - mu))
# for x the shown signed sagitta in metres. mu is the point of subjective
# equality (PSE, metres), beta the slope (1/m; 1/beta is the SD of the
# internal noise). For a 2-option observer with bias b and slope s, mu = -b
# and beta = s. Without lapse (lambda = 0) this is a probit GLM.

# Completed, non-practice trials that got an answer. A response window that
# ran out is stored as response "timeout" from device "none": not a judgement.
analysed_trials <- function(trials) {
  trials[trials$status == "completed" & !is.na(trials$response) & !no_answer(trials) &
           (is.na(trials$is_practice) | trials$is_practice == 0), , drop = FALSE]
}

no_answer <- function(trials) {
  device <- if ("response_device" %in% names(trials)) trials$response_device else rep(NA, nrow(trials))
  (!is.na(device) & device == "none") | (!is.na(trials$response) & trials$response == "timeout")
}

# Condition factors: cond_* columns that label conditions (not the staircase
# name, not numeric stimulus levels, which are the psychometric x).
condition_columns <- function(trials, varying_only = FALSE) {
  cols <- setdiff(grep("^cond_", names(trials), value = TRUE), "cond_staircase")
  cols <- cols[!vapply(cols, function(c) {
    v <- trials[[c]][!is.na(trials[[c]])]
    length(v) > 0 && all(!is.na(suppressWarnings(as.numeric(v))))
  }, TRUE)]
  if (varying_only)
    cols <- cols[vapply(cols, function(c) length(unique(stats::na.omit(trials[[c]]))) > 1, TRUE)]
  # A factor that only relabels an earlier one (view = tourist always with
  # projection = tourist) adds nothing to a condition label.
  kept <- character(0)
  for (c in cols) {
    redundant <- any(vapply(kept, function(k) {
      pairs <- unique(trials[c(k, c)])
      nrow(pairs) == length(unique(trials[[k]])) && nrow(pairs) == length(unique(trials[[c]]))
    }, TRUE))
    if (!redundant) kept <- c(kept, c)
  }
  kept
}

# One label per trial from the varying condition factors, e.g. "H3 / native".
condition_label <- function(trials, cols = condition_columns(trials, varying_only = TRUE)) {
  if (!length(cols)) return(rep("all trials", nrow(trials)))
  do.call(paste, c(unname(as.list(trials[cols])), sep = " / "))
}

wilson_ci <- function(k, n, level = 0.95) {
  z <- stats::qnorm(1 - (1 - level) / 2)
  p <- k / n
  p[n == 0] <- NA_real_
  centre <- (p + z^2 / (2 * n)) / (1 + z^2 / n)
  half <- z * sqrt(p * (1 - p) / n + z^2 / (4 * n^2)) / (1 + z^2 / n)
  data.frame(lower = pmax(0, centre - half), upper = pmin(1, centre + half))
}

# Proportion of each response per `by` group, with Wilson 95 % intervals.
# Responses never given in a group appear with k = 0.
response_proportions <- function(trials, by) {
  d <- analysed_trials(trials)
  if (!nrow(d)) return(data.frame())
  key <- do.call(paste, c(unname(as.list(d[by])), sep = "\r"))
  responses <- sort(unique(d$response))
  groups <- unique(d[by])
  out <- do.call(rbind, lapply(seq_len(nrow(groups)), function(g) {
    gkey <- do.call(paste, c(unname(as.list(groups[g, , drop = FALSE])), sep = "\r"))
    r <- d$response[key == gkey]
    k <- vapply(responses, function(x) sum(r == x), 0)
    cbind(groups[rep(g, length(responses)), , drop = FALSE],
          response = responses, k = k, n = length(r), p = k / length(r),
          wilson_ci(k, length(r)))
  }))
  rownames(out) <- NULL
  out
}

# Number of answer options per trial: distinct responses given in the same
# protocol block across all sessions (the lapse guess rate is 1/K).
option_count <- function(trials) {
  d <- analysed_trials(trials)
  key <- paste(d$protocol_sha256, d$block_name)
  counts <- tapply(d$response, key, function(r) length(unique(r)))
  as.integer(pmax(2, counts[paste(trials$protocol_sha256, trials$block_name)]))
}

psychometric_p <- function(x, mu, beta, lambda, k_options) {
  lambda / k_options + (1 - lambda) * stats::pnorm(beta * (x - mu))
}

# Fits one psychometric function. y: 0/1 (1 = positive option).
# lapse = "free": ML with lambda in [0, lapse_max]; "none": probit GLM.
# Returns a one-row data frame; never stops (problems go to `note`).
fit_psychometric <- function(x, y, k_options = 2L, lapse = c("free", "none"), lapse_max = 0.1) {
  lapse <- match.arg(lapse)
  ok <- !is.na(x) & !is.na(y)
  x <- x[ok]; y <- y[ok]
  res <- data.frame(n = length(y), levels = length(unique(x)), pse_m = NA_real_, pse_se_m = NA_real_,
                    pse_ci_low_m = NA_real_, pse_ci_high_m = NA_real_,
                    slope_per_m = NA_real_, slope_se_per_m = NA_real_,
                    slope_ci_low_per_m = NA_real_, slope_ci_high_per_m = NA_real_, lapse = NA_real_,
                    lapse_se = NA_real_, loglik = NA_real_, method = NA_character_, separated = FALSE, note = "")
  if (length(unique(x)) < 2 || length(unique(y)) < 2) {
    res$note <- "not enough variation in stimulus or response to fit"
    return(res)
  }
  notes <- character(0)
  # With one covariate, (quasi-)complete separation is a threshold on x that
  # no answer contradicts; the ML slope is then infinite, so the fit is the
  # Jeffreys-penalised probit GLM (brglm2), finite by construction (Kosmidis
  # & Firth 2021), and no lapse is fitted.
  separated <- threshold_separates(x, y)
  if (separated) {
    notes <- c(notes, paste0("separation: ", threshold_words(x, y), ", so the ML slope is infinite; ",
                             "fitted by the Jeffreys-penalised probit GLM (brglm2), lapse fixed at 0"))
    lapse <- "none"
    res$separated <- TRUE
  }
  g <- withCallingHandlers(
    if (separated) stats::glm(y ~ x, family = stats::binomial(link = "probit"), method = brglm2::brglmFit,
                              type = "MPL_Jeffreys")
    else stats::glm(y ~ x, family = stats::binomial(link = "probit")),
    warning = function(w) {
      if (!grepl("non-integer #successes", conditionMessage(w))) notes <<- c(notes, plain_note(conditionMessage(w)))
      invokeRestart("muffleWarning")
    })
  a <- stats::coef(g)[1]; b <- stats::coef(g)[2]; V <- stats::vcov(g)
  mu <- unname(-a / b)
  grad <- c(-1 / b, a / b^2)  # d mu / d(a, b)
  res$pse_m <- mu; res$slope_per_m <- unname(b)
  res$pse_se_m <- sqrt(drop(t(grad) %*% V %*% grad))
  res$slope_se_per_m <- sqrt(V[2, 2]); res$lapse <- 0
  res$loglik <- as.numeric(stats::logLik(g))
  res$method <- if (separated) "Jeffreys-penalised probit GLM (separation)" else "probit GLM"
  if (lapse == "free") {
    nll <- function(p) {
      pr <- psychometric_p(x, p[1], p[2], p[3], k_options)
      pr <- pmin(pmax(pr, 1e-12), 1 - 1e-12)
      -sum(y * log(pr) + (1 - y) * log(1 - pr))
    }
    to_nat <- function(q) c(q[1], q[2], lapse_max * stats::plogis(q[3]))
    start <- c(mu, unname(b), stats::qlogis(0.02 / lapse_max))
    opt <- stats::optim(start, function(q) nll(to_nat(q)), method = "BFGS",
                        control = list(maxit = 500, parscale = c(0.01, abs(b) + 1, 1)))
    if (opt$convergence != 0) notes <- c(notes, "lapse fit: optimizer did not converge")
    est <- to_nat(opt$par)
    # Standard errors from the observed information in natural units; at a
    # lapse bound the information for (mu, beta) is taken with lambda fixed.
    at_bound <- est[3] < 1e-3 * lapse_max || est[3] > (1 - 1e-3) * lapse_max
    H <- if (at_bound) stats::optimHess(est[1:2], function(p) nll(c(p, est[3])))
         else stats::optimHess(est, nll)
    V <- tryCatch(solve(H), error = function(e) NULL)
    if (is.null(V) || any(diag(V) < 0)) {
      notes <- c(notes, "lapse fit: information matrix singular, no standard errors")
      V <- matrix(NA_real_, nrow(H), ncol(H))
    }
    res$pse_m <- est[1]; res$slope_per_m <- est[2]; res$lapse <- est[3]
    res$pse_se_m <- sqrt(V[1, 1]); res$slope_se_per_m <- sqrt(V[2, 2])
    res$lapse_se <- if (at_bound) NA_real_ else sqrt(V[3, 3])
    if (at_bound) notes <- c(notes, sprintf("lapse at its bound %.3g (SEs with lapse fixed)", est[3]))
    res$loglik <- -opt$value
    res$method <- sprintf("ML with lapse in [0, %.2g], guess rate lapse/%d", lapse_max, k_options)
  }
  z <- stats::qnorm(0.975)
  res$pse_ci_low_m <- res$pse_m - z * res$pse_se_m; res$pse_ci_high_m <- res$pse_m + z * res$pse_se_m
  res$slope_ci_low_per_m <- res$slope_per_m - z * res$slope_se_per_m
  res$slope_ci_high_per_m <- res$slope_per_m + z * res$slope_se_per_m
  # A PSE whose uncertainty exceeds the whole range shown (or that is not
  # finite) is not estimated by these data: near-separation or a flat curve.
  # It is reported as such, never as a number with an absurd interval.
  # So is a PSE taken as the ratio -a/b of the GLM's coefficients whose
  # slope is not distinguished from 0 at the 5 % level: its Fieller interval
  # is then unbounded (Fieller 1954), whatever the delta method says. (With
  # a lapse the PSE is a parameter of its own, with its own Wald interval.)
  span <- diff(range(x))
  flat <- lapse == "none" && is.finite(res$slope_se_per_m) && abs(res$slope_per_m) < z * res$slope_se_per_m
  outside <- is.finite(res$pse_m) && (res$pse_m < min(x) || res$pse_m > max(x))
  if (!is.finite(res$pse_m) || !is.finite(res$slope_per_m) || flat || outside ||
      (is.finite(res$pse_se_m) && res$pse_se_m > span)) {
    notes <- c(notes, sprintf(paste0("not estimated: PSE %.3g m (SE %.3g m), levels shown %.3g to %.3g m, ",
                                     "slope %.3g /m (SE %.3g): the PSE lies beyond the levels shown or its ",
                                     "interval is unbounded"),
                              res$pse_m, res$pse_se_m, min(x), max(x), res$slope_per_m, res$slope_se_per_m))
    res[c("pse_m", "pse_se_m", "pse_ci_low_m", "pse_ci_high_m", "slope_per_m", "slope_se_per_m",
          "slope_ci_low_per_m", "slope_ci_high_per_m")] <- NA_real_
    res$separated <- TRUE
  }
  res$note <- paste(unique(notes), collapse = "; ")
  res
}

# Whether a threshold on the level separates one-covariate data: every
# answer one way below it and the other way above (ties allowed: quasi-
# complete separation). Levels closer than tol_m are the same level (a
# staircase's arithmetic leaves 1e-18 m where it meant 0).
threshold_separates <- function(x, y, tol_m = 1e-9) {
  if (length(unique(y)) < 2) return(FALSE)
  max(x[y == 0]) <= min(x[y == 1]) + tol_m || max(x[y == 1]) <= min(x[y == 0]) + tol_m
}

# What separates one-covariate data, in words: the threshold on the level
# below which every answer is one way and above which the other.
threshold_words <- function(x, y, tol_m = 1e-9) {
  if (max(x[y == 0]) <= min(x[y == 1]) + tol_m)
    sprintf("every answer negative at levels <= %.4g m and positive at levels >= %.4g m", max(x[y == 0]), min(x[y == 1]))
  else
    sprintf("every answer positive at levels <= %.4g m and negative at levels >= %.4g m", max(x[y == 1]), min(x[y == 0]))
}

# Psychometric fits per participant × condition (× judged object) wherever the
# shown intensity varies: constant-stimulus designs and staircases (all steps
# of a condition's staircases pooled).
psychometric_fits <- function(trials, positive = "convex", lapse = "free", lapse_max = 0.1) {
  d <- analysed_trials(trials)
  d <- d[!is.na(d$x_m), , drop = FALSE]
  if (!nrow(d)) return(data.frame())
  d$k_options <- option_count(d)
  d$condition <- condition_label(d)
  d$design <- trial_design(d)
  groups <- unique(d[c("participant", "condition")])
  out <- lapply(seq_len(nrow(groups)), function(g) {
    s <- d[d$participant == groups$participant[g] & d$condition == groups$condition[g], ]
    if (length(unique(s$x_m)) < 3) return(NULL)
    f <- fit_psychometric(s$x_m, as.integer(s$response == positive), max(s$k_options),
                          lapse = lapse, lapse_max = lapse_max)
    cbind(groups[g, , drop = FALSE], design = paste(sort(unique(s$design)), collapse = "+"),
          tracks = length(unique(stats::na.omit(s$staircase))), f)
  })
  out <- do.call(rbind, out[!vapply(out, is.null, TRUE)])
  if (is.null(out)) return(data.frame())
  rownames(out) <- NULL
  out
}

# Binned proportions behind each psychometric fit (one bin per shown level;
# staircase intensities are many, so they are pooled into at most `bins`
# equal-count bins).
psychometric_bins <- function(trials, positive = "convex", bins = 8L) {
  d <- analysed_trials(trials)
  d <- d[!is.na(d$x_m), , drop = FALSE]
  if (!nrow(d)) return(data.frame())
  d$condition <- condition_label(d)
  d$y <- as.integer(d$response == positive)
  split_key <- paste(d$participant, d$condition, sep = "\r")
  out <- lapply(split(d, split_key), function(s) {
    levels_x <- sort(unique(s$x_m))
    if (length(levels_x) < 3) return(NULL)
    bin <- if (length(levels_x) <= 12) match(s$x_m, levels_x)
           else as.integer(cut(rank(s$x_m, ties.method = "first"), bins))
    agg <- do.call(rbind, lapply(split(s, bin), function(b)
      data.frame(x_m = mean(b$x_m), k = sum(b$y), n = nrow(b))))
    cbind(participant = s$participant[1], condition = s$condition[1], agg, p = agg$k / agg$n)
  })
  do.call(rbind, out[!vapply(out, is.null, TRUE)])
}

# Thresholds per adaptive track, the second estimate beside the fitted PSE:
#   threshold_m  mean intensity at the reversals after the first `discard`
#                (Levitt 1971), SE = SD/sqrt(n);
#   final_m      the intensity of the track's last step (the export has no
#                next intensity, so database and export give the same);
#   posterior_pse_m  the adaptive method's own posterior PSE after its last
#                step, when its steps carry one (psi).
staircase_thresholds <- function(trials, discard = 2L) {
  d <- analysed_trials(trials)
  d <- d[!is.na(d$staircase) & !is.na(d$intensity), , drop = FALSE]
  if (!nrow(d)) return(data.frame())
  d$condition <- condition_label(d)
  d$design <- trial_design(d)
  posterior <- posterior_pse_column(d)
  out <- lapply(split(d, paste(d$participant, d$staircase, sep = "\r")), function(s) {
    s <- s[order(if (all(is.na(s$step_index))) s$trial_index else s$step_index), ]
    rev_x <- s$intensity[!is.na(s$is_reversal) & s$is_reversal == 1]
    used <- if (length(rev_x) > discard) rev_x[-seq_len(discard)] else numeric(0)
    last <- nrow(s)
    final <- s$intensity[last]
    post <- if (is.na(posterior)) NA_real_ else {
      v <- as.numeric(s[[posterior]]); v <- v[!is.na(v)]
      if (length(v)) v[length(v)] else NA_real_
    }
    data.frame(participant = s$participant[1], condition = s$condition[1], staircase = s$staircase[1],
               method = s$design[1], steps = nrow(s), reversals = length(rev_x),
               threshold_m = if (length(used)) mean(used) else NA_real_,
               threshold_se_m = if (length(used) > 1) stats::sd(used) / sqrt(length(used)) else NA_real_,
               final_m = final, posterior_pse_m = post)
  })
  out <- do.call(rbind, out)
  rownames(out) <- NULL
  out
}
