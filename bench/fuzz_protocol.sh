#!/usr/bin/env bash
# Fuzzes the protocol loader with libFuzzer + AddressSanitizer + UBSan.
# Builds its own tree (build/fuzz, clang, CURVLAB_FUZZ=ON) so the default and
# CI builds never see it, seeds the corpus with protocols/ and the malformed
# corpus, and runs RUNS executions (default 1,000,000).
#   bash bench/fuzz_protocol.sh [RUNS] [extra libFuzzer flags…]
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
cmake --build "$build" --target fuzz_protocol_loader -j "$(nproc)"

corpus="$build/corpus"   # grows as the fuzzer finds new paths; seeds copied in
artifacts="$build/artifacts/"
mkdir -p "$corpus" "$artifacts"
cp protocols/*.toml tests/protocol/malformed/*.toml "$corpus/"

export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export ASAN_OPTIONS=detect_leaks=1
"$build/bin/fuzz_protocol_loader" "$corpus" \
  -runs="$runs" -max_len=8192 -timeout=10 -rss_limit_mb=2048 \
  -dict=tests/protocol/fuzz_protocol.dict -artifact_prefix="$artifacts" \
  -print_final_stats=1 "$@"
