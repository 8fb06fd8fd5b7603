# Models of the judgements: space × view effects on one binary reading of the
# response (P(convex), P(not straight)), logit link,
#   y ~ [x_std +] space * view [+ (1 | participant)]
# where x_std is the shown sagitta standardised to mean 0 and 2 SD = 1
# (Gelman et al. 2008), entered when it varies within the space × view cells
# (constant-stimulus and staircase designs): the space and view terms are
# then shifts of the PSE in logit units.
#
# The paradigm's strong effects (H3 native judged convex every time) make
# maximum likelihood diverge: separation. So every model is checked for it
# (separation.R) and fitted with methods that stay finite:
#   - always a bias-reduced logistic GLM (brglm2), participants pooled, with
#     profile penalised-likelihood intervals and tests; the per-space view
#     contrasts (emmeans) come from it;
#   - the mixed model with a random intercept per participant: lme4::glmer
#     by maximum likelihood when the data are not separated; blme::bglmer
#     with N(0, 2.5²) priors on the non-intercept fixed effects (N(0, 10²) on
#     the intercept) when they are, or when glmer fails;
#   - tests of "any space/view effect": likelihood-ratio tests of the glmer
#     fits without separation; penalised likelihood-ratio tests of the
#     bias-reduced GLM with it (no test of a separated ML fit is shown).
# With one participant the mixed model is the GLM itself.

model_outcomes <- function(trials, positive = "convex") {
  responses <- unique(stats::na.omit(analysed_trials(trials)$response))
  out <- list()
  if (positive %in% responses)
    out[[paste0("P(", positive, ")")]] <- function(r) as.integer(r == positive)
  if ("straight" %in% responses && length(responses) > 2)
    out[["P(not straight)"]] <- function(r) as.integer(r != "straight")
  out
}

prior_sd_intercept <- 10
prior_sd_effects <- 2.5

# What R's fitting functions warn, said for a reader of the report: the
# known messages in plain words, any other kept as R wrote it.
plain_note <- function(msg) {
  msg <- trimws(msg)
  known <- list(
    c("non-integer #successes", "the answers were fitted as proportions with trial-count weights; the binomial fit treats them as counts (harmless)"),
    c("fitted probabilities numerically 0 or 1", "some conditions were answered all one way (fitted probabilities of 0 or 1): their estimates are unbounded; see the separation check"),
    c("algorithm did not converge", "the fit did not converge: its estimates are unreliable"),
    c("failed to converge", "the mixed model's optimiser stopped before it converged: treat its estimates with caution"),
    c("singular", "the participants' random effects have (near) zero variance: the mixed model reduces to its fixed effects"),
    c("nearly unidentifiable", "the model is nearly unidentifiable: it has more terms than the data can separate"))
  for (k in known) if (grepl(k[1], msg, fixed = TRUE)) return(k[2])
  paste0("R: ", msg)
}

# Runs a fit, collecting its warnings and messages as notes (plain_note).
with_notes <- function(expr) {
  notes <- character(0)
  collect <- function(w) { notes <<- c(notes, plain_note(conditionMessage(w))); invokeRestart(
    if (inherits(w, "warning")) "muffleWarning" else "muffleMessage") }
  fit <- tryCatch(withCallingHandlers(expr, warning = collect, message = collect),
                  error = function(e) {
                    # Some lme4 errors embed the whole call with its data: keep the message's first line.
                    msg <- strsplit(conditionMessage(e), "\n", fixed = TRUE)[[1]][1]
                    if (nchar(msg) > 300) msg <- paste0(substr(msg, 1, 300), " ...")
                    notes <<- c(notes, paste("fit failed:", msg)); NULL })
  list(fit = fit, notes = unique(notes))
}

fit_mixed <- function(formula, data, bayes) {
  if (is.null(lme4::findbars(formula)))
    return(with_notes(stats::glm(formula, data = data, family = stats::binomial(link = "logit"))))
  # bobyqa first; when it stops short of the optimum (a convergence warning,
  # common near separation), Nelder-Mead from lme4's start.
  for (optimizer in c("bobyqa", "Nelder_Mead")) {
    r <- fit_mixed_with(formula, data, bayes, optimizer)
    if (!any(grepl("optimiser stopped before it converged", r$notes, fixed = TRUE))) break
  }
  if (!is.null(r$fit) && lme4::isSingular(r$fit))
    r$notes <- c(r$notes, "singular fit: the participant variance is estimated at (or near) zero")
  # A fit whose estimates are not finite is no fit.
  if (!is.null(r$fit) && !all(is.finite(stats::coef(summary(r$fit))[, 1:2]))) {
    r$notes <- c(r$notes, "fit failed: non-finite estimates")
    r$fit <- NULL
  }
  r
}

