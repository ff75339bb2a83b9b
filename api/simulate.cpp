#include "hsnc/simulate.h"

#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <utility>

#include "aot_registry.h"
#include "assembly.h"
#include "cached_kernel_provider.h"
#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "ginac_lock.h"
#include "jit_module.h"
#include "jit_solver_provider.h"
#include "kernel_cache.h"
#include "kernel_mode.h"
#include "lowering.h"
#include "number_text.h"
#include "reference.h"
#include "sample_grid.h"
#include "solver_choice.h"
#include "solver_provider.h"
#include "tiered_provider.h"
#include "transitions.h"

namespace hsnc {
namespace {

constexpr const char* kSimulate = "hsnc::simulate";

class NullObserver : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double, EventKind, int, const double*, const double*) override {}
};

std::string digits_range() {
    return std::to_string(reference::kMinDigits) + ".." + std::to_string(reference::kMaxDigits);
}

double end_time(const Model& model, const SimulateOptions& o) {
    return std::isnan(o.t_end) ? model.t_end.value_or(NAN) : o.t_end;
}

// Options that do not fit, each named by its field; nothing has run yet.
void check_options(const Model& model, const SimulateOptions& o) {
    const double t_end = end_time(model, o);
    if (std::isnan(t_end))
        throw OptionError(kSimulate, "t_end", "NaN",
                          "no end time: none given and the model has no [simulate].t_end (" + model.source + ")");
    if (!(t_end > model.t0) || !std::isfinite(t_end))
        throw OptionError(kSimulate, "t_end", number_text(t_end),
                          "must be finite and after t0 = " + number_text(model.t0));
    if (!std::isnan(o.dt) && !(o.dt > 0 && std::isfinite(o.dt)))
        throw OptionError(kSimulate, "dt", number_text(o.dt), "must be > 0");
    if (o.method == Method::cvode && !HSNC_WITH_CVODE)
        throw OptionError(kSimulate, "method", "cvode", "not available: this build has no SUNDIALS CVODE");
    const IntegratorOptions& i = o.integrator;
    if (o.method == Method::ab4 && !(i.h > 0 && std::isfinite(i.h)))
        throw OptionError(kSimulate, "integrator.h", number_text(i.h),
                          "method ab4 needs a fixed step h > 0");
    if (o.method == Method::ab4) {
        // A step longer than the run, or so short that it never ends (or that
        // t + h rounds to t), would be a run that silently does nothing.
        const double span = t_end - model.t0, t_max = std::max(std::fabs(model.t0), std::fabs(t_end));
        if (i.h > span) throw OptionError(kSimulate, "integrator.h", number_text(i.h), "longer than the run (t_end - t0)");
        if (span / i.h > kMaxSteps)
            throw OptionError(kSimulate, "integrator.h", number_text(i.h), "more than 1e12 steps over the run");
        if (t_max + i.h == t_max)
            throw OptionError(kSimulate, "integrator.h", number_text(i.h), "below the rounding of t (t + h == t)");
    }
    // Tolerances are checked whatever the method (a bad one is a mistake even where it is unused).
    const std::string why = "must be finite and > 0";
    if (!(i.rtol > 0 && std::isfinite(i.rtol)))
        throw OptionError(kSimulate, "integrator.rtol", number_text(i.rtol), why);
    if (!(i.atol > 0 && std::isfinite(i.atol)))
        throw OptionError(kSimulate, "integrator.atol", number_text(i.atol), why);
    if (o.precision_digits != 0) {
        const std::string digits = std::to_string(o.precision_digits);
        if (o.precision_digits < reference::kMinDigits || o.precision_digits > reference::kMaxDigits)
            throw OptionError(kSimulate, "precision_digits", digits,
                              "expected 0 (double), or N in " + digits_range() + " decimal digits");
        if (o.method != Method::hsnc)
            throw OptionError(kSimulate, "precision_digits", digits,
                              std::string("only with method hsnc (not ") + method_name(o.method) + ")");
        if (o.kernels != KernelChoice::automatic)
            throw OptionError(kSimulate, "kernels", kernel_choice_name(o.kernels),
                              "applies to double precision only");
    }
    // Non-proportional damping (dampers): every kernel kind takes it (state-space
    // pseudo-modes, generator/derivation.h; the configurations the derivation
    // refuses run on the Eigen solver in every kind), and the reference too
    // (the matrix exponential at N digits, reference/mp_segment.h).
    // Jenkins elements (a slider carried beside the state) and friction between
    // two bodies (a stuck pair, one body): hsnc (every kernel kind), rk45 and
    // CVODE take both, ab4 neither (its own stick rules hold a mass against
    // the ground); the reference takes both.
    if (const std::string what = stick_elements(model); !what.empty()) {
        if (o.method == Method::ab4)
            throw OptionError(kSimulate, "method", method_name(o.method),
                              "the model has " + what + ", which hsnc, rk45 and cvode run, for now");
    }
    if (o.tier_evaluations < 1)
        throw OptionError(kSimulate, "tier_evaluations", "0", "must be at least 1");
    if (o.method != Method::hsnc && o.kernels != KernelChoice::automatic)
        throw OptionError(kSimulate, "kernels", kernel_choice_name(o.kernels),
                          std::string("applies to method hsnc only (not ") + method_name(o.method) + ")");
    if (o.precision_digits == 0 && o.method == Method::hsnc && o.kernels == KernelChoice::aot &&
        !has_aot_kernels(model, &aot_registry()))
        throw OptionError(kSimulate, "kernels", "aot",
                          "no ahead-of-time kernels for model '" + model.name +
                              "' (bundled models only, and only as generated: an override or an edited file "
                              "changes the model)");
}

