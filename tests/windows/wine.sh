#!/usr/bin/env bash
# Runs a program of the Windows build (scripts/build_windows.sh) under Wine:
#   tests/windows/wine.sh WINDOWS_BUILD_DIR PROGRAM.exe [ARGS...]
# The Wine prefix lives in $CURVLAB_WINEPREFIX (made on first use by
# tests/windows/run.sh prefix); the DLLs curvlab.exe loads are found through
# WINEPATH in the dependency prefix the Windows build was configured with.
set -euo pipefail
build=$1
shift
deps=$(sed -n 's/^CURVLAB_WINDOWS_DEPS:[A-Z]*=//p' "$build/CMakeCache.txt")
export WINEPREFIX=${CURVLAB_WINEPREFIX:?}
export WINEDEBUG=${WINEDEBUG:--all}
export WINEDLLOVERRIDES="mscoree,mshtml=;winemenubuilder.exe=d"
export WINEPATH="$deps/bin"
exec /usr/lib/wine/wine64 "$@"
