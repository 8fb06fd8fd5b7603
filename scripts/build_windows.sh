#!/usr/bin/env bash
# Cross-compiles curvlab for 64-bit Windows with MinGW-w64 (docs/windows.md).
#
# 1. installs the Debian packages it needs (only those missing);
# 2. verifies the pinned sources in ../shared/third_party against SHA256SUMS
#    and builds SQLite, Nettle, GLFW, hidapi, the OpenXR loader, ENet, GoogleTest
#    and the stb implementations for x86_64-w64-mingw32 once, into a cache
#    outside the clone keyed by the sources' checksums and this recipe
#    (/var/cache/curvlab/mingw-<key>, or $CURVLAB_CACHE/mingw-<key>);
# 3. builds curvlab with cmake/mingw-w64-x86_64.cmake into build/windows,
#    with the Lab Streaming Layer where scripts/lsl.sh --windows builds
#    liblsl (its own cache; without its source curvlab.exe has no LSL);
# 4. packs build/windows/curvlab-VERSION-win64.zip: curvlab.exe, the DLLs it
#    loads (MinGW runtime, sqlite, nettle, glfw, hidapi, openxr_loader, liblsl; never
#    vulkan-1.dll nor an OpenXR runtime: the lab's driver and headset vendor
#    provide those), protocols/, analysis/, data_schema/, a font and
#    README-windows.txt.
#
# With no ../shared/third_party it says what is missing and exits 0 (the
# windows tests then skip). Prints the zip's path on stdout.
#
#   bash scripts/build_windows.sh                 # curvlab.exe, Windows unit tests, zip
#   CURVLAB_CACHE=DIR bash scripts/build_windows.sh
#   bash scripts/build_windows.sh --deps-only     # only the cached dependencies; prints the prefix
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

third_party=$(cd .. && pwd)/shared/third_party
tarballs=(sqlite-3.40.1-src.tar.xz nettle-3.8.1.tar.gz glfw-3.3.8.tar.gz hidapi-0.13.1.tar.gz OpenXR-SDK-1.0.34.tar.gz)
for t in "${tarballs[@]}"; do
  if [ ! -f "$third_party/$t" ]; then
    echo "build_windows: $third_party/$t is not here; no Windows build (the windows tests will be skipped)" >&2
    exit 0
  fi
done

log() { echo "build_windows: $*" >&2; }

# --- 1. packages ---------------------------------------------------------
packages=(g++-mingw-w64-x86-64-posix gcc-mingw-w64-x86-64-posix libz-mingw-w64-dev wine64 xvfb xauth
          zip cmake ninja-build pkg-config ccache tcl m4 glslang-tools libgtest-dev libgmock-dev
          libglm-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libstb-dev libvulkan-dev
          fonts-dejavu-core)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get -o DPkg::Lock::Timeout=900 update -qq
  $SUDO apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

for t in "${tarballs[@]}"; do
  (cd "$third_party" && grep " $t\$" SHA256SUMS | sha256sum -c --quiet -) || {
    log "$third_party/$t does not match SHA256SUMS"
    exit 1
  }
done

