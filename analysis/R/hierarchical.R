# Hierarchical psychometric model of adaptive blocks (staircase, psi).
#
# An adaptive method chooses each intensity from the previous answers, so
# the answers' proportions carry no information by themselves; what the data
# identify is the psychometric function of the shown intensity x (metres of
# signed sagitta). Across participants, with conditions c and participants j:
#
#   P(positive) = Phi(a_c + u_j + (b_c + v_j) * z),   z = (x - m) / s,
#   (u_j, v_j) ~ N(0, Sigma),
#
# a probit GLMM (lme4::glmer, Laplace) with a random intercept and a random
# slope on intensity per participant; m and s are the mean and SD of x over
# the model's trials (for numerical conditioning only). The population PSE of
# condition c is the x where the linear predictor is 0,
#   PSE_c = m - s * a_c / b_c,   slope_c = b_c / s  (1/m, as in fits.R),
# with standard errors by the delta method (gradient of -a/b is
# (-1/b, a/b^2)) from the fixed effects' covariance; 95 % Wald intervals.
# PSE differences between conditions that differ in one factor (per-space
# view contrasts, for instance) get the same treatment with the joint
# covariance.
#
# Lapses: a staircase's first trials lie far from the PSE, where one lapse
# flattens a probit curve badly (on curvlab's staircase protocol the slopes
# fall by a factor of ten without a lapse term). The model therefore has a
# common lapse rate lambda (a lapse gives a uniformly random one of K
# options), P = lambda/K + (1 - lambda) Phi(eta), as in fits.R, through a
# custom link; lambda is estimated by profile likelihood over a grid in
# [0, lapse_max], and the other estimates are conditional on it.
#
# Separation is checked on the fixed-effects design (separation.R, Konis
# 2007); a separated model is fitted by blme::bglmer with N(0, 10^2) priors on
# every fixed effect (probit units per SD of x: weak for any plausible curve)
# and says so. A PSE whose SE exceeds the range of intensities shown in its
# condition is reported as not estimated, never as a number.

hierarchical_prior_sd <- 10

# Models of all adaptive trials, one per judged object.
psychometric_hierarchical <- function(trials, positive = "convex", lapse = "free", lapse_max = 0.1) {
  d <- analysed_trials(trials)
  d <- d[is_adaptive(trial_design(d)) & !is.na(d$x_m), , drop = FALSE]
  if (!nrow(d)) return(list())
  judged <- ifelse(is.na(d$cond_judged), "stick", d$cond_judged)
  d$condition <- condition_label(d)
  lapply(unique(judged), function(j) {
    m <- hierarchical_model(d[judged == j, , drop = FALSE], positive, lapse = lapse, lapse_max = lapse_max)
    m$judged <- j
    m
  })
}

# The model's data: y, the condition indicators a_k and slopes b_k (one per
# condition, named so the fixed effects read as intercept and slope of a
# condition), the standardised intensity z.
hierarchical_frame <- function(d, positive) {
  d$y <- as.integer(d$response == positive)
  d$participant <- factor(d$participant)
  conditions <- sort(unique(d$condition))
  centre <- mean(d$x_m)
  scale <- stats::sd(d$x_m)
  if (!is.finite(scale) || scale == 0) scale <- 1
  d$z <- (d$x_m - centre) / scale
  k <- match(d$condition, conditions)
  a <- paste0("a", seq_along(conditions)); b <- paste0("b", seq_along(conditions))
  for (i in seq_along(conditions)) {
    d[[a[i]]] <- as.numeric(k == i)
    d[[b[i]]] <- as.numeric(k == i) * d$z
  }
  list(d = d, conditions = conditions, a = a, b = b, centre = centre, scale = scale)
}

# The probit link with a lapse rate: mu = lambda/K + (1 - lambda) Phi(eta).
lapse_probit_link <- function(lambda, k_options = 2L) {
  g <- lambda / k_options
  structure(list(
    linkfun = function(mu) stats::qnorm(pmin(pmax((mu - g) / (1 - lambda), 1e-12), 1 - 1e-12)),
    linkinv = function(eta) g + (1 - lambda) * stats::pnorm(eta),
    mu.eta = function(eta) pmax((1 - lambda) * stats::dnorm(eta), .Machine$double.eps),
    valideta = function(eta) TRUE,
    name = sprintf("probit with lapse %g", lambda)), class = "link-glm")
}

