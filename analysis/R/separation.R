# Separation in binary-response models, and the bias-reduced logistic fit
# used so that every reported estimate stays finite.
#
# Separation: the maximum-likelihood estimate of a logistic (or probit) GLM
# is infinite exactly when some non-zero direction b puts every trial on the
# side of its answer, s_i x_i'b >= 0 with s_i = +1 for y = 1 and -1 for
# y = 0 (Albert & Anderson 1984; quasi-complete when some equalities hold).
# Following Konis (2007), a linear programme finds such a direction: maximise
# sum_i s_i x_i'b subject to s_i x_i'b >= 0 and -1 <= b_j <= 1. The optimum is
# 0 when the MLE exists (X of full rank) and positive under separation; the
# non-zero components of the optimal b are coefficients that diverge.
#
# Bias reduction: for the logit link, Firth's (1993) mean-bias-reducing
# estimate is the maximiser of the Jeffreys-penalised log-likelihood
#   l*(beta) = l(beta) + 1/2 log det I(beta),  I = X' W X,
# which is always finite for binomial responses (Kosmidis & Firth 2021).
# brglm2 (type "AS_mean") fits it; intervals and tests come from profiles of
# l* (Heinze & Schemper 2002): {t : 2 (l*(beta_hat) - max_{L'beta = t} l*) <=
# chi2_1(0.95)}, which stay finite where Wald intervals of the unpenalised
# fit do not exist.

detect_separation <- function(X, y) {
  X <- X[, colSums(abs(X)) > 0, drop = FALSE]
  A <- (2 * y - 1) * X
  p <- ncol(X)
  objective <- colSums(A)
  constraints <- rbind(cbind(A, -A), diag(2 * p))
  lp <- lpSolve::lp("max", c(objective, -objective), constraints,
                    c(rep(">=", nrow(A)), rep("<=", 2 * p)), c(rep(0, nrow(A)), rep(1, 2 * p)))
  if (lp$status != 0) return(list(separated = NA, infinite = character(0)))
  direction <- stats::setNames(lp$solution[seq_len(p)] - lp$solution[p + seq_len(p)], colnames(X))
  separated <- lp$objval > 1e-7 * max(1, sum(abs(objective)))
  list(separated = separated,
       infinite = if (separated) names(direction)[abs(direction) > 1e-7] else character(0))
}

# Cells (labels) in which every answer is the same: the most common cause of
# separation in a factorial design.
constant_cells <- function(y, cells) {
  rates <- tapply(y, cells, mean)
  names(rates)[!is.na(rates) & (rates == 0 | rates == 1)]
}

# ---------------------------------------------------------------------------
# Jeffreys-penalised logistic likelihood and its profiles

log1pexp <- function(eta) pmax(eta, 0) + log1p(exp(-abs(eta)))

penalised_loglik <- function(beta, X, y) {
  eta <- drop(X %*% beta)
  pr <- stats::plogis(eta)
  info <- crossprod(X, X * (pr * (1 - pr)))
  sum(y * eta - log1pexp(eta)) + 0.5 * as.numeric(determinant(info, logarithm = TRUE)$modulus)
}

# Maximum of l* over beta = origin + N gamma (N spans the free directions),
# by Fisher scoring on Firth's modified score X'(y - p + h (1/2 - p)) with
# step halving. Returns the maximised l*.
constrained_max <- function(X, y, origin, N) {
  beta <- origin
  value <- penalised_loglik(beta, X, y)
  if (!ncol(N)) return(value)
  for (iter in 1:100) {
    pr <- stats::plogis(drop(X %*% beta))
    w <- pr * (1 - pr)
    info <- crossprod(X, X * w)
    info_inv <- tryCatch(solve(info), error = function(e) NULL)
    if (is.null(info_inv)) break
    h <- w * rowSums((X %*% info_inv) * X)
    score <- drop(crossprod(N, crossprod(X, y - pr + h * (0.5 - pr))))
    step <- drop(N %*% solve(crossprod(N, info %*% N), score))
    for (halving in 0:30) {
      candidate <- beta + step / 2^halving
      cv <- penalised_loglik(candidate, X, y)
      if (is.finite(cv) && cv >= value - 1e-12) break
    }
    improved <- cv - value
    beta <- candidate; value <- max(value, cv)
    if (abs(improved) < 1e-10) break
  }
  value
}

