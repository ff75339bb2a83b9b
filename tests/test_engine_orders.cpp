// Several commensurate forcing frequencies (engine orders, issue 38 item 6):
// `periodic` and `sweep` take the forcing's common period, 2 pi / omega0 with
// omega0 the largest frequency of which every harmonic's is a whole multiple.
//
// The truths: the fundamental of given frequency sets; a periodic orbit under
// omega and 2 omega against a long simulation that settles onto it, on every
// kernel kind and the reference; a sweep over a parameter that moves both.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "model.h"
#include "model_reader.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

Model forced(const std::vector<double>& omegas) {
    Model m;
    m.masses.push_back(Mass{});
    for (double w : omegas) m.forcing.push_back({w, 0.0, {1.0}});
    return m;
}

TEST(EngineOrders, TheFundamentalIsTheLargestCommonDivisorOfTheFrequencies) {
    EXPECT_EQ(forcing_fundamental(forced({3.0})), 3.0);
    EXPECT_EQ(forcing_fundamental(forced({3.0, 3.0})), 3.0);
    EXPECT_EQ(forcing_fundamental(forced({5.0, 10.0, 15.0})), 5.0);
    EXPECT_EQ(forcing_fundamental(forced({4.0, 6.0})), 2.0);           // orders 2 and 3 of 2 rad/s
    EXPECT_NEAR(forcing_fundamental(forced({0.3, 0.7})), 0.1, 1e-16);  // 3 and 7 times 0.1
    EXPECT_NEAR(forcing_period(forced({4.0, 6.0})), M_PI, 1e-15);
    EXPECT_TRUE(std::isnan(forcing_fundamental(forced({1.0, std::sqrt(2.0)}))));  // quasi-periodic
    EXPECT_TRUE(std::isnan(forcing_fundamental(forced({1.0, 1001.0}))));          // beyond order 1000
    EXPECT_TRUE(std::isnan(forcing_fundamental(forced({}))));
}

// A stop and a spring, heavily damped, driven at omega and 2 omega (a
// rotor's unbalance and its second order).
std::string two_orders() {
    return R"(name = "two-orders"
[parameters]
omega = 9.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 100.0
[[contact]]
name = "stop"
between = ["m", "ground"]
gap = 0.02
k = 900.0
[damping]
alpha = 3.0
[[forcing]]
omega = "omega"
amplitude = { m = 3.0 }
[[forcing]]
omega = "2 * omega"
phase = 0.4
amplitude = { m = 2.0 }
)";
}

TEST(EngineOrders, APeriodicOrbitUnderTwoOrdersIsWhereALongRunSettles) {
    const Model model = parse_model(two_orders(), "two-orders.toml");
    const double T = 2 * M_PI / 9.0;
    ASSERT_NEAR(forcing_period(model), T, 1e-16);
    PeriodicResult orbit;
    for (KernelChoice k : {KernelChoice::generic, KernelChoice::eigen}) {
        PeriodicOptions o;
        o.kernels = k;
        o.tolerance = 1e-13;
        const PeriodicResult r = periodic(model, o);
        ASSERT_EQ(r.status, PeriodicStatus::ok) << r.message;
        EXPECT_NEAR(r.period, T, 1e-15);
        EXPECT_TRUE(r.stable);
        EXPECT_GE(r.events, 2u);  // the stop closes and opens once a period at least
        if (k == KernelChoice::generic)
            orbit = r;
        else
            EXPECT_NEAR(r.x[0], orbit.x[0], 1e-12);
    }
    // alpha = 3: the start decays as exp(-1.5 t); after 40 periods (28 s) by 1e-18.
    for (int digits : {0, 30}) {
        SimulateOptions s;
        s.t_end = orbit.t + 40 * T;
        s.precision_digits = digits;
        const SimulateSummary end = simulate(model, s);
        ASSERT_EQ(end.status, RunStatus::ok) << end.message;
        EXPECT_NEAR(end.x[0], orbit.x[0], 1e-11) << digits;
        EXPECT_NEAR(end.v[0], orbit.v[0], 1e-10) << digits;
    }
}

TEST(EngineOrders, ASweepMovesBothOrdersAndIncommensurateOnesAreRefused) {
    testing::TempDir dir;
    const std::string model = dir / "two-orders.toml", out = dir / "curve.csv";
    {
        std::FILE* f = std::fopen(model.c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs(two_orders().c_str(), f);
        std::fclose(f);
    }
    const testing::CliRun r =
        testing::run_hsnc("sweep '" + model + "' --param omega --from 8 --to 10 --points 3 --out '" + out + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("status=ok points=3"), std::string::npos) << r.out;
    const std::string curve = testing::slurp(out);
    EXPECT_NE(curve.find("\n9,up,true,"), std::string::npos) << curve;
    // omega and sqrt(2) omega have no common period: refused by what they are.
    std::FILE* f = std::fopen(model.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::string text = two_orders();
    text.replace(text.find("\"2 * omega\""), 11, "\"sqrt(2) * omega\"");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    const testing::CliRun q =
        testing::run_hsnc("sweep '" + model + "' --param omega --from 8 --to 10 --points 3 --out '" + out + "'");
    EXPECT_EQ(q.exit_code, 2) << q.err;
    EXPECT_NE(q.err.find("are not commensurate"), std::string::npos) << q.err;
    const testing::CliRun p = testing::run_hsnc("periodic '" + model + "'");
    EXPECT_EQ(p.exit_code, 2) << p.err;
    EXPECT_NE(p.err.find("not commensurate"), std::string::npos) << p.err;
}

}  // namespace
}  // namespace hsnc
