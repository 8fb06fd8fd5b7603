// The table calibration step as `curvlab calibrate` and `curvlab run` (a
// protocol's [calibration] at_start) both run it on their opened devices.
#pragma once

#include "station.hpp"

#include "curvlab/harness/runner/calibration.hpp"

namespace curvlab::harness::cli {

// Runs the calibration (runner/calibration.hpp) on the devices and says on
// stderr what happened: each refused fit with its reason, then the fit kept.
// A calibration that ends before a fit is accepted (the window closed, the
// runtime exiting, a stop signal) is a RuntimeFailure — exit 1, or 128 + N
// after signal N — and nothing has been written.
harness::runner::CalibrationResult calibrate_on(const Devices& devices,
                                                const harness::runner::CalibrationOptions& options);

// The calibration file: what `run --calibration` reads (the fit with its
// residuals per corner, runner/stimulus.hpp) and the touches it was fitted
// to, in touch order.
Json calibration_document(const geometry::PhysicalTableFit& fit, const std::vector<geometry::Vec3>& touches_m);

}  // namespace curvlab::harness::cli
