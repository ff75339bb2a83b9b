#include "flow.h"

#include <cmath>
#include <sstream>

#include "aot_registry.h"
#include "kernel_mode.h"

namespace hsnc::analysis {

Flow::Flow(const Model& model, KernelChoice kernels, const char* function) : work_(model) {
    KernelMode mode = KernelMode::automatic;
    if (kernels == KernelChoice::generic) mode = KernelMode::generic;
    if (kernels == KernelChoice::aot) mode = KernelMode::aot;
    if (kernels == KernelChoice::jit)
        throw OptionError(function, "kernels", "jit", "the analyses use the ahead-of-time kernels or the generic solver");
    if (mode == KernelMode::aot && !has_aot_kernels(work_, &aot_registry()))
        throw OptionError(function, "kernels", "aot", "no ahead-of-time kernels for model '" + work_.name + "'");
    provider_ = make_solver_provider(work_, mode, &aot_registry());
}

RunSummary Flow::run(double t, const double* x, const double* v, double t_end, Observer& observer, bool samples,
                     double dt) {
    const std::size_t n = work_.dof();
    work_.t0 = t;
    work_.x0.assign(x, x + n);
    work_.v0.assign(v, v + n);
    Engine engine(work_, *provider_);
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = samples;
    opt.dt = dt;
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
