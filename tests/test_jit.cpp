// Kernels compiled in-process (runtime/jit/jit.h, runtime/jit/jit_solver_provider.h):
// the JIT itself, its error path, and a 12-mass run against the generic solver.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "error.h"
#include "jit.h"
#include "jit_solver_provider.h"
#include "kernel_mode.h"
#include "model_reader.h"

namespace hsnc {
namespace {

// A chain of 12 unit masses, ground - m1 - ... - m12 - ground, Coulomb friction
// on every mass (mu_s m g = 14.7 N), three contacts (m3-m4, m8-m9, a stop of m12
// to ground) and a 60 N harmonic force on m1: in 4 s the masses release one by
// one down the chain, stick and release again, and the contacts close and open
// (72 events, 30 configurations).
std::string chain12_toml() {
    std::string t = R"toml(name = "chain-12-test"
description = "12-mass chain with 3 contacts and friction everywhere (tests/test_jit.cpp)"

[parameters]
m = 1.0
k = 100.0
k_c = 1000.0
gap = 0.02
mu_k = 1.0
mu_s = 1.5
alpha = 0.02
beta = 0.0005
F = 60.0
omega = 5.0

[damping]
alpha = "alpha"
beta = "beta"

[[contact]]
name = "c34"
between = ["m3", "m4"]
gap = "gap"
k = "k_c"

[[contact]]
name = "c89"
between = ["m8", "m9"]
gap = "gap"
k = "k_c"

[[contact]]
name = "stop12"
between = ["m12", "ground"]
gap = "gap"
k = "k_c"

[[forcing]]
omega = "omega"
amplitude = { m1 = "F" }
)toml";
    for (int i = 1; i <= 12; ++i)
        t += "\n[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = \"m\"\nmu_k = \"mu_k\"\nmu_s = \"mu_s\"\n";
    for (int i = 0; i <= 12; ++i) {
        const std::string a = i == 0 ? "ground" : "m" + std::to_string(i);
        const std::string b = i == 12 ? "ground" : "m" + std::to_string(i + 1);
        t += "\n[[spring]]\nbetween = [\"" + a + "\", \"" + b + "\"]\nk = \"k\"\n";
    }
    return t;
}

struct Event {
    double t;
    EventKind kind;
    int element;
};

class EventRecorder : public Observer {
public:
    void on_sample(double, const double*, const double*) override {}
    void on_event(double t, EventKind kind, int element, const double*, const double*) override {
        events.push_back({t, kind, element});
    }
    std::vector<Event> events;
};

std::vector<Event> run(const Model& model, SolverProvider& provider, double t_end, RunSummary& summary) {
    Engine engine(model, provider);
    EventRecorder rec;
    EngineOptions opt;
    opt.t_end = t_end;
    summary = engine.run(opt, rec);
    return rec.events;
}

JitSolverProvider::SourceFn emitter_of(const Model& model) {
    return [&model](const Configuration& cfg) {
        return JitKernelSource{kernel_symbol(model, cfg), emit_kernel(derive(model, cfg))};
    };
}

TEST(Jit, CompilesAndRunsAFunction) {
    Jit jit;
    jit.add("twice.cpp", "#include \"kernel_abi.h\"\n"
                         "extern \"C\" double twice(double x) { return 2 * x + 0 * HSNC_KERNEL_ABI_VERSION; }\n");
    auto* twice = reinterpret_cast<double (*)(double)>(jit.lookup("twice"));
    EXPECT_EQ(twice(1.25), 2.5);
}

TEST(Jit, SyntaxErrorGivesClangsDiagnostic) {
    Jit jit;
    try {
        jit.add("broken.cpp", "extern \"C\" int f() { return 1 }\n");
        FAIL() << "a syntax error compiled";
    } catch (const RunError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("Jit::compile(): Clang cannot compile broken.cpp"), std::string::npos) << what;
        EXPECT_NE(what.find("broken.cpp:1:"), std::string::npos) << what;
        EXPECT_NE(what.find("error: expected ';'"), std::string::npos) << what;
    }
}

TEST(Jit, UnknownSymbolIsARunError) {
    Jit jit;
    jit.add("one.cpp", "extern \"C\" int one() { return 1; }\n");
    EXPECT_THROW(jit.lookup("two"), RunError);
}

