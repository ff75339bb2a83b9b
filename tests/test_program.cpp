// One closed form, printed and interpreted: the Program of a configuration
// (kernels/program.h, generator/lowering.h) printed as C++ and compiled by GCC
// ahead of time or by Clang in process, and run by the interpreter
// (runtime/solvers/interpreted_solver.h), gives the same bits -- every output of
// setup and eval compared with memcmp, whole runs compared as CSV bytes. The
// generic (Eigen) solver is an independent implementation: it agrees to a
// tolerance, not to the bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

#include "aot_registry.h"
#include "csv_writer.h"
#include "derivation.h"
#include "emitter.h"
#include "engine.h"
#include "error.h"
#include "forwarding_solver.h"
#include "generic_solver.h"
#include "interpreted_solver.h"
#include "jit.h"
#include "jit_solver_provider.h"
#include "kernel_mode.h"
#include "kernel_set.h"
#include "kernel_solver.h"
#include "lowering.h"
#include "model_hash.h"
#include "model_reader.h"
#include "random_model.h"
#include "sample_models.h"
#include "segment_start.h"

namespace hsnc {
const AotRegistry& sample_registry();  // tests' build-time kernels (hsnc_gen --samples)

namespace {

const char* const kBundled[] = {"bilinear-1dof", "chain-8", "coulomb-1dof", "seed-scenario-1", "seed-scenario-2"};

Model bundled(const std::string& stem) { return read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + stem + ".toml"); }

/// Everything setup and eval write, for one segment at a few instants.
struct Trace {
    std::vector<double> coef;
    std::vector<double> out;  // x, v, a, g, dg, bound, scale at each tau, concatenated
};

const double kTaus[] = {0.0, 1e-9, 1e-3, 0.07, 0.4, 1.1, 2.5, 17.0};

using testing::Start;
using testing::start_of;

// n masses, nx = n + the sliders (x's length), ns switch functions.
template <class Setup, class Eval>
Trace trace(std::size_t n_coef, std::size_t n, std::size_t nx, std::size_t ns, const Start& s, Setup setup, Eval eval) {
    Trace t;
    t.coef.assign(n_coef, 0.0);
    setup(t.coef.data(), s);
    const std::size_t per = nx + 2 * n + 4 * ns;
    t.out.assign(per * (sizeof kTaus / sizeof kTaus[0]), 0.0);
    double* o = t.out.data();
    for (double tau : kTaus) {
        double* g = o + nx + 2 * n;
        eval(t.coef.data(), tau, SegmentEval{o, o + nx, o + nx + n, g, g + ns, g + 2 * ns, g + 3 * ns});
        o += per;
    }
    return t;
}

Trace kernel_trace(const hsnc_kernel& k, const Start& s) {
    return trace(
        static_cast<std::size_t>(k.n_coef), static_cast<std::size_t>(k.n_dof),
        static_cast<std::size_t>(k.n_dof + k.n_slider), static_cast<std::size_t>(k.n_switch), s, [&](double* coef, const Start& st) { k.setup(coef, st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data()); },
        [&](const double* coef, double tau, const SegmentEval& o) {
            k.eval(coef, tau, o.x, o.v, o.a, o.g, o.dg, o.bound, o.scale);
        });
}

Trace program_trace(const Program& p, const Start& s) {
    auto ip = std::make_shared<InterpretedSolver>(p);
    return trace(
        static_cast<std::size_t>(p.n_coef), static_cast<std::size_t>(p.n_dof), static_cast<std::size_t>(p.n_state()),
        p.n_switch(), s,
        [&](double* coef, const Start& st) {
            ip->setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
            if (p.n_coef) std::memcpy(coef, ip->coefficients(), static_cast<std::size_t>(p.n_coef) * sizeof(double));
        },
        [&](const double*, double tau, const SegmentEval& o) { ip->eval(tau, o); });
}

/// memcmp equality, and where it fails the first differing double.
::testing::AssertionResult same_bits(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " != " << b.size();
    if (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0)
        return ::testing::AssertionSuccess();
    for (std::size_t i = 0; i < a.size(); ++i)
        if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) {
            char buf[128];
            std::snprintf(buf, sizeof buf, "element %zu: %.17g != %.17g", i, a[i], b[i]);
            return ::testing::AssertionFailure() << buf;
        }
    return ::testing::AssertionFailure() << "memcmp differs";
}

void expect_identical(const Trace& a, const Trace& b, const std::string& what) {
    EXPECT_TRUE(same_bits(a.coef, b.coef)) << what << ": coefficient blocks";
    EXPECT_TRUE(same_bits(a.out, b.out)) << what << ": eval outputs";
}