fit_mixed_with <- function(formula, data, bayes, optimizer) {
  binomial_logit <- stats::binomial(link = "logit")
  control <- lme4::glmerControl(optimizer = optimizer, optCtrl = list(maxfun = 1e5))
  if (!bayes) return(with_notes(lme4::glmer(formula, data = data, family = binomial_logit, control = control)))
  # blme reads the prior as an unevaluated call: the numbers go in literally
  # (sd = c(intercept, every other coefficient)).
  call <- bquote(blme::bglmer(formula, data = data, family = binomial_logit, control = control,
                              fixef.prior = normal(sd = c(.(prior_sd_intercept), .(prior_sd_effects)))))
  with_notes(eval(call))
}

# Coefficients of a glmer/bglmer fit with 95 % normal-approximation intervals
# (at the maximum, or the posterior mode for bglmer).
mixed_coefficients <- function(fit) {
  cf <- summary(fit)$coefficients
  z <- stats::qnorm(0.975)
  data.frame(term = rownames(cf), estimate = cf[, 1], se = cf[, 2], ci_low = cf[, 1] - z * cf[, 2],
             ci_high = cf[, 1] + z * cf[, 2], p = 2 * stats::pnorm(-abs(cf[, 1] / cf[, 2])), row.names = NULL)
}

mixed_lrt <- function(full, d, make, label, reduced_terms) {
  reduced <- fit_mixed(make(reduced_terms), d, bayes = FALSE)
  if (is.null(reduced$fit)) return(NULL)
  dev <- as.numeric(2 * (stats::logLik(full) - stats::logLik(reduced$fit)))
  df <- attr(stats::logLik(full), "df") - attr(stats::logLik(reduced$fit), "df")
  data.frame(test = label, chisq = max(dev, 0), df = df,
             p = if (df > 0) stats::pchisq(max(dev, 0), df, lower.tail = FALSE) else NA_real_,
             method = "likelihood ratio (glmer, ML)")
}

# The model's data: y, factors, the standardised covariate; and the terms.
model_frame <- function(d, outcome_fun) {
  d$y <- outcome_fun(d$response)
  d$space <- factor(d$cond_space)
  d$view <- factor(d$cond_view)
  d$participant <- factor(d$participant)
  factors <- c("space", "view")[vapply(c("space", "view"), function(f) nlevels(droplevels(d[[f]])) > 1, TRUE)]
  cells <- interaction(d[c("space", "view")], drop = TRUE, sep = " / ")
  covariate <- any(tapply(d$x_m, cells, function(v) length(unique(stats::na.omit(v))) > 1), na.rm = TRUE)
  scale <- NULL
  if (covariate) {
    d <- d[!is.na(d$x_m), ]
    scale <- c(mean = mean(d$x_m), two_sd = 2 * stats::sd(d$x_m))
    d$x_std <- (d$x_m - scale[["mean"]]) / scale[["two_sd"]]
  }
  d$cell <- interaction(d[c("space", "view")], drop = TRUE, sep = " / ")
  list(d = droplevels(d), factors = factors, covariate = covariate, scale = scale)
}

