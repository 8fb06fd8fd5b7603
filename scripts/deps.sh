#!/usr/bin/env bash
# Installs the Debian 12 packages curvlab needs, skipping those already there.
# Runs as root (or through sudo when available).
#   bash scripts/deps.sh run   what building the curvlab executable, running
#                              sessions and writing the report need (scripts/quickstart.sh)
#   bash scripts/deps.sh all   that and every tool the test suite uses: GoogleTest,
#                              Xvfb, the validation layers, Chromium, Monado's build
#                              dependencies, MinGW-w64 and Wine, npm tools (default;
#                              scripts/test.sh)
set -euo pipefail

mode=${1:-all}
case "$mode" in
  run|all) ;;
  *) echo "deps: expected 'run' or 'all', got '$mode'" >&2; exit 2 ;;
esac

# Building curvlab, running it headless (lavapipe), the report (R) and the
# Python summary.
run_packages=(
  build-essential cmake pkg-config ccache git
  libglm-dev libvulkan-dev mesa-vulkan-drivers
  glslang-dev glslang-tools spirv-tools
  libsqlite3-dev sqlite3 nettle-dev libhidapi-dev libglfw3-dev libx11-dev libopenxr-dev libopenxr-loader1
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libpng-dev libstb-dev libenet-dev
  fonts-dejavu-core
  r-base-core r-cran-lme4 r-cran-ggplot2 r-cran-rsqlite r-cran-jsonlite python3-pandas python3-matplotlib
  r-cran-brglm2 r-cran-blme r-cran-emmeans r-cran-lpsolve
)
# The test suite's tools.
test_packages=(
  vulkan-validationlayers xvfb xauth
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-mpmath
  openxr-layer-corevalidation libopenxr-utils
  xdotool universal-ctags
  # Monado, the OpenXR runtime of the `monado` tests (scripts/monado.sh)
  ninja-build libeigen3-dev libudev-dev libxcb-randr0-dev libxrandr-dev libx11-xcb-dev
  chromium
  # the Windows cross-build and its tests under Wine (scripts/build_windows.sh)
  g++-mingw-w64-x86-64-posix gcc-mingw-w64-x86-64-posix libz-mingw-w64-dev wine64 zip tcl m4
)

packages=("${run_packages[@]}")
if [ "$mode" = all ]; then packages+=("${test_packages[@]}"); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# npm comes with the nodejs of some repositories and separately in Debian's;
# only the test suite's tools need it.
if [ "$mode" = all ] && ! command -v npm >/dev/null; then
  command -v node >/dev/null || missing+=(nodejs)
  missing+=(npm)
fi

if [ ${#missing[@]} -eq 0 ]; then
  echo "deps ($mode): all ${#packages[@]} packages present"
else
  echo "deps ($mode): installing ${#missing[@]} missing packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get -o DPkg::Lock::Timeout=900 update -qq
  $SUDO apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "deps: done"
fi

[ "$mode" = all ] || exit 0

# npm tools pinned by tools/package-lock.json (taplo checks protocols against
# protocols/schema.json), installed into tools/node_modules.
tools="$(cd "$(dirname "$0")/.." && pwd)/tools"
# The stamp is the lock file that was last installed.
stamp="$tools/node_modules/.installed-package-lock.json"
if ! cmp -s "$tools/package-lock.json" "$stamp" 2>/dev/null || [ ! -x "$tools/node_modules/.bin/taplo" ]; then
  echo "deps: installing npm tools into $tools/node_modules"
  npm ci --prefix "$tools" --no-audit --no-fund --loglevel=error
  cp "$tools/package-lock.json" "$stamp"
fi
