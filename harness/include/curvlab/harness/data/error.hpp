// The data layer's failures are the harness's one Error type (result.hpp):
// disk full, read-only, a file from a newer curvlab, a corrupt or foreign
// file… as values the caller must handle.
#pragma once

#include "curvlab/harness/result.hpp"

namespace curvlab::harness::data {

using DataError = harness::Error;
template <class T>
using Expected = harness::Result<T>;
using harness::Done;
using harness::to_string;

}  // namespace curvlab::harness::data