// KernelChoice::jit: kernels from the persistent cache without LLVM, the JIT
// module (LLVM) loaded only for a kernel the cache cannot give; no cache: the
// JIT module for every kernel. RunError (a JitUnavailable) when it is needed
// and cannot be loaded.
JitOptions jit_options(const SimulateOptions& o) {
    JitOptions jopt;
    jopt.cache_dir = !o.use_cache ? "" : o.cache_dir.empty() ? default_cache_dir() : o.cache_dir;
    jopt.warn = o.warn;
    jopt.cache_max_bytes = o.cache_max_bytes;
    return jopt;
}

std::unique_ptr<SolverProvider> make_jit_provider(const Model& model, const SimulateOptions& o, const std::string& who,
                                                  bool tiered = false) {
    const JitOptions jopt = jit_options(o);
    JitSolverProvider::SourceFn source = [&model](const Configuration& cfg) {
        const auto lock = ginac_lock();  // the derivation is GiNaC (ginac_lock.h)
        return JitKernelSource{kernel_symbol(model, cfg), emit_kernel(derive(model, cfg))};
    };
    // Checked up front even when every kernel may come from the cache: asking
    // for the JIT is asking for the module, and a missing one says so at once.
    const std::string module = api::jit_module_path();
    const std::string kind = tiered ? "tiered" : "jit";
    if (module.empty()) throw api::JitUnavailable(who + "(): kernels = " + kind + ": this hsnc was built without the JIT");
    if (::access(module.c_str(), R_OK) != 0)
        throw api::JitUnavailable(who + "(): kernels = " + kind + ": cannot load the JIT module: " + module + ": " +
                                  std::strerror(errno));
    if (jopt.cache_dir.empty()) {
        try {
            return api::load_jit_provider(model, source, jopt);
        } catch (const api::JitUnavailable& e) {
            throw api::JitUnavailable(who + "(): kernels = " + kind + ": " + e.what());
        }
    }
    return std::make_unique<CachedKernelProvider>(
        model, source, jopt, [&model, who](JitSolverProvider::SourceFn s, const JitOptions& opt) {
            try {
                return api::load_jit_provider(model, std::move(s), opt);
            } catch (const api::JitUnavailable& e) {
                throw RunError(who + "(): cannot compile a kernel: " + e.what());
            }
        });
}

// KernelChoice::tiered: the interpreter, then kernels, from the cache at a
// configuration's first entry (a provider that never compiles) or compiled
// into the cache by a child process once the configuration has earned them.
// Without a cache, interpreted only.
std::unique_ptr<SolverProvider> make_tiered_provider(const Model& model, const SimulateOptions& o, const std::string& who) {
    TieredSolverProvider::ProbeFn probe;
    TieredSolverProvider::CompileFn compile;
    std::shared_ptr<CachedKernelProvider> lookup;
    if (o.use_cache) {
        auto never_emitted = [](const Configuration&) -> JitKernelSource { throw std::logic_error("never emitted"); };
        auto never_compiles = [](JitSolverProvider::SourceFn, const JitOptions&) -> std::unique_ptr<JitSolverProvider> {
            throw std::logic_error("never compiles");
        };
        lookup = std::make_shared<CachedKernelProvider>(model, never_emitted, jit_options(o), never_compiles);
    }
    if (lookup && !lookup->refused()) {  // a refused cache (others can write to it) was warned about
        probe = [lookup](const Configuration& cfg) { return lookup->cached(cfg); };
        // In the child: a kernel compiled but not stored (a cache it cannot
        // write) is a failure, which the run reports once; its warnings would
        // interleave with the run's output.
        compile = [&model, o, who](const Configuration& cfg) {
            SimulateOptions quiet = o;
            auto problem = std::make_shared<std::string>();
            quiet.warn = [problem](const std::string& w) {
                if (problem->empty()) *problem = w;
            };
            make_jit_provider(model, quiet, who, true)->solver(cfg);
            if (!problem->empty()) throw RunError(*problem);
        };
    }
    TierOptions tier;
    tier.compile_after = o.tier_evaluations;
    return std::make_unique<TieredSolverProvider>(
        make_solver_provider(model, KernelChoice::generic, &aot_registry(), program_source(model)), std::move(probe),
        std::move(compile), tier, o.warn);
}

}  // namespace

