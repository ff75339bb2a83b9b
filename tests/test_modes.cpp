// Nonlinear normal modes of conservative piecewise-linear models (hsnc::modes,
// `hsnc modes`, interface.md): the backbone of a linear mode continued in
// amplitude by exact shooting with the period as an unknown.
//
// The truths: the bilinear oscillator's period and energy in closed form
// (two arcs of two harmonic motions joined at the gap), a 2-dof chain with
// symmetric stops against an independent quarter-period shooting on the
// 30-digit reference engine (finite differences, no monodromy), and the
// linear range against the linear modes and their Floquet multipliers.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "cli_runner.h"
#include "engine_runner.h"
#include "error.h"
#include "fe_models.h"
#include "hsnc/modes.h"
#include "hsnc/simulate.h"
#include "model.h"
#include "model_reader.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

// m x'' = -k1 x, and -k2 (x - d) more while x >= d: k1 = 4, k2 = 12, d = 0.1, m = 1.
const std::string kBilinearFile = std::string(HSNC_SOURCE_DIR) + "/examples/modes/bilinear-gap.toml";
Model bilinear() {
    return read_model(kBilinearFile);
}

// The period of the orbit turning at x = A > d (v = 0): beyond the gap a
// harmonic motion of omega2 about c = k2 d/(k1 + k2) from A to d, below it one
// of omega1 about 0 through d with the speed it arrives with.
double bilinear_period(double A_, double k1_, double k2_, double d_) {
    using R = long double;  // the closed form's own rounding well below the tolerance
    const R A = A_, k1 = k1_, k2 = k2_, d = d_, pi = 3.141592653589793238462643383279502884L;
    const R w1 = std::sqrt(k1), w2 = std::sqrt(k1 + k2);
    if (A <= d) return static_cast<double>(2 * pi / w1);
    const R c = k2 * d / (k1 + k2);
    const R t2 = std::acos((d - c) / (A - c)) / w2;  // from A to d
    const R vd = (A - c) * w2 * std::sin(w2 * t2);
    const R C = std::hypot(d, vd / w1);  // the amplitude below the gap
    return static_cast<double>(2 * t2 + (2 * pi - 2 * std::acos(d / C)) / w1);
}

TEST(Modes, BilinearBackboneMatchesItsClosedForm) {
    const Model model = bilinear();
    ModesOptions o;
    o.from = 0.03;
    o.to = 0.6;
    o.points = 12;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_EQ(r.dof, 0u);
    EXPECT_DOUBLE_EQ(r.linear_omega, 2.0);
    ASSERT_EQ(r.points.size(), 12u);
    for (const ModePoint& p : r.points) {
        const double T = bilinear_period(p.amplitude, 4, 12, 0.1);
        EXPECT_NEAR(p.period, T, 1e-12 * T) << "A = " << p.amplitude;
        EXPECT_NEAR(p.omega, 2 * M_PI / T, 1e-12 * p.omega);
        const double pen = std::max(0.0, p.amplitude - 0.1);
        const double E = 0.5 * 4 * p.amplitude * p.amplitude + 0.5 * 12 * pen * pen;
        EXPECT_NEAR(p.energy, E, 1e-12 * E);
        EXPECT_EQ(p.x[0], p.amplitude);
        EXPECT_EQ(p.v[0], 0.0);
        // The amplitude is on the free side beyond the gap: k1 C^2 = k1 A^2 + k2 (A - d)^2.
        const double C = std::sqrt(p.amplitude * p.amplitude + 3 * pen * pen);
        EXPECT_NEAR(p.peaks[0], C, 1e-13 * C) << "A = " << p.amplitude;
        EXPECT_EQ(p.events, p.amplitude > 0.1 ? 2u : 0u);  // closes and opens once a period
        EXPECT_EQ(p.multipliers.size(), 2u);
        EXPECT_EQ(p.max_multiplier, 1.0);  // only the family's pair: neutrally stable
        EXPECT_TRUE(p.stable);
        EXPECT_LE(p.residual, o.tolerance);
    }
    // Toward the bilinear limit pi/omega1 + pi/omega2 as the gap becomes small against A.
    o.from = 10.0;
    o.to = 100.0;
    o.points = 2;
    const ModesResult far = modes(model, o);
    ASSERT_EQ(far.status, ModesStatus::ok) << far.message;
    const double limit = M_PI / 2 + M_PI / 4;
    EXPECT_NEAR(far.points.back().period, bilinear_period(100.0, 4, 12, 0.1), 1e-12 * limit);
    EXPECT_NEAR(far.points.back().period, limit, 2e-3 * limit);  // O(d/A)
}

// The turning point on the free side: |A| below the gap on the other side
// too (the motion there is symmetric), and beyond it the stop is reached.
TEST(Modes, NegativeAmplitudesTurnOnTheFreeSide) {
    const Model model = bilinear();
    ModesOptions o;
    o.from = -0.05;
    o.to = -0.3;
    o.points = 6;
    o.tolerance = 1e-13;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    for (const ModePoint& p : r.points) {
        const double C = -p.amplitude;  // the same harmonic arc reaches +C on the other side
        if (C < 0.1) {
            EXPECT_NEAR(p.period, M_PI, 1e-12 * M_PI);
            continue;
        }
        // Reaching the gap with v = w1 sqrt(C^2 - d^2); beyond it the turning point A solves
        // k1 A^2 + k2 (A - d)^2 = k1 C^2 (energy): the same orbit as the positive A's.
        const long double a = 4 + 12, b = -2 * 12 * 0.1L, c = 12 * 0.01L - 4.0L * C * C;
        const auto A = static_cast<double>((-b + std::sqrt(b * b - 4 * a * c)) / (2 * a));
        EXPECT_NEAR(p.period, bilinear_period(A, 4, 12, 0.1), 1e-12 * p.period) << "A = " << p.amplitude;
    }
}

// m1 = m2 = 1, springs 1 (ground-m1, m1-m2, m2-ground): omega 1 and sqrt(3),
// mode 2 = (1, -1); stops k_c = 10 on m1 at x1 = d and x1 = -d, d = 0.1.
Model chain() {
    return read_model(std::string(HSNC_SOURCE_DIR) + "/examples/modes/chain-stops.toml");
}

// The symmetric mode (odd in x, reversible in t) passes x = 0 on every dof at
// a quarter period: find x2(0) and tau = T/4 with x(tau) = 0 from x = (A,
// x2), v = 0, by Newton with finite differences on the 30-digit reference.
struct Quarter {
    double x2, T;
};
Quarter quarter_period_shooting(const Model& base, double A, double x2, double tau) {
    auto end = [&](double x2_trial, double tau_trial) {
        Model m = base;
        m.x0 = {A, x2_trial};
        m.v0 = {0.0, 0.0};
        SimulateOptions o;
        o.t_end = tau_trial;
        o.samples = false;
        o.precision_digits = 30;
        testing::Recorder none(2);
        const SimulateSummary s = simulate(m, o, none);
        EXPECT_EQ(s.status, RunStatus::ok) << s.message;
        return std::array<double, 2>{s.x[0], s.x[1]};
    };
    for (int it = 0; it < 30; ++it) {
        const auto r = end(x2, tau);
        if (std::hypot(r[0], r[1]) < 1e-15 * A) break;
        const double h1 = 1e-7 * A, h2 = 1e-7 * tau;
        const auto a = end(x2 + h1, tau), b = end(x2, tau + h2);
        const double j11 = (a[0] - r[0]) / h1, j21 = (a[1] - r[1]) / h1;
        const double j12 = (b[0] - r[0]) / h2, j22 = (b[1] - r[1]) / h2;
        const double det = j11 * j22 - j12 * j21;
        x2 -= (j22 * r[0] - j12 * r[1]) / det;
        tau -= (-j21 * r[0] + j11 * r[1]) / det;
    }
    return {x2, 4 * tau};
}

