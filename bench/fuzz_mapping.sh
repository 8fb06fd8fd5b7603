#!/usr/bin/env bash
# Fuzzes the HID mapping-file reader (and the report parser it configures)
# with libFuzzer + AddressSanitizer + UBSan, the same way bench/fuzz_protocol.sh
# fuzzes the protocol loader: its own tree (build/fuzz, clang,
# CURVLAB_FUZZ=ON), a corpus seeded with the mapping files under tests/, and
# RUNS executions (default 1,000,000).
#   bash bench/fuzz_mapping.sh [RUNS] [extra libFuzzer flags…]
# Exit status is libFuzzer's: 0 when no crash, hang or sanitizer report.
set -euo pipefail
cd "$(dirname "$0")/.."

runs=${1:-1000000}
shift || true
build=build/fuzz
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCURVLAB_FUZZ=ON -DCURVLAB_BUILD_TESTS=OFF -DCURVLAB_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" --target fuzz_mapping_file -j "$(nproc)"

corpus="$build/mapping_corpus"   # grows as the fuzzer finds new paths; seeds copied in
artifacts="$build/mapping_artifacts/"
mkdir -p "$corpus" "$artifacts"
cp tests/devices/data/*.toml "$corpus/"

export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export ASAN_OPTIONS=detect_leaks=1
"$build/bin/fuzz_mapping_file" "$corpus" \
  -runs="$runs" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
  -dict=tests/devices/fuzz_mapping.dict -artifact_prefix="$artifacts" \
  -print_final_stats=1 "$@"
