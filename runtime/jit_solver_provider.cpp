#include "jit_solver_provider.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "error.h"
#include "kernel_solver.h"
#include "model_hash.h"

namespace hsnc {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

JitSolverProvider::JitSolverProvider(const Model& model, SourceFn source)
    : model_(model), source_(std::move(source)), hash_(model_hash(model)), jit_(std::make_unique<Jit>()) {}

JitSolverProvider::~JitSolverProvider() = default;

SegmentSolver& JitSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) return *it->second;

    auto start = std::chrono::steady_clock::now();
    const JitKernelSource unit = source_(cfg);
    emit_seconds_ += seconds_since(start);

    start = std::chrono::steady_clock::now();
    jit_->add(unit.symbol + ".cpp", unit.source);
    const auto* kernel = static_cast<const hsnc_kernel*>(jit_->lookup(unit.symbol));
    compile_seconds_ += seconds_since(start);
    ++compiled_;

    // The kernel says what it was built for: it must be this model and configuration.
    if (kernel->abi_version == HSNC_KERNEL_ABI_VERSION &&
        (kernel->model_hash != hash_ || std::strcmp(kernel->config_key, cfg.key().c_str()) != 0))
        throw RunError("JitSolverProvider::solver(): kernel '" + unit.symbol + "' is for configuration '" +
                       kernel->config_key + "', not '" + cfg.key() + "' of model '" + model_.name + "'");
    return *cache_.emplace(cfg, std::make_unique<KernelSolver>(*kernel)).first->second;
}

std::string JitSolverProvider::describe() const {
    char text[200];
    std::snprintf(text, sizeof text,
                  "JIT: %zu configurations visited, %zu kernels compiled (derive+emit %.3f s, compile %.3f s, "
                  "%.1f ms per kernel)",
                  cache_.size(), compiled_, emit_seconds_, compile_seconds_,
                  compiled_ ? 1e3 * compile_seconds_ / static_cast<double>(compiled_) : 0.0);
    return text;
}

}  // namespace hsnc

extern "C" __attribute__((visibility("default"))) hsnc::SolverProvider* hsnc_jit_create_provider(
    const hsnc::Model& model, hsnc::JitSolverProvider::SourceFn source) {
    return new hsnc::JitSolverProvider(model, std::move(source));
}