TEST(Modes, ChainWithStopsMatchesQuarterPeriodShootingOnTheReference) {
    const Model model = chain();
    ModesOptions o;
    o.mode = 2;
    o.dof = "m1";
    o.from = 0.06;
    o.to = 0.41;
    o.points = 8;  // 0.06, 0.11, ...: none at the gap, where the orbit grazes the stops
    o.tolerance = 1e-13;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_NEAR(r.linear_omega, std::sqrt(3.0), 1e-15);
    EXPECT_NEAR(r.shape[1] / r.shape[0], -1.0, 1e-14);
    for (const ModePoint& p : r.points) {
        if (p.amplitude < 0.1) {  // below the stops: the linear mode, and mode 1's multipliers
            EXPECT_NEAR(p.period, 2 * M_PI / std::sqrt(3.0), 1e-13);
            EXPECT_NEAR(p.x[1], -p.amplitude, 1e-13 * p.amplitude);
            EXPECT_NEAR(p.energy, 0.5 * 3 * 2 * p.amplitude * p.amplitude, 1e-13 * p.energy);
            const double theta = 2 * M_PI / std::sqrt(3.0);  // omega1 T
            int found = 0;
            for (const auto& mu : p.multipliers)
                found +=
                    std::abs(mu - std::polar(1.0, theta)) < 1e-10 || std::abs(mu - std::polar(1.0, -theta)) < 1e-10;
            EXPECT_EQ(found, 2);
            EXPECT_TRUE(p.stable);
            continue;
        }
        const Quarter q = quarter_period_shooting(model, p.amplitude, p.x[1], p.period / 4);
        EXPECT_NEAR(p.period, q.T, 1e-10 * q.T) << "A = " << p.amplitude;
        EXPECT_NEAR(p.x[1] / p.amplitude, q.x2 / p.amplitude, 1e-10) << "A = " << p.amplitude;
        EXPECT_LT(p.period, 2 * M_PI / std::sqrt(3.0));  // the stops stiffen the mode
        // A synchronous mode: every dof turns with m1, so its peaks are the turning point's.
        EXPECT_NEAR(p.peaks[0], p.amplitude, 1e-13 * p.amplitude);
        EXPECT_NEAR(p.peaks[1], std::fabs(p.x[1]), 1e-13 * std::fabs(p.x[1]));
        EXPECT_EQ(p.events, 4u);
    }
}

// Mode 1 of the chain stiffens past the ratio omega2/omega = 2: its multiplier
// pair of mode 2 reaches +1 and leaves the circle (a 2:1 internal resonance),
// the orbit is unstable while the pair is real, and the branch goes on beyond.
TEST(Modes, InternalResonanceIsMarkedAndTheBranchFollowedWithoutAJump) {
    const Model model = chain();
    ModesOptions o;
    o.mode = 1;
    o.dof = "m1";
    o.from = 0.06;
    o.to = 0.51;
    o.points = 10;  // 0.06, 0.11, ..., 0.51: a coarse grid across the tongue
    o.tolerance = 1e-13;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    ASSERT_EQ(r.others, std::vector<int>{2});
    EXPECT_NEAR(r.points.front().ratios[0], std::sqrt(3.0), 1e-12);  // omega2/omega1 below the stops
    int marked = 0;
    bool passed = false;
    for (const ModePoint& p : r.points) {
        const double ratio = p.ratios.at(0);
        for (const std::string& s : p.resonances) {
            EXPECT_EQ(s, "mode2 2:1") << "A = " << p.amplitude;
            ++marked;
            passed = true;
        }
        if (!passed) EXPECT_LT(ratio, 2.0) << "A = " << p.amplitude;
        if (std::fabs(ratio - 2.0) < 1e-9) {  // in the tongue: a real pair mu, 1/mu
            EXPECT_FALSE(p.stable) << "A = " << p.amplitude;
            EXPECT_GT(p.max_multiplier, 1.01);
            EXPECT_NEAR(p.multipliers.front().imag(), 0.0, 1e-9);
            EXPECT_GT(p.multipliers.front().real(), 1.0);
        } else {
            EXPECT_TRUE(p.stable) << "A = " << p.amplitude;
            // The ratio is the pair's angle: e^{+-i 2 pi ratio} among the multipliers.
            int found = 0;
            for (const auto& mu : p.multipliers)
                found += std::abs(mu - std::polar(1.0, 2 * M_PI * ratio)) < 1e-8 ||
                         std::abs(mu - std::polar(1.0, -2 * M_PI * ratio)) < 1e-8;
            EXPECT_EQ(found, 2) << "A = " << p.amplitude;
        }
    }
    EXPECT_EQ(marked, 1);
    EXPECT_GT(r.points.back().ratios[0], 2.0);  // out of the tongue again, beyond it
    EXPECT_TRUE(r.points.back().stable);

    // The same branch on a grid five times finer: the same orbits where the grids meet.
    ModesOptions fine = o;
    fine.points = 46;
    const ModesResult f = modes(model, fine);
    ASSERT_EQ(f.status, ModesStatus::ok) << f.message;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
        const ModePoint& a = r.points[i];
        const ModePoint& b = f.points[5 * i];
        ASSERT_NEAR(a.amplitude, b.amplitude, 1e-15);
        EXPECT_NEAR(a.period, b.period, 1e-11 * a.period) << "A = " << a.amplitude;
        EXPECT_NEAR(a.x[1], b.x[1], 1e-11 * std::fabs(a.x[1])) << "A = " << a.amplitude;
    }
    // In the tongue, the unstable orbit against the quarter-period shooting on the reference.
    const ModePoint& in = r.points[3];  // A = 0.21
    ASSERT_FALSE(in.stable);
    const Quarter q = quarter_period_shooting(model, in.amplitude, in.x[1], in.period / 4);
    EXPECT_NEAR(in.period, q.T, 1e-10 * q.T);
    EXPECT_NEAR(in.x[1], q.x2, 1e-10 * std::fabs(q.x2));
}

// Continued in energy (a frequency-energy backbone): the bilinear oscillator
// turns at the A with 1/2 k1 A^2 + 1/2 k2 (A - d)^2 = E, its period the closed
// form there; the chain's mode 1 through its tongue gives the orbits the
// amplitude continuation gives at those energies.
TEST(Modes, EnergyBackbonesMatchTheClosedFormAndTheAmplitudeBackbone) {
    ModesOptions o;
    o.parameter = ModesParameter::energy;
    o.from = 1e-3;
    o.to = 100.0;
    o.points = 11;
    o.geometric = true;
    o.tolerance = 1e-13;
    const ModesResult r = modes(bilinear(), o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        const double E = 1e-3 * std::pow(1e5, static_cast<double>(i) / 10);
        EXPECT_NEAR(p.energy, E, 1e-12 * E);
        // The turning point of that energy: below the gap sqrt(2E/k1), beyond it the quadratic's root.
        double A = std::sqrt(2 * E / 4);
        if (A > 0.1) A = (2 * 12 * 0.1 + std::sqrt(4 * 144 * 0.01 - 4 * 16 * (12 * 0.01 - 2 * E))) / (2 * 16);
        EXPECT_NEAR(p.amplitude, A, 1e-12 * A) << "E = " << E;
        const double T = bilinear_period(p.amplitude, 4, 12, 0.1);
        EXPECT_NEAR(p.period, T, 1e-12 * T) << "E = " << E;
        EXPECT_EQ(p.v[0], 0.0);
    }

    ModesOptions a;
    a.mode = 1;
    a.dof = "m1";
    a.from = 0.06;
    a.to = 0.51;
    a.points = 10;
    a.tolerance = 1e-13;
    const ModesResult by_amplitude = modes(chain(), a);
    ASSERT_EQ(by_amplitude.status, ModesStatus::ok) << by_amplitude.message;
    ModesOptions e = a;
    e.parameter = ModesParameter::energy;
    e.from = by_amplitude.points.front().energy;
    e.to = by_amplitude.points.back().energy;
    e.points = 2;
    const ModesResult by_energy = modes(chain(), e);
    ASSERT_EQ(by_energy.status, ModesStatus::ok) << by_energy.message;
    for (std::size_t i : {std::size_t{0}, std::size_t{1}}) {
        const ModePoint& p = by_energy.points[i];
        const ModePoint& q = i == 0 ? by_amplitude.points.front() : by_amplitude.points.back();
        EXPECT_NEAR(p.amplitude, q.amplitude, 1e-11 * q.amplitude);
        EXPECT_NEAR(p.period, q.period, 1e-11 * q.period);
        EXPECT_NEAR(p.x[1], q.x[1], 1e-11 * std::fabs(q.x[1]));
    }
    EXPECT_EQ(by_energy.points.back().resonances, std::vector<std::string>{"mode2 2:1"});
}

