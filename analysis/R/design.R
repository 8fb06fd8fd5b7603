# The design of each judgement block, read from the data rather than from
# the protocol text, so that files of any curvlab version and export
# directories are classified the same way.
#
#   constant   the shown intensities are the protocol's fixed levels; the
#              proportion of each answer per level and condition is a
#              meaningful summary, and the space × view choice models apply;
#   staircase  an adaptive method chose each intensity from the previous
#              answers (the block's trials have staircase_steps rows);
#   psi        the same, with a Bayesian adaptive method (Kontsevich & Tyler
#              1999): its step rows carry posterior columns (posterior_*),
#              or its track is named psi.
#
# Under an adaptive method the proportion of an answer depends on the answers
# themselves (a staircase converges on 50 %), so proportions mean nothing;
# such blocks are analysed by psychometric functions of the shown intensity
# per participant and condition, and by a hierarchical psychometric model
# across participants (hierarchical.R).

design_levels <- c("constant", "staircase", "psi")

# Columns of posterior summaries an adaptive method stored with its steps;
# the PSE (the posterior mean or mode of the threshold) first, if any.
posterior_columns <- function(trials) grep("^posterior_", names(trials), value = TRUE)
posterior_pse_column <- function(trials) {
  cols <- posterior_columns(trials)
  pse <- grep("pse|threshold|alpha|location|mean", cols, value = TRUE)
  if (length(pse)) pse[1] else NA_character_
}

# One key per judgement block: a session's block (by index when the source
# has it, else by name).
block_key <- function(trials) {
  block <- if ("block_index" %in% names(trials) && !all(is.na(trials$block_index))) trials$block_index
           else if ("block_name" %in% names(trials)) trials$block_name else rep("block", nrow(trials))
  session <- if ("session_id" %in% names(trials)) trials$session_id else trials$participant
  paste(session, block, sep = "\r")
}

# The design of every trial's block: "constant", "staircase" or "psi".
trial_design <- function(trials) {
  if (!nrow(trials)) return(character(0))
  if ("design" %in% names(trials) && !anyNA(trials$design)) return(as.character(trials$design))
  key <- block_key(trials)
  step <- (!is.na(trials$staircase) & nzchar(trials$staircase)) | !is.na(trials$intensity)
  post <- posterior_columns(trials)
  posterior <- if (length(post)) rowSums(!is.na(trials[post])) > 0 else rep(FALSE, nrow(trials))
  psi_name <- !is.na(trials$staircase) & grepl("(^|[^a-z])psi([^a-z]|$)", tolower(trials$staircase))
  adaptive <- tapply(step, key, any)[key]
  psi <- tapply(posterior | psi_name, key, any)[key]
  unname(ifelse(!adaptive, "constant", ifelse(psi, "psi", "staircase")))
}

is_adaptive <- function(design) design %in% c("staircase", "psi")

# One row per protocol block and design: sessions, participants, trials
# analysed. The design table at the top of the report.
design_summary <- function(trials) {
  d <- analysed_trials(trials)
  if (!nrow(d)) return(data.frame())
  d$design <- trial_design(d)
  block <- if ("block_name" %in% names(d)) d$block_name else rep("(all)", nrow(d))
  key <- paste(block, d$design, sep = "\r")
  rows <- lapply(split(seq_len(nrow(d)), key), function(i) {
    s <- d[i, , drop = FALSE]
    data.frame(block = block[i[1]], design = s$design[1],
               analysis = if (is_adaptive(s$design[1]))
                 "psychometric functions per participant and condition; hierarchical psychometric model"
               else "proportions; psychometric functions where levels vary; space × view choice models",
               sessions = length(unique(s$session_id)), participants = length(unique(s$participant)),
               trials = nrow(s), tracks = length(unique(stats::na.omit(s$staircase))),
               stringsAsFactors = FALSE)
  })
  out <- do.call(rbind, rows)
  rownames(out) <- NULL
  out[order(out$block, match(out$design, design_levels)), , drop = FALSE]
}
