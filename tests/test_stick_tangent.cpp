// The tangent dynamics of models with stick elements (analysis/stick_tangent.h):
// Jenkins elements (the slider is state: z = (x, v, s)) and friction between
// two bodies (a stuck pair moves as one body). The Jacobian of the flow map
// over runs with releases and sticks of both, J = S_k Phi_k ... S_1 Phi_1,
// against central differences of the exact engine, column by column; the
// Floquet multipliers of the friction damper's orbit against its Lyapunov
// spectrum; and the command line's outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "hsnc/lyapunov.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "jacobian_check.h"
#include "kernel_mode.h"
#include "model_reader.h"
#include "tangent.h"

namespace hsnc {
namespace {

using testing::expect_jacobian_matches;

Model example(const std::string& path) {
    return read_model(std::string(HSNC_SOURCE_DIR) + "/examples/" + path);
}

TEST(StickTangent, JenkinsRunsJacobianMatchesFiniteDifferences) {
    // The blade with its friction damper: releases and sticks of the element.
    EXPECT_EQ(expect_jacobian_matches(example("jenkins/friction_damper.toml"), 3.0, 1e-6, 2e-6, 6), 5);
    // Two elements (the under-platform damper), one made to slip later than the other so
    // that a perturbation cannot swap the order of their switches.
    Model up = example("jenkins/under_platform_damper.toml");
    up.jenkins[1].slip_force *= 1.3;
    EXPECT_EQ(expect_jacobian_matches(up, 2.5, 1e-6, 2e-6, 6), 12);
}

TEST(StickTangent, FrictionPairRunsJacobianMatchesFiniteDifferences) {
    // The load on a shaking table: the pair releases and sticks again. Started sliding
    // (stuck at the start, a velocity perturbation of one block alone is a slip of
    // its own: not differentiable there).
    Model m = example("friction/stacked_blocks.toml");
    m.v0[1] += 0.05;
    EXPECT_EQ(expect_jacobian_matches(m, 1.2, 1e-6, 2e-6, 6), 4);
}

// Floquet multipliers mu of the friction damper's stable orbit and the
// Lyapunov spectrum of the motion that settles on it: lambda = log|mu| / T,
// and the slider's direction, slaved to x while it slips, is a multiplier 0
// and an exponent -inf (a direction a release collapses).
TEST(StickTangent, FrictionDamperFloquetMultipliersAreItsLyapunovExponents) {
    const Model m = example("jenkins/friction_damper.toml");
    PeriodicOptions po;
    po.transient = 30.0;
    po.kernels = KernelChoice::generic;
    const PeriodicResult orbit = periodic(m, po);
    ASSERT_EQ(orbit.status, PeriodicStatus::ok) << orbit.message;
    ASSERT_EQ(orbit.multipliers.size(), 5u);
    ASSERT_EQ(orbit.s.size(), 1u);
    EXPECT_TRUE(orbit.stable);
    EXPECT_LT(std::abs(orbit.multipliers.back()), 1e-12);
    LyapunovOptions lo;
    lo.transient = 30.0;
    lo.t_end = 3000.0;
    lo.kernels = KernelChoice::generic;
    const LyapunovResult ly = lyapunov(m, lo);
    ASSERT_EQ(ly.status, RunStatus::ok) << ly.message;
    ASSERT_EQ(ly.exponents.size(), 5u);
    EXPECT_EQ(ly.exponents[4], -INFINITY);
    for (std::size_t k = 0; k < 4; ++k) {
        const double expected = std::log(std::abs(orbit.multipliers[k])) / orbit.period;
        std::printf("lambda_%zu = %.6f, log|mu_%zu| / T = %.6f\n", k + 1, ly.exponents[k], k + 1, expected);
        EXPECT_NEAR(ly.exponents[k], expected, 0.005 * std::fabs(expected));  // measured 0.24% at most
    }
}

// The continuation of the friction damper's orbit over the forcing frequency
// (y = (x, v, s)): every point is an orbit that hsnc::periodic finds again from
// a transient at that frequency, with the same largest multiplier. Where the
// damper slips the orbit is stable; above about 10.43 rad/s it stays stuck all
// period, its slider is neutral (the orbit at another slider offset is an
// orbit too: a multiplier 1 to rounding, a family's: left out of stability,
// docs/interface.md) and the orbit is stable too.
TEST(StickTangent, ContinuationOfTheFrictionDamperFollowsItsOrbits) {
    SweepOptions o;
    o.param = "omega";
    o.from = 8.0;
    o.to = 12.0;
    o.points = 5;
    o.continuation = true;
    o.max_periods = 3000;
    const std::string path = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml";
    const SweepResult r = SweepPlan::from_file(path, {}, o).run();
    ASSERT_GE(r.points.size(), 5u);
    EXPECT_EQ(r.points.back().value, 12.0);
    std::size_t checked = 0, slipping = 0, neutral = 0;
    for (const SweepPoint& p : r.points) {
        const bool stuck_all_period = std::fabs(p.max_multiplier - 1.0) < 1e-12;
        EXPECT_TRUE(p.stable) << p.value;
        (stuck_all_period ? neutral : slipping) += 1;
    }
    EXPECT_GT(slipping, 0u);
    EXPECT_GT(neutral, 0u);
    for (std::size_t k = 0; k < r.points.size(); k += r.points.size() / 4) {
        const SweepPoint& p = r.points[k];
        SCOPED_TRACE("omega = " + std::to_string(p.value));
        EXPECT_EQ(p.failure, "");
        char text[64];
        std::snprintf(text, sizeof text, "omega=%.17g", p.value);
        ModelOverrides set;
        set.set.emplace_back(text);
        const Model m = read_model(path, set);
        PeriodicOptions po;
        po.transient = 40.0;
        po.kernels = KernelChoice::generic;
        const PeriodicResult orbit = periodic(m, po);
        ASSERT_EQ(orbit.status, PeriodicStatus::ok) << orbit.message;
        EXPECT_NEAR(p.max_multiplier, orbit.max_multiplier, 1e-8);
        ++checked;
    }
    EXPECT_GE(checked, 4u);
}

TEST(StickTangentCli, PeriodicAndLyapunovCarryTheSlider) {
    const std::string model = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml";
    const std::string mu = testing::temp_path("stick-mu.csv");
    const testing::CliRun p = testing::run_hsnc("periodic " + model + " --transient 30 --multipliers " + mu);
    ASSERT_EQ(p.exit_code, 0) << p.err;
    EXPECT_NE(p.out.find(" s_damper="), std::string::npos) << p.out;
    EXPECT_NE(p.out.find("stable=true"), std::string::npos) << p.out;
    std::ifstream in(mu);
    std::string line;
    int rows = -1;
    while (std::getline(in, line)) ++rows;
    EXPECT_EQ(rows, 5) << "2 per mass, 1 per Jenkins element";
    const testing::CliRun l = testing::run_hsnc("lyapunov " + model + " --t-end 20");
    ASSERT_EQ(l.exit_code, 0) << l.err;
    EXPECT_NE(l.out.find(" lambda_5=-inf"), std::string::npos) << l.out;
    // The load on the table rides at any offset: a neutral multiplier (1 to rounding, a
    // family's), left out of stability whichever side of 1 rounding puts it.
    const std::string pair = std::string(HSNC_SOURCE_DIR) + "/examples/friction/stacked_blocks.toml";
    const testing::CliRun q = testing::run_hsnc("periodic " + pair + " --transient 10");
    ASSERT_EQ(q.exit_code, 0) << q.err;
    EXPECT_NE(q.out.find("status=ok"), std::string::npos) << q.out;
    EXPECT_NE(q.out.find("stable=true max_multiplier=0.99999999999"), std::string::npos) << q.out;
    EXPECT_NE(q.out.find(" neutral=1\n"), std::string::npos) << q.out;
}

}  // namespace
}  // namespace hsnc
