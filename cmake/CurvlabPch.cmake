# Precompiled third-party headers (CURVLAB_PCH, off by default). A first
# build of the curvlab executable parses Vulkan-Hpp, CLI11, nlohmann/json
# and toml++ in dozens of translation units; precompiling them once per
# target shortens scripts/quickstart.sh's build. Off in the development and
# CI builds, whose compiler cache does not reuse precompiled headers.
option(CURVLAB_PCH "Precompile the heaviest third-party headers per target" OFF)

# curvlab_pch(TARGET HEADER...): precompile HEADERs (<...> names) for TARGET
# when CURVLAB_PCH is on.
function(curvlab_pch target)
  if(CURVLAB_PCH)
    foreach(header IN LISTS ARGN)
      target_precompile_headers(${target} PRIVATE "$<$<COMPILE_LANGUAGE:CXX>:${header}>")
    endforeach()
  endif()
endfunction()
