// hsnc -- one point of a sweep (api/hsnc/sweep.h): the transient to a steady
// state on the stroboscopic map, then the recorded periods and what they
// give (xmax, xrms, a1, the stroboscopic samples). Private to the library.
#pragma once

#include <vector>

#include "hsnc/sweep.h"
#include "engine.h"
#include "model.h"

namespace hsnc::sweep_detail {

/// The state a sweep carries from point to point.
struct State {
    std::vector<double> x, v;
    std::vector<double> slider;  ///< Jenkins sliders' positions (empty: unstretched, Model::slider0)
};

/// Runs one point of `model` (its parameters at the point's values; its
/// initial state is ignored) from `state` at the model's t0; leaves in
/// `state` the state at the end of the recorded periods. `what` names the
/// point in messages. RunError when a run stops (chattering, Zeno, failure).
SweepPoint run_point(const Model& model, State& state, const SweepOptions& options, const std::string& what);

/// Records `periods` forcing periods of `model` from `state` at t0 + k*T
/// into `pt` (xmax, xrms, a1, the stroboscopic samples), leaving the end
/// state in `state`; `provider` (may be null: a generic one) gives the
/// solvers with method hsnc. RunError naming `what` when the run stops.
void record(const Model& model, State& state, const SweepOptions& options, const std::string& what, std::size_t k,
            std::size_t periods, SweepPoint& pt, SolverProvider* provider = nullptr);

/// Fills a failed point's metrics (xmax, xrms, a1, amp, phase) with NaN.
void mark_failed(SweepPoint& point, std::size_t masses, std::size_t harmonics);

/// SweepCancelled when options.cancel is set.
void check_cancel(const SweepOptions& options);

/// True when options.stop is set: the task ends after the point it has finished.
bool stop_requested(const SweepOptions& options);

/// The forcing frequency of `model`; InputError (naming `what`) unless it has
/// forcing with one frequency.
double forcing_frequency(const Model& model, const std::string& what);

/// The highest natural frequency (rad/s) with every contact closed and no
/// mass stuck: no configuration oscillates faster.
double highest_natural_frequency(const Model& model);

}  // namespace hsnc::sweep_detail