// Whatever the grid, the continuation follows one branch to one end: the
// chain's mode 1 crosses its 2:1 tongue and a branch point where the pair
// returns to the circle (where grids of 13 and 23 points jumped or stopped before
// steps could leap), mode 2 its grazing onset in energy.
TEST(Modes, EveryGridReachesTheSameEndOfTheBranch) {
    auto last = [](ModesOptions o, int points) {
        o.points = points;
        const ModesResult r = modes(chain(), o);
        EXPECT_EQ(r.status, ModesStatus::ok) << points << " points: " << r.message;
        return r.points.empty() ? ModePoint{} : r.points.back();
    };
    ModesOptions a;
    a.mode = 1;
    a.dof = "m1";
    a.from = 0.03;
    a.to = 2.0;
    const ModePoint end = last(a, 61);
    for (int points : {3, 4, 6, 13, 23}) {
        const ModePoint p = last(a, points);
        EXPECT_NEAR(p.period, end.period, 1e-10 * end.period) << points << " points";
        EXPECT_NEAR(p.x[1], end.x[1], 1e-10 * std::fabs(end.x[1])) << points << " points";
    }
    ModesOptions e;
    e.mode = 2;
    e.dof = "m1";
    e.parameter = ModesParameter::energy;
    e.from = 1e-4;
    e.to = 100.0;
    const ModePoint top = last(e, 33);
    for (int points : {3, 6, 9}) {
        const ModePoint p = last(e, points);
        EXPECT_NEAR(p.period, top.period, 1e-10 * top.period) << points << " points";
        EXPECT_NEAR(p.amplitude, top.amplitude, 1e-10 * top.amplitude) << points << " points";
    }
}

TEST(Modes, CommandWritesTheBackboneAndRefusesByFlag) {
    testing::TempDir dir;
    const std::string model = "'" + std::string(HSNC_SOURCE_DIR) + "/examples/modes/chain-stops.toml'";
    const testing::CliRun ok = testing::run_hsnc("modes " + model +
                                                 " --mode 1 --dof m1 --from 0.06 --to 0.51 "
                                                 "--points 10 --out '" +
                                                 dir / "b.csv" + "' --multipliers '" + dir / "mu.csv" + "' --quiet");
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(ok.out.rfind("status=ok mode=1 dof=m1 linear_omega=", 0), 0u) << ok.out;
    EXPECT_NE(ok.out.find(" points=10 "), std::string::npos) << ok.out;
    EXPECT_NE(ok.out.find(" unstable="), std::string::npos) << ok.out;
    const std::string csv = testing::slurp(dir / "b.csv");
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "amplitude,omega,omega_ratio,period,energy,x_m1,x_m2,v_m1,v_m2,peak_m1,peak_m2,ratio_mode2,resonance,"
              "max_multiplier,"
              "stable,events,grazing,iterations,residual");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 11);
    EXPECT_NE(csv.find(",mode2 2:1,"), std::string::npos);
    const std::string mu = testing::slurp(dir / "mu.csv");
    EXPECT_EQ(mu.substr(0, mu.find('\n')), "amplitude,index,re,im,abs");
    EXPECT_EQ(std::count(mu.begin(), mu.end(), '\n'), 1 + 10 * 4);

    auto refused = [&](const std::string& flags, const std::string& word) {
        const testing::CliRun r = testing::run_hsnc("modes " + model + " " + flags);
        EXPECT_EQ(r.exit_code, 2) << flags << ": " << r.err;
        EXPECT_NE(r.err.find(word), std::string::npos) << r.err;
        EXPECT_EQ(r.out, "");
    };
    refused("--points 5", "--to");
    refused("--to 0.2 --mode 3", "--mode");
    refused("--to 0.2 --dof m7", "--dof");
    refused("--to 0.2 --x0 m1=0.1", "--x0");
    refused("--to nan", "--to");
    refused("--to 0.2 --record-dofs m2,m9 --out '" + dir / "r.csv" + "'", "--record-dofs: 'm9'");
    refused("--to 0.2 --record-dofs m2,m2 --out '" + dir / "r.csv" + "'", "named twice");
    EXPECT_FALSE(std::ifstream(dir / "r.csv").good()) << "nothing written";

    // --record-dofs: the state and peak columns of those dofs only, in that order, the same numbers.
    const testing::CliRun some = testing::run_hsnc("modes " + model +
                                                   " --mode 1 --dof m1 --from 0.06 --to 0.51 --points 10 "
                                                   "--record-dofs m2 --quiet --out '" +
                                                   dir / "m2.csv" + "'");
    ASSERT_EQ(some.exit_code, 0) << some.err;
    const std::string part = testing::slurp(dir / "m2.csv");
    EXPECT_EQ(part.substr(0, part.find('\n')),
              "amplitude,omega,omega_ratio,period,energy,x_m2,v_m2,peak_m2,ratio_mode2,resonance,max_multiplier,"
              "stable,events,grazing,iterations,residual");
    auto field = [](const std::string& text, std::size_t row, std::size_t col) {
        std::istringstream in(text);
        std::string line, cell;
        for (std::size_t r = 0; r <= row; ++r) std::getline(in, line);
        std::istringstream cells(line);
        for (std::size_t c = 0; c <= col; ++c) std::getline(cells, cell, ',');
        return cell;
    };
    for (std::size_t row = 1; row <= 10; ++row) {
        EXPECT_EQ(field(part, row, 5), field(csv, row, 6)) << "x_m2, row " << row;
        EXPECT_EQ(field(part, row, 7), field(csv, row, 10)) << "peak_m2, row " << row;
    }
}

TEST(Modes, RefusesWhatItDoesNotTakeByName) {
    auto refused = [](const std::string& extra, const std::string& word) {
        const Model model = parse_model(testing::slurp(kBilinearFile) + extra, "m.toml");
        ModesOptions o;
        o.to = 0.2;
        try {
            modes(model, o);
            ADD_FAILURE() << "accepted: " << extra;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
        }
    };
    refused("[load]\nm = 0.1\n[[load_step]]\nname = \"off\"\nt = 1.0\nload = { m = 0.0 }\n", "[[load_step]] off");
    // Every mass with friction: nothing moves in the linear limit.
    try {
        ModesOptions o;
        o.to = 0.1;
        modes(parse_model("name = \"held\"\n[[mass]]\nname = \"m\"\nm = 1.0\nmu_k = 0.1\n[[spring]]\nbetween = "
                          "[\"m\", \"ground\"]\nk = 1.0\n",
                          "held.toml"),
              o);
        ADD_FAILURE() << "accepted a model whose every mass has friction";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("every mass has friction"), std::string::npos) << e.what();
    }
    // A free body: no equilibrium to start from.
    const Model free = parse_model("name = \"free\"\n[[mass]]\nname = \"m\"\nm = 1.0\n", "free.toml");
    ModesOptions o;
    o.to = 0.1;
    EXPECT_THROW(modes(free, o), InputError);
}

