// hsnc -- the reference engine's results at full precision (CLN floats), for
// comparing runs at N and 2N digits and the double engine against them.
#pragma once

#include <cstddef>
#include <vector>

#include <cln/float.h>

#include "reference.h"

namespace hsnc::reference {

/// One switch event at full precision (the state at the switch instant).
struct PreciseEvent {
    cln::cl_F t;
    EventKind kind;
    int element;
    std::vector<cln::cl_F> x, v;
};

/// A run at full precision: the summary (rounded to double) plus every event
/// and the final state at the run's precision.
struct PreciseRun {
    RunSummary summary;
    std::vector<PreciseEvent> events;
    cln::cl_F t;
    std::vector<cln::cl_F> x, v;
};

/// How many steps the switch search may take in one segment before the run ends with RunStatus::failure
/// ("switch search stalls ..."): base_steps plus steps_per_period for each period of the segment's fastest
/// motion (MpSegment::fastest_rate) over the rest of the run. The guaranteed search takes a few steps per period
/// and a few dozen onto each root, so the defaults never stop a legitimate run.
struct SearchLimits {
    std::size_t base_steps = 100'000;
    std::size_t steps_per_period = 1'000;
};

/// search_step_limit(span, rate, limits): the step limit of a segment with `span` seconds left to run.
std::size_t search_step_limit(double span, double fastest_rate, const SearchLimits& limits);

/// As simulate(), and also keeps every event and the end state at full precision.
/// `digits` may be any value >= 17 here (tests and measurements compare N with 2N).
/// `offset` (may be null; 2n values, positions then velocities) is added to
/// the initial state at full precision, so two runs can start closer than a
/// double can tell apart (x0 + 1e-30).
PreciseRun simulate_precise(const Model& model, int digits, const EngineOptions& options, Observer& observer,
                            const SearchLimits& limits = {}, const std::vector<double>* offset = nullptr);

/// |a - b| / max(|a|, |b|, floor) at the lower of the two precisions, rounded to double.
double relative_difference(const cln::cl_F& a, const cln::cl_F& b, double floor = 0.0);

}  // namespace hsnc::reference
