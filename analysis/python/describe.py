#!/usr/bin/python3
"""Descriptive summary of a curvlab CSV export (pandas + matplotlib).

    /usr/bin/python3 analysis/python/describe.py EXPORT_DIR_OR_TRIALS_CSV [--figure FILE.png]
                                                 [--discard-reversals N]

Each judgement block is described by its design, read from the data as the R
report does (analysis/R/design.R): a block whose trials have staircase steps
is adaptive (a staircase, or a psi method when its steps carry posterior_*
columns or its track is named psi), any other block has constant stimuli.

- Constant-stimulus blocks: how often each judgement was given per condition
  (the cond_* columns that vary) among completed non-practice trials, and a
  figure of those proportions by space and view.
- Adaptive blocks: an answer's share there depends on the answers themselves
  (a staircase converges on 50 %), so they are described by their thresholds
  instead: per track, the mean intensity at its reversals after the first N
  (Levitt 1971), the final step's intensity and, when the method stores one,
  its last posterior PSE; then per participant and condition, the means over
  the condition's tracks. Without constant blocks the figure shows these.

Fits and models are in the R scripts (analysis/report.R); this is the quick
look. Exit 2 on bad input.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

COLOURS = {"convex": "#d95f02", "straight": "#7570b3", "concave": "#1b9e77"}


def fail(message):
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def load(path):
    csv = os.path.join(path, "trials.csv") if os.path.isdir(path) else path
    if not os.path.exists(csv):
        fail(f"{csv}: no such file (expected trials.csv from `curvlab export --format csv`)")
    try:
        trials = pd.read_csv(csv, dtype=str, keep_default_na=False, na_values=["NA"])
    except (pd.errors.ParserError, UnicodeDecodeError, pd.errors.EmptyDataError) as e:
        fail(f"{csv}: cannot read as CSV ({e})")
    # The psi method's posterior summaries, under the names the R report uses.
    trials = trials.rename(columns={c: "posterior_" + c for c in
                                    ("pse_mean", "pse_sd", "slope_mean", "slope_sd", "lapse_mean", "lapse_sd")}
                           | {"posterior_entropy": "posterior_entropy_nats"})
    missing = [c for c in ("participant", "status", "response") if c not in trials.columns]
    if missing:
        fail(f"{csv}: missing column(s) {', '.join(missing)} (expected the curvlab trial CSV)")
    done = trials[(trials["status"] == "completed") & trials["response"].notna()]
    # A response window that ran out is stored as "timeout" from device "none".
    answered = done["response"] != "timeout"
    if "response_device" in done.columns:
        answered &= done["response_device"] != "none"
    done = done[answered]
    if "is_practice" in done.columns:
        done = done[done["is_practice"] != "1"]
    return csv, done


def condition_columns(trials):
    """cond_* columns that label conditions and vary (not staircase names, not numeric levels)."""
    cols = []
    for c in trials.columns:
        if not c.startswith("cond_") or c == "cond_staircase":
            continue
        values = trials[c].dropna()
        if values.nunique() < 2 or pd.to_numeric(values, errors="coerce").notna().all():
            continue
        # A column that only relabels an earlier one (view/projection) adds nothing.
        if any(trials[[k, c]].drop_duplicates().shape[0] == trials[k].nunique() == values.nunique()
               for k in cols):
            continue
        cols.append(c)
    return cols


def block_designs(trials):
    """The design of every trial's block: "constant", "staircase" or "psi" (as analysis/R/design.R)."""
    if trials.empty:
        return pd.Series([], dtype=str)
    block = trials["block_index"] if "block_index" in trials.columns else (
        trials["block_name"] if "block_name" in trials.columns else pd.Series("block", index=trials.index))
    session = trials["session_id"] if "session_id" in trials.columns else trials["participant"]
    key = session.astype(str) + "\r" + block.astype(str)
    track = trials["staircase"] if "staircase" in trials.columns else pd.Series(pd.NA, index=trials.index)
    intensity = trials["intensity"] if "intensity" in trials.columns else pd.Series(pd.NA, index=trials.index)
    step = (track.notna() & (track.astype(str) != "")) | intensity.notna()
    posterior = [c for c in trials.columns if c.startswith("posterior_")]
    psi = track.fillna("").str.lower().str.contains(r"(?:^|[^a-z])psi(?:[^a-z]|$)", regex=True)
    if posterior:
        psi |= trials[posterior].notna().any(axis=1)
    adaptive = step.groupby(key).transform("any")
    psi = psi.groupby(key).transform("any")
    return pd.Series(["constant" if not a else ("psi" if p else "staircase") for a, p in zip(adaptive, psi)],
                     index=trials.index)


