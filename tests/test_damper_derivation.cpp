// Dampers on the derivation path (generator/derivation.h, StateSpaceData):
// non-proportional damping as state-space pseudo-modes in the programs that
// the interpreter runs and the emitter prints.
//  - Every configuration of three damper models (forced absorber with a
//    stop; a heavy dashpot that makes real state-space eigenvalues, with
//    friction; a Jenkins friction damper with a dashpot) and of random ones,
//    against the Eigen state-space solver, the independent oracle.
//  - The bound on |g''| over the step, against central differences.
//  - What the derivation refuses (critical damping, rigid-body modes) runs on
//    the generic solver in every kind.
//  - The JIT-compiled kernel and the interpreter, bit for bit.
//  - Whole runs against CVODE.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "derivation.h"
#include "emitter.h"
#include "engine_runner.h"
#include "error.h"
#include "fe_models.h"
#include "interpreted_solver.h"
#include "kernel_mode.h"
#include "kernel_set.h"
#include "lowering.h"
#include "model_reader.h"
#include "random_model.h"
#include "reference_engine.h"
#include "sample_models.h"
#include "segment_start.h"
#include "state_space_solver.h"
#include "temp_dir.h"
#if HSNC_WITH_JIT
#include "jit.h"
#include "kernel_abi.h"
#endif

