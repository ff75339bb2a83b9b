// Tests of restarting a segment at a reversal from its coefficient block
// (runtime/solvers/restart.h): against the Coulomb oscillator's closed form
// over nine half-cycles carried over by restarts alone, and against setup
// from the event state on a damped, forced 8-mass chain. Then through the
// engine: 16 Coulomb oscillators of different frequencies, every reversal
// against the closed form; a forced bank of 16 over 300 s, 10690 segments
// carried over, against the Eigen solver's events; a forced friction chain of
// 20 masses, the same bits whether the plan is the solver's or
// EngineOptions::restart_plans', and, to rounding, what setting up every
// segment gives, also with overdamped modes and on random chains of 20.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "derivation.h"
#include "engine_runner.h"
#include "forwarding_solver.h"
#include "friction_bank.h"
#include "generic_solver.h"
#include "interpreted_solver.h"
#include "lowering.h"
#include "model_reader.h"
#include "random_model.h"
#include "restart.h"

namespace hsnc {
namespace {

Model bundled(const std::string& stem) { return read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + stem + ".toml"); }

struct Outputs {
    std::vector<double> x, v, a, g, dg, bound, scale;
    explicit Outputs(const Model& m, std::size_t ns)
        : x(m.state_size()), v(m.dof()), a(m.dof()), g(ns), dg(ns), bound(ns), scale(ns) {}
    SegmentEval view() { return {x.data(), v.data(), a.data(), g.data(), dg.data(), bound.data(), scale.data()}; }
};

// Released from rest at 0.2 m, each half-cycle lasts pi/omega and ends at rest
// 2 mu g / omega^2 nearer the origin (models/coulomb-1dof.toml). Each segment
// is started by restarting the previous one at its reversal, never by setup.
TEST(Restart, CoulombHalfCyclesCarriedOverByRestartsAloneMatchTheClosedForm) {
    const Model m = bundled("coulomb-1dof");
    const Configuration cfg = Configuration::all_open(m);
    const Derivation d = derive(m, cfg);
    const Program p = lower(d, ProgramNames::no);
    const RestartPlan plan = restart_plan(d, p);
    ASSERT_FALSE(plan.empty());
    InterpretedSolver s(p);
    Outputs out(m, s.switches().size());
    const double omega = 10.0, half = M_PI / omega, drop = 2 * 0.1 * m.g / (omega * omega);
    std::vector<signed char> sgn{-1}, next{1};
    const double x0[1] = {0.2}, v0[1] = {0.0};
    s.setup(0.0, x0, v0, sgn.data());
    double t = 0.0;
    for (int k = 1; k <= 9; ++k) {
        s.eval(half, out.view());
        const double expected = (k % 2 ? -1.0 : 1.0) * (0.2 - k * drop);
        EXPECT_NEAR(out.x[0], expected, 2e-15) << "half-cycle " << k;
        EXPECT_NEAR(out.v[0], 0.0, 1e-14) << "half-cycle " << k;
        t += half;
        next[0] = static_cast<signed char>(-sgn[0]);
        restart_coefficients(plan, s.coefficient_block(), half, t, 0.0, sgn.data(), next.data());
        sgn = next;
        // The restarted segment starts where the last one ended.
        s.eval(0.0, out.view());
        EXPECT_NEAR(out.x[0], expected, 2e-15) << "restart " << k;
    }
}

// A damped chain with contacts and forcing (models/chain-8.toml, 8 modes): a
// restart and a setup from the state at the reversal give the same segment to
// rounding, over 50 reversals in a row, each of another mass.
TEST(Restart, AgreesWithSetupFromTheEventStateOnAForcedDampedChain) {
    const Model m = bundled("chain-8");
    for (const char* spec : {"", "closed=c23"}) {
        const Configuration cfg = Configuration::parse(m, spec);
        const Derivation d = derive(m, cfg);
        const Program p = lower(d, ProgramNames::no);
        const RestartPlan plan = restart_plan(d, p);
        ASSERT_FALSE(plan.empty()) << spec;
        InterpretedSolver s(p), ref(p);
        const std::size_t n = m.dof(), ns = s.switches().size();
        Outputs out(m, ns), rout(m, ns);
        std::vector<signed char> sgn(n, 1), next;
        std::vector<double> x0(n), v0(n);
        for (std::size_t i = 0; i < n; ++i) x0[i] = 0.002 * std::sin(1.0 + i), v0[i] = 0.1 + 0.01 * i;
        const double tau = 0.00390625;  // 2^-8: every segment start is exact
        double t = 1.0, worst = 0.0;
        s.setup(t, x0.data(), v0.data(), sgn.data());
        for (int rev = 0; rev < 50; ++rev) {
            s.eval(tau, out.view());
            next = sgn;
            next[static_cast<std::size_t>(rev * 3) % n] *= -1;
            t += tau;
            ref.setup(t, out.x.data(), out.v.data(), next.data());
            restart_coefficients(plan, s.coefficient_block(), tau, t, 0.0, sgn.data(), next.data());
            sgn = next;
            for (double at : {0.0, 1e-3, 3.9e-3}) {
                s.eval(at, out.view());
                ref.eval(at, rout.view());
                // Against the magnitude of the terms summed into each switch
                // function (its rounding level is about 1e-16 of that).
                for (std::size_t f = 0; f < ns; ++f)
                    worst = std::max(worst, std::fabs(out.g[f] - rout.g[f]) / rout.scale[f]);
            }
        }
        EXPECT_LT(worst, 1e-14) << spec;
        std::printf("[ restart  ] chain-8 [%s] 50 reversals: worst |g - g_setup| / scale %.2e\n", spec, worst);
    }
}

// What it does not carry over: a configuration with a stuck mass between two
// sliding ones still restarts (its blocks are plain modes), one with a rigid
// mode, a damper or a Jenkins element does not.
TEST(Restart, PlansOnlyForPlainModes) {
    const Model chain = bundled("chain-8");
    const Derivation stuck = derive(chain, Configuration::parse(chain, "stuck=m4"));
    EXPECT_FALSE(restart_plan(stuck, lower(stuck, ProgramNames::no)).empty());
    const Model rigid = parse_model("name = \"free\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu_k = 0.1\n", "free.toml");
    const Derivation free = derive(rigid, Configuration::all_open(rigid));
    EXPECT_TRUE(restart_plan(free, lower(free, ProgramNames::no)).empty());
    // A damper (state-space pseudo-modes) or a Jenkins element (a slider's
    // state beside the masses'): set up at every segment, so the engine
    // never asks more of them.
    const std::string two = "[[mass]]\nname = \"a\"\nm = 1\nmu_k = 0.1\n[[mass]]\nname = \"b\"\nm = 1\n"
                            "[[spring]]\nbetween = [\"ground\", \"a\"]\nk = 100\n"
                            "[[spring]]\nbetween = [\"a\", \"b\"]\nk = 100\n";
    const Model damped = parse_model("name = \"damped\"\n" + two + "[[damper]]\nbetween = [\"b\", \"ground\"]\nc = 0.5\n",
                                     "damped.toml");
    const Derivation dd = derive(damped, Configuration::all_open(damped));
    EXPECT_TRUE(dd.state_space);
    EXPECT_TRUE(restart_plan(dd, lower(dd, ProgramNames::no)).empty());
    const Model jenkins = parse_model("name = \"jenkins\"\n" + two +
                                          "[[jenkins]]\nbetween = [\"b\", \"ground\"]\nk = 50\nslip_force = 1\n",
                                      "jenkins.toml");
    const Derivation dj = derive(jenkins, Configuration::all_open(jenkins));
    EXPECT_TRUE(lower(dj, ProgramNames::no).restart.empty());
    // A plain chain's program carries its plan.
    EXPECT_FALSE(lower(stuck, ProgramNames::no).restart.empty());
}

// 16 masses on springs of their own (k_i = 100 + 10 i N/m), each with
// Coulomb friction (mu_k N = 0.5 N) and released from rest at 0.5 m: the
// modes are the masses, and each mass's half-cycles last pi / omega_i and
// end 2 mu_k N / k_i nearer the origin, as a lone Coulomb oscillator's. All
// 16 slide throughout, so every reversal keeps the configuration and the
// engine carries the segment over it (restart.h kRestartFrom = 16).
std::string coulomb_bank(int n) {
    std::string t = "name = \"coulomb-bank\"\n";
    for (int i = 1; i <= n; ++i)
        t += "[[mass]]\nname = \"m" + std::to_string(i) + "\"\nm = 1\nmu_k = " + std::to_string(0.5 / 9.81) +
             "\nmu_s = " + std::to_string(0.6 / 9.81) + "\n";
    for (int i = 1; i <= n; ++i)
        t += "[[spring]]\nbetween = [\"ground\", \"m" + std::to_string(i) + "\"]\nk = " + std::to_string(100 + 10 * i) +
             "\n";
    t += "[initial]\nx = { ";
    for (int i = 1; i <= n; ++i) t += (i > 1 ? ", m" : "m") + std::to_string(i) + " = 0.5";
    return t + " }\n";
}

TEST(RestartEngine, SixteenCoulombOscillatorsReverseOnTheirClosedForms) {
    const int n = 16;
    const Model m = parse_model(coulomb_bank(n), "coulomb-bank.toml");
    InterpretedSolverProvider programs(program_source(m));
    const testing::Outcome r = testing::run_engine(m, programs, 3.0, 0.0, kScheduleFrom, restart_plan_source(m));
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    std::vector<int> half(n, 0);
    double worst_t = 0, worst_x = 0;
    for (const testing::Recorded& e : r.events) {
        ASSERT_EQ(e.kind, EventKind::reversal) << "at t = " << e.t;
        const int i = e.element;
        const double k = 100.0 + 10.0 * (i + 1), w = std::sqrt(k), d = m.friction_slot(i).mu_k * 9.81 / k;
        const int h = ++half[i];
        const double t = h * M_PI / w, x = (h % 2 ? -1.0 : 1.0) * (0.5 - 2 * h * d);
        worst_t = std::max(worst_t, std::fabs(e.t - t) / t);
        worst_x = std::max(worst_x, std::fabs(e.x[i] - x));
    }
    // Every reversal but the run's first configuration's first segment was carried over.
    EXPECT_EQ(r.summary.restarts, r.summary.segments - 1);
    for (int i = 0; i < n; ++i)  // none sticks: every half-cycle that ends by t = 3 s reverses
        EXPECT_EQ(half[i], static_cast<int>(3.0 * std::sqrt(100.0 + 10.0 * (i + 1)) / M_PI)) << "m" << i + 1;
    EXPECT_LT(worst_t, 1e-14);
    EXPECT_LT(worst_x, 1e-14);
    std::printf("[ restart  ] %zu reversals of 16 Coulomb oscillators, all carried over: worst |t - t_exact| / t %.1e, "
                "|x - x_exact| %.1e m\n", r.events.size(), worst_t, worst_x);
}

// 16 masses on springs of their own, coupled by weaker ones, each forced
// (11 to 26 N at 7 rad/s) and sliding on Coulomb friction: they reverse
// twice a forcing period and never stick, so nearly every segment over 300 s
// is carried over a reversal (10690 of 10715). The Eigen solver, written
// apart, sets every segment up from the state: the two runs' events stay
// within 1e-13 s of each other to the end (measured: 5.7e-14 s at t = 280 s,
// one ulp of t), so carrying segments over does not walk the motion away.
TEST(RestartEngine, TenThousandCarriedSegmentsKeepToTheEigenSolversEvents) {
    const Model m = parse_model(
        testing::friction_bank("forced-bank-16", 16, [](int i) { return 10.0 + i; }, 0.0), "forced-bank-16.toml");
    InterpretedSolverProvider programs(program_source(m));
    GenericSolverProvider eigen(m);
    const testing::Outcome carried = testing::run_engine(m, programs, 300.0, 0.0, kScheduleFrom, restart_plan_source(m));
    const testing::Outcome set_up = testing::run_engine(m, eigen, 300.0);
    ASSERT_EQ(carried.summary.status, RunStatus::ok) << carried.summary.message;
    ASSERT_EQ(set_up.summary.status, RunStatus::ok) << set_up.summary.message;
    EXPECT_GT(carried.summary.restarts, 10000u);
    EXPECT_EQ(set_up.summary.restarts, 0u);
    ASSERT_EQ(carried.events.size(), set_up.events.size());
    double worst = 0;
    for (std::size_t k = 0; k < carried.events.size(); ++k) {
        ASSERT_EQ(carried.events[k].kind, set_up.events[k].kind) << k;
        ASSERT_EQ(carried.events[k].element, set_up.events[k].element) << k;
        worst = std::max(worst, std::fabs(carried.events[k].t - set_up.events[k].t));
    }
    EXPECT_LT(worst, 1e-13);
    std::printf("[ restart  ] forced bank over 300 s: %zu of %zu segments carried over, events within %.1e s of the "
                "Eigen solver's\n", carried.summary.restarts, carried.summary.segments, worst);
}

// The interpreter's solvers, keeping no plan of their own, as compiled
// kernels: the engine asks EngineOptions::restart_plans.
struct PlanlessSolver : testing::ForwardingSolver {
    const RestartPlan* restart_plan() const override { return nullptr; }
};

bool same_bits(const std::vector<testing::Recorded>& a, const std::vector<testing::Recorded>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k)
        if (a[k].t != b[k].t || a[k].kind != b[k].kind || a[k].element != b[k].element || a[k].x != b[k].x ||
            a[k].v != b[k].v)
            return false;
    return true;
}