// glibc computes sincos with the code of sin and cos: a compiler that merges
// sin(x) and cos(x) into one sincos call (GCC does, at -O2) changes no bit.
// The printed kernels and the interpreter rely on it; called through
// volatile pointers so that nothing here is merged.
TEST(Program, LibmSincosEqualsSinAndCos) {
    double (*volatile fsin)(double) = &::sin;
    double (*volatile fcos)(double) = &::cos;
    void (*volatile fsincos)(double, double*, double*) = &::sincos;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int differ = 0;
    for (int k = 0; k < 200000; ++k) {
        const double x = u(rng) * std::pow(10.0, (k % 24) - 8);
        double s, c;
        fsincos(x, &s, &c);
        const double s1 = fsin(x), c1 = fcos(x);
        differ += std::memcmp(&s, &s1, sizeof s) != 0 || std::memcmp(&c, &c1, sizeof c) != 0;
    }
    EXPECT_EQ(differ, 0);
}

// Every configuration each bundled model has kernels for (its manifest): the
// AOT kernel (GCC), the same kernel compiled by the JIT (Clang) and the
// interpreter of the program it was printed from.
TEST(Program, BundledModelsAotJitAndInterpreterAreBitIdentical) {
    std::size_t checked = 0;
    for (const char* stem : kBundled) {
        const Model m = bundled(stem);
        std::string note;
        const std::vector<Configuration> cfgs = configurations_to_generate(m, &note);
        Jit jit;
        jit.add(std::string(stem) + ".cpp", combined_source(generate_kernel_set(m)));
        for (const Configuration& cfg : cfgs) {
            const std::string what = std::string(stem) + " " + cfg.spec(m);
            const hsnc_kernel* aot = find_aot_kernel(aot_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
            ASSERT_NE(aot, nullptr) << what << ": no AOT kernel";
            const auto* jk = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, cfg)));
            const Program p = lower(derive(m, cfg));
            ASSERT_EQ(p.n_coef, aot->n_coef) << what;
            for (unsigned seed = 1; seed <= 3; ++seed) {
                const Start s = start_of(m, cfg, seed);
                const Trace ta = kernel_trace(*aot, s), tj = kernel_trace(*jk, s), ti = program_trace(p, s);
                expect_identical(ta, ti, what + ": AOT vs interpreter");
                expect_identical(tj, ti, what + ": JIT vs interpreter");
                ++checked;
            }
        }
    }
    EXPECT_GE(checked, 3u * 50u);
}

