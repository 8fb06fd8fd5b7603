#!/usr/bin/env bash
# The Psych-DS export of the demo session against the specification's rules
# (check_psychds.py; no Psych-DS validator is published on npm or in
# Debian), and the same checker rejecting broken copies, so it can fail.
# Usage: psychds_rules.sh SOURCE_DIR CURVLAB
set -uo pipefail
src=$1
curvlab=$2
check="/usr/bin/python3 $(dirname "$0")/check_psychds.py"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$curvlab" run "$src/protocols/demo.toml" --participant P01 --db "$work/demo.sqlite" >"$work/run.log" 2>&1 ||
  { echo "FAIL: curvlab run of the demo"; cat "$work/run.log"; exit 1; }
"$curvlab" export --db "$work/demo.sqlite" --format psychds --out "$work/export" >"$work/export.log" 2>&1 ||
  { echo "FAIL: curvlab export --format psychds"; cat "$work/export.log"; exit 1; }
dataset="$work/export/psychds"
fail=0
if $check "$dataset" >"$work/check.log"; then
  echo "ok: the demo's Psych-DS export follows the rules ($(tail -1 "$work/check.log"))"
else
  echo "FAIL: the demo's Psych-DS export breaks a rule:"; cat "$work/check.log"; fail=1
fi

# Each broken copy must give its error code.
broken() {  # name, expected code, command run inside the copy
  rm -rf "$work/$1"; cp -r "$dataset" "$work/$1"
  (cd "$work/$1" && eval "$3")
  if $check "$work/$1" >"$work/$1.log"; then
    echo "FAIL: $1 was accepted"; fail=1
  elif grep -q "^error $2:" "$work/$1.log"; then
    echo "ok: $1 gives $2"
  else
    echo "FAIL: $1 did not give $2:"; cat "$work/$1.log"; fail=1
  fi
}
first_csv='$(ls data/*.csv | head -1)'
broken bad_name FILENAME_KEYWORD_FORMATTING_ERROR "mv $first_csv data/demo_P01.csv"
broken not_a_dataset INCORRECT_DATASET_TYPE "sed -i 's/\"@type\": \"Dataset\"/\"@type\": \"Thing\"/' dataset_description.json"
broken no_context INVALID_JSONLD_FORMATTING "sed -i '/\"@context\"/d' dataset_description.json"
broken undescribed_column CSV_COLUMN_MISSING_FROM_METADATA "sed -i '1s/^session_id,/session_key,/' $first_csv"
broken ragged_row CSV_HEADER_LENGTH_MISMATCH "sed -i '2s/\$/,extra/' $first_csv"
broken no_data MISSING_DATA_DIRECTORY "rm -r data"
exit $fail
