// The high-precision reference engine (reference/reference.h) against closed
// forms evaluated independently at full precision, against itself at N and 2N
// digits, and the double engine against it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <cln/float.h>
#include <cln/real.h>

#include "engine_runner.h"
#include "error.h"
#include "model_reader.h"
#include "reference_engine.h"

namespace hsnc {
namespace {

using cln::cl_F;
using reference::PreciseRun;
using reference::relative_difference;
using reference::simulate_precise;
using testing::Recorder;

Model model_from(const std::string& toml) { return parse_model(toml, "test.toml"); }
Model bundled(const std::string& name) { return read_model(std::string(HSNC_SOURCE_DIR) + "/models/" + name); }

PreciseRun run_at(const Model& m, int digits, double t_end, std::size_t max_events = 0) {
    Recorder rec(m.dof());
    EngineOptions opt;
    opt.t_end = t_end;
    opt.samples = false;
    opt.max_events = max_events;
    return simulate_precise(m, digits, opt, rec);
}

// Exact conversion of a double at the precision of `like`.
cl_F F(double d, const cl_F& like) { return cln::cl_float(d, like); }

// m x'' + k x = -mu m g sign(x'), omega = 10, released from x = 0.2: half-cycles
// of pi/omega centred on -+x_e = mu g/omega^2; the extreme drops by 2 x_e each.
constexpr const char* kCoulomb = R"(
name = "coulomb"
[[mass]]
name = "m1"
m = 1
mu_k = 0.1
[[spring]]
between = ["ground", "m1"]
k = 100
[initial]
x = { m1 = 0.2 }
)";

TEST(ReferenceClosedForm, CoulombDecayAt40Digits) {
    const Model m = model_from(kCoulomb);
    const PreciseRun r = run_at(m, 40, 5.0);
    ASSERT_EQ(r.summary.status, RunStatus::ok) << r.summary.message;
    ASSERT_EQ(r.events.size(), 10u);
    const cl_F one = cln::cl_float(1, cln::float_format(40));
    const cl_F pi = cln::pi(one), omega = F(10.0, one);
    const cl_F xe = F(0.1, one) * F(9.81, one) / (omega * omega);  // the model's doubles, exactly
    double worst_t = 0, worst_x = 0;
    for (int k = 1; k <= 10; ++k) {
        const auto& e = r.events[static_cast<std::size_t>(k - 1)];
        EXPECT_EQ(e.kind, k < 10 ? EventKind::reversal : EventKind::stick) << k;
        const cl_F t = pi * F(k, one) / omega;
        cl_F x = F(0.2, one) - F(2.0 * k, one) * xe;
        if (k % 2) x = -x;
        worst_t = std::max(worst_t, relative_difference(e.t, t));
        worst_x = std::max(worst_x, relative_difference(e.x[0], x));
        EXPECT_TRUE(cln::zerop(e.v[0]));
    }
    EXPECT_LT(worst_t, 1e-36);
    EXPECT_LT(worst_x, 1e-35);
    std::printf("coulomb 40 digits: max rel error reversal times %.2e, extremes %.2e\n", worst_t, worst_x);
}

}  // namespace
}  // namespace hsnc