// The kernel ABI names every switch kind of the model (kernel_solver.cpp
// static_asserts the values); a kernel that reports a kind past them is
// refused by name instead of being cast into a SwitchKind no rule knows.
TEST(Program, AKernelWithAnUnknownSwitchKindIsRefused) {
    const Model m = bundled("chain-8");
    const Configuration cfg = Configuration::all_open(m);
    const hsnc_kernel* aot = find_aot_kernel(aot_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
    ASSERT_NE(aot, nullptr);
    ASSERT_GE(aot->n_switch, 1);
    EXPECT_NO_THROW(KernelSolver{*aot});
    std::vector<hsnc_switch> switches(aot->switches, aot->switches + aot->n_switch);
    switches.back().kind = HSNC_SWITCH_KINDS_END;
    hsnc_kernel bad = *aot;
    bad.switches = switches.data();
    try {
        KernelSolver solver(bad);
        ADD_FAILURE() << "a switch kind past the ABI's was taken";
    } catch (const RunError& e) {
        EXPECT_NE(std::string(e.what()).find("of kind 7, which this runtime does not know"), std::string::npos)
            << e.what();
    }
    static_assert(HSNC_SWITCH_SLIP_VELOCITY == static_cast<int>(SwitchKind::slip_velocity));
}

// The sample catalogue (generator/sample_models.h) has every regime and
// resonance (its kernels are compiled by GCC at build time): every
// configuration of every sample, AOT against the interpreter.
TEST(Program, SampleModelsEveryRegimeAotAndInterpreterAreBitIdentical) {
    std::size_t checked = 0;
    bool regimes[6] = {};
    for (const Model& m : sample_models()) {
        for (const Configuration& cfg : all_configurations(m)) {
            const hsnc_kernel* k = find_aot_kernel(sample_registry(), m.name.c_str(), model_hash(m), cfg.key().c_str());
            if (!k) continue;
            const Program p = lower(derive(m, cfg));
            for (const ProgramInstr& in : p.eval.code)
                if (in.op == ProgramOp::mode) regimes[in.regime] = true;
            const Start s = start_of(m, cfg, 11);
            expect_identical(kernel_trace(*k, s), program_trace(p, s), m.name + " " + cfg.spec(m));
            ++checked;
        }
    }
    EXPECT_GE(checked, 20u);
    for (int r = 0; r < 6; ++r) EXPECT_TRUE(regimes[r]) << "regime " << r << " not covered";
}

// A program lowered without names (ProgramNames::no: the interpreter's) is the
// printed one's instructions, terms and constants, bit for bit, with no
// register names and every slot name, comment and note empty: what the
// printer alone reads.
TEST(Program, WithoutNamesItIsThePrintedProgram) {
    auto same_body = [](const ProgramBody& a, const ProgramBody& b, const std::string& what) {
        ASSERT_EQ(a.code.size(), b.code.size()) << what;
        ASSERT_EQ(a.registers(), b.registers()) << what;
        EXPECT_TRUE(a.kinds == b.kinds) << what;
        for (std::size_t i = 0; i < a.code.size(); ++i) {
            const ProgramInstr &x = a.code[i], &y = b.code[i];
            EXPECT_TRUE(x.op == y.op && x.regime == y.regime && x.accumulates == y.accumulates && x.dst == y.dst &&
                        x.a == y.a && x.b == y.b && x.c == y.c && x.d == y.d && x.first == y.first &&
                        x.count == y.count && std::equal(x.tail, x.tail + 5, y.tail))
                << what << " instruction " << i;
            EXPECT_EQ(y.text, kNoText) << what << " instruction " << i;
        }
        EXPECT_TRUE(b.names.empty() && b.texts.empty()) << what;
        EXPECT_EQ(a.names.size(), a.registers()) << what;
    };
    std::size_t checked = 0, named = 0;
    auto check = [&](const Model& m, const Configuration& cfg) {
        const std::string what = m.name + " " + cfg.spec(m);
        const Derivation d = derive(m, cfg);
        const Program a = lower(d), b = lower(d, ProgramNames::no);
        ASSERT_EQ(a.constants.size(), b.constants.size()) << what;
        EXPECT_EQ(std::memcmp(a.constants.data(), b.constants.data(), sizeof(double) * a.constants.size()), 0) << what;
        ASSERT_EQ(a.terms.size(), b.terms.size()) << what;
        for (std::size_t t = 0; t < a.terms.size(); ++t)
            EXPECT_TRUE(std::memcmp(&a.terms[t].c, &b.terms[t].c, sizeof(double)) == 0 && a.terms[t].reg == b.terms[t].reg)
                << what << " term " << t;
        EXPECT_EQ(a.n_coef, b.n_coef) << what;
        EXPECT_TRUE(a.setup_coef == b.setup_coef) << what;
        EXPECT_EQ(a.coef_names.size(), b.coef_names.size()) << what;
        for (const std::string& name : b.coef_names) EXPECT_TRUE(name.empty()) << what;
        same_body(a.setup, b.setup, what + " setup");
        same_body(a.eval, b.eval, what + " eval");
        for (const std::string& name : a.eval.names) named += !name.empty();
        ++checked;
    };
    for (int n = 1; n <= 8; ++n)
        for (unsigned seed = 300 * n; seed < 300 * n + 3; ++seed) {
            const testing::Drawn dr = testing::draw(seed, n);
            check(dr.model, dr.cfg);
        }
    for (const Model& m : sample_models())
        for (const Configuration& cfg : all_configurations(m)) check(m, cfg);
    EXPECT_GE(checked, 40u);
    EXPECT_GT(named, 0u);  // the printed programs do have names
}

// Random models of 1 to 8 masses (tests/random_model.h), each in a random
// configuration: the JIT-compiled kernel against the interpreter.
TEST(Program, RandomModelsJitAndInterpreterAreBitIdentical) {
    for (int n = 1; n <= 8; ++n) {
        for (unsigned seed = 100 * n; seed < 100 * n + 3; ++seed) {
            const testing::Drawn d = testing::draw(seed, n);
            const Model& m = d.model;
            const Derivation der = derive(m, d.cfg);
            const Program p = lower(der);
            Jit jit;
            jit.add(m.name, emit_kernel(der, p));
            const auto* k = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, d.cfg)));
            const Start s = start_of(m, d.cfg, seed);
            expect_identical(kernel_trace(*k, s), program_trace(p, s), m.name + " " + d.cfg.spec(m));
        }
    }
}

