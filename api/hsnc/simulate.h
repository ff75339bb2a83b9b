// hsnc -- the library facade: simulate a model with the exact method or a
// numerical baseline, as `hsnc simulate` does, without the command line.
//
//     const hsnc::Model model = hsnc::read_model("models/seed-scenario-1.toml");
//     hsnc::SimulateOptions options;
//     options.t_end = 2.0;
//     const hsnc::SimulateSummary s = hsnc::simulate(model, options);
//
// One call covers the method (hsnc or the baselines ab4, rk45, cvode), the
// kernels of the exact method (ahead-of-time, JIT-compiled with their
// persistent cache, or the generic path: the same programs interpreted), the precision (double, or the
// high-precision reference at N digits) and sampling. The JIT module
// (libhsnc_jit.so, which links LLVM) is loaded here, from beside the library,
// and only when the caller asks for KernelChoice::jit.
//
// Errors. Options that do not fit are an OptionError (an InputError) naming
// the SimulateOptions field, "hsnc::simulate(): kernels = aot: no
// ahead-of-time kernels for model 'x' ..."; a failure while running (a kernel
// that does not compile, the JIT module missing) is a RunError. A run that
// stops early (chattering, Zeno, max_events, the observer) is not an error:
// RunSummary::status says so, with RunSummary::message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include "error.h"
#include "integrators.h"
#include "kernel_choice.h"
#include "model.h"
#include "model_reader.h"
#include "observer.h"
#include "run_summary.h"

namespace hsnc {

/// What computed a run (for statistics): the kernel kind that ran (a
/// KernelChoice other than automatic, with its value and its name), or one of
/// two engines that are not kernel kinds.
enum class SolverKind {
    aot = static_cast<int>(KernelChoice::aot),          ///< ahead-of-time kernels (the generic solver for configurations without one)
    jit = static_cast<int>(KernelChoice::jit),          ///< JIT-compiled or cached kernels
    generic = static_cast<int>(KernelChoice::generic),  ///< interpreted programs (KernelChoice::generic)
    interp = static_cast<int>(KernelChoice::interp),    ///< interpreted programs (KernelChoice::interp)
    eigen = static_cast<int>(KernelChoice::eigen),      ///< the Eigen solver
    tiered = static_cast<int>(KernelChoice::tiered),    ///< interpreted programs, then kernels (KernelChoice::tiered)
    reference = 100,                                    ///< the high-precision reference engine (precision_digits > 0)
    integrator,                                         ///< a numerical baseline (ab4, rk45, cvode)
};

struct SimulateOptions {
    /// End time; NaN: the model's [simulate].t_end (an OptionError when it has none).
    double t_end = std::numeric_limits<double>::quiet_NaN();
    /// Sample spacing for Observer::on_sample; NaN: (t_end - t0) / 1000.
    double dt = std::numeric_limits<double>::quiet_NaN();
    /// Whether Observer::on_sample is called at all.
    bool samples = true;
    /// Stop after this many switch events (status max_events); 0: no limit.
    std::size_t max_events = 0;

    Method method = Method::hsnc;
    /// The baselines' step (ab4: h, required) and tolerances (rk45, cvode).
    IntegratorOptions integrator;

    /// Method hsnc in double precision only.
    KernelChoice kernels = KernelChoice::automatic;
    /// 0: double precision; N in [20, 100]: the reference engine at N decimal
    /// digits (method hsnc, kernels automatic).
    int precision_digits = 0;

    /// KernelChoice::jit: directory of the persistent kernel cache; "": the
    /// default ($XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc).
    std::string cache_dir;
    /// KernelChoice::jit: false compiles every kernel and reads and writes no cache.
    bool use_cache = true;
    /// KernelChoice::jit: the cache's size limit in bytes (storing a kernel
    /// evicts the least recently used entries beyond it); 0: no limit.
    std::uint64_t cache_max_bytes = std::uint64_t{256} << 20;
    /// KernelChoice::tiered: evaluations a configuration runs interpreted
    /// before its kernel is compiled (at least 1).
    std::uint64_t tier_evaluations = 200000;
    /// Problems that do not stop the run (a damaged cache entry, an
    /// unwritable cache), one line each; empty: "hsnc: warning: ..." on stderr.
    std::function<void(const std::string&)> warn;
};

/// A RunSummary, and what computed it.
struct SimulateSummary : RunSummary {
    SolverKind solver = SolverKind::generic;
    /// One line for run statistics: "4 ahead-of-time kernels, generic solver
    /// for 0 configurations", "JIT: 3 configurations visited, ...".
    std::string solver_detail;
};

/// An option that does not fit: `option()` is the SimulateOptions field
/// ("t_end", "dt", "method", "integrator.h", "integrator.rtol",
/// "integrator.atol", "kernels", "precision_digits"), `reason()` says why
/// without naming any command-line flag. what() is
/// "FUNCTION(): OPTION = VALUE: REASON".
class OptionError : public InputError {
public:
    OptionError(const std::string& function, std::string option, const std::string& value, std::string reason);
    const std::string& option() const { return option_; }
    const std::string& reason() const { return reason_; }

private:
    std::string option_, reason_;
};

/// Runs `model` from its initial state with `options`, reporting samples and
/// switch events to `observer`. Throws OptionError (bad options), RunError
/// (a failure while running: the JIT module missing, a kernel that does not
/// compile, a modal analysis that fails).
SimulateSummary simulate(const Model& model, const SimulateOptions& options, Observer& observer);

/// The same without an observer (no samples).
SimulateSummary simulate(const Model& model, const SimulateOptions& options = {});

/// The checks simulate() makes before it runs anything: OptionError when
/// `options` do not fit `model` (for a caller that has files to open first).
void check_simulate_options(const Model& model, const SimulateOptions& options);

/// "hsnc", "ab4", "rk45", "cvode"; OptionError (option "method") otherwise.
Method method_from_name(const std::string& name);
const char* method_name(Method method);
/// A name of kernel_choice.h's table ("auto", "aot", "generic", "interp",
/// "eigen", "jit", "tiered"); OptionError (option "kernels") otherwise.
/// kernel_choice_name() (kernel_choice.h) gives the name back.
KernelChoice kernel_choice_from_name(const std::string& name);
/// "double" gives 0, "mp:N" gives N (N in [20, 100]); OptionError (option
/// "precision_digits") otherwise.
int precision_digits_from_name(const std::string& name);
/// The kernel kind's name (kernel_choice_name), "reference" or "integrator".
const char* solver_kind_name(SolverKind kind);

}  // namespace hsnc