namespace hsnc {
namespace {

Model absorber() { return read_model(std::string(HSNC_SOURCE_DIR) + "/examples/dashpot/absorber.toml"); }

// A dashpot heavy enough (zeta 1.6 on m1 with m2 stuck) that the state matrix
// has real eigenvalues, a light one between the masses, a stop and friction.
Model heavy_dashpot() {
    return parse_model(R"(
name = "heavy-dashpot"
[[mass]]
name = "m1"
m = 1.0
[[mass]]
name = "m2"
m = 0.5
mu_s = 0.3
mu_k = 0.2
[[spring]]
between = ["ground", "m1"]
k = 100.0
[[spring]]
between = ["m1", "m2"]
k = 50.0
[[damper]]
between = ["m1", "ground"]
c = 40.0
[[damper]]
between = ["m1", "m2"]
c = 0.3
[[contact]]
name = "stop"
between = ["m2", "ground"]
gap = 0.02
k = 2000.0
[[forcing]]
omega = 3.0
amplitude = { m2 = 3.0 }
[initial]
x = { m1 = 0.05 }
)",
                       "heavy-dashpot.toml");
}

// The bundled friction damper with a dashpot between airfoil and platform.
Model jenkins_with_dashpot() {
    Model m = read_model(std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml");
    m.name = "jenkins-dashpot";
    m.dampers.push_back({0, 1, 0.3});
    return m;
}

// A random chain (tests/random_model.h) with two random dampers.
testing::Drawn random_damped(unsigned seed, int n) {
    testing::Drawn d = testing::draw(900 + seed, n);
    testing::add_random_dampers(d, seed);
    return d;
}

using testing::Start;
using testing::start_of;

struct Out {
    std::vector<double> x, v, a, g, dg, bound, scale;
    Out(std::size_t nx, std::size_t n, std::size_t ns) : x(nx), v(n), a(n), g(ns), dg(ns), bound(ns), scale(ns) {}
    SegmentEval view() { return {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()}; }
};

/// The largest relative difference, program against the state-space solver,
/// over a few instants: x, v, a against the largest of each since the
/// segment's start (a decayed transient keeps the absolute error of its
/// start), g against the size of its terms, dg against itself plus the
/// terms' rate.
double worst_difference(const Model& m, const Configuration& cfg, const Program& p, unsigned seed) {
    InterpretedSolver ip(p);
    StateSpaceSolver ss(m, cfg);
    EXPECT_EQ(ip.switches(), ss.switches());
    const Start st = start_of(m, cfg, seed);
    ip.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
    ss.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
    const std::size_t n = m.dof(), nx = m.state_size(), ns = ss.switches().size();
    double worst = 0.0;
    double xs = 1e-300, vs = 1e-300, as = 1e-300;  // the largest sizes so far (tau = 0 first: the segment's start)
    for (double tau : {0.0, 0.01, 0.3, 1.7, 6.0}) {
        Out a(nx, n, ns), b(nx, n, ns);
        ip.eval(tau, a.view());
        ss.eval(tau, b.view());
        for (std::size_t i = 0; i < nx; ++i) xs = std::max(xs, std::fabs(b.x[i]));
        for (std::size_t i = 0; i < n; ++i) vs = std::max(vs, std::fabs(b.v[i])), as = std::max(as, std::fabs(b.a[i]));
        for (std::size_t i = 0; i < nx; ++i) worst = std::max(worst, std::fabs(a.x[i] - b.x[i]) / xs);
        for (std::size_t i = 0; i < n; ++i) {
            worst = std::max(worst, std::fabs(a.v[i] - b.v[i]) / vs);
            worst = std::max(worst, std::fabs(a.a[i] - b.a[i]) / as);
        }
        for (std::size_t f = 0; f < ns; ++f) {
            worst = std::max(worst, std::fabs(a.g[f] - b.g[f]) / (b.scale[f] + 1e-300));
            const double rate_scale = is_velocity(ss.switches()[f].kind) ? as + vs : vs + xs;
            worst = std::max(worst, std::fabs(a.dg[f] - b.dg[f]) / (std::fabs(b.dg[f]) + rate_scale * b.scale[f] / (xs + vs)));
        }
    }
    return worst;
}

TEST(DamperDerivation, ProgramsAgreeWithTheStateSpaceSolverInEveryConfiguration) {
    std::size_t compared = 0;
    for (const Model& m : {absorber(), heavy_dashpot(), jenkins_with_dashpot()}) {
        double worst = 0.0;
        for (const Configuration& cfg : all_configurations(m)) {
            const Derivation d = derive(m, cfg);  // none refused
            ASSERT_TRUE(d.state_space);
            for (unsigned seed = 1; seed <= 2; ++seed) worst = std::max(worst, worst_difference(m, cfg, lower(d), seed));
            ++compared;
        }
        std::printf("%s: %zu configurations, worst relative difference %.2g\n", m.name.c_str(),
                    all_configurations(m).size(), worst);
        EXPECT_LT(worst, 1e-12) << m.name;  // measured 3.7e-14 at most
    }
    EXPECT_EQ(compared, 2u + 4u + 3u);
    std::size_t refused = 0, random = 0;
    double worst = 0.0;
    for (unsigned seed = 1; seed <= 12; ++seed) {
        const testing::Drawn dr = random_damped(seed, 2 + static_cast<int>(seed % 4));
        try {
            worst = std::max(worst, worst_difference(dr.model, dr.cfg, lower(derive(dr.model, dr.cfg)), seed));
            ++random;
        } catch (const NotDerivable& e) {
            ++refused;  // floating components under dampers
        }
    }
    std::printf("random damper models: %zu compared, %zu refused, worst relative difference %.2g\n", random, refused, worst);
    EXPECT_GE(random, 8u);
    EXPECT_LT(worst, 1e-12);  // measured 4e-14
}

TEST(DamperDerivation, ACantileverWithADamperIsDerivedAndAgreesWithTheStateSpaceSolver) {
    // 8 consistent-mass Euler-Bernoulli elements (16 dofs, omega 24.9 .. 2.7e4 rad/s), Rayleigh
    // damping, a damper at the tip, a stop there closed or open: in (x, v/s) the derivation's
    // eigenvectors measured condition 2.9e3 ("nearly dependent") and every configuration went to
    // the Eigen solver; in the energy scaling (energy_scaled()) both are derived, and the programs
    // agree with the state-space solver to its own error on this structure in double (x 5e-10 of
    // the motion against long double, tests/test_dampers.cpp; here measured 4.8e-10).
    const fe::Beam beam = fe::cantilever(8);
    testing::TempDir dir;
    const Model m = read_model(
        fe::structure_model(dir, "beam.toml", "beam-damper", beam.M, beam.K, beam.dofs,
                            "[damping]\nalpha = 0.2\nbeta = 2e-5\n[[damper]]\nbetween = [\"w8\", \"ground\"]\nc = 0.5\n"
                            "[[contact]]\nname = \"stop\"\nbetween = [\"w8\", \"ground\"]\ngap = 0.004\nk = 2000.0\n"));
    double worst = 0.0;
    for (const Configuration& cfg : all_configurations(m)) {
        const Derivation d = derive(m, cfg);  // NotDerivable before
        ASSERT_TRUE(d.state_space);
        for (unsigned seed = 1; seed <= 2; ++seed) worst = std::max(worst, worst_difference(m, cfg, lower(d), seed));
    }
    std::printf("[ info ] cantilever with a damper: programs against the state-space solver %.2g\n", worst);
    EXPECT_LT(worst, 2e-9);
}

// The state matrix is balanced before its eigenvectors are judged (y = (x, v/s),
// as the state-space solver does): unbalanced, this configuration of a 16-mass
// chain with a dashpot between neighbours measured condition 226 and was
// refused as nearly defective, like 17 others of the 29 a 20 s run enters.
TEST(DamperDerivation, BalancedStateMatrixIsNotMistakenForADefectiveOne) {
    std::string t = "name = \"chain-16-dampers\"\n";
    for (int i = 1; i <= 16; ++i) t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n[[spring]]\nbetween = [\"m16\", \"ground\"]\nk = 400\n";
    for (int i = 1; i < 16; ++i) {
        const std::string pair = "between = [\"m" + std::to_string(i) + "\", \"m" + std::to_string(i + 1) + "\"]\n";
        t += "[[spring]]\n" + pair + "k = 400\n[[damper]]\n" + pair + "c = 0.05\n";
    }
    t += "[[contact]]\nname = \"contact1\"\nbetween = [\"m4\", \"m5\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nname = \"contact2\"\nbetween = [\"m8\", \"m9\"]\ngap = 0.01\nk = 4000\n";
    const Model m = parse_model(t, "chain-16-dampers.toml");
    for (const char* spec : {"closed=contact2 stuck=m2,m3,m4,m5,m11,m12,m13,m14,m15", "closed=", "closed=contact1,contact2"}) {
        const Configuration cfg = Configuration::parse(m, spec);
        Derivation d;
        EXPECT_NO_THROW(d = derive(m, cfg)) << spec;
        EXPECT_EQ(d.modes.size(), 2 * d.n_free()) << spec;
    }
}

// Real state-space eigenvalues are pseudo-modes of the critical regime.
TEST(DamperDerivation, RealEigenvaluesArePseudoModesOfTheCriticalRegime) {
    const Model m = heavy_dashpot();
    Configuration cfg = Configuration::all_open(m);
    cfg.stuck[1] = true;
    const Derivation d = derive(m, cfg);
    ASSERT_EQ(d.modes.size(), 2u);
    for (const Mode& md : d.modes) {
        EXPECT_EQ(md.regime, Regime::critical);
        EXPECT_EQ(md.c, 2 * md.sigma);
    }
    // m1 alone: s^2 + 40.3 s + 150 = 0, decay rates (40.3 -+ sqrt(40.3^2 - 600))/2.
    const double root = std::sqrt(40.3 * 40.3 - 600.0);
    EXPECT_NEAR(d.modes[0].sigma.to_double(), (40.3 - root) / 2, 1e-12);
    EXPECT_NEAR(d.modes[1].sigma.to_double(), (40.3 + root) / 2, 1e-12);
}

// bound[f] >= |g_f''(s)| for s in [tau, tau + step] (step = max_step or 2),
// g'' by central differences of the program's dg (h = 1e-5: truncation
// ~1e-10 |g''''|, rounding ~1e-11 |dg|, both inside the slack below).
TEST(DamperDerivation, BoundHoldsOverTheStep) {
    std::size_t checked = 0;
    double tightest = 1e300;  // smallest bound / max |g''| seen: how close the bound comes
    for (const Model& m : {absorber(), heavy_dashpot(), jenkins_with_dashpot()})
        for (const Configuration& cfg : all_configurations(m)) {
            InterpretedSolver ip(lower(derive(m, cfg)));
            const Start st = start_of(m, cfg, 7);
            ip.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
            const std::size_t n = m.dof(), nx = m.state_size(), ns = ip.switches().size();
            const double step = std::min(ip.max_step(), 2.0), h = 1e-5;
            for (double t0 : {0.0, 0.7}) {
                Out o(nx, n, ns);
                ip.eval(t0, o.view());
                std::vector<double> peak(ns, 0.0), rate(ns, 0.0);
                for (int k = 0; k <= 64; ++k) {
                    const double t = t0 + step * k / 64;
                    Out lo(nx, n, ns), hi(nx, n, ns);
                    ip.eval(t - h, lo.view());
                    ip.eval(t + h, hi.view());
                    for (std::size_t f = 0; f < ns; ++f) {
                        peak[f] = std::max(peak[f], std::fabs(hi.dg[f] - lo.dg[f]) / (2 * h));
                        rate[f] = std::max(rate[f], std::fabs(hi.dg[f]) + std::fabs(lo.dg[f]));
                    }
                }
                for (std::size_t f = 0; f < ns; ++f) {
                    EXPECT_LE(peak[f], o.bound[f] * (1 + 1e-6) + 1e-9 * rate[f])
                        << m.name << " " << cfg.key() << " g" << f << " from " << t0;
                    if (peak[f] > 1e-6 * o.bound[f]) tightest = std::min(tightest, o.bound[f] / peak[f]);
                    ++checked;
                }
            }
        }
    std::printf("%zu bounds checked; the tightest is %.4g times the largest |g''| sampled\n", checked, tightest);
    EXPECT_EQ(checked, 32u);  // 9 configurations, 16 switch functions, 2 starts
}

// What the derivation refuses runs on the generic solver in every kernel
// kind: critical damping (a defective state matrix: the matrix exponential)
// and rigid-body modes under a dashpot; the events are the generic solver's,
// and the provider says so.
TEST(DamperDerivation, RefusedConfigurationsRunOnTheGenericSolver) {
    Model critical = parse_model(R"(
name = "critical-stop"
[[mass]]
name = "m1"
m = 2.0
[[spring]]
between = ["ground", "m1"]
k = 50.0
[[damper]]
between = ["m1", "ground"]
c = 20.0
[[contact]]
name = "stop"
between = ["m1", "ground"]
gap = 0.01
k = 1000.0
[initial]
v = { m1 = 1.0 }
)",
                                 "critical-stop.toml");
    Model floating = parse_model(R"(
name = "floating-dashpot"
[[mass]]
name = "m1"
m = 1.0
[[mass]]
name = "m2"
m = 2.0
[[spring]]
between = ["m1", "m2"]
k = 30.0
[[damper]]
between = ["m1", "m2"]
c = 0.4
[[contact]]
name = "wall"
between = ["m2", "ground"]
gap = 0.3
k = 500.0
[initial]
v = { m1 = 0.8 }
)",
                                 "floating-dashpot.toml");
    // c = 2 sqrt(k m) = 20 with the stop open; with it closed (k = 1050) it is derivable.
    EXPECT_THROW(derive(critical, Configuration::all_open(critical)), NotDerivable);
    EXPECT_THROW(derive(floating, Configuration::all_open(floating)), NotDerivable);
    for (const Model* m : {&critical, &floating}) {
        const testing::Outcome gi = testing::simulate(*m, 5.0, 0.1, testing::Solvers::generic);
        const testing::Outcome ii = testing::simulate(*m, 5.0, 0.1, testing::Solvers::interp);
        ASSERT_EQ(ii.summary.status, RunStatus::ok) << m->name << ": " << ii.summary.message;
        EXPECT_GE(ii.events.size(), 1u) << m->name;
        ASSERT_EQ(gi.events.size(), ii.events.size()) << m->name;
        // Up to the first event both runs are the same solver: the same bits.
        EXPECT_EQ(std::memcmp(gi.events[0].x.data(), ii.events[0].x.data(), m->dof() * sizeof(double)), 0) << m->name;
        for (std::size_t k = 0; k < gi.events.size(); ++k)
            EXPECT_NEAR(gi.events[k].t, ii.events[k].t, 1e-12) << m->name << " event " << k;
    }
    DerivationFallbackProvider p(floating, std::make_unique<InterpretedSolverProvider>(program_source(floating)));
    p.solver(Configuration::all_open(floating));
    EXPECT_EQ(p.not_derivable(), 1u);
    EXPECT_NE(p.describe().find("rigid-body modes under dampers"), std::string::npos) << p.describe();
}

// Whole runs of the three models on the interpreter against CVODE (rtol
// 1e-12): the same events, to the integrator's accuracy; and against the
// state-space solver, to rounding.
TEST(DamperDerivation, WholeRunsAgreeWithCvode) {
#if !HSNC_WITH_CVODE
    GTEST_SKIP() << "built without CVODE";
#endif
    for (const Model& m : {absorber(), heavy_dashpot(), jenkins_with_dashpot()}) {
        const double t_end = 20.0;
        const testing::Outcome h = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        ASSERT_EQ(h.summary.status, RunStatus::ok) << h.summary.message;
        const testing::Outcome c = testing::baseline(m, t_end, 1e-12, 1e-14, Method::cvode);
        ASSERT_EQ(c.summary.status, RunStatus::ok) << c.summary.message;
        std::size_t same = 0;
        double dt = 0.0;
        while (same < h.events.size() && same < c.events.size() && h.events[same].kind == c.events[same].kind &&
               h.events[same].element == c.events[same].element) {
            dt = std::max(dt, std::fabs(h.events[same].t - c.events[same].t));
            ++same;
        }
        std::printf("%s: %zu/%zu events as CVODE's, max |dt| %.2g s\n", m.name.c_str(), same, h.events.size(), dt);
        // The state-space solver (the independent oracle) to rounding: CVODE's own
        // error is larger at the heavy dashpot's stick and release (1.2e-9 s).
        const testing::Outcome g = testing::simulate(m, t_end, 0.0, testing::Solvers::generic);
        ASSERT_EQ(g.events.size(), h.events.size()) << m.name;
        double dg = 0.0;
        for (std::size_t k = 0; k < h.events.size(); ++k) dg = std::max(dg, std::fabs(h.events[k].t - g.events[k].t));
        std::printf("%s: the state-space solver's events within %.2g s\n", m.name.c_str(), dg);
        EXPECT_LT(dg, 1e-12) << m.name;
        EXPECT_EQ(same, h.events.size()) << m.name;
        EXPECT_GE(same, 10u) << m.name;
        EXPECT_LT(dt, 1e-8) << m.name;
    }
}

// The CLN reference with dampers (reference/mp_segment.h: the matrix
// exponential at N digits, bounds from the energy): at 30 and 60 digits it
// agrees with itself, and the interpreter (the derivation's pseudo-modes, in
// double) with it, on the three models and on critical damping, which the
// derivation refuses and the exponential takes.
reference::PreciseRun reference_run(const Model& m, double t_end, int digits) {
    testing::Recorder rec(m.dof(), m.state_size());
    EngineOptions opt;
    opt.t_end = t_end;
    return reference::simulate_precise(m, digits, opt, rec);
}

TEST(DamperReference, AgreesWithItselfAndWithTheInterpreter) {
    Model critical = heavy_dashpot();
    critical.name = "critical";
    critical.dampers[0].c = 2.0 * std::sqrt(150.0 * 1.0) - 0.3;  // m1 alone with m2 stuck: c = 2 sqrt(k m)
    Configuration m2_stuck = Configuration::all_open(critical);
    m2_stuck.stuck[1] = true;
    EXPECT_THROW(derive(critical, m2_stuck), NotDerivable);  // the interpreter's run takes it on the generic solver
    for (const Model& m : {absorber(), heavy_dashpot(), jenkins_with_dashpot(), critical}) {
        const double t_end = 8.0;
        const reference::PreciseRun r30 = reference_run(m, t_end, 30), r60 = reference_run(m, t_end, 60);
        ASSERT_EQ(r30.summary.status, RunStatus::ok) << m.name << ": " << r30.summary.message;
        ASSERT_EQ(r60.summary.status, RunStatus::ok) << m.name << ": " << r60.summary.message;
        const testing::Outcome h = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        ASSERT_EQ(r30.events.size(), r60.events.size()) << m.name;
        ASSERT_EQ(h.events.size(), r60.events.size()) << m.name;
        double self = 0.0, vs_double = 0.0;
        for (std::size_t k = 0; k < r60.events.size(); ++k) {
            EXPECT_EQ(r30.events[k].kind, r60.events[k].kind) << m.name << " event " << k;
            EXPECT_EQ(h.events[k].kind, r60.events[k].kind) << m.name << " event " << k;
            self = std::max(self, reference::relative_difference(r30.events[k].t, r60.events[k].t, 1.0));
            vs_double = std::max(vs_double, std::fabs(h.events[k].t - cln::double_approx(r60.events[k].t)));
        }
        std::printf("%s: %zu events; reference 30 vs 60 digits %.2g s, interpreter vs reference %.2g s\n",
                    m.name.c_str(), r60.events.size(), self, vs_double);
        EXPECT_GE(r60.events.size(), 10u) << m.name;
        EXPECT_LT(self, 1e-25) << m.name;
        EXPECT_LT(vs_double, 1e-12) << m.name;
    }
}

// Random damper chains (contacts, friction, forcing, two dampers each): the
// reference at 30 digits against the interpreter, every event in order.
TEST(DamperReference, RandomModelsAgreeWithTheInterpreter) {
    std::size_t compared = 0, events = 0;
    for (unsigned seed = 1; seed <= 8; ++seed) {
        testing::Drawn dr = random_damped(seed, 2 + static_cast<int>(seed % 3));
        Model& m = dr.model;
        m.x0.assign(m.dof(), 0.0);
        m.v0.assign(m.dof(), 0.0);
        m.v0[0] = 0.5;
        const double t_end = 4.0;
        reference::PreciseRun r;
        try {
            r = reference_run(m, t_end, 30);
        } catch (const RunError& e) {
            std::printf("seed %u: %s\n", seed, e.what());  // rigid-body modes under dampers
            continue;
        }
        ASSERT_EQ(r.summary.status, RunStatus::ok) << "seed " << seed << ": " << r.summary.message;
        const testing::Outcome h = testing::simulate(m, t_end, 0.0, testing::Solvers::interp);
        ASSERT_EQ(h.events.size(), r.events.size()) << "seed " << seed;
        double apart = 0.0;
        for (std::size_t k = 0; k < r.events.size(); ++k) {
            EXPECT_EQ(h.events[k].kind, r.events[k].kind) << "seed " << seed << " event " << k;
            apart = std::max(apart, std::fabs(h.events[k].t - cln::double_approx(r.events[k].t)));
        }
        std::printf("seed %u (%zu masses): %zu events, the interpreter within %.2g s of the reference\n", seed, m.dof(),
                    r.events.size(), apart);
        EXPECT_LT(apart, 1e-11) << "seed " << seed;
        ++compared;
        events += r.events.size();
    }
    EXPECT_GE(compared, 5u);
    EXPECT_GE(events, 50u);
}

#if HSNC_WITH_JIT
// The kernel printed from a program and the interpreter running it: the same
// bits in every configuration (setup and eval at a few instants).
TEST(DamperDerivation, JitKernelsAndTheInterpreterAreBitIdentical) {
    std::size_t checked = 0;
    for (const Model& m : {absorber(), heavy_dashpot(), jenkins_with_dashpot()}) {
        Jit jit;
        jit.add(m.name + ".cpp", combined_source(generate_kernel_set(m)));
        for (const Configuration& cfg : all_configurations(m)) {
            const auto* k = static_cast<const hsnc_kernel*>(jit.lookup(kernel_symbol(m, cfg)));
            ASSERT_NE(k, nullptr) << m.name << " " << cfg.spec(m);
            InterpretedSolver ip(lower(derive(m, cfg)));
            const Start st = start_of(m, cfg, 3);
            std::vector<double> coef(static_cast<std::size_t>(k->n_coef));
            k->setup(coef.data(), st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
            ip.setup(st.t0, st.t0_lo, st.x0.data(), st.v0.data(), st.sgn.data());
            ASSERT_EQ(std::memcmp(coef.data(), ip.coefficients(), coef.size() * sizeof(double)), 0) << m.name << " " << cfg.key();
            const std::size_t n = m.dof(), nx = m.state_size(), ns = ip.switches().size();
            for (double tau : {0.0, 1e-3, 0.4, 2.5, 9.0}) {
                Out a(nx, n, ns), b(nx, n, ns);
                k->eval(coef.data(), tau, a.x.data(), a.v.data(), a.a.data(), a.g.data(), a.dg.data(), a.bound.data(),
                        a.scale.data());
                ip.eval(tau, b.view());
                for (auto [p, q] : {std::pair{&a.x, &b.x}, {&a.v, &b.v}, {&a.a, &b.a}, {&a.g, &b.g}, {&a.dg, &b.dg},
                                    {&a.bound, &b.bound}, {&a.scale, &b.scale}})
                    EXPECT_EQ(std::memcmp(p->data(), q->data(), p->size() * sizeof(double)), 0)
                        << m.name << " " << cfg.key() << " tau " << tau;
            }
            ++checked;
        }
    }
    EXPECT_EQ(checked, 2u + 4u + 3u);
}
#endif

}  // namespace
}  // namespace hsnc