namespace api {

std::unique_ptr<SolverProvider> make_provider(const Model& model, const SimulateOptions& o, SolverKind* kind,
                                              const char* function) {
    if (o.kernels != KernelChoice::eigen) refuse_negative_damping(model, o.kernels);
    if (o.kernels == KernelChoice::tiered) {
        if (kind) *kind = SolverKind::tiered;
        return make_tiered_provider(model, o, function);
    }
    if (o.kernels == KernelChoice::jit) {
        if (kind) *kind = SolverKind::jit;
        return std::make_unique<DerivationFallbackProvider>(model, make_jit_provider(model, o, function));
    }
    const KernelChoice mode = o.kernels;
    // generic (and auto without AOT kernels, and for the configurations the
    // AOT kernels leave out) runs each configuration's program: the bits of
    // the kernels printed from it, without a compiler.
    std::unique_ptr<SolverProvider> provider =
        make_solver_provider(model, mode, &aot_registry(), program_source(model));
    if (kind)
        *kind = dynamic_cast<AotSolverProvider*>(provider.get()) ? SolverKind::aot
                : mode == KernelChoice::interp                   ? SolverKind::interp
                : mode == KernelChoice::eigen                    ? SolverKind::eigen
                                                                 : SolverKind::generic;
    return provider;
}

}  // namespace api

OptionError::OptionError(const std::string& function, std::string option, const std::string& value,
                         std::string reason)
    : InputError(function + "(): " + option + " = " + value + ": " + reason),
      option_(std::move(option)),
      reason_(std::move(reason)) {}

void check_simulate_options(const Model& model, const SimulateOptions& options) { check_options(model, options); }

namespace {

// One run at one constant load: the reference, a baseline or the engine.
SimulateSummary run_at_one_load(const Model& model, const SimulateOptions& o, const EngineOptions& eopt,
                                Observer& observer) {
    SimulateSummary s;
    if (o.precision_digits > 0) {
        static_cast<RunSummary&>(s) = reference::simulate(model, o.precision_digits, eopt, observer);
        s.solver = SolverKind::reference;
        s.solver_detail = "reference engine at " + std::to_string(o.precision_digits) + " digits (CLN, " +
                          std::to_string(reference::carried_bits(o.precision_digits)) + " bits)";
    } else if (o.method != Method::hsnc) {
        static_cast<RunSummary&>(s) = integrate(model, o.method, o.integrator, eopt, observer);
        s.solver = SolverKind::integrator;
        s.solver_detail = method_name(o.method);
    } else {
        const std::unique_ptr<SolverProvider> provider = api::make_provider(model, o, &s.solver, kSimulate);
        EngineOptions with_plans = eopt;
        with_plans.restart_plans = restart_plan_source(model);  // for the kernels: the interpreter keeps its own
        Engine engine(model, *provider);
        static_cast<RunSummary&>(s) = engine.run(with_plans, observer);
        s.solver_detail = provider->describe();
    }
    return s;
}

// A model with [[load_step]]s runs in pieces, one per constant load: each
// piece is the model with that load, started from the exact state (masses,
// velocities, sliders) where the last one ended, on the whole run's sample
// grid; each step's instant is a load_change row between the two pieces. A
// step at or after t_end changes nothing. The reference carries the state
// across a step in double (rounded once there).
SimulateSummary run_in_pieces(const Model& model, const SimulateOptions& o, const EngineOptions& whole,
                              Observer& observer) {
    const SampleGrid grid(model.t0, whole.t_end, whole.dt);
    Model piece = model;
    piece.load_steps.clear();
    SimulateSummary total;
    std::optional<Configuration> carried;  // the configuration a step carries into the next piece
    for (std::size_t p = 0;; ++p) {
        const bool last = p == model.load_steps.size() || !(model.load_steps[p].t < whole.t_end);
        EngineOptions eopt = whole;
        eopt.t_end = last ? whole.t_end : model.load_steps[p].t;
        eopt.grid_t0 = model.t0;
        eopt.grid_t_end = whole.t_end;
        eopt.first_sample = p == 0 ? 0 : grid.first_after(piece.t0);
        if (whole.max_events > 0) eopt.max_events = whole.max_events - total.events;
        eopt.carried = carried;
        const SimulateSummary s = run_at_one_load(piece, o, eopt, observer);
        const std::size_t events = total.events, segments = total.segments, restarts = total.restarts,
                          evaluations = total.evaluations, configurations = total.configurations;
        total = s;
        total.events += events, total.segments += segments, total.restarts += restarts;
        total.evaluations += evaluations, total.configurations += configurations;
        if (s.status == RunStatus::max_events)
            total.message = "stopped after " + std::to_string(total.events) + " events";
        if (last || s.status != RunStatus::ok) return total;
        // The step: the next piece starts here, with the step's load.
        const LoadStep& step = model.load_steps[p];
        std::vector<double> x = s.x;
        x.insert(x.end(), s.slider.begin(), s.slider.end());
        observer.on_event(step.t, EventKind::load_change, static_cast<int>(p), x.data(), s.v.data());
        ++total.events;
        piece.load = step.load;
        if (model.condensation.present()) piece.condensation.load = step.condensed_load;
        // Contacts and Jenkins elements keep their state across the step; friction
        // is decided again with the new load, and a change is a row of its own
        // (a stuck mass the new load pulls beyond mu_s N releases here).
        std::vector<signed char> sgn;
        const Configuration after = entered_configuration(piece, step.t, x.data(), s.v.data(), sgn, &s.configuration);
        for (std::size_t i = 0; i < model.dof(); ++i)
            if (after.stuck[i] != s.configuration.stuck[i]) {
                observer.on_event(step.t, after.stuck[i] ? EventKind::stick : EventKind::release, static_cast<int>(i),
                                  x.data(), s.v.data());
                ++total.events;
            }
        carried = after;
        if (whole.max_events > 0 && total.events >= whole.max_events) {
            total.status = RunStatus::max_events;
            total.message = "stopped after " + std::to_string(total.events) + " events";
            return total;
        }
        piece.t0 = step.t;
        piece.x0 = s.x;
        piece.v0 = s.v;
        piece.slider0 = s.slider;
    }
}

}  // namespace

