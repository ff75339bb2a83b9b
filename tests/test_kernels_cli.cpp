// One closed form, printed and interpreted, through the command line: `hsnc
// simulate` with --kernels aot (bundled models), jit and generic (the
// interpreter of each configuration's program; interp is its other name)
// writes byte-identical trajectory and events CSV files, and so does auto,
// with ahead-of-time kernels or without; auto gives the same bytes whether or
// not the JIT module can be loaded, and generic needs no compiler. (The Eigen
// solver, --kernels eigen, an independent implementation, is compared in
// process to tolerances: tests/test_program.cpp, tests/test_kernel_agreement.cpp.)
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "friction_bank.h"
#include "random_model.h"

namespace hsnc {
namespace {

using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

struct Output {
    int exit_code = -1;
    std::string err, trajectory, events;
};

/// `BINARY simulate MODEL ARGS --kernels KIND --out T --events E`, the two files read back.
Output simulate(const std::string& model, const std::string& args, const std::string& kind,
                const std::string& binary = HSNC_BINARY, const std::string& env = "") {
    const std::string traj = temp_path("traj.csv"), ev = temp_path("events.csv");
    const std::string out = temp_path("stdout"), err = temp_path("stderr");
    const std::string command = std::string("XDG_CACHE_HOME='") + HSNC_TEST_CACHE_HOME + "' " + env + " '" + binary +
                                "' simulate '" + model + "' " + args + " --kernels " + kind + " --out '" + traj +
                                "' --events '" + ev + "' >'" + out + "' 2>'" + err + "'";
    const int status = std::system(command.c_str());
    Output o;
    o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    o.err = slurp(err);
    o.trajectory = slurp(traj);
    o.events = slurp(ev);
    for (const std::string& f : {traj, ev, out, err}) std::remove(f.c_str());
    return o;
}

std::size_t rows(const std::string& csv) {
    std::size_t n = 0;
    for (char c : csv) n += c == '\n';
    return n;
}

/// Every kind in `kinds` writes the bytes of the first.
void expect_identical(const std::string& model, const std::string& args, const std::vector<std::string>& kinds,
                      std::size_t min_events) {
    std::vector<Output> outs;
    for (const std::string& k : kinds) {
        outs.push_back(simulate(model, args, k));
        ASSERT_EQ(outs.back().exit_code, 0) << model << " --kernels " << k << ": " << outs.back().err;
    }
    ASSERT_GE(rows(outs[0].events), min_events + 1) << model;
    ASSERT_GT(rows(outs[0].trajectory), 10u) << model;
    for (std::size_t k = 1; k < kinds.size(); ++k) {
        EXPECT_TRUE(outs[k].events == outs[0].events)
            << model << " " << args << ": events CSV, --kernels " << kinds[k] << " vs " << kinds[0] << " ("
            << rows(outs[k].events) << " vs " << rows(outs[0].events) << " lines)";
        EXPECT_TRUE(outs[k].trajectory == outs[0].trajectory)
            << model << " " << args << ": trajectory CSV, --kernels " << kinds[k] << " vs " << kinds[0];
    }
}

TEST(ProgramRun, CliSeedScenario1AotJitGenericAutoWriteIdenticalCsv) {
    expect_identical(model_path("seed-scenario-1.toml"), "--t-end 20 --dt 0.01",
                     {"aot", "jit", "generic", "interp", "auto"}, 100);
}

// Chaotic: one differing bit shows within 300 s (the Eigen solver writes the
// same number of events with other bytes).
TEST(ProgramRun, CliSeedScenario2Over300sAotJitGenericAutoWriteIdenticalCsv) {
    expect_identical(model_path("seed-scenario-2.toml"), "--t-end 300 --dt 0.01", {"aot", "jit", "generic", "auto"},
                     4000);
}

TEST(ProgramRun, CliChain8AotJitGenericAutoWriteIdenticalCsv) {
    expect_identical(model_path("chain-8.toml"), "--t-end 20 --dt 0.01", {"aot", "jit", "generic", "auto"}, 200);
}

// An edited bundled model has no ahead-of-time kernels: auto is generic.
TEST(ProgramRun, CliEditedModelJitGenericAutoWriteIdenticalCsv) {
    expect_identical(model_path("chain-8.toml"), "--t-end 10 --dt 0.01 --set gap=0.011", {"jit", "generic", "auto"},
                     50);
}

// 16 masses on springs of their own, coupled by weaker ones, with friction on
// each, damped and forced: every switch is a reversal, which keeps the one
// configuration, so every segment after the first is carried over the switch
// (runtime/solvers/restart.h): by the interpreter with its program's plan, by
// the compiled kernel (jit, and tiered from the cache) with the plan the
// engine asks for. The same bytes.
TEST(ProgramRun, CliSegmentsCarriedOverSwitchesJitGenericTieredWriteIdenticalCsv) {
    const std::string path = write_temp(
        "friction-bank-16.toml", testing::friction_bank("friction-bank-16", 16, [](int i) { return i == 1 ? 5.0 : 0.0; }, 0.5));
    const Output generic = simulate(path, "--t-end 3 --dt 0.01", "generic");
    ASSERT_EQ(generic.exit_code, 0) << generic.err;
    EXPECT_NE(generic.err.find("204 segments (203 carried over a switch)"), std::string::npos) << generic.err;
    expect_identical(path, "--t-end 3 --dt 0.01", {"generic", "jit", "tiered"}, 150);
    std::remove(path.c_str());
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// tests/random_model.h's model as a model file (every number to 17 digits).
std::string toml(const Model& m) {
    auto body = [&](int b) { return b == kGround ? std::string("ground") : m.masses[b].name; };
    std::string t = "name = \"" + m.name + "\"\n";
    for (std::size_t i = 0; i < m.dof(); ++i) {
        const Mass& ms = m.masses[i];
        const FrictionSlot& f = m.friction_slot(i);
        t += "[[mass]]\nname = \"" + ms.name + "\"\nm = " + number(ms.m) + "\n";
        if (f.active) t += "mu_k = " + number(f.mu_k) + "\nmu_s = " + number(f.mu_s) + "\n";
    }
    for (const Spring& s : m.springs)
        t += "[[spring]]\nbetween = [\"" + body(s.a) + "\", \"" + body(s.b) + "\"]\nk = " + number(s.k) + "\n";
    t += "[damping]\nalpha = " + number(m.alpha) + "\nbeta = " + number(m.beta) + "\n";
    for (const Contact& c : m.contacts)
        t += "[[contact]]\nname = \"" + c.name + "\"\nbetween = [\"" + body(c.a) + "\", \"" + body(c.b) +
             "\"]\ngap = " + number(c.gap) + "\nk = " + number(c.k) + "\n";
    for (const Harmonic& h : m.forcing) {
        t += "[[forcing]]\nomega = " + number(h.omega) + "\nphase = " + number(h.phase) + "\namplitude = {";
        for (std::size_t i = 0; i < h.amplitude.size(); ++i)
            t += (i ? ", " : " ") + m.masses[i].name + " = " + number(h.amplitude[i]);
        t += " }\n";
    }
    auto table = [&](const std::vector<double>& v) {
        std::string s = "{";
        for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : " ") + m.masses[i].name + " = " + number(v[i]);
        return s + " }";
    };
    t += "[load]\n";
    for (std::size_t i = 0; i < m.load.size(); ++i) t += m.masses[i].name + " = " + number(m.load[i]) + "\n";
    t += "[initial]\nt0 = " + number(m.t0) + "\nx = " + table(m.x0) + "\nv = " + table(m.v0) + "\n";
    return t;
}

TEST(ProgramRun, CliRandomModelsJitGenericAutoWriteIdenticalCsv) {
    for (int n : {2, 3, 5, 8}) {
        const testing::Drawn d = testing::draw(900 + static_cast<unsigned>(n), n);
        const std::string path = write_temp("random.toml", toml(d.model));
        const std::string t_end = number(d.model.t0 + 5.0);
        expect_identical(path, "--t-end " + t_end + " --dt 0.01", {"jit", "generic", "auto"}, 1);
        std::remove(path.c_str());
    }
}

// A copy of the hsnc executable alone in a directory: libhsnc_jit.so is
// neither beside it nor in ../lib, so the JIT cannot be loaded.
struct LoneCopy {
    LoneCopy() : dir(temp_path("nojit")), binary(dir + "/bin/hsnc") {
        std::filesystem::create_directories(dir + "/bin");
        std::filesystem::copy_file(HSNC_BINARY, binary);
        ::chmod(binary.c_str(), 0755);
    }
    ~LoneCopy() { std::filesystem::remove_all(dir); }
    std::string dir, binary;
};

// auto never loads the JIT: the same bytes with and without it, on a bundled
// model (ahead-of-time kernels) and on models without kernels (generic, the
// interpreter), and they are the JIT's bytes; generic needs no compiler (and
// no PATH).
TEST(ProgramRun, CliAutoWritesTheSameBytesWhetherOrNotTheJitLoadsAndInterpTheJits) {
    const LoneCopy copy;
    const Output jit = simulate(model_path("seed-scenario-1.toml"), "--t-end 1 --no-cache", "jit", copy.binary);
    EXPECT_EQ(jit.exit_code, 1) << jit.err;
    EXPECT_NE(jit.err.find("JIT module"), std::string::npos) << jit.err;

    const testing::Drawn d = testing::draw(905, 5);
    const std::string random = write_temp("random.toml", toml(d.model));
    const struct {
        std::string model, args;
    } cases[] = {
        {model_path("seed-scenario-2.toml"), "--t-end 300 --dt 0.01"},
        {model_path("chain-8.toml"), "--t-end 10 --dt 0.01 --set gap=0.011"},
        {random, "--t-end " + number(d.model.t0 + 5.0) + " --dt 0.01"},
    };
    for (const auto& c : cases) {
        const Output with = simulate(c.model, c.args, "auto");
        const Output without = simulate(c.model, c.args, "auto", copy.binary);
        ASSERT_EQ(with.exit_code, 0) << with.err;
        ASSERT_EQ(without.exit_code, 0) << without.err;
        EXPECT_GT(rows(with.events), 1u) << c.model;
        EXPECT_TRUE(with.events == without.events) << c.model << ": events CSV, auto with and without the JIT";
        EXPECT_TRUE(with.trajectory == without.trajectory) << c.model << ": trajectory CSV, auto with and without the JIT";
        const Output interp = simulate(c.model, c.args + " --quiet", "generic", copy.binary, "PATH=");
        const Output compiled = simulate(c.model, c.args, "jit");
        EXPECT_EQ(interp.exit_code, 0) << interp.err;
        ASSERT_EQ(compiled.exit_code, 0) << compiled.err;
        EXPECT_TRUE(interp.events == compiled.events) << c.model << ": events CSV, generic without the JIT vs jit";
        EXPECT_TRUE(interp.trajectory == compiled.trajectory) << c.model << ": trajectory CSV, generic vs jit";
        EXPECT_TRUE(without.events == compiled.events) << c.model << ": events CSV, auto without the JIT vs jit";
        EXPECT_TRUE(without.trajectory == compiled.trajectory) << c.model << ": trajectory CSV, auto vs jit";
    }
    std::remove(random.c_str());
}

}  // namespace
}  // namespace hsnc
