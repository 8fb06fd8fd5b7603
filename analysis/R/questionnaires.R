# Questionnaire blocks (docs/questionnaires.md): each block's subscale scores
# as curvlab stored them when the block ended, per participant — for the
# Simulator Sickness Questionnaire the Nausea, Oculomotor, Disorientation and
# Total scores of Kennedy, Lane, Berbaum & Lilienthal (1993) in each SSQ
# block (before and after exposure), and the change from a session's first
# SSQ block to its last; for the protocol's own instruments their subscales.

ssq_subscales <- c("nausea", "oculomotor", "disorientation", "total")

# One row per participant × session × block, one column per SSQ subscale.
ssq_score_table <- function(scores) {
  if (is.null(scores) || !nrow(scores)) return(data.frame())
  d <- scores[scores$instrument == "ssq", , drop = FALSE]
  if (!nrow(d)) return(data.frame())
  d$score <- as.numeric(d$score)
  d$block_index <- as.integer(d$block_index)
  keys <- unique(d[c("session_id", "participant", "block_index", "block")])
  keys <- keys[order(keys$participant, keys$session_id, keys$block_index), , drop = FALSE]
  out <- data.frame(participant = keys$participant, session = keys$session_id, block = keys$block,
                    stringsAsFactors = FALSE)
  for (s in ssq_subscales)
    out[[s]] <- vapply(seq_len(nrow(keys)), function(i) {
      v <- d$score[d$session_id == keys$session_id[i] & d$block_index == keys$block_index[i] & d$subscale == s]
      if (length(v)) round(v[1], 2) else NA_real_
    }, 0)
  out
}

# Per session with two SSQ blocks or more: the last minus the first, per
# subscale (positive: more sickness after exposure).
ssq_change_table <- function(ssq) {
  if (!nrow(ssq)) return(data.frame())
  rows <- lapply(split(ssq, ssq$session), function(s) {
    if (nrow(s) < 2) return(NULL)
    first <- s[1, ]; last <- s[nrow(s), ]
    r <- data.frame(participant = first$participant, session = first$session,
                    from = first$block, to = last$block, stringsAsFactors = FALSE)
    for (k in ssq_subscales) r[[paste0(k, "_change")]] <- round(last[[k]] - first[[k]], 2)
    r
  })
  rows <- rows[!vapply(rows, is.null, TRUE)]
  if (!length(rows)) data.frame() else do.call(rbind, rows)
}

# The protocol's own instruments: one row per participant × block × subscale.
custom_score_table <- function(scores) {
  if (is.null(scores) || !nrow(scores)) return(data.frame())
  d <- scores[scores$instrument != "ssq", , drop = FALSE]
  if (!nrow(d)) return(data.frame())
  d <- d[order(d$participant, d$session_id, as.integer(d$block_index)), , drop = FALSE]
  data.frame(participant = d$participant, session = d$session_id, block = d$block, instrument = d$instrument,
             subscale = d$subscale, rule = d$rule, answered = paste0(d$answered, "/", d$items),
             score = round(as.numeric(d$score), 3), stringsAsFactors = FALSE)
}

questionnaire_section_html <- function(scores) {
  if (is.null(scores) || !nrow(scores)) return("")
  ssq <- ssq_score_table(scores)
  change <- ssq_change_table(ssq)
  custom <- custom_score_table(scores)
  c("<h2>Questionnaires</h2>",
    if (nrow(ssq)) c(
      "<h3>Simulator Sickness Questionnaire</h3>",
      "<p class=\"method\">Scores as Kennedy, Lane, Berbaum &amp; Lilienthal (1993, Int. J. Aviation Psychology 3(3):203&ndash;220): the 0&ndash;3 ratings summed over each factor's items and weighted, Nausea &times; 9.54, Oculomotor &times; 7.58, Disorientation &times; 13.92, Total (the three raw sums added) &times; 3.74. A score is empty where an item was not answered.</p>",
      html_table(ssq, "SSQ scores per participant and block, in the session's run order"),
      if (nrow(change)) html_table(change, "Change across exposure: the session's last SSQ block minus its first")
      else "<p class=\"empty\">(no session with two SSQ blocks: no change to show)</p>")
    else "",
    if (nrow(custom)) c("<h3>The protocol's instruments</h3>",
                        html_table(custom, "Subscale scores (weight × sum or mean of the items; reversed items mirrored)"))
    else "")
}
