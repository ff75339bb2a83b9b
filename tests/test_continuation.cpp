// hsnc sweep --continuation (api/hsnc/sweep.h, analysis/continuation.cpp):
// branches of periodic orbits against closed forms (the linear damped
// oscillator's F|H(omega)| and Floquet multipliers, Den Hartog's friction
// oscillator's amplitude and multipliers), the two folds of a hardening
// contact oscillator with its unstable middle branch between the up and
// down sweeps, how a branch stops; and a failing sweep point that does not
// stop the sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "continuation.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "hsnc/sweep.h"
#include "model_reader.h"
#include "number_text.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

constexpr double kPi = 3.14159265358979323846;

// x'' + 2 zeta x' + x = F sin(omega t) (Rayleigh alpha = 2 zeta).
const char* const kLinear = R"(
name = "linear"
[parameters]
omega = 1.0
zeta = 0.05
F = 2.5
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
)";

// m x'' + k x + F_f sign(x') = F0 sin(omega t), m = k = F0 = 1, F_f = beta.
const char* const kDenHartog = R"(
name = "den-hartog"
[parameters]
r = 2.0
beta = 0.3
g = 1.0
[[mass]]
name = "m"
m = 1.0
mu_k = "beta"
[[spring]]
between = ["ground", "m"]
k = 1.0
[[forcing]]
omega = "r"
amplitude = { m = 1.0 }
)";

// omega_n = 1, zeta = 0.02, a stiff stop (k = 10) at x = 0.5 (examples/hardening-stop.toml).
const char* const kHardening = R"(
name = "hardening"
[parameters]
omega = 1.0
F = 0.1
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[damping]
alpha = 0.04
[[contact]]
between = ["m", "ground"]
gap = 0.5
k = 10.0
[[forcing]]
omega = "omega"
amplitude = { m = "F" }
)";

SweepOptions continuation(const std::string& param, double from, double to, std::size_t points) {
    SweepOptions o;
    o.param = param;
    o.from = from;
    o.to = to;
    o.points = points;
    o.continuation = true;
    o.max_periods = 3000;
    return o;
}

// The response x = F |H| sin(omega t + phi), |H| = 1/sqrt((1 - w^2)^2 +
// (2 zeta w)^2), through resonance; the multipliers are exp(s T) for the
// eigenvalues s = -zeta +- i sqrt(1 - zeta^2): |mu| = exp(-zeta 2 pi / w).
TEST(ContinuationClosedForm, LinearOscillatorIsFHAllStable) {
    const SweepResult r = SweepPlan(kLinear, "linear.toml", {}, continuation("omega", 0.5, 1.5, 11)).run();
    ASSERT_GE(r.points.size(), 11u);
    EXPECT_TRUE(r.continuation);
    double previous = 0;
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("omega = " + std::to_string(p.value));
        const double w = p.value, X = 2.5 / std::sqrt((1 - w * w) * (1 - w * w) + (0.1 * w) * (0.1 * w));
        EXPECT_EQ(p.failure, "");
        EXPECT_EQ(p.stop, "");
        EXPECT_TRUE(p.settled);
        EXPECT_NEAR(p.xmax[0] / X, 1.0, 1e-8);
        EXPECT_NEAR(p.a1[0] / X, 1.0, 1e-8);
        EXPECT_NEAR(p.xrms[0] / (X / std::sqrt(2.0)), 1.0, 1e-8);
        EXPECT_TRUE(p.stable);
        EXPECT_NEAR(p.max_multiplier, std::exp(-0.05 * 2 * kPi / w), 1e-10);
        EXPECT_EQ(p.bifurcation, "");
        EXPECT_EQ(p.direction, SweepDirection::up);
        EXPECT_GT(w, previous);  // no turning point
        previous = w;
    }
    EXPECT_EQ(r.points.front().value, 0.5);
    EXPECT_EQ(r.points.back().value, 1.5);  // landed on --to
    // The steps follow the curve: closer at the resonance peak than on its flanks.
    double near_peak = 1, far = 0;
    for (std::size_t k = 1; k < r.points.size(); ++k) {
        const double w = r.points[k].value, dw = w - r.points[k - 1].value;
        if (std::fabs(w - 1) < 0.05) near_peak = std::min(near_peak, dw);
        if (w < 0.7) far = std::max(far, dw);
    }
    EXPECT_LT(near_peak, 0.5 * far);
    std::printf("linear oscillator: %zu points from 0.5 to 1.5\n", r.points.size());
}

// Den Hartog (1930): X = sqrt(V^2 - beta^2 U^2), U = tan(pi/(2r))/r,
// V = 1/(1 - r^2); multipliers mu = lambda^2 with lambda^2 - cos(pi/r)(1 +
// rho) lambda + rho = 0, rho = (r^2 X - beta)/(r^2 X + beta). Both
// directions, two friction levels.
TEST(ContinuationClosedForm, DenHartogAmplitudeAndMultipliers) {
    SweepOptions o = continuation("r", 1.5, 3.0, 7);
    o.direction = SweepDirection::both;
    o.param2 = "beta";
    o.values2 = {0.1, 0.3};
    const SweepResult r = SweepPlan(kDenHartog, "den-hartog.toml", {}, o).run();
    std::size_t points = 0, ups = 0, downs = 0;
    for (const SweepPoint& p : r.points) {
        SCOPED_TRACE("r = " + std::to_string(p.value) + ", beta = " + std::to_string(p.value2));
        const double rr = p.value, beta = p.value2;
        const double U = std::tan(kPi / (2 * rr)) / rr, V = 1 / (1 - rr * rr);
        const double X = std::sqrt(V * V - beta * beta * U * U);
        const double rho = (rr * rr * X - beta) / (rr * rr * X + beta);
        const std::complex<double> b = -std::cos(kPi / rr) * (1 + rho), disc = std::sqrt(b * b - 4.0 * rho);
        const std::complex<double> l1 = (-b + disc) / 2.0, l2 = (-b - disc) / 2.0;
        const double mu = std::max(std::abs(l1 * l1), std::abs(l2 * l2));
        EXPECT_EQ(p.failure, "");
        EXPECT_EQ(p.stop, "");
        EXPECT_NEAR(p.xmax[0] / X, 1.0, 1e-8);
        EXPECT_NEAR(p.max_multiplier, mu, 1e-9);
        EXPECT_EQ(p.stable, mu < 1);
        EXPECT_EQ(p.bifurcation, "");
        ++points;
        if (p.branch_start) (p.direction == SweepDirection::up ? ups : downs)++;
    }
    EXPECT_EQ(ups, 2u);
    EXPECT_EQ(downs, 2u);
    EXPECT_GE(points, 4u * 7u);
}

