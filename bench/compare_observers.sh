#!/usr/bin/env bash
# Runs a protocol with the human-model observer and with the
# image-reading observer (`--observer image`) for the same participants —
# same seeds, so the same noise and lapses — and prints the response
# proportions per condition side by side. A protocol whose stick is plain is
# given rings first (stimulus.stick_marks = "rings"; the perception model
# ignores marks). Both observers perceive with the same human limits: the
# model from the scene's geometry, the image observer from the disparities of
# the rings it finds in the pixels. Beside the proportions, each condition's
# mean perceived sagitta from each observer (the onset events' values, stick
# trials), so that agreement is seen in the percepts and not only in answers
# that saturate.
#
#   bash bench/compare_observers.sh [PROTOCOL] [PARTICIPANTS] [CURVLAB]
#   (defaults: protocols/proposed_study.toml, 4, build/release/bin/curvlab)
set -euo pipefail
protocol=${1:-protocols/proposed_study.toml}
participants=${2:-4}
curvlab=${3:-build/release/bin/curvlab}
work=$(mktemp -d "${TMPDIR:-/tmp}/compare-observers.XXXXXX")
trap 'rm -rf "$work"' EXIT

marked="$work/marked.toml"
if grep -q '^stick_marks' "$protocol"; then
  cp "$protocol" "$marked"
else
  sed 's/^\[stimulus\]$/[stimulus]\nstick_marks = "rings"/' "$protocol" > "$marked"
fi

for observer in human image; do
  start=$(date +%s)
  for n in $(seq 1 "$participants"); do
    "$curvlab" run "$marked" --participant "P$(printf %02d "$n")" --db "$work/$observer.sqlite" \
      --render none --quiet --observer "$observer" > /dev/null
  done
  echo "$observer: $participants participants in $(( $(date +%s) - start )) s" >&2
done

/usr/bin/python3 - "$work/human.sqlite" "$work/image.sqlite" <<'PY'
import sqlite3, sys
from collections import defaultdict

def proportions(path):
    rows = sqlite3.connect(path).execute(
        "SELECT json_extract(conditions, '$.judged'), json_extract(conditions, '$.space'), "
        "json_extract(conditions, '$.view'), "
        "CASE json_extract(conditions, '$.judged') WHEN 'stick' THEN json_extract(conditions, '$.stick_bend') "
        "ELSE json_extract(conditions, '$.table_bend') END, "
        "response FROM trials t JOIN blocks b ON b.block_id = t.block_id "
        "WHERE b.is_practice = 0 AND t.status = 'completed'").fetchall()
    counts = defaultdict(lambda: defaultdict(int))
    for judged, space, view, bend, response in rows:
        counts[(judged, space, view, bend)][response] += 1
    return counts

def sagittas(path):
    rows = sqlite3.connect(path).execute(
        "SELECT json_extract(t.conditions, '$.space'), json_extract(t.conditions, '$.view'), "
        "json_extract(t.conditions, '$.stick_bend'), json_extract(e.detail, '$.perceived_sagitta_m') "
        "FROM events e JOIN trials t ON t.trial_id = e.trial_id JOIN blocks b ON b.block_id = t.block_id "
        "WHERE e.kind = 'onset' AND b.is_practice = 0 "
        "AND json_extract(t.conditions, '$.judged') = 'stick'").fetchall()
    sums = defaultdict(lambda: [0.0, 0])
    for space, view, bend, s in rows:
        if s is not None:
            sums[("stick", space, view, bend)][0] += s
            sums[("stick", space, view, bend)][1] += 1
    return {k: v[0] / v[1] for k, v in sums.items()}

model, image = proportions(sys.argv[1]), proportions(sys.argv[2])
model_s, image_s = sagittas(sys.argv[1]), sagittas(sys.argv[2])
options = ["convex", "straight", "concave"]
print(f"{'judged':6} {'space':5} {'view':9} {'bend':>6} {'n':>3} | "
      + " ".join(f"{'model ' + o[:4]:>11}" for o in options) + " | "
      + " ".join(f"{'image ' + o[:4]:>11}" for o in options) + " | max |diff| | s model  s image (m)")
worst = 0.0
for key in sorted(model):
    m, i = model[key], image[key]
    n = sum(m.values())
    pm = [m[o] / n for o in options]
    pi = [i[o] / max(1, sum(i.values())) for o in options]
    diff = max(abs(a - b) for a, b in zip(pm, pi))
    worst = max(worst, diff)
    print(f"{key[0]:6} {key[1]:5} {key[2]:9} {key[3]:>6} {n:3d} | "
          + " ".join(f"{p:11.2f}" for p in pm) + " | " + " ".join(f"{p:11.2f}" for p in pi)
          + f" | {diff:10.2f} | " + (f"{model_s[key]:+7.4f} {image_s[key]:+8.4f}" if key in model_s and key in image_s else ""))
print(f"largest difference in any proportion: {worst:.2f}")
PY