// m = 1 on k = 1, a Jenkins element k_t = 3, F_s = 0.3 to the ground: stuck omega = 2, free omega = 1,
// slip from the amplitude F_s / k_t = 0.1 on; `extra` TOML appended.
Model jenkins_oscillator(const std::string& extra = "") {
    return parse_model(
        "name = \"jenkins-1dof\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[spring]]\nbetween = [\"m\", \"ground\"]\n"
        "k = 1.0\n[[jenkins]]\nname = \"joint\"\nbetween = [\"m\", \"ground\"]\nk = 3.0\nslip_force = 0.3\n" +
            extra,
        "jenkins-1dof.toml");
}

// The EPMC orbit of the Jenkins oscillator in closed form: m x'' - xi x' + k x + f_J = 0 turning
// at +A (just stuck, stretch +F_s/k_t), stuck (stiffness k + k_t about k_t s/(k + k_t)) until the
// stretch is -F_s/k_t, then slipping (k about F_s/k) until v = 0, where x = -A by symmetry: xi
// is found by bisection on x_end(xi) + A, T = 2 (t_stuck + t_slip). Long double throughout.
struct JenkinsOrbit {
    long double xi, T;
};
JenkinsOrbit jenkins_epmc(long double A) {
    using R = long double;
    const R k = 1, kt = 3, Fs = 0.3L, pi = 3.141592653589793238462643383279502884L;
    // u'' + c u' + lambda u = 0 from (u0, ud0): u and u' at t.
    struct Free {
        R lam, c, u0, ud0;
        R sigma() const { return c / 2; }
        R wd() const { return std::sqrt(lam - sigma() * sigma()); }
        R u(R t) const {
            return std::exp(-sigma() * t) * (u0 * std::cos(wd() * t) + (ud0 + sigma() * u0) / wd() * std::sin(wd() * t));
        }
        R du(R t) const {
            return std::exp(-sigma() * t) *
                   (ud0 * std::cos(wd() * t) - (lam * u0 + sigma() * ud0) / wd() * std::sin(wd() * t));
        }
    };
    auto bisect = [](auto f, R a, R b) {  // f(a) and f(b) of opposite signs
        const bool fa = f(a) > 0;
        for (int i = 0; i < 200; ++i) {
            const R m = (a + b) / 2;
            ((f(m) > 0) == fa ? a : b) = m;
        }
        return (a + b) / 2;
    };
    struct Halves {
        R t1, t2, x_end;
    };
    auto half = [&](R xi) {
        const R s = A - Fs / kt, x1 = kt * s / (k + kt);
        const Free stuck{k + kt, -xi, A - x1, 0};
        const R u_end = A - 2 * Fs / kt - x1;
        const R t1 = bisect([&](R t) { return stuck.u(t) - u_end; }, 0, pi / stuck.wd());
        const R x2 = Fs / k;
        const Free slip{k, -xi, A - 2 * Fs / kt - x2, stuck.du(t1)};
        const R t2 = bisect([&](R t) { return slip.du(t); }, 0, pi / slip.wd() * R(0.999999));
        return Halves{t1, t2, x2 + slip.u(t2)};
    };
    const R xi = bisect([&](R x) { return half(x).x_end + A; }, 0, 1.5);
    const Halves h = half(xi);
    return {xi, 2 * (h.t1 + h.t2)};
}

TEST(Modes, JenkinsOscillatorDampedModeMatchesItsClosedForm) {
    // The extended periodic motion (api/hsnc/modes.h): frequency from stuck (2) toward free (1),
    // xi against the closed-form orbit; below the slip onset the linear mode, undamped.
    const Model model = jenkins_oscillator();
    ModesOptions o;
    o.from = 0.05;
    o.to = 1.0;
    o.points = 20;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_TRUE(r.damped);
    EXPECT_NEAR(r.linear_omega, 2.0, 1e-15);
    ASSERT_EQ(r.points.size(), 20u);
    double last_omega = 2.0, last_ratio = 0.0, worst_T = 0.0, worst_xi = 0.0;
    for (const ModePoint& p : r.points) {
        if (p.amplitude <= 0.1 + 1e-12) {
            EXPECT_NEAR(p.omega, 2.0, 1e-12) << p.amplitude;
            EXPECT_NEAR(p.xi, 0.0, 1e-12) << p.amplitude;
            continue;
        }
        const JenkinsOrbit e = jenkins_epmc(p.amplitude);
        worst_T = std::max(worst_T, std::fabs(p.period - static_cast<double>(e.T)) / p.period);
        worst_xi = std::max(worst_xi, std::fabs(p.xi - static_cast<double>(e.xi)));
        EXPECT_NEAR(p.period, static_cast<double>(e.T), 1e-11 * p.period) << p.amplitude;  // measured 7.9e-14
        EXPECT_NEAR(p.xi, static_cast<double>(e.xi), 1e-10) << p.amplitude;                // measured 2.6e-13
        EXPECT_NEAR(p.damping_ratio, p.xi / (2 * p.omega), 1e-15);
        EXPECT_LT(p.omega, last_omega) << "the frequency falls with amplitude, from stuck toward free";
        EXPECT_GT(p.omega, 1.0);
        last_omega = p.omega;
        // Dissipation 4 F_s (A - F_s/k_t) against xi times the mean square velocity: only of the
        // same size (the orbit is not harmonic), and positive.
        EXPECT_GT(p.damping_ratio, 0.0);
        last_ratio = p.damping_ratio;
        ASSERT_EQ(p.sliders.size(), 1u);
        EXPECT_NEAR(p.sliders[0], p.amplitude - 0.1, 1e-9) << "turning: just stuck, stretched F_s/k_t";
        EXPECT_NEAR(p.energy, 0.5 * p.amplitude * p.amplitude + 0.5 * 3 * 0.01, 1e-9);
    }
    EXPECT_GT(last_ratio, 0.0);
    std::printf("[ info ] Jenkins EPMC against the closed form: period %.2g (relative), xi %.2g\n", worst_T, worst_xi);
}

TEST(Modes, BeamWithAJenkinsJointSoftensFromStuckTowardFreeAndDamps) {
    // A clamped-free Euler-Bernoulli beam from matrices (4 elements, consistent mass, 8 dofs)
    // held at mid-span (w2) by a Jenkins joint to the ground: the damped first mode from
    // sticking through macroslip. Limits: the stuck beam (K + k_t e e^T) at small amplitudes,
    // the free beam (K) as the amplitude grows; between them the frequency falls. (4 elements:
    // 6 take 2-3 times as long, slow Newton steps near the slip onset; docs/interface.md.)
    const fe::Beam beam = fe::cantilever(4);
    const double kt = 2000.0, Fs = 10.0;
    testing::TempDir dir;
    const std::string path = fe::structure_model(
        dir, "beam.toml", "beam-joint", beam.M, beam.K, beam.dofs,
"[[jenkins]]\nname = \"joint\"\nbetween = [\"w2\", \"ground\"]\nk = " + fe::num(kt) +
            "\nslip_force = " + fe::num(Fs) + "\n");
    const Model model = read_model(path);
    auto first = [&](const Eigen::MatrixXd& K) {
        return std::sqrt(Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(K, beam.M).eigenvalues()(0));
    };
    Eigen::MatrixXd stuck = beam.K;
    stuck(2, 2) += kt;  // w2: dofs w1 t1 w2 t2 ...
    const double w_stuck = first(stuck), w_free = first(beam.K);
    ModesOptions o;
    o.dof = "w4";
    o.from = 0.002;
    o.to = 0.5;
    o.points = 12;
    o.geometric = true;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_NEAR(r.linear_omega, w_stuck, 1e-12 * w_stuck);
    ASSERT_EQ(r.points.size(), 12u);
    EXPECT_NEAR(r.points.front().omega, w_stuck, 1e-11 * w_stuck) << "below the slip onset: the stuck beam";
    EXPECT_EQ(r.points.front().xi, 0.0);
    for (std::size_t i = 1; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        EXPECT_LE(p.omega, r.points[i - 1].omega) << p.amplitude;
        EXPECT_GT(p.omega, w_free) << p.amplitude;
        EXPECT_GE(p.damping_ratio, 0.0) << p.amplitude;
    }
    const ModePoint& last = r.points.back();
    std::printf("[ info ] beam joint: stuck %.6g, free %.6g rad/s; at A = %.3g omega %.6g, D %.3g\n", w_stuck, w_free,
                last.amplitude, last.omega, last.damping_ratio);
    EXPECT_LT((last.omega - w_free) / (w_stuck - w_free), 0.1) << "macroslip: near the free beam";
    EXPECT_GT(last.damping_ratio, 0.0);
}