// The hardening oscillator's branch bends to the right: followed from 0.8
// to 2.0 it turns back at a fold, runs back along an unstable middle branch
// to a second fold and on along the lower branch to 2.0. Folds are marked
// where the largest multiplier crosses +1 (det(M - I) changes sign) and the
// parameter turns; the middle branch lies between the branches an up and a
// down sweep end on.
TEST(ContinuationClosedForm, HardeningOscillatorPassesTwoFolds) {
    const SweepResult c = SweepPlan(kHardening, "hardening.toml", {}, continuation("omega", 0.8, 2.0, 25)).run();
    ASSERT_GE(c.points.size(), 25u);
    EXPECT_EQ(c.points.front().value, 0.8);
    EXPECT_EQ(c.points.back().value, 2.0);
    std::vector<std::size_t> folds;
    for (std::size_t k = 0; k < c.points.size(); ++k) {
        const SweepPoint& p = c.points[k];
        EXPECT_EQ(p.failure, "");
        EXPECT_EQ(p.stop, "");
        // The lower branch's fold is where it leaves the stop: a grazing
        // crossed with it (GrazingOfALinearOscillatorIsLocatedToRounding).
        EXPECT_TRUE(p.bifurcation == "" || p.bifurcation == "fold" || p.bifurcation == "grazing" ||
                    p.bifurcation == "fold+grazing")
            << p.bifurcation;
        const bool fold = p.bifurcation.rfind("fold", 0) == 0;
        if (fold) folds.push_back(k);
        // Stable exactly outside the two folds.
        if (k > 0) EXPECT_EQ(p.stable != c.points[k - 1].stable, fold) << "point " << k;
    }
    ASSERT_EQ(folds.size(), 2u);
    for (std::size_t f : folds) {
        // The largest multiplier crosses 1 between the marked point and the one before.
        const double a = c.points[f - 1].max_multiplier, b = c.points[f].max_multiplier;
        EXPECT_LT(std::min(a, b), 1.0);
        EXPECT_GT(std::max(a, b), 1.0);
        // The parameter turns there.
        ASSERT_GE(f, 2u);
        ASSERT_LT(f + 1, c.points.size());
        const double d1 = c.points[f - 1].value - c.points[f - 2].value, d2 = c.points[f + 1].value - c.points[f].value;
        EXPECT_LT(d1 * d2, 0) << "fold at omega = " << c.points[f].value;
    }
    const double upper_fold = c.points[folds[0]].value, lower_fold = c.points[folds[1]].value;
    EXPECT_GT(upper_fold, 1.35);
    EXPECT_LT(lower_fold, 1.15);
    for (std::size_t k = 0; k < c.points.size(); ++k) EXPECT_EQ(c.points[k].stable, k < folds[0] || k >= folds[1]);

    // The up and down sweeps on a grid of 0.05.
    SweepOptions o;
    o.param = "omega";
    o.from = 0.8;
    o.to = 2.0;
    o.points = 25;
    o.direction = SweepDirection::both;
    o.max_periods = 3000;
    const SweepResult s = SweepPlan(kHardening, "hardening.toml", {}, o).run();
    ASSERT_EQ(s.points.size(), 50u);
    std::size_t checked = 0;
    for (std::size_t k = folds[0]; k < folds[1]; ++k) {
        const SweepPoint& u = c.points[k];
        // Bracketing grid values where the sweeps are on different branches.
        const std::size_t j = static_cast<std::size_t>(std::floor((u.value - 0.8) / 0.05));
        if (j + 1 >= 25) continue;
        const SweepPoint &up0 = s.points[j], &up1 = s.points[j + 1];
        const SweepPoint &down0 = s.points[49 - j], &down1 = s.points[49 - (j + 1)];
        ASSERT_EQ(up0.value, down0.value);
        if (!(up0.xmax[0] > 1.5 * down0.xmax[0] && up1.xmax[0] > 1.5 * down1.xmax[0])) continue;
        // The lower branch is linear (below the stop): its closed form. Over
        // the interval the up sweep's branch rises with omega and the down
        // sweep's falls, so each lies beyond its value at one end.
        const double w = u.value;
        const double lower = 0.1 / std::sqrt((1 - w * w) * (1 - w * w) + (0.04 * w) * (0.04 * w));
        EXPECT_GT(u.xmax[0], lower) << "omega = " << w;
        EXPECT_GT(u.xmax[0], std::max(down0.xmax[0], down1.xmax[0])) << "omega = " << w;
        EXPECT_LT(u.xmax[0], std::min(up0.xmax[0], up1.xmax[0])) << "omega = " << w;
        EXPECT_LT(up0.xmax[0], up1.xmax[0]);
        EXPECT_GT(down0.xmax[0], down1.xmax[0]);
        ++checked;
    }
    EXPECT_GE(checked, 3u);
    std::printf("hardening: %zu points, folds at omega = %.6f and %.6f, %zu middle points between the sweeps\n",
                c.points.size(), upper_fold, lower_fold, checked);
}

