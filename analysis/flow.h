// hsnc -- the flow map of a model for the analyses: run the exact engine from
// any state at any time over a given span, with one set of segment solvers
// kept across runs (the solvers depend on the model's numbers, not on its
// initial state).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine.h"
#include "hsnc/simulate.h"
#include "model.h"

namespace hsnc::analysis {

/// Where a flow's segment solvers come from: the kernel kind the facade
/// selects (SimulateOptions::kernels) and, for jit, its persistent cache.
struct FlowKernels {
    KernelChoice kernels = KernelChoice::automatic;
    std::string cache_dir;  ///< jit: "" the default cache directory
    bool use_cache = true;  ///< jit: false compiles every kernel, no cache
};

class Flow {
public:
    /// OptionError (naming option "kernels", `function` the caller) for aot
    /// on a model without ahead-of-time kernels; RunError when jit is asked
    /// for and the JIT module cannot be loaded.
    Flow(const Model& model, const FlowKernels& kernels, const char* function);
    Flow(const Flow&) = delete;  ///< the provider refers to work_
    Flow& operator=(const Flow&) = delete;
    const Model& model() const { return work_; }
    /// What computes the runs, and its statistics line (SolverProvider::describe).
    SolverKind solver() const { return solver_; }
    std::string describe() const { return provider_->describe(); }

    /// Runs from (x, v) at time t to t_end, reporting to `observer`; `slider`:
    /// the Jenkins sliders' positions (null: unstretched, interface.md).
    RunSummary run(double t, const double* x, const double* v, double t_end, Observer& observer,
                   bool samples = false, double dt = 0.0, const double* slider = nullptr);

    /// `progress(t)` is called during every run now and then (after every
    /// segment the observer takes, every 1024 samples, and at the engine's
    /// progress checks) with the time reached; when it returns false the run
    /// stops soon after (RunStatus::stopped) and stopped() is true from then on.
    void set_progress(std::function<bool(double)> progress) { progress_ = std::move(progress); }
    bool stopped() const { return stopped_; }

private:
    class ProgressObserver;
    Model work_;
    SolverKind solver_ = SolverKind::generic;
    std::unique_ptr<SolverProvider> provider_;
    // EngineOptions::restart_plans, as hsnc::simulate sets it: a flow's
    // segments are simulate's, bit for bit.
    std::function<std::shared_ptr<const RestartPlan>(const Configuration&)> restart_plans_;
    std::function<bool(double)> progress_;
    bool stopped_ = false;
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
