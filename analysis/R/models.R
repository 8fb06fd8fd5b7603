# Mixed model of the judgements: a binomial GLMM (probit link) with space ×
# view fixed effects and a random intercept per participant,
#   y ~ [x_m +] space * view + (1 | participant)
# where y is one binary reading of the response (P(convex), P(not straight))
# and x_m (the shown sagitta) enters as a covariate when it varies within the
# space × view cells (constant-stimulus and staircase designs), so the space
# and view terms then measure PSE shifts in probit units.
#
# Robustness: a factor with one level is dropped from the formula; with one
# participant the random effect is dropped (GLM); glmer's convergence and
# singular-fit messages are collected and reported, never fatal. The test of
# "any space/view effect" is a likelihood-ratio test against the model
# without space and view terms (same random effect, same covariate).

model_outcomes <- function(trials, positive = "convex") {
  responses <- unique(stats::na.omit(analysed_trials(trials)$response))
  out <- list()
  if (positive %in% responses)
    out[[paste0("P(", positive, ")")]] <- function(r) as.integer(r == positive)
  if ("straight" %in% responses && length(responses) > 2)
    out[["P(not straight)"]] <- function(r) as.integer(r != "straight")
  out
}

fit_glmm_safely <- function(formula, data, random) {
  notes <- character(0)
  collect <- function(w) { notes <<- c(notes, conditionMessage(w)); invokeRestart(
    if (inherits(w, "warning")) "muffleWarning" else "muffleMessage") }
  fit <- tryCatch(withCallingHandlers(
    if (random) lme4::glmer(formula, data = data, family = stats::binomial(link = "probit"),
                            control = lme4::glmerControl(optimizer = "bobyqa",
                                                         optCtrl = list(maxfun = 2e4)))
    else stats::glm(formula, data = data, family = stats::binomial(link = "probit")),
    warning = collect, message = collect),
    error = function(e) { notes <<- c(notes, paste("fit failed:", conditionMessage(e))); NULL })
  if (!is.null(fit) && random && lme4::isSingular(fit))
    notes <- c(notes, "singular fit: the participant variance is estimated at (or near) zero")
  list(fit = fit, notes = unique(notes))
}

# Fits the model for one outcome on one subset (e.g. one judged object).
# Returns list(formula, family, coefficients (data frame), tests (data frame),
# notes, n, participants, random_sd).
space_view_model <- function(d, outcome_name, outcome_fun, interaction_test = TRUE) {
  d$y <- outcome_fun(d$response)
  d$space <- factor(d$cond_space)
  d$view <- factor(d$cond_view)
  d$participant <- factor(d$participant)
  factors <- c("space", "view")[vapply(c("space", "view"), function(f) nlevels(droplevels(d[[f]])) > 1, TRUE)]
  cells <- interaction(d[c("space", "view")], drop = TRUE)
  covariate <- any(tapply(d$x_m, cells, function(v) length(unique(stats::na.omit(v))) > 1), na.rm = TRUE)
  if (covariate) d <- d[!is.na(d$x_m), ]
  random <- nlevels(droplevels(d$participant)) > 1
  notes <- character(0)
  if (!random) notes <- c(notes, "one participant: GLM without the random effect")
  dropped <- setdiff(c("space", "view"), factors)
  if (length(dropped)) notes <- c(notes, paste0("dropped (one level): ", paste(dropped, collapse = ", ")))
  rhs_fixed <- c(if (covariate) "x_m", if (length(factors)) paste(factors, collapse = " * "))
  rhs_null <- c(if (covariate) "x_m")
  re <- if (random) "(1 | participant)" else NULL
  make <- function(terms) stats::as.formula(paste("y ~", paste(c(if (length(terms)) terms else "1", re), collapse = " + ")))
  f_full <- make(rhs_fixed)
  result <- list(outcome = outcome_name, formula = paste(deparse(f_full), collapse = " "),
                 family = "binomial (probit)", n = nrow(d), participants = nlevels(droplevels(d$participant)),
                 coefficients = data.frame(), tests = data.frame(), random_sd = NA_real_)
  if (length(unique(d$y)) < 2) {
    result$notes <- c(notes, "outcome does not vary: no model")
    return(result)
  }
  full <- fit_glmm_safely(f_full, d, random)
  notes <- c(notes, full$notes)
  if (is.null(full$fit) && random) {
    notes <- c(notes, "fell back to a GLM without the random effect")
    random <- FALSE; re <- NULL
    f_full <- make(rhs_fixed)
    result$formula <- paste(deparse(f_full), collapse = " ")
    full <- fit_glmm_safely(f_full, d, FALSE)
    notes <- c(notes, full$notes)
  }
  if (is.null(full$fit)) { result$notes <- unique(notes); return(result) }
  cf <- if (random) summary(full$fit)$coefficients else summary(full$fit)$coefficients
  result$coefficients <- data.frame(term = rownames(cf), estimate = cf[, 1], se = cf[, 2],
                                    z = cf[, 3], p = cf[, 4], row.names = NULL)
  if (random) result$random_sd <- sqrt(unname(unlist(lme4::VarCorr(full$fit)))[1])
  lrt <- function(label, reduced_terms) {
    reduced <- fit_glmm_safely(make(reduced_terms), d, random)
    if (is.null(reduced$fit)) return(NULL)
    dev <- as.numeric(2 * (stats::logLik(full$fit) - stats::logLik(reduced$fit)))
    df <- attr(stats::logLik(full$fit), "df") - attr(stats::logLik(reduced$fit), "df")
    data.frame(test = label, chisq = max(dev, 0), df = df,
               p = if (df > 0) stats::pchisq(max(dev, 0), df, lower.tail = FALSE) else NA_real_)
  }
  tests <- list()
  if (length(factors)) tests[[1]] <- lrt(paste(paste(factors, collapse = " × "), "(all terms)"), rhs_null)
  if (length(factors) == 2 && interaction_test)
    tests[[2]] <- lrt("space:view interaction", c(rhs_null, "space + view"))
  tests <- tests[!vapply(tests, is.null, TRUE)]
  if (length(tests)) result$tests <- do.call(rbind, tests)
  result$notes <- unique(notes)
  result$fit <- full$fit
  result
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