// Grazing located as a point of the branch: the hardening oscillator's
// lower branch is linear until its amplitude F |H(omega)| reaches the stop's
// gap, at (1 - w^2)^2 + (0.04 w)^2 = (F / gap)^2 (w = 0.896236122676936057...
// for F = 0.1, gap 0.5); the row says "grazing", its xmax is the gap, and it
// lies between its neighbours. A preloaded contact (gap -0.1: closed at rest,
// x_e = k_c gap / (1 + k_c)) lifts off where x_e - F |H_c| = gap, H_c the
// closed oscillator's (stiffness 1 + k_c): the smallest G crossing zero.
TEST(ContinuationClosedForm, GrazingOfALinearOscillatorIsLocatedToRounding) {
    struct Case {
        std::string model;
        double from, to, omega, xmax;
        bool lift_off;
        ModelOverrides start;
    };
    auto root = [](double k, double zeta2, double ratio, bool lower) {
        // (k - s)^2 + zeta2^2 s = ratio^2 in s = w^2.
        const double b = 2 * k - zeta2 * zeta2, c = k * k - ratio * ratio;
        const double s = lower ? (b - std::sqrt(b * b - 4 * c)) / 2 : (b + std::sqrt(b * b - 4 * c)) / 2;
        return std::sqrt(s);
    };
    std::string preloaded = kHardening;
    preloaded.replace(preloaded.find("gap = 0.5"), 9, "gap = -0.1");
    preloaded.replace(preloaded.find("F = 0.1"), 7, "F = 0.05");
    const double xe = 10 * -0.1 / 11;
    // The preloaded one starts at rest at x_e, on the closed branch (from x = 0
    // the transient settles on a lifted-off orbit at low omega).
    const Case cases[] = {{kHardening, 0.8, 2.0, root(1.0, 0.04, 0.1 / 0.5, true), 0.5, false, {}},
                          {preloaded, 0.5, 2.6, root(11.0, 0.04, 0.05 / (xe + 0.1), true), 0.1, true,
                           ModelOverrides{{}, {"m=" + std::to_string(xe)}, {}, {}}}};
    for (const Case& k : cases) {
        SCOPED_TRACE(k.lift_off ? "lift-off" : "closing");
        const SweepResult r =
            SweepPlan(k.model, "hardening.toml", k.start, continuation("omega", k.from, k.to, 25)).run();
        std::vector<std::size_t> grazing;
        for (std::size_t i = 0; i < r.points.size(); ++i)
            if (r.points[i].bifurcation == "grazing") grazing.push_back(i);
        ASSERT_EQ(grazing.size(), 1u);
        const std::size_t g = grazing[0];
        ASSERT_GT(g, 0u);
        ASSERT_LT(g + 1, r.points.size());
        const SweepPoint& p = r.points[g];
        EXPECT_NEAR(p.value, k.omega, 1e-14 * k.omega);
        EXPECT_NEAR(p.xmax[0], k.xmax, 1e-13);
        ASSERT_EQ(p.gap_max.size(), 1u);
        EXPECT_NEAR(k.lift_off ? p.gap_min[0] : p.gap_max[0], 0.0, 1e-14);
        EXPECT_LT(r.points[g - 1].value, p.value);
        EXPECT_GT(r.points[g + 1].value, p.value);
        EXPECT_TRUE(p.stable);
        EXPECT_EQ(p.periods, 0u);
        std::printf("grazing at omega = %.17g, closed form %.17g\n", p.value, k.omega);
    }
}

// The hardening oscillator's lower fold is where its branch leaves the
// stop: the unstable middle branch turns (at 1.0932185 rad/s, a multiplier
// through +1, still touching) and leaves the stop 1.6e-5 rad/s higher at
// the orbit that just touches it, whose amplitude is the linear one,
// F |H| = gap, on the upper root. The step that crosses the fold and the
// grazing together locates the grazing along the chord (the parameter is
// no coordinate of the branch at a fold): a row of its own, fold+grazing
// (the fold crossed since the row before), at the closed-form frequency to
// rounding; the next row says no fold.
TEST(ContinuationClosedForm, FoldAtAGrazingIsLocatedToRounding) {
    // (1 - s)^2 + 0.04^2 s = (0.1 / 0.5)^2 in s = omega^2, the upper root.
    const double b = 2 - 0.04 * 0.04, c = 1 - 0.2 * 0.2;
    const double omega = std::sqrt((b + std::sqrt(b * b - 4 * c)) / 2);
    for (const std::size_t points : {25u, 29u}) {
        SCOPED_TRACE(points);
        const SweepResult r =
            SweepPlan(kHardening, "hardening.toml", {}, continuation("omega", 0.6, 2.0, points)).run();
        std::vector<std::size_t> rows;
        for (std::size_t i = 0; i < r.points.size(); ++i)
            if (r.points[i].bifurcation == "fold+grazing") rows.push_back(i);
        ASSERT_EQ(rows.size(), 1u);
        const std::size_t g = rows[0];
        ASSERT_GT(g, 0u);
        ASSERT_LT(g + 1, r.points.size());
        const SweepPoint& p = r.points[g];
        EXPECT_NEAR(p.value, omega, 1e-14 * omega);
        EXPECT_NEAR(p.xmax[0], 0.5, 1e-13);
        ASSERT_EQ(p.gap_max.size(), 1u);
        EXPECT_NEAR(p.gap_max[0], 0.0, 1e-14);
        EXPECT_EQ(p.periods, 0u);
        EXPECT_TRUE(p.stable);
        EXPECT_FALSE(r.points[g - 1].stable);       // the middle branch
        EXPECT_GT(r.points[g - 1].value, p.value);  // the parameter turned since the row before
        EXPECT_GT(r.points[g + 1].value, p.value);
        EXPECT_EQ(r.points[g + 1].bifurcation.find("fold"), std::string::npos) << r.points[g + 1].bifurcation;
        EXPECT_LT(r.points[g + 1].xmax[0], 0.5);  // the lower branch, off the stop
        std::printf("fold at grazing: omega = %.17g, closed form %.17g\n", p.value, omega);
    }
}