TEST(Jit, CompiledObjectsAreDeterministicAndReloadable) {
    const std::string source = "extern \"C\" double thrice(double x) { return 3 * x; }\n";
    Jit a, b;
    const std::string object = a.compile("thrice.cpp", source);
    EXPECT_EQ(b.compile("thrice.cpp", source), object) << "the cache relies on equal source -> equal object";
    EXPECT_EQ(object.substr(0, 4), std::string("\x7f" "ELF")) << "a relocatable ELF object";
    // Keys: equal for equal source, different for any other source; 128-bit hex.
    EXPECT_EQ(a.cache_key(source), b.cache_key(source));
    EXPECT_NE(a.cache_key(source), a.cache_key(source + " "));
    EXPECT_EQ(a.cache_key(source).size(), 32u);
    // Garbage, or a cut object, is refused before the JIT owns it, and the JIT
    // still takes the real object afterwards.
    EXPECT_THROW(b.add_object("thrice", "not an object file at all"), RunError);
    EXPECT_THROW(b.add_object("thrice", object.substr(0, object.size() / 3)), RunError);
    b.add_object("thrice", object);
    auto* thrice = reinterpret_cast<double (*)(double)>(b.lookup("thrice"));
    EXPECT_EQ(thrice(1.5), 4.5);
}

TEST(JitSolverProvider, Chain12AgreesWithGenericSolver) {
    const Model model = parse_model(chain12_toml(), "chain-12-test.toml");
    const double t_end = 4.0;

    GenericSolverProvider generic(model);
    RunSummary gsum;
    const std::vector<Event> expected = run(model, generic, t_end, gsum);

    JitSolverProvider jit(model, emitter_of(model));
    RunSummary jsum;
    const std::vector<Event> got = run(model, jit, t_end, jsum);

    ASSERT_EQ(gsum.status, RunStatus::ok) << gsum.message;
    ASSERT_EQ(jsum.status, RunStatus::ok) << jsum.message;
    ASSERT_GE(expected.size(), 10u) << "the horizon should hold several events";
    ASSERT_EQ(got.size(), expected.size());
    bool contact = false, stick = false;
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].kind, expected[i].kind) << "event " << i;
        EXPECT_EQ(got[i].element, expected[i].element) << "event " << i;
        EXPECT_NEAR(got[i].t, expected[i].t, 1e-9 * std::fabs(expected[i].t)) << "event " << i;
        contact |= expected[i].kind == EventKind::contact_close;
        stick |= expected[i].kind == EventKind::stick;
    }
    EXPECT_TRUE(contact && stick) << "the run should close contacts and stick masses";
    for (std::size_t i = 0; i < model.dof(); ++i) EXPECT_NEAR(jsum.x[i], gsum.x[i], 1e-9) << "x of mass " << i;

    // Only the configurations visited are compiled, each once.
    EXPECT_GT(jit.configurations(), 1u);
    EXPECT_EQ(jit.configurations(), jsum.configurations);
    EXPECT_EQ(jit.kernels_compiled(), jit.configurations());
    EXPECT_GT(jit.compile_seconds(), 0.0);
    EXPECT_NE(jit.describe().find(std::to_string(jit.kernels_compiled()) + " kernels compiled"), std::string::npos)
        << jit.describe();
    std::printf("[ jit      ] %s\n", jit.describe().c_str());
}

TEST(JitSolverProvider, KernelThatDoesNotCompileIsARunError) {
    const Model model = parse_model(chain12_toml(), "chain-12-test.toml");
    JitSolverProvider jit(model, [](const Configuration&) {
        return JitKernelSource{"hsnc_kernel_broken", "#include \"kernel_abi.h\"\nint x = ;\n"};
    });
    try {
        jit.solver(Configuration::all_open(model));
        FAIL() << "a broken kernel compiled";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("error: expected expression"), std::string::npos) << e.what();
    }
}

TEST(SimulateCli, KernelsJitOnANonBundledModel) {
    const std::string path = testing::write_temp("chain12.toml", chain12_toml());
    const testing::CliRun r = testing::run_hsnc("simulate '" + path + "' --t-end 1 --kernels jit");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("status=ok method=hsnc t=1 "), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("kernels compiled"), std::string::npos) << r.err;
    const testing::CliRun bad = testing::run_hsnc("simulate '" + path + "' --t-end 1 --kernels jot");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("expected auto, aot, generic, interp, eigen, jit or tiered"), std::string::npos) << bad.err;
    std::remove(path.c_str());
}

}  // namespace
}  // namespace hsnc
