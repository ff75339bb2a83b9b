// hsnc -- where a run (the engine, a baseline, the reference) reports what it
// produces: samples, switch events, progress, and on request every segment
// and switch instant.
#pragma once

#include <vector>

#include "configuration.h"
#include "event_kind.h"
#include "switch_function.h"

namespace hsnc {

/// One closed-form segment of a run, reported when it ends (Observer::on_segment):
/// the motion from the instant t + t_lo over tau seconds in configuration cfg
/// with friction directions sgn, from the state (x, v). The pointers are valid
/// during the call only.
struct SegmentRecord {
    double t = 0.0, t_lo = 0.0;  ///< start instant (t_lo: its rounding, as SegmentSolver::setup)
    double tau = 0.0;            ///< duration
    const Configuration* cfg = nullptr;
    const signed char* sgn = nullptr;  ///< n entries: direction of each sliding friction mass, else 0
    const double* x = nullptr;   ///< state at the segment start
    const double* v = nullptr;
};

/// One switch instant (Observer::on_switch), after the transitions of
/// interface.md section 2 are applied: the functions the search found
/// switching, the configuration before and after (with the friction
/// directions), the state at the instant (velocities of stopped masses 0).
struct SwitchRecord {
    double t = 0.0, t_lo = 0.0;
    const std::vector<SwitchFunction>* switched = nullptr;
    const Configuration* before = nullptr;
    const signed char* sgn_before = nullptr;
    const Configuration* after = nullptr;
    const signed char* sgn_after = nullptr;
    const double* x = nullptr;
    const double* v = nullptr;
};

/// Where a run reports what it produces. x and v hold all masses.
class Observer {
public:
    virtual ~Observer() = default;
    virtual void on_sample(double t, const double* x, const double* v) = 0;
    virtual void on_event(double t, EventKind kind, int element, const double* x, const double* v) = 0;
    /// Called now and then with the current time; return false to stop.
    virtual bool on_progress(double /*t*/) { return true; }
    /// True when the run should report every segment and switch instant
    /// (on_segment, on_switch: the tangent dynamics of analysis/ use them).
    /// Asked once at the start of Engine::run; false costs the run nothing.
    virtual bool wants_segments() const { return false; }
    virtual void on_segment(const SegmentRecord& /*segment*/) {}
    virtual void on_switch(const SwitchRecord& /*instant*/) {}
};

}  // namespace hsnc
