// hsnc -- work-precision measurement (hsnc::tradeoff, tradeoff.h): the error
// of a run against a reference trajectory and event list, and where the
// reference comes from.
//
// Errors (interface.md section 4 files, compared row by row):
//  - position error: max over the common sample times and all masses of
//    |x_run - x_ref|. Sample times are common when they agree to rounding
//    (both runs sample at t0 + k*dt); positions are never interpolated.
//  - relative position error: the position error divided by the response's
//    magnitude, max over the same sample times and masses of |x_ref| (an
//    error in metres means nothing without the size of the motion: the seed
//    scenarios move by metres, a damper by 3e-4 m).
//  - diverged: the position error is not finite or exceeds kDivergedRatio
//    times the response's magnitude (a blown-up run, e.g. ab4 beyond its
//    stability limit at 1e100 m): reported, kept out of the accuracy summary
//    and pinned at the top of the plot.
//  - event-time error: events of both lists are put in canonical order (by
//    time, and by (kind, element) among rows of one instant, whose order the
//    contract leaves free) and matched in order by (kind, element); matching
//    stops at the first mismatch. Reported: the matched count and the max
//    |t_run - t_ref| over the matched prefix.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "engine_options.h"
#include "model.h"
#include "observer.h"
#include "run_summary.h"

namespace hsnc {

struct EventRecord {
    double t;
    EventKind kind;
    int element;  ///< contact index for contact kinds, mass index otherwise
};

/// Samples and events of one run (all masses' positions; velocities are not compared).
struct RecordedRun {
    std::size_t dof = 0;
    std::vector<double> t;
    std::vector<double> x;  ///< row-major: x[k*dof + i]
    std::vector<EventRecord> events;
};

/// An Observer that records samples and events into a RecordedRun.
class RecordingObserver : public Observer {
public:
    explicit RecordingObserver(RecordedRun& run, std::size_t dof) : run_(run) { run_.dof = dof; }
    void on_sample(double t, const double* x, const double* v) override;
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override;

private:
    RecordedRun& run_;
};

/// The reference read from a trajectory CSV and an events CSV in the contract's
/// format for `model` (headers must match the model's). InputError naming the
/// file and line otherwise.
RecordedRun read_reference(const Model& model, const std::string& trajectory_csv, const std::string& events_csv);

/// A run whose position error exceeds this many times the response's magnitude has diverged.
inline constexpr double kDivergedRatio = 10.0;

struct RunErrors {
    double max_position_error = std::numeric_limits<double>::quiet_NaN();
    double response_magnitude = std::numeric_limits<double>::quiet_NaN();  ///< max |x_ref| over the compared times
    double relative_position_error = std::numeric_limits<double>::quiet_NaN();  ///< NaN when the magnitude is 0
    bool diverged = false;
    std::size_t sample_times = 0;  ///< common sample times compared
    std::size_t events = 0;        ///< events of the run
    std::size_t reference_events = 0;
    std::size_t matched_events = 0;
    double max_event_time_error = std::numeric_limits<double>::quiet_NaN();  ///< NaN when none matched
};

/// Errors of `run` against `reference` (see the header comment).
RunErrors compare_runs(const RecordedRun& reference, const RecordedRun& run);

/// Computes the reference in process: a run from the model's initial state,
/// reported like Engine::run.
using ReferenceRunner = std::function<RunSummary(const Model&, const EngineOptions&, Observer&)>;

/// The in-process reference at `digits` significant digits (hsnc::reference,
/// the CLN engine). OptionError (option "digits") when out of its range.
ReferenceRunner reference_runner(int digits);

}  // namespace hsnc
