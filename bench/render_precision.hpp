// Section 4 of bench_render_accuracy: edge-position precision per MSAA
// sample count (render_precision.cpp).
#pragma once

#include "curvlab/renderer/context.hpp"

#include <cstdint>
#include <functional>

namespace bench {

// The plain loop's median frame time for the billiards frame (E3, native,
// 1024² per eye) at a sample count, or for a frame with nothing drawn (only
// clearing, resolving and reading back) when `empty` (render_accuracy.cpp).
using PlainFrameMs = std::function<double(std::uint32_t msaa, bool empty)>;

// Prints the precision table (residual RMS and max in px and arcsec, frame
// time ratio to msaa 1, the plain loop's beside it), measuring frame times
// over `frames` frames.
void print_precision_table(const curvlab::renderer::Context& ctx, int frames, const PlainFrameMs& plain_ms);

}  // namespace bench
