#!/usr/bin/env bash
# A whole simulated session with its stimulus onsets drawn (`curvlab run
# --render onset`, the simulated observer answering) on this machine's
# Vulkan device, once with 4 samples per pixel (`--msaa 4`, the default
# before "auto") and once with the protocol's default (`[viewing] msaa`
# unset, "auto": 4 on a GPU, 1 on a CPU device such as lavapipe), in the same
# run, alternating when repeated. Prints per run the samples per pixel drawn
# with, trials, frames, frames drawn, the process's wall time and the
# session loop's (`wall_s` of the summary), and the ratio of the mean times
# to msaa 4's.
#
#   bash bench/simulated_session.sh [PROTOCOL] [REPEATS] [CURVLAB]
#   (defaults: protocols/proposed_study.toml, 1, build/release/bin/curvlab)
set -euo pipefail
protocol=${1:-protocols/proposed_study.toml}
repeats=${2:-1}
curvlab=${3:-build/release/bin/curvlab}
work=$(mktemp -d "${TMPDIR:-/tmp}/simulated-session.XXXXXX")
trap 'rm -rf "$work"' EXIT

for r in $(seq 1 "$repeats"); do
  for setting in 4 default; do
    name="$setting-$r"
    args=()
    [ "$setting" = default ] || args=(--msaa "$setting")
    start=$(date +%s.%N)
    "$curvlab" run "$protocol" --participant P01 --render onset --db "$work/$name.sqlite" --quiet --json \
      "${args[@]}" > "$work/$name.json"
    end=$(date +%s.%N)
    echo "$start $end" > "$work/$name.time"
  done
done

/usr/bin/python3 - "$work" "$repeats" "$protocol" <<'PY'
import json, sqlite3, statistics, sys
work, repeats, protocol = sys.argv[1], int(sys.argv[2]), sys.argv[3]
rows = []
for r in range(1, repeats + 1):
    for setting in ("4", "default"):
        name = f"{work}/{setting}-{r}"
        summary = json.load(open(name + ".json"))
        start, end = (float(t) for t in open(name + ".time").read().split())
        db = sqlite3.connect(f"file:{name}.sqlite?mode=ro", uri=True)
        drawn = db.execute("SELECT COUNT(*) FROM frames WHERE passes > 0").fetchone()[0]
        device = db.execute("SELECT renderer_device FROM sessions").fetchone()[0]
        rows.append(dict(setting="4" if setting == "4" else "auto (default)", msaa=summary["msaa"],
                         trials=summary["trials_completed"], frames=summary["frames"], drawn=drawn,
                         process_s=end - start, session_s=summary["wall_s"], device=device))
print(f"{protocol}, --render onset, on {rows[0]['device']}, {repeats} run(s) each")
print("| msaa asked | msaa drawn | trials | frames | frames drawn | process wall s | session wall s |")
print("|---|---|---|---|---|---|---|")
for x in rows:
    print(f"| {x['setting']} | {x['msaa']} | {x['trials']} | {x['frames']} | {x['drawn']} | "
          f"{x['process_s']:.1f} | {x['session_s']:.1f} |")
def mean(setting, key):
    return statistics.mean(x[key] for x in rows if x["setting"].startswith(setting))
for key, what in (("process_s", "process"), ("session_s", "session")):
    print(f"{what} wall time, auto / msaa 4: {mean('auto', key) / mean('4', key):.2f}")
PY
