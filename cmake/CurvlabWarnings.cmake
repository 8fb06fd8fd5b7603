# Warnings live in an interface target that each curvlab target links PRIVATE,
# so they never leak into consumers and there are no global CMAKE_CXX_FLAGS.
add_library(curvlab_warnings INTERFACE)
target_compile_options(curvlab_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
    -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion -Wformat=2
    -Wimplicit-fallthrough>
  $<$<BOOL:${CURVLAB_WERROR}>:-Werror>)
