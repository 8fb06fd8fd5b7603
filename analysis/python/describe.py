#!/usr/bin/python3
"""Descriptive summary of a curvlab CSV export (pandas + matplotlib).

    /usr/bin/python3 analysis/python/describe.py EXPORT_DIR_OR_TRIALS_CSV [--figure FILE.png]

Prints, per condition (the cond_* columns that vary), how often each judgement
was given among completed non-practice trials, and writes one figure: the
proportion of each judgement by space and view. Fits and models are in the R
scripts (analysis/report.R); this is the quick look. Exit 2 on bad input.
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("export", help="export directory (with trials.csv) or the trials.csv file")
    parser.add_argument("--figure", default=None, help="PNG to write (default: EXPORT/describe.png)")
    args = parser.parse_args()
    csv, done = load(args.export)
    if done.empty:
        fail(f"{csv}: no completed non-practice trials")

    cols = condition_columns(done)
    by = cols if cols else None
    counts = (done.groupby(by)["response"].value_counts() if by else done["response"].value_counts())
    table = counts.unstack(fill_value=0) if by else counts.to_frame().T
    n = table.sum(axis=1)
    props = table.div(n, axis=0)
    props["n"] = n
    print(f"{csv}: {len(done)} completed trials, {done['participant'].nunique()} participant(s)")
    print("Proportion of each judgement per condition:")
    with pd.option_context("display.width", 160, "display.max_rows", 500):
        print(props.round(3).to_string())
    if "rt_ns" in done.columns:
        rt = pd.to_numeric(done["rt_ns"], errors="coerce") / 1e6
        print(f"response time: median {rt.median():.0f} ms, IQR {rt.quantile(.25):.0f}-{rt.quantile(.75):.0f} ms")

    space = done["cond_space"] if "cond_space" in done.columns else pd.Series("all", index=done.index)
    view = done["cond_view"] if "cond_view" in done.columns else pd.Series("all", index=done.index)
    cell = pd.crosstab([space, view], done["response"], normalize="index")
    spaces = list(dict.fromkeys(space))
    fig, axes = plt.subplots(1, len(spaces), figsize=(4 * len(spaces) + 1, 4), sharey=True, squeeze=False)
    for ax, s in zip(axes[0], spaces):
        part = cell.loc[s]
        bottom = pd.Series(0.0, index=part.index)
        for response in part.columns:
            ax.bar(part.index, part[response], bottom=bottom, label=response,
                   color=COLOURS.get(response, None))
            bottom += part[response]
        ax.set_title(s)
        ax.set_xlabel("view")
        ax.set_ylim(0, 1)
    axes[0][0].set_ylabel("proportion of trials")
    axes[0][-1].legend(title="judgement", loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.suptitle("Judgements by space and view")
    fig.tight_layout()
    out = args.figure or os.path.join(os.path.dirname(os.path.abspath(csv)), "describe.png")
    fig.savefig(out, dpi=100)
    print(f"figure: {out}")


if __name__ == "__main__":
    main()
