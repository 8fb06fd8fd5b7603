#!/usr/bin/env bash
# The body both fuzz scripts share: builds TARGET in its own tree
# (build/fuzz, clang, CURVLAB_FUZZ=ON, libFuzzer + AddressSanitizer + UBSan)
# so the default and CI builds never see it, seeds NAME's corpus with SEEDS,
# and runs RUNS executions with DICT and MAX_LEN.
#   bash bench/fuzz_run.sh TARGET NAME DICT MAX_LEN RUNS "SEEDS…" [extra libFuzzer flags…]
# Exit status is libFuzzer's: 0 when no crash, hang or sanitizer report.
set -euo pipefail
cd "$(dirname "$0")/.."

target=$1 name=$2 dict=$3 max_len=$4 runs=$5 seeds=$6
shift 6
build=build/fuzz
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCURVLAB_FUZZ=ON -DCURVLAB_BUILD_TESTS=OFF -DCURVLAB_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" --target "$target" -j "$(nproc)"

corpus="$build/${name}corpus"   # grows as the fuzzer finds new paths; seeds copied in
artifacts="$build/${name}artifacts/"
mkdir -p "$corpus" "$artifacts"
# shellcheck disable=SC2086  # SEEDS is a list of globs
cp $seeds "$corpus/"

export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export ASAN_OPTIONS=detect_leaks=1
"$build/bin/$target" "$corpus" \
  -runs="$runs" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -dict="$dict" -artifact_prefix="$artifacts" -print_final_stats=1 "$@"