// Chains of frictions (a body with a friction of its own carrying others):
// every configuration of examples/friction/friction_tower.toml (16, a body
// held or riding up to two levels) is derived, its program against the
// textbook closed form GiNaC builds (symbolic_segment, 40 digits: the
// motion, and every switch function with the held forces of the chain),
// and its JIT-compiled kernel bit-identical to the interpreter.
TEST(Program, AFrictionTowerIsDerivedAndJitAndInterpreterAreBitIdenticalInEveryConfiguration) {
    const Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/friction/friction_tower.toml");
    ASSERT_TRUE(m.friction_chain());
    const std::vector<Configuration> cfgs = all_configurations(m);
    ASSERT_EQ(cfgs.size(), 16u);
    std::size_t riders = 0, compared = 0;
    for (const Configuration& cfg : cfgs) {
        const Derivation der = derive(m, cfg);
        riders += der.riders.size();
        const Program p = lower(der);
        Jit jit;
        jit.add(m.name, emit_kernel(der, p));
        const auto* k = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, cfg)));
        ASSERT_NE(k, nullptr) << cfg.spec(m);
        for (unsigned seed = 1; seed <= 2; ++seed) {
            const Start s = start_of(m, cfg, seed);
            expect_identical(kernel_trace(*k, s), program_trace(p, s), m.name + " " + cfg.spec(m));
        }
        const Start s = start_of(m, cfg, 3);
        SegmentInputs in;
        in.t0 = exact(s.t0);  // t0_lo is below the closed form's reach here: compared without it
        for (std::size_t i = 0; i < m.dof(); ++i)
            in.x0.push_back(exact(s.x0[i])), in.v0.push_back(exact(s.v0[i])),
                in.sgn.push_back(static_cast<int>(s.sgn[i]));
        GiNaC::symbol tau("tau");
        const SymbolicSegment sym = symbolic_segment(der, in, tau);
        InterpretedSolver ip(p);
        ip.setup(s.t0, 0.0, s.x0.data(), s.v0.data(), s.sgn.data());
        const std::size_t n = m.dof(), ns = der.switches.size();
        std::vector<double> x(n), v(n), a(n), g(ns), dg(ns), bound(ns), scale(ns);
        for (const double t : {0.0, 0.05, 0.4, 1.3}) {
            ip.eval(t, {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()});
            auto at = [&](const GiNaC::ex& e) {
                return GiNaC::ex_to<GiNaC::numeric>(e.subs(tau == exact(t)).evalf()).to_double();
            };
            const std::string where = cfg.spec(m) + " tau=" + std::to_string(t);
            for (std::size_t i = 0; i < n; ++i) {
                EXPECT_NEAR(x[i], at(sym.x[i]), 1e-13) << where << " x" << i;
                EXPECT_NEAR(v[i], at(sym.v[i]), 1e-12) << where << " v" << i;
            }
            for (std::size_t f = 0; f < ns; ++f) {
                EXPECT_NEAR(g[f], at(sym.g[f]), 1e-13 * scale[f]) << where << " g" << f;
                ++compared;
            }
        }
    }
    EXPECT_GT(riders, 8u) << "configurations with a body riding another up the chain";
    EXPECT_GT(compared, 100u);
}

// Jenkins elements: the sliders are inputs of setup (stuck: their preload)
// and outputs of eval. Every configuration of both bundled examples (3 and 9),
// the JIT-compiled kernel set against the interpreter.
Model jenkins_example(const std::string& stem) {
    return read_model(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/" + stem + ".toml");
}

TEST(Program, JenkinsExamplesJitAndInterpreterAreBitIdenticalInEveryConfiguration) {
    std::size_t checked = 0;
    for (const char* stem : {"friction_damper", "under_platform_damper"}) {
        const Model m = jenkins_example(stem);
        Jit jit;
        jit.add(std::string(stem) + ".cpp", combined_source(generate_kernel_set(m)));
        const std::vector<Configuration> cfgs = all_configurations(m);
        ASSERT_EQ(configurations_to_generate(m, nullptr).size(), cfgs.size()) << stem;
        for (const Configuration& cfg : cfgs) {
            const auto* jk = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, cfg)));
            ASSERT_NE(jk, nullptr) << stem << " " << cfg.spec(m);
            EXPECT_EQ(jk->n_slider, static_cast<int>(m.jenkins.size()));
            const Program p = lower(derive(m, cfg));
            for (unsigned seed = 1; seed <= 3; ++seed) {
                const Start s = start_of(m, cfg, seed);
                expect_identical(kernel_trace(*jk, s), program_trace(p, s), std::string(stem) + " " + cfg.spec(m));
                ++checked;
            }
        }
    }
    EXPECT_EQ(checked, 3u * (3u + 9u));
}

// ---- whole runs ----

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct RunFiles {
    RunSummary summary;
    std::string trajectory, events;
};

RunFiles run_to_csv(const Model& m, SolverProvider& provider, double t_end, double dt, const std::string& tag) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::string base = (dir / ("hsnc_test_program_" + std::to_string(::getpid()) + "_" + tag)).string();
    RunFiles r;
    {
        CsvFile traj(base + ".traj.csv"), ev(base + ".events.csv");
        traj.text(trajectory_header(m).c_str());
        traj.end_row();
        ev.text(events_header(m).c_str());
        ev.end_row();
        CsvObserver obs(m, &traj, &ev);
        Engine engine(m, provider);
        EngineOptions opt;
        opt.t_end = t_end;
        opt.dt = dt;
        r.summary = engine.run(opt, obs);
        traj.commit();
        ev.commit();
    }
    r.trajectory = slurp(base + ".traj.csv");
    r.events = slurp(base + ".events.csv");
    std::remove((base + ".traj.csv").c_str());
    std::remove((base + ".events.csv").c_str());
    return r;
}

InterpretedSolverProvider::ProgramFn lowering_of(const Model& m) {
    return [&m](const Configuration& cfg) { return lower(derive(m, cfg)); };
}
JitSolverProvider::SourceFn emitter_of(const Model& m) {
    return [&m](const Configuration& cfg) { return JitKernelSource{kernel_symbol(m, cfg), emit_kernel(derive(m, cfg))}; };
}