triple=x86_64-w64-mingw32
toolchain=$root/cmake/mingw-w64-x86_64.cmake
jobs=${CURVLAB_JOBS:-$(nproc)}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# --- 2. dependencies, once per key ---------------------------------------
# Everything below writes only under $1 (the cache folder).
build_deps() {
  local cache=$1 prefix=$1/prefix src=$1/src
  mkdir -p "$prefix/include" "$prefix/lib/pkgconfig" "$prefix/lib/cmake" "$prefix/bin" "$src"
  local cmake_common=(-G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE="$toolchain"
                      -DCURVLAB_WINDOWS_DEPS="$prefix" -DCMAKE_INSTALL_PREFIX="$prefix" "${launcher[@]}")

  # SQLite: the amalgamation is generated on the host (tclsh), then compiled
  # as a DLL with the options Debian's libsqlite3 uses that curvlab relies on.
  log "sqlite"
  mkdir -p "$src/sqlite"
  tar -xJf "$third_party/sqlite-3.40.1-src.tar.xz" -C "$src/sqlite" --strip-components=1
  (cd "$src/sqlite" && ./configure --disable-tcl >/dev/null && make -j"$jobs" sqlite3.c >/dev/null)
  local sqlite_defs=(-DSQLITE_ENABLE_COLUMN_METADATA -DSQLITE_ENABLE_FTS3 -DSQLITE_ENABLE_RTREE
                     -DSQLITE_ENABLE_DBSTAT_VTAB -DSQLITE_ENABLE_UNLOCK_NOTIFY -DSQLITE_SECURE_DELETE
                     -DSQLITE_MAX_SCHEMA_RETRY=25 -DSQLITE_ENABLE_MATH_FUNCTIONS -DSQLITE_THREADSAFE=1
                     "-DSQLITE_API=__declspec(dllexport)")
  $triple-gcc-posix -O2 "${sqlite_defs[@]}" -shared -o "$prefix/bin/libsqlite3-0.dll" "$src/sqlite/sqlite3.c" \
    -Wl,--out-implib,"$prefix/lib/libsqlite3.dll.a"
  cp "$src/sqlite/sqlite3.h" "$src/sqlite/sqlite3ext.h" "$prefix/include/"

  # Nettle: only the symmetric part (SHA-256); no GMP.
  log "nettle"
  mkdir -p "$src/nettle"
  tar -xzf "$third_party/nettle-3.8.1.tar.gz" -C "$src/nettle" --strip-components=1
  (cd "$src/nettle" && ./configure --host=$triple CC=$triple-gcc-posix --prefix="$prefix" --disable-public-key \
     --disable-documentation --disable-openssl --disable-assembler --enable-shared --disable-static >/dev/null \
   && make -j"$jobs" >/dev/null && make install >/dev/null)

  log "glfw"
  mkdir -p "$src/glfw"
  tar -xzf "$third_party/glfw-3.3.8.tar.gz" -C "$src/glfw" --strip-components=1
  cmake -S "$src/glfw" -B "$src/glfw/build" "${cmake_common[@]}" -DBUILD_SHARED_LIBS=ON \
    -DGLFW_BUILD_EXAMPLES=OFF -DGLFW_BUILD_TESTS=OFF -DGLFW_BUILD_DOCS=OFF >/dev/null
  cmake --build "$src/glfw/build" -j"$jobs" >/dev/null && cmake --install "$src/glfw/build" >/dev/null

  log "hidapi"
  mkdir -p "$src/hidapi"
  tar -xzf "$third_party/hidapi-0.13.1.tar.gz" -C "$src/hidapi" --strip-components=1
  cmake -S "$src/hidapi" -B "$src/hidapi/build" "${cmake_common[@]}" -DBUILD_SHARED_LIBS=ON >/dev/null
  cmake --build "$src/hidapi/build" -j"$jobs" >/dev/null && cmake --install "$src/hidapi/build" >/dev/null

  log "openxr loader"
  mkdir -p "$src/openxr"
  tar -xzf "$third_party/OpenXR-SDK-1.0.34.tar.gz" -C "$src/openxr" --strip-components=1
  cmake -S "$src/openxr" -B "$src/openxr/build" "${cmake_common[@]}" -DDYNAMIC_LOADER=ON \
    -DBUILD_TESTS=OFF -DBUILD_API_LAYERS=OFF -DBUILD_WITH_SYSTEM_JSONCPP=OFF >/dev/null
  cmake --build "$src/openxr/build" -j"$jobs" >/dev/null && cmake --install "$src/openxr/build" >/dev/null

  # GoogleTest from the source Debian's libgtest-dev ships.
  log "googletest"
  cmake -S /usr/src/googletest -B "$src/googletest" "${cmake_common[@]}" -DBUILD_SHARED_LIBS=OFF \
    -Dgtest_disable_pthreads=OFF >/dev/null
  cmake --build "$src/googletest" -j"$jobs" >/dev/null && cmake --install "$src/googletest" >/dev/null

  # Header-only libraries come from Debian's packages, as on Linux; staged
  # into the prefix so that no host header directory is ever searched.
  log "headers"
  local d
  for d in glm CLI nlohmann toml++ stb vulkan vk_video; do cp -r "/usr/include/$d" "$prefix/include/"; done
  # Debian's libstb and libtomlplusplus carry compiled implementations; for
  # Windows they are compiled here once, into static libraries.
  mkdir -p "$src/impl"
  printf '#define STB_IMAGE_IMPLEMENTATION\n#include <stb_image.h>\n#define STB_IMAGE_WRITE_IMPLEMENTATION\n#include <stb_image_write.h>\n#define STB_TRUETYPE_IMPLEMENTATION\n#include <stb_truetype.h>\n' > "$src/impl/stb.c"
  printf '#define TOML_IMPLEMENTATION\n#include <toml++/toml.h>\n' > "$src/impl/toml.cpp"
  $triple-gcc-posix -O2 -I"$prefix/include/stb" -c "$src/impl/stb.c" -o "$src/impl/stb.o"
  $triple-ar rcs "$prefix/lib/libstb.a" "$src/impl/stb.o"
  $triple-g++-posix -std=c++17 -O2 -DTOML_HEADER_ONLY=0 -I"$prefix/include" -c "$src/impl/toml.cpp" -o "$src/impl/toml.o"
  $triple-ar rcs "$prefix/lib/libtomlplusplus.a" "$src/impl/toml.o"
  cat > "$prefix/lib/pkgconfig/stb.pc" <<EOF
prefix=$prefix
Name: stb
Description: stb single-file libraries (implementations compiled for Windows)
Version: 0.0
Libs: -L\${prefix}/lib -lstb
Cflags: -I\${prefix}/include/stb
EOF
  # Package configs for the header-only libraries, pointing into the prefix.
  write_config() {  # name target [compile definitions] [library]
    mkdir -p "$prefix/lib/cmake/$1"
    {
      echo "if(NOT TARGET $2)"
      echo "  add_library($2 INTERFACE IMPORTED)"
      echo "  set_target_properties($2 PROPERTIES INTERFACE_INCLUDE_DIRECTORIES \"$prefix/include\")"
      [ -n "${3:-}" ] && echo "  set_target_properties($2 PROPERTIES INTERFACE_COMPILE_DEFINITIONS \"$3\")"
      [ -n "${4:-}" ] && echo "  set_target_properties($2 PROPERTIES INTERFACE_LINK_LIBRARIES \"$4\")"
      echo "endif()"
      echo "set($1_FOUND TRUE)"
    } > "$prefix/lib/cmake/$1/$1Config.cmake"
  }
  write_config glm glm::glm
  write_config CLI11 CLI11::CLI11
  write_config nlohmann_json nlohmann_json::nlohmann_json
  write_config tomlplusplus tomlplusplus::tomlplusplus "TOML_HEADER_ONLY=0" "$prefix/lib/libtomlplusplus.a"
  # The MinGW runtime DLLs curvlab.exe loads, next to the others.
  local gcc_dir
  gcc_dir=$(dirname "$($triple-g++-posix -print-libgcc-file-name)")
  cp "$gcc_dir/libstdc++-6.dll" "$gcc_dir/libgcc_s_seh-1.dll" "$prefix/bin/"
  cp "$gcc_dir/libquadmath-0.dll" "$prefix/bin/"  # the geometry tests' __float128 oracle
  cp /usr/$triple/lib/libwinpthread-1.dll "$prefix/bin/"
  cp /usr/$triple/lib/zlib1.dll "$prefix/bin/" 2>/dev/null || true
}