TEST(Modes, AJenkinsJointWithStiffnessProportionalDampingHasTheLinearRatioBelowTheSlip) {
    // beta K with EPMC's alpha - xi < 0: the Eigen solver's bound of a rigid-body
    // mode's terms, e^{-alpha s} at the horizon's end, was e^{+inf} times a zero
    // weight (no rigid mode: NaN), and every run failed at t = 0 ("non-finite
    // switch function"). Stuck (A <= F_s / k_t = 0.1) the mode is linear, omega = 2
    // and xi = beta omega^2 = 0.04; slipping it softens and damps more.
    Model model = jenkins_oscillator();
    model.beta = 0.01;
    ModesOptions o;
    o.from = 0.05;
    o.to = 0.3;
    o.points = 6;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    ASSERT_EQ(r.points.size(), 6u);
    for (const ModePoint& p : r.points) {
        if (p.amplitude <= 0.1 + 1e-12) {
            EXPECT_NEAR(p.omega, 2.0, 1e-12) << p.amplitude;
            EXPECT_NEAR(p.xi, 0.04, 1e-12) << p.amplitude;
            EXPECT_NEAR(p.damping_ratio, 0.01, 1e-12) << p.amplitude;
        } else {
            EXPECT_LT(p.omega, 2.0) << p.amplitude;
            EXPECT_GT(p.damping_ratio, 0.01) << p.amplitude;
        }
    }
    std::printf("[ info ] Jenkins joint with beta K: omega %.6f, ratio %.6f at A = %.2f\n", r.points.back().omega,
                r.points.back().damping_ratio, r.points.back().amplitude);
}

TEST(Modes, RayleighDampingAloneGivesTheConservativeBackboneAndTheLinearRatio) {
    // alpha M only: EPMC's xi cancels it exactly, so the orbit is the conservative one (the
    // bilinear closed form) and the damping ratio alpha / (2 omega) at every amplitude.
    Model model = parse_model(testing::slurp(kBilinearFile) + "[damping]\nalpha = 0.2\n", "damped.toml");
    ModesOptions o;
    o.from = 0.05;
    o.to = 0.5;
    o.points = 10;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_TRUE(r.damped);
    EXPECT_NEAR(r.linear_damping_ratio, 0.2 / 4, 1e-15);
    for (const ModePoint& p : r.points) {
        EXPECT_NEAR(p.xi, 0.2, 1e-10) << p.amplitude;
        EXPECT_NEAR(p.period, bilinear_period(p.amplitude, 4, 12, 0.1), 1e-10 * p.period) << p.amplitude;
        EXPECT_NEAR(p.damping_ratio, 0.2 / (2 * p.omega), 1e-10);
    }
}

TEST(Modes, AJenkinsJointWithADamperAddsTheDampersRateToXi) {
    // m = 1 with a damper c: on one dof the EPMC system's net damping is c - xi, so its orbits
    // are the undamped joint's with xi larger by exactly c (the joint's closed form plus c). The
    // damper puts the runs on the state-space solver (a model with dampers is not Rayleigh).
    const double c = 0.04;
    const Model model = jenkins_oscillator("[[damper]]\nbetween = [\"m\", \"ground\"]\nc = 0.04\n");
    ModesOptions o;
    o.from = 0.05;
    o.to = 1.0;
    o.points = 8;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_TRUE(r.damped);
    EXPECT_NEAR(r.linear_omega, 2.0, 1e-14);
    EXPECT_NEAR(r.linear_damping_ratio, c / 4, 1e-15);
    ASSERT_EQ(r.points.size(), 8u);
    EXPECT_NEAR(r.points.front().omega, 2.0, 1e-12) << "below the slip onset: the stuck oscillator";
    EXPECT_NEAR(r.points.front().xi, c, 1e-12);
    for (std::size_t i = 1; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        const JenkinsOrbit e = jenkins_epmc(p.amplitude);
        EXPECT_NEAR(p.period, static_cast<double>(e.T), 1e-11 * p.period) << p.amplitude;
        EXPECT_NEAR(p.xi, static_cast<double>(e.xi) + c, 1e-10) << p.amplitude;
    }
}

