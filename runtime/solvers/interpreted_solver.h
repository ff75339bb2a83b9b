// hsnc -- the interpreter of a configuration's Program (kernels/program.h),
// and the SegmentSolver and SolverProvider that run on it: the runtime's
// generic path (--kernels generic, and auto for a model without
// ahead-of-time kernels).
//
// It computes each instruction as the emitter prints it (generator/emitter.cpp):
// the same operations in the same order, the same libm calls, the same
// helpers of kernel_abi.h (a configuration's modes may take their exp, sin
// and cos four lanes at a time there, grouped as it likes: a lane's bits are
// its own), no fma contraction. So it gives the bits of the
// printed kernel, ahead-of-time (GCC) or JIT-compiled (Clang), without a
// compiler (tests/test_program.cpp holds the three to memcmp equality).
//
// What it runs is not the instruction list itself: the constructor schedules
// each program by dependency level and batches the instructions of one level
// that have one shape (linear combinations of as many terms, the states of
// masses over the same modes) into blocks, run a few rows at a time with the
// sums in registers. Every sum is still taken in its own order, so the
// batching changes no bit; it removes the dispatch, loop and branch cost per
// instruction that made the interpreter slower than the Eigen solver.
#pragma once

#include <cstddef>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "program.h"
#include "segment_solver.h"
#include "solver_provider.h"

namespace hsnc {

class InterpretedSolver : public SegmentSolver {
public:
    /// Compiles `program` (taken by value: a program moved in is compiled in
    /// place, without a copy of its terms).
    explicit InterpretedSolver(Program program);
    ~InterpretedSolver() override;

