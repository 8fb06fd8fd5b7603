#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds with -Werror
# (preset "ci") and runs every ctest test. Exit status is ctest's.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/deps.sh all
jobs=$(nproc)
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
# liblsl, built once from the pinned source into a cache outside the clone:
# curvlab is then built and tested with the Lab Streaming Layer (nothing
# where ../shared is absent; curvlab builds without it and its LSL tests skip).
lsl_prefix=$(bash scripts/lsl.sh)
prefix=()
if [ -n "$lsl_prefix" ]; then prefix=(-DCMAKE_PREFIX_PATH="$lsl_prefix"); fi
cmake --preset ci "${launcher[@]}" "${prefix[@]}" >/dev/null
cmake --build --preset ci -j "$jobs"
# Monado, the OpenXR runtime the `monado` tests run sessions through, built
# once into a cache outside the clone (nothing where ../shared is absent).
bash scripts/monado.sh > /dev/null
# The Windows cross-build the `windows` tests run under Wine: dependencies
# cached outside the clone, curvlab into build/windows (nothing where
# ../shared is absent; the tests then skip).
bash scripts/build_windows.sh > /dev/null
ctest --preset ci -j "$jobs" "$@"
