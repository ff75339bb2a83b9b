// `hsnc simulate MODEL [options]` (interface.md sections 3 and 4).
#include <dlfcn.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "csv_writer.h"
#include "engine.h"
#include "error.h"
#include "derivation.h"
#include "emitter.h"
#include "integrators.h"
#include "cached_kernel_provider.h"
#include "jit_solver_provider.h"
#include "kernel_cache.h"
#include "model_reader.h"
#include "plot.h"
#include "reference.h"
#include "solver_provider.h"

namespace hsnc::cli {
namespace {

struct SimulateOptions {
    std::string model;
    double t_end = NAN;
    ModelOverrides overrides;
    double dt = NAN;
    std::string out, events, plot;
    std::string method = "hsnc";
    double h = NAN;
    double rtol = 1e-10, atol = 1e-12;
    std::string kernels = "auto";
    std::string cache_dir;
    bool no_cache = false;
    std::uint64_t cache_max_bytes = kDefaultCacheMaxBytes;
    std::size_t max_events = 0;
    bool quiet = false;
    std::string precision = "double";
};

// Wraps the CSV observer: counts event kinds, draws a progress bar on a terminal.
class RunObserver : public Observer {
public:
    RunObserver(Observer& inner, double t0, double t_end, bool show)
        : inner_(inner), t0_(t0), t_end_(t_end), show_(show), start_(std::chrono::steady_clock::now()) {}
    void on_sample(double t, const double* x, const double* v) override {
        inner_.on_sample(t, x, v);
        if ((++samples_ & 1023) == 0) on_progress(t);
    }
    void on_event(double t, EventKind kind, int element, const double* x, const double* v) override {
        inner_.on_event(t, kind, element, x, v);
        ++counts_[static_cast<int>(kind)];
    }
    bool on_progress(double t) override {
        if (!show_) return true;
        const double elapsed = seconds();
        if (elapsed < 0.5 || elapsed - last_draw_ < 0.1) return true;
        last_draw_ = elapsed;
        const double frac = std::min(1.0, std::max(0.0, (t - t0_) / (t_end_ - t0_)));
        const int width = 30, filled = static_cast<int>(frac * width);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  t = %.6g s", filled, "##############################",
                     width - filled, "", 100 * frac, t);
        drawn_ = true;
        return true;
    }
    void clear() {
        if (drawn_) std::fprintf(stderr, "\r%60s\r", "");
    }
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    std::size_t count(EventKind k) const { return counts_[static_cast<int>(k)]; }

private:
    Observer& inner_;
    double t0_, t_end_;
    bool show_;
    std::chrono::steady_clock::time_point start_;
    double last_draw_ = 0;
    bool drawn_ = false;
    std::size_t samples_ = 0;
    std::size_t counts_[5] = {};
};

// LLVM and Clang are loaded only when a kernel has to be compiled (or loaded
// without the cache): libhsnc_jit.so, from beside the executable (both are
// built into the same directory). Throws JitUnavailable when it cannot be loaded.
struct JitUnavailable : RunError {
    using RunError::RunError;
};
std::string jit_module_path() {
    char exe[4096];
    const ssize_t len = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
    std::string dir = len > 0 ? std::string(exe, static_cast<std::size_t>(len)) : std::string(".");
    return dir.substr(0, dir.find_last_of('/') + 1) + HSNC_JIT_MODULE;
}
std::unique_ptr<JitSolverProvider> load_jit_provider(const Model& model, JitSolverProvider::SourceFn source,
                                                     const JitOptions& options) {
    const std::string path = jit_module_path();
    void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // kept loaded: kernels live in it
    if (!module) throw JitUnavailable(std::string("cannot load the JIT module: ") + ::dlerror());
    auto factory = reinterpret_cast<JitProviderFactory>(::dlsym(module, kJitProviderFactorySymbol));
    if (!factory) throw JitUnavailable(path + " has no " + kJitProviderFactorySymbol);
    // The factory makes a JitSolverProvider (jit_solver_provider.cpp).
    return std::unique_ptr<JitSolverProvider>(
        static_cast<JitSolverProvider*>(factory(model, std::move(source), options)));
}

// --precision: 0 for double, else the decimal digits of the reference engine (mp:N).
int parse_precision(const SimulateOptions& o, Method method) {
    if (o.precision == "double") return 0;
    if (o.precision == "long-double")
        throw InputError("--precision long-double: not offered; use mp:N (N in " +
                         std::to_string(reference::kMinDigits) + ".." + std::to_string(reference::kMaxDigits) +
                         ") for a high-precision reference run");
    const std::string prefix = "mp:";
    std::size_t used = 0;
    int digits = 0;
    bool ok = o.precision.compare(0, prefix.size(), prefix) == 0 && o.precision.size() > prefix.size();
    if (ok) {
        try {
            digits = std::stoi(o.precision.substr(prefix.size()), &used);
        } catch (const std::exception&) {
            ok = false;
        }
        ok = ok && used == o.precision.size() - prefix.size();
    }
    if (!ok || digits < reference::kMinDigits || digits > reference::kMaxDigits)
        throw InputError("--precision " + o.precision + ": expected double, or mp:N with N in " +
                         std::to_string(reference::kMinDigits) + ".." + std::to_string(reference::kMaxDigits));
    if (method != Method::hsnc)
        throw InputError("--precision " + o.precision + ": only with --method hsnc (not " + o.method + ")");
    if (o.kernels != "auto")
        throw InputError("--precision " + o.precision + ": --kernels applies to double precision only");
    return digits;
}

std::string number_text(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

int simulate(const SimulateOptions& o) {
    const Model model = read_model(o.model, o.overrides);
    const double t_end = std::isnan(o.t_end) ? model.t_end.value_or(NAN) : o.t_end;
    if (std::isnan(t_end))
        throw InputError("--t-end: no end time: give --t-end or [simulate].t_end in " + o.model);
    if (!(t_end > model.t0) || !std::isfinite(t_end))
        throw InputError("--t-end " + number_text(t_end) + ": must be finite and after t0 = " + number_text(model.t0));
    if (!std::isnan(o.dt) && !(o.dt > 0 && std::isfinite(o.dt)))
        throw InputError("--dt " + number_text(o.dt) + ": must be > 0");
    if (!o.plot.empty() && o.out.empty()) throw InputError("--plot: needs --out (the trajectory it draws)");
    Method method = parse_method(o.method);
    IntegratorOptions iopt;
    iopt.h = o.h;
    iopt.rtol = o.rtol;
    iopt.atol = o.atol;
    validate(method, iopt);
    const KernelMode mode = parse_kernel_mode(o.kernels);
    const int digits = parse_precision(o, method);

    std::unique_ptr<CsvFile> traj, events;
    if (!o.out.empty()) traj = std::make_unique<CsvFile>(o.out);
    if (!o.events.empty()) events = std::make_unique<CsvFile>(o.events);
    CsvObserver csv(model, traj.get(), events.get());
    RunObserver obs(csv, model.t0, t_end, !o.quiet && ::isatty(2));

    EngineOptions eopt;
    eopt.t_end = t_end;
    // Default sampling: 1000 intervals over the run.
    eopt.dt = std::isnan(o.dt) ? (t_end - model.t0) / 1000 : o.dt;
    eopt.samples = traj != nullptr;
    eopt.max_events = o.max_events;

    RunSummary sum;
    std::string detail;
    if (digits > 0) {
        sum = reference::simulate(model, digits, eopt, obs);
        detail = "reference engine at " + std::to_string(digits) + " digits (CLN, " +
                 std::to_string(reference::carried_bits(digits)) + " bits)";
    } else if (method == Method::hsnc) {
        std::unique_ptr<SolverProvider> provider;
        // auto: the ahead-of-time kernels when the model has them, else the
        // JIT, else (no libhsnc_jit.so) the generic solver, with a note.
        if (mode == KernelMode::jit || (mode == KernelMode::automatic && !has_aot_kernels(model, &aot_registry()))) {
            JitOptions jopt;
            jopt.cache_dir = o.no_cache ? "" : o.cache_dir.empty() ? default_cache_dir() : o.cache_dir;
            jopt.cache_max_bytes = o.cache_max_bytes;
            JitSolverProvider::SourceFn source = [&model](const Configuration& cfg) {
                return JitKernelSource{kernel_symbol(model, cfg), emit_kernel(derive(model, cfg))};
            };
            try {
                const std::string module = jit_module_path();
                if (::access(module.c_str(), R_OK) != 0)
                    throw JitUnavailable("cannot load the JIT module: " + module + ": " + std::strerror(errno));
                if (jopt.cache_dir.empty())
                    provider = load_jit_provider(model, source, jopt);
                else  // cached kernels without LLVM; the JIT only for the others
                    provider = std::make_unique<CachedKernelProvider>(
                        model, source, jopt, [&model](JitSolverProvider::SourceFn s, const JitOptions& opt) {
                            try {
                                return load_jit_provider(model, std::move(s), opt);
                            } catch (const JitUnavailable& e) {
                                throw RunError(std::string("cannot compile a kernel: ") + e.what());
                            }
                        });
            } catch (const JitUnavailable& e) {
                if (mode == KernelMode::jit) throw RunError(std::string("--kernels jit: ") + e.what());
                if (!o.quiet) std::fprintf(stderr, "hsnc: note: %s; using the generic solver\n", e.what());
            }
        }
        if (!provider) provider = make_solver_provider(model, mode, &aot_registry());
        Engine engine(model, *provider);
        sum = engine.run(eopt, obs);
        detail = provider->describe();
    } else {
        sum = integrate(model, method, iopt, eopt, obs);
    }
    obs.clear();
    if (sum.status != RunStatus::ok && sum.status != RunStatus::max_events)
        throw RunError(std::string("simulate: ") + run_status_name(sum.status) + ": " + sum.message);
    if (traj) traj->commit();
    if (events) events->commit();
    if (!o.plot.empty()) plot_trajectory(model, o.out, o.plot);

    // The summary line (stdout): status, switch events, end state.
    std::ostringstream line;
    line << "status=" << run_status_name(sum.status) << " method=" << o.method << " t=" << number_text(sum.t)
         << " events=" << sum.events;
    for (EventKind k : {EventKind::contact_close, EventKind::contact_open, EventKind::stick, EventKind::release,
                        EventKind::reversal})
        line << " " << event_kind_name(k) << "=" << obs.count(k);
    for (std::size_t i = 0; i < model.dof(); ++i) line << " x_" << model.masses[i].name << "=" << number_text(sum.x[i]);
    for (std::size_t i = 0; i < model.dof(); ++i) line << " v_" << model.masses[i].name << "=" << number_text(sum.v[i]);
    std::cout << line.str() << std::endl;
    if (!o.quiet) {
        std::fprintf(stderr, "hsnc: %zu segments, %zu evaluations (%.1f per switch), %zu configurations visited%s%s, %.3f s\n",
                     sum.segments, sum.evaluations,
                     sum.events ? static_cast<double>(sum.evaluations) / static_cast<double>(sum.events) : 0.0,
                     sum.configurations, detail.empty() ? "" : ", ", detail.c_str(), obs.seconds());
        if (sum.status == RunStatus::max_events) std::fprintf(stderr, "hsnc: %s\n", sum.message.c_str());
    }
    return 0;
}

}  // namespace

void add_simulate(CLI::App& app, int& exit_code) {
    auto o = std::make_shared<SimulateOptions>();
    auto* sub = app.add_subcommand("simulate", "run a simulation from the model's initial state");
    sub->add_option("MODEL", o->model, "model file (TOML)")->required();
    sub->add_option("--t-end", o->t_end, "end time (default [simulate].t_end)");
    sub->add_option("--set", o->overrides.set, "override a parameter, NAME=VALUE (repeatable)");
    sub->add_option("--x0", o->overrides.x0, "override an initial position, NAME=VALUE (repeatable)");
    sub->add_option("--v0", o->overrides.v0, "override an initial velocity, NAME=VALUE (repeatable)");
    sub->add_option("--dt", o->dt, "trajectory rows at t0, t0+DT, ... and t_end (default: (t_end-t0)/1000)");
    sub->add_option("--out", o->out, "trajectory CSV (default: none)");
    sub->add_option("--events", o->events, "switch-event CSV (default: none)");
    sub->add_option("--plot", o->plot, "draw x(t) of every mass from --out into this PNG (gnuplot)");
    sub->add_option("--method", o->method,
                    "hsnc (exact, default); ab4 (fixed-step Adams-Bashforth 4, needs --h); "
                    "rk45 (adaptive Dormand-Prince with event location, --rtol/--atol); "
                    "cvode (SUNDIALS CVODE, Adams with root finding, --rtol/--atol)");
    sub->add_option("--h", o->h, "step of --method ab4");
    sub->add_option("--rtol", o->rtol, "relative tolerance of --method rk45/cvode (default 1e-10)");
    sub->add_option("--atol", o->atol, "absolute tolerance of --method rk45/cvode (default 1e-12)");
    sub->add_option("--kernels", o->kernels,
                    "auto (default: ahead-of-time kernels when the model has them, else jit), aot, generic, "
                    "jit (compile a kernel in-process for each configuration the run enters)");
    sub->add_option("--cache-dir", o->cache_dir,
                    "keep compiled kernels (jit) in DIR (default $XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc)");
    auto* no_cache = sub->add_flag("--no-cache", o->no_cache, "compile every kernel (jit); read and write no cache");
    no_cache->excludes(sub->get_option("--cache-dir"));
    sub->add_option_function<std::string>(
        "--cache-max-size", [o](const std::string& t) { o->cache_max_bytes = parse_byte_size(t, "--cache-max-size"); },
        "keep the cache under this size, evicting the least recently used kernels (default 256M; 0: no limit)");
    sub->add_option("--max-events", o->max_events, "stop after this many switch events (0: no limit)");
    sub->add_option("--precision", o->precision,
                    "double (default); mp:N: the high-precision reference engine, every quantity at N decimal "
                    "digits (N in 20..100, CLN) from the model's double values taken exactly; output still "
                    "rounded to 17 digits. long-double is not offered");
    sub->add_flag("--quiet", o->quiet, "no progress or statistics on stderr");
    sub->callback([o, &exit_code] { exit_code = simulate(*o); });
}

}  // namespace hsnc::cli