hierarchical_model <- function(d, positive, lapse = "free", lapse_max = 0.1) {
  k_options <- max(option_count(d))
  hf <- hierarchical_frame(d, positive)
  d <- hf$d
  fixed <- paste(c("0", hf$a, hf$b), collapse = " + ")
  random <- nlevels(d$participant) > 1
  result <- list(outcome = paste0("P(", positive, ")"), n = nrow(d), participants = nlevels(d$participant),
                 conditions = hf$conditions, centre_m = hf$centre, scale_m = hf$scale,
                 formula = NA_character_, method = "none", pse = data.frame(), differences = data.frame(),
                 random = data.frame(), notes = character(0), methods = character(0),
                 separation = list(separated = FALSE, infinite = character(0), cells = character(0)))
  if (length(unique(d$y)) < 2) {
    result$notes <- "the outcome does not vary: every answer is the same, no model"
    result$separation <- list(separated = TRUE, infinite = character(0),
                              cells = paste(hf$conditions, collapse = ", "))
    return(result)
  }
  X <- as.matrix(d[c(hf$a, hf$b)])
  sep <- detect_separation(X, d$y)
  sep$cells <- constant_cells(d$y, d$condition)
  sep$thresholds <- separating_thresholds(d)
  # Name the diverging terms by their condition.
  label <- stats::setNames(c(paste0("intercept of ", hf$conditions), paste0("slope of ", hf$conditions)),
                           c(hf$a, hf$b))
  sep$infinite <- unname(label[sep$infinite])
  result$separation <- sep
  separated <- isTRUE(sep$separated)

  fit <- NULL
  tries <- if (!random) list(list(re = "", what = "probit GLM (one participant, maximum likelihood)"))
           else list(list(re = "(1 + z | participant)",
                           what = "random intercept and slope on intensity per participant, correlated"),
                      list(re = "(1 + z || participant)",
                           what = "random intercept and slope on intensity per participant, uncorrelated"),
                      list(re = "(1 | participant)", what = "random intercept per participant only"))
  failed <- character(0)
  lambdas <- if (lapse == "free") lapse_max * c(0, 0.1, 0.25, 0.5, 1) else 0
  for (t in tries) {
    f <- stats::as.formula(paste("y ~", fixed, if (nzchar(t$re)) paste("+", t$re)))
    # Profile likelihood over the lapse rate; the best fit is kept.
    fits <- lapply(lambdas, function(l) fit_psychometric_mixed(f, d, bayes = separated, lambda = l, k_options = k_options))
    ll <- vapply(fits, function(r) if (is.null(r$fit)) -Inf else as.numeric(stats::logLik(r$fit)), 0)
    r <- fits[[which.max(ll)]]
    if (!is.null(r$fit)) {
      result$lapse <- lambdas[which.max(ll)]
      result$lapse_profile <- data.frame(lapse = lambdas, loglik = ll)
      fit <- r$fit
      result$formula <- paste(deparse(f, width.cutoff = 500L), collapse = " ")
      result$notes <- c(result$notes, r$notes)
      result$structure <- t$what
      break
    }
    failed <- c(failed, paste0(t$re, ": ", paste(r$notes, collapse = "; ")))
  }
  if (length(failed))
    result$notes <- c(result$notes, paste("simpler random effects after failed fits:", paste(failed, collapse = " | ")))
  pooled <- FALSE
  if (is.null(fit) && separated) {
    # Under complete separation glmer's iterations diverge even with priors;
    # the Jeffreys-penalised probit GLM (brglm2), participants pooled and no
    # lapse, is finite by construction (Kosmidis & Firth 2021).
    f <- stats::as.formula(paste("y ~", fixed))
    r <- fit_psychometric_mixed(f, d, bayes = TRUE)
    if (!is.null(r$fit)) {
      fit <- r$fit
      pooled <- TRUE
      result$lapse <- 0
      result$formula <- paste(deparse(f, width.cutoff = 500L), collapse = " ")
      result$notes <- c(result$notes, r$notes)
    }
  }
  if (is.null(fit)) {
    result$methods <- c(result$methods, "No hierarchical model could be fitted; the per-participant fits are the estimates to read.")
    return(result)
  }
  lapse_words <- if (lapse == "free")
    sprintf("common lapse rate %.3g (profile likelihood over %s; guess rate lapse/%d)", result$lapse,
            paste(format(lambdas), collapse = ", "), k_options)
  else "no lapse term (--lapse none)"
  result$method <- if (pooled) paste0("Jeffreys-penalised probit GLM (brglm2 MPL_Jeffreys), participants pooled, no lapse: ",
                                      "glmer and bglmer diverge on these separated data; 95% delta-method intervals")
    else if (!random) paste0("probit GLM, maximum likelihood (one participant); ", lapse_words)
    else if (separated) sprintf(paste0("bglmer (blme), probit: posterior mode with N(0, %g²) priors on every fixed ",
                                       "effect; %s; %s; 95%% intervals by the delta method at the mode"),
                                hierarchical_prior_sd, result$structure, lapse_words)
    else paste0("glmer (lme4), probit, maximum likelihood (Laplace); ", result$structure, "; ", lapse_words,
                "; PSE and slope per condition with 95% delta-method Wald intervals")
  if (separated)
    result$methods <- paste0("The fixed-effects design is separated (", separation_words(sep), "): maximum-likelihood ",
                             "estimates are infinite, so the model is ",
                             if (pooled) "penalised (Jeffreys prior) instead." else "the posterior mode under weakly informative priors.")
  beta <- if (inherits(fit, "glm")) stats::coef(fit) else lme4::fixef(fit)
  V <- as.matrix(stats::vcov(fit))
  result$pse <- hierarchical_pse(beta, V, hf, d)
  result$differences <- pse_differences(beta, V, hf, d)
  if (random && !pooled) result$random <- random_effects_table(fit, hf$scale)
  result
}

