#include "kernel_mode.h"

#include <algorithm>
#include <stdexcept>

#include "error.h"
#include "generic_solver.h"
#include "exponential_solver.h"
#include "state_space_solver.h"
#include "kernel_solver.h"
#include "model_hash.h"

namespace hsnc {
namespace {

// Negative Rayleigh damping (hsnc modes' EPMC model copies; a model file cannot give it).
bool negative_damping(const Model& model) {
    return model.alpha < 0.0 || model.beta < 0.0;
}

}  // namespace

SegmentSolver& GenericSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second.lru);  // most recently used
        return *it->second.solver;
    }
    std::unique_ptr<SegmentSolver> s;
    std::size_t bytes = 0;
    if (model_.proportional_damping()) {
        auto g = std::make_unique<GenericSolver>(model_, cfg);
        bytes = g->memory_bytes();
        s = std::move(g);
    } else {
        try {
            auto g = std::make_unique<StateSpaceSolver>(model_, cfg);
            bytes = g->memory_bytes();
            s = std::move(g);
        } catch (const DefectiveModes&) {  // critically damped: the matrix exponential takes every regime
            auto g = std::make_unique<ExponentialSolver>(model_, cfg);
            bytes = g->memory_bytes();
            s = std::move(g);
            ++exponential_;
        }
    }
    ++built_;
    seen_.insert(cfg);
    lru_.push_front(cfg);
    it = cache_.emplace(cfg, Entry{std::move(s), bytes, lru_.begin()}).first;
    bytes_ += bytes;
    // Drop the least recently used until within budget; never the one returned now.
    while (bytes_ > max_bytes_ && lru_.size() > 1) {
        const auto victim = cache_.find(lru_.back());
        bytes_ -= victim->second.bytes;
        cache_.erase(victim);
        lru_.pop_back();
        ++evicted_;
    }
    return *it->second.solver;
}

std::string GenericSolverProvider::describe() const {
    std::string text = std::string(model_.proportional_damping() ? "Eigen solver" : "Eigen solver (state-space modes)") +
                       " for " + std::to_string(seen_.size()) + " configurations";
    if (exponential_ > 0)
        text += " (" + std::to_string(exponential_) + " critically damped: by the matrix exponential)";
    if (evicted_ > 0)
        text += " (" + std::to_string(cache_.size()) + " kept within " + std::to_string(max_bytes_ >> 20) +
                " MB, " + std::to_string(built_ - seen_.size()) + " rebuilt)";
    return text;
}

AotSolverProvider::AotSolverProvider(const Model& model, const AotRegistry& registry, bool fallback,
                                     InterpretedSolverProvider::ProgramFn lower)
    : model_(model), registry_(registry), fallback_(fallback), hash_(model_hash(model)) {
    if (!fallback_) return;
    fallback_eigen_ = !lower;
    if (lower)
        fallback_provider_ = std::make_unique<DerivationFallbackProvider>(
            model_, std::make_unique<InterpretedSolverProvider>(std::move(lower)));
    else
        fallback_provider_ = std::make_unique<GenericSolverProvider>(model_);
}

SegmentSolver& AotSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) return *it->second;
    if (generic_.count(cfg)) return fallback_provider_->solver(cfg);
    if (const hsnc_kernel* k = find_aot_kernel(registry_, model_.name.c_str(), hash_, cfg.key().c_str()))
        return *cache_.emplace(cfg, std::make_unique<KernelSolver>(*k)).first->second;
    if (!fallback_)
        throw RunError("AotSolverProvider::solver(): no ahead-of-time kernel for configuration '" +
                       cfg.spec(model_) + "' of model '" + model_.name +
                       "' (generate it with hsnc generate, or choose the kernels auto)");
    generic_.insert(cfg);
    return fallback_provider_->solver(cfg);
}

std::string AotSolverProvider::describe() const {
    return std::to_string(cache_.size()) + " ahead-of-time kernels, " +
           (fallback_eigen_ ? "Eigen solver for " : "generic solver for ") + std::to_string(generic_.size()) +
           " configurations";
}

SegmentSolver& DerivationFallbackProvider::solver(const Configuration& cfg) {
    if (refused_.count(cfg)) return generic_.solver(cfg);
    try {
        return primary_->solver(cfg);
    } catch (const NotDerivable& e) {
        if (refused_.empty()) first_reason_ = e.what();
        refused_.insert(cfg);
        return generic_.solver(cfg);
    }
}

std::string DerivationFallbackProvider::describe() const {
    std::string text = primary_->describe();
    if (!refused_.empty())
        text += "; " + generic_.describe() + " the derivation does not take (first: " + first_reason_ + ")";
    return text;
}

void refuse_negative_damping(const Model& model, KernelChoice mode) {
    if (negative_damping(model))
        throw InputError(std::string("--kernels ") + kernel_choice_name(mode) + ": negative Rayleigh damping (alpha = " +
                         std::to_string(model.alpha) + ", beta = " + std::to_string(model.beta) +
                         ", as hsnc modes' extended periodic motion adds) is run by the Eigen solver only "
                         "(--kernels eigen): the kernels' switch bounds assume damping >= 0");
}

bool has_aot_kernels(const Model& model, const AotRegistry* registry) {
    const std::uint64_t hash = model_hash(model);
    return registry && std::any_of(registry->kernels, registry->kernels + registry->count, [&](const hsnc_kernel* k) {
               return k->model_hash == hash && model.name == k->model_name;
           });
}

std::unique_ptr<SolverProvider> make_solver_provider(const Model& model, KernelChoice mode,
                                                     const AotRegistry* registry,
                                                     InterpretedSolverProvider::ProgramFn lower) {
    if (mode == KernelChoice::jit || mode == KernelChoice::tiered)
        throw std::logic_error(std::string("make_solver_provider(): --kernels ") + kernel_choice_name(mode) +
                               (mode == KernelChoice::jit ? " is built with JitSolverProvider"
                                                          : " is built with TieredSolverProvider"));
    if (mode == KernelChoice::eigen) return std::make_unique<GenericSolverProvider>(model);
    refuse_negative_damping(model, mode);
    auto interpreted = [&] {
        return std::make_unique<DerivationFallbackProvider>(model,
                                                            std::make_unique<InterpretedSolverProvider>(std::move(lower)));
    };
    if (mode == KernelChoice::generic || mode == KernelChoice::interp) {
        if (!lower)
            throw std::invalid_argument(std::string("make_solver_provider(): --kernels ") +
                                        kernel_choice_name(mode) +
                                        " needs a program source");
        return interpreted();
    }
    const bool has_kernels = has_aot_kernels(model, registry);
    if (mode == KernelChoice::aot && !has_kernels)
        throw InputError("--kernels aot: no ahead-of-time kernels for model '" + model.name +
                         "' (bundled models only, and only as generated: a --set or an edited file changes the model)");
    if (!has_kernels) {
        if (lower) return interpreted();
        return std::make_unique<GenericSolverProvider>(model);
    }
    return std::make_unique<AotSolverProvider>(model, *registry, mode == KernelChoice::automatic, std::move(lower));
}

}  // namespace hsnc
