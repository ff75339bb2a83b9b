// The quasi-periodic diagnostic (issue 38 item 6): the stroboscopic section
// of `hsnc simulate --section period[:OMEGA]` and its rotation number
// (hsnc::rotation_number, a weighted Birkhoff average).
//
// The truths: points turning by a known angle on an ellipse; a p-cycle's
// q/p; a linear oscillator under omega and sqrt(2) omega, whose section lies
// on an ellipse turning by sqrt(2) - 1 of a turn per period and whose points
// are the closed-form steady response at t = 2 pi k (the 30-digit reference
// and CVODE, independent integrators, agree); the bilinear cascade's
// period-3 orbit (2/3) and chaotic set (an error near 1/sqrt(n), not
// rounding); a stop under two incommensurate frequencies against CVODE.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "hsnc/periodic.h"

namespace hsnc {
namespace {

using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

// `key=` of a summary line, as a number (NaN when absent).
double summary_value(const std::string& line, const std::string& key) {
    const std::size_t at = line.find(" " + key + "=");
    return at == std::string::npos ? NAN : std::strtod(line.c_str() + at + key.size() + 2, nullptr);
}

// The rows of a section CSV (after its header): t, x..., v... each.
std::vector<std::vector<double>> csv_rows(const std::string& path) {
    std::istringstream in(slurp(path));
    std::string line;
    std::getline(in, line);
    std::vector<std::vector<double>> rows;
    while (std::getline(in, line)) {
        std::vector<double> row;
        std::istringstream cells(line);
        std::string cell;
        while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
        rows.push_back(row);
    }
    return rows;
}

TEST(RotationNumber, PointsTurningOnAnEllipseAndCycles) {
    // Clockwise in (x, v) by rho of a turn per step, on an ellipse about (3, -1).
    for (const double rho : {0.5 * (std::sqrt(5.0) - 1.0), 0.1, std::sqrt(2.0) - 1.0}) {
        std::vector<double> x, v;
        for (int k = 0; k < 2000; ++k) {
            const double a = 2 * M_PI * rho * k + 0.3;
            x.push_back(3 + 0.2 * std::cos(a));
            v.push_back(-1 - 5.0 * std::sin(a));
        }
        const RotationNumber r = rotation_number(x.data(), v.data(), x.size());
        EXPECT_NEAR(r.value, rho, 1e-13);
        EXPECT_LT(r.error, 1e-12);
        // The same points read with a stride (a section's rows hold every dof).
        std::vector<double> rows;
        for (std::size_t k = 0; k < x.size(); ++k) rows.insert(rows.end(), {0.0, x[k], v[k]});
        EXPECT_EQ(rotation_number(rows.data() + 1, rows.data() + 2, x.size(), 3).value, r.value);
    }
    // A 5-cycle that advances two fifths of a turn each step: 2/5.
    std::vector<double> x, v;
    for (int k = 0; k < 500; ++k) {
        x.push_back(std::cos(2 * M_PI * 2 * k / 5.0));
        v.push_back(-std::sin(2 * M_PI * 2 * k / 5.0));
    }
    EXPECT_NEAR(rotation_number(x.data(), v.data(), x.size()).value, 0.4, 1e-14);
    // Counter-clockwise by 2/5: 3/5 of a turn clockwise.
    for (double& s : v) s = -s;
    EXPECT_NEAR(rotation_number(x.data(), v.data(), x.size()).value, 0.6, 1e-14);
    // Too few points, a fixed point, a dof that does not move: no number.
    EXPECT_TRUE(std::isnan(rotation_number(x.data(), v.data(), 7).value));
    const std::vector<double> still(100, 1.25);
    EXPECT_TRUE(std::isnan(rotation_number(still.data(), still.data(), still.size()).value));
    EXPECT_TRUE(std::isnan(rotation_number(x.data(), still.data(), still.size()).value));
    // Points at random: an error far from rounding.
    std::vector<double> rx, rv;
    unsigned seed = 12345;
    for (int k = 0; k < 2000; ++k) {
        seed = seed * 1103515245u + 12345u;
        rx.push_back(std::cos(seed * 1e-3));
        rv.push_back(std::sin(seed * 7e-3));
    }
    EXPECT_GT(rotation_number(rx.data(), rv.data(), rx.size()).error, 1e-4);
}

// m x'' + c x' + k x = sin(t) + 0.5 sin(sqrt(2) t), m = k = c = 1: its steady
// response at t = 2 pi k lies on an ellipse about the 1 rad/s term's point,
// turned by sqrt(2) 2 pi each period.
const char* kTwoTone = R"(name = "two_tone"
[parameters]
w2 = 1.4142135623730951
[simulate]
t_end = 8000.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["m", "ground"]
k = 1.0
[damping]
alpha = 1.0
[[forcing]]
omega = 1.0
amplitude = { m = 1.0 }
[[forcing]]
omega = "w2"
amplitude = { m = 0.5 }
)";

// The closed-form steady state of kTwoTone at t: sum of Im(F H(w) e^{i w t}), H = 1/(k - w^2 + i c w).
void two_tone_state(double t, double* x, double* v) {
    *x = *v = 0;
    for (const auto& [w, F] : {std::pair{1.0, 1.0}, std::pair{std::sqrt(2.0), 0.5}}) {
        const std::complex<double> z =
            F / std::complex<double>(1 - w * w, w) * std::exp(std::complex<double>(0, w * t));
        *x += z.imag();
        *v += (std::complex<double>(0, w) * z).imag();
    }
}

TEST(QuasiPeriodic, TwoToneLinearOscillatorTurnsBySqrt2) {
    const std::string model = write_temp("two_tone.toml", kTwoTone), section = temp_path("two_tone_section.csv");
    const double rho = std::sqrt(2.0) - 1.0;
    double exact = NAN;
    for (const std::string& how : {std::string(""), std::string(" --precision mp:30"),
                                   std::string(" --method cvode --rtol 1e-12 --atol 1e-14")}) {
        const auto r = run_hsnc("simulate '" + model + "' --section period:1 --section-out '" + section + "'" + how);
        ASSERT_EQ(r.exit_code, 0) << how << r.err;
        const double value = summary_value(r.out, "rotation"), error = summary_value(r.out, "rotation_error");
        EXPECT_NEAR(value, rho, how.find("cvode") != std::string::npos ? 1e-9 : 1e-13) << how;
        EXPECT_LT(error, 1e-11) << how;
        EXPECT_NE(r.err.find("rotation number over 1274 section points (error), per dof: m "), std::string::npos)
            << r.err;
        if (how.empty()) exact = value;
        if (how.find("mp") != std::string::npos) EXPECT_NEAR(value, exact, 1e-14);
        // The section: t = 2 pi k, the closed-form steady state once the transient (e^{-t/2}) is gone.
        const auto rows = csv_rows(section);
        ASSERT_EQ(rows.size(), 1274u);
        for (std::size_t k = 100; k < rows.size(); k += 97) {
            EXPECT_NEAR(rows[k][0], 2 * M_PI * static_cast<double>(k), 1e-9 * rows[k][0]);
            double x, v;
            two_tone_state(rows[k][0], &x, &v);
            const double tol = how.find("cvode") != std::string::npos ? 1e-8 : 1e-11;
            EXPECT_NEAR(rows[k][1], x, tol) << how << " k " << k;
            EXPECT_NEAR(rows[k][2], v, tol) << how << " k " << k;
        }
    }
    // With a trajectory: the rows every 2 pi / m for the least whole m that is at most --dt's spacing.
    const std::string out = temp_path("two_tone_traj.csv");
    const auto r = run_hsnc("simulate '" + model + "' --t-end 100 --dt 0.5235987755982988 --out '" + out +
                            "' --section period:1 --section-out '" + section + "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(csv_rows(section).size(), 16u);  // t = 0, 2 pi, ..., 30 pi
    EXPECT_EQ(csv_rows(out).size(), 192u);     // every pi/6 up to 100, and 100
}

const std::string kCascade = std::string(HSNC_SOURCE_DIR) + "/examples/bilinear-cascade.toml";

TEST(QuasiPeriodic, ACycleGivesItsFractionAndChaosItsError) {
    const std::string section = temp_path("cascade_section.csv");
    // omega 2.55 from rest: a period-6 orbit (its section repeats every sixth
    // point; points three apart differ by 3e-3) turning 4/6 of a turn.
    auto r = run_hsnc("simulate '" + kCascade + "' --set omega=2.55 --t-end 7392 --section period --section-out '" +
                      section + "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = csv_rows(section);
    ASSERT_GT(rows.size(), 3000u);
    const auto& last = rows.back();
    EXPECT_NEAR(rows[rows.size() - 7][1], last[1], 1e-12);
    EXPECT_GT(std::fabs(rows[rows.size() - 4][1] - last[1]), 1e-3);
    EXPECT_NEAR(summary_value(r.out, "rotation"), 2.0 / 3.0, 1e-9);
    EXPECT_LT(summary_value(r.out, "rotation_error"), 1e-8);
    // omega 2.7: the chaotic set (hsnc lyapunov: largest exponent +0.14/s, tests/test_basins.cpp).
    r = run_hsnc("simulate '" + kCascade + "' --set omega=2.7 --t-end 6981 --section period --section-out '" + section +
                 "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_GT(summary_value(r.out, "rotation_error"), 1e-4);
}

// A stop and a spring, heavily damped, under 9 and 9 sqrt(2) rad/s: a torus
// of the forcing's two phases (the bundled example; tests/test_engine_orders.cpp's
// model with an incommensurate second order).
const std::string kStopTwoTone = std::string(HSNC_SOURCE_DIR) + "/examples/two-tone-stop.toml";

TEST(QuasiPeriodic, AStopUnderTwoFrequenciesAgainstCvode) {
    const std::string& model = kStopTwoTone;
    const std::string section = temp_path("stop_section.csv");
    double values[2];
    for (int k = 0; k < 2; ++k) {
        const auto r = run_hsnc("simulate '" + model + "' --t-end 2800 --section period:9 --section-out '" + section +
                                "' --quiet" + (k ? " --method cvode --rtol 1e-12 --atol 1e-14" : ""));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        EXPECT_GT(summary_value(r.out, "contact_close"), 4000);
        values[k] = summary_value(r.out, "rotation");
        // The invariant circle has kinks (the stop): the average converges
        // algebraically, 1.4e-9 over 1000 periods, 5e-13 over 4000; the
        // error estimate 8.6e-9 and 1.4e-10 covers it.
        EXPECT_LT(summary_value(r.out, "rotation_error"), 1e-9) << r.out;
    }
    // The section turns with the second forcing's phase: sqrt(2) - 1 of a turn per period.
    EXPECT_NEAR(values[0], std::sqrt(2.0) - 1.0, 1e-11);
    EXPECT_NEAR(values[1], values[0], 1e-11);
}

TEST(QuasiPeriodic, RefusalsNameTheFlag) {
    const std::string model = write_temp("two_tone.toml", kTwoTone), section = temp_path("refused_section.csv");
    const auto refused = [&](const std::string& args, const std::string& says) {
        const auto r = run_hsnc(args);
        EXPECT_EQ(r.exit_code, 2) << args;
        EXPECT_NE(r.err.find(says), std::string::npos) << args << ": " << r.err;
        EXPECT_FALSE(testing::file_exists(section)) << args;
    };
    const std::string sim = "simulate '" + model + "' --t-end 100 --section-out '" + section + "' ";
    refused(sim + "--section period",
            "--section 'period': give period:OMEGA, the frequency whose period the section "
            "is taken at (the forcing has 2 frequencies: 1, 1.4142135623730951)");
    refused(sim + "--section period:0", "--section 'period:0': OMEGA must be a finite number > 0 (rad/s)");
    refused(sim + "--section period:x", "--section 'period:x': OMEGA must be a finite number > 0");
    refused(sim + "--section period:1 --dt 0.1",
            "--dt 0.1: --section period:1 takes the state every 6.283185307179586 s: give a --dt that divides it");
    refused("lyapunov '" + model + "' --t-end 100 --section period:1 --section-out '" + section + "'",
            "a stroboscopic section is taken by hsnc simulate --section period[:OMEGA]");
    // periodic and sweep, which need a common period, say where the diagnostic is.
    refused("periodic '" + model + "'", "hsnc simulate --section period:OMEGA gives its section and rotation number");
}

}  // namespace
}  // namespace hsnc