// Through stick-slip transitions: the bundled friction damper (a Jenkins
// element at the platform) is stuck all period at low and high omega and
// slips near the resonance; the branch passes both transitions, each row
// saying what its orbit does (SweepPoint::sticks, slips: the Jenkins element
// slips only between the two `slip_onset` rows), the family of stuck orbits
// (the slider may sit anywhere: a multiplier at +1 that rounding puts on
// either side of 1) gives no fold, and the slipping orbits are those
// `hsnc periodic` finds at the same omega (a unique orbit: 1e-8).
TEST(ContinuationClosedForm, FrictionDamperThroughStickAndSlipOnset) {
    const std::string path = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml";
    const SweepResult r = SweepPlan::from_file(path, {}, continuation("omega", 6.0, 20.0, 15)).run();
    ASSERT_FALSE(r.points.empty());
    EXPECT_EQ(r.points.back().value, 20.0);
    std::vector<std::size_t> onsets;
    const std::size_t j = r.masses.size();  // the Jenkins element's flag, after the masses'
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        EXPECT_EQ(p.stop, "");
        EXPECT_TRUE(p.bifurcation == "" || p.bifurcation == "slip_onset") << p.bifurcation << " at " << p.value;
        if (p.bifurcation == "slip_onset") onsets.push_back(k);
        ASSERT_EQ(p.slips.size(), j + 1);
        EXPECT_EQ(p.sticks[j], 1);  // stuck all period, or at every turn while slipping
    }
    ASSERT_EQ(onsets.size(), 2u);
    EXPECT_GT(r.points[onsets[0]].value, 7.0);
    EXPECT_LT(r.points[onsets[1]].value, 11.0);
    std::size_t compared = 0;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        const bool slipping = k >= onsets[0] && k < onsets[1];
        EXPECT_EQ(p.slips[j], slipping ? 1 : 0) << "omega = " << p.value;
        if (!slipping || k % 4 != 0) continue;
        // hsnc periodic at this omega, from the steady state of a long run.
        PeriodicOptions po;
        po.kernels = KernelChoice::eigen;
        po.transient = 300 * 2 * kPi / p.value;
        const PeriodicResult orbit =
            periodic(read_model(path, ModelOverrides{{"omega=" + shortest_text(p.value)}, {}, {}, {}}), po);
        ASSERT_EQ(orbit.status, PeriodicStatus::ok) << orbit.message;
        EXPECT_FALSE(orbit.stable && orbit.neutral > 0);  // slipping: no family
        // The orbit's state at t0 against the row's diagram state (one period after t0, the same on an orbit).
        for (std::size_t i = 0; i < j; ++i) {
            EXPECT_NEAR(orbit.x[i], p.strobe_x[i], 1e-8) << "omega = " << p.value << ", mass " << i;
            EXPECT_NEAR(orbit.v[i], p.strobe_v[i], 1e-7) << "omega = " << p.value << ", mass " << i;
        }
        ++compared;
    }
    EXPECT_GE(compared, 3u);
}

// Stick onset: Den Hartog's friction oscillator x'' + x + beta sgn(x') =
// sin(r t) (beta = 0.5) stops in every half period at low r and moves
// without stopping above r*, where the non-stop orbit's force at its
// reversal, A + sin(r t0), equals beta: from the half-wave symmetric orbit
// in closed form, beta^2 (1 - r^2)^2 (tan^2(pi / 2r) / r^2 + 1 / r^4) = 1,
// r* = 0.58497494298499... The continuation from r = 0.4 up locates it (a
// row of its own, `stick_onset`, to 1e-12), its rows' sticks flags agree,
// and so does an independent long run (the engine's own stick events in
// its last 20 periods) at the rows either side.
TEST(ContinuationClosedForm, DenHartogStickOnset) {
    const SweepResult r = SweepPlan(kDenHartog, "den-hartog.toml", ModelOverrides{{"beta=0.5"}, {}, {}, {}},
                                    continuation("r", 0.4, 0.9, 11))
                              .run();
    std::vector<std::size_t> onset;
    for (std::size_t k = 0; k < r.points.size(); ++k)
        if (!r.points[k].bifurcation.empty()) {
            EXPECT_EQ(r.points[k].bifurcation, "stick_onset");
            onset.push_back(k);
        }
    ASSERT_EQ(onset.size(), 1u);
    const std::size_t g = onset[0];
    ASSERT_GT(g, 0u);
    ASSERT_LT(g + 1, r.points.size());
    for (std::size_t k = 0; k < r.points.size(); ++k) EXPECT_EQ(r.points[k].sticks[0], k < g ? 1 : 0) << k;
    const double beta = 0.5;
    auto boundary = [&](double x) {
        const double t = std::tan(kPi / (2 * x));
        return beta * beta * (1 - x * x) * (1 - x * x) * (t * t / (x * x) + 1 / (x * x * x * x)) - 1;
    };
    double lo = 0.55, hi = 0.6;  // boundary > 0 below r*, < 0 above
    for (int i = 0; i < 200 && hi - lo > 0; ++i) (boundary(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
    EXPECT_NEAR(r.points[g].value, lo, 1e-12 * lo);
    EXPECT_EQ(r.points[g].periods, 0u);
    class Sticks : public Observer {
    public:
        explicit Sticks(double from) : from_(from) {}
        void on_sample(double, const double*, const double*) override {}
        void on_event(double t, EventKind kind, int, const double*, const double*) override {
            count += t > from_ && kind == EventKind::stick;
        }
        std::size_t count = 0;

    private:
        double from_;
    };
    for (const std::size_t k : {g - 1, g + 1}) {
        const double rr = r.points[k].value, T = 2 * kPi / rr;
        Model m = parse_model(kDenHartog, "den-hartog.toml",
                              ModelOverrides{{"beta=0.5", "r=" + shortest_text(rr)}, {}, {}, {}});
        SimulateOptions so;
        so.t_end = 400 * T;
        Sticks sticks(380 * T);
        ASSERT_EQ(simulate(m, so, sticks).status, RunStatus::ok);
        EXPECT_EQ(sticks.count > 0, k < g) << "r = " << rr << ": " << sticks.count << " stops";
    }
    std::printf("Den Hartog, beta 0.5: stops end at r = %.17g, closed form %.17g\n", r.points[g].value, lo);
}

// m x'' + 0.05 x' + x + (Jenkins: k_t = 1, F_s = 0.1) = 0.1 sin(omega t).
const char* const kJenkinsOscillator = R"(
name = "jenkins-1dof"
[parameters]
omega = 1.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["ground", "m"]
k = 1.0
[[jenkins]]
name = "joint"
between = ["m", "ground"]
k = 1.0
slip_force = 0.1
[damping]
alpha = 0.05
[[forcing]]
omega = "omega"
amplitude = { m = 0.1 }
)";

// The issue's two cases, continued to the end through stick and slip onset:
// a 1-dof oscillator with a Jenkins element (the continuation stopped at the
// first slip onset: "the Newton residual stops falling") and the bundled
// under-platform damper (it walked along the family of stuck orbits, the
// sliders' positions, at one omega until its step budget ran out). While the
// element is stuck all period the orbits form a family (the slider anywhere);
// the branch takes its centred member, the stretch symmetric in the slip
// band, which for the 1-dof oscillator is the linear closed form F |H| of
// the stuck system (stiffness 2) about x = 0; the slipping orbits are
// `hsnc periodic`'s at the same omega; each slip onset is located where that
// closed form's stretch reaches the slip band.
// The 1-dof oscillator's branch (model `text`, its joint along u = w x):
// the slip onsets where the closed form puts them, the stuck rows the linear
// response, the slipping rows the orbits `periodic` finds.
void jenkins_oscillator_through_slip_onset(const std::string& text, double w_joint) {
    const SweepResult r = SweepPlan(text, "jenkins.toml", {}, continuation("omega", 0.5, 3.0, 26)).run();
    ASSERT_FALSE(r.points.empty());
    EXPECT_EQ(r.points.back().value, 3.0);
    std::vector<std::size_t> onsets;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        EXPECT_EQ(r.points[k].stop, "");
        EXPECT_TRUE(r.points[k].bifurcation == "" || r.points[k].bifurcation == "slip_onset")
            << r.points[k].bifurcation;
        if (r.points[k].bifurcation == "slip_onset") onsets.push_back(k);
    }
    ASSERT_EQ(onsets.size(), 2u);
    // Located to rounding where the stuck system's stretch amplitude reaches
    // the slip band, k_t F |H_stuck| = F_s: |2 - w^2 + 0.05 i w| = 1, a
    // quadratic in w^2.
    const double b = 4 - 0.05 * 0.05, d = std::sqrt(b * b - 4 * 3);
    const double roots[2] = {std::sqrt((b - d) / 2), std::sqrt((b + d) / 2)};
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_NEAR(r.points[onsets[i]].value, roots[i], 1e-12 * roots[i]);
        EXPECT_EQ(r.points[onsets[i]].periods, 0u);
        std::printf("Jenkins slip onset at omega = %.17g, closed form %.17g\n", r.points[onsets[i]].value, roots[i]);
    }
    std::size_t stuck = 0, compared = 0;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
        const SweepPoint& p = r.points[k];
        const double w = p.value;
        SCOPED_TRACE("omega = " + std::to_string(w));
        if (k < onsets[0] || k >= onsets[1]) {
            ASSERT_EQ(p.slips[1], 0);
            const double A = 0.1 / std::abs(std::complex<double>(2 - w * w, 0.05 * w));
            EXPECT_NEAR(p.xmax[0], A, 1e-10);
            EXPECT_NEAR(p.stretch_max[0], -p.stretch_min[0], 1e-12);
            EXPECT_NEAR(p.stretch_max[0], w_joint * A, 1e-10);  // the stretch of u = w x about the centred slider
            ++stuck;
            continue;
        }
        ASSERT_EQ(p.slips[1], 1);
        if (k % 8 != 0) continue;
        PeriodicOptions po;
        po.kernels = KernelChoice::eigen;
        po.transient = 300 * 2 * kPi / w;
        const PeriodicResult orbit =
            periodic(parse_model(text, "jenkins.toml", ModelOverrides{{"omega=" + shortest_text(w)}, {}, {}, {}}), po);
        ASSERT_EQ(orbit.status, PeriodicStatus::ok) << orbit.message;
        EXPECT_NEAR(orbit.x[0], p.strobe_x[0], 1e-8);
        EXPECT_NEAR(orbit.v[0], p.strobe_v[0], 1e-8);
        ++compared;
    }
    EXPECT_GE(stuck, 10u);
    EXPECT_GE(compared, 3u);
}

