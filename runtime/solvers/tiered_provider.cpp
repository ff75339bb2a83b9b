#include "tiered_provider.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

#include "error.h"
#include "interpreted_solver.h"

namespace hsnc {

namespace {

// A compiling child's exit status.
constexpr int kCompiled = 0, kFailed = 1, kNotDerivable = 2;

}  // namespace

/// A solver that forwards to another and counts its evaluations.
class TieredSolverProvider::Counted : public SegmentSolver {
public:
    SegmentSolver* inner = nullptr;  // re-set at each entry: the base tier may rebuild its solvers
    mutable std::uint64_t evaluations = 0;

    const Configuration& configuration() const override { return inner->configuration(); }
    const std::vector<SwitchFunction>& switches() const override { return inner->switches(); }
    using SegmentSolver::setup;
    void setup(double t0, double t0_lo, const double* x0, const double* v0, const signed char* sgn) override {
        inner->setup(t0, t0_lo, x0, v0, sgn);
    }
    void eval(double tau, const SegmentEval& out) const override {
        ++evaluations;
        inner->eval(tau, out);
    }
    void eval_switches(double tau, const SegmentEval& out) const override {
        ++evaluations;
        inner->eval_switches(tau, out);
    }
    void eval_some(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override {
        ++evaluations;
        inner->eval_some(tau, which, count, out);
    }
    void eval_start(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override {
        ++evaluations;
        inner->eval_start(tau, which, count, out);
    }
    double max_step() const override { return inner->max_step(); }
    bool splits_bound() const override { return inner->splits_bound(); }
    double* coefficient_block() override { return inner->coefficient_block(); }
    const RestartPlan* restart_plan() const override { return inner->restart_plan(); }
};

namespace {

/// Whether a kernel would search slower than the interpreter: a kernel
/// evaluates everything (2.5-3 times faster than the interpreter's eval), the
/// interpreter's search program only what the switch functions read. Its
/// estimated share of eval's work runs about 0.1 below the measured share of
/// time (0.40 -> 0.50 at 32 masses, 0.15 -> 0.21 at 128), so 0.3 here is
/// about 0.4 of eval's time. A configuration searched by function (16
/// switch functions or more, segment_solver.h kScheduleFrom) computes at most
/// instants a few functions, where a kernel computes all: a 16-mass friction
/// chain over 1000 s ran in 0.39 s interpreted, 0.52 s on warm JIT kernels.
bool search_cheaper_interpreted(const SegmentSolver* s) {
    const auto* in = dynamic_cast<const InterpretedSolver*>(s);
    return in && (in->switch_program_share() < 0.3 || in->has_function_rows());
}

}  // namespace

/// One configuration's tiers: its base-tier solver, and its kernel once it has one.
struct TieredSolverProvider::Tier {
    Counted base, kernel;
    bool queued = false;     // its kernel asked for
    bool stored = false;     // a child compiled it into the cache
    bool on_kernel = false;  // runs on `kernel`
};

TieredSolverProvider::TieredSolverProvider(std::unique_ptr<SolverProvider> base, ProbeFn probe, CompileFn compile,
                                           TierOptions options, std::function<void(const std::string&)> warn)
    : base_(std::move(base)),
      probe_(std::move(probe)),
      compile_(std::move(compile)),
      options_(options),
      warn_(std::move(warn)) {}

void TieredSolverProvider::warn(const std::string& text) const {
    if (warn_)
        warn_(text);
    else
        std::fprintf(stderr, "hsnc: warning: %s\n", text.c_str());
}

TieredSolverProvider::~TieredSolverProvider() {
    if (child_ > 0) {  // never wait for a compiler: stop it
        ::kill(child_, SIGKILL);
        while (::waitpid(child_, nullptr, 0) < 0 && errno == EINTR) {
        }
    }
}

void TieredSolverProvider::start_next() {
    while (child_ < 0 && !queue_.empty()) {
        const Configuration cfg = queue_.front();
        queue_.pop_front();
        const pid_t pid = ::fork();
        if (pid == 0) {
            // The child: compile into the cache, then leave without running the
            // parent's exit handlers or flushing its buffers (_exit).
            int status = kCompiled;
            try {
                compile_(cfg);
            } catch (const NotDerivable&) {
                status = kNotDerivable;
            } catch (...) {
                status = kFailed;
            }
            ::_exit(status);
        }
        if (pid < 0) {
            if (failed_++ == 0)
                warn(std::string("kernels = tiered: cannot start a compile (the configuration stays interpreted): ") +
                     std::strerror(errno));
            continue;
        }
        child_ = pid;
        child_cfg_ = cfg;
        child_start_ = std::chrono::steady_clock::now();
    }
}

void TieredSolverProvider::poll(bool block) {
    if (child_ < 0) return;
    int status = 0;
    pid_t done;
    do {
        done = ::waitpid(child_, &status, block ? 0 : WNOHANG);
    } while (done < 0 && errno == EINTR);
    if (done == 0) return;  // still compiling
    compile_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - child_start_).count();
    const int code = done > 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == kCompiled) {
        ++compiled_;
        tiers_.at(child_cfg_)->stored = true;
    } else if (code != kNotDerivable) {  // not derivable: on the Eigen solver in every tier
        // The configuration stays on the base tier: the same results, at its speed.
        if (failed_++ == 0)
            warn("kernels = tiered: the kernel of configuration '" + child_cfg_.key() +
                 "' could not be compiled into the cache (it stays interpreted; --kernels jit shows why)");
    }
    child_ = -1;
    start_next();
}

bool TieredSolverProvider::take_stored(Tier& t, const Configuration& cfg) {
    if (!t.on_kernel && t.stored) {  // a child has compiled it into the cache: loaded once
        t.stored = false;
        if (SegmentSolver* made = probe_(cfg)) t.kernel.inner = made, t.on_kernel = true;
    }
    return t.on_kernel;
}

SegmentSolver& TieredSolverProvider::solver(const Configuration& cfg) {
    poll(false);
    auto it = tiers_.find(cfg);
    if (it == tiers_.end()) {
        it = tiers_.emplace(cfg, std::make_unique<Tier>()).first;
        Tier& t = *it->second;
        if (probe_)
            if (SegmentSolver* cached = probe_(cfg)) {
                t.kernel.inner = cached;
                t.on_kernel = true;
                ++probed_;
            }
    }
    Tier& t = *it->second;
    if (take_stored(t, cfg)) return t.kernel;
    t.base.inner = &base_->solver(cfg);
    // Three kernels that failed (a cache it cannot write, a compiler missing): stop asking.
    if (!t.queued && t.base.evaluations >= options_.compile_after && compile_ && probe_ && failed_ < 3 &&
        !search_cheaper_interpreted(t.base.inner)) {
        t.queued = true;
        queue_.push_back(cfg);
        start_next();
        if (options_.wait_for_compiles) {
            while (child_ > 0) poll(true);
            if (take_stored(t, cfg)) return t.kernel;
        }
    }
    return t.base;
}

std::size_t TieredSolverProvider::on_kernels() const {
    std::size_t n = 0;
    for (const auto& [cfg, t] : tiers_) n += t->on_kernel;
    return n;
}

std::uint64_t TieredSolverProvider::base_evaluations() const {
    std::uint64_t n = 0;
    for (const auto& [cfg, t] : tiers_) n += t->base.evaluations;
    return n;
}

std::uint64_t TieredSolverProvider::kernel_evaluations() const {
    std::uint64_t n = 0;
    for (const auto& [cfg, t] : tiers_) n += t->kernel.evaluations;
    return n;
}

std::string TieredSolverProvider::describe() const {
    const std::uint64_t b = base_evaluations(), k = kernel_evaluations();
    char text[400];
    std::snprintf(text, sizeof text,
                  "tiered: %zu configurations, %zu on kernels (%zu from the cache at entry, %zu compiled in %.3f s "
                  "by a child process%s%s), %.1f%% of %llu evaluations interpreted; ",
                  tiers_.size(), on_kernels(), probed_, compiled_, compile_seconds_, child_ > 0 ? ", 1 under way" : "",
                  failed_ ? (", " + std::to_string(failed_) + " failed").c_str() : "",
                  b + k ? 100.0 * static_cast<double>(b) / static_cast<double>(b + k) : 100.0,
                  static_cast<unsigned long long>(b + k));
    std::string line = text;
    if (!compile_ || !probe_) line += "no kernel cache: interpreted only; ";
    return line + base_->describe();
}

}  // namespace hsnc