# Profile of l* along the linear function L'beta, as a function of its value.
linear_profile <- function(X, y, beta_hat, L) {
  L <- as.numeric(L)
  free <- qr.Q(qr(matrix(L)), complete = TRUE)[, -1, drop = FALSE]
  function(t) {
    origin <- beta_hat + L * (t - sum(L * beta_hat)) / sum(L^2)
    constrained_max(X, y, origin, free)
  }
}

# Profile penalised-likelihood interval and test of L'beta = 0.
# Returns c(estimate, ci_low, ci_high, p); a bound that is not reached within
# |t| < limit is infinite (reported as such, never replaced by a number).
profile_inference <- function(X, y, beta_hat, L, se, level = 0.95, limit = 60) {
  profile <- linear_profile(X, y, beta_hat, L)
  top <- penalised_loglik(beta_hat, X, y)
  estimate <- sum(L * beta_hat)
  crit <- stats::qchisq(level, 1)
  gap <- function(t) 2 * (top - profile(t)) - crit
  bound <- function(dir) {
    step <- if (is.finite(se) && se > 0) min(se, 5) else 1
    inner <- estimate
    for (k in 0:20) {
      outer <- estimate + dir * step * 2^k
      if (abs(outer) > limit) return(dir * Inf)
      if (gap(outer) > 0) return(stats::uniroot(gap, sort(c(inner, outer)), tol = 1e-6)$root)
      inner <- outer
    }
    dir * Inf
  }
  stat <- max(0, 2 * (top - profile(0)))
  c(estimate = estimate, ci_low = bound(-1), ci_high = bound(1),
    p = stats::pchisq(stat, 1, lower.tail = FALSE))
}

# Bias-reduced logistic GLM (brglm2, mean bias reduction = Jeffreys penalty
# for the logit link) with profile intervals and tests for every coefficient.
fit_bias_reduced <- function(formula, data, profiles = TRUE) {
  # glm's binomial initialisation warns about the adjusted (non-integer)
  # responses brglmFit works with; that is expected, not a problem.
  fit <- withCallingHandlers(
    stats::glm(formula, data = data, family = stats::binomial(link = "logit"),
               method = brglm2::brglmFit, type = "AS_mean"),
    warning = function(w) if (grepl("non-integer #successes", conditionMessage(w))) invokeRestart("muffleWarning"))
  X <- stats::model.matrix(fit)
  keep <- !is.na(stats::coef(fit))
  X <- X[, keep, drop = FALSE]
  beta <- stats::coef(fit)[keep]
  V <- stats::vcov(fit)[keep, keep, drop = FALSE]
  y <- stats::model.response(stats::model.frame(fit))
  rows <- lapply(seq_along(beta), function(j) {
    L <- as.numeric(seq_along(beta) == j)
    if (profiles) profile_inference(X, y, beta, L, sqrt(V[j, j]))
    else c(estimate = beta[[j]], ci_low = NA_real_, ci_high = NA_real_, p = NA_real_)
  })
  table <- data.frame(term = names(beta), do.call(rbind, rows), row.names = NULL)
  table$se <- sqrt(diag(V))
  list(fit = fit, X = X, y = y, beta = beta, V = V, keep = keep,
       coefficients = table[c("term", "estimate", "se", "ci_low", "ci_high", "p")])
}

