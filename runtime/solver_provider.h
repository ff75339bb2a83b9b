// hsnc -- where the engine's segment solvers come from (--kernels).
#pragma once

#include <map>
#include <memory>
#include <string>

#include "aot_registry.h"
#include "engine.h"

namespace hsnc {

enum class KernelMode {
    automatic,  ///< ahead-of-time kernels when the model has them, else the
                ///  generic solver (never the JIT: hsnc::simulate, api/hsnc/simulate.h)
    aot,        ///< ahead-of-time kernels only (error when the model has none)
    generic,    ///< the Eigen-based generic solver
    jit,        ///< a kernel compiled in-process per configuration visited
                ///  (runtime/jit_solver_provider.h; opt-in, built by the command line)
};

/// "auto", "aot", "generic", "jit"; InputError otherwise.
KernelMode parse_kernel_mode(const std::string& name);

/// The generic (Eigen) solver for every configuration, created on first use and cached.
class GenericSolverProvider : public SolverProvider {
public:
    explicit GenericSolverProvider(const Model& model) : model_(model) {}
    explicit GenericSolverProvider(const Model&& model) = delete;  ///< would dangle: `model` must outlive it
    SegmentSolver& solver(const Configuration& cfg) override;
    std::string describe() const override;

private:
    const Model& model_;
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;
};

/// Ahead-of-time kernels where the registry has one for (model, configuration);
/// otherwise the generic solver (mode automatic) or a RunError naming the
/// configuration (mode aot).
class AotSolverProvider : public SolverProvider {
public:
    AotSolverProvider(const Model& model, const AotRegistry& registry, bool fallback);
    AotSolverProvider(const Model&& model, const AotRegistry& registry, bool fallback) = delete;  ///< would dangle
    SegmentSolver& solver(const Configuration& cfg) override;
    std::string describe() const override;

private:
    const Model& model_;
    const AotRegistry& registry_;
    bool fallback_;
    std::uint64_t hash_;
    std::size_t aot_ = 0, generic_ = 0;
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;
};

/// Whether `registry` (may be null) holds ahead-of-time kernels of `model` as it is.
bool has_aot_kernels(const Model& model, const AotRegistry* registry);

/// The provider for `mode` (not jit: that one needs the generator, see
/// JitSolverProvider; automatic without kernels gives the generic solver); `registry` (may be null) lists the AOT kernels linked in.
std::unique_ptr<SolverProvider> make_solver_provider(const Model& model, KernelMode mode,
                                                     const AotRegistry* registry);
/// The provider keeps a reference to `model`: a temporary would dangle.
std::unique_ptr<SolverProvider> make_solver_provider(const Model&& model, KernelMode mode,
                                                     const AotRegistry* registry) = delete;

}  // namespace hsnc
