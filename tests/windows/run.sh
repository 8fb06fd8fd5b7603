#!/usr/bin/env bash
# The `windows` ctest label (tests/windows/CMakeLists.txt): the Windows build
# of scripts/build_windows.sh run under Wine and compared with the Linux
# build. Exit 77 (skipped) where ../shared/third_party is absent.
#
#   run.sh CASE SOURCE_DIR LINUX_CURVLAB WINDOWS_BUILD_DIR WORK_DIR
#
# Cases: prefix (makes the Wine prefix the others use), unit-NAME (a gtest
# binary), cli, session, render, resume, desktop, xr, shared.
set -euo pipefail
case_name=$1 src=$2 linux=$3 wbuild=$4 work=$5

third_party=$(cd "$src/.." && pwd)/shared/third_party
if [ ! -d "$third_party" ]; then
  echo "SKIP: $third_party is not here: no Windows build to test (scripts/build_windows.sh)"
  exit 77
fi
# The unpacked zip: what a lab gets, DLLs and fonts included.
exe=$(ls "$wbuild"/package/curvlab-*-win64/curvlab.exe 2>/dev/null | head -1)
if [ ! -f "$exe" ]; then
  exe=$wbuild/package/curvlab-VERSION-win64/curvlab.exe
  echo "$exe is missing: run bash scripts/build_windows.sh (scripts/test.sh does)" >&2
  exit 1
fi

export CURVLAB_WINEPREFIX=$work/wineprefix
wine=("$src/tests/windows/wine.sh" "$wbuild")
compare=(/usr/bin/python3 "$src/tests/windows/compare.py")
# Windows console programs write CRLF to a pipe; JSON does not care.
win() { "${wine[@]}" "$exe" "$@"; }
# Vulkan through winevulkan on lavapipe needs an X display (docs/windows.md).
win_x() { xvfb-run -a "${wine[@]}" "$exe" "$@"; }

out=$work/$case_name
rm -rf "$out"
mkdir -p "$out"
cd "$out"