# Penalised likelihood-ratio test of dropping the columns `drop` (Heinze &
# Schemper 2002): the penalty stays the full model's.
penalised_lrt <- function(br, drop) {
  cols <- colnames(br$X) %in% drop
  if (!any(cols)) return(NULL)
  top <- penalised_loglik(br$beta, br$X, br$y)
  origin <- ifelse(cols, 0, br$beta)
  free <- diag(ncol(br$X))[, !cols, drop = FALSE]
  stat <- max(0, 2 * (top - constrained_max(br$X, br$y, origin, free)))
  data.frame(chisq = stat, df = sum(cols), p = stats::pchisq(stat, sum(cols), lower.tail = FALSE))
}

# Per-space contrasts of the views (log odds ratios) from the bias-reduced
# fit: emmeans gives the linear functions of the coefficients, the profile
# of l* their intervals and tests.
view_contrasts <- function(br) {
  if (!all(c("space", "view") %in% names(br$fit$model)) || nlevels(br$fit$model$view) < 2) return(data.frame())
  emm <- emmeans::emmeans(br$fit, ~ view | space)
  ctr <- emmeans::contrast(emm, method = "revpairwise")
  s <- as.data.frame(summary(ctr))
  L <- ctr@linfct[, br$keep, drop = FALSE]
  rows <- lapply(seq_len(nrow(L)), function(i)
    profile_inference(br$X, br$y, br$beta, L[i, ], sqrt(drop(t(L[i, ]) %*% br$V %*% L[i, ]))))
  out <- data.frame(space = as.character(s$space), contrast = as.character(s$contrast),
                    do.call(rbind, rows), se = s$SE, row.names = NULL)
  # A contrast that involves a cell with no trials is not estimable.
  out[is.finite(out$estimate) & !is.na(s$estimate), , drop = FALSE]
}

# ---------------------------------------------------------------------------
# Estimates that blow up

# A logit-scale estimate is reported only when it is finite, its interval
# closes on both sides, its SE is below max_logit_se and, for the effects of
# factors, its magnitude is below max_abs_logit: a log odds ratio of 10 is an
# odds ratio of 22 000, beyond what a few hundred binary answers can
# estimate; larger values come from (near-)separation, where the likelihood
# keeps rising along a direction. The covariate x_std is exempt from the
# magnitude bound (a steep psychometric function over a wide range of levels
# legitimately has a large slope per 2 SD), not from the others.
max_abs_logit <- 10
max_logit_se <- 10
diverges_note <- paste0("diverges: not estimable from these data (|estimate| > ", max_abs_logit,
                        " logit units, SE > ", max_logit_se, ", or an interval that does not close)")

diverging_rows <- function(table) {
  if (is.null(table) || !nrow(table)) return(logical(0))
  term <- if (is.null(table$term)) rep("", nrow(table)) else table$term
  est <- table$estimate
  ci_ok <- if (all(c("ci_low", "ci_high") %in% names(table)))
    (is.na(table$ci_low) | is.finite(table$ci_low)) & (is.na(table$ci_high) | is.finite(table$ci_high))
  else rep(TRUE, nrow(table))
  !is.finite(est) | !ci_ok | (!is.na(table$se) & table$se > max_logit_se) |
    (abs(est) > max_abs_logit & term != "x_std")
}

# Names of the diverging rows with the numbers that gave them away.
diverging_terms <- function(table, label = function(t) t$term) {
  bad <- diverging_rows(table)
  if (!any(bad)) return(character(0))
  t <- table[bad, , drop = FALSE]
  sprintf("%s (estimate %.3g, SE %.3g, CI %.3g to %.3g)", label(t), t$estimate, t$se, t$ci_low, t$ci_high)
}

# The same table with diverging rows' numbers removed (NA) and marked, so
# that no odds ratio or interval of a diverging estimate is ever printed.
mask_diverging <- function(table) {
  if (is.null(table) || !nrow(table)) return(table)
  bad <- diverging_rows(table)
  cols <- intersect(c("estimate", "se", "ci_low", "ci_high", "p"), names(table))
  table[bad, cols] <- NA_real_
  table$diverges <- bad
  table
}
