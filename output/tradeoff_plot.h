// hsnc -- the work-precision figure of `hsnc tradeoff --plot`, drawn by
// gnuplot (Debian gnuplot-nox) from the study's CSV (cli/tradeoff.cpp writes
// it; its columns: method, setting, ..., wall_seconds (4), ...,
// max_event_time_error (12), ..., relative_position_error (15), diverged (16)).
#pragma once

#include <string>
#include <vector>

#include "output_file.h"

namespace hsnc {

struct TradeoffPlot {
    struct Curve {
        std::string method;  ///< the CSV's `method` column
        bool sweep = true;   ///< a line through a sweep's points; false: points only (hsnc's kernel kinds)
    };
    std::string model;            ///< in the title
    std::string reference_label;  ///< "40-digit engine", or the reference file's name
    double magnitude = 0.0;       ///< max |x_ref|, m
    double diverged_ratio = 10.0; ///< where diverged runs are pinned (relative error)
    bool any_diverged = false;
    bool any_matched = false;     ///< some run that ran ok matched an event
    double min_wall = 0.0, max_wall = 0.0;
    std::vector<Curve> curves;    ///< one per method, in the CSV's order
};

/// Draws `plot` from `csv` into `png` (written beside it, then renamed into
/// place). RunError when gnuplot cannot be started or fails.
void plot_tradeoff(const TradeoffPlot& plot, const std::string& csv, const OutputTarget& png);

}  // namespace hsnc