key=$( { for t in "${tarballs[@]}"; do grep " $t\$" "$third_party/SHA256SUMS"; done
         declare -f build_deps; cat "$toolchain"; $triple-g++-posix --version | head -1; } | sha256sum | cut -c1-16)
cache=${CURVLAB_CACHE:-/var/cache/curvlab}/mingw-$key
prefix=$cache/prefix
if [ ! -f "$cache/built" ]; then
  rm -rf "$cache"
  mkdir -p "$cache"
  start=$(date +%s)
  log "building the dependencies into $cache"
  build_deps "$cache"
  touch "$cache/built"
  log "dependencies built in $(( $(date +%s) - start )) s"
fi
# ENet, the transport of shared play (docs/shared_play.md): a static
# library built into the same prefix once, from the pinned tarball, so that
# adding it did not rebuild the dependencies above. Without the tarball
# curvlab.exe is built without shared play and says so.
enet_tar=enet-1.3.17.tar.gz
if [ -f "$third_party/$enet_tar" ] && [ ! -f "$prefix/lib/libenet.a" ]; then
  (cd "$third_party" && grep " $enet_tar\$" SHA256SUMS | sha256sum -c --quiet -) || {
    log "$third_party/$enet_tar does not match SHA256SUMS"
    exit 1
  }
  log "ENet"
  enet_src=$cache/src/enet
  rm -rf "$enet_src"
  mkdir -p "$enet_src/obj"
  tar -xzf "$third_party/$enet_tar" -C "$enet_src" --strip-components=1
  for c in callbacks compress host list packet peer protocol win32; do
    $triple-gcc-posix -O2 -I"$enet_src/include" -c "$enet_src/$c.c" -o "$enet_src/obj/$c.o"
  done
  $triple-ar rcs "$enet_src/libenet.a" "$enet_src"/obj/*.o
  mkdir -p "$prefix/include/enet"
  cp "$enet_src"/include/enet/*.h "$prefix/include/enet/"
  cat > "$prefix/lib/pkgconfig/libenet.pc" <<EOF
prefix=$prefix
Name: libenet
Description: ENet reliable UDP networking (static, for Windows)
Version: 1.3.17
Libs: -L\${prefix}/lib -lenet -lws2_32 -lwinmm
Cflags: -I\${prefix}/include
EOF
  # Last: its presence marks ENet as built.
  cp "$enet_src/libenet.a" "$prefix/lib/"
fi
if [ "${1:-}" = "--deps-only" ]; then
  echo "$prefix"
  exit 0
fi

# --- 3. curvlab ------------------------------------------------------------
out=$root/build/windows
start=$(date +%s)
# liblsl for Windows, cached apart from the dependencies above (docs/lsl.md).
lsl_prefix=$(bash scripts/lsl.sh --windows)
lsl=()
if [ -n "$lsl_prefix" ]; then lsl=(-DLSL_DIR="$lsl_prefix/lib/cmake/LSL"); fi
cmake -S "$root" -B "$out" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
  -DCURVLAB_WINDOWS_DEPS="$prefix" -DCURVLAB_WERROR=ON -DCURVLAB_BUILD_BENCH=OFF "${lsl[@]}" "${launcher[@]}" >/dev/null
cmake --build "$out" -j"$jobs" --target curvlab >&2
# Beside curvlab.exe, where Windows (and Wine, for the windows tests) looks first.
if [ -n "$lsl_prefix" ]; then cp "$lsl_prefix/bin/liblsl.dll" "$out/bin/"; fi
cmake --build "$out" -j"$jobs" --target curvlab_windows_tests >&2  # run under Wine by tests/windows
log "curvlab built in $(( $(date +%s) - start )) s"

# --- 4. the zip --------------------------------------------------------------
version=$(sed -n 's/^project(curvlab VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
name=curvlab-$version-win64
stage=$out/package/$name
rm -rf "$out/package"
mkdir -p "$stage"
cp "$out/bin/curvlab.exe" "$stage/"
for dll in libstdc++-6.dll libgcc_s_seh-1.dll libwinpthread-1.dll zlib1.dll libsqlite3-0.dll libnettle-8.dll \
           glfw3.dll libhidapi.dll libopenxr_loader.dll; do
  cp "$prefix/bin/$dll" "$stage/"
done
if [ -n "$lsl_prefix" ]; then cp "$lsl_prefix/bin/liblsl.dll" "$stage/"; fi
# Debug symbols are not shipped (libstdc++ alone carries 20 MB of them).
$triple-strip --strip-unneeded "$stage"/*.exe "$stage"/*.dll
cp -r protocols analysis data_schema "$stage/"
mkdir -p "$stage/fonts"
cp /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf "$stage/fonts/"
cp docs/windows-readme.txt "$stage/README-windows.txt"
# Every DLL the executable imports must be in the zip or be part of Windows
# (vulkan-1.dll comes with the GPU driver and is loaded at run time).
windows_dlls='^(kernel32|user32|gdi32|shell32|advapi32|ole32|oleaut32|ws2_32|mswsock|iphlpapi|bcrypt|rpcrt4|setupapi|hid|opengl32|msvcrt|winmm|imm32|version|shlwapi|comdlg32|cfgmgr32|api-ms-win-.*)\.dll$'
for f in "$stage"/*.exe "$stage"/*.dll; do
  for dll in $($triple-objdump -p "$f" | sed -n 's/^\s*DLL Name: //p'); do
    [ -f "$stage/$dll" ] || echo "$dll" | tr 'A-Z' 'a-z' | grep -Eq "$windows_dlls" || {
      log "$(basename "$f") imports $dll, which is neither in the zip nor part of Windows"
      exit 1
    }
  done
done
rm -f "$out/$name.zip"
(cd "$out/package" && zip -qr "$out/$name.zip" "$name")
log "$(du -k "$out/$name.zip" | cut -f1) KiB: $out/$name.zip"
echo "$out/$name.zip"
