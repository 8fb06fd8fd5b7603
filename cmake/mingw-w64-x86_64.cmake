# Cross-compiling curvlab for 64-bit Windows with Debian's MinGW-w64 (the
# POSIX-threads flavour: std::thread and std::mutex need it). The
# dependencies are found only under CURVLAB_WINDOWS_DEPS, the prefix that
# scripts/build_windows.sh fills from ../shared/third_party, and MinGW's own
# sysroot; nothing is taken from the build host's /usr except programs.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)

set(CURVLAB_MINGW_TRIPLE x86_64-w64-mingw32)
set(CMAKE_C_COMPILER ${CURVLAB_MINGW_TRIPLE}-gcc-posix)
set(CMAKE_CXX_COMPILER ${CURVLAB_MINGW_TRIPLE}-g++-posix)
set(CMAKE_RC_COMPILER ${CURVLAB_MINGW_TRIPLE}-windres)

if(NOT CURVLAB_WINDOWS_DEPS AND DEFINED ENV{CURVLAB_WINDOWS_DEPS})
  set(CURVLAB_WINDOWS_DEPS $ENV{CURVLAB_WINDOWS_DEPS})
endif()
# try_compile projects see the prefix too.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES CURVLAB_WINDOWS_DEPS)

set(CMAKE_FIND_ROOT_PATH /usr/${CURVLAB_MINGW_TRIPLE})
if(CURVLAB_WINDOWS_DEPS)
  list(PREPEND CMAKE_FIND_ROOT_PATH ${CURVLAB_WINDOWS_DEPS})
  set(ENV{PKG_CONFIG_LIBDIR} "${CURVLAB_WINDOWS_DEPS}/lib/pkgconfig")
  set(ENV{PKG_CONFIG_SYSROOT_DIR} "")
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Tests built for Windows run through Wine (tests/windows).
find_program(CURVLAB_WINE64 NAMES wine64 PATHS /usr/lib/wine NO_CMAKE_FIND_ROOT_PATH)
if(CURVLAB_WINE64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${CURVLAB_WINE64})
endif()
