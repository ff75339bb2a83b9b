// --kernels tiered (runtime/solvers/tiered_provider.h): configurations start
// on the interpreter and move to their compiled kernels, from the persistent
// cache at a first entry or compiled by a child process once they have run
// enough evaluations. Which tier ran never changes a bit; the run never waits
// for the compiler; a compiler that fails costs the kernel, not the run.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cached_kernel_provider.h"
#include "cli_runner.h"
#include "derivation.h"
#include "emitter.h"
#include "engine_runner.h"
#include "error.h"
#include "ginac_lock.h"
#include "jit_solver_provider.h"
#include "model_reader.h"
#include "tiered_provider.h"

namespace hsnc {
namespace {

using testing::model_path;

JitOptions cache_options(const std::string& dir) {
    JitOptions o;
    o.cache_dir = dir;
    o.warn = [](const std::string&) {};
    return o;
}

JitKernelSource kernel_source(const Model& model, const Configuration& cfg) {
    const auto lock = ginac_lock();
    return JitKernelSource{kernel_symbol(model, cfg), emit_kernel(derive(model, cfg))};
}

/// The tiered provider of `model` over the cache in `dir`: the interpreter,
/// kernels looked up in the cache, `compile` in a child process.
std::unique_ptr<TieredSolverProvider> tiered(const Model& model, const std::string& dir,
                                             TieredSolverProvider::CompileFn compile, TierOptions options,
                                             std::vector<std::string>* warnings = nullptr) {
    auto lookup = std::make_shared<CachedKernelProvider>(
        model, [&model](const Configuration& cfg) { return kernel_source(model, cfg); }, cache_options(dir),
        [](JitSolverProvider::SourceFn, const JitOptions&) -> std::unique_ptr<JitSolverProvider> {
            throw std::logic_error("the lookup never compiles");
        });
    auto base = std::make_unique<DerivationFallbackProvider>(
        model, std::make_unique<InterpretedSolverProvider>(program_source(model)));
    return std::make_unique<TieredSolverProvider>(
        std::move(base), [lookup](const Configuration& cfg) { return lookup->cached(cfg); }, std::move(compile),
        options,
        [warnings](const std::string& w) {
            if (warnings) warnings->push_back(w);
        });
}

/// What a real run's child does: the JIT compiles the kernel into the cache.
TieredSolverProvider::CompileFn jit_compile(const Model& model, const std::string& dir) {
    return [&model, dir](const Configuration& cfg) {
        CachedKernelProvider jit(
            model, [&model](const Configuration& c) { return kernel_source(model, c); }, cache_options(dir),
            [&model](JitSolverProvider::SourceFn source, const JitOptions& o) {
                return std::make_unique<JitSolverProvider>(model, std::move(source), o);
            });
        jit.solver(cfg);
    };
}

testing::Outcome run(const Model& model, SolverProvider& provider, double t_end) {
    return testing::run_engine(model, provider, t_end, t_end / 200);
}

/// Every event and sample the same, to the bit.
void expect_same_bits(const testing::Outcome& a, const testing::Outcome& b) {
    ASSERT_EQ(a.events.size(), b.events.size());
    ASSERT_EQ(a.samples.size(), b.samples.size());
    auto same = [](const testing::Recorded& p, const testing::Recorded& q) {
        return std::memcmp(&p.t, &q.t, sizeof p.t) == 0 && p.kind == q.kind && p.element == q.element &&
               p.x.size() == q.x.size() && p.v.size() == q.v.size() &&
               std::memcmp(p.x.data(), q.x.data(), p.x.size() * sizeof(double)) == 0 &&
               std::memcmp(p.v.data(), q.v.data(), p.v.size() * sizeof(double)) == 0;
    };
    for (std::size_t i = 0; i < a.events.size(); ++i) ASSERT_TRUE(same(a.events[i], b.events[i])) << "event " << i;
    for (std::size_t i = 0; i < a.samples.size(); ++i) ASSERT_TRUE(same(a.samples[i], b.samples[i])) << "sample " << i;
}

TEST(Tiered, KernelsTakeOverWithoutChangingABit) {
    const Model model = read_model(model_path("chain-8.toml"));
    const std::string dir = testing::temp_path("tiered_cache");
    const testing::Outcome interp = testing::simulate(model, 20.0, 0.1, testing::Solvers::interp);

    TierOptions o;
    o.compile_after = 500;  // a few configurations of the 20 earn a kernel
    o.wait_for_compiles = true;
    {
        auto provider = tiered(model, dir, jit_compile(model, dir), o);
        const testing::Outcome first = run(model, *provider, 20.0);
        expect_same_bits(interp, first);
        EXPECT_GE(provider->compiled(), 1u) << provider->describe();
        EXPECT_EQ(provider->on_kernels(), provider->compiled()) << provider->describe();
        EXPECT_EQ(provider->from_cache(), 0u);
        EXPECT_GT(provider->kernel_evaluations(), 0u) << provider->describe();
        EXPECT_NE(provider->describe().find("tiered: "), std::string::npos);
    }
    {  // Again: the kernels compiled before come from the cache at their first entry.
        o.compile_after = 1u << 30;
        auto provider = tiered(model, dir, jit_compile(model, dir), o);
        const testing::Outcome again = run(model, *provider, 20.0);
        expect_same_bits(interp, again);
        EXPECT_GE(provider->from_cache(), 1u) << provider->describe();
        EXPECT_EQ(provider->compiled(), 0u);
    }
    std::filesystem::remove_all(dir);
}

/// A run of `model` on tiered kernels that compile after one evaluation,
/// with a compiler that fails: no kernel may be asked for (no warning), and
/// the run has the interpreter's bits.
void expect_interpreted_throughout(const Model& model, double t_end, std::size_t min_events) {
    const std::string dir = testing::temp_path("tiered_interpreted");
    const testing::Outcome interp = testing::simulate(model, t_end, t_end / 200, testing::Solvers::interp);
    TierOptions o;
    o.compile_after = 1;
    o.wait_for_compiles = true;
    // A compile would run in a child and fail: the run would warn that the
    // kernel could not be compiled into the cache.
    std::vector<std::string> warnings;
    auto provider = tiered(model, dir, [](const Configuration&) { throw RunError("asked for a kernel"); }, o, &warnings);
    const testing::Outcome run_ = run(model, *provider, t_end);
    expect_same_bits(interp, run_);
    EXPECT_GE(interp.events.size(), min_events);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    EXPECT_EQ(provider->on_kernels(), 0u) << provider->describe();
    std::filesystem::remove_all(dir);
}

// A structure whose switch functions read one mass of 64: the interpreter's
// search program (SegmentSolver::eval_switches) does less than a kernel's
// whole eval would, so no kernel is asked for, however long it runs.
TEST(Tiered, AStructureWithFewSwitchesKeepsItsInterpretedSearch) {
    constexpr int n = 64;
    const std::string last = "m" + std::to_string(n);
    std::string text = "name = \"jointed\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i)
        text += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\n" + (i == n ? "mu_k = 0.05\nmu_s = 0.07\n" : "");
    text += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i)
        text += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = 400\n";
    text += "[[contact]]\nbetween = [\"" + last + "\", \"ground\"]\ngap = 0.002\nk = 4000\n";
    text += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0 }\n[initial]\nv = { " + last + " = 0.5 }\n";
    const Model model = parse_model(text, "jointed.toml");
    expect_interpreted_throughout(model, 20.0, 10);
}

