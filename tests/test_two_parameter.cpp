// hsnc sweep --continuation --track (api/hsnc/sweep.h): curves of folds,
// period doublings and grazing orbits over two parameters, against what
// does not use them: the turning points of one-parameter branches at fixed
// values of the second parameter, the period doublings --branch-switch
// locates (Illinois on det(M + I), another algorithm), and the closed form
// of a linear oscillator's grazing (F |H(omega)| = gap).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;

const std::string kHardening = std::string(HSNC_SOURCE_DIR) + "/examples/hardening-stop.toml";

SweepOptions curve_options(const std::string& kind, const std::string& param2, double from2, double to2) {
    SweepOptions o;
    o.param = "omega";
    o.from = 0.6;
    o.to = 2.0;
    o.points = 29;
    o.continuation = true;
    o.track = kind;
    o.param2 = param2;
    o.values2 = {from2, to2};
    return o;
}

// The one-parameter branch of a curve's options `o` (its track, second
// parameter and values dropped) with the second parameter at `value`.
SweepResult branch_at(const std::string& text, const std::string& param2, double value, SweepOptions o) {
    o.track.clear();
    o.param2.clear();
    o.values2.clear();
    char set[64];
    std::snprintf(set, sizeof set, "=%.17g", value);
    return SweepPlan(text, "model.toml", ModelOverrides{{param2 + set}, {}, {}, {}}, o).run();
}

// The hardening stop's first fold over (omega, F), F from 0.1 to 0.3: at
// three of its F, the one-parameter branch from the upper branch turns there
// (no point beyond it, one within 1e-4), and hsnc periodic's shooting from
// the branch finds an orbit near the curve's with a multiplier near +1 at
// 1e-6 below its omega and none near at 1e-6 above.
TEST(TwoParameter, FoldCurveOfTheHardeningStopAgainstTurningPointsOfBranches) {
    const std::string text = slurp(kHardening);
    const SweepResult curve = SweepPlan(text, "hardening-stop.toml", {}, curve_options("fold", "F", 0.1, 0.3)).run();
    ASSERT_GE(curve.points.size(), 20u);
    EXPECT_EQ(curve.points.front().value2, 0.1);
    EXPECT_GT(curve.points.back().value2, 0.29);
    for (const SweepPoint& p : curve.points) {
        EXPECT_EQ(p.bifurcation, "fold");
        EXPECT_EQ(p.stop, "");
        EXPECT_NEAR(p.max_multiplier, 1.0, 1e-9);  // a multiplier at +1
    }
    for (const std::size_t k : {std::size_t{0}, curve.points.size() / 2, curve.points.size() - 1}) {
        const SweepPoint& c = curve.points[k];
        SCOPED_TRACE("F = " + std::to_string(c.value2));
        SweepOptions o;
        o.param = "omega";
        o.from = 1.3;  // from the upper branch (the transient from x = 1.5)
        o.to = 1.8;
        o.points = 201;
        o.continuation = true;
        char f[64];
        std::snprintf(f, sizeof f, "F=%.17g", c.value2);
        const SweepResult branch =
            SweepPlan(text, "hardening-stop.toml", ModelOverrides{{f}, {"m=1.5"}, {}, {}}, o).run();
        std::size_t top = 0;
        for (std::size_t i = 0; i < branch.points.size(); ++i)
            if (branch.points[i].value > branch.points[top].value) top = i;
        ASSERT_GT(top, 0u);
        ASSERT_LT(top + 1, branch.points.size());
        EXPECT_GE(c.value, branch.points[top].value - 1e-12);  // no branch point beyond the fold
        EXPECT_LT(c.value - branch.points[top].value, 1e-4);   // and one close to it

        // hsnc periodic from the branch's orbit before the top: just below
        // the curve's omega an orbit near the curve's with a multiplier near
        // +1; just above, none near.
        const SweepPoint& near = branch.points[top - 1];
        const auto shoot = [&](double omega) {
            char w[64];
            std::snprintf(w, sizeof w, "omega=%.17g", omega);
            Model m = parse_model(text, "hardening-stop.toml", ModelOverrides{{f, w}, {}, {}, {}});
            m.x0 = {near.strobe_x.back()};
            m.v0 = {near.strobe_v.back()};
            PeriodicOptions po;
            po.max_iterations = 200;
            return periodic(m, po);
        };
        const PeriodicResult below = shoot(c.value * (1 - 1e-6)), above = shoot(c.value * (1 + 1e-6));
        ASSERT_EQ(below.status, PeriodicStatus::ok) << below.message;
        EXPECT_NEAR(below.x[0], c.strobe_x.back(), 1e-2 * std::fabs(c.strobe_x.back()));
        EXPECT_NEAR(std::abs(below.multipliers.front()), 1.0, 2e-2);
        EXPECT_TRUE(above.status != PeriodicStatus::ok || std::fabs(above.x[0] - c.strobe_x.back()) > 1e-2)
            << above.x[0] << " " << c.strobe_x.back();
    }
}