fit_psychometric_mixed <- function(formula, d, bayes, lambda = 0, k_options = 2L) {
  probit <- if (lambda > 0) stats::binomial(link = lapse_probit_link(lambda, k_options))
            else stats::binomial(link = "probit")
  if (is.null(lme4::findbars(formula))) {
    if (bayes) return(with_notes(stats::glm(formula, data = d, family = probit, method = brglm2::brglmFit,
                                            type = "MPL_Jeffreys")))
    return(with_notes(stats::glm(formula, data = d, family = probit)))
  }
  r <- NULL
  for (optimizer in c("bobyqa", "Nelder_Mead")) {
    control <- lme4::glmerControl(optimizer = optimizer, optCtrl = list(maxfun = 1e5))
    r <- if (!bayes) with_notes(lme4::glmer(formula, data = d, family = probit, control = control))
         else with_notes(eval(bquote(blme::bglmer(formula, data = d, family = probit, control = control,
                                                  fixef.prior = normal(sd = c(.(hierarchical_prior_sd),
                                                                              .(hierarchical_prior_sd)))))))
    if (!any(grepl("optimiser stopped before it converged", r$notes, fixed = TRUE))) break
  }
  if (!is.null(r$fit) && lme4::isSingular(r$fit))
    r$notes <- c(r$notes, "singular fit: a participant variance is estimated at (or near) zero, or the slopes and intercepts are perfectly correlated")
  if (!is.null(r$fit) && (!all(is.finite(lme4::fixef(r$fit))) || !all(is.finite(diag(as.matrix(stats::vcov(r$fit))))))) {
    r$notes <- c(r$notes, "fit failed: non-finite estimates")
    r$fit <- NULL
  }
  r
}

# Per condition: the thresholds on x that separate its answers, if any.
separating_thresholds <- function(d) {
  out <- character(0)
  for (c in sort(unique(d$condition))) {
    s <- d[d$condition == c, , drop = FALSE]
    if (threshold_separates(s$x_m, s$y)) out <- c(out, paste0(c, ": ", threshold_words(s$x_m, s$y)))
  }
  out
}

hierarchical_pse <- function(beta, V, hf, d) {
  z <- stats::qnorm(0.975)
  rows <- lapply(seq_along(hf$conditions), function(i) {
    a <- beta[[hf$a[i]]]; b <- beta[[hf$b[i]]]
    idx <- match(c(hf$a[i], hf$b[i]), names(beta))
    Vi <- V[idx, idx]
    grad <- c(-1 / b, a / b^2)
    pse <- hf$centre + hf$scale * (-a / b)
    pse_se <- hf$scale * sqrt(drop(t(grad) %*% Vi %*% grad))
    slope <- b / hf$scale
    slope_se <- sqrt(Vi[2, 2]) / hf$scale
    x <- d$x_m[d$condition == hf$conditions[i]]
    span <- diff(range(x))
    note <- ""
    # The PSE's Fieller interval is bounded only where the slope differs from
    # 0 at the 5 % level (Fieller 1954); otherwise, or when its SE exceeds the
    # range shown, the PSE is not estimated by these data.
    if (!is.finite(pse) || !is.finite(pse_se) || pse_se > span || abs(slope) < z * slope_se) {
      note <- sprintf(paste0("not estimated: slope %.3g /m (SE %.3g) is not distinguished from 0, or the PSE's SE %.3g m ",
                             "exceeds the %.3g m range shown; the PSE's interval is unbounded"), slope, slope_se, pse_se, span)
      pse <- pse_se <- NA_real_
    } else if (slope < 0) note <- "the curve decreases with the intensity"
    data.frame(condition = hf$conditions[i], n = length(x), participants = length(unique(d$participant[d$condition == hf$conditions[i]])),
               pse_m = pse, pse_se_m = pse_se, pse_ci_low_m = pse - z * pse_se, pse_ci_high_m = pse + z * pse_se,
               slope_per_m = slope, slope_se_per_m = slope_se, slope_ci_low_per_m = slope - z * slope_se,
               slope_ci_high_per_m = slope + z * slope_se, note = note, stringsAsFactors = FALSE)
  })
  do.call(rbind, rows)
}