TEST(ContinuationClosedForm, JenkinsOscillatorAndUnderPlatformDamperCompleteThroughSlipOnset) {
    // The joint written between the mass and the ground, and along the
    // scaled direction u = 2 x with k/4 and slip_force/2 (the same element,
    // interface.md "Jenkins elements along a direction"): the same closed forms.
    std::string scaled = kJenkinsOscillator;
    scaled.replace(scaled.find("between = [\"m\", \"ground\"]\nk = 1.0\nslip_force = 0.1"), 50,
                   "direction = { m = 2.0 }\nk = 0.25\nslip_force = 0.05");
    for (const std::string& text : {std::string(kJenkinsOscillator), scaled}) {
        SCOPED_TRACE(text == scaled ? "along u = 2 x" : "between m and ground");
        jenkins_oscillator_through_slip_onset(text, text == scaled ? 2.0 : 1.0);
    }

    const std::string path = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/under_platform_damper.toml";
    const SweepResult u = SweepPlan::from_file(path, {}, continuation("omega", 6.0, 14.0, 17)).run();
    ASSERT_FALSE(u.points.empty());
    EXPECT_EQ(u.points.back().value, 14.0);
    EXPECT_EQ(u.points.back().stop, "");
    std::size_t slip_onsets = 0;
    for (const SweepPoint& p : u.points) {
        EXPECT_TRUE(p.bifurcation == "" || p.bifurcation == "slip_onset") << p.bifurcation << " at " << p.value;
        slip_onsets += p.bifurcation == "slip_onset";
    }
    EXPECT_EQ(slip_onsets, 2u);
}

// The same continuation on 1 and 2 threads (both directions: two branches): bit-equal.
TEST(Continuation, ThreadsGiveTheSameBits) {
    SweepOptions o = continuation("omega", 0.8, 2.0, 13);
    o.direction = SweepDirection::both;
    const SweepResult one = SweepPlan(kHardening, "hardening.toml", {}, o).run();
    o.threads = 2;
    const SweepResult two = SweepPlan(kHardening, "hardening.toml", {}, o).run();
    ASSERT_EQ(one.points.size(), two.points.size());
    for (std::size_t i = 0; i < one.points.size(); ++i) {
        EXPECT_EQ(one.points[i].value, two.points[i].value);
        EXPECT_EQ(one.points[i].xmax, two.points[i].xmax);
        EXPECT_EQ(one.points[i].max_multiplier, two.points[i].max_multiplier);
        EXPECT_EQ(one.points[i].bifurcation, two.points[i].bifurcation);
    }
}

