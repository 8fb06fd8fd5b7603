#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds with -Werror
# (preset "ci") and runs every ctest test. Exit status is ctest's.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/deps.sh all
jobs=$(nproc)
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
cmake --preset ci "${launcher[@]}" >/dev/null
cmake --build --preset ci -j "$jobs"
# Monado, the OpenXR runtime the `monado` tests run sessions through, built
# once into a cache outside the clone (nothing where ../shared is absent).
bash scripts/monado.sh > /dev/null
# The Windows cross-build the `windows` tests run under Wine: dependencies
# cached outside the clone, curvlab into build/windows (nothing where
# ../shared is absent; the tests then skip).
bash scripts/build_windows.sh > /dev/null
ctest --preset ci -j "$jobs" "$@"