// A forced chain of 20 masses with friction on each and three contacts
// (bench/bench_common.h friction_chain): contacts open and close, masses
// stick and release, and in between the sliding masses reverse.
std::string friction_chain_20(const std::string& beta = "0.002") {
    const int n = 20;
    auto name = [](int i) { return "m" + std::to_string(i); };
    std::string t = "name = \"chain-20\"\n[damping]\nbeta = " + beta + "\n";
    for (int i = 1; i <= n; ++i) t += "[[mass]]\nname = \"" + name(i) + "\"\nm = 1\nmu_k = 0.05\nmu_s = 0.07\n";
    t += "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 400\n";
    for (int i = 1; i < n; ++i) t += "[[spring]]\nbetween = [\"" + name(i) + "\", \"" + name(i + 1) + "\"]\nk = 400\n";
    t += "[[spring]]\nbetween = [\"m20\", \"ground\"]\nk = 400\n";
    t += "[[contact]]\nbetween = [\"m5\", \"m6\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m10\", \"m11\"]\ngap = 0.01\nk = 4000\n";
    t += "[[contact]]\nbetween = [\"m15\", \"ground\"]\ngap = 0.02\nk = 4000\n";
    t += "[[forcing]]\nomega = 9.0\namplitude = { m1 = 30.0, m20 = -20.0 }\n";
    return t + "[initial]\nv = { m10 = 1.0 }\n";
}