// A linear oscillator reaches its stop at exactly F |H(omega)| = gap: the
// grazing curve of the hardening stop's lower branch, F from 0.1 down.
TEST(TwoParameter, GrazingCurveIsTheLinearOscillatorsClosedForm) {
    const SweepResult curve =
        SweepPlan(slurp(kHardening), "hardening-stop.toml", {}, curve_options("grazing", "F", 0.1, 0.05)).run();
    ASSERT_GE(curve.points.size(), 10u);
    EXPECT_LT(curve.points.back().value2, 0.055);
    for (const SweepPoint& p : curve.points) {
        const double w = p.value;
        const double H = std::abs(1.0 / std::complex<double>(1 - w * w, 0.04 * w));
        EXPECT_NEAR(p.value2 * H, 0.5, 1e-10) << w;
        EXPECT_NEAR(p.xmax[0], 0.5, 1e-10) << w;
        EXPECT_TRUE(p.stable);
    }
}

// The period doubling of the bilinear oscillator's period-1 orbit over
// (omega, damping c): at two of its c, where --branch-switch (Illinois on
// det(M + I) along the one-parameter branch) locates it.
TEST(TwoParameter, PeriodDoublingCurveAgainstLocatedDoublings) {
    std::string text = slurp(std::string(HSNC_SOURCE_DIR) + "/examples/bilinear-cascade.toml");
    text.replace(text.find("alpha = 0.1"), 11, "alpha = \"c\"");
    text.replace(text.find("F = 1.0\n"), 8, "F = 1.0\nc = 0.1\n");
    SweepOptions o = curve_options("period_doubling", "c", 0.1, 0.2);
    o.from = 2.4;
    o.to = 2.66;
    o.points = 14;
    const SweepResult curve = SweepPlan(text, "cascade.toml", {}, o).run();
    ASSERT_GE(curve.points.size(), 5u);
    EXPECT_GT(curve.points.back().value2, 0.19);
    for (const std::size_t k : {std::size_t{0}, curve.points.size() - 2}) {
        const SweepPoint& c = curve.points[k];
        SCOPED_TRACE("c = " + std::to_string(c.value2));
        SweepOptions b = o;
        b.branch_switch = 1;
        const SweepResult branch = branch_at(text, "c", c.value2, b);
        const auto pd = std::find_if(branch.points.begin(), branch.points.end(),
                                     [](const SweepPoint& p) { return p.bifurcation == "period_doubling"; });
        ASSERT_NE(pd, branch.points.end());
        EXPECT_NEAR(c.value, pd->value, 1e-10 * c.value);
    }
}

