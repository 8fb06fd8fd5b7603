#!/usr/bin/env bash
# taplo (the TOML toolkit behind Even Better TOML and other editors) checks
# every example protocol against protocols/schema.json through its
# `#:schema` directive, and rejects a misspelt key and an unknown space at
# the lines where they are written — as `curvlab validate` does.
# Usage: taplo_protocols.sh SOURCE_DIR CURVLAB
set -uo pipefail
src=$1
curvlab=$2
taplo="$src/tools/node_modules/.bin/taplo"
if [ ! -x "$taplo" ]; then
  echo "FAIL: taplo is not installed at $taplo; run: bash scripts/deps.sh all (it installs tools/package-lock.json's @taplo/cli with npm)"
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0

# 1. Every example validates against the committed schema.
shopt -s nullglob
examples=("$src"/protocols/*.toml)
if [ ${#examples[@]} -lt 5 ]; then echo "FAIL: expected the example protocols in $src/protocols"; exit 1; fi
if ! (cd "$work" && "$taplo" lint --no-auto-config --colors never "${examples[@]}") >"$work/examples.log" 2>&1; then
  echo "FAIL: taplo rejects an example protocol:"; cat "$work/examples.log"; fail=1
else
  echo "ok: taplo validates ${#examples[@]} example protocols against protocols/schema.json"
fi

# 2. A protocol with a misspelt key (line 14) and an unknown space (line 11).
cat >"$work/bad.toml" <<TOML
#:schema $src/protocols/schema.json
[protocol]
name = "bad"
version = "1.0.0"

[randomization]
seed = 1

[space]
# a space that does not exist
kind = "H4"

[timeline]
fixation_msec = 500

[judgement]
type = "choice"
options = [{ value = "a", keys = ["1"] }, { value = "b", keys = ["2"] }]
TOML
(cd "$work" && "$taplo" lint --no-auto-config --colors never bad.toml) >"$work/bad.log" 2>&1
rc=$?
if [ $rc -eq 0 ]; then echo "FAIL: taplo accepted bad.toml"; fail=1; fi
expect() {  # pattern, what
  if grep -Eq "$1" "$work/bad.log"; then echo "ok: taplo reports $2"; else echo "FAIL: taplo does not report $2 (expected /$1/)"; fail=1; fi
}
expect 'bad\.toml:14:1$' "a problem at line 14, column 1 (fixation_msec)"
expect "'fixation_msec' was unexpected" "fixation_msec as an unexpected key"
expect 'bad\.toml:11:8$' "a problem at line 11, column 8 (kind = \"H4\")"
expect '"H4" is not one of \["S3","E3","H3"\]' "H4 as not one of S3, E3, H3"
# Line 14's report is about fixation_msec and line 11's about H4.
if ! grep -A3 'bad\.toml:14:1$' "$work/bad.log" | grep -q 'fixation_msec'; then
  echo "FAIL: the line-14 report does not name fixation_msec"; fail=1
fi
if ! grep -A3 'bad\.toml:11:8$' "$work/bad.log" | grep -q 'H4'; then
  echo "FAIL: the line-11 report does not name H4"; fail=1
fi
# 3. curvlab validate finds the same two problems at the same lines.
"$curvlab" validate "$work/bad.toml" >"$work/validate.log" 2>&1
vrc=$?
[ $vrc -eq 2 ] || { echo "FAIL: curvlab validate exited $vrc, expected 2"; fail=1; }
grep -q 'bad.toml:14:1: error: timeline.fixation_msec: unknown key "fixation_msec"; did you mean "fixation_ms"' "$work/validate.log" ||
  { echo "FAIL: curvlab validate does not report fixation_msec at 14:1"; fail=1; }
grep -q 'bad.toml:11:8: error: space.kind: unknown value "H4"' "$work/validate.log" ||
  { echo "FAIL: curvlab validate does not report H4 at 11:8"; fail=1; }
if [ $fail -ne 0 ]; then
  echo "--- taplo output"; cat "$work/bad.log"; echo "--- curvlab validate output"; cat "$work/validate.log"
fi
exit $fail