// Shooting that fails stops the branch: no row for the failed step, the
// reason on the last point. Here the model is invalid beyond omega = 1.3
// (the model reader refuses it there, as it refuses a negative stiffness).
TEST(Continuation, ShootingFailureStopsTheBranch) {
    const SweepOptions o = continuation("omega", 0.5, 1.5, 11);
    const SweepPlan plan(kLinear, "linear.toml", {}, o);
    sweep_detail::Branch b;
    b.param = "omega";
    b.where = " (up)";
    b.start = 0.5;
    b.end = 1.5;
    b.value2 = std::nan("");
    b.start_model = &plan.model();
    Model start = plan.model();
    start.forcing[0].omega = 0.5;
    b.start_model = &start;
    b.model_at = [](double w) {
        if (w > 1.3) throw InputError("linear.toml: omega = " + std::to_string(w) + ": refused");
        char text[40];
        std::snprintf(text, sizeof text, "omega=%.17g", w);
        return parse_model(kLinear, "linear.toml", ModelOverrides{{text}, {}, {}, {}});
    };
    std::size_t reported = 0;
    const std::vector<SweepPoint> pts =
        sweep_detail::run_continuation(b, o, [&](const SweepPoint&, double) { ++reported; });
    ASSERT_GE(pts.size(), 5u) << pts.back().failure << pts.back().stop;
    EXPECT_EQ(reported, pts.size());
    for (const SweepPoint& p : pts) EXPECT_LE(p.value, 1.3);
    EXPECT_GT(pts.back().value, 1.29);
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) EXPECT_EQ(pts[k].stop, "");
    EXPECT_NE(pts.back().stop.find("shooting fails beyond omega = "), std::string::npos) << pts.back().stop;
    EXPECT_NE(pts.back().stop.find("refused"), std::string::npos) << pts.back().stop;
}

TEST(Continuation, Bifurcations) {
    using C = std::complex<double>;
    // A real multiplier through +1; through -1; a complex pair through the circle.
    EXPECT_EQ(sweep_detail::bifurcations_between({C(0.9, 0), C(0.2, 0)}, {C(1.1, 0), C(0.2, 0)}), "fold");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(-0.9, 0), C(0.2, 0)}, {C(-1.1, 0), C(0.2, 0)}), "period_doubling");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(0.5, 0.8), C(0.5, -0.8)}, {C(0.6, 0.9), C(0.6, -0.9)}),
              "neimark_sacker");
    // A complex pair outside the circle meeting on the real axis: nothing.
    EXPECT_EQ(sweep_detail::bifurcations_between({C(1.5, 0.1), C(1.5, -0.1)}, {C(1.6, 0), C(1.4, 0)}), "");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(0.5, 0.1), C(0.5, -0.1)}, {C(0.6, 0), C(0.4, 0)}), "");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(0.9, 0)}, {C(0.95, 0)}), "");
    // A family's multiplier at +1 that rounding puts on either side: no fold
    // (it counts as inside); one that leaves the family's +1 outward: a fold.
    EXPECT_EQ(sweep_detail::bifurcations_between({C(1 + 1e-13, 0), C(0.5, 0)}, {C(1 - 1e-13, 0), C(0.5, 0)}), "fold");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(1 + 1e-13, 0), C(0.5, 0)}, {C(1 - 1e-13, 0), C(0.5, 0)}, 1, 1), "");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(1 + 1e-13, 0), C(0.5, 0)}, {C(0.97, 0), C(0.5, 0)}, 1, 0), "");
    EXPECT_EQ(sweep_detail::bifurcations_between({C(1 - 1e-13, 0), C(0.5, 0)}, {C(1.2, 0), C(0.5, 0)}, 1, 0), "fold");
}

// ---- the command line ----

TEST(ContinuationCli, CurveColumnsPlotAndBudget) {
    const std::string model = write_temp("hardening.toml", kHardening);
    const std::string out = temp_path("cont.csv"), png = temp_path("cont.png"), diagram = temp_path("cd.csv");
    const auto r = run_hsnc("sweep '" + model + "' --param omega --from 0.8 --to 2.0 --points 25 --continuation --quiet" +
                            " --out '" + out + "' --plot '" + png + "' --diagram '" + diagram + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(r.out.substr(0, 10), "status=ok ");
    EXPECT_NE(r.out.find(" bifurcations=3 stopped=0"), std::string::npos) << r.out;  // two folds, a grazing
    const std::string curve = slurp(out);
    EXPECT_EQ(curve.substr(0, curve.find('\n')),
              "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m,stable,max_multiplier,bifurcation");
    // The diagram: one period of each orbit, one row per point.
    const std::string d = slurp(diagram);
    EXPECT_EQ(std::count(curve.begin(), curve.end(), '\n'), std::count(d.begin(), d.end(), '\n'));
    EXPECT_NE(curve.find(",false,"), std::string::npos);
    EXPECT_NE(curve.find(",fold\n"), std::string::npos);
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");

    // A step budget that runs out: the rows so far, a message, exit 1.
    const std::string out2 = temp_path("cont2.csv");
    const auto b = run_hsnc("sweep '" + model + "' --param omega --from 0.8 --to 2.0 --points 25 --continuation " +
                            "--max-steps 20 --quiet --out '" + out2 + "'");
    EXPECT_EQ(b.exit_code, 1);
    EXPECT_NE(b.err.find("the step budget (20 points) ran out at omega = "), std::string::npos) << b.err;
    const std::string c2 = slurp(out2);
    EXPECT_EQ(std::count(c2.begin(), c2.end(), '\n'), 21);
    EXPECT_EQ(b.out.substr(0, 14), "status=failed ");

    // Progress lines name stability and bifurcations.
    const auto p = run_hsnc("sweep '" + model + "' --param omega --from 1.0 --to 1.5 --points 5 --continuation");
    ASSERT_EQ(p.exit_code, 0) << p.err;
    EXPECT_NE(p.err.find("hsnc sweep: branch point 1 omega = 1 (up): stable, max |multiplier| "), std::string::npos)
        << p.err;
    EXPECT_NE(p.err.find("crossed: fold"), std::string::npos) << p.err;

    // What does not go with it: bad input, nothing written.
    const std::string never = temp_path("never.csv");
    const std::string base = "sweep '" + model + "' --param omega --from 0.8 --to 2.0 --out '" + never + "' ";
    for (const std::string& flags :
         {std::string("--points 5 --continuation --restart-each"), std::string("--points 5 --continuation --method rk45"),
          std::string("--points 1 --continuation"), std::string("--points 5 --max-steps 5")}) {
        SCOPED_TRACE(flags);
        const auto e = run_hsnc(base + flags);
        EXPECT_EQ(e.exit_code, 2) << e.err;
        EXPECT_FALSE(file_exists(never));
    }
}

// ---- a failing point does not stop a sweep ----

// x'' + k x + (contact at 0, k 12) = sin(t): k = 10^(300 exp(-100 (p - 2)^2))
// is about 1 at p = 1 and p = 3, and 1e300 at p = 2, where the run fails at
// once (the switch functions overflow: status failure).
const char* const kZenoInTheMiddle = R"M(
name = "zeno-in-the-middle"
[parameters]
p = 1.0
[[mass]]
name = "m"
m = 1.0
[[spring]]
between = ["m", "ground"]
k = "pow(10, 300*exp(-100*(p - 2)^2))"
[[contact]]
between = ["m", "ground"]
gap = 0
k = 12
[damping]
alpha = 0.1
[[forcing]]
omega = 1.0
amplitude = { m = 1.0 }
[initial]
v = { m = 1.0 }
)M";