case $case_name in
  prefix)
    rm -rf "$CURVLAB_WINEPREFIX"
    WINEPREFIX=$CURVLAB_WINEPREFIX WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" /usr/lib/wine/wine64 wineboot -i
    "${wine[@]}" cmd /c echo wine ready
    ;;

  unit-*)
    name=${case_name#unit-}
    case $name in
      protocol) test_exe=$wbuild/tests/windows/protocol_unit_tests.exe ;;
      platform) test_exe=$wbuild/tests/windows/platform_tests.exe ;;
      *) test_exe=$wbuild/tests/$name/${name}_tests.exe ;;
    esac
    filter=${CURVLAB_WINDOWS_GTEST_FILTER:-*}
    (cd "$src" && "${wine[@]}" "$test_exe" --gtest_filter="$filter" --gtest_brief=1)
    ;;

  cli)
    # Every command that needs no GPU, on every example protocol and the
    # geometry of every space: the same JSON as the Linux build.
    commands=()
    # A point of each space of radius 2 m, off the axes.
    declare -A point=([S3]=0.4,0.8,-0.8,1.6 [E3]=0.4,0.8,-0.8,2 [H3]=0.4,0.8,-0.8,2.33238075793812)
    for space in S3 E3 H3; do
      commands+=("inspect table --space $space --edge-m 0.9 --json"
                 "inspect holonomy --space $space --theta-rad 0.3 --json"
                 "inspect map --space $space --radius-m 2 --point ${point[$space]} --json"
                 "inspect vergence --space $space --radius-m 2 --distance-m 1.5 --json"
                 "inspect stick --space $space --radius-m 2 --length-m 1 --distance-m 1.2 --view native --bend-m 0.01 --json")
    done
    # A path that begins with a slash is a path, not a Windows-style /option.
    commands+=("validate $src/protocols/demo.toml --json")
    for p in "$src"/protocols/*.toml; do
      rel=protocols/$(basename "$p")
      commands+=("validate $rel --json" "design $rel --participant 3 --json"
                 "predict $rel --participants 4 --simulations 20 --json")
    done
    n=0
    failed=0
    for c in "${commands[@]}"; do
      n=$((n + 1))
      # The exit status, and the JSON on success or the message on failure.
      lrc=0 wrc=0
      # shellcheck disable=SC2086
      (cd "$src" && "$linux" $c > "$out/$n.linux.json" 2> "$out/$n.linux.err") || lrc=$?
      # shellcheck disable=SC2086
      (cd "$src" && win $c > "$out/$n.windows.json" 2> "$out/$n.windows.err") || wrc=$?
      if [ "$lrc" != "$wrc" ]; then
        echo "differs: curvlab $c: exit $lrc on Linux, $wrc on Windows: $(head -c 300 "$out/$n.windows.err")" >&2
        failed=1
      elif [ "$lrc" != 0 ]; then
        cmp -s "$out/$n.linux.err" <(tr -d '\r' < "$out/$n.windows.err") ||
          { echo "differs: curvlab $c: its message" >&2; failed=1; }
      else
        # MinGW's libm and glibc's differ by an ulp here and there (atan2,
        # asinh): geometry and designs agree to 1e-15. predict's disparities
        # are differences of nearly equal vergence angles, which magnify
        # that ulp (measured: 1.2e-11 relative at most, 1e-9 arcsec).
        tol=1e-12
        case $c in predict*) tol=1e-10 ;; esac
        "${compare[@]}" json --tol $tol "$out/$n.linux.json" "$out/$n.windows.json" ||
          { echo "differs: curvlab $c" >&2; failed=1; }
      fi
    done
    echo "$n commands compared"
    exit $failed
    ;;

  session)
    # A whole headless session of the demo protocol with the simulated
    # observer, rendered on lavapipe, then exported: the same trials as the
    # Linux build's for the same participant. The session's UUID and the
    # wall-clock completion times are the only cells that may differ.
    (cd "$src" && "$linux" run protocols/demo.toml --participant P07 --db "$out/linux.sqlite" --quiet --json > "$out/linux.json")
    (cd "$src" && win_x run protocols/demo.toml --participant P07 --db "$out/windows.sqlite" --quiet --json > "$out/windows.json")
    "$linux" export --db "$out/linux.sqlite" --out "$out/linux" --format csv > /dev/null
    win export --db "$out/windows.sqlite" --out "$out/windows" --format csv > /dev/null
    "${compare[@]}" csv linux/trials.csv windows/trials.csv --ignore session_uuid,completed_utc
    echo "trials.csv: $(($(wc -l < windows/trials.csv) - 1)) trials equal"
    ;;

  render)
    # One stereo frame of each scene in each space, drawn by lavapipe
    # through winevulkan, against the Linux build's PNGs: the same pixels
    # (tolerance 0; set CURVLAB_WINDOWS_PNG_TOL to allow more).
    failed=0
    for space in S3 E3 H3; do
      for scene in stick table billiards; do
        for build in linux windows; do
          args=(render --space $space --view tourist --scene $scene --size 512x512 --out "$out/$build-$space-$scene" --json)
          if [ $build = linux ]; then "$linux" "${args[@]}" > "$out/$build-$space-$scene.json"
          else win_x "${args[@]}" > "$out/$build-$space-$scene.json"; fi
        done
        for eye in left right; do
          "${compare[@]}" png --tol "${CURVLAB_WINDOWS_PNG_TOL:-0}" "linux-$space-$scene/$eye.png" \
            "windows-$space-$scene/$eye.png" || { echo "differs: $space $scene $eye" >&2; failed=1; }
        done
        "${compare[@]}" json --ignore cpu_ms,gpu_ms,frame_ms "linux-$space-$scene.json" "windows-$space-$scene.json" ||
          { echo "differs: $space $scene plan" >&2; failed=1; }
      done
    done
    exit $failed
    ;;

  resume)
    # Durability with Windows file semantics: a realtime session is ended
    # by TerminateProcess (taskkill /F, Windows' kill -9) after its third
    # trial; the trials it completed are in the file, its lock is free at
    # once, and `curvlab resume` completes it. The result equals the Linux
    # build's uninterrupted session but for provenance, the realtime clock
    # (onset_ns, response_ns, rt_ns) and the attempt that was cut short
    # (attempt, and the response its new random stream gave).
    (cd "$src" && xvfb-run -a "${wine[@]}" "$exe" run protocols/demo.toml --participant P05 --db "$out/w.sqlite" \
       --pace realtime --progress json > "$out/run.out" 2> "$out/run.err") &
    runner=$!
    for _ in $(seq 1 240); do
      done_trials=$(grep -c '"status":"completed"' run.out 2>/dev/null || true)
      [ "${done_trials:-0}" -ge 3 ] && break
      kill -0 $runner 2>/dev/null || break
      sleep 0.25
    done
    "${wine[@]}" taskkill /F /IM curvlab.exe
    wait $runner || true
    win sessions --db w.sqlite --json > killed.json
    /usr/bin/python3 - killed.json <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))[0]
assert s["status"] == "interrupted", s
assert s["writer"] is None, f"the killed writer still holds the session: {s['writer']}"
assert 3 <= s["trials_completed"] < s["trials_planned"], s
print(f"killed after {s['trials_completed']} of {s['trials_planned']} trials; the session is free")
PY
    win export --db w.sqlite --out killed --format csv > /dev/null
    (cd "$src" && xvfb-run -a "${wine[@]}" "$exe" resume --db "$out/w.sqlite" --session 1 --quiet --json > "$out/resumed.json")
    grep -q '"trials_completed": 8' resumed.json || { cat resumed.json >&2; exit 1; }
    win export --db w.sqlite --out resumed --format csv > /dev/null
    "${compare[@]}" rows --only status=completed killed/trials.csv resumed/trials.csv
    (cd "$src" && "$linux" run protocols/demo.toml --participant P05 --db "$out/linux.sqlite" --quiet > /dev/null)
    "$linux" export --db "$out/linux.sqlite" --out linux --format csv > /dev/null
    "${compare[@]}" csv linux/trials.csv resumed/trials.csv \
      --ignore session_uuid,completed_utc,onset_ns,response_ns,rt_ns,attempt,response
    echo "resumed: 8 trials, the killed run's trials kept as they were"
    ;;

  desktop)
    # The desktop pilot: a GLFW window with a Win32 Vulkan surface under
    # Xvfb, answered from a key script, on both builds. Every onset
    # screenshot (both eyes and the window) is the Linux build's pixels, and
    # the trials agree but for provenance and the realtime clock.
    { printf 'space 100\n'; for _ in 1 2 3 4 5 6 7 8; do echo "2 100"; done; printf 'space 100\nspace 100\n'; } > keys.txt
    for build in linux windows; do
      args=(run protocols/demo.toml --participant T1 --db "$out/$build.sqlite" --backend desktop --software
            --window-size 256x256 --key-script "$out/keys.txt" --screenshot "$out/$build-shots" --quiet --json)
      if [ $build = linux ]; then (cd "$src" && xvfb-run -a "$linux" "${args[@]}" > "$out/$build.json")
      else (cd "$src" && win_x "${args[@]}" > "$out/$build.json"); fi
      grep -q '"trials_completed": 8' "$out/$build.json" || { echo "$build: $(cat "$out/$build.json")" >&2; exit 1; }
    done
    failed=0
    shots=0
    for f in linux-shots/*.png; do
      shots=$((shots + 1))
      "${compare[@]}" png "$f" "windows-shots/$(basename "$f")" > /dev/null || { echo "differs: $f" >&2; failed=1; }
    done
    [ "$shots" -ge 24 ] || { echo "only $shots screenshots" >&2; failed=1; }
    "$linux" export --db linux.sqlite --out linux --format csv > /dev/null
    win export --db windows.sqlite --out windows --format csv > /dev/null
    "${compare[@]}" csv linux/trials.csv windows/trials.csv \
      --ignore session_uuid,completed_utc,onset_ns,response_ns,rt_ns || failed=1
    echo "desktop: 8 trials, $shots screenshots equal"
    exit $failed
    ;;

  xr)
    # The scripted OpenXR test runtime (tests/xr/runtime) built as a Windows
    # DLL, registered as the active runtime the way SteamVR registers itself
    # (the loader ignores XR_RUNTIME_JSON in an elevated process, and Wine's
    # are), then xr-check and a whole --backend xr session of the buttons
    # demo through the Khronos loader built for Windows. The runtime converts
    # its times to the performance counter, as Windows runtimes do
    # (XR_KHR_win32_convert_performance_counter_time), and scatters its
    # display times by up to 4 ms: every stored display time must be one the
    # runtime handed out, to 50 us, which only the conversion gives.
    cp "$wbuild/tests/windows/xr_runtime/libcurvlab_test_xr_runtime.dll" .
    printf '{\n  "file_format_version": "1.0.0",\n  "runtime": {\n    "name": "curvlab test runtime",\n    "library_path": ".\\\\libcurvlab_test_xr_runtime.dll"\n  }\n}\n' > runtime.json
    manifest=$("${wine[@]}" winepath -w "$out/runtime.json" | tr -d '\r')
    key='HKLM\SOFTWARE\Khronos\OpenXR\1'
    "${wine[@]}" reg add "$key" /v ActiveRuntime /t REG_SZ /d "$manifest" /f > /dev/null
    trap '"${wine[@]}" reg delete "$key" /v ActiveRuntime /f > /dev/null 2>&1 || true' EXIT
    win_x xr-check --json > check.json
    /usr/bin/python3 - check.json <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["ok"] is True and d["runtime"] == "curvlab test runtime 0.1.0", d
assert d["system"] == "curvlab scripted headset" and d["position_tracking"] is True, d
PY
    log_win=$("${wine[@]}" winepath -w "$out/runtime.log" | tr -d '\r')
    (cd "$src" && CURVLAB_TEST_XR_PRESS="right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8" \
       CURVLAB_TEST_XR_TIMING="jitter=4,seed=3" \
       CURVLAB_TEST_XR_LOG="$log_win" win_x run tests/xr/demo_buttons.toml --participant X01 --backend xr \
       --db "$out/xr.sqlite" --json > "$out/run.json")
    win sessions --db xr.sqlite --json > sessions.json
    /usr/bin/python3 - run.json sessions.json runtime.log xr.sqlite <<'PY'
import bisect, json, sqlite3, sys
run = json.load(open(sys.argv[1]))
assert run["status"] == "completed" and run["trials_completed"] == 8, run
assert json.load(open(sys.argv[2]))[0]["backend"] == "xr"
lines = open(sys.argv[3]).read().splitlines()
problems = [l for l in lines if l.startswith(("violation", "warning"))]
assert not problems, "the runtime saw broken rules:\n" + "\n".join(problems[:5])
states = [l.split()[1] for l in lines if l.startswith("state ")]
assert states[:5] == ["XR_SESSION_STATE_IDLE", "XR_SESSION_STATE_READY", "XR_SESSION_STATE_SYNCHRONIZED",
                      "XR_SESSION_STATE_VISIBLE", "XR_SESSION_STATE_FOCUSED"], states
assert states[-1] == "XR_SESSION_STATE_EXITING", states
handed_out = sorted(int(l.split()[5]) for l in lines if l.startswith("frame "))
frames = len(handed_out)
assert frames > 100, frames
assert any(l.startswith("pacing ") for l in lines), "no display time was scattered"
stored = [t for (t,) in sqlite3.connect(sys.argv[4]).execute(
    "SELECT predicted_display_ns FROM frames WHERE predicted_display_ns IS NOT NULL")]
def off(t):
    i = bisect.bisect_left(handed_out, t)
    return min(abs(t - handed_out[j]) for j in (i - 1, i) if 0 <= j < len(handed_out))
worst = max(off(t) for t in stored)
assert len(stored) > 100 and worst < 50_000, (
    f"stored display times are up to {worst / 1e6:.3f} ms from the runtime's ({len(stored)} frames)")
print(f"xr session through the Windows loader: 8 trials, {frames} frames, {len(states)} state changes, "
      f"{len(stored)} stored display times within {worst / 1e3:.1f} us of the runtime's")
PY
    ;;

  shared)
    # Shared play across builds (docs/shared_play.md): the Linux build hosts,
    # curvlab.exe under Wine joins over ENet on the loopback, each with its
    # own database. Both store the same game: the same shot inputs and rest
    # states (each station keeps the shooter's), the same events to the last
    # bits of two C libraries, and every shot the other build simulated again
    # recorded with its difference.
    /usr/bin/python3 - "$src/protocols/adaptation_play.toml" "$out/play.toml" <<'PY'
import sys
text = open(sys.argv[1]).read()
text = text[:text.index("[[blocks]]")].replace('levels = ["E3", "H3"]', 'levels = ["S3", "E3", "H3"]')
text += ('[[blocks]]\nname = "play"\nkind = "play"\nlevels = { space = "H3" }\nduration_s = 120\n'
         'shots = 4\nuntil = "time"\nrack = 3\n')
open(sys.argv[2], "w").write(text)
PY
    port=$((23000 + $$ % 4000))
    station=(run "$out/play.toml" --render none --pace realtime --partner-wait-s 90 --json)
    "$linux" "${station[@]}" --participant HOST01 --db "$out/host.sqlite" --shared host --bind 127.0.0.1 \
      --listen $port > "$out/host.json" 2> "$out/host.err" &
    host=$!
    win "${station[@]}" --participant JOIN01 --db "$out/join.sqlite" --shared join \
      --partner 127.0.0.1:$port > "$out/join.json" 2> "$out/join.err" || { cat "$out/join.err" >&2; kill $host; exit 1; }
    wait $host || { cat "$out/host.err" >&2; exit 1; }
    /usr/bin/python3 - "$out/host.sqlite" "$out/join.sqlite" <<'PY'
import json, sqlite3, sys
q = "SELECT shot_index, player, ball, shot, before_state, rest_state, pocketed, events FROM shots ORDER BY shot_index"
host, join = (sqlite3.connect(p) for p in sys.argv[1:3])
a, b = host.execute(q).fetchall(), join.execute(q).fetchall()
assert len(a) == 4 and len(b) == 4, f"shots stored: host {len(a)}, joiner {len(b)}, expected 4 each"
# Inputs, the state before, the rest state (the shooter's, kept by both)
# and the balls pocketed: the same bytes.
assert [r[:7] for r in a] == [r[:7] for r in b], "the two builds stored different shots or rest states"
# The events each station stored: the same collisions in the same order; the
# numbers may differ in their last bits (two C libraries' sin, cos, exp).
worst_t = worst_x = 0.0
for ra, rb in zip(a, b):
    ea, eb = json.loads(ra[7]), json.loads(rb[7])
    assert [(e["kind"], e.get("balls")) for e in ea] == [(e["kind"], e.get("balls")) for e in eb], \
        f"shot {ra[0]}: different events"
    for x, y in zip(ea, eb):
        worst_t = max(worst_t, abs(x["t_s"] - y["t_s"]))
        for p, r in zip(x.get("after", []), y.get("after", [])):
            worst_x = max(worst_x, abs(p["x_m"] - r["x_m"]), abs(p["z_m"] - r["z_m"]))
assert worst_t < 1e-9 and worst_x < 1e-9, f"events differ by {worst_t} s, {worst_x} m"
game = "SELECT json_extract(detail, '$.game_uuid') FROM events WHERE kind = 'shared_game'"
assert host.execute(game).fetchall() == join.execute(game).fetchall()
checks = ("SELECT json_extract(detail, '$.rest_difference_m') FROM events WHERE kind = 'shared_shot' "
          "AND json_extract(detail, '$.local') = 0")
diffs = [d for (d,) in host.execute(checks).fetchall() + join.execute(checks).fetchall()]
assert len(diffs) == 4 and max(diffs) < 1e-9, f"the other build's rest places: {diffs}"
drawn = join.execute("SELECT count(*) FROM partner_samples WHERE device = 'head'").fetchone()[0]
assert drawn > 20, f"the Windows station drew the Linux player {drawn} times"
print(f"shared game, Linux host and Windows joiner: 4 shots with the same inputs and rest states; "
      f"events within {worst_t:.2g} s and {worst_x:.2g} m; the other build's rest places within "
      f"{max(diffs):.2g} m; the partner drawn {drawn} frames")
PY
    ;;

  *)
    echo "unknown case $case_name" >&2
    exit 2
    ;;
esac
