// hsnc -- where a run (the engine, a baseline, the reference) reports what it
// produces: samples, switch events, progress.
#pragma once

#include "event_kind.h"

namespace hsnc {

/// Where a run reports what it produces. x and v hold all masses.
class Observer {
public:
    virtual ~Observer() = default;
    virtual void on_sample(double t, const double* x, const double* v) = 0;
    virtual void on_event(double t, EventKind kind, int element, const double* x, const double* v) = 0;
    /// Called now and then with the current time; return false to stop.
    virtual bool on_progress(double /*t*/) { return true; }
};

}  // namespace hsnc
