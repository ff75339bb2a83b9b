// hsnc sweep --harmonics (api/hsnc/sweep.h): amplitude and phase of the
// first K harmonics of each mass from the exact segments, against the linear
// oscillator's H(omega) and against a Fourier series of a bilinear
// oscillator's periodic orbit written in closed form here (piecewise
// particular + homogeneous solutions, its switch instants found by
// bisection): nothing of hsnc's solvers in the oracle.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "bilinear_closed_form.h"
#include "cli_runner.h"
#include "hsnc/sweep.h"

namespace hsnc {
namespace {

using testing::Bilinear;
using testing::file_exists;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

constexpr double kPi = 3.14159265358979323846;

// x'' + 2 zeta x' + x = F sin(omega t).
const char* const kLinear = R"(
name = "linear"
[parameters]
omega = 1.0
zeta = 0.05
F = 1.0
t0 = 0.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = "2*zeta"
[[forcing]]
omega = "omega"
amplitude = { m = "F" }
[initial]
t0 = "t0"
)";

// x'' + c x' + k(x) x = F sin(omega t): k = 1 for x < 0, 1 + kc for x > 0
// (a stop at the equilibrium).
const std::string kBilinear = testing::bilinear_model(1.0, 0.1, 3.0, 0.3);

SweepOptions one_point(double omega, std::size_t harmonics) {
    SweepOptions o;
    o.param = "omega";
    o.from = omega;
    o.to = omega;
    o.points = 1;
    o.max_periods = 4000;
    o.record_periods = 4;
    o.harmonics = harmonics;
    return o;
}

// x = F |H| sin(omega t + arg H), H = 1/(1 - w^2 + 2 i zeta w): amp1 = F |H|,
// phase1 = arg H whatever the model's t0 (the phase is against sin(omega t)
// of the model's time), amp_k ~ 0 for k > 1, and amp1 is a1.
TEST(SweepHarmonics, LinearOscillatorAmplitudeAndPhaseAreH) {
    for (const double t0 : {0.0, 2.7}) {
        for (const double w : {0.5, 0.97, 1.0, 1.6, 3.0}) {
            SCOPED_TRACE("t0 = " + std::to_string(t0) + ", omega = " + std::to_string(w));
            const SweepResult r =
                SweepPlan(kLinear, "linear.toml", ModelOverrides{{"F=2.5", "t0=" + std::to_string(t0)}, {}, {}, {}},
                          one_point(w, 3))
                    .run();
            ASSERT_EQ(r.harmonics, 3u);
            ASSERT_EQ(r.points.size(), 1u);
            const SweepPoint& p = r.points[0];
            ASSERT_TRUE(p.settled);
            ASSERT_EQ(p.amp.size(), 3u);
            const std::complex<double> H = 1.0 / std::complex<double>(1 - w * w, 0.1 * w);
            EXPECT_NEAR(p.amp[0] / (2.5 * std::abs(H)), 1.0, 1e-8);
            EXPECT_NEAR(p.phase[0], std::arg(H), 1e-8);
            EXPECT_EQ(p.amp[0], p.a1[0]);
            EXPECT_LT(p.amp[1], 1e-8 * p.amp[0]);
            EXPECT_LT(p.amp[2], 1e-8 * p.amp[0]);
            for (double ph : p.phase) EXPECT_TRUE(ph > -kPi && ph <= kPi) << ph;
        }
    }
    // A baseline (its samples on a grid of 1/16 of the third harmonic's
    // period, trapezoidal integrals) gives the same to its own accuracy.
    SweepOptions o = one_point(1.6, 3);
    o.method = Method::rk45;
    const SweepResult r = SweepPlan(kLinear, "linear.toml", {}, o).run();
    const std::complex<double> H = 1.0 / std::complex<double>(1 - 1.6 * 1.6, 0.1 * 1.6);
    EXPECT_NEAR(r.points[0].amp[0] / std::abs(H), 1.0, 1e-6);
    EXPECT_NEAR(r.points[0].phase[0], std::arg(H), 1e-6);
    EXPECT_LT(r.points[0].amp[2], 1e-6 * r.points[0].amp[0]);
}

// The third harmonic (and the first and fifth) of a bilinear orbit against
// the Fourier series of the closed form: its periodic orbit reached by 300
// periods of the closed-form map from rest, then one period's coefficients
// A_k, B_k = 2/T integral x cos, sin(k w t) by 6-point Gauss-Legendre on
// 400 pieces of every switch-free stretch. Agreement: 7e-12 of amp1 (the
// sweep's steady state is settled to 1e-9 of the state, its error decays
// in the recorded periods).
TEST(SweepHarmonics, BilinearOrbitAgainstTheFourierSeriesOfItsClosedForm) {
    const Bilinear bl{1.0, 0.1, 3.0, 0.3};
    const double T = 2 * kPi / bl.w;
    double x = 0, v = 0;
    bl.run(0.0, x, v, 300 * T, [](const Bilinear::Piece&, double, double) {});
    const double t0 = 300 * T;
    std::vector<double> A(6, 0.0), B(6, 0.0);
    const double gx[6] = {-0.93246951420315202781, -0.66120938646626451366, -0.23861918608319690863,
                          0.23861918608319690863,  0.66120938646626451366,  0.93246951420315202781};
    const double gw[6] = {0.17132449237917034504, 0.36076157304813860757, 0.46791393457269104739,
                          0.46791393457269104739, 0.36076157304813860757, 0.17132449237917034504};
    double xe = x, ve = v;
    bl.run(t0, xe, ve, t0 + T, [&](const Bilinear::Piece& p, double a, double b) {
        const int pieces = 400;
        for (int j = 0; j < pieces; ++j) {
            const double lo = a + (b - a) * j / pieces, hi = a + (b - a) * (j + 1) / pieces;
            for (int q = 0; q < 6; ++q) {
                const double t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * gx[q], wq = 0.5 * (hi - lo) * gw[q];
                double xt, vt;
                bl.eval(p, t, xt, vt);
                for (int k = 1; k <= 5; ++k) {
                    A[k] += wq * xt * std::cos(k * bl.w * t) * 2 / T;
                    B[k] += wq * xt * std::sin(k * bl.w * t) * 2 / T;
                }
            }
        }
    });
    // The orbit is periodic to the oracle's own accuracy.
    ASSERT_NEAR(xe, x, 1e-12);
    ASSERT_NEAR(ve, v, 1e-12);

    SweepOptions o = one_point(1.0, 5);
    o.max_periods = 3000;
    const SweepResult r = SweepPlan(kBilinear, "bilinear.toml", {}, o).run();
    ASSERT_EQ(r.points.size(), 1u);
    const SweepPoint& p = r.points[0];
    ASSERT_TRUE(p.settled);
    ASSERT_EQ(p.multiple, 1);
    const double amp1 = std::hypot(A[1], B[1]);
    for (int k = 1; k <= 5; ++k) {
        SCOPED_TRACE("harmonic " + std::to_string(k));
        const double amp = std::hypot(A[k], B[k]), phase = std::atan2(A[k], B[k]);
        EXPECT_NEAR(p.amp[k - 1], amp, 5e-11 * amp1);
        if (amp > 1e-3 * amp1) {
            EXPECT_NEAR(p.phase[k - 1], phase, 5e-11 * amp1 / amp);
        }
    }
    // The third harmonic is there (the stop's asymmetry makes the even ones too).
    EXPECT_GT(std::hypot(A[3], B[3]), 1e-3 * amp1);
    EXPECT_GT(std::hypot(A[2], B[2]), 1e-3 * amp1);
}

// The CLI: columns amp<k>_<mass>,phase<k>_<mass> at the end (after the
// continuation's), the same numbers as the library; parts merged give the
// same bytes; a bad count is bad input.
TEST(SweepHarmonics, CommandLineColumnsPartsAndRefusals) {
    const std::string model = write_temp("bilinear.toml", kBilinear);
    const std::string args = "sweep '" + model +
                             "' --param omega --from 0.9 --to 1.1 --points 3 --max-periods 3000 --record-periods 2 "
                             "--quiet --harmonics 3 ";
    const std::string a = temp_path("a.csv");
    const auto whole = run_hsnc(args + "--out '" + a + "'");
    ASSERT_EQ(whole.exit_code, 0) << whole.err;
    const std::string text = slurp(a);
    ASSERT_EQ(text.substr(0, text.find('\n')),
              "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m,amp1_m,phase1_m,amp2_m,phase2_m,amp3_m,"
              "phase3_m");
    SweepOptions o;
    o.param = "omega";
    o.from = 0.9;
    o.to = 1.1;
    o.points = 3;
    o.max_periods = 3000;
    o.record_periods = 2;
    o.harmonics = 3;
    const SweepResult r = SweepPlan(kBilinear, model, {}, o).run();
    // Row 2 (omega 1): its amp3 and phase3 as the library's, to the digit.
    std::size_t at = text.find('\n') + 1;
    at = text.find('\n', at) + 1;
    const std::string row = text.substr(at, text.find('\n', at) - at);
    std::vector<double> cells;
    for (std::size_t b = 0, e; b < row.size(); b = e + 1) {
        e = row.find(',', b);
        if (e == std::string::npos) e = row.size();
        cells.push_back(std::strtod(row.substr(b, e - b).c_str(), nullptr));
    }
    ASSERT_EQ(cells.size(), 14u) << row;
    EXPECT_EQ(cells[12], r.points[1].amp[2]);
    EXPECT_EQ(cells[13], r.points[1].phase[2]);

    // Two parts merged: the whole run's bytes.
    const std::string p1 = temp_path("h1"), p2 = temp_path("h2"), m = temp_path("m.csv");
    ASSERT_EQ(run_hsnc(args + "--restart-each --part 1/2 --part-out '" + p1 + "'").exit_code, 0);
    ASSERT_EQ(run_hsnc(args + "--restart-each --part 2/2 --part-out '" + p2 + "'").exit_code, 0);
    const std::string b = temp_path("b.csv");
    ASSERT_EQ(run_hsnc(args + "--restart-each --out '" + b + "'").exit_code, 0);
    const auto merged = run_hsnc("sweep-merge '" + p2 + "' '" + p1 + "' --out '" + m + "'");
    ASSERT_EQ(merged.exit_code, 0) << merged.err;
    EXPECT_EQ(slurp(m), slurp(b));

    for (const std::string& bad : {std::string("-1"), std::string("1001"), std::string("two")}) {
        const std::string out = temp_path("bad.csv");
        const auto e =
            run_hsnc("sweep '" + model + "' --param omega --from 0.9 --to 1.1 --points 3 --quiet --harmonics " + bad +
                     " --out '" + out + "'");
        EXPECT_EQ(e.exit_code, 2) << bad;
        EXPECT_NE(e.err.find("--harmonics"), std::string::npos) << e.err;
        EXPECT_FALSE(file_exists(out));
    }
}

}  // namespace
}  // namespace hsnc
