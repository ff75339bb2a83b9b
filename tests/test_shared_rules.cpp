// Contract rules written once and used by several methods, tested directly:
// the sample grid (runtime/engine/sample_grid.h), the floating components
// (model/free_components.h), phi2 (kernels/kernel_abi.h hsnc_phi2) and the
// decision rules of a switch (runtime/engine/transition_rules.h).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <ginac/ginac.h>

#include "configuration.h"
#include "free_components.h"
#include "kernel_abi.h"
#include "model.h"
#include "sample_grid.h"
#include "transition_rules.h"

namespace hsnc {
namespace {

// ---- sample grid ----

TEST(SampleGrid, TimesAreT0PlusKDtThenTEnd) {
    const SampleGrid g(1.0, 1.95, 0.1);
    for (std::size_t k = 0; k < 10; ++k) {
        EXPECT_EQ(g.time(k), 1.0 + static_cast<double>(k) * 0.1) << k;  // from k, never accumulated
        EXPECT_FALSE(g.last(k)) << k;
    }
    EXPECT_EQ(g.time(10), 1.95);
    EXPECT_TRUE(g.last(10));
    EXPECT_EQ(g.time(11), 1.95);
    EXPECT_EQ(g.count(), 11.0);
}

TEST(SampleGrid, ATimeWithinRoundingOfTEndIsTEnd) {
    // 0.1 * 3 = 0.30000000000000004 > 0.3: without the 1e-9 dt margin the grid
    // would end ... 0.2, 0.3 (t_end) or add a row a hair after; with it, t_end once.
    const SampleGrid g(0.0, 0.3, 0.1);
    EXPECT_EQ(g.time(2), 0.2);
    EXPECT_EQ(g.time(3), 0.3);
    EXPECT_TRUE(g.last(3));
    EXPECT_EQ(g.count(), 4.0);
    // And one a hair below t_end (within 1e-9 dt) is taken for it too.
    const SampleGrid h(0.0, 1.0 + 1e-12, 0.5);
    EXPECT_EQ(h.time(2), 1.0 + 1e-12);
    EXPECT_EQ(h.count(), 3.0);
}

TEST(SampleGrid, NoDtMeansT0AndTEndOnly) {
    const SampleGrid g(0.5, 2.0, 0.0);
    EXPECT_EQ(g.time(0), 0.5);
    EXPECT_EQ(g.time(1), 2.0);
    EXPECT_TRUE(g.last(1));
    EXPECT_EQ(g.count(), 2.0);
    EXPECT_EQ(SampleGrid(3.0, 3.0, 0.1).count(), 1.0);  // an empty run: t0 = t_end, one sample
    EXPECT_EQ(SampleGrid::default_dt(1.0, 3.0), 2.0 / SampleGrid::kDefaultIntervals);
}

TEST(SampleGrid, CountIsTheNumberOfSamplesTheLoopWrites) {
    for (const double t0 : {0.0, -3.0, 1e3})
        for (const double span : {1.0, 0.95, 7.3, 1e-3})
            for (const double dt : {0.1, 0.01, 0.003, 0.7, 2.0}) {
                const SampleGrid g(t0, t0 + span, dt);
                std::size_t k = 0;
                while (!g.last(k)) {
                    ASSERT_LT(g.time(k), g.time(k + 1));
                    ++k;
                }
                EXPECT_EQ(g.count(), static_cast<double>(k + 1)) << t0 << " " << span << " " << dt;
            }
    // Far beyond anything written out: the estimate, without the loop.
    EXPECT_NEAR(SampleGrid(0.0, 10.0, 1e-9).count(), 1e10 + 1, 2.0);
}

// ---- floating components ----

Model masses(int n) {
    Model m;
    m.name = "components";
    for (int i = 0; i < n; ++i) m.masses.push_back({"m" + std::to_string(i + 1), 1.0 + i});
    m.load.assign(static_cast<std::size_t>(n), 0.0);
    m.x0 = m.v0 = m.load;
    return m;
}

TEST(FreeComponents, AFreePairFloatsAndAnAnchoredChainDoesNot) {
    Model m = masses(4);
    m.springs = {{0, 1, 2.0}, {kGround, 2, 1e12}, {2, 3, 1e-6}};
    const FreeComponents fc = free_components(m, Configuration::all_open(m));
    EXPECT_EQ(fc.free, (std::vector<int>{0, 1, 2, 3}));
    EXPECT_EQ(fc.component, (std::vector<int>{0, 0, 1, 1}));
    EXPECT_EQ(fc.floating, (std::vector<char>{1, 0}));
    EXPECT_EQ(fc.n_floating(), 1);
    EXPECT_EQ(fc.floating_members(), (std::vector<std::vector<int>>{{0, 1}}));
}

TEST(FreeComponents, ClosedContactsLinkStuckMassesAnchorAndZeroStiffnessDoesNothing) {
    Model m = masses(3);
    m.springs = {{0, 1, 0.0}, {1, 2, 3.0}};
    m.contacts = {{"c", 0, kGround, 0.1, 50.0}};
    Configuration cfg = Configuration::all_open(m);
    // k = 0 links nothing: m1 floats alone, m2 and m3 together.
    FreeComponents fc = free_components(m, cfg);
    EXPECT_EQ(fc.component, (std::vector<int>{0, 1, 1}));
    EXPECT_EQ(fc.floating_members(), (std::vector<std::vector<int>>{{0}, {1, 2}}));
    // The closed contact anchors m1.
    cfg.closed[0] = 1;
    fc = free_components(m, cfg);
    EXPECT_EQ(fc.floating_members(), (std::vector<std::vector<int>>{{1, 2}}));
    // A stuck mass is a support: m3 stuck anchors m2 through the spring.
    cfg.stuck[2] = 1;
    fc = free_components(m, cfg);
    EXPECT_EQ(fc.free, (std::vector<int>{0, 1}));
    EXPECT_EQ(fc.n_floating(), 0);
}

// ---- phi2 ----

TEST(Phi2, MatchesA40DigitEvaluationOnBothSidesOfTheSeriesSwitch) {
    GiNaC::Digits = 40;
    for (double x = -40.0; x <= 5.0; x += 0.03125) {
        for (const double xx : {x, x * 1e-3, x * 1e-9}) {
            double exact = 0.5;
            if (xx != 0.0) {
                const GiNaC::numeric X(xx);  // exactly the double
                exact = GiNaC::ex_to<GiNaC::numeric>(((GiNaC::exp(X) - 1 - X) / (X * X)).evalf()).to_double();
            }
            // The series (|x| < 1/2) to a few ulps; beyond it (e^x - 1 - x)/x^2 from expm1,
            // whose rounding the subtraction amplifies by (|e^x - 1| + |x|)/|e^x - 1 - x| (<= 4.4).
            const double eps = 2.220446049250313e-16, e1 = std::expm1(xx);
            const double level = std::fabs(xx) < 0.5 ? 4 * eps : 4 * eps * (std::fabs(e1) + std::fabs(xx)) / std::fabs(e1 - xx);
            EXPECT_NEAR(hsnc_phi2(xx), exact, level * std::fabs(exact)) << "x = " << xx;
        }
    }
}

// ---- decision rules at a switch (transition_rules.h), on a scalar stand-in ----

// The arithmetic a method gives the rules, here with the values set by hand.
struct FakePhysics {
    using Scalar = double;
    double A = 0.0, limit = 1.0, rate = 0.0;
    rules::Series<double> series{{0.0, 0.0}, {1.0, 1.0}};
    int sign(double y) const { return y > 0 ? 1 : y < 0 ? -1 : 0; }
    bool negligible(double value, double magnitude) const { return std::fabs(value) <= 16 * 2.2e-16 * magnitude; }
    double abs(double y) const { return std::fabs(y); }
    double force(const Configuration&, int) const { return A; }
    double static_limit(int) const { return limit; }
    double held_rate(const Configuration&, int) const { return rate; }
    int tie_order() const { return 4; }  // 2n + 2H + 2 of one mass, no forcing
    rules::Series<double> held_series(const Configuration& hold, const std::vector<signed char>& sgn, int i,
                                      int order) const {
        EXPECT_TRUE(hold.stuck[i]);  // the held motion
        EXPECT_EQ(sgn[i], 0);
        EXPECT_EQ(order, tie_order());  // every order up to tie_order can decide
        return series;
    }
};

signed char stick(const FakePhysics& p) {
    Configuration cfg;
    cfg.stuck = {0};
    const std::vector<signed char> sgn = {1};
    return rules::stick_rule(p, cfg, sgn, 0);
}

TEST(TransitionRules, FirstNonzeroSignSkipsValuesAtTheirRoundingLevel) {
    const FakePhysics p;
    const rules::Series<double> s{{5.0, 1e-17, -2.0, 3.0}, {1.0, 1.0, 1.0, 1.0}};
    int order = -1;
    EXPECT_EQ(rules::first_nonzero_sign(p, s, 0, &order), 1);
    EXPECT_EQ(order, 0);
    EXPECT_EQ(rules::first_nonzero_sign(p, s, 1, &order), -1);
    EXPECT_EQ(order, 2);
    EXPECT_EQ(rules::first_nonzero_sign(p, rules::Series<double>{{1.0, 0.0, 1e-20}, {1.0, 1.0, 1.0}}, 1), 0);
}

TEST(TransitionRules, StickRuleAwayFromTheLimitByTheSizeOfTheForce) {
    FakePhysics p;
    p.A = 0.5;
    EXPECT_EQ(stick(p), 0);
    p.A = -0.5;
    EXPECT_EQ(stick(p), 0);
    p.A = 2.0;
    EXPECT_EQ(stick(p), 1);
    p.A = -2.0;
    EXPECT_EQ(stick(p), -1);
}

TEST(TransitionRules, StickRuleAtTheLimitByTheFirstNonzeroDerivative) {
    FakePhysics p;
    p.A = 1.0 + 2.2e-16;  // |A| = mu_s N to rounding
    p.rate = 0.3;         // |A| increasing: slides along A
    EXPECT_EQ(stick(p), 1);
    p.rate = -0.3;  // decreasing: sticks
    EXPECT_EQ(stick(p), 0);
    p.A = -1.0;
    p.rate = -0.3;  // A = -mu_s N and falling: |A| increasing
    EXPECT_EQ(stick(p), -1);
    // The rate vanishes: the held motion's higher derivatives decide.
    p.A = 1.0;
    p.rate = 0.0;
    p.series = {{1.0, 0.0, 0.0, 2.0}, {1.0, 1.0, 1.0, 1.0}};
    EXPECT_EQ(stick(p), 1);
    p.series.d[3] = -2.0;
    EXPECT_EQ(stick(p), 0);
    p.series.d[3] = 0.0;  // stays at the limit: not increasing
    EXPECT_EQ(stick(p), 0);
}

TEST(TransitionRules, StickRuleWithoutStaticFrictionSlidesAlongTheFirstNonzeroDerivativeOfTheForce) {
    FakePhysics p;
    p.limit = 0.0;
    p.A = 0.0;
    p.rate = 0.0;
    p.series = {{0.0, 0.0, -3.0}, {1.0, 1.0, 1.0}};
    EXPECT_EQ(stick(p), -1);
    p.series.d[2] = 3.0;
    EXPECT_EQ(stick(p), 1);
    p.series.d[2] = 0.0;
    EXPECT_EQ(stick(p), 0);
}

TEST(TransitionRules, TiedContactEntersTheStateItsFirstNonzeroDerivativeFromGddGives) {
    const FakePhysics p;
    using S = rules::Series<double>;
    EXPECT_TRUE(rules::tied(p, S{{1e-18, -1e-18}, {1.0, 1.0}}));
    EXPECT_FALSE(rules::tied(p, S{{1e-18, 1e-3}, {1.0, 1.0}}));
    EXPECT_EQ(rules::tied_contact_state(p, S{{0.0, 0.0, 2.0, -1.0}, {1.0, 1.0, 1.0, 1.0}}), 1);
    EXPECT_EQ(rules::tied_contact_state(p, S{{0.0, 0.0, 1e-20, -1.0}, {1.0, 1.0, 1.0, 1.0}}), 0);
    EXPECT_EQ(rules::tied_contact_state(p, S{{0.0, 0.0, 0.0, 0.0}, {1.0, 1.0, 1.0, 1.0}}), -1);
}

}  // namespace
}  // namespace hsnc
