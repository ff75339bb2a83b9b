// hsnc -- the guard against switches that do not end, written once for the
// engine and the numerical baselines (runtime/baselines): a run stops with a
// named status instead of looping (CVODE's root finding does the same after a
// root: close pairs fail with a named status).
//
//  chattering: switch instants that keep coming at one and the same t (a
//              configuration cycle the decisions at one instant cannot settle);
//  zeno:       EngineOptions::zeno_events switches within zeno_span * max(1,
//              t - t0) of the run's own clock, plus the time's own resolution
//              (8 eps |t| a switch, twice the smallest step): switches that
//              accumulate in time, or that a method can only separate by the
//              rounding of t. The baselines need this as much as the engine: at
//              a Jenkins element's stick, CVODE's restarts stuck and released it
//              one ulp of t apart for ever (tests/test_cvode.cpp).
#pragma once

#include <cstddef>
#include <deque>
#include <string>

#include "engine_options.h"
#include "run_summary.h"

namespace hsnc {

class SwitchGuard {
public:
    SwitchGuard(const EngineOptions& options, double t0);

    /// One event at time t (a row of the events CSV).
    void event(double t);
    /// After the events of one switch instant t, in a configuration that
    /// watched `switch_functions` functions: RunStatus::ok to go on, else
    /// chattering or zeno (then message() says what and where).
    RunStatus after_switch(double t, std::size_t switch_functions);
    /// What stopped the run, ending with the configuration it was in (its spec).
    std::string message(const std::string& configuration) const;

private:
    std::size_t zeno_events_;
    double zeno_span_, t0_;
    std::deque<double> recent_;  // times of the latest events
    std::size_t same_instant_ = 0;
    double last_t_;
    RunStatus status_ = RunStatus::ok;
};

}  // namespace hsnc
