// hsnc -- where the engine's segment solvers come from (--kernels): the
// ahead-of-time and generic SolverProviders of each KernelChoice
// (kernel_choice.h, solver_provider.h; the JIT's and the cache's are in
// runtime/jit/, the tiered one in tiered_provider.h).
#pragma once

#include <list>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "aot_registry.h"
#include "generic_solver.h"
#include "kernel_choice.h"
#include "solver_provider.h"
#include "interpreted_solver.h"

namespace hsnc {

/// The Eigen solver (runtime/generic_solver.h) for every configuration (for a
/// model with dampers, non-proportional damping, state_space_solver.h): an
/// implementation of the closed forms independent of the programs, the tests'
/// oracle, and the generic path of a runtime used without the generator (no
/// program source). Created on first use and
/// kept in a cache bounded by memory: when the solvers kept exceed `max_bytes`
/// the least recently used are dropped (and rebuilt if the run comes back to
/// them). The solver just returned is never dropped, so the reference the
/// engine holds to the current configuration's solver stays valid until its
/// next call. A run on many masses visits thousands of configurations (a
/// 64-mass chain: about 0.4 MB each); unbounded, they held 5.4 GB at t = 40 s.
class GenericSolverProvider : public SolverProvider {
public:
    /// Default budget: 64 MB of solver data (a few hundred configurations of
    /// 64 masses; every configuration of the small models).
    static constexpr std::size_t kDefaultMaxBytes = std::size_t{64} << 20;

    explicit GenericSolverProvider(const Model& model, std::size_t max_bytes = kDefaultMaxBytes)
        : model_(model), max_bytes_(max_bytes) {}
    GenericSolverProvider(const Model&& model, std::size_t max_bytes = kDefaultMaxBytes) = delete;  ///< would dangle: `model` must outlive it
    SegmentSolver& solver(const Configuration& cfg) override;
    std::string describe() const override;

    std::size_t cached() const { return cache_.size(); }       ///< solvers kept now
    std::size_t built() const { return built_; }               ///< solvers constructed (rebuilds included)
    std::size_t evicted() const { return evicted_; }           ///< solvers dropped
    std::size_t cached_bytes() const { return bytes_; }        ///< their estimated memory

private:
    struct Entry {
        std::unique_ptr<SegmentSolver> solver;  // GenericSolver, or StateSpaceSolver for dampers
        std::size_t bytes;
        std::list<Configuration>::iterator lru;  // position in lru_ (front: most recent)
    };
    const Model& model_;
    std::size_t max_bytes_;
    std::map<Configuration, Entry> cache_;
    std::list<Configuration> lru_;
    std::set<Configuration> seen_;
    std::size_t bytes_ = 0, built_ = 0, evicted_ = 0;
    std::size_t exponential_ = 0;  ///< configurations taken by ExponentialSolver (critically damped)
};

/// Ahead-of-time kernels where the registry has one for (model, configuration);
/// otherwise (fallback) the Eigen solver, or the interpreter of the
/// configuration's program when `lower` is given (kept within memory as those
/// providers keep them), or (no fallback) a RunError naming the configuration.
/// make_solver_provider() gives mode automatic the interpreter as fallback
/// when it has a program source (the kernels' bits for every configuration),
/// else the Eigen solver.
class AotSolverProvider : public SolverProvider {
public:
    AotSolverProvider(const Model& model, const AotRegistry& registry, bool fallback,
                      InterpretedSolverProvider::ProgramFn lower = {});
    AotSolverProvider(const Model&& model, const AotRegistry& registry, bool fallback,
                      InterpretedSolverProvider::ProgramFn lower = {}) = delete;  ///< would dangle
    SegmentSolver& solver(const Configuration& cfg) override;
    std::string describe() const override;

private:
    const Model& model_;
    const AotRegistry& registry_;
    bool fallback_;
    bool fallback_eigen_ = false;  ///< the fallback is the Eigen solver (no program source)
    std::uint64_t hash_;
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;  // the kernels
    std::set<Configuration> generic_;                                // configurations without one
    std::unique_ptr<SolverProvider> fallback_provider_;
};

/// Any provider whose solvers come from the derivation (interpreted programs,
/// JIT kernels; generator/derivation.h), with the configurations the
/// derivation refuses (NotDerivable: critical damping or rigid-body modes
/// under dampers) on the Eigen solver: the same configurations on the same
/// solver whatever the kernel kind, so that every kind still gives the same
/// bits.
class DerivationFallbackProvider : public SolverProvider {
public:
    DerivationFallbackProvider(const Model& model, std::unique_ptr<SolverProvider> primary)
        : primary_(std::move(primary)), generic_(model) {}
    DerivationFallbackProvider(const Model&& model, std::unique_ptr<SolverProvider> primary) = delete;  ///< would dangle
    SegmentSolver& solver(const Configuration& cfg) override;
    /// The primary's line, then "; Eigen solver for N configurations the
    /// derivation does not take (first: reason)" when there were any.
    std::string describe() const override;
    std::size_t not_derivable() const { return refused_.size(); }  ///< configurations on the Eigen solver
    SolverProvider& primary() { return *primary_; }

private:
    std::unique_ptr<SolverProvider> primary_;
    GenericSolverProvider generic_;
    std::set<Configuration> refused_;
    std::string first_reason_;
};

/// Whether `registry` (may be null) holds ahead-of-time kernels of `model` as it is.
bool has_aot_kernels(const Model& model, const AotRegistry* registry);

/// InputError for negative Rayleigh damping (alpha or beta < 0) under any
/// `mode` but eigen: only GenericSolver bounds a growing mode's energy
/// (generic_solver.h); the emitted kernels' bounds assume damping >= 0.
void refuse_negative_damping(const Model& model, KernelChoice mode);

/// The provider for `mode` (not jit or tiered, std::logic_error: those need
/// the generator, see JitSolverProvider and TieredSolverProvider); `registry`
/// (may be null) lists the AOT kernels linked in. Modes generic and interp interpret the programs `lower` gives
/// (generator/lowering.h, program_source(): the same bits as the kernels) and
/// need it (std::invalid_argument without). Mode automatic takes the AOT
/// kernels when the model has them, and the interpreter for every other
/// configuration, or, without `lower` (a runtime used without the generator),
/// the Eigen solver. Mode eigen does not use `lower`. Mode aot: InputError
/// when the model has no ahead-of-time kernels.
std::unique_ptr<SolverProvider> make_solver_provider(const Model& model, KernelChoice mode,
                                                     const AotRegistry* registry,
                                                     InterpretedSolverProvider::ProgramFn lower = {});
/// The provider keeps a reference to `model`: a temporary would dangle.
std::unique_ptr<SolverProvider> make_solver_provider(const Model&& model, KernelChoice mode,
                                                     const AotRegistry* registry,
                                                     InterpretedSolverProvider::ProgramFn lower = {}) = delete;

}  // namespace hsnc