TEST(RestartEngine, TheSolversPlanAndTheSourcesGiveTheSameBits) {
    const Model m = parse_model(friction_chain_20(), "chain-20.toml");
    InterpretedSolverProvider own(program_source(m)), programs(program_source(m));
    testing::ForwardingProvider<PlanlessSolver> planless(programs);
    const testing::Outcome a = testing::run_engine(m, own, 10.0, 0.05, kScheduleFrom, restart_plan_source(m));
    const testing::Outcome b = testing::run_engine(m, planless, 10.0, 0.05, kScheduleFrom, restart_plan_source(m));
    ASSERT_EQ(a.summary.status, RunStatus::ok) << a.summary.message;
    EXPECT_GT(a.summary.restarts, a.summary.segments / 2);
    EXPECT_EQ(a.summary.restarts, b.summary.restarts);
    EXPECT_TRUE(same_bits(a.events, b.events));
    EXPECT_TRUE(same_bits(a.samples, b.samples));
    // Without a plan source nothing restarts, whatever the solver keeps.
    EXPECT_EQ(testing::run_engine(m, own, 1.0).summary.restarts, 0u);
}

// What a carried segment's start takes from the event (engine.cpp): every
// function's g and g' but those it lists for eval_start. A solver in front
// of the interpreter keeps the last full evaluation's (the event's: no
// samples in between) and, at each carried start, compares the new
// segment's own values at 0 with them for the functions not listed: they
// must be continuous. The velocities of the masses whose friction flipped
// must be listed: their g' jumps by 2 mu_k N / m.
struct ContinuityCheck : testing::ForwardingSolver {
    mutable std::vector<double> g, dg, scale;
    mutable double worst_g = 0, worst_dg = 0;
    mutable std::size_t starts = 0, listed = 0;
    void eval(double tau, const SegmentEval& out) const override {
        inner->eval(tau, out);
        const std::size_t ns = switches().size();
        g.assign(out.g, out.g + ns), dg.assign(out.dg, out.dg + ns), scale.assign(out.scale, out.scale + ns);
    }
    void eval_start(double tau, const std::uint32_t* which, std::size_t count, const SegmentEval& out) const override {
        const std::size_t ns = switches().size();
        std::vector<double> x(state_size), v(state_size), a(state_size), g0(ns), dg0(ns), b0(ns), s0(ns);
        inner->eval(tau, {x.data(), v.data(), a.data(), g0.data(), dg0.data(), b0.data(), s0.data()});
        std::vector<char> in(ns, 0);
        for (std::size_t k = 0; k < count; ++k) in[which[k]] = 1;
        for (std::size_t f = 0; f < ns; ++f) {
            if (in[f]) continue;
            worst_g = std::max(worst_g, std::fabs(g0[f] - g[f]) / (scale[f] + 1e-300));
            worst_dg = std::max(worst_dg, std::fabs(dg0[f] - dg[f]) / (std::fabs(dg[f]) + 1e-3));
        }
        ++starts, listed += count;
        inner->eval_start(tau, which, count, out);
    }
    std::size_t state_size = 0;  ///< Model::state_size(): x, v and a are at most that long
};

