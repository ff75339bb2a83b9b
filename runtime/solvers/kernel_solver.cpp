#include "kernel_solver.h"

#include <string>

#include "error.h"

// The kernel ABI's switch kinds are the model's (one list: HSNC_SWITCH_KINDS).
static_assert(HSNC_SWITCH_GAP == static_cast<int>(hsnc::SwitchKind::gap));
static_assert(HSNC_SWITCH_VELOCITY == static_cast<int>(hsnc::SwitchKind::velocity));
static_assert(HSNC_SWITCH_RELEASE_POS == static_cast<int>(hsnc::SwitchKind::release_pos));
static_assert(HSNC_SWITCH_RELEASE_NEG == static_cast<int>(hsnc::SwitchKind::release_neg));
static_assert(HSNC_SWITCH_SLIP_POS == static_cast<int>(hsnc::SwitchKind::slip_pos));
static_assert(HSNC_SWITCH_SLIP_NEG == static_cast<int>(hsnc::SwitchKind::slip_neg));
static_assert(HSNC_SWITCH_SLIP_VELOCITY == static_cast<int>(hsnc::SwitchKind::slip_velocity));
static_assert(HSNC_SWITCH_KINDS_END == hsnc::kSwitchKinds, "a switch kind the kernel ABI does not name");

namespace hsnc {

Configuration configuration_from_key(const char* key) {
    const std::string k = key ? key : "";
    const auto us = k.find("_s");
    if (k.empty() || k[0] != 'c' || us == std::string::npos)
        throw RunError("KernelSolver: '" + k + "' is not a configuration key");
    const auto uj = k.find("_j", us + 2);  // Jenkins elements: 0 stuck, p / n slipping (Configuration::key)
    const std::size_t stuck_end = uj == std::string::npos ? k.size() : uj;
    Configuration cfg;
    for (std::size_t i = 1; i < us; ++i) cfg.closed.push_back(k[i] == '1');
    for (std::size_t i = us + 2; i < stuck_end; ++i) cfg.stuck.push_back(k[i] == '1');
    for (std::size_t i = stuck_end + 2; i < k.size(); ++i)
        cfg.slip.push_back(static_cast<signed char>(k[i] == 'p' ? 1 : k[i] == 'n' ? -1 : 0));
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
    for (int f = 0; f < kernel.n_switch; ++f) {
        const int kind = kernel.switches[f].kind;
        if (kind < 0 || kind >= kSwitchKinds)
            throw RunError("KernelSolver: kernel '" + std::string(kernel.config_key) + "' of model '" +
                           kernel.model_name + "' has switch function " + std::to_string(f) + " of kind " +
                           std::to_string(kind) + ", which this runtime does not know (kinds 0.." +
                           std::to_string(kSwitchKinds - 1) + ")");
        switches_.push_back({static_cast<SwitchKind>(kind), kernel.switches[f].element});
    }
    max_step_ = kernel.max_step;
    configured_ = kernel.n_param == 0;
}

KernelSolver::KernelSolver(const hsnc_kernel& kernel, const std::vector<double>& params) : KernelSolver(kernel) {
    configure(params);
}

void KernelSolver::configure(const std::vector<double>& params) {
    const std::string what = "KernelSolver: kernel '" + std::string(kernel_.config_key) + "' of model '" +
                             kernel_.model_name + "'";
    if (kernel_.n_param == 0 || !kernel_.configure)
        throw RunError(what + " folds every parameter; it takes no parameter values");
    if (params.size() != static_cast<std::size_t>(kernel_.n_param))
        throw RunError(what + " takes " + std::to_string(kernel_.n_param) + " parameter values, got " +
                       std::to_string(params.size()));
    double max_step = 0.0;
    const int rc = kernel_.configure(coef_.data(), params.data(), &max_step);
    if (rc != HSNC_CONFIGURE_OK) {
        configured_ = false;
        std::string values;
        for (int p = 0; p < kernel_.n_param; ++p)
            values += (p ? ", " : "") + std::string(kernel_.param_names[p]) + " = " + std::to_string(params[p]);
        const char* why = rc == HSNC_CONFIGURE_INVALID     ? "the values are not a valid model"
                          : rc == HSNC_CONFIGURE_STRUCTURE ? "a stiffness moved between zero and positive, which "
                                                             "changes the rigid-body modes the kernel was generated for"
                                                           : "the eigen-solver failed";
        throw RunError(what + ": configure(" + values + "): " + why);
    }
    max_step_ = max_step;
    configured_ = true;
}

void KernelSolver::setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) {
    if (!configured_)
        throw RunError("KernelSolver: sweep kernel '" + std::string(kernel_.config_key) + "' of model '" +
                       kernel_.model_name + "' used before a successful configure()");
    kernel_.setup(coef_.data(), t0, t0_lo, x0, v0, sgn);
}

void KernelSolver::eval(double tau, const SegmentEval& out) const {
    kernel_.eval(coef_.data(), tau, out.x, out.v, out.a, out.g, out.dg, out.bound, out.scale);
}

}  // namespace hsnc
