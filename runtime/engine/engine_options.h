// hsnc -- how far a run goes and what it reports (Engine::run, and the
// baselines and the reference, which take the same options).
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>

#include "segment_solver.h"  // kScheduleFrom, RestartPlan

namespace hsnc {

struct EngineOptions {
    double t_end = 0.0;
    double dt = 0.0;                   ///< sample spacing; 0: samples only at t0 and t_end
    bool samples = true;               ///< call on_sample at all
    /// The grid of a longer run this one is a piece of (api/simulate.cpp runs
    /// a model with [[load_step]]s in pieces, one per load): samples at
    /// grid_t0 + k dt from k = first_sample on, up to this run's t_end; the
    /// grid's own end grid_t_end only where the run reaches it. NaN (the
    /// default): the run's own grid, from t0 to t_end.
    double grid_t0 = NAN, grid_t_end = NAN;
    std::size_t first_sample = 0;
    /// The configuration the previous piece ended in, where a piece starts at
    /// a change of load: contacts and Jenkins elements keep their state there
    /// and friction is decided again (rules::carried_configuration). Empty
    /// (the default): the configuration is entered from the initial state
    /// (interface.md "At t0").
    std::optional<Configuration> carried;
    std::size_t max_events = 0;        ///< 0: unlimited
    /// Zeno: zeno_events switches within zeno_span * max(1, t - t0) seconds
    /// (relative to the time the run has covered; plus the time's resolution,
    /// 8 eps |t| per switch, twice the smallest step) stop the run with RunStatus::zeno.
    std::size_t zeno_events = 1000;
    double zeno_span = 1e-9;
    /// A configuration with at least this many switch functions is searched
    /// on a schedule per function (engine.cpp; the default is
    /// kScheduleFrom, segment_solver.h). Results depend on it to rounding
    /// only; tests set it to search small models that way too.
    std::size_t schedule_from = kScheduleFrom;
    /// The restart plan of a configuration (kernels/program.h; the facade's
    /// is generator/lowering.h restart_plan_source), for a solver that keeps
    /// none of its own: the engine asks once per configuration, and only for
    /// one with restart.h kRestartFrom modes or more. Empty (the default):
    /// every segment is set up from the state, whatever the solver. Results
    /// depend on it to rounding only.
    std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plans;
};

}  // namespace hsnc
