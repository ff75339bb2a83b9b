// hsnc -- the `hsnc sweep --plot` figure (gnuplot): on top the response
// curve, xmax of every mass against the parameter, the up sweep solid with
// filled points, the down sweep dashed with open points, points that did not
// settle ringed in black; under it the bifurcation diagram (the stroboscopic
// x of a mass against the parameter, every recorded period a dot; up and
// down in two colours), one panel for each of the first three dofs drawn.
// The dofs drawn are chosen by plot.h plot_dofs (--plot-dofs), at most 8,
// each its colour; axes say m or rad by dof kind (plot.h dof_unit).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "hsnc/sweep.h"
#include "output_file.h"

namespace hsnc {

/// The gnuplot script (terminal pngcairo, the image on stdout) of the dofs
/// `dofs` (indices of r.masses, at most kMaxPlotDofs: plot.h plot_dofs).
std::string sweep_plot_script(const SweepResult& r, const std::string& title, const std::vector<std::size_t>& dofs);

/// Draw it into `png` (RunError when gnuplot fails).
void draw_sweep_plot(const SweepResult& r, const std::string& title, const OutputTarget& png,
                     const std::vector<std::size_t>& dofs);

/// The basins of attraction of a sweep over two initial state coordinates:
/// each point coloured by the attractor it reached (grey: not settled,
/// black: failed), a legend entry per attractor.
std::string basin_plot_script(const SweepResult& r, const Attractors& a, const std::string& title);
void draw_basin_plot(const SweepResult& r, const Attractors& a, const std::string& title, const OutputTarget& png);

}  // namespace hsnc
