// hsnc -- the `hsnc sweep --plot` figure (gnuplot): on top the response
// curve, xmax of every mass against the parameter, the up sweep solid with
// filled points, the down sweep dashed with open points, points that did not
// settle ringed in black; under it the bifurcation diagram (the stroboscopic
// x of a mass against the parameter, every recorded period a dot; up and
// down in two colours), one panel for each of the first three masses.
#pragma once

#include <string>

#include "hsnc/sweep.h"
#include "output_file.h"

namespace hsnc {

/// The gnuplot script (terminal pngcairo, the image on stdout).
std::string sweep_plot_script(const SweepResult& r, const std::string& title);

/// Draw it into `png` (RunError when gnuplot fails).
void draw_sweep_plot(const SweepResult& r, const std::string& title, const OutputTarget& png);

}  // namespace hsnc