// The independent integrator of the damped-mode tests below: classical RK4 in long double over
// t (n steps) of a system (N = 2 x dofs states) whose vector field `field(z, mode)` depends on a
// discrete mode (a contact closed or open; stuck or sliding), which switches where
// `keep(z, mode)` falls below 0 (located within a step by bisection on the step's length);
// `next(z, mode)` gives the mode after, and may fix z there (a stuck relative velocity to 0).
using State = std::array<long double, 4>;
template <std::size_t N, class Field, class Keep, class Next>
std::array<long double, N> switched_rk4(std::array<long double, N> y, int mode, long double t, int n, Field field,
                                        Keep keep, Next next) {
    using R = long double;
    using Y = std::array<long double, N>;
    auto step = [&](const Y& z, R h, int md) {
        auto add = [](Y a, const Y& b, R s) {
            for (std::size_t i = 0; i < N; ++i) a[i] += s * b[i];
            return a;
        };
        const Y k1 = field(z, md), k2 = field(add(z, k1, h / 2), md), k3 = field(add(z, k2, h / 2), md),
                k4 = field(add(z, k3, h), md);
        Y out = z;
        for (std::size_t i = 0; i < N; ++i) out[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
        return out;
    };
    const R h = t / n;
    R left = t;
    while (left > t * 1e-18L) {
        const R dt = std::min(h, left);
        const Y ahead = step(y, dt, mode);
        if (!(keep(ahead, mode) < 0)) {
            y = ahead;
            left -= dt;
            continue;
        }
        R lo = 0, hi = dt;
        for (int b = 0; b < 90; ++b) {
            const R mid = (lo + hi) / 2;
            (keep(step(y, mid, mode), mode) < 0 ? hi : lo) = mid;
        }
        y = step(y, hi, mode);
        mode = next(y, mode);
        left -= hi;
    }
    return y;
}

// How far `rk4` (an EPMC system's independent integrator: state, xi, t, steps; N states) leaves
// the orbit of point p after its period, against its amplitude: 0 for an exact periodic orbit.
template <std::size_t N = 4, class Rk4>
double closure(const ModePoint& p, Rk4 rk4) {
    std::array<long double, N> y0{};
    for (std::size_t i = 0; i < N / 2; ++i) y0[i] = p.x[i], y0[N / 2 + i] = p.v[i];
    const std::array<long double, N> y1 = rk4(y0, p.xi, p.period, 40000);
    double worst = 0.0;
    for (std::size_t i = 0; i < N; ++i)
        worst = std::max(worst, static_cast<double>(std::fabs(y1[i] - y0[i])) / p.amplitude);
    return worst;
}

// Two masses (m1 = 1, m2 = 2; k 1 to the ground, 20 between), a damper c = 0.3 from the first
// to the ground (non-proportional), a stop of stiffness 5 at x2 = 0.1 (kContactDamping adds a
// dashpot 0.5 to it while closed). The first mode (0.57 rad/s) stiffens toward 1.35 with the
// stop closed, below a third of the second (5.5): no 3:1 internal resonance on the way.
const char* kContactDamping = "c = 0.5\n";
const char* kDampedChain =
    "name = \"damped-chain\"\n[[mass]]\nname = \"a\"\nm = 1.0\n[[mass]]\nname = \"b\"\nm = 2.0\n"
    "[[spring]]\nbetween = [\"a\", \"ground\"]\nk = 1.0\n"
    "[[spring]]\nbetween = [\"a\", \"b\"]\nk = 20.0\n"
    "[[damper]]\nbetween = [\"a\", \"ground\"]\nc = 0.3\n"
    "[[contact]]\nname = \"stop\"\nbetween = [\"b\", \"ground\"]\ngap = 0.1\nk = 5.0\n";

// The EPMC system of kDampedChain (C - xi M) from (x, v) over t, by classical RK4 in long double
// (n steps), the stop's closing and opening located within a step by bisection on the step
// length: an integrator of its own, sharing nothing with hsnc.
State damped_chain_rk4(State y, long double xi, long double t, int n, long double contact_c = 0) {
    using R = long double;
    auto field = [&](const State& z, int closed) {
        const R x1 = z[0], x2 = z[1], v1 = z[2], v2 = z[3];
        const R stop = closed ? 5 * (x2 - R(0.1)) + contact_c * v2 : R(0);
        return State{v1, v2, (-x1 - 20 * (x1 - x2) - (R(0.3) - xi) * v1), (-20 * (x2 - x1) + 2 * xi * v2 - stop) / 2};
    };
    auto keep = [](const State& z, int closed) { return closed ? z[1] - R(0.1) : R(0.1) - z[1]; };
    auto next = [](State&, int closed) { return 1 - closed; };
    return switched_rk4(y, y[1] > R(0.1) ? 1 : 0, t, n, field, keep, next);
}

TEST(Modes, ANonProportionalDamperGivesTheClosedFormLinearLimitAndExactOrbitsBeyondTheStop) {
    // Linear limit: det(K - w^2 M + i w (C - xi M)) = 0, whose imaginary part gives xi = c a22 /
    // (m1 a22 + m2 a11) (a = K - w^2 M) and whose real part a11 a22 - a12^2 + w^2 xi m2 (c - xi
    // m1) = 0 the frequency (bisection); the dofs' amplitude ratio |x2/x1| = |a12 / (a22 - i w xi
    // m2)|. Below the stop the backbone is that linear mode; beyond it each orbit (shooting to
    // 1e-13), run from its turning point for one period by the RK4 above, comes back to it (1e-12
    // of the amplitude: measured 1.1e-13), its frequency rising
    // toward the mode with the stop held closed.
    using R = long double;
    const R c = 0.3L, m1 = 1, m2 = 2;
    auto parts = [&](R w) {
        const R a11 = 21 - w * w * m1, a22 = 20 - w * w * m2, a12 = -20;
        const R xi = c * a22 / (m1 * a22 + m2 * a11);
        return std::array<R, 4>{a11 * a22 - a12 * a12 + w * w * xi * m2 * (c - xi * m1), xi, a12, a22};
    };
    R lo = 0.45L, hi = 0.7L;  // about the undamped first mode, 0.577
    const bool sign_lo = parts(lo)[0] > 0;
    for (int i = 0; i < 200; ++i) ((parts((lo + hi) / 2)[0] > 0) == sign_lo ? lo : hi) = (lo + hi) / 2;
    const R w = (lo + hi) / 2;
    const std::array<R, 4> at = parts(w);
    const R xi = at[1];
    const R ratio = std::abs(at[2]) / std::abs(std::complex<R>(at[3], -w * xi * m2));

    const Model model = parse_model(kDampedChain, "damped-chain.toml");
    ModesOptions o;
    o.dof = "b";
    o.from = 0.02;
    o.to = 0.5;
    o.points = 12;
    o.tolerance = 1e-13;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_TRUE(r.damped);
    EXPECT_NEAR(r.linear_omega, static_cast<double>(w), 1e-12);
    EXPECT_NEAR(r.linear_damping_ratio, static_cast<double>(xi / (2 * w)), 1e-12);
    ASSERT_EQ(r.points.size(), 12u);
    Eigen::Matrix2d M, K;
    M << 1, 0, 0, 2;
    K << 21, -20, -20, 25;
    const double w_closed = std::sqrt(Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d>(K, M).eigenvalues()(0));
    double worst = 0.0, last = static_cast<double>(w);
    int beyond = 0;
    for (const ModePoint& p : r.points) {
        if (p.amplitude <= 0.1 + 1e-9) {  // up to the stop (grazing at 0.1)
            EXPECT_NEAR(p.omega, static_cast<double>(w), 1e-11) << p.amplitude;
            EXPECT_NEAR(p.xi, static_cast<double>(xi), 1e-11) << p.amplitude;
            EXPECT_NEAR(p.peaks[0] / p.peaks[1], static_cast<double>(1 / ratio), 1e-9) << p.amplitude;
            continue;
        }
        ++beyond;
        EXPECT_NEAR(p.v[1], 0.0, 1e-12 * p.amplitude) << "the turning point of the amplitude dof";
        worst = std::max(worst, closure(p, [](const State& y, long double xi, long double t, int n) {
                             return damped_chain_rk4(y, xi, t, n);
                         }));
        EXPECT_GT(p.omega, last) << "the stop stiffens the mode";
        EXPECT_LT(p.omega, w_closed) << "below the mode with the stop held closed";
        last = p.omega;
    }
    EXPECT_GE(beyond, 9);
    EXPECT_LT(worst, 1e-12) << "an orbit that the independent integrator does not close";
    std::printf("[ info ] damped chain: linear omega %.12g, xi %.12g; orbits beyond the stop close to %.2g\n",
                static_cast<double>(w), static_cast<double>(xi), worst);
}

TEST(Modes, ContactDampingTakesMoreOutOnlyWhileTheStopIsClosed) {
    // kDampedChain with a dashpot in the stop: the same linear limit, a larger xi beyond the stop,
    // and orbits the RK4 closes as before.
    const Model plain = parse_model(kDampedChain, "damped-chain.toml");
    const Model model = parse_model(std::string(kDampedChain) + kContactDamping, "contact-damping.toml");
    ModesOptions o;
    o.dof = "b";
    o.from = 0.02;
    o.to = 0.5;
    o.points = 12;
    o.tolerance = 1e-13;
    const ModesResult r = modes(model, o), r0 = modes(plain, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    ASSERT_EQ(r0.status, ModesStatus::ok) << r0.message;
    EXPECT_EQ(r.linear_omega, r0.linear_omega);
    EXPECT_EQ(r.linear_damping_ratio, r0.linear_damping_ratio);
    ASSERT_EQ(r.points.size(), 12u);
    ASSERT_EQ(r0.points.size(), 12u);
    double worst = 0.0;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        if (p.amplitude <= 0.1 + 1e-9) {
            EXPECT_NEAR(p.xi, r0.points[i].xi, 1e-12) << "open: no contact damping";
            continue;
        }
        EXPECT_GT(p.xi, r0.points[i].xi + 1e-3) << p.amplitude;
        worst = std::max(worst, closure(p, [](const State& y, long double xi, long double t, int n) {
                             return damped_chain_rk4(y, xi, t, n, 0.5L);
                         }));
    }
    EXPECT_LT(worst, 1e-12);
    std::printf("[ info ] damped chain with contact damping: orbits close to %.2g\n", worst);
}

// m1 = 1 on k1 = 1 to the ground, a friction mass m2 = 0.05 (Coulomb to the ground, mu_s = mu_k,
// N = m2 g, mu N = 0.3) on k_t = 3 to it: with m2 stuck the oscillator of omega 2, and as m2 -> 0
// the Jenkins joint above.
const char* kFrictionMass =
    "name = \"friction-2dof\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[mass]]\nname = \"f\"\n"
    "m = 0.05\nmu_k = 0.61162079510703364\n[[spring]]\nbetween = [\"m\", \"ground\"]\nk = 1.0\n"
    "[[spring]]\nbetween = [\"m\", \"f\"]\nk = 3.0\n";

// The EPMC system of kFrictionMass from (x, v) over t by classical RK4 in long double (n steps),
// with its own stick-slip rules: sliding, m2 a2 = k_t (x1 - x2) + xi m2 v2 - F sign(v2); where v2
// passes 0 it sticks if |k_t (x1 - x2)| <= F, else slides back; stuck (v2 = 0) until |k_t (x1 -
// x2)| reaches F. Switches located within a step by bisection on the step length.
State friction_mass_rk4(State y, long double xi, long double t, int n) {
    using R = long double;
    const R m2 = 0.05L, F = 0.61162079510703364L * m2 * 9.81L, kt = 3;
    auto hold = [&](const State& z) { return kt * (z[0] - z[1]); };  // the spring's force on f
    auto field = [&](const State& z, int md) {                       // md: 0 stuck, +-1 sliding that way
        const R a1 = -z[0] - kt * (z[0] - z[1]) + xi * z[2];
        const R a2 = md == 0 ? R(0) : (hold(z) + xi * m2 * z[3] - F * md) / m2;
        return State{z[2], md == 0 ? R(0) : z[3], a1, a2};
    };
    auto keep = [&](const State& z, int md) { return md == 0 ? F - std::fabs(hold(z)) : z[3] * md; };
    auto next = [&](State& z, int md) {
        if (md != 0) z[3] = 0;
        return std::fabs(hold(z)) <= F && md != 0 ? 0 : (hold(z) > 0 ? 1 : -1);
    };
    const int start = y[3] != 0 ? (y[3] > 0 ? 1 : -1) : std::fabs(hold(y)) <= F ? 0 : (hold(y) > 0 ? 1 : -1);
    return switched_rk4(y, start, t, n, field, keep, next);
}

TEST(Modes, AFrictionMassGivesADampedModeThatAnIndependentStickSlipIntegratorCloses) {
    // Friction on a mass (here its own mu_k; a [[friction]] element to the ground is the same):
    // the linear limit holds it (omega 2, xi 0 up to the slip onset at A = F / k_t = 0.1); beyond
    // it each orbit, run from its turning point for one period by the RK4 above, comes back to it.
    const Model model = parse_model(kFrictionMass, "friction-2dof.toml");
    ModesOptions o;
    o.from = 0.05;
    o.to = 1.0;
    o.points = 10;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    EXPECT_TRUE(r.damped);
    EXPECT_NEAR(r.linear_omega, 2.0, 1e-14);
    EXPECT_EQ(r.linear_damping_ratio, 0.0);
    ASSERT_EQ(r.points.size(), 10u);
    EXPECT_NEAR(r.points.front().omega, 2.0, 1e-12);
    EXPECT_NEAR(r.points.front().xi, 0.0, 1e-12);
    double worst = 0.0;
    for (std::size_t i = 1; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        worst = std::max(worst, closure(p, friction_mass_rk4));
        EXPECT_GT(p.damping_ratio, 0.0) << p.amplitude;
        EXPECT_LT(p.omega, 2.0) << p.amplitude;
    }
    std::printf("[ info ] friction mass: orbits close to %.2g under an independent stick-slip RK4\n", worst);
    EXPECT_LT(worst, 1e-9);  // measured 1.3e-11 (shooting to 1e-11)

    // The same friction as a [[friction]] element to the ground with its own normal force (mu N =
    // 0.5 * 0.6 = 0.3): the same backbone.
    std::string text = kFrictionMass;
    text.replace(text.find("mu_k = 0.61162079510703364\n"), std::strlen("mu_k = 0.61162079510703364\n"), "");
    const Model element = parse_model(
        text + "[[friction]]\nname = \"pad\"\nbetween = [\"f\", \"ground\"]\nmu_k = 0.5\nnormal = 0.6\n", "pad.toml");
    o.to = 0.6;
    o.points = 3;
    const ModesResult e = modes(element, o), m = modes(model, o);
    ASSERT_EQ(e.status, ModesStatus::ok) << e.message;
    ASSERT_EQ(m.status, ModesStatus::ok) << m.message;
    for (std::size_t i = 0; i < e.points.size(); ++i) {
        EXPECT_NEAR(e.points[i].omega, m.points[i].omega, 1e-9) << e.points[i].amplitude;
        EXPECT_NEAR(e.points[i].xi, m.points[i].xi, 1e-9) << e.points[i].amplitude;
    }
}

// m = 1 on k = 1 to the ground and f = 0.05 on k_t = 3 to the ground, a [[friction]] between them
// (mu N = 0.5 * 0.6 = 0.3): stuck, f rides on m (omega sqrt(4 / 1.05)).
const char* kFrictionPair =
    "name = \"friction-pair\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[mass]]\nname = \"f\"\n"
    "m = 0.05\n[[spring]]\nbetween = [\"m\", \"ground\"]\nk = 1.0\n[[spring]]\nbetween = "
    "[\"f\", \"ground\"]\nk = 3.0\n[[friction]]\nname = \"pad\"\nbetween = [\"f\", \"m\"]\n"
    "mu_k = 0.5\nnormal = 0.6\n";

// The EPMC system of kFrictionPair by RK4 in long double with its own stick-slip rules on the
// relative velocity w = v_f - v_m: sliding, -F sign(w) on f and +F sign(w) on m; stuck, both at
// the common acceleration while the friction that takes, m_f a - (f's other forces), is at most F.
State friction_pair_rk4(State y, long double xi, long double t, int n) {
    using R = long double;
    const R mm = 1, mf = 0.05L, F = 0.3L;
    auto forces = [&](const State& z) {  // on m and on f, friction apart
        return std::array<R, 2>{-z[0] + xi * mm * z[2], -3 * z[1] + xi * mf * z[3]};
    };
    auto need = [&](const State& z) {  // the friction on f that keeps it with m
        const auto fo = forces(z);
        return mf * (fo[0] + fo[1]) / (mm + mf) - fo[1];
    };
    auto field = [&](const State& z, int md) {  // md: 0 stuck, +-1 the sign of w = v_f - v_m
        const auto fo = forces(z);
        if (md == 0) {
            const R a = (fo[0] + fo[1]) / (mm + mf);
            return State{z[2], z[3], a, a};
        }
        return State{z[2], z[3], (fo[0] + F * md) / mm, (fo[1] - F * md) / mf};
    };
    auto keep = [&](const State& z, int md) { return md == 0 ? F - std::fabs(need(z)) : (z[3] - z[2]) * md; };
    auto next = [&](State& z, int md) {
        if (md != 0) z[3] = z[2];
        return std::fabs(need(z)) <= F && md != 0 ? 0 : (need(z) > 0 ? -1 : 1);
    };
    const R w = y[3] - y[2];
    const int start = w != 0 ? (w > 0 ? 1 : -1) : std::fabs(need(y)) <= F ? 0 : (need(y) > 0 ? -1 : 1);
    return switched_rk4(y, start, t, n, field, keep, next);
}

TEST(Modes, FrictionBetweenTwoBodiesGivesADampedModeThatAnIndependentIntegratorCloses) {
    // Stuck, f moves with m: omega = sqrt((1 + 3) / (1 + 0.05)) with xi 0 up to the first slip;
    // beyond it the orbits close under the RK4 above.
    const Model model = parse_model(kFrictionPair, "friction-pair.toml");
    ModesOptions o;
    o.from = 0.05;
    o.to = 1.0;
    o.points = 8;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    const double w = std::sqrt(4.0 / 1.05);
    EXPECT_NEAR(r.linear_omega, w, 1e-14);
    ASSERT_EQ(r.points.size(), 8u);
    EXPECT_NEAR(r.points.front().omega, w, 1e-12);
    EXPECT_NEAR(r.points.front().x[1] - r.equilibrium[1], r.points.front().x[0] - r.equilibrium[0], 1e-15);
    double worst = 0.0;
    for (std::size_t i = 1; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        worst = std::max(worst, closure(p, friction_pair_rk4));
        EXPECT_GT(p.xi, 0.0) << p.amplitude;
    }
    std::printf("[ info ] friction between two bodies: orbits close to %.2g under an independent RK4\n", worst);
    EXPECT_LT(worst, 1e-9);
}

// m = 1 on k = 1 to the ground carrying two riders through frictions between bodies: f = 0.05
// on k = 3 (mu N = 0.3) and g = 0.1 on k = 1 (mu N = 0.4), each on a spring to the ground.
// All stuck, both ride m (omega sqrt(5 / 1.15)).
const char* kSharedDamper =
    "name = \"shared-damper\"\n[[mass]]\nname = \"m\"\nm = 1.0\n[[mass]]\nname = \"f\"\nm = 0.05\n"
    "[[mass]]\nname = \"g\"\nm = 0.1\n[[spring]]\nbetween = [\"m\", \"ground\"]\nk = 1.0\n"
    "[[spring]]\nbetween = [\"f\", \"ground\"]\nk = 3.0\n[[spring]]\nbetween = [\"g\", \"ground\"]\nk = 1.0\n"
    "[[friction]]\nname = \"pad\"\nbetween = [\"f\", \"m\"]\nmu_k = 0.5\nnormal = 0.6\n"
    "[[friction]]\nname = \"wedge\"\nbetween = [\"g\", \"m\"]\nmu_k = 0.4\nnormal = 1.0\n";

// The EPMC system of kSharedDamper by RK4 in long double with its own rules: a sliding rider i
// feels -F_i sign(w_i), w_i = v_i - v_m, and m the reaction; the stuck riders move with m at the
// acceleration of m and them together; a stuck rider slips when the friction that keeps it
// there, m_i a - (its other forces), exceeds F_i. The mode is 3 (s_f + 1) + (s_g + 1), s the
// sign of w (0 stuck); one rider switches at a time.
using State6 = std::array<long double, 6>;
State6 shared_damper_rk4(State6 y, long double xi, long double t, int n) {
    using R = long double;
    const std::array<R, 3> m{1, 0.05L, 0.1L}, k{1, 3, 1}, F{0, 0.3L, 0.4L};
    auto sign_of = [](int md, int i) { return i == 1 ? md / 3 - 1 : md % 3 - 1; };
    auto with = [](int md, int i, int s) { return i == 1 ? 3 * (s + 1) + md % 3 : md - md % 3 + (s + 1); };
    auto own = [&](const State6& z, int i) { return -k[i] * z[i] + xi * m[i] * z[3 + i]; };
    auto accel = [&](const State6& z, int md) {
        R mass = m[0], force = own(z, 0);
        std::array<R, 3> a{};
        for (int i = 1; i <= 2; ++i) {
            const int s = sign_of(md, i);
            if (s == 0) {
                mass += m[i], force += own(z, i);
            } else {
                force += F[i] * s;
                a[i] = (own(z, i) - F[i] * s) / m[i];
            }
        }
        a[0] = force / mass;
        for (int i = 1; i <= 2; ++i)
            if (sign_of(md, i) == 0) a[i] = a[0];
        return a;
    };
    auto need = [&](const State6& z, int md, int i) { return m[i] * accel(z, md)[0] - own(z, i); };
    auto field = [&](const State6& z, int md) {
        const auto a = accel(z, md);
        return State6{z[3], z[4], z[5], a[0], a[1], a[2]};
    };
    auto keep_i = [&](const State6& z, int md, int i) {
        const int s = sign_of(md, i);
        return s == 0 ? F[i] - std::fabs(need(z, md, i)) : (z[3 + i] - z[3]) * s;
    };
    auto keep = [&](const State6& z, int md) { return std::min(keep_i(z, md, 1), keep_i(z, md, 2)); };
    auto settle = [&](State6& z, int md, int i) {  // rider i with w_i = 0: stuck if its friction holds it
        z[3 + i] = z[3];
        const int stuck = with(md, i, 0);
        const R f = need(z, stuck, i);
        return std::fabs(f) <= F[i] ? stuck : with(md, i, f > 0 ? -1 : 1);
    };
    auto next = [&](State6& z, int md) {
        const int i = keep_i(z, md, 1) < keep_i(z, md, 2) ? 1 : 2;
        return sign_of(md, i) != 0 ? settle(z, md, i) : with(md, i, need(z, md, i) > 0 ? -1 : 1);
    };
    int start = 4;  // both stuck, then each rider's own state
    for (int i = 1; i <= 2; ++i) {
        const R w = y[3 + i] - y[3];
        start = w != 0 ? with(start, i, w > 0 ? 1 : -1) : settle(y, start, i);
    }
    return switched_rk4(y, start, t, n, field, keep, next);
}

TEST(Modes, APartnerCarryingTwoRidersGivesADampedModeThatAnIndependentIntegratorCloses) {
    // Stuck, f and g move with m: omega = sqrt((1 + 3 + 1) / (1 + 0.05 + 0.1)) with xi 0 up to
    // the first slip; beyond it the orbits (each rider sticking and slipping, together they
    // decide what the other holds) close under the RK4 above. (The backbone is not smooth where
    // a rider's stick phase begins or ends: 4 to 14 events a period over these points.)
    const Model model = parse_model(kSharedDamper, "shared-damper.toml");
    ModesOptions o;
    o.from = 0.05;
    o.to = 1.0;
    o.points = 8;
    const ModesResult r = modes(model, o);
    ASSERT_EQ(r.status, ModesStatus::ok) << r.message;
    const double w = std::sqrt(5.0 / 1.15);
    EXPECT_NEAR(r.linear_omega, w, 1e-14);
    ASSERT_EQ(r.points.size(), 8u);
    EXPECT_NEAR(r.points.front().omega, w, 1e-12);
    double worst = 0.0;
    for (std::size_t i = 1; i < r.points.size(); ++i) {
        const ModePoint& p = r.points[i];
        worst = std::max(worst, closure<6>(p, shared_damper_rk4));
        EXPECT_GT(p.xi, 0.0) << p.amplitude;
        std::printf("[ info ] A %.4f: omega %.6f, xi %.6f, %d events\n", p.amplitude, p.omega, p.xi, p.events);
    }
    std::printf("[ info ] a partner carrying two riders: orbits close to %.2g under an independent RK4\n", worst);
    EXPECT_LT(worst, 1e-9);
}

TEST(Modes, DampedModesRefuseEnergyAndNegativeAmplitudes) {
    const Model model = jenkins_oscillator();
    ModesOptions o;
    o.to = -0.5;
    EXPECT_THROW(modes(model, o), OptionError);
    o.to = 0.5;
    o.parameter = ModesParameter::energy;
    try {
        modes(model, o);
        ADD_FAILURE() << "energy accepted for a damped mode";
    } catch (const OptionError& e) {
        EXPECT_EQ(e.option(), "parameter");
    }
}

TEST(Modes, RefusesOptionsThatDoNotFit) {
    const Model model = chain();
    auto option = [&](const ModesOptions& o) {
        try {
            modes(model, o);
        } catch (const OptionError& e) {
            return e.option();
        }
        return std::string("accepted");
    };
    ModesOptions o;
    EXPECT_EQ(option(o), "to");  // required
    o.to = 0.2;
    o.mode = 3;
    EXPECT_EQ(option(o), "mode");
    o.mode = 1;
    o.dof = "m3";
    EXPECT_EQ(option(o), "dof");
    o.dof = "";
    o.from = -0.1;
    EXPECT_EQ(option(o), "from");
    o.from = NAN;
    o.points = 0;
    EXPECT_EQ(option(o), "points");
}

}  // namespace
}  // namespace hsnc
