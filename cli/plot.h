// hsnc -- a plot of a trajectory CSV, drawn by gnuplot (Debian gnuplot-nox).
#pragma once

#include <string>

#include "model.h"

namespace hsnc::cli {

/// Draw x(t) of every mass from the trajectory CSV `csv` into the PNG `png`.
/// Throws RunError when gnuplot is missing or fails.
void plot_trajectory(const Model& model, const std::string& csv, const std::string& png);

}  // namespace hsnc::cli