TEST(SweepCli, FailingPointGivesARowAndTheSweepGoesOn) {
    SweepOptions o;
    o.param = "p";
    o.from = 1;
    o.to = 3;
    o.points = 3;
    o.max_periods = 400;
    o.record_periods = 2;
    const SweepResult r = SweepPlan(kZenoInTheMiddle, "zeno.toml", {}, o).run();
    ASSERT_EQ(r.points.size(), 3u);
    EXPECT_EQ(r.points[0].failure, "");
    EXPECT_TRUE(r.points[0].settled);
    EXPECT_NE(r.points[1].failure.find("sweep: p = 2 (up): the run stopped: failure: "), std::string::npos)
        << r.points[1].failure;
    EXPECT_FALSE(r.points[1].settled);
    EXPECT_EQ(r.points[1].multiple, 0);
    EXPECT_TRUE(std::isnan(r.points[1].xmax[0]) && std::isnan(r.points[1].xrms[0]) && std::isnan(r.points[1].a1[0]));
    EXPECT_TRUE(r.points[1].strobe_t.empty());
    EXPECT_EQ(r.points[2].failure, "");
    EXPECT_TRUE(r.points[2].settled);
    EXPECT_GT(r.points[2].xmax[0], 0.1);

    // The command line: every row written, the failure said on stderr (also with --quiet), exit 1.
    const std::string model = write_temp("zeno.toml", kZenoInTheMiddle);
    const std::string out = temp_path("zeno.csv"), png = temp_path("zeno.png");
    const auto c = run_hsnc("sweep '" + model + "' --param p --from 1 --to 3 --points 3 --max-periods 400 " +
                            "--record-periods 2 --quiet --out '" + out + "' --plot '" + png + "'");
    EXPECT_EQ(c.exit_code, 1);
    EXPECT_NE(c.err.find("hsnc sweep: point 2 p = 2 up failed: "), std::string::npos) << c.err;
    EXPECT_NE(c.err.find("1 point failed (the outputs are written; the first: "), std::string::npos) << c.err;
    EXPECT_NE(c.out.find("status=failed points=3 up=3 down=0 settled=2 unsettled=1 failed=1"), std::string::npos)
        << c.out;
    const std::string curve = slurp(out);
    EXPECT_EQ(std::count(curve.begin(), curve.end(), '\n'), 4);
    EXPECT_NE(curve.find("\n2,up,false,0,0,nan,nan,nan\n"), std::string::npos) << curve;
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");

    // In parts: the part with the failing point exits 1 too, its file written;
    // the merge gives the same rows and exit status.
    const std::string args = "sweep '" + model + "' --param p --from 1 --to 3 --points 3 --restart-each " +
                             "--max-periods 400 --record-periods 2 --quiet ";
    const std::string whole = temp_path("zeno-whole.csv"), merged = temp_path("zeno-merged.csv");
    EXPECT_EQ(run_hsnc(args + "--out '" + whole + "'").exit_code, 1);
    const std::string p1 = temp_path("zeno-p1"), p2 = temp_path("zeno-p2");
    const auto r1 = run_hsnc(args + "--part 1/2 --part-out '" + p1 + "'");
    EXPECT_EQ(r1.exit_code, 0) << r1.err;  // points 1 and 3
    const auto r2 = run_hsnc(args + "--part 2/2 --part-out '" + p2 + "'");
    EXPECT_EQ(r2.exit_code, 1);
    EXPECT_EQ(r2.out, "status=failed part=2/2 tasks=1\n");
    EXPECT_TRUE(file_exists(p2));
    const auto m = run_hsnc("sweep-merge '" + p2 + "' '" + p1 + "' --out '" + merged + "'");
    EXPECT_EQ(m.exit_code, 1);
    EXPECT_EQ(slurp(merged), slurp(whole));
}

}  // namespace
}  // namespace hsnc

