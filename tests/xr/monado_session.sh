#!/usr/bin/env bash
# Whole `--backend xr` sessions through Monado, a real OpenXR runtime (built
# from ../shared/third_party by scripts/monado.sh), with its null compositor
# and simulated headset, under Khronos' core validation layer:
#   - xr-check finds Monado and its simulated HMD;
#   - the demo protocol with buttons with the default head policy: Monado's simulated
#     headset tracks neither orientation nor position, so the first trial
#     waits for the head and, after the bounded wait, the session stops
#     interrupted, resumable, with a message naming the runtime's flags;
#   - the same protocol with `[tracking] head_requires = "none"` completes
#     (nobody presses: every response window times out);
#   - the validation layer reports nothing in either session.
# Exit 77 (skipped) when Monado's source is not here (a user's clone).
#
#   bash tests/xr/monado_session.sh SOURCE_ROOT CURVLAB_BIN LAYER_DIR
set -uo pipefail
source_root=$1
curvlab=$2
layer_dir=${3:-}

manifest=$(bash "$source_root/scripts/monado.sh")
if [ -z "$manifest" ]; then
  echo "skipped: ../shared/third_party/monado-25.0.0.tar.xz is not here (Monado's pinned source)"
  exit 77
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/curvlab-monado.XXXXXX")
trap 'rm -rf "$work"' EXIT
failures=0
check() {  # check CONDITION-EXIT-STATUS WHAT
  if [ "$1" -eq 0 ]; then echo "  ok   $2"; else echo "  FAIL $2"; failures=$((failures + 1)); fi
}

export XR_RUNTIME_JSON=$manifest XRT_COMPOSITOR_NULL=1
export XR_ENABLE_API_LAYERS=XR_APILAYER_LUNARG_core_validation XR_CORE_VALIDATION_EXPORT_TYPE=text
[ -n "$layer_dir" ] && export XR_API_LAYER_PATH=$layer_dir

echo "xr-check through Monado"
XR_CORE_VALIDATION_FILE_NAME=$work/check.txt timeout 60 "$curvlab" xr-check > "$work/check.out" 2>&1
status=$?
cat "$work/check.out"
check "$status" "xr-check exits 0"
grep -q "Monado" "$work/check.out"; check $? "xr-check names Monado"
grep -q "Simulated HMD" "$work/check.out"; check $? "xr-check names the simulated HMD"

echo "the demo protocol with buttons, default head policy (position)"
db=$work/default.sqlite
XR_CORE_VALIDATION_FILE_NAME=$work/default.txt timeout 120 "$curvlab" run "$source_root/tests/xr/demo_buttons.toml" \
  --participant M01 --backend xr --db "$db" --operator-window off > "$work/default.out" 2>&1
status=$?
tail -5 "$work/default.out"
[ "$status" -eq 1 ]; check $? "the session stops with exit 1 (got $status), not killed by the timeout"
[ "$(sqlite3 "$db" "SELECT status FROM sessions")" = "interrupted" ]; check $? "stored interrupted"
grep -q "POSITION_TRACKED" "$work/default.out"; check $? "the message names the runtime's tracking flags"
grep -q "curvlab resume" "$work/default.out"; check $? "the message says how to resume"
[ ! -s "$work/default.txt" ]; check $? "the core validation layer reported nothing"

echo "the demo protocol with buttons, head_requires = \"none\""
protocol=$work/demo_none.toml
sed 's/^\[tracking\]$/[tracking]\nhead_requires = "none"/' "$source_root/tests/xr/demo_buttons.toml" > "$protocol"
grep -q '^head_requires = "none"' "$protocol" || printf '\n[tracking]\nhead_requires = "none"\n' >> "$protocol"
db=$work/none.sqlite
XR_CORE_VALIDATION_FILE_NAME=$work/none.txt timeout 300 "$curvlab" run "$protocol" \
  --participant M02 --backend xr --db "$db" --operator-window off > "$work/none.out" 2>&1
status=$?
tail -5 "$work/none.out"
check "$status" "the session exits 0"
[ "$(sqlite3 "$db" "SELECT status FROM sessions")" = "completed" ]; check $? "stored completed"
[ "$(sqlite3 "$db" "SELECT count(*) FROM trials WHERE status != 'completed'")" = "0" ]; check $? "every trial ended"
[ ! -s "$work/none.txt" ]; check $? "the core validation layer reported nothing"

if [ "$failures" -gt 0 ]; then echo "$failures check(s) failed"; exit 1; fi
echo "all checks passed"
