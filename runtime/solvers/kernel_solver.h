// hsnc -- KernelSolver: a SegmentSolver backed by a generated kernel
// (kernels/kernel_abi.h), ahead-of-time compiled or JIT-compiled.
#pragma once

#include <vector>

#include "kernel_abi.h"
#include "segment_solver.h"

namespace hsnc {

/// Parse a Configuration::key() ("c01_s10") back into flags.
/// Throws RunError when the text is not a key.
Configuration configuration_from_key(const char* key);

class KernelSolver : public SegmentSolver {
public:
    /// Wraps `kernel`, which must outlive the solver. Throws RunError when the
    /// kernel was built for another ABI version.
    explicit KernelSolver(const hsnc_kernel& kernel);
    /// A sweep kernel (kernel.n_param > 0, kernels/kernel_abi.h) configured
    /// with `params` (kernel.param_names order). Throws RunError when the
    /// kernel is folded, the count differs or configure rejects the values.
    KernelSolver(const hsnc_kernel& kernel, const std::vector<double>& params);

    /// Re-configure a sweep kernel with new parameter values (no allocation);
    /// the next setup starts from them. Throws as the constructor does.
    void configure(const std::vector<double>& params);

    const Configuration& configuration() const override { return cfg_; }
    const std::vector<SwitchFunction>& switches() const override { return switches_; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    double max_step() const override { return max_step_; }
    /// A folded kernel's block; null for a sweep kernel (its block starts
    /// with the configured parameters' terms, so it is set up every segment).
    double* coefficient_block() override { return kernel_.n_param == 0 ? coef_.data() : nullptr; }

    const hsnc_kernel& kernel() const { return kernel_; }

private:
    const hsnc_kernel& kernel_;
    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    std::vector<double> coef_;  // written by configure (sweep kernels) and setup, read by eval
    double max_step_ = 0.0;
    bool configured_ = false;
};

}  // namespace hsnc