// Seed scenario 2's period-1 orbit gains stability through a Neimark-Sacker
// point near omega = 11.4 (a complex pair enters the unit circle): its curve
// over (omega, F1) has the pair on the circle, and at two of its F1 the
// one-parameter branch marks the crossing in the step that holds it.
TEST(TwoParameter, NeimarkSackerCurveOfScenarioTwo) {
    const std::string text = slurp(std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-2.toml");
    SweepOptions o = curve_options("neimark_sacker", "F1", 225, 180);
    o.from = 10;
    o.to = 14;
    o.points = 9;
    const SweepResult curve = SweepPlan(text, "seed-scenario-2.toml", {}, o).run();
    ASSERT_GE(curve.points.size(), 5u);
    EXPECT_LT(curve.points.back().value2, 185);
    for (const SweepPoint& p : curve.points) {
        EXPECT_EQ(p.bifurcation, "neimark_sacker");
        EXPECT_NEAR(p.max_multiplier, 1.0, 1e-9);
    }
    for (const std::size_t k : {std::size_t{0}, curve.points.size() - 1}) {
        const SweepPoint& c = curve.points[k];
        SCOPED_TRACE("F1 = " + std::to_string(c.value2));
        SweepOptions b = o;
        b.points = 41;  // steps short enough to part the crossing from the period doubling after it
        const SweepResult branch = branch_at(text, "F1", c.value2, b);
        char set[64];
        std::snprintf(set, sizeof set, "F1=%.17g", c.value2);
        const auto ns = std::find_if(branch.points.begin(), branch.points.end(),
                                     [](const SweepPoint& p) { return p.bifurcation == "neimark_sacker"; });
        ASSERT_NE(ns, branch.points.end());
        ASSERT_NE(ns, branch.points.begin());
        EXPECT_GT(c.value, (ns - 1)->value);
        EXPECT_LT(c.value, ns->value);
        EXPECT_FALSE((ns - 1)->stable);
        EXPECT_TRUE(ns->stable);
        // hsnc periodic at the curve's point: a complex pair on the unit circle.
        char w[64];
        std::snprintf(w, sizeof w, "omega=%.17g", c.value);
        Model m = parse_model(text, "seed-scenario-2.toml", ModelOverrides{{set, w}, {}, {}, {}});
        m.x0 = {c.strobe_x.end() - 2, c.strobe_x.end()};
        m.v0 = {c.strobe_v.end() - 2, c.strobe_v.end()};
        const PeriodicResult r = periodic(m, PeriodicOptions());
        ASSERT_EQ(r.status, PeriodicStatus::ok) << r.message;
        EXPECT_NE(r.multipliers[0].imag(), 0.0);
        EXPECT_NEAR(std::abs(r.multipliers[0]), 1.0, 1e-8);
        EXPECT_NEAR(std::abs(r.multipliers[1]), 1.0, 1e-8);
    }
}

// The command line: the second parameter's column and the curve's rows, the
// plot of the curve in the parameter plane, and what is refused.
TEST(TwoParameterCli, ColumnsPlotAndRefusals) {
    const std::string out = temp_path("fold.csv"), png = temp_path("fold.png");
    const std::string base = "sweep '" + kHardening + "' --param omega --from 0.6 --to 2.0 --points 29 ";
    const auto r = run_hsnc(base + "--continuation --track fold --param2 F --values2 0.1,0.2 --quiet --out '" + out +
                            "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string csv = slurp(out);
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m,F,stable,max_multiplier,bifurcation");
    EXPECT_EQ(csv.compare(csv.find('\n') + 1, 22, "1.4024877417251087,up,"), 0) << csv.substr(0, 200);
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
    for (const std::string& bad :
         {std::string("--track fold --param2 F --values2 0.1,0.2"),
          std::string("--continuation --track cusp --param2 F --values2 0.1,0.2"),
          std::string("--continuation --track fold"),
          std::string("--continuation --track fold --param2 F --values2 0.1"),
          std::string("--continuation --track fold --param2 F --values2 0.1,0.2 --branch-switch 1")}) {
        const std::string o2 = temp_path("bad.csv");
        const auto b = run_hsnc(base + bad + " --quiet --out '" + o2 + "'");
        EXPECT_EQ(b.exit_code, 2) << bad << "\n" << b.err;
        EXPECT_TRUE(b.err.find("--track") != std::string::npos || b.err.find("--values2") != std::string::npos ||
                    b.err.find("--branch-switch") != std::string::npos)
            << b.err;
        EXPECT_FALSE(testing::file_exists(o2));
    }
}

}  // namespace
}  // namespace hsnc
