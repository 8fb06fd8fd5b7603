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
#   - through Monado's `remote` driver (P_OVERRIDE_ACTIVE_CONFIG=remote), a
#     scripted participant (curvlab_monado_remote) streams a tracked head,
#     both Index controllers and their buttons over Monado's socket: the
#     demo protocol with instruction pages, a break and a closing page is
#     answered with buttons through the runtime's Touch bindings and
#     completes; the stored head and hands are where the stream put them;
#   - the session the untracked headset interrupted is resumed through the
#     remote driver and completes;
#   - the validation layer reports nothing in any session.
# Exit 77 (skipped) when Monado's source is not here (a user's clone).
#
#   bash tests/xr/monado_session.sh SOURCE_ROOT CURVLAB_BIN LAYER_DIR REMOTE_BIN
set -uo pipefail
source_root=$1
curvlab=$2
layer_dir=${3:-}
remote=${4:-}

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

echo "the demo protocol with pages and a break, answered with buttons through Monado's remote driver"
# Monado reads the remote driver's port from its config file; a free port
# keeps concurrent runs apart.
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
mkdir -p "$work/config/monado"
printf '{"remote": {"version": 0, "port": %s, "view_count": 2}}\n' "$port" > "$work/config/monado/config_v0.json"
protocol=$work/demo_pages.toml
sed 's/^\[session\]$/[session]\nbreak_every_trials = 4/' "$source_root/tests/xr/demo_buttons.toml" > "$protocol"
printf '\n[instructions]\nstart = ["Judge the stick.", "Answer with the buttons."]\nend = ["Thank you."]\n' >> "$protocol"
db=$work/remote.sqlite
# The scripted runtime's participant: A, X, right trigger, one every 0.6 s.
CURVLAB_TEST_XR_PRESS="right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8" \
  timeout 300 "$remote" "$port" > "$work/remote_participant.out" 2>&1 &
participant=$!
P_OVERRIDE_ACTIVE_CONFIG=remote XDG_CONFIG_HOME=$work/config XR_CORE_VALIDATION_FILE_NAME=$work/remote.txt \
  timeout 240 "$curvlab" run "$protocol" --participant M03 --backend xr --db "$db" --operator-window off \
  > "$work/remote.out" 2>&1
status=$?
grep -v "Dropping old missed frame" "$work/remote.out" | tail -3
wait "$participant"
participant_status=$?
cat "$work/remote_participant.out"
check "$status" "the session exits 0"
[ "$participant_status" -eq 0 ]; check $? "Monado's remote driver took the participant's stream (layout checked against its reset packet)"
grep -q "Remote HMD" "$work/remote.out"; check $? "Monado chose its remote devices"
[ "$(sqlite3 "$db" "SELECT status FROM sessions")" = "completed" ]; check $? "stored completed"
answered=$(sqlite3 "$db" "SELECT count(*) FROM trials WHERE status = 'completed' AND response_device LIKE 'xr:%' AND response IN ('convex', 'straight', 'concave')")
[ "$answered" = "8" ]; check $? "all 8 trials answered with controller buttons (got $answered)"
[ "$(sqlite3 "$db" "SELECT count(DISTINCT response) FROM trials")" = "3" ]; check $? "A, X and the trigger each gave their answer"
pages=$(sqlite3 "$db" "SELECT group_concat(kind) FROM (SELECT kind FROM events WHERE kind IN ('instructions', 'break') ORDER BY t_ns)")
[ "$pages" = "instructions,instructions,break" ]; check $? "two instruction pages and a break were shown and left with a button (got $pages)"
# The stream's head: 1.6 m up, 0.85 m behind the table's centre, swaying by
# at most 10 mm sideways and 8 mm forwards; the hands rest at (±0.25, 0.79,
# 0.52) (tests/xr/runtime/script.cpp). Monado's stage is the stream's frame.
far=$(sqlite3 "$db" "SELECT count(*) FROM tracking_samples WHERE position_valid = 1 AND (
  (device = 'head' AND (abs(lab_px_m) > 0.0101 OR abs(lab_py_m - 1.6) > 1e-5 OR abs(lab_pz_m - 0.85) > 0.0081)) OR
  (device = 'left_hand' AND (abs(lab_px_m + 0.25) > 1e-5 OR abs(lab_py_m - 0.79) > 1e-5 OR abs(lab_pz_m - 0.52) > 1e-5)) OR
  (device = 'right_hand' AND (abs(lab_px_m - 0.25) > 1e-5 OR abs(lab_py_m - 0.79) > 1e-5 OR abs(lab_pz_m - 0.52) > 1e-5)))")
tracked=$(sqlite3 "$db" "SELECT count(*) FROM tracking_samples WHERE position_valid = 1")
[ "$far" = "0" ] && [ "$tracked" -gt 100 ]; check $? "$tracked tracked samples stored where the stream put the head and hands ($far elsewhere)"
[ ! -s "$work/remote.txt" ]; check $? "the core validation layer reported nothing"

echo "the session the untracked headset interrupted, resumed with a tracked head through the remote driver"
db=$work/default.sqlite
CURVLAB_TEST_XR_PRESS="right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8" \
  timeout 300 "$remote" "$port" > "$work/resume_participant.out" 2>&1 &
participant=$!
P_OVERRIDE_ACTIVE_CONFIG=remote XDG_CONFIG_HOME=$work/config XR_CORE_VALIDATION_FILE_NAME=$work/resume.txt \
  timeout 240 "$curvlab" resume --db "$db" --session 1 --backend xr --operator-window off > "$work/resume.out" 2>&1
status=$?
grep -v "Dropping old missed frame" "$work/resume.out" | tail -3
wait "$participant"
check "$status" "the resumed session exits 0"
[ "$(sqlite3 "$db" "SELECT status FROM sessions")" = "completed" ]; check $? "stored completed"
answered=$(sqlite3 "$db" "SELECT count(*) FROM trials WHERE status = 'completed' AND response_device LIKE 'xr:%'")
[ "$answered" = "8" ]; check $? "all 8 trials answered with buttons after the resume (got $answered)"
[ ! -s "$work/resume.txt" ]; check $? "the core validation layer reported nothing"

if [ "$failures" -gt 0 ]; then echo "$failures check(s) failed"; exit 1; fi
echo "all checks passed"
