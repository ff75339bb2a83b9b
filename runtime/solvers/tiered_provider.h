// hsnc -- TieredSolverProvider: a run that never waits for a compiler
// (--kernels tiered).
//
// Every configuration starts on the base tier (the interpreter: each
// configuration's program, the bits of the printed kernels), unless the
// persistent kernel cache already holds its kernel (`probe`, which never
// compiles): then it runs on that kernel from its first entry. A
// configuration that has run `compile_after` evaluations on the base tier has
// earned a kernel: a child process compiles it into the cache (`compile`,
// one child at a time, so the run keeps its own core), and the next time the
// run enters that configuration after the child is done, it runs on the
// kernel. Since the interpreter and the compiled kernels give the same bits
// (tests/test_program.cpp), which tier ran a segment never changes a result;
// only the time does.
//
// The run never waits for the compiler: at the end a compile under way is
// stopped (its child killed; the cache drops what a killed writer leaves),
// and a short run compiles nothing, since no configuration reaches
// `compile_after`. A compiler that fails or crashes costs its configuration
// the kernel, never the run. The child is a fork() of the run: a caller
// with other threads should know that only the forking thread lives on in
// it (a lock another thread held is never released there: that child's
// kernel is lost, and it is killed at the end).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "solver_provider.h"

namespace hsnc {

struct TierOptions {
    /// Evaluations a configuration runs on the base tier before its kernel is
    /// compiled. The compile runs on another core, so it need not be won back
    /// on the run's own; the threshold keeps short runs from compiling at all.
    /// (What a kernel saves: 0.75 us an evaluation on the 32-mass chain, 0.2
    /// us on chain-8, build/hsnc_program_bench; its compile: 0.4-6 s and 0.17 s,
    /// so on one core it would pay after 0.5-8 and about 0.9 million.)
    std::uint64_t compile_after = 200000;
    /// Tests: solver() waits for a compile it has just started, so that the
    /// switch of tier happens at a known entry. Runs never set it.
    bool wait_for_compiles = false;
};

class TieredSolverProvider : public SolverProvider {
public:
    /// The kernel of a configuration from the persistent cache, or null
    /// (never compiles).
    using ProbeFn = std::function<SegmentSolver*(const Configuration&)>;
    /// Compiles the kernel of a configuration into the persistent cache, in a
    /// child process; throws on failure (NotDerivable: the configuration runs
    /// on the Eigen solver in every tier).
    using CompileFn = std::function<void(const Configuration&)>;

    /// Without `probe` or `compile` the run stays on the base tier. `warn`
    /// gets one line per problem (empty: "hsnc: warning: ..." on stderr).
    TieredSolverProvider(std::unique_ptr<SolverProvider> base, ProbeFn probe, CompileFn compile,
                         TierOptions options = {}, std::function<void(const std::string&)> warn = {});
    ~TieredSolverProvider() override;
    TieredSolverProvider(const TieredSolverProvider&) = delete;
    TieredSolverProvider& operator=(const TieredSolverProvider&) = delete;

    SegmentSolver& solver(const Configuration& cfg) override;

    /// "tiered: 80 configurations, 2 on kernels (1 from the cache at entry, 1
    /// compiled in 0.41 s by a child process), 97.1% of 8000 evaluations
    /// interpreted; " and the base tier's line.
    std::string describe() const override;

    std::size_t configurations() const { return tiers_.size(); }
    std::size_t on_kernels() const;                     ///< configurations that run on a kernel
    std::size_t compiled() const { return compiled_; }  ///< kernels a child compiled
    std::size_t from_cache() const { return probed_; }  ///< kernels the cache had at a first entry
    std::uint64_t base_evaluations() const;             ///< solver evaluations (samples' too) per tier
    std::uint64_t kernel_evaluations() const;

    class Counted;  // a solver that counts its evaluations (tiered_provider.cpp)

private:
    struct Tier;
    void start_next();
    void warn(const std::string& text) const;
    /// Whether `t` runs on its kernel, after loading the one a child stored.
    bool take_stored(Tier& t, const Configuration& cfg);
    void poll(bool block);

    std::unique_ptr<SolverProvider> base_;
    ProbeFn probe_;
    CompileFn compile_;
    TierOptions options_;
    std::function<void(const std::string&)> warn_;
    std::map<Configuration, std::unique_ptr<Tier>> tiers_;
    std::size_t probed_ = 0, compiled_ = 0, failed_ = 0;
    double compile_seconds_ = 0;
    std::deque<Configuration> queue_;
    pid_t child_ = -1;  // the compile under way, if any
    Configuration child_cfg_;
    std::chrono::steady_clock::time_point child_start_;
};

}  // namespace hsnc
