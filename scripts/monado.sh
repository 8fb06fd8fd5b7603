#!/usr/bin/env bash
# Builds Monado, the open-source OpenXR runtime, from the pinned source in
# ../shared/third_party (checksum verified) into a cache outside the clone,
# keyed by the tarball's checksum, so that a second run skips the build.
# Prints the runtime manifest's path (for XR_RUNTIME_JSON) on stdout; with no
# ../shared/third_party, prints nothing and exits 0 (the monado tests then
# skip, naming what is missing). Build facts: ../shared/third_party/README.md.
#
#   bash scripts/monado.sh            # → /var/cache/curvlab/monado-<sha>/build/openxr_monado-dev.json
#   CURVLAB_CACHE=DIR bash scripts/monado.sh
set -euo pipefail
cd "$(dirname "$0")/.."

third_party=$(cd .. && pwd)/shared/third_party
tarball=monado-25.0.0.tar.xz
if [ ! -f "$third_party/$tarball" ]; then
  echo "monado: $third_party/$tarball is not here; the monado tests will be skipped" >&2
  exit 0
fi
(cd "$third_party" && grep " $tarball\$" SHA256SUMS | sha256sum -c --quiet -) || {
  echo "monado: $third_party/$tarball does not match SHA256SUMS" >&2
  exit 1
}
sha=$(sha256sum "$third_party/$tarball" | cut -c1-16)
cache=${CURVLAB_CACHE:-/var/cache/curvlab}/monado-$sha
manifest=$cache/build/openxr_monado-dev.json
if [ -f "$manifest" ] && [ -f "$cache/built" ]; then
  echo "$manifest"
  exit 0
fi

rm -rf "$cache"
mkdir -p "$cache"
tar -xJf "$third_party/$tarball" -C "$cache" --strip-components=1
echo "monado: building $tarball into $cache (about 3 minutes on 2 cores)" >&2
cmake -S "$cache" -B "$cache/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DXRT_FEATURE_SERVICE=OFF \
  -DBUILD_TESTING=OFF > "$cache/configure.log" 2>&1 || {
  tail -30 "$cache/configure.log" >&2
  exit 1
}
cmake --build "$cache/build" -j "$(nproc)" > "$cache/build.log" 2>&1 || {
  tail -30 "$cache/build.log" >&2
  exit 1
}
[ -f "$manifest" ] || { echo "monado: the build wrote no $manifest" >&2; exit 1; }
touch "$cache/built"
echo "$manifest"
