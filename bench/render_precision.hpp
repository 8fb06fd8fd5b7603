// Section 4 of bench_render_accuracy: edge-position precision per MSAA
// sample count (render_precision.cpp).
#pragma once

#include "curvlab/renderer/context.hpp"

namespace bench {

// Prints the precision table (residual RMS and max in px and arcsec, frame
// time ratio to msaa 1), measuring frame times over `frames` frames.
void print_precision_table(const curvlab::renderer::Context& ctx, int frames);

}  // namespace bench