TEST(RestartEngine, WhatACarriedStartTakesFromTheEventIsContinuous) {
    for (const std::string& text : {friction_chain_20(), friction_chain_20("0.08")}) {
        const Model m = parse_model(text, "chain-20.toml");
        InterpretedSolverProvider programs(program_source(m));
        testing::ForwardingProvider<ContinuityCheck> check(programs);
        check.front().state_size = m.state_size();
        const testing::Outcome r = testing::run_engine(m, check, 2.0, 0.0, kScheduleFrom, restart_plan_source(m));
        ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
        const ContinuityCheck& c = check.front();
        EXPECT_EQ(c.starts, r.summary.restarts);
        EXPECT_GT(c.starts, 50u);
        EXPECT_GE(c.listed, c.starts);  // at least the reversing mass's velocity each time
        EXPECT_LT(c.worst_g, 1e-12);
        EXPECT_LT(c.worst_dg, 1e-10);
        std::printf("[ restart  ] %zu carried starts, %zu functions listed: the others' g within %.1e of their scale, "
                    "g' within %.1e\n", c.starts, c.listed, c.worst_g, c.worst_dg);
    }
}

// With light damping every mode is underdamped; with beta = 0.08 the modes
// above 25 rad/s are overdamped (restart.cpp's scalar branch).
TEST(RestartEngine, RestartsAgreeWithSetupToRounding) {
    for (const std::string beta : {"0.002", "0.08"}) {
        const Model m = parse_model(friction_chain_20(beta), "chain-20.toml");
        std::size_t overdamped = 0;
        for (const Mode& mode : derive(m, Configuration::all_open(m)).modes) overdamped += mode.regime == Regime::overdamped;
        if (beta == "0.08") EXPECT_GT(overdamped, 0u);
        InterpretedSolverProvider programs(program_source(m));
        const testing::Outcome carried = testing::run_engine(m, programs, 2.0, 0.01, kScheduleFrom, restart_plan_source(m));
        const testing::Outcome set_up = testing::run_engine(m, programs, 2.0, 0.01);
        ASSERT_EQ(carried.summary.status, RunStatus::ok) << carried.summary.message;
        ASSERT_EQ(set_up.summary.status, RunStatus::ok) << set_up.summary.message;
        EXPECT_GT(carried.summary.restarts, 50u) << beta;
        EXPECT_EQ(set_up.summary.restarts, 0u);
        ASSERT_EQ(carried.events.size(), set_up.events.size()) << beta;
        double worst_t = 0, worst_x = 0, top = 0;
        for (std::size_t k = 0; k < carried.events.size(); ++k) {
            EXPECT_EQ(carried.events[k].kind, set_up.events[k].kind) << k;
            EXPECT_EQ(carried.events[k].element, set_up.events[k].element) << k;
            worst_t = std::max(worst_t, std::fabs(carried.events[k].t - set_up.events[k].t));
        }
        ASSERT_EQ(carried.samples.size(), set_up.samples.size());
        for (std::size_t k = 0; k < carried.samples.size(); ++k)
            for (std::size_t i = 0; i < m.dof(); ++i) {
                top = std::max(top, std::fabs(set_up.samples[k].x[i]));
                worst_x = std::max(worst_x, std::fabs(carried.samples[k].x[i] - set_up.samples[k].x[i]));
            }
        EXPECT_LT(worst_t, 1e-12) << beta;
        EXPECT_LT(worst_x, 1e-12 * top) << beta;
        std::printf("[ restart  ] chain-20, beta %s (%zu overdamped modes) over 2 s, %zu of %zu segments carried "
                    "over: event times within %.1e s, x within %.1e of max|x|\n", beta.c_str(), overdamped,
                    carried.summary.restarts, carried.summary.segments, worst_t, worst_x / top);
    }
}

