#!/usr/bin/env bash
# The BIDS motion export of the demo session, checked by the official BIDS
# validator (npm bids-validator, pinned in tools/package-lock.json): no
# errors allowed. The warnings it still gives are listed in docs/data.md
# ("Checked by the standards' validators") and printed here.
# Usage: bids_validator.sh SOURCE_DIR CURVLAB
set -uo pipefail
src=$1
curvlab=$2
validator="$src/tools/node_modules/.bin/bids-validator"
if [ ! -x "$validator" ]; then
  echo "FAIL: bids-validator is not installed at $validator; run: bash scripts/deps.sh all (npm ci in tools/)"
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$curvlab" run "$src/protocols/demo.toml" --participant P01 --db "$work/demo.sqlite" >"$work/run.log" 2>&1 ||
  { echo "FAIL: curvlab run of the demo"; cat "$work/run.log"; exit 1; }
"$curvlab" export --db "$work/demo.sqlite" --format bids-motion --out "$work/export" >"$work/export.log" 2>&1 ||
  { echo "FAIL: curvlab export --format bids-motion"; cat "$work/export.log"; exit 1; }
dataset="$work/export/bids"
[ -f "$dataset/dataset_description.json" ] || { echo "FAIL: no $dataset/dataset_description.json"; exit 1; }

# Summarises the validator's JSON: "ERRORS n WARNINGS m" and one line per error or warning.
summarise() {
  /usr/bin/python3 - "$1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
found = d["issues"]
print("ERRORS", len(found["errors"]), "WARNINGS", len(found["warnings"]))
for level in ("errors", "warnings"):
    for i in found[level]:
        files = sorted({f["file"]["relativePath"] for f in i["files"] if f.get("file")})
        print(f"  {level[:-1]} {i['key']}: {i['reason']}" + (f" ({len(files)} file(s), e.g. {files[0]})" if files else ""))
PY
}

HOME="$work" "$validator" "$dataset" --json >"$work/result.json" 2>"$work/validator.log"
summary=$(summarise "$work/result.json") || { echo "FAIL: the validator gave no JSON"; cat "$work/validator.log"; exit 1; }
echo "bids-validator $("$validator" --version 2>/dev/null) on the demo export:"
echo "$summary"
fail=0
grep -q '^ERRORS 0 ' <<<"$summary" || { echo "FAIL: the validator reports errors"; fail=1; }

# The check can fail: the same export with a channel type BIDS does not know.
cp -r "$dataset" "$work/broken"
channels=$(find "$work/broken" -name '*_channels.tsv' | head -1)
sed -i '2s/\tLATENCY\t/\tNOT_A_TYPE\t/' "$channels"
HOME="$work" "$validator" "$work/broken" --json >"$work/broken.json" 2>/dev/null
broken=$(summarise "$work/broken.json")
if grep -q '^ERRORS 0 ' <<<"$broken"; then
  echo "FAIL: the validator accepted a channels.tsv with type NOT_A_TYPE"; fail=1
else
  echo "ok: a channels.tsv with type NOT_A_TYPE is an error ($(head -1 <<<"$broken"))"
fi
exit $fail
