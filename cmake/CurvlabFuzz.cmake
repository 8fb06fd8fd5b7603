# curvlab_add_fuzzer(NAME SOURCES …): a libFuzzer target (clang only, with
# -DCURVLAB_FUZZ=ON; see bench/fuzz_protocol.sh and bench/fuzz_mapping.sh).
# toml++ is compiled header-only into it so the parser itself is instrumented
# too, and AddressSanitizer and UBSan stop at the first report.
function(curvlab_add_fuzzer name)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "CURVLAB_FUZZ=ON needs clang (libFuzzer): -DCMAKE_CXX_COMPILER=clang++")
  endif()
  find_package(tomlplusplus REQUIRED)
  add_executable(${name} ${ARGN})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/harness/include
                                             ${PROJECT_SOURCE_DIR}/harness/src/protocol)
  get_target_property(_toml_inc tomlplusplus::tomlplusplus INTERFACE_INCLUDE_DIRECTORIES)
  target_include_directories(${name} SYSTEM PRIVATE ${_toml_inc})
  target_compile_definitions(${name} PRIVATE TOML_HEADER_ONLY=1)
  target_compile_options(${name} PRIVATE -g -fsanitize=fuzzer,address,undefined
    -fno-sanitize-recover=undefined)
  target_link_options(${name} PRIVATE -fsanitize=fuzzer,address,undefined)
  target_link_libraries(${name} PRIVATE curvlab_warnings)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
endfunction()