namespace hsnc {
namespace {

// Under MPI every rank says its own points and rank 0 the whole run's; a
// continuation (two branches: both directions) gives the same bytes on 1
// and 2 ranks.
TEST(SweepCli, MpiProgressPerRankAndOverall) {
    if (!HSNC_WITH_MPI) GTEST_SKIP() << "built without MPI";
    ASSERT_EQ(std::system("command -v mpirun >/dev/null 2>&1"), 0) << "mpirun not on PATH (Debian package openmpi-bin)";
    const std::string model = write_temp("hardening.toml", kHardening);
    const std::string mpirun = "mpirun --allow-run-as-root --oversubscribe -np 2 '" + std::string(HSNC_BINARY) + "' ";
    const std::string log = temp_path("mpi-progress.log"), out = temp_path("mpi-progress.csv");
    const std::string cmd = mpirun + "sweep '" + model + "' --param omega --from 1.0 --to 1.4 --points 5 " +
                            "--direction both --restart-each --max-periods 300 --record-periods 4 --out '" + out +
                            "' >/dev/null 2>'" + log + "'";
    int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(log);
    const std::string err = slurp(log);
    for (int r = 0; r < 2; ++r)
        for (int k = 1; k <= 5; ++k)
            EXPECT_NE(err.find("hsnc sweep [rank " + std::to_string(r) + "/2]: point " + std::to_string(k) + "/5 "),
                      std::string::npos)
                << err;
    const std::size_t last = err.rfind("hsnc sweep [all 2 ranks]: ");
    ASSERT_NE(last, std::string::npos) << err;
    EXPECT_EQ(err.compare(last, 36, "hsnc sweep [all 2 ranks]: 10/10 poin"), 0) << err;

    const std::string a = temp_path("cont-1.csv"), b = temp_path("cont-2.csv");
    const std::string args = "sweep '" + model + "' --param omega --from 0.8 --to 2.0 --points 13 --continuation " +
                             "--direction both --quiet --out ";
    ASSERT_EQ(run_hsnc(args + "'" + a + "'").exit_code, 0);
    status = std::system((mpirun + args + "'" + b + "' >'" + log + "' 2>&1").c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(log);
    EXPECT_EQ(slurp(a), slurp(b));
    EXPECT_GT(slurp(a).size(), 1000u);
}


// ---- a period doubling on a bundled model, checked by simulation ----

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::istringstream l(line);
        std::string cell;
        while (std::getline(l, cell, ',')) cells.push_back(cell);
        if (!line.empty() && line.back() == ',') cells.emplace_back();
        rows.push_back(cells);
    }
    return rows;
}

// `name=value` from a stdout line of hsnc periodic.
std::string field(const std::string& line, const std::string& name) {
    const std::size_t at = line.find(" " + name + "=");
    if (at == std::string::npos) return "";
    const std::size_t from = at + name.size() + 2;
    return line.substr(from, line.find_first_of(" \n", from) - from);
}

// Scenario 2's period-1 orbit, continued down in omega from 21, loses its
// stability through a period doubling (a real multiplier through -1). The
// branch marks it between two points; hsnc periodic, started from a transient
// (its own path to the orbit), finds there the same orbits with a leading
// multiplier of negative real part inside the circle before and a real one
// below -1 after. And the multiplier is what the motion does: a perturbation of the
// orbit, simulated period after period (no tangent dynamics at all), shrinks by
// that factor each period with alternating sign.
TEST(ContinuationCli, PeriodDoublingOfScenarioTwoMatchesSimulation) {
    const std::string model = model_path("seed-scenario-2.toml");
    const std::string out = temp_path("pd.csv");
    const auto r = run_hsnc("sweep '" + model + "' --param omega --from 19.5 --to 21 --points 8 --continuation " +
                            "--direction down --quiet --out '" + out + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rows = csv_rows(slurp(out));
    ASSERT_GE(rows.size(), 3u);
    // omega,direction,settled,periods,multiple,xmax_m1,xrms_m1,a1_m1,xmax_m2,xrms_m2,a1_m2,stable,max_multiplier,bifurcation
    std::size_t pd = 0, marks = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        ASSERT_EQ(rows[i].size(), 14u) << i;
        if (rows[i][13].empty()) continue;
        ++marks;
        EXPECT_EQ(rows[i][13], "period_doubling") << i;
        pd = i;
    }
    ASSERT_EQ(marks, 1u);
    ASSERT_GE(pd, 1u);
    for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i][11], i < pd ? "true" : "false") << i;

    const auto leading = [&](const std::string& omega, std::string* line) {
        const std::string mult = temp_path("mu.csv");
        const auto p = run_hsnc("periodic '" + model + "' --set omega=" + omega + " --transient 100 --multipliers '" +
                                mult + "'");
        EXPECT_EQ(p.exit_code, 0) << p.err;
        *line = p.out;
        const auto mu = csv_rows(slurp(mult));  // index,re,im,abs, largest abs first
        EXPECT_FALSE(mu.empty());
        return mu.empty() ? std::complex<double>(NAN, NAN)
                          : std::complex<double>(std::stod(mu[0][1]), std::stod(mu[0][2]));
    };
    for (std::size_t i : {pd - 1, pd}) {
        std::string line;
        const std::complex<double> mu = leading(rows[i][0], &line);
        // Before: a complex pair of negative real part inside the circle (it
        // meets the real axis between the points); after: real, below -1.
        if (i == pd) EXPECT_EQ(mu.imag(), 0.0) << rows[i][0];
        EXPECT_LT(mu.real(), 0.0) << rows[i][0];
        EXPECT_NEAR(std::abs(mu), std::stod(rows[i][12]), 1e-8 * std::abs(mu)) << rows[i][0];
        EXPECT_EQ(std::abs(mu) < 1, i < pd) << rows[i][0];
    }

    // By simulation, at omega = 19.6 (stable, leading multiplier near -0.99).
    std::string line;
    const std::complex<double> mu = leading("19.6", &line);
    ASSERT_LT(mu.real(), -0.98) << line;
    const double period = std::stod(field(" " + line, "period"));
    const std::string x1 = field(line, "x_m1"), x2 = field(line, "x_m2"), v1 = field(line, "v_m1"),
                      v2 = field(line, "v_m2");
    ASSERT_FALSE(x1.empty() || v2.empty()) << line;
    const auto run = [&](double dx) {
        std::ostringstream x1p;
        x1p.precision(17);
        x1p << std::stod(x1) + dx;
        const std::string csv = temp_path("orbit.csv");
        std::ostringstream args;
        args.precision(17);
        args << "simulate '" << model << "' --set omega=19.6 --x0 m1=" << x1p.str() << " --x0 m2=" << x2
             << " --v0 m1=" << v1 << " --v0 m2=" << v2 << " --t-end " << 60 * period << " --dt " << period
             << " --quiet --out '" << csv << "'";
        const auto s = run_hsnc(args.str());
        EXPECT_EQ(s.exit_code, 0) << s.err;
        std::vector<double> x;
        for (const auto& row : csv_rows(slurp(csv))) x.push_back(std::stod(row[1]));
        return x;
    };
    const std::vector<double> a = run(0), b = run(1e-7);
    ASSERT_EQ(a.size(), 61u);
    ASSERT_EQ(b.size(), 61u);
    for (int k = 38; k < 58; ++k)  // the other multipliers (|mu| < 0.9) have faded by then
        EXPECT_LT((b[k + 1] - a[k + 1]) * (b[k] - a[k]), 0.0) << "period " << k << ": the sign alternates";
    const double per_period = std::pow((b[58] - a[58]) / (b[38] - a[38]), 1.0 / 20);
    EXPECT_NEAR(per_period, std::abs(mu), 1e-3) << "measured by simulation over periods 38..58";
}

}  // namespace
}  // namespace hsnc
