// hsnc -- the flow map of a model for the analyses: run the exact engine from
// any state at any time over a given span, with one set of segment solvers
// kept across runs (the solvers depend on the model's numbers, not on its
// initial state).
#pragma once

#include <memory>
#include <vector>

#include "engine.h"
#include "hsnc/simulate.h"
#include "model.h"

namespace hsnc::analysis {

class Flow {
public:
    /// kernels: automatic, aot or generic (OptionError for jit).
    Flow(const Model& model, KernelChoice kernels, const char* function);
    const Model& model() const { return work_; }

    /// Runs from (x, v) at time t to t_end, reporting to `observer`.
    RunSummary run(double t, const double* x, const double* v, double t_end, Observer& observer,
                   bool samples = false, double dt = 0.0);

private:
    Model work_;
    std::unique_ptr<SolverProvider> provider_;
};

/// An observer that ignores everything.
class NullObserver : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

/// OptionError naming `option` unless `value` is finite (and > 0 when positive is set).
void check_number(const char* function, const char* option, double value, bool positive);

}  // namespace hsnc::analysis