# Fits the models for one outcome on one subset (e.g. one judged object).
# Returns list(outcome, formula, n, participants, separation, fixed (bias-
# reduced GLM coefficients), contrasts, mixed_method, coefficients (mixed
# model or GLM), random_sd, tests, methods (sentences), notes).
space_view_model <- function(d, outcome_name, outcome_fun, interaction_test = TRUE) {
  mf <- model_frame(d, outcome_fun)
  d <- mf$d
  random <- nlevels(d$participant) > 1
  notes <- character(0)
  if (!random) notes <- c(notes, "one participant: GLM without the random effect")
  dropped <- setdiff(c("space", "view"), mf$factors)
  if (length(dropped)) notes <- c(notes, paste0("dropped (one level): ", paste(dropped, collapse = ", ")))
  if (mf$covariate)
    notes <- c(notes, sprintf("x_std = (x_m - %.4g m) / %.4g m (the shown sagitta, 2 SD = 1)",
                              mf$scale[["mean"]], mf$scale[["two_sd"]]))
  rhs_fixed <- c(if (mf$covariate) "x_std", if (length(mf$factors)) paste(mf$factors, collapse = " * "))
  rhs_null <- c(if (mf$covariate) "x_std")
  make <- function(terms, re = random)
    stats::as.formula(paste("y ~", paste(c(if (length(terms)) terms else "1", if (re) "(1 | participant)"),
                                         collapse = " + ")))
  result <- list(outcome = outcome_name, formula = paste(deparse(make(rhs_fixed)), collapse = " "),
                 family = "binomial (logit)", n = nrow(d), participants = nlevels(d$participant),
                 coefficients = data.frame(), fixed = data.frame(), contrasts = data.frame(),
                 tests = data.frame(), random_sd = NA_real_, methods = character(0),
                 separation = list(separated = FALSE, infinite = character(0), cells = character(0)))
  if (length(unique(d$y)) < 2) {
    result$notes <- c(notes, "outcome does not vary: no model")
    return(result)
  }
  f_glm <- make(rhs_fixed, re = FALSE)
  sep <- detect_separation(stats::model.matrix(f_glm, d), d$y)
  sep$cells <- constant_cells(d$y, d$cell)
  result$separation <- sep
  br <- with_notes(fit_bias_reduced(f_glm, d))
  notes <- c(notes, br$notes)
  if (!is.null(br$fit)) {
    result$fixed <- br$fit$coefficients
    result$contrasts <- tryCatch(view_contrasts(br$fit), error = function(e) {
      notes <<- c(notes, paste("per-space contrasts failed:", conditionMessage(e))); data.frame() })
  }
  # Estimates that blow up (beyond the sane range of a log odds ratio, or
  # with an interval that does not close) mean the data are separated in
  # effect even where the linear programme finds no exact separation: the
  # model is flagged as separated, naming those terms.
  diverging <- c(diverging_terms(result$fixed), diverging_terms(result$contrasts, label = function(t)
    paste0(t$space, ": ", t$contrast)))
  if (length(diverging)) {
    result$separation$separated <- TRUE
    result$separation$diverging <- diverging
  }
  result <- add_mixed_model(result, d, make, rhs_fixed, rhs_null, mf$factors, random,
                            isTRUE(result$separation$separated), br$fit, interaction_test)
  result$fixed <- mask_diverging(result$fixed)
  result$contrasts <- mask_diverging(result$contrasts)
  if (!isTRUE(result$mixed_is_fixed)) {
    blown <- diverging_terms(result$coefficients)
    if (length(blown))
      notes <- c(notes, paste("mixed model estimates diverge, not shown:", paste(blown, collapse = ", ")))
    result$coefficients <- mask_diverging(result$coefficients)
  }
  result$notes <- unique(c(notes, result$notes))
  result
}

# The participant-level model and the tests, chosen by separation (see top).
add_mixed_model <- function(result, d, make, rhs_fixed, rhs_null, factors, random, separated, br,
                            interaction_test) {
  notes <- character(0)
  if (separated)
    result$methods <- c(result$methods, paste0(
      "Because of the separation the maximum-likelihood estimates of this model are infinite (or, where ",
      "the estimates blow up without exact separation, meaninglessly large): no Wald ",
      "statistic of an ML fit is shown; the bias-reduced GLM with profile intervals is reported, and the tests ",
      "are its penalised likelihood-ratio tests."))
  ml <- if (!separated) fit_mixed(make(rhs_fixed), d, bayes = FALSE) else NULL
  if (!random) {
    if (!separated && !is.null(ml$fit)) {
      result$coefficients <- mixed_coefficients_glm(ml$fit)
      result$mixed_method <- "logistic GLM (maximum likelihood; one participant)"
    } else if (!is.null(br)) {
      result$coefficients <- br$coefficients
      result$mixed_method <- "bias-reduced logistic GLM (one participant; see above)"
      result$mixed_is_fixed <- TRUE
    }
  } else if (!separated && !is.null(ml$fit)) {
    result$coefficients <- mixed_coefficients(ml$fit)
    result$random_sd <- sqrt(unname(unlist(lme4::VarCorr(ml$fit)))[1])
    result$mixed_method <- "glmer (maximum likelihood, Laplace); 95% Wald intervals"
    notes <- c(notes, ml$notes)
  } else {
    why <- if (separated) "the data are separated" else
      paste0("glmer failed (", paste(ml$notes, collapse = "; "), ")")
    bayes <- fit_mixed(make(rhs_fixed), d, bayes = TRUE)
    notes <- c(notes, bayes$notes)
    if (!is.null(bayes$fit)) {
      result$coefficients <- mixed_coefficients(bayes$fit)
      result$random_sd <- sqrt(unname(unlist(lme4::VarCorr(bayes$fit)))[1])
      result$mixed_method <- sprintf(paste0(
        "bglmer (blme): posterior mode with N(0, %g²) priors on the fixed effects (N(0, %g²) on the intercept), ",
        "95%% intervals from the normal approximation at the mode"), prior_sd_effects, prior_sd_intercept)
      result$methods <- c(result$methods, paste0("Mixed model: bglmer with weakly informative priors because ", why, "."))
    } else {
      result$methods <- c(result$methods, paste0(
        "Mixed model: none. ", why, ", and bglmer failed too (", paste(bayes$notes, collapse = "; "),
        "); the bias-reduced GLM above, which pools participants, is the model to read."))
    }
  }
  result$tests <- model_tests(result, d, make, rhs_null, factors, random, separated, ml, br, interaction_test)
  result$notes <- notes
  result
}

