// A SegmentSolver that hands every call to another one, for tests that watch
// or change one call of a provider's solvers (derive from it, override that
// call), and the provider that puts it in front of another provider's solvers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment_solver.h"
#include "solver_provider.h"

namespace hsnc::testing {

struct ForwardingSolver : SegmentSolver {
    SegmentSolver* inner = nullptr;
    const Configuration& configuration() const override { return inner->configuration(); }
    const std::vector<SwitchFunction>& switches() const override { return inner->switches(); }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override {
        inner->setup(t0, t0_lo, x0, v0, sgn);
    }
    void eval(double tau, const SegmentEval& out) const override { inner->eval(tau, out); }
    void eval_switches(double tau, const SegmentEval& out) const override { inner->eval_switches(tau, out); }
    void eval_some(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override {
        inner->eval_some(tau, which, count, out);
    }
    void eval_start(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override {
        inner->eval_start(tau, which, count, out);
    }
    double max_step() const override { return inner->max_step(); }
    double* coefficient_block() override { return inner->coefficient_block(); }
    const RestartPlan* restart_plan() const override { return inner->restart_plan(); }
};

/// `inner`'s solvers behind one Solver (a ForwardingSolver).
template <class Solver>
class ForwardingProvider : public SolverProvider {
public:
    explicit ForwardingProvider(SolverProvider& inner) : inner_(inner) {}
    SegmentSolver& solver(const Configuration& cfg) override {
        solver_.inner = &inner_.solver(cfg);
        return solver_;
    }
    const Solver& front() const { return solver_; }
    Solver& front() { return solver_; }

private:
    SolverProvider& inner_;
    Solver solver_;
};

}  // namespace hsnc::testing
