#!/usr/bin/python3
"""describe.py per design: proportions for constant-stimulus blocks only,
thresholds (reversal mean, final step, posterior PSE) for adaptive blocks.

    /usr/bin/python3 tests/analysis/test_describe.py SOURCE_ROOT

Builds trials.csv files the way `curvlab export --format csv` names their
columns (one session: a constant block, a staircase block and a psi block
whose steps carry posterior_pse_m), runs describe.py on them and checks the
numbers against hand-computed ones. Exit 77 (skipped) without pandas.
"""
import os
import subprocess
import sys
import tempfile

try:
    import pandas as pd
except ImportError:
    print("pandas not installed (apt-get install python3-pandas): skipped")
    sys.exit(77)

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ".")
DESCRIBE = os.path.join(ROOT, "analysis", "python", "describe.py")
failures = 0


def check(ok, what):
    global failures
    print(("  ok   " if ok else "  FAIL ") + what)
    if not ok:
        failures += 1


def trial(block_index, block_name, index, response, space="E3", view="tourist", **extra):
    row = {"session_id": 1, "participant": "P01", "block_index": block_index, "block_name": block_name,
           "is_practice": 0, "trial_index": index, "status": "completed", "response": response,
           "response_device": "keyboard", "rt_ns": 500_000_000 + 1000 * index, "staircase": None,
           "staircase_step": None, "intensity": None, "is_reversal": None,
           "cond_space": space, "cond_view": view, "cond_judged": "stick"}
    row.update(extra)
    return row


def staircase_rows(block_index, block_name, track, space, intensities, reversals, start, posterior=None):
    rows = []
    for step, (x, rev) in enumerate(zip(intensities, reversals)):
        extra = {"staircase": track, "staircase_step": step, "intensity": x, "is_reversal": rev,
                 "stim_stick_sagitta_m": x, "cond_staircase": track.split(":")[-1]}
        if posterior is not None:
            extra["posterior_pse_m"] = posterior[step]
        rows.append(trial(block_index, block_name, start + step, "convex" if step % 2 else "concave",
                          space=space, view="native", **extra))
    return rows


def run(args):
    p = subprocess.run([sys.executable, DESCRIBE] + args, capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


with tempfile.TemporaryDirectory() as tmp:
    rows = []
    # Constant block: E3 tourist, 3 convex of 4; H3 tourist, 1 convex of 4.
    for i, (space, r) in enumerate([("E3", "convex")] * 3 + [("E3", "concave")] +
                                   [("H3", "convex")] + [("H3", "concave")] * 3):
        rows.append(trial(0, "constant", i, r, space=space, stim_stick_sagitta_m=0.0))
    # Staircase block, E3 native: reversals at 0.02, -0.01, 0.01, -0.004; after
    # discarding 2, the mean is (0.01 - 0.004) / 2 = 0.003; last step 0.002.
    st_x = [0.06, 0.02, -0.01, 0.01, -0.004, 0.002]
    st_rev = [0, 1, 1, 1, 1, 0]
    rows += staircase_rows(1, "staircase", "staircase:cell0:up", "E3", st_x, st_rev, 100)
    # Psi block, H3 native: no reversals flagged; posterior PSE after the last
    # step -0.0123; last intensity -0.011.
    psi_x = [0.0, -0.02, -0.015, -0.011]
    rows += staircase_rows(2, "psi", "psi:cell0:track", "H3", psi_x, [0, 0, 0, 0], 200,
                           posterior=[0.0, -0.01, -0.012, -0.0123])
    trials = pd.DataFrame(rows)
    mixed_dir = os.path.join(tmp, "mixed")
    os.makedirs(mixed_dir)
    trials.to_csv(os.path.join(mixed_dir, "trials.csv"), index=False, na_rep="NA")

    print("A constant, a staircase and a psi block in one export")
    code, out = run([mixed_dir, "--figure", os.path.join(tmp, "mixed.png")])
    print("\n".join("    " + line for line in out.splitlines()))
    check(code == 0, "exit 0")
    lines = out.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.startswith("Constant-stimulus blocks (8 trials)"))
        end = next(i for i, line in enumerate(lines) if line.startswith("Adaptive blocks"))
        proportions = "\n".join(lines[start:end])
    except StopIteration:
        proportions = ""
    check(proportions != "", "a proportions section for the 8 constant trials, before the adaptive one")
    check("0.75" in proportions and "0.25" in proportions, "E3 0.75 and H3 0.25 convex in the constant block")
    rows_n = [line.split()[-1] for line in proportions.splitlines() if line.startswith(("E3", "H3"))]
    check(rows_n == ["4", "4"], f"proportions count only the constant block's trials (n per row: {rows_n})")
    check("Adaptive blocks (psi, staircase; 10 trials)" in out, "adaptive blocks named by method, 10 trials")
    track = [line for line in lines if "staircase:cell0:up" in line]
    check(len(track) == 1 and " staircase " in track[0] and "0.00300" in track[0] and "0.00200" in track[0],
          "staircase track: method staircase, reversal mean 0.00300 m, final step 0.00200 m")
    psi = [line for line in lines if "psi:cell0:track" in line]
    check(len(psi) == 1 and " psi " in psi[0] and "-0.01230" in psi[0] and "-0.01100" in psi[0]
          and "NaN" in psi[0], "psi track: method psi, posterior PSE -0.01230 m, final -0.01100 m, no reversal mean")
    check(os.path.getsize(os.path.join(tmp, "mixed.png")) > 5000, "figure written")

    print("--discard-reversals 0 uses every reversal")
    code, out = run([mixed_dir, "--figure", os.path.join(tmp, "mixed0.png"), "--discard-reversals", "0"])
    track = [line for line in out.splitlines() if "staircase:cell0:up" in line]
    check(code == 0 and len(track) == 1 and "0.00400" in track[0], "reversal mean (0.02 - 0.01 + 0.01 - 0.004) / 4 = 0.00400")

    print("Only adaptive blocks: no proportions at all, a threshold figure")
    adaptive_dir = os.path.join(tmp, "adaptive")
    os.makedirs(adaptive_dir)
    trials[trials["block_index"] != 0].to_csv(os.path.join(adaptive_dir, "trials.csv"), index=False, na_rep="NA")
    code, out = run([adaptive_dir])
    check(code == 0 and "proportion of each judgement" not in out.lower() and "Per participant and condition" in out,
          "thresholds per participant and condition, no proportions")
    check(os.path.getsize(os.path.join(adaptive_dir, "describe.png")) > 5000, "threshold figure written")

    print("Bad input")
    code, out = run([os.path.join(tmp, "missing")])
    check(code == 2 and "no such file" in out, "exit 2 without trials.csv")
    code, out = run([mixed_dir, "--discard-reversals", "-1"])
    check(code == 2, "exit 2 for a negative --discard-reversals")

if failures:
    print(f"{failures} check(s) failed")
    sys.exit(1)
print("all checks passed")