    const Configuration& configuration() const override { return cfg_; }
    const std::vector<SwitchFunction>& switches() const override { return switches_; }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override;
    void eval(double tau, const SegmentEval& out) const override;
    /// Runs only the instructions the switch outputs depend on, when that
    /// leaves out a fifth of eval's work or more (the state of masses no switch
    /// function reads); the same bits as eval() for g, dg, bound and scale.
    void eval_switches(double tau, const SegmentEval& out) const override;
    /// With kScheduleFrom switch functions or more: the modes once, then the
    /// instructions each listed function needs beyond them (the states of the
    /// masses it reads, its sums); the same bits as eval() for the listed
    /// functions' g, dg, bound and scale, the others' left as they were.
    void eval_some(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override;
    /// The common part, the steps of eval that every bound needs beyond it,
    /// then the listed functions' rows, when that leaves out a good part of
    /// eval and at most a quarter of the functions are listed (else
    /// eval_switches(): the 128-mass chain, with many stuck masses' release
    /// functions listed, ran 1.06x slower without that limit).
    void eval_start(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override;
    double max_step() const override { return max_step_; }
    /// Whether eval_some() runs the listed functions' rows alone (else it is eval_switches()).
    bool has_function_rows() const { return static_cast<bool>(common_); }
    /// Whether eval_start() runs the common part and the bounds' steps (else it is eval_switches()).
    bool has_start_steps() const { return !start_steps_.empty(); }
    /// Whether eval_switches() runs a program of its own (else it is eval()).
    bool has_switch_program() const { return static_cast<bool>(switches_body_); }
    /// The share of eval's work (terms summed, libm calls) the search does (1
    /// without a program of its own).
    double switch_program_share() const { return switch_share_; }

    /// The coefficient block the last setup computed (n_coef doubles): what a
    /// kernel's setup writes into `coef`.
    const double* coefficients() const { return eval_regs_.data() + Program::kEvalCoef; }
    double* coefficient_block() override { return eval_regs_.data() + Program::kEvalCoef; }
    /// The program's plan (Program::restart; empty where it cannot restart).
    const RestartPlan* restart_plan() const override { return &plan_; }
    std::size_t n_coef() const { return n_coef_; }

    /// Estimated heap memory of this solver (its compiled programs, constants
    /// and registers), bytes.
    std::size_t memory_bytes() const;

    struct Body;  // a program as run: its steps and their data (interpreted_solver.cpp)
    /// One row of one step of a body (a block runs its rows independently).
    struct RowRef {
        std::uint32_t step, row;
    };

private:
    void switch_outputs(std::size_t f, const SegmentEval& out) const;  // function f's four outputs, from eval's registers
    const double* switch_registers() const;  // eval's g of every function, then dg, bound and scale
    // The listed functions' rows of eval_ (after common_ has run) and their outputs.
    void function_rows(const std::uint32_t* which, std::size_t count, const SegmentEval& out) const;

    Configuration cfg_;
    std::vector<SwitchFunction> switches_;
    double max_step_ = 0;
    int n_dof_ = 0;
    int n_slider_ = 0;
    std::size_t n_coef_ = 0;
    std::vector<double> constants_;
    std::vector<std::uint32_t> setup_coef_;  // setup's registers of coef[k]
    std::vector<std::uint32_t> no_exports_;
    std::unique_ptr<Body> setup_, eval_, switches_body_;  // switches_body_: null when eval_switches() is eval()
    std::vector<std::uint32_t> start_steps_;  // eval_start: eval_'s steps after common_ (none: eval_switches())
    // eval_some: the modes and harmonics once (null: eval_some() is
    // eval_switches()), then function f's rows of eval_, part_rows_[part_at_[f] .. part_at_[f + 1]).
    std::unique_ptr<Body> common_;
    std::vector<RowRef> part_rows_;
    std::vector<std::uint32_t> part_at_;
    double switch_share_ = 1.0;
    RestartPlan plan_;
    std::vector<double> setup_regs_;
    // eval's register file; setup writes the coefficient block straight into it.
    mutable std::vector<double> eval_regs_;
};

/// One interpreted solver per configuration visited, its program from a
/// callback (the facade's: derive and lower, generator/lowering.h), so that
/// the runtime needs neither GiNaC nor a compiler. The solvers are kept in a
/// cache bounded by memory, as GenericSolverProvider's: beyond `max_bytes`
/// the least recently used are dropped (and derived again if the run comes
/// back to them); the solver just returned is never dropped.
class InterpretedSolverProvider : public SolverProvider {
public:
    using ProgramFn = std::function<Program(const Configuration&)>;
    /// Default budget: 64 MB of solver data, as GenericSolverProvider's.
    static constexpr std::size_t kDefaultMaxBytes = std::size_t{64} << 20;

    explicit InterpretedSolverProvider(ProgramFn lower, std::size_t max_bytes = kDefaultMaxBytes)
        : lower_(std::move(lower)), max_bytes_(max_bytes) {}
    SegmentSolver& solver(const Configuration& cfg) override;
    /// "generic solver for 5 configurations (interpreted programs)", with what
    /// was kept and rebuilt when the bound dropped any (no times: a run's
    /// summary is the same every time).
    std::string describe() const override;

    std::size_t cached() const { return cache_.size(); }  ///< solvers kept now
    std::size_t built() const { return built_; }          ///< solvers constructed (rebuilds included)
    std::size_t evicted() const { return evicted_; }      ///< solvers dropped
    std::size_t cached_bytes() const { return bytes_; }   ///< their estimated memory
    double lower_seconds() const { return lower_seconds_; }  ///< spent in the callback and compiling programs

private:
    struct Entry {
        std::unique_ptr<InterpretedSolver> solver;
        std::size_t bytes;
        std::list<Configuration>::iterator lru;  // position in lru_ (front: most recent)
    };
    ProgramFn lower_;
    std::size_t max_bytes_;
    std::map<Configuration, Entry> cache_;
    std::list<Configuration> lru_;
    std::set<Configuration> seen_;
    std::size_t bytes_ = 0, built_ = 0, evicted_ = 0;
    double lower_seconds_ = 0;
};

}  // namespace hsnc