void expect_same_runs(const Model& m, double t_end, double dt, bool with_aot, std::size_t min_events) {
    InterpretedSolverProvider interp(lowering_of(m));
    const RunFiles ri = run_to_csv(m, interp, t_end, dt, "interp");
    JitSolverProvider jit(m, emitter_of(m));
    const RunFiles rj = run_to_csv(m, jit, t_end, dt, "jit");
    ASSERT_EQ(ri.summary.status, RunStatus::ok) << m.name << ": " << ri.summary.message;
    EXPECT_GE(ri.summary.events, min_events) << m.name;
    EXPECT_EQ(ri.summary.events, rj.summary.events) << m.name;
    EXPECT_TRUE(ri.events == rj.events) << m.name << ": events CSV, interpreter vs JIT";
    EXPECT_TRUE(ri.trajectory == rj.trajectory) << m.name << ": trajectory CSV, interpreter vs JIT";
    if (with_aot) {
        AotSolverProvider aot(m, aot_registry(), /*fallback=*/false);
        const RunFiles ra = run_to_csv(m, aot, t_end, dt, "aot");
        EXPECT_EQ(ri.summary.events, ra.summary.events) << m.name;
        EXPECT_TRUE(ri.events == ra.events) << m.name << ": events CSV, interpreter vs AOT";
        EXPECT_TRUE(ri.trajectory == ra.trajectory) << m.name << ": trajectory CSV, interpreter vs AOT";
    }
}

TEST(ProgramRun, SeedScenario1AotJitInterpreterWriteIdenticalCsv) {
    expect_same_runs(bundled("seed-scenario-1"), 20.0, 0.01, true, 50);
}

// Chaotic: a single differing bit would show within the 300 s (issue 12: AOT
// and JIT gave 4180 switches and the generic solver 4181).
TEST(ProgramRun, SeedScenario2Over300sAotJitInterpreterWriteIdenticalCsv) {
    expect_same_runs(bundled("seed-scenario-2"), 300.0, 0.05, true, 4000);
}

TEST(ProgramRun, Chain8AotJitInterpreterWriteIdenticalCsv) {
    expect_same_runs(bundled("chain-8"), 10.0, 0.01, true, 20);
}

// The bundled Jenkins examples over their default horizons: the JIT and the
// interpreter write the same bytes (sliders in the last columns), and the
// generic solver, an independent oracle, gives the same events to 1e-11 s.
TEST(ProgramRun, JenkinsExamplesJitInterpreterWriteIdenticalCsvAndAgreeWithGeneric) {
    for (const char* stem : {"friction_damper", "under_platform_damper"}) {
        const Model m = jenkins_example(stem);
        expect_same_runs(m, *m.t_end, 0.01, false, 200);
        InterpretedSolverProvider interp(lowering_of(m));
        GenericSolverProvider generic(m);
        const RunFiles ri = run_to_csv(m, interp, *m.t_end, 0.01, "jenkins-interp");
        const RunFiles rg = run_to_csv(m, generic, *m.t_end, 0.01, "jenkins-generic");
        EXPECT_NE(ri.trajectory.substr(0, ri.trajectory.find('\n')).find(",s_"), std::string::npos) << stem;
        ASSERT_EQ(ri.summary.events, rg.summary.events) << stem;
        auto times = [](const std::string& csv) {  // the events' instants, sorted (ties may list in either order)
            std::vector<double> t;
            std::istringstream in(csv);
            std::string line;
            while (std::getline(in, line))  // the header (run_to_csv writes it, and so does the observer) skipped
                if (!line.empty() && line[0] != 't') t.push_back(std::stod(line.substr(0, line.find(','))));
            std::sort(t.begin(), t.end());
            return t;
        };
        const std::vector<double> ti = times(ri.events), tg = times(rg.events);
        ASSERT_EQ(ti.size(), tg.size()) << stem;
        double apart = 0;
        for (std::size_t k = 0; k < ti.size(); ++k) apart = std::max(apart, std::fabs(ti[k] - tg[k]));
        EXPECT_LT(apart, 1e-11) << stem;
    }
}

TEST(ProgramRun, RandomModelsJitInterpreterWriteIdenticalCsv) {
    for (int n : {2, 3, 5, 8}) {
        const testing::Drawn d = testing::draw(700 + n, n);
        expect_same_runs(d.model, 5.0, 0.01, false, 1);
    }
}