def posterior_pse_column(trials):
    """The posterior PSE an adaptive method stored with its steps, if any."""
    cols = [c for c in trials.columns if c.startswith("posterior_")]
    pse = [c for c in cols if any(k in c for k in ("pse", "threshold", "alpha", "location", "mean"))]
    return pse[0] if pse else None


def condition_label(trials, cols):
    if not cols:
        return pd.Series("all trials", index=trials.index)
    return trials[cols].astype(str).agg(" / ".join, axis=1)


def track_thresholds(adaptive, cols, discard):
    """One row per participant and track: steps, reversals, reversal mean, final step, posterior PSE (m)."""
    d = adaptive[adaptive["staircase"].notna()].copy()
    d["condition"] = condition_label(d, cols)
    d["intensity"] = pd.to_numeric(d["intensity"], errors="coerce")
    order = "step_index" if "step_index" in d.columns else (
        "staircase_step" if "staircase_step" in d.columns else "trial_index")
    d["_order"] = pd.to_numeric(d[order], errors="coerce")
    reversal = pd.to_numeric(d["is_reversal"], errors="coerce") if "is_reversal" in d.columns else 0
    d["_reversal"] = pd.Series(reversal, index=d.index).fillna(0) == 1
    posterior = posterior_pse_column(d)
    rows = []
    for (participant, track), s in d.groupby(["participant", "staircase"], sort=True):
        s = s.sort_values("_order")
        reversals = s.loc[s["_reversal"], "intensity"].tolist()
        used = reversals[discard:]
        post = pd.to_numeric(s[posterior], errors="coerce").dropna() if posterior else pd.Series([], dtype=float)
        rows.append({"participant": participant, "condition": s["condition"].iloc[0], "track": track,
                     "method": s["design"].iloc[0], "steps": len(s), "reversals": len(reversals),
                     "reversal_mean_m": sum(used) / len(used) if used else float("nan"),
                     "final_m": s["intensity"].iloc[-1],
                     "posterior_pse_m": post.iloc[-1] if len(post) else float("nan")})
    return pd.DataFrame(rows)


def describe_constant(constant):
    cols = condition_columns(constant)
    by = cols if cols else None
    counts = (constant.groupby(by)["response"].value_counts() if by else constant["response"].value_counts())
    table = counts.unstack(fill_value=0) if by else counts.to_frame().T
    n = table.sum(axis=1)
    props = table.div(n, axis=0)
    props["n"] = n
    print(f"Constant-stimulus blocks ({len(constant)} trials): proportion of each judgement per condition:")
    with pd.option_context("display.width", 160, "display.max_rows", 500):
        print(props.round(3).to_string())


def describe_adaptive(adaptive, discard):
    cols = condition_columns(adaptive)
    tracks = track_thresholds(adaptive, cols, discard)
    methods = ", ".join(sorted(adaptive["design"].unique()))
    print(f"Adaptive blocks ({methods}; {len(adaptive)} trials): proportions are not shown, they depend on the "
          f"answers; thresholds in metres (reversal mean after the first {discard} reversals, final step, "
          "posterior PSE where stored):")
    with pd.option_context("display.width", 200, "display.max_rows", 500, "display.float_format", "{:.5f}".format):
        print("Per track:")
        print(tracks.to_string(index=False))
        summary = (tracks.groupby(["participant", "condition"], sort=True)
                   .agg(method=("method", "first"), tracks=("track", "count"),
                        reversal_mean_m=("reversal_mean_m", "mean"), final_m=("final_m", "mean"),
                        posterior_pse_m=("posterior_pse_m", "mean")))
        print("Per participant and condition (means over tracks):")
        print(summary.to_string())
    return tracks


