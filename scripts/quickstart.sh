#!/usr/bin/env bash
# First command of the README: installs what is missing, builds Release and
# runs the main job on its embedded default, then says where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/deps.sh
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
cmake --preset release "${launcher[@]}" >/dev/null
cmake --build --preset release -j "$(nproc)"

bin=build/release/bin/curvlab
out=results/quickstart
mkdir -p "$out"
echo
echo "== The right-angled billiards tables for a 0.90 m physical edge =="
for space in S3 E3 H3; do
  "$bin" inspect table --space "$space" --edge-m 0.9 | tee "$out/table_$space.txt"
  echo
done
echo "== Holonomy of the head-square (theta = 0.2 rad) =="
for space in S3 H3; do
  "$bin" inspect holonomy --space "$space" --theta-rad 0.2 | tee "$out/holonomy_$space.txt"
  echo
done
echo "== A point 2.5 rad away on S3 of radius 1 m: native and back-hemisphere images =="
"$bin" inspect map --space S3 --radius-m 1 --point 0,0,-0.5984721441,-0.8011436155 | tee "$out/map_S3.txt"
echo
echo "== The cue stick and billiards table in H3, native view (offscreen Vulkan) =="
"$bin" render --space H3 --view native --scene billiards --size 1024x1024 --out "$out/render_H3_native"
echo
echo "Results are in $(pwd)/$out (text tables, and left.png/right.png/plan.json under render_H3_native/)"
