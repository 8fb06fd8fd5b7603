# Play blocks (docs/billiards.md): each block's figures — shots, balls
# pocketed, time, distance walked, laps round the physical and the virtual
# table — and, for judge → play → judge designs, how the judgements changed
# across play, per space × view, with a logistic model of the change.

play_summary_table <- function(play) {
  if (is.null(play) || !nrow(play)) return(data.frame())
  out <- data.frame(participant = play$participant, block = play$block, space = play$space,
                    shots = as.integer(play$shots), pocketed = as.integer(play$pocketed),
                    minutes = round(as.numeric(play$time_s) / 60, 2),
                    walked_m = round(as.numeric(play$walked_m), 1),
                    laps_physical = round(abs(as.numeric(play$laps_physical)), 2),
                    laps_virtual = round(abs(as.numeric(play$laps_virtual)), 2),
                    stringsAsFactors = FALSE)
  out$laps_ratio <- ifelse(out$laps_virtual > 0,
                           round(abs(as.numeric(play$laps_physical) / as.numeric(play$laps_virtual)), 3), NA)
  out$hand_error_mm <- round(1000 * as.numeric(play$hand_error_m), 2)
  out
}

# Each analysed trial's place relative to its session's first play block:
# "before" or "after" (NA in sessions without play).
play_phase <- function(trials, play) {
  first <- if (is.null(play) || !nrow(play)) numeric(0) else
    tapply(as.numeric(play$block_index), play$session_id, min)
  at <- first[as.character(trials$session_id)]
  ifelse(is.na(at), NA_character_, ifelse(trials$block_index < at, "before", "after"))
}

# Shares of `positive` answers before and after play per space × view, and
# y ~ phase * space (+ view where it varies), binomial; the phase terms are
# the change across play.
play_change <- function(trials, play, positive) {
  d <- trials
  d$phase <- play_phase(d, play)
  d <- d[!is.na(d$phase), , drop = FALSE]
  if (!nrow(d) || length(unique(d$phase)) < 2) return(NULL)
  d$space <- if ("cond_space" %in% names(d)) as.character(d$cond_space) else "(one space)"
  d$view <- if ("cond_view" %in% names(d)) as.character(d$cond_view) else "(one view)"
  d$y <- as.integer(d$response == positive)
  cells <- stats::aggregate(y ~ space + view + phase, d, function(v) c(n = length(v), share = mean(v)))
  shares <- data.frame(space = cells$space, view = cells$view, phase = cells$phase,
                       trials = as.integer(cells$y[, "n"]), share = round(cells$y[, "share"], 3))
  wide <- stats::reshape(shares, idvar = c("space", "view"), timevar = "phase", direction = "wide")
  if (all(c("share.before", "share.after") %in% names(wide)))
    wide$change <- round(wide$share.after - wide$share.before, 3)
  d$phase <- factor(d$phase, levels = c("before", "after"))
  terms <- c("phase", if (length(unique(d$space)) > 1) "phase:space" else NULL,
             if (length(unique(d$view)) > 1) "phase:view" else NULL)
  rhs <- paste(c("phase", if (length(unique(d$space)) > 1) c("space") else NULL,
                 if (length(unique(d$view)) > 1) "view" else NULL, terms[-1]), collapse = " + ")
  formula_text <- paste("y ~", rhs)
  notes <- character(0)
  fit <- withCallingHandlers(
    tryCatch(stats::glm(stats::as.formula(formula_text), family = stats::binomial(), data = d),
             error = function(e) { notes <<- c(notes, paste("the model could not be fitted:", conditionMessage(e))); NULL }),
    warning = function(w) {
      notes <<- c(notes, if (grepl("fitted probabilities numerically 0 or 1", conditionMessage(w)))
        "some cells are all one answer, so their log-odds are unbounded (separation); read their estimates as large, not exact"
      else paste("R warned:", conditionMessage(w)))
      invokeRestart("muffleWarning")
    })
  coefs <- if (is.null(fit)) data.frame() else {
    s <- summary(fit)$coefficients
    keep <- grepl("^phase", rownames(s)) | grepl(":phase", rownames(s))
    data.frame(term = rownames(s)[keep], log_odds = round(s[keep, 1], 3), se = round(s[keep, 2], 3),
               p = signif(s[keep, 4], 3), row.names = NULL)
  }
  if (nrow(coefs) && any(coefs$se > 50))
    notes <- c(notes, paste("some cells are all one answer before or after play, so their log-odds change is unbounded",
                            "(separation: huge standard errors); read the shares instead"))
  list(shares = wide, coefficients = coefs, formula = formula_text, notes = unique(notes), trials = nrow(d))
}