def figure_constant(ax_row, constant):
    space = constant["cond_space"] if "cond_space" in constant.columns else pd.Series("all", index=constant.index)
    view = constant["cond_view"] if "cond_view" in constant.columns else pd.Series("all", index=constant.index)
    cell = pd.crosstab([space, view], constant["response"], normalize="index")
    for ax, s in zip(ax_row, list(dict.fromkeys(space))):
        part = cell.loc[s]
        bottom = pd.Series(0.0, index=part.index)
        for response in part.columns:
            ax.bar(part.index, part[response], bottom=bottom, label=response,
                   color=COLOURS.get(response, None))
            bottom += part[response]
        ax.set_title(s)
        ax.set_xlabel("view")
        ax.set_ylim(0, 1)
    ax_row[0].set_ylabel("proportion of trials")
    ax_row[-1].legend(title="judgement", loc="upper left", bbox_to_anchor=(1.0, 1.0))


def figure_adaptive(ax, tracks):
    conditions = sorted(tracks["condition"].unique())
    for i, participant in enumerate(sorted(tracks["participant"].unique())):
        t = tracks[tracks["participant"] == participant]
        x = [conditions.index(c) + (i - 2) * 0.04 for c in t["condition"]]
        value = t["reversal_mean_m"].where(t["reversal_mean_m"].notna(), t["final_m"])
        ax.plot(x, 1000 * value, "o", label=participant, alpha=0.8)
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xticks(range(len(conditions)))
    ax.set_xticklabels(conditions, rotation=20)
    ax.set_ylabel("threshold (mm; reversal mean, else final step)")
    ax.legend(title="participant", loc="upper left", bbox_to_anchor=(1.0, 1.0))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("export", help="export directory (with trials.csv) or the trials.csv file")
    parser.add_argument("--figure", default=None, help="PNG to write (default: EXPORT/describe.png)")
    parser.add_argument("--discard-reversals", type=int, default=2,
                        help="reversals left out of each track's reversal mean (default 2, as report.R)")
    args = parser.parse_args()
    if args.discard_reversals < 0:
        fail("--discard-reversals must be a whole number >= 0")
    csv, done = load(args.export)
    if done.empty:
        fail(f"{csv}: no completed non-practice trials")
    done = done.copy()
    done["design"] = block_designs(done)
    constant = done[done["design"] == "constant"]
    adaptive = done[done["design"] != "constant"]

    print(f"{csv}: {len(done)} completed trials, {done['participant'].nunique()} participant(s)")
    if not constant.empty:
        describe_constant(constant)
    tracks = describe_adaptive(adaptive, args.discard_reversals) if not adaptive.empty else None
    if "rt_ns" in done.columns:
        rt = pd.to_numeric(done["rt_ns"], errors="coerce") / 1e6
        print(f"response time: median {rt.median():.0f} ms, IQR {rt.quantile(.25):.0f}-{rt.quantile(.75):.0f} ms")

    if not constant.empty:
        space = constant["cond_space"] if "cond_space" in constant.columns else pd.Series("all", index=constant.index)
        spaces = list(dict.fromkeys(space))
        fig, axes = plt.subplots(1, len(spaces), figsize=(4 * len(spaces) + 1, 4), sharey=True, squeeze=False)
        figure_constant(axes[0], constant)
        fig.suptitle("Judgements by space and view (constant-stimulus blocks)")
    else:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        figure_adaptive(ax, tracks)
        fig.suptitle("Adaptive thresholds per condition (one point per track)")
    fig.tight_layout()
    out = args.figure or os.path.join(os.path.dirname(os.path.abspath(csv)), "describe.png")
    fig.savefig(out, dpi=100)
    print(f"figure: {out}")


if __name__ == "__main__":
    main()