mixed_coefficients_glm <- function(fit) {
  cf <- summary(fit)$coefficients
  ci <- suppressMessages(stats::confint(fit))  # profile likelihood (MASS)
  data.frame(term = rownames(cf), estimate = cf[, 1], se = cf[, 2], ci_low = ci[, 1], ci_high = ci[, 2],
             p = cf[, 4], row.names = NULL)
}

separation_words <- function(sep) {
  parts <- c(if (length(sep$cells)) paste0("every answer the same in ", paste(sep$cells, collapse = ", ")),
             if (length(sep$thresholds)) paste0("a threshold on the intensity separates the answers in ",
                                                paste(sep$thresholds, collapse = "; ")),
             if (length(sep$infinite)) paste0("diverging terms: ", paste(sep$infinite, collapse = ", ")),
             if (length(sep$diverging)) paste0("estimates that blow up (near-separation): ",
                                               paste(sep$diverging, collapse = ", ")))
  if (length(parts)) paste(parts, collapse = "; ") else "linear-programming check"
}

model_tests <- function(result, d, make, rhs_null, factors, random, separated, ml, br, interaction_test) {
  if (!length(factors)) return(data.frame())
  all_label <- paste(paste(factors, collapse = " × "), "(all terms)")
  use_glmer <- !separated && random && !is.null(ml$fit)
  tests <- list()
  if (use_glmer) {
    tests[[1]] <- mixed_lrt(ml$fit, d, make, all_label, rhs_null)
    if (length(factors) == 2 && interaction_test)
      tests[[2]] <- mixed_lrt(ml$fit, d, make, "space:view interaction", c(rhs_null, "space + view"))
  } else if (!is.null(br)) {
    terms <- setdiff(colnames(br$X), c("(Intercept)", "x_std"))
    label_test <- function(label, drop) {
      t <- penalised_lrt(br, drop)
      if (is.null(t)) NULL else cbind(test = label, t, method = "penalised likelihood ratio (bias-reduced GLM)")
    }
    tests[[1]] <- label_test(all_label, terms)
    if (length(factors) == 2 && interaction_test)
      tests[[2]] <- label_test("space:view interaction", grep(":", terms, value = TRUE))
  }
  tests <- tests[!vapply(tests, is.null, TRUE)]
  if (length(tests)) do.call(rbind, tests) else data.frame()
}

# All models of a data set: each outcome × each judged object.
space_view_models <- function(trials, positive = "convex") {
  d <- analysed_trials(trials)
  if (!nrow(d)) return(list())
  if (!"cond_space" %in% names(d)) d$cond_space <- "unknown"
  if (!"cond_view" %in% names(d)) d$cond_view <- "unknown"
  judged <- unique(ifelse(is.na(d$cond_judged), "stick", d$cond_judged))
  out <- list()
  for (j in judged) for (o in names(model_outcomes(d, positive))) {
    s <- d[ifelse(is.na(d$cond_judged), "stick", d$cond_judged) == j, ]
    m <- space_view_model(s, o, model_outcomes(d, positive)[[o]])
    m$judged <- j
    out[[length(out) + 1]] <- m
  }
  out
}

# models.csv: one row per reported estimate of every model.
models_table <- function(models) {
  rows <- lapply(models, function(m) {
    label <- paste0(m$outcome, " | ", m$judged)
    note <- if (isTRUE(m$separation$separated)) paste("separation:", separation_words(m$separation)) else ""
    part <- function(df, what, method, term = df$term)
      if (!nrow(df)) NULL else data.frame(model = paste(label, what, sep = " | "), term = term,
                                          df[c("estimate", "se", "ci_low", "ci_high", "p")], method = method,
                                          note = if (is.null(df$diverges)) note
                                                 else ifelse(df$diverges, trimws(paste(note, diverges_note)), note),
                                          row.names = NULL)
    br_method <- "bias-reduced logistic GLM (brglm2 AS_mean); profile penalised-likelihood CI and LR test"
    rbind(part(m$fixed, "bias-reduced GLM", br_method),
          part(m$contrasts, "view contrasts (log odds ratio)", paste(br_method, "; emmeans contrast"),
               term = if (nrow(m$contrasts)) paste0(m$contrasts$space, ": ", m$contrasts$contrast)),
          if (!isTRUE(m$mixed_is_fixed)) part(m$coefficients, "mixed model", m$mixed_method))
  })
  out <- do.call(rbind, rows[!vapply(rows, is.null, TRUE)])
  if (is.null(out)) data.frame(model = character(0), term = character(0), estimate = numeric(0), se = numeric(0),
                               ci_low = numeric(0), ci_high = numeric(0), p = numeric(0), method = character(0),
                               note = character(0))
  else out
}