// A friction chain of 20 masses: every configuration has a switch function
// per mass, searched by function (kScheduleFrom), where the interpreter
// computes the few functions due and a kernel would compute all of them: no
// kernel is asked for.
TEST(Tiered, ASearchByFunctionKeepsTheInterpreter) {
    std::string text = "name = \"friction-chain\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= 20; ++i) text += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    text += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < 20; ++i)
        text += "[[spring]]\nbetween = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\nk = 400\n";
    text += "[[contact]]\nbetween = [\"m10\", \"m11\"]\ngap = 0.01\nk = 4000\n";
    text += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0, m20 = -20.0 }\n[initial]\nv = { m10 = 1.0 }\n";
    const Model model = parse_model(text, "friction-chain.toml");
    expect_interpreted_throughout(model, 5.0, 100);
}

TEST(Tiered, TheRunNeverWaitsForTheCompiler) {
    const Model model = read_model(model_path("chain-8.toml"));
    const std::string dir = testing::temp_path("tiered_slow");
    TierOptions o;
    o.compile_after = 100;
    const auto start = std::chrono::steady_clock::now();
    {
        // A compiler that takes a minute: the run ends long before it, and the
        // provider stops it rather than wait.
        auto provider = tiered(
            model, dir, [](const Configuration&) { ::sleep(60); }, o);
        const testing::Outcome r = run(model, *provider, 20.0);
        EXPECT_EQ(r.summary.status, RunStatus::ok);
        EXPECT_NE(provider->describe().find("1 under way"), std::string::npos) << provider->describe();
        EXPECT_EQ(provider->on_kernels(), 0u);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 30.0) << "the provider waited for its compiler";
}

