// Driving the engine (and the rk45 baseline) from tests: record every event
// and sample, in the order the run reports them.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "engine.h"
#include "integrators.h"
#include "interpreted_solver.h"
#include "kernel_mode.h"
#include "lowering.h"

namespace hsnc::testing {

struct Recorded {
    double t;
    EventKind kind;
    int element;  ///< -1 for samples
    std::vector<double> x, v;  ///< x: the masses', then the Jenkins sliders (Model::state_size())
};

class Recorder : public Observer {
public:
    /// n masses; nx = n plus the Jenkins sliders recorded after them (the engine's and
    /// the rk45 and CVODE baselines' x), n for an observer that gets the masses only.
    explicit Recorder(std::size_t n, std::size_t nx = 0) : n_(n), nx_(std::max(n, nx)) {}
    void on_sample(double t, const double* x, const double* v) override {
        samples.push_back({t, EventKind::stick, -1, {x, x + nx_}, {v, v + n_}});
    }
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        events.push_back({t, kind, element, {x, x + nx_}, {v, v + n_}});
    }
    std::vector<Recorded> samples, events;

private:
    std::size_t n_, nx_;
};

/// The (kind, element) of every event of a run, in order.
class EventSequence : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind k, int e, const double*, const double*) override { seq.emplace_back(k, e); }
    std::vector<std::pair<EventKind, int>> seq;
};

/// The end state (x, v, then the Jenkins sliders) of the engine's run of m on
/// the Eigen solver from its initial state (sliders: slider0) to t_end, and
/// its events' kinds.
inline std::vector<double> end_state(const Model& m, double t_end, EventSequence& kinds) {
    GenericSolverProvider provider(m);
    Engine engine(m, provider);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    const RunSummary s = engine.run(opt, kinds);
    EXPECT_EQ(s.status, RunStatus::ok) << s.message;
    std::vector<double> y = s.x;
    y.resize(m.dof());
    y.insert(y.end(), s.v.begin(), s.v.end());
    y.insert(y.end(), s.slider.begin(), s.slider.end());
    return y;
}

struct Outcome {
    RunSummary summary;
    std::vector<Recorded> events, samples;
};

/// Which segment solvers a test run uses: the Eigen generic solver, or the
/// interpreted programs of the derivation (the kernels' closed form).
enum class Solvers { generic, interp };
inline const char* solvers_name(Solvers s) { return s == Solvers::generic ? "generic" : "interp"; }

/// The HSNC engine over `provider` from the model's initial state;
/// configurations with `schedule_from` switch functions or more searched on a
/// schedule per function (EngineOptions::schedule_from); segments restarted
/// with `restart_plans` (EngineOptions::restart_plans), else all set up.
inline Outcome run_engine(const Model& model, SolverProvider& provider, double t_end, double dt = 0.0,
                          std::size_t schedule_from = kScheduleFrom,
                          std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plans = {}) {
    Engine engine(model, provider);
    Recorder rec(model.dof(), model.state_size());
    EngineOptions opt;
    opt.t_end = t_end;
    opt.dt = dt;
    opt.schedule_from = schedule_from;
    opt.restart_plans = std::move(restart_plans);
    Outcome r;
    r.summary = engine.run(opt, rec);
    r.events = std::move(rec.events);
    r.samples = std::move(rec.samples);
    return r;
}

/// The HSNC engine from the model's initial state.
inline Outcome simulate(const Model& model, double t_end, double dt = 0.0, Solvers solvers = Solvers::generic) {
    GenericSolverProvider generic(model);
    // The configurations the derivation refuses (NotDerivable) on the generic solver, as in the facade.
    DerivationFallbackProvider interp(model, std::make_unique<InterpretedSolverProvider>(program_source(model)));
    SolverProvider& provider = solvers == Solvers::generic ? static_cast<SolverProvider&>(generic) : interp;
    return run_engine(model, provider, t_end, dt);
}

/// A baseline at the given tolerances: rk45 (Dormand-Prince with event
/// location) unless `method` says cvode.
inline Outcome baseline(const Model& model, double t_end, double rtol, double atol, Method method = Method::rk45) {
    Recorder rec(model.dof(), model.state_size());
    EngineOptions eo;
    eo.t_end = t_end;
    IntegratorOptions io;
    io.rtol = rtol;
    io.atol = atol;
    Outcome r;
    r.summary = integrate(model, method, io, eo, rec);
    r.events = std::move(rec.events);
    r.samples = std::move(rec.samples);
    return r;
}

/// Rows of one instant may come in any order (interface.md section 2): sort
/// each run of rows with the same time by (kind, element).
inline void canonical_order(std::vector<Recorded>& ev) {
    for (std::size_t i = 0; i < ev.size();) {
        std::size_t j = i + 1;
        while (j < ev.size() && ev[j].t == ev[i].t) ++j;
        std::sort(ev.begin() + static_cast<std::ptrdiff_t>(i), ev.begin() + static_cast<std::ptrdiff_t>(j),
                  [](const Recorded& a, const Recorded& b) {
                      return a.kind != b.kind ? a.kind < b.kind : a.element < b.element;
                  });
        i = j;
    }
}

}  // namespace hsnc::testing
