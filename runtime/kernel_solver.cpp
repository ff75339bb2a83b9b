#include "kernel_solver.h"

#include <string>

#include "error.h"

namespace hsnc {

Configuration configuration_from_key(const char* key) {
    const std::string k = key ? key : "";
    const auto us = k.find("_s");
    if (k.empty() || k[0] != 'c' || us == std::string::npos)
        throw RunError("KernelSolver: '" + k + "' is not a configuration key");
    Configuration cfg;
    for (std::size_t i = 1; i < us; ++i) cfg.closed.push_back(k[i] == '1');
    for (std::size_t i = us + 2; i < k.size(); ++i) cfg.stuck.push_back(k[i] == '1');
    return cfg;
}

KernelSolver::KernelSolver(const hsnc_kernel& kernel)
    : kernel_(kernel), cfg_(configuration_from_key(kernel.config_key)),
      coef_(static_cast<std::size_t>(kernel.n_coef > 0 ? kernel.n_coef : 1), 0.0) {
    if (kernel.abi_version != HSNC_KERNEL_ABI_VERSION)
        throw RunError("KernelSolver: kernel '" + std::string(kernel.config_key) + "' of model '" +
                       kernel.model_name + "' has ABI version " + std::to_string(kernel.abi_version) +
                       ", this runtime expects " + std::to_string(HSNC_KERNEL_ABI_VERSION));
    switches_.reserve(static_cast<std::size_t>(kernel.n_switch));
    for (int f = 0; f < kernel.n_switch; ++f)
        switches_.push_back({static_cast<SwitchKind>(kernel.switches[f].kind), kernel.switches[f].element});
}

void KernelSolver::setup(double t0, const double* x0, const double* v0, const signed char* sgn) {
    kernel_.setup(coef_.data(), t0, x0, v0, sgn);
}

void KernelSolver::eval(double tau, const SegmentEval& out) const {
    kernel_.eval(coef_.data(), tau, out.x, out.v, out.a, out.g, out.dg, out.bound, out.scale);
}

}  // namespace hsnc
