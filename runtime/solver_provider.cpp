#include "solver_provider.h"

#include "error.h"
#include "generic_solver.h"

namespace hsnc {

KernelMode parse_kernel_mode(const std::string& name) {
    if (name == "auto") return KernelMode::automatic;
    if (name == "aot") return KernelMode::aot;
    if (name == "generic") return KernelMode::generic;
    throw InputError("--kernels '" + name + "': expected auto, aot or generic");
}

SegmentSolver& GenericSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it == cache_.end()) it = cache_.emplace(cfg, std::make_unique<GenericSolver>(model_, cfg)).first;
    return *it->second;
}

std::string GenericSolverProvider::describe() const {
    return "generic solver for " + std::to_string(cache_.size()) + " configurations";
}

std::unique_ptr<SolverProvider> make_solver_provider(const Model& model, KernelMode mode) {
    if (mode == KernelMode::aot)
        throw InputError("--kernels aot: no ahead-of-time kernels for model '" + model.name + "'");
    return std::make_unique<GenericSolverProvider>(model);
}

}  // namespace hsnc