# PSE differences (row condition minus reference condition) between every
# pair of conditions that differ in exactly one condition factor.
pse_differences <- function(beta, V, hf, d) {
  cols <- condition_columns(d, varying_only = TRUE)
  if (length(hf$conditions) < 2 || !length(cols)) return(data.frame())
  levels_of <- d[match(hf$conditions, d$condition), cols, drop = FALSE]
  z <- stats::qnorm(0.975)
  rows <- list()
  for (i in seq_along(hf$conditions)) for (j in seq_along(hf$conditions)) {
    if (j >= i) next
    differs <- cols[unlist(levels_of[i, ]) != unlist(levels_of[j, ])]
    if (length(differs) != 1) next
    idx <- match(c(hf$a[i], hf$b[i], hf$a[j], hf$b[j]), names(beta))
    ai <- beta[idx[1]]; bi <- beta[idx[2]]; aj <- beta[idx[3]]; bj <- beta[idx[4]]
    est <- hf$scale * (-ai / bi + aj / bj)
    grad <- hf$scale * c(-1 / bi, ai / bi^2, 1 / bj, -aj / bj^2)
    se <- sqrt(drop(t(grad) %*% V[idx, idx] %*% grad))
    rows[[length(rows) + 1]] <- data.frame(
      factor = sub("^cond_", "", differs), contrast = paste(hf$conditions[i], "-", hf$conditions[j]),
      difference_m = unname(est), se_m = se, ci_low_m = unname(est) - z * se, ci_high_m = unname(est) + z * se,
      p = 2 * stats::pnorm(-abs(unname(est) / se)), stringsAsFactors = FALSE)
  }
  out <- if (length(rows)) do.call(rbind, rows) else data.frame()
  # A difference involving an unestimated PSE is not shown.
  bad <- hierarchical_pse(beta, V, hf, d)
  bad <- bad$condition[is.na(bad$pse_m)]
  if (nrow(out) && length(bad))
    out <- out[!vapply(out$contrast, function(c) any(vapply(bad, function(b) grepl(b, c, fixed = TRUE), TRUE)), TRUE), ,
               drop = FALSE]
  out
}

# Participant standard deviations of the intercept (probit units) and of the
# slope (1/m), and their correlation.
random_effects_table <- function(fit, scale) {
  vc <- lme4::VarCorr(fit)
  rows <- list()
  for (g in names(vc)) {
    m <- vc[[g]]
    sds <- attr(m, "stddev")
    for (k in names(sds))
      rows[[length(rows) + 1]] <- data.frame(
        term = if (k == "z") "slope (1/m)" else if (k == "(Intercept)") "intercept (probit units)" else k,
        sd = if (k == "z") unname(sds[[k]]) / scale else unname(sds[[k]]), stringsAsFactors = FALSE)
    corr <- attr(m, "correlation")
    if (!is.null(corr) && nrow(corr) == 2)
      rows[[length(rows) + 1]] <- data.frame(term = "correlation of intercept and slope", sd = corr[1, 2])
  }
  if (!length(rows)) return(data.frame())
  out <- do.call(rbind, rows)
  names(out)[2] <- "value"
  out
}

# psychometric_model.csv: the hierarchical model's PSEs and differences.
hierarchical_table <- function(models) {
  rows <- lapply(models, function(m) {
    p <- m$pse
    dfr <- m$differences
    note <- if (isTRUE(m$separation$separated)) paste("separation:", separation_words(m$separation)) else ""
    a <- if (nrow(p)) data.frame(judged = m$judged, part = "PSE", term = p$condition, estimate = p$pse_m,
                                 se = p$pse_se_m, ci_low = p$pse_ci_low_m, ci_high = p$pse_ci_high_m,
                                 method = m$method, note = trimws(paste(note, p$note)))
    s <- if (nrow(p)) data.frame(judged = m$judged, part = "slope (1/m)", term = p$condition,
                                 estimate = p$slope_per_m, se = p$slope_se_per_m, ci_low = p$slope_ci_low_per_m,
                                 ci_high = p$slope_ci_high_per_m, method = m$method, note = note)
    b <- if (nrow(dfr)) data.frame(judged = m$judged, part = paste("PSE difference,", dfr$factor), term = dfr$contrast,
                                   estimate = dfr$difference_m, se = dfr$se_m, ci_low = dfr$ci_low_m,
                                   ci_high = dfr$ci_high_m, method = m$method, note = note)
    rbind(a, s, b)
  })
  rows <- rows[!vapply(rows, is.null, TRUE)]
  if (!length(rows)) return(data.frame())
  do.call(rbind, rows)
}