# Shared games (docs/shared_play.md), one row per station: each station
# stores its own copy of the game, so a merged study has both sides; the
# shots each player struck and the balls pocketed on them must agree.
shared_games_table <- function(play) {
  if (is.null(play) || !nrow(play) || !"game_uuid" %in% names(play)) return(data.frame())
  g <- play[!is.na(play$game_uuid), , drop = FALSE]
  if (!nrow(g)) return(data.frame())
  out <- data.frame(game = substr(g$game_uuid, 1, 8), participant = g$participant, role = g$role, space = g$space,
                    ended = g$ended, host_shots = as.integer(g$host_shots), join_shots = as.integer(g$join_shots),
                    host_pocketed = as.integer(g$host_pocketed), join_pocketed = as.integer(g$join_pocketed),
                    walked_m = round(as.numeric(g$walked_m), 1),
                    laps_physical = round(abs(as.numeric(g$laps_physical)), 2),
                    laps_virtual = round(abs(as.numeric(g$laps_virtual)), 2),
                    partner_distance_m = if ("partner_distance_m" %in% names(g)) round(as.numeric(g$partner_distance_m), 2) else NA_real_,
                    partner_closest_m = if ("partner_closest_m" %in% names(g)) round(as.numeric(g$partner_closest_m), 2) else NA_real_,
                    stringsAsFactors = FALSE)
  key <- paste(out$host_shots, out$join_shots, out$host_pocketed, out$join_pocketed)
  sides <- tapply(key, out$game, function(k) if (length(k) < 2) NA else length(unique(k)) == 1)
  out$both_sides_agree <- ifelse(is.na(sides[out$game]), "(one side)", ifelse(sides[out$game], "yes", "NO"))
  out[order(out$game, out$role), , drop = FALSE]
}

play_section_html <- function(play, trials, positive) {
  summary <- play_summary_table(play)
  if (!nrow(summary)) return("")
  change <- play_change(trials, play, positive)
  shared <- shared_games_table(play)
  c("<h2>Play</h2>",
    "<p class=\"method\">Each play block's figures: laps are the head's unwrapped azimuth about the physical table's centre and about the virtual table's, so their ratio is the number of physical laps per virtual lap (the paper's 0.75 for the S3 triangle, 1.25 for the H3 pentagon); the hand error is the mean seen-versus-felt distance of the hands.</p>",
    html_table(summary, "Play blocks per participant (laps as absolute values)"),
    if (nrow(shared)) c(
      "<h3>Shared games</h3>",
      "<p class=\"method\">Two stations, one game (docs/shared_play.md): each row is one station's copy, with the shots the host and the joiner struck and the balls pocketed on them, that station's player's walk round its own physical table, and how far apart the two players' heads were in the virtual space (mean and closest, geodesic, as this station drew the partner). Where both stations' files are in the study, their copies must agree.</p>",
      html_table(shared, "Shared games, from each station"))
    else "",
    if (!is.null(change)) c(
      sprintf("<p>Judgements before and after the first play block of each session (%d answered trials): the share of <em>%s</em> answers per space &times; view, and a logistic model <code>%s</code> whose phase terms are the change across play.</p>",
              change$trials, html_escape(positive), html_escape(change$formula)),
      html_table(change$shares, "Share of positive answers before and after play"),
      html_table(change$coefficients, "Change across play: log-odds (after vs before), Wald SE and p"),
      if (length(change$notes)) paste0("<p class=\"note\">", html_escape(change$notes), "</p>", collapse = "") else "")
    else "<p class=\"empty\">(no judgements on both sides of a play block)</p>")
}