// Random chains of 20 masses (tests/random_model.h: random springs,
// contacts, friction on about half of them, Rayleigh damping from none to
// heavy, one or two harmonics, loads): carried over and set up, the runs'
// events agree to rounding over 3 s, whatever the regimes and forces.
TEST(RestartEngine, RandomChainsAgreeWithSetUpRuns) {
    std::size_t carried_total = 0, compared = 0;
    for (unsigned seed = 1; seed <= 8; ++seed) {
        const testing::Drawn d = testing::draw(7100 + seed, 20);
        const Model& m = d.model;
        InterpretedSolverProvider programs(program_source(m));
        const double t_end = m.t0 + 3.0;
        const testing::Outcome carried = testing::run_engine(m, programs, t_end, 0.0, kScheduleFrom, restart_plan_source(m));
        const testing::Outcome set_up = testing::run_engine(m, programs, t_end);
        ASSERT_EQ(carried.summary.status, set_up.summary.status) << seed;
        carried_total += carried.summary.restarts;
        ASSERT_EQ(carried.events.size(), set_up.events.size()) << "seed " << seed;
        double worst = 0;
        for (std::size_t k = 0; k < carried.events.size(); ++k) {
            ASSERT_EQ(carried.events[k].kind, set_up.events[k].kind) << "seed " << seed << " event " << k;
            ASSERT_EQ(carried.events[k].element, set_up.events[k].element) << "seed " << seed << " event " << k;
            worst = std::max(worst, std::fabs(carried.events[k].t - set_up.events[k].t));
        }
        EXPECT_LT(worst, 1e-12) << "seed " << seed;
        compared += carried.events.size();
        std::printf("[ restart  ] random chain %u: %zu events, %zu of %zu segments carried over, times within %.1e s\n",
                    seed, carried.events.size(), carried.summary.restarts, carried.summary.segments, worst);
    }
    EXPECT_GT(carried_total, 100u);
    EXPECT_GT(compared, 500u);
}

}  // namespace
}  // namespace hsnc
