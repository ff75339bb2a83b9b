// Tests of restarting a segment at a reversal from its coefficient block
// (runtime/solvers/restart.h): against the Coulomb oscillator's closed form
// over nine half-cycles carried over by restarts alone, and against setup
// from the event state on a damped, forced 8-mass chain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "derivation.h"
#include "interpreted_solver.h"
#include "lowering.h"
#include "model_reader.h"
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
        s.restart(plan, half, t, 0.0, sgn.data(), next.data());
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
            s.restart(plan, tau, t, 0.0, sgn.data(), next.data());
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
// mode does not.
TEST(Restart, PlansOnlyForPlainModes) {
    const Model chain = bundled("chain-8");
    const Derivation stuck = derive(chain, Configuration::parse(chain, "stuck=m4"));
    EXPECT_FALSE(restart_plan(stuck, lower(stuck, ProgramNames::no)).empty());
    const Model rigid = parse_model("name = \"free\"\n[[mass]]\nname = \"m1\"\nm = 1\nmu_k = 0.1\n", "free.toml");
    const Derivation free = derive(rigid, Configuration::all_open(rigid));
    EXPECT_TRUE(restart_plan(free, lower(free, ProgramNames::no)).empty());
}

}  // namespace
}  // namespace hsnc
