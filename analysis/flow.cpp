#include "flow.h"

#include <cmath>
#include <sstream>

#include "aot_registry.h"
#include "assembly.h"
#include "engine.h"
#include "kernel_mode.h"
#include "lowering.h"
#include "number_text.h"
#include "solver_choice.h"

namespace hsnc::analysis {

Flow::Flow(const Model& model, const FlowKernels& k, const char* function) : work_(model) {
    refuse_load_steps(model, std::string(function) + "()");
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

// Forwards everything to the run's observer and asks Flow::progress_ now and
// then whether to go on; a stop asked for between two engine checks is
// answered at the next one.
class Flow::ProgressObserver : public Observer {
public:
    ProgressObserver(Observer& inner, const std::function<bool(double)>& progress, bool& stopped)
        : inner_(inner), progress_(progress), stopped_(stopped) {}
    bool wants_segments() const override { return inner_.wants_segments(); }
    void on_sample(double t, const double* x, const double* v) override {
        inner_.on_sample(t, x, v);
        if ((++samples_ & 1023) == 0) ask(t);
    }
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        inner_.on_event(t, kind, element, x, v);
    }
    bool on_progress(double t) override {
        ask(t);
        return !stopped_ && inner_.on_progress(t);
    }
    void on_segment(const SegmentRecord& s) override {
        inner_.on_segment(s);
        ask(s.t + s.t_lo + s.tau);
    }
    void on_switch(const SwitchRecord& r) override { inner_.on_switch(r); }

private:
    void ask(double t) {
        if (!stopped_ && !progress_(t)) stopped_ = true;
    }
    Observer& inner_;
    const std::function<bool(double)>& progress_;
    bool& stopped_;
    std::size_t samples_ = 0;
};

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
    if (!progress_) return engine.run(opt, observer);
    ProgressObserver watched(observer, progress_, stopped_);
    return engine.run(opt, watched);
}

void check_number(const char* function, const char* option, double value, bool positive) {
    if (std::isfinite(value) && (!positive || value > 0)) return;
    throw OptionError(function, option, number_text(value), positive ? "must be finite and > 0" : "must be finite");
}

}  // namespace hsnc::analysis