TEST(Tiered, AFailingCompilerCostsTheKernelNotTheRun) {
    const Model model = read_model(model_path("chain-8.toml"));
    const std::string dir = testing::temp_path("tiered_fail");
    const testing::Outcome interp = testing::simulate(model, 20.0, 0.1, testing::Solvers::interp);
    TierOptions o;
    o.compile_after = 500;
    o.wait_for_compiles = true;
    for (int crash = 0; crash < 2; ++crash) {
        std::vector<std::string> warnings;
        TieredSolverProvider::CompileFn fail = [](const Configuration&) { throw RunError("no compiler here"); };
        // A compiler that dies (a signal, as a crash; SIGKILL leaves no core file).
        TieredSolverProvider::CompileFn die = [](const Configuration&) { ::raise(SIGKILL); };
        auto provider = tiered(model, dir, crash ? die : fail, o, &warnings);
        const testing::Outcome r = run(model, *provider, 20.0);
        expect_same_bits(interp, r);
        EXPECT_EQ(provider->on_kernels(), 0u);
        ASSERT_EQ(warnings.size(), 1u) << "one warning for every kernel that failed";
        EXPECT_NE(warnings[0].find("stays interpreted"), std::string::npos) << warnings[0];
        EXPECT_NE(provider->describe().find("failed"), std::string::npos) << provider->describe();
    }
}

TEST(TieredCli, WritesTheBytesOfInterpAndAot) {
    const std::string model = "'" + model_path("chain-8.toml") + "'";
    const std::string dir = testing::temp_path("tiered_cli_cache");
    const std::string interp = testing::events_csv(model, "--kernels interp");
    ASSERT_FALSE(interp.empty());
    EXPECT_EQ(testing::events_csv(model, "--kernels aot"), interp);
    EXPECT_EQ(testing::events_csv(model, "--kernels tiered --tier-evaluations 500 --cache-dir '" + dir + "'"), interp);
    // Every kernel in the cache (a jit run fills it): tiered runs on kernels from the first entry.
    const testing::CliRun fill = testing::run_hsnc("simulate " + model + " --kernels jit --cache-dir '" + dir + "'");
    ASSERT_EQ(fill.exit_code, 0) << fill.err;
    const std::string events = testing::temp_path("events.csv");
    const testing::CliRun warm = testing::run_hsnc("simulate " + model + " --kernels tiered --cache-dir '" + dir +
                                                   "' --events '" + events + "'");
    ASSERT_EQ(warm.exit_code, 0) << warm.err;
    EXPECT_EQ(testing::slurp(events), interp);
    EXPECT_NE(warm.err.find("tiered: 20 configurations, 20 on kernels (20 from the cache at entry"), std::string::npos)
        << warm.err;
    EXPECT_NE(warm.err.find("0.0% of"), std::string::npos) << warm.err;
    std::filesystem::remove_all(dir);
    std::remove(events.c_str());
}

TEST(TieredCli, ACacheOthersCanWriteIsNotUsed) {
    // As --kernels jit: a cache directory others can write to is refused, with
    // a warning; tiered then stays on the interpreter (and compiles nothing).
    const std::string model = "'" + model_path("chain-8.toml") + "'";
    const std::string dir = testing::temp_path("tiered_open_cache");
    std::filesystem::create_directory(dir);
    std::filesystem::permissions(dir, std::filesystem::perms::all);
    const std::string events = testing::temp_path("events.csv");
    const testing::CliRun r = testing::run_hsnc("simulate " + model + " --kernels tiered --tier-evaluations 100 " +
                                                "--cache-dir '" + dir + "' --events '" + events + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("world-writable"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("no kernel cache: interpreted only"), std::string::npos) << r.err;
    EXPECT_EQ(testing::slurp(events), testing::events_csv(model, "--kernels interp"));
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    std::filesystem::remove_all(dir);
    std::remove(events.c_str());
}

TEST(TieredCli, RefusesZeroEvaluations) {
    const testing::CliRun r =
        testing::run_hsnc("simulate '" + model_path("chain-8.toml") + "' --kernels tiered --tier-evaluations 0");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--tier-evaluations"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hsnc