SimulateSummary simulate(const Model& model, const SimulateOptions& o, Observer& observer) {
    check_options(model, o);
    const double t_end = end_time(model, o);

    EngineOptions eopt;
    eopt.t_end = t_end;
    eopt.dt = std::isnan(o.dt) ? SampleGrid::default_dt(model.t0, t_end) : o.dt;
    eopt.samples = o.samples;
    eopt.max_events = o.max_events;
    if (!model.load_steps.empty()) return run_in_pieces(model, o, eopt, observer);
    return run_at_one_load(model, o, eopt, observer);
}

SimulateSummary simulate(const Model& model, const SimulateOptions& options) {
    NullObserver none;
    SimulateOptions o = options;
    o.samples = false;
    return simulate(model, o, none);
}

Method method_from_name(const std::string& name) {
    for (Method m : {Method::hsnc, Method::ab4, Method::rk45, Method::cvode})
        if (name == method_name(m)) return m;
    throw OptionError("hsnc::method_from_name", "method", "'" + name + "'", "expected hsnc, ab4, rk45 or cvode");
}

const char* method_name(Method method) {
    switch (method) {
    case Method::hsnc: return "hsnc";
    case Method::ab4: return "ab4";
    case Method::rk45: return "rk45";
    case Method::cvode: return "cvode";
    }
    return "?";
}

KernelChoice kernel_choice_from_name(const std::string& name) {
    if (const std::optional<KernelChoice> k = parse_kernel_choice(name)) return *k;
    throw OptionError("hsnc::kernel_choice_from_name", "kernels", "'" + name + "'",
                      "expected " + kernel_choice_names());
}

int precision_digits_from_name(const std::string& name) {
    constexpr const char* kFunction = "hsnc::precision_digits_from_name";
    if (name == "double") return 0;
    if (name == "long-double")
        throw OptionError(kFunction, "precision_digits", name,
                          "not offered; use mp:N (N in " + digits_range() + ") for a high-precision reference run");
    const std::string prefix = "mp:";
    std::size_t used = 0;
    int digits = 0;
    bool ok = name.compare(0, prefix.size(), prefix) == 0 && name.size() > prefix.size();
    if (ok) {
        try {
            digits = std::stoi(name.substr(prefix.size()), &used);
        } catch (const std::exception&) {
            ok = false;
        }
        ok = ok && used == name.size() - prefix.size();
    }
    if (!ok || digits < reference::kMinDigits || digits > reference::kMaxDigits)
        throw OptionError(kFunction, "precision_digits", name, "expected double, or mp:N with N in " + digits_range());
    return digits;
}

const char* solver_kind_name(SolverKind kind) {
    switch (kind) {
    case SolverKind::reference: return "reference";
    case SolverKind::integrator: return "integrator";
    default: return kernel_choice_name(static_cast<KernelChoice>(kind));
    }
}

}  // namespace hsnc