// The interpreted programs are kept within a memory budget, as the Eigen
// solvers are (tests/test_generic_solver.cpp): with room for a single one,
// every change of configuration drops the previous solver and a return to it
// derives it again, and the run writes the same bytes as with no bound.
TEST(Program, ProviderKeepsItsSolversWithinTheBudgetAndRebuildsTheSame) {
    const Model m = bundled("chain-8");
    InterpretedSolverProvider unbounded(lowering_of(m), std::numeric_limits<std::size_t>::max());
    InterpretedSolverProvider one(lowering_of(m), 1);  // below any solver's size: only the one in use
    const RunFiles a = run_to_csv(m, unbounded, 5.0, 0.01, "unbounded"), b = run_to_csv(m, one, 5.0, 0.01, "one");
    EXPECT_EQ(unbounded.evicted(), 0u);
    ASSERT_GT(unbounded.cached(), 3u) << "the run should visit several configurations";
    EXPECT_EQ(one.cached(), 1u);
    EXPECT_GT(one.evicted(), 0u);
    EXPECT_GT(one.built(), unbounded.built()) << "revisited configurations are rebuilt";
    EXPECT_EQ(one.built(), one.evicted() + one.cached());
    EXPECT_TRUE(a.events == b.events) << "events CSV, bounded vs unbounded";
    EXPECT_TRUE(a.trajectory == b.trajectory) << "trajectory CSV, bounded vs unbounded";
    EXPECT_NE(one.describe().find("rebuilt"), std::string::npos) << one.describe();

    // A budget of three solvers: the least recently used goes first.
    Configuration c0 = Configuration::all_open(m), c1 = c0, c2 = c0, c3 = c0;
    c1.closed[0] = 1;
    c2.stuck[0] = 1;
    c3.stuck[1] = 1;
    const std::size_t size = InterpretedSolver(lower(derive(m, c0))).memory_bytes();
    EXPECT_GT(size, 1000u);
    InterpretedSolverProvider few(lowering_of(m), 3 * size);
    SegmentSolver* s0 = &few.solver(c0);
    few.solver(c1);
    few.solver(c2);
    EXPECT_EQ(&few.solver(c0), s0) << "c0 kept, and now the most recently used";
    few.solver(c3);  // evicts c1, the least recently used
    const std::size_t built = few.built();
    few.solver(c0);
    EXPECT_EQ(few.built(), built) << "c0 was not evicted";
    few.solver(c1);
    EXPECT_EQ(few.built(), built + 1) << "c1 was evicted and is rebuilt";
}

// The generic solver shares no code with the programs: an independent oracle,
// held to agreement to rounding, not to the bit.
TEST(Program, GenericSolverAgreesAsAnIndependentOracle) {
    for (int n = 1; n <= 8; ++n) {
        const testing::Drawn d = testing::draw(500 + n, n);
        const Model& m = d.model;
        InterpretedSolver ip(lower(derive(m, d.cfg)));
        GenericSolver g(m, d.cfg);
        const Start s = start_of(m, d.cfg, 3);
        ip.setup(s.t0, s.t0_lo, s.x0.data(), s.v0.data(), s.sgn.data());
        g.setup(s.t0, s.t0_lo, s.x0.data(), s.v0.data(), s.sgn.data());
        const std::size_t ns = ip.switches().size();
        ASSERT_EQ(ns, g.switches().size());
        std::vector<double> a(3 * m.dof() + 4 * ns), b(a.size());
        auto view = [&](std::vector<double>& o) {
            const std::size_t k = m.dof();
            return SegmentEval{o.data(), o.data() + k, o.data() + 2 * k, o.data() + 3 * k, o.data() + 3 * k + ns,
                               o.data() + 3 * k + 2 * ns, o.data() + 3 * k + 3 * ns};
        };
        for (double tau : {0.0, 0.01, 0.3, 1.7}) {
            ip.eval(tau, view(a));
            g.eval(tau, view(b));
            for (std::size_t i = 0; i < m.dof(); ++i) {
                EXPECT_NEAR(a[i], b[i], 1e-12 * (1 + std::fabs(b[i]))) << m.name << " x" << i << " tau " << tau;
                EXPECT_NEAR(a[m.dof() + i], b[m.dof() + i], 1e-11 * (1 + std::fabs(b[m.dof() + i]))) << m.name;
            }
            for (std::size_t f = 0; f < ns; ++f) {
                const double scale = b[3 * m.dof() + 3 * ns + f];
                EXPECT_NEAR(a[3 * m.dof() + f], b[3 * m.dof() + f], 1e-11 * (1 + scale)) << m.name << " g" << f;
            }
        }
    }
}

}  // namespace
}  // namespace hsnc

// ---- the switch search's own program (SegmentSolver::eval_switches) ----

