#include "flow.h"

#include <cmath>
#include <sstream>

#include "aot_registry.h"
#include "assembly.h"
#include "kernel_mode.h"
#include "lowering.h"
#include "solver_choice.h"

namespace hsnc::analysis {

Flow::Flow(const Model& model, const FlowKernels& k, const char* function) : work_(model) {
    if (k.kernels == KernelChoice::aot && !has_aot_kernels(work_, &aot_registry()))
        throw OptionError(function, "kernels", "aot", "no ahead-of-time kernels for model '" + work_.name + "'");
    SimulateOptions o;
    o.kernels = k.kernels;
    o.cache_dir = k.cache_dir;
    o.use_cache = k.use_cache;
    // The kernels of a JIT provider depend on the model's numbers only, not on
    // the initial state that run() rewrites.
    provider_ = api::make_provider(work_, o, &solver_, function);
    restart_plans_ = restart_plan_source(work_);
}

RunSummary Flow::run(double t, const double* x, const double* v, double t_end, Observer& observer, bool samples,
                     double dt, const double* slider) {
    const std::size_t n = work_.dof();
    work_.t0 = t;
    work_.x0.assign(x, x + n);
    work_.v0.assign(v, v + n);
    if (slider)
        work_.slider0.assign(slider, slider + work_.jenkins.size());
    else
        work_.slider0.clear();  // at rest, unstretched
    Engine engine(work_, *provider_);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = samples;
    opt.dt = dt;
    opt.restart_plans = restart_plans_;
    return engine.run(opt, observer);
}

void check_number(const char* function, const char* option, double value, bool positive) {
    if (std::isfinite(value) && (!positive || value > 0)) return;
    std::ostringstream s;
    s.precision(17);
    s << value;
    throw OptionError(function, option, s.str(), positive ? "must be finite and > 0" : "must be finite");
}

}  // namespace hsnc::analysis
