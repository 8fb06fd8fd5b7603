#!/usr/bin/env bash
# First command of the README: installs what running and reporting need
# (not the test suite's tools: scripts/test.sh adds those), builds the
# curvlab executable alone in Release and runs the main job on its embedded
# default, then says where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/deps.sh run
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
# No test suite in this build folder (its GoogleTest is a test tool); the
# benchmarks stay configured and build on request (README, "Tests and
# golden images"). A first build's largest costs are cut: the heaviest
# third-party headers are precompiled once per target (cmake/CurvlabPch.cmake)
# and the code is optimised at -O2, as Debian builds its packages (the ci
# preset keeps CMake's Release -O3). The compiler's output goes to a log; its
# end is shown if the build fails.
cmake --preset release -DCURVLAB_BUILD_TESTS=OFF -DCURVLAB_PCH=ON -DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" \
  "${launcher[@]}" >/dev/null
log=build/release/build.log
echo "== Building curvlab (about 5 minutes on 2 cores the first time; log: $log) =="
if ! cmake --build --preset release -j "$(nproc)" --target curvlab >"$log" 2>&1; then
  tail -n 40 "$log" >&2
  echo "quickstart: the build failed; the whole log is $log" >&2
  exit 1
fi

bin=build/release/bin/curvlab
out=results/demo
rm -rf "$out"
mkdir -p "$out"
echo
echo "== Validating the demo protocol =="
"$bin" validate protocols/demo.toml
echo
echo "== Running it headless: offscreen Vulkan, simulated participant, SQLite =="
"$bin" run protocols/demo.toml --participant P01 --db "$out/demo.sqlite" \
  --images "$out/stimuli" --export "$out/export" | grep -v '^exports:'
echo
echo "== What the simulated observer should find (human observer model, 20 participants) =="
"$bin" predict protocols/demo.toml --participants 20 --simulations 200
if [ -f analysis/report.R ] && command -v Rscript >/dev/null; then
  echo
  echo "== Analysis report =="
  Rscript analysis/report.R --db "$out/demo.sqlite" --out "$out/report"
fi
echo
echo "Results are in $(pwd)/$out:"
echo "  database          $out/demo.sqlite   (every trial, tracked pose and frame; data_schema/codebook.md)"
echo "  exports           $out/export/csv/trials.csv, $out/export/psychds/, $out/export/bids/"
echo "  stimulus images   $out/stimuli/trial_NNNN_{left,right}.png (each trial's onset frame)"
if [ -f "$out/report/report.html" ]; then
  echo "  report            $out/report/report.html"
fi
