// hsnc -- the interpreter of a configuration's Program (kernels/program.h),
// and the SegmentSolver and SolverProvider that run on it.
//
// It executes each instruction as the emitter prints it (generator/emitter.cpp):
// the same operations in the same order, the same libm calls, the same
// helpers of kernel_abi.h, no fma contraction. So it gives the bits of the
// printed kernel, ahead-of-time (GCC) or JIT-compiled (Clang), without a
// compiler: the generic path of the runtime (tests/test_program.cpp holds
// the three to memcmp equality).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "program.h"
#include "segment_solver.h"
#include "solver_provider.h"

namespace hsnc {

class InterpretedSolver : public SegmentSolver {
public:
    explicit InterpretedSolver(Program program);
    ~InterpretedSolver() override;

    const Configuration& configuration() const override { return program_.cfg; }
    const std::vector<SwitchFunction>& switches() const override { return program_.switches; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    double max_step() const override { return program_.max_step; }

    const Program& program() const { return program_; }
    /// The coefficient block the last setup computed (program().n_coef
    /// doubles): what a kernel's setup writes into `coef`.
    const double* coefficients() const { return eval_regs_.data() + Program::kEvalCoef; }

    struct Exec;  // an instruction as run (interpreted_solver.cpp)

private:
    Program program_;
    std::vector<Exec> setup_code_, eval_code_;
    std::vector<double> setup_regs_;
    // eval's register file; setup writes the coefficient block straight into it.
    mutable std::vector<double> eval_regs_;
};

/// One interpreted solver per configuration visited, its program from a
/// callback (the command line's: derive and lower, generator/lowering.h), so
/// that the runtime needs neither GiNaC nor a compiler.
class InterpretedSolverProvider : public SolverProvider {
public:
    using ProgramFn = std::function<Program(const Configuration&)>;
    explicit InterpretedSolverProvider(ProgramFn lower) : lower_(std::move(lower)) {}
    SegmentSolver& solver(const Configuration& cfg) override;
    /// "interpreted programs: 5 configurations (lowering 0.004 s)".
    std::string describe() const override;

private:
    ProgramFn lower_;
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;
    double lower_seconds_ = 0;
};

}  // namespace hsnc
