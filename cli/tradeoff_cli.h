// hsnc -- `hsnc tradeoff`: the command line of the work-precision study
// (hsnc::tradeoff, analysis/tradeoff.h says what is swept and measured).
#pragma once

#include <cmath>
#include <string>

#include "model_reader.h"
#include "work_precision.h"  // ReferenceRunner

namespace hsnc::cli {

struct TradeoffOptions {
    std::string model;
    double t_end = NAN;
    ModelOverrides overrides;
    double dt = NAN;
    std::string reference_out, reference_events;  ///< both or neither
    int reference_digits = 40;
    std::string csv, plot;
    std::string methods;  ///< comma-separated; empty: every method this build has
    bool quick = false;
    double budget = 20.0;  ///< seconds
    int runs = 0;          ///< timed runs per setting; 0: as many as fit in about 0.2 s
};

/// Run the command. Without reference CSVs the reference is `reference` when
/// given, else reference_runner(o.reference_digits). Returns the exit code;
/// throws InputError (bad input, nothing written) or RunError.
int tradeoff(const TradeoffOptions& o, const ReferenceRunner& reference = {});

}  // namespace hsnc::cli