namespace hsnc {
namespace {

/// A chain of n unit masses whose only switch functions are one contact at
/// its far end and, on that mass, friction: the search needs the state of
/// one mass, eval computes that of all n.
Model beam_chain(int n) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"beam\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\n" + (i == n ? "mu_k = 0.05\nmu_s = 0.07\n" : "");
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 400\n";
    t += "[[contact]]\nbetween = [\"" + m(n) + "\", \"ground\"]\ngap = 0.002\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0 }\n";
    t += "[initial]\nv = { " + m(n) + " = 0.5 }\n";
    return parse_model(t, "beam.toml");
}

/// Another provider's solvers with the search evaluating in full (what the
/// printed kernels do: SegmentSolver's defaults for eval_switches and eval_some).
struct FullEval : testing::ForwardingSolver {
    void eval_switches(double tau, const SegmentEval& out) const override { eval(tau, out); }
    void eval_some(double tau, const std::uint32_t*, std::size_t, const SegmentEval& out) const override {
        eval(tau, out);
    }
};
using FullEvalProvider = testing::ForwardingProvider<FullEval>;

/// A run of m on the interpreter and one whose search evaluates in full (as
/// a kernel does) are the same run, byte for byte: events and trajectory
/// CSVs, state reached and evaluations.
void expect_same_as_a_full_search(const Model& m, double t_end, const std::string& tag, std::size_t min_events) {
    InterpretedSolverProvider own(lowering_of(m));
    const RunFiles a = run_to_csv(m, own, t_end, 0.01, tag);
    InterpretedSolverProvider inner(lowering_of(m));
    FullEvalProvider full(inner);
    const RunFiles b = run_to_csv(m, full, t_end, 0.01, tag + "-full");
    ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
    EXPECT_GE(a.summary.events, min_events);
    EXPECT_EQ(a.summary.evaluations, b.summary.evaluations);
    EXPECT_TRUE(same_bits(a.summary.x, b.summary.x)) << "the state reached";
    EXPECT_TRUE(same_bits(a.summary.v, b.summary.v)) << "the state reached";
    EXPECT_TRUE(a.events == b.events) << "events CSV";
    EXPECT_TRUE(a.trajectory == b.trajectory) << "trajectory CSV";
}

TEST(SwitchProgram, HasTheBitsOfEvalAndLeavesOutTheRest) {
    const Model m = beam_chain(24);
    int with_program = 0;
    for (const Configuration& cfg : {Configuration::all_open(m), Configuration::parse(m, "closed=contact1 stuck=m24")}) {
        InterpretedSolver s(lower(derive(m, cfg)));
        with_program += s.has_switch_program();
        const testing::Start st = testing::start_of(m, cfg, 7);
        const std::size_t n = m.dof(), ns = s.switches().size();
        std::vector<double> x(m.state_size()), v(n), a(n), g(ns), dg(ns), b(ns), sc(ns);
        std::vector<double> x2 = x, v2 = v, a2 = a, g2 = g, dg2 = dg, b2 = b, sc2 = sc;
        const SegmentEval full{x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()};
        const SegmentEval search{x2.data(), v2.data(), a2.data(), g2.data(), dg2.data(), b2.data(), sc2.data()};
        s.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
        for (double tau : {0.0, 1e-9, 0.013, 0.5, 3.25, 40.0}) {
            s.eval_switches(tau, search);  // first, so that eval cannot leave it its registers
            s.eval(tau, full);
            EXPECT_TRUE(same_bits(g, g2)) << cfg.spec(m) << " tau " << tau << ": g";
            EXPECT_TRUE(same_bits(dg, dg2)) << cfg.spec(m) << " tau " << tau << ": dg";
            EXPECT_TRUE(same_bits(b, b2)) << cfg.spec(m) << " tau " << tau << ": bound";
            EXPECT_TRUE(same_bits(sc, sc2)) << cfg.spec(m) << " tau " << tau << ": scale";
        }
    }
    EXPECT_EQ(with_program, 2) << "24 masses, one of them read by the switch functions: a program of its own";
    // Where every mass has a switch function there is nothing to leave out.
    const Model chain = bundled("chain-8");
    EXPECT_FALSE(InterpretedSolver(lower(derive(chain, Configuration::all_open(chain)))).has_switch_program());
}

TEST(SwitchProgram, ARunSearchingWithItWritesTheBytesOfAFullSearch) {
    expect_same_as_a_full_search(beam_chain(24), 30.0, "switch-program", 20);
}

// ---- the search by function (SegmentSolver::eval_some) ----

/// A chain of n unit masses with friction on every one and three contacts:
/// a switch function for every mass (bench_common.h friction_chain's kind).
Model friction_chain_model(int n) {
    auto m = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"friction-chain\"\n[damping]\nbeta = 0.002\n";
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"" + m(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + m(i) + "\", \"" + m(i + 1) + "\"]\nk = 400\n";
    t += "[[spring]]\nbetween = [\"" + m(n) + "\", \"ground\"]\nk = 400\n";
    for (int q : {n / 4, n / 2})
        t += "[[contact]]\nbetween = [\"" + m(q) + "\", \"" + m(q + 1) + "\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"" + m(3 * n / 4) + "\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0, " + m(n) + " = -20.0 }\n";
    t += "[initial]\nv = { " + m(n / 2) + " = 1.0 }\n";
    return parse_model(t, "friction-chain.toml");
}

/// eval's outputs for a solver of n masses (nx state entries) and ns
/// functions, every one NaN to start with.
struct Outs {
    std::vector<double> x, v, a, g, dg, b, sc;
    Outs(std::size_t nx, std::size_t n, std::size_t ns)
        : x(nx, kNaN), v(n, kNaN), a(n, kNaN), g(ns, kNaN), dg(ns, kNaN), b(ns, kNaN), sc(ns, kNaN) {}
    SegmentEval view() { return {x.data(), v.data(), a.data(), g.data(), dg.data(), b.data(), sc.data()}; }
    static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
};

/// Each configuration of the 20-mass friction chain the function-row tests
/// take, its interpreter set up at a start state: body(spec, solver).
template <class Body>
void for_each_rows_case(const Model& m, Body&& body) {
    for (const char* spec : {"", "closed=contact1", "closed=contact2,contact3 stuck=m3,m4,m11,m17", "stuck=m1,m20"}) {
        const Configuration cfg = Configuration::parse(m, spec);
        InterpretedSolver s(lower(derive(m, cfg)));
        const testing::Start st = testing::start_of(m, cfg, 5);
        s.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
        body(spec, s);
    }
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(FunctionRows, EvalSomeHasTheBitsOfEvalForTheListedFunctionsAndLeavesTheOthers) {
    const Model m = friction_chain_model(20);
    std::mt19937 rng(11);
    for_each_rows_case(m, [&](const char* spec, InterpretedSolver& s) {
        const std::size_t n = m.dof(), ns = s.switches().size();
        ASSERT_GE(ns, kScheduleFrom) << spec;
        ASSERT_TRUE(s.has_function_rows()) << spec;
        Outs full(m.state_size(), n, ns);
        for (double tau : {0.0, 1e-9, 0.013, 0.5, 3.25}) {
            // A few functions, listed in any order (the engine lists them ascending).
            std::vector<std::uint32_t> which;
            for (std::uint32_t f = 0; f < ns; ++f)
                if (rng() % 5 == 0) which.push_back(f);
            std::shuffle(which.begin(), which.end(), rng);
            Outs some(m.state_size(), n, ns);
            s.eval_some(tau, which.data(), which.size(), some.view());  // first: eval cannot leave it its registers
            s.eval(tau, full.view());
            std::vector<char> listed(ns, 0);
            for (std::uint32_t f : which) {
                listed[f] = 1;
                EXPECT_TRUE(same_bits(full.g[f], some.g[f])) << spec << " tau " << tau << " g " << f;
                EXPECT_TRUE(same_bits(full.dg[f], some.dg[f])) << spec << " tau " << tau << " dg " << f;
                EXPECT_TRUE(same_bits(full.b[f], some.b[f])) << spec << " tau " << tau << " bound " << f;
                EXPECT_TRUE(same_bits(full.sc[f], some.sc[f])) << spec << " tau " << tau << " scale " << f;
            }
            for (std::size_t f = 0; f < ns; ++f)
                if (!listed[f])
                    EXPECT_TRUE(std::isnan(some.g[f]) && std::isnan(some.dg[f]) && std::isnan(some.b[f]) &&
                                std::isnan(some.sc[f]))
                        << f;
        }
    });
}

// eval_start (a segment carried over a switch starts with it, engine.cpp):
// every function's bound and the listed functions' four outputs with eval's
// bits, whatever the registers held from the evaluation before.
TEST(FunctionRows, EvalStartHasTheBitsOfEvalForEveryBoundAndTheListedFunctions) {
    const Model m = friction_chain_model(20);
    std::mt19937 rng(12);
    for_each_rows_case(m, [&](const char* spec, InterpretedSolver& s) {
        const std::size_t n = m.dof(), ns = s.switches().size();
        ASSERT_TRUE(s.has_start_steps()) << spec;
        Outs full(m.state_size(), n, ns);
        for (double tau : {0.0, 1e-9, 0.013, 0.5, 3.25}) {
            std::vector<std::uint32_t> which;
            for (std::uint32_t f = 0; f < ns; ++f)
                if (rng() % (tau == 3.25 ? 2 : 8) == 0) which.push_back(f);  // the last: more than a quarter
            Outs start(m.state_size(), n, ns);
            s.eval(0.77 * tau + 0.1, full.view());  // the registers hold another instant's values
            s.eval_start(tau, which.data(), which.size(), start.view());
            s.eval(tau, full.view());
            std::vector<char> listed(ns, 0);
            for (std::uint32_t f : which) {
                listed[f] = 1;
                EXPECT_TRUE(same_bits(full.g[f], start.g[f])) << spec << " tau " << tau << " g " << f;
                EXPECT_TRUE(same_bits(full.dg[f], start.dg[f])) << spec << " tau " << tau << " dg " << f;
                EXPECT_TRUE(same_bits(full.sc[f], start.sc[f])) << spec << " tau " << tau << " scale " << f;
            }
            // With at most a quarter listed, the others' g, g' and scale are not computed.
            const bool start_path = 4 * which.size() <= ns;
            for (std::size_t f = 0; f < ns; ++f) {
                EXPECT_TRUE(same_bits(full.b[f], start.b[f])) << spec << " tau " << tau << " bound " << f;
                if (start_path && !listed[f])
                    EXPECT_TRUE(std::isnan(start.g[f]) && std::isnan(start.dg[f]) && std::isnan(start.sc[f])) << f;
            }
        }
    });
}

TEST(FunctionRows, ARunSearchingByFunctionWritesTheBytesOfAFullSearch) {
    // What a kernel does (every function at every instant, the search reading
    // the listed ones) and what the interpreter does (the listed ones alone)
    // must be the same run: aot, jit and generic write the same bytes.
    expect_same_as_a_full_search(friction_chain_model(20), 10.0, "by-function", 500);
}

}  // namespace
}  // namespace hsnc
