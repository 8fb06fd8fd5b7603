#!/usr/bin/env bash
# Builds liblsl, the Lab Streaming Layer library, from the pinned source in
# ../shared/third_party (checksum verified) into a cache outside the clone,
# keyed by the tarball's checksum, so that a second run skips the build.
# Prints the install prefix (for CMAKE_PREFIX_PATH) on stdout; with no
# ../shared/third_party, prints nothing and exits 0 (curvlab is then built
# without LSL and its LSL tests skip). Build facts: ../shared/third_party/README.md.
#
# With --windows, the same for 64-bit Windows with MinGW-w64
# (cmake/mingw-w64-x86_64.cmake), for scripts/build_windows.sh.
#
#   bash scripts/lsl.sh               # → /var/cache/curvlab/liblsl-<sha>/install
#   bash scripts/lsl.sh --windows     # → /var/cache/curvlab/liblsl-win64-<sha>/install
#   CURVLAB_CACHE=DIR bash scripts/lsl.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

flavour=""
toolchain=()
if [ "${1:-}" = "--windows" ]; then
  flavour="win64-"
  toolchain=(-DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake")
fi

third_party=$(cd .. && pwd)/shared/third_party
tarball=liblsl-1.16.2.tar.gz
if [ ! -f "$third_party/$tarball" ]; then
  echo "liblsl: $third_party/$tarball is not here; curvlab builds without LSL" >&2
  exit 0
fi
(cd "$third_party" && grep " $tarball\$" SHA256SUMS | sha256sum -c --quiet -) || {
  echo "liblsl: $third_party/$tarball does not match SHA256SUMS" >&2
  exit 1
}
sha=$(sha256sum "$third_party/$tarball" | cut -c1-16)
cache=${CURVLAB_CACHE:-/var/cache/curvlab}/liblsl-$flavour$sha
prefix=$cache/install
if [ -f "$cache/built" ] && [ -f "$prefix/include/lsl_cpp.h" ]; then
  echo "$prefix"
  exit 0
fi

rm -rf "$cache"
mkdir -p "$cache/src"
tar -xzf "$third_party/$tarball" -C "$cache/src" --strip-components=1
echo "liblsl: building $tarball into $cache (about 1 minute of CPU)" >&2
cmake -S "$cache/src" -B "$cache/build" -DCMAKE_BUILD_TYPE=Release -DLSL_UNITTESTS=OFF "${toolchain[@]}" \
  -DCMAKE_INSTALL_PREFIX="$prefix" > "$cache/configure.log" 2>&1 || {
  tail -30 "$cache/configure.log" >&2
  exit 1
}
cmake --build "$cache/build" -j "$(nproc)" > "$cache/build.log" 2>&1 || {
  tail -30 "$cache/build.log" >&2
  exit 1
}
cmake --install "$cache/build" > "$cache/install.log" 2>&1 || {
  tail -30 "$cache/install.log" >&2
  exit 1
}
[ -f "$prefix/include/lsl_cpp.h" ] || { echo "liblsl: the install wrote no $prefix/include/lsl_cpp.h" >&2; exit 1; }
touch "$cache/built"
echo "$prefix"
