#!/usr/bin/env bash
# What including a header costs: for each translation unit given (default:
# one that includes only the display seam, and two runner sources),
# the number of headers it pulls in (g++ -H), how many of them are Vulkan's,
# and the user CPU time of a syntax-only compile. Run from the repository
# root; compare two checkouts by running it in each.
set -euo pipefail
root=$(pwd)
flags=(-DCURVLAB_DEFAULT_FONT=\"x\" -DGLM_FORCE_XYZW_ONLY -DVULKAN_HPP_NO_CONSTRUCTORS
       -I"$root/harness/include" -I"$root/geometry/include" -I"$root/renderer/include" -O3 -DNDEBUG -std=c++20)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '#include "curvlab/harness/io/display.hpp"\nint main() { return 0; }\n' > "$tmp/display_only.cpp"
units=("$@")
[ ${#units[@]} -eq 0 ] && units=("$tmp/display_only.cpp" harness/src/runner/predict.cpp harness/src/runner/session.cpp)
for tu in "${units[@]}"; do
  out=$( { /usr/bin/time -f "%U" c++ "${flags[@]}" -H -fsyntax-only "$tu"; } 2>&1 )
  headers=$(grep -c '^\.' <<<"$out" || true)
  vulkan=$(grep '^\.' <<<"$out" | grep -c 'vulkan' || true)
  echo "$(basename "$tu"): headers=$headers vulkan_headers=$vulkan user_cpu_s=$(tail -1 <<<"$out")"
done
