// hsnc sweep --continuation --branch-switch (api/hsnc/sweep.h): period
// doublings located to rounding and the branches of twice the period born
// there followed, on a forced bilinear oscillator whose period-1 orbit
// doubles into a cascade (1 -> 2 -> 4 -> 8 within 6% of the frequency).
// Checked against hsnc periodic on either side of each located point and
// against the oscillator in closed form (tests/bilinear_closed_form.h):
// shooting of its own (finite-difference Newton on the closed-form map)
// finds the same period-2 and period-4 orbits, and its multipliers put the
// doublings where the branch does.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "bilinear_closed_form.h"
#include "cli_runner.h"
#include "hsnc/periodic.h"
#include "hsnc/sweep.h"
#include "model_reader.h"
#include "number_text.h"

namespace hsnc {
namespace {

using testing::Bilinear;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

constexpr double kPi = 3.14159265358979323846;

// x'' + 0.1 x' + x + 50 max(x, 0) = sin(omega t).
const std::string kCascade = testing::bilinear_model(2.4, 0.1, 50.0, 1.0);

SweepOptions cascade_options(int depth) {
    SweepOptions o;
    o.param = "omega";
    o.from = 2.4;
    o.to = 2.66;
    o.points = 14;
    o.continuation = true;
    o.branch_switch = depth;
    return o;
}

// The closed-form map over `periods` forcing periods from (x, v) at t = 0.
Eigen::Vector2d closed_form_map(const Bilinear& bl, const Eigen::Vector2d& y, int periods) {
    double x = y(0), v = y(1);
    bl.run(0.0, x, v, periods * 2 * kPi / bl.w, [](const Bilinear::Piece&, double, double) {});
    return {x, v};
}

// Shooting on the closed form: Newton on P(y) - y with a central-difference
// Jacobian (the orbit to 1e-13), and that Jacobian's eigenvalues there (the
// multipliers, to about 1e-9).
struct ClosedFormOrbit {
    Eigen::Vector2d y;
    Eigen::Vector2cd mu;
    double residual = INFINITY;
};
ClosedFormOrbit closed_form_orbit(const Bilinear& bl, Eigen::Vector2d y, int periods) {
    ClosedFormOrbit o;
    Eigen::Matrix2d J;
    for (int it = 0; it < 30; ++it) {
        const Eigen::Vector2d r = closed_form_map(bl, y, periods) - y;
        for (int j = 0; j < 2; ++j) {
            const double h = 1e-6 * std::max(1.0, std::fabs(y(j)));
            Eigen::Vector2d a = y, b = y;
            a(j) += h;
            b(j) -= h;
            J.col(j) = (closed_form_map(bl, a, periods) - closed_form_map(bl, b, periods)) / (2 * h);
        }
        o.residual = r.norm();
        if (o.residual < 1e-13) break;
        y -= (J - Eigen::Matrix2d::Identity()).lu().solve(r);
    }
    o.y = y;
    o.mu = J.eigenvalues();
    return o;
}

// The real multiplier closest to -1.
double flip_multiplier(const std::vector<std::complex<double>>& mu) {
    double best = NAN;
    for (const auto& m : mu)
        if (m.imag() == 0 && (std::isnan(best) || std::fabs(m.real() + 1) < std::fabs(best + 1))) best = m.real();
    return best;
}

// hsnc periodic's multiplier closest to -1 of the orbit of `periods` forcing
// periods at omega, from (x, v).
double periodic_flip_multiplier(double omega, double x, double v, int periods) {
    char text[64];
    std::snprintf(text, sizeof text, "omega=%.17g", omega);
    Model m = parse_model(kCascade, "cascade.toml", ModelOverrides{{text}, {}, {}, {}});
    m.x0 = {x};
    m.v0 = {v};
    PeriodicOptions o;
    o.harmonic = periods;
    o.tolerance = 1e-12;
    const PeriodicResult r = periodic(m, o);
    EXPECT_EQ(r.status, PeriodicStatus::ok) << r.message;
    return flip_multiplier(r.multipliers);
}

// The rows of branch `b`.
std::vector<const SweepPoint*> branch_rows(const SweepResult& r, std::size_t b) {
    std::vector<const SweepPoint*> rows;
    for (const SweepPoint& p : r.points)
        if (p.branch == b) rows.push_back(&p);
    return rows;
}

// The located doubling of a branch: its one row labelled period_doubling.
const SweepPoint* doubling_row(const std::vector<const SweepPoint*>& rows) {
    const SweepPoint* found = nullptr;
    for (const SweepPoint* p : rows)
        if (("+" + p->bifurcation + "+").find("+period_doubling+") != std::string::npos) {
            EXPECT_EQ(found, nullptr) << "a second doubling at " << p->value;
            found = p;
        }
    return found;
}

TEST(BranchSwitch, CascadeOfABilinearOscillatorAgainstItsClosedForm) {
    const SweepResult r = SweepPlan(kCascade, "cascade.toml", {}, cascade_options(2)).run();
    ASSERT_EQ(r.branch_switch, 2);
    // Three branches: the period-1 orbit, the period-2 one born at its
    // doubling, the period-4 one born at the period-2 one's.
    std::size_t branches = 0;
    for (const SweepPoint& p : r.points) {
        branches = std::max(branches, p.branch + 1);
        EXPECT_EQ(p.stop, "") << p.value;
    }
    ASSERT_EQ(branches, 3u);
    double born_at = NAN;  // where the branch begins
    for (std::size_t b = 0; b < 3; ++b) {
        SCOPED_TRACE("branch " + std::to_string(b));
        const auto rows = branch_rows(r, b);
        ASSERT_GE(rows.size(), 5u);
        const int periods = 1 << b;
        for (const SweepPoint* p : rows) EXPECT_EQ(p->multiple, periods);
        EXPECT_TRUE(rows.front()->branch_start);
        if (b > 0) {
            EXPECT_EQ(rows.front()->value, born_at);
            EXPECT_FALSE(rows.front()->stable);  // the doubling itself
            EXPECT_TRUE(rows[1]->stable);        // a supercritical one: the new branch is stable
        }
        if (b == 2) {  // its own doubling is marked on the row after it, neither located nor followed (depth 2)
            const SweepPoint* pd = doubling_row(rows);
            ASSERT_NE(pd, nullptr);
            EXPECT_GT(pd->periods, 0u);
            continue;
        }
        const SweepPoint* pd = doubling_row(rows);
        ASSERT_NE(pd, nullptr);
        born_at = pd->value;
        EXPECT_EQ(pd->periods, 0u);  // a located row
        const double x = pd->strobe_x.back(), v = pd->strobe_v.back();

        // Located to rounding: hsnc periodic puts the multiplier on either
        // side of -1 at 1e-10 (relative) before and after it.
        const double before = periodic_flip_multiplier(born_at * (1 - 1e-10), x, v, periods),
                     after = periodic_flip_multiplier(born_at * (1 + 1e-10), x, v, periods);
        EXPECT_GT(before, -1.0);
        EXPECT_LT(after, -1.0);

        // And the closed form's own shooting and multipliers: -1 crossed
        // within 1e-8 of it.
        for (const double side : {-1.0, 1.0}) {
            const double w = born_at * (1 + side * 1e-8);
            const ClosedFormOrbit o = closed_form_orbit(Bilinear{w, 0.1, 50.0, 1.0}, Eigen::Vector2d(x, v), periods);
            ASSERT_LT(o.residual, 1e-11);
            EXPECT_NEAR(o.y(0), x, 1e-6);
            const double mu = flip_multiplier({o.mu(0), o.mu(1)});
            EXPECT_EQ(mu > -1.0, side < 0) << w << " " << mu;
        }
    }

    // Orbits of the switched branches, away from their ends, against the
    // closed form's shooting started 1e-3 off: the same orbit, of that
    // period and not of half of it.
    for (std::size_t b = 1; b < 3; ++b) {
        const auto rows = branch_rows(r, b);
        const SweepPoint* p = rows[rows.size() / 2];
        SCOPED_TRACE("branch " + std::to_string(b) + " at omega = " + std::to_string(p->value));
        const Bilinear bl{p->value, 0.1, 50.0, 1.0};
        const Eigen::Vector2d y(p->strobe_x.back(), p->strobe_v.back());
        const ClosedFormOrbit o = closed_form_orbit(bl, y + Eigen::Vector2d(1e-3, -1e-3), 1 << b);
        ASSERT_LT(o.residual, 1e-11);
        EXPECT_NEAR(o.y(0), y(0), 1e-10);
        EXPECT_NEAR(o.y(1), y(1), 1e-10);
        EXPECT_GT((closed_form_map(bl, y, 1 << (b - 1)) - y).norm(), 1e-3);
        // Its stability as the multipliers of the closed form say.
        EXPECT_EQ(p->stable, std::abs(o.mu(0)) < 1 && std::abs(o.mu(1)) < 1);
    }
}

// Continuing from a row of an earlier run (--start-periods K): the
// period-2 branch's row at about 2.55 rad/s, its state at t0 given as the
// initial state and K = 2, starts a branch of period 2 there with no
// transient: the same orbit (1e-10), followed up to 2.63 through the
// period-2 orbit's own doubling, which it locates where the switched branch
// did (1e-10); its orbits are closed-form period-2 orbits.
TEST(BranchSwitch, ContinuesFromARowOfAnEarlierRun) {
    const SweepResult r = SweepPlan(kCascade, "cascade.toml", {}, cascade_options(1)).run();
    const auto rows = branch_rows(r, 1);
    ASSERT_GE(rows.size(), 5u);
    const SweepPoint* row = nullptr;
    for (const SweepPoint* p : rows)
        if (row == nullptr && p->value > 2.55) row = p;
    ASSERT_NE(row, nullptr);
    const double pd2 = doubling_row(branch_rows(SweepPlan(kCascade, "cascade.toml", {}, cascade_options(2)).run(), 1))
                           ->value;       // the period-2 orbit's doubling, located by the switched branch
    SweepOptions o = cascade_options(2);  // the period-2 branch's doubling located, the period-4 one followed
    o.from = row->value;
    o.to = 2.63;
    o.start_periods = 2;
    const ModelOverrides from_row{
        {}, {"m=" + shortest_text(row->strobe_x.back())}, {"m=" + shortest_text(row->strobe_v.back())}, {}};
    const SweepResult c = SweepPlan(kCascade, "cascade.toml", from_row, o).run();
    const auto again = branch_rows(c, 0);
    ASSERT_GE(again.size(), 5u);
    const SweepPoint& first = *again.front();
    EXPECT_EQ(first.value, row->value);
    EXPECT_EQ(first.multiple, 2);
    EXPECT_EQ(first.periods, 0u);  // no transient
    EXPECT_NEAR(first.strobe_x.back(), row->strobe_x.back(), 1e-10);
    EXPECT_NEAR(first.strobe_v.back(), row->strobe_v.back(), 1e-10);
    EXPECT_NEAR(first.max_multiplier, row->max_multiplier, 1e-8);
    for (const SweepPoint* p : again) EXPECT_EQ(p->multiple, 2);
    const SweepPoint* pd = doubling_row(again);
    ASSERT_NE(pd, nullptr);
    EXPECT_NEAR(pd->value, pd2, 1e-10 * pd2);
    const SweepPoint* mid = again[again.size() / 2];
    const Bilinear bl{mid->value, 0.1, 50.0, 1.0};
    const Eigen::Vector2d y(mid->strobe_x.back(), mid->strobe_v.back());
    const ClosedFormOrbit orbit = closed_form_orbit(bl, y + Eigen::Vector2d(1e-3, -1e-3), 2);
    ASSERT_LT(orbit.residual, 1e-11);
    EXPECT_NEAR(orbit.y(0), y(0), 1e-10);
    EXPECT_GT((closed_form_map(bl, y, 1) - y).norm(), 1e-3);  // not of period 1
}

// The command line: the branch column after bifurcation, the library's
// numbers, the plot, parts merged to the same bytes, and bad values refused.
TEST(BranchSwitchCli, ColumnPartsPlotAndRefusals) {
    const std::string model = write_temp("cascade.toml", kCascade);
    const std::string args =
        "sweep '" + model + "' --param omega --from 2.4 --to 2.66 --points 14 --continuation --quiet ";
    const std::string whole = temp_path("whole.csv"), png = temp_path("cascade.png");
    const auto r = run_hsnc(args + "--branch-switch 2 --direction both --out '" + whole + "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string csv = slurp(whole);
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "omega,direction,settled,periods,multiple,xmax_m,xrms_m,a1_m,stable,max_multiplier,bifurcation,branch");
    // The up task's branches 0, 1, 2 (period 1, 2, 4), then the down task's
    // 3.. (from 2.66 down: the period-1 orbit, unstable, through the same doubling).
    EXPECT_NE(csv.find(",period_doubling,0\n"), std::string::npos);
    EXPECT_NE(csv.find(",period_doubling,1\n"), std::string::npos);
    EXPECT_NE(csv.find(",4,"), std::string::npos);
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
    // The same rows as the library's.
    SweepOptions o = cascade_options(2);
    o.direction = SweepDirection::both;
    const SweepResult lib = SweepPlan(kCascade, "cascade.toml", {}, o).run();
    EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), lib.points.size() + 1);

    // Two parts, one task each, merged: the same file.
    const std::string p1 = temp_path("p1.txt"), p2 = temp_path("p2.txt"), merged = temp_path("merged.csv");
    for (const auto& [part, file] : {std::pair<std::string, std::string>{"1/2", p1}, {"2/2", p2}}) {
        const auto q =
            run_hsnc(args + "--branch-switch 2 --direction both --part " + part + " --part-out '" + file + "'");
        ASSERT_EQ(q.exit_code, 0) << q.err;
    }
    const auto m = run_hsnc("sweep-merge '" + p1 + "' '" + p2 + "' --out '" + merged + "'");
    ASSERT_EQ(m.exit_code, 0) << m.err;
    EXPECT_EQ(slurp(merged), csv);
    // Two MPI ranks: the same file (the ranks send every point's branch).
    if (HSNC_WITH_MPI) {
        const std::string mpi = temp_path("mpi.csv"), log = temp_path("mpi.log");
        const int status =
            std::system(("mpirun --allow-run-as-root --oversubscribe -np 2 '" + std::string(HSNC_BINARY) + "' " + args +
                         "--branch-switch 2 --direction both --out '" + mpi + "' >'" + log + "' 2>&1")
                            .c_str());
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(log);
        EXPECT_EQ(slurp(mpi), csv);
    }

    // Refused: without --continuation, beyond 6, below 0.
    for (const std::string& bad : {std::string("--branch-switch 1"), std::string("--continuation --branch-switch 7"),
                                   std::string("--continuation --branch-switch -1")}) {
        const std::string out = temp_path("bad.csv");
        const auto b = run_hsnc("sweep '" + model + "' --param omega --from 2.4 --to 2.66 --points 14 " + bad +
                                " --quiet --out '" + out + "'");
        EXPECT_EQ(b.exit_code, 2) << bad << "\n" << b.err;
        EXPECT_NE(b.err.find("--branch-switch"), std::string::npos) << b.err;
        EXPECT_FALSE(testing::file_exists(out));
    }
    // --start-periods: refused without --continuation, with --track, beyond 1024.
    for (const std::string& bad :
         {std::string("--start-periods 2"), std::string("--continuation --start-periods 1025"),
          std::string("--continuation --start-periods -1"),
          std::string("--continuation --start-periods 2 --track fold --param2 F --values2 1,2")}) {
        const std::string out = temp_path("bad.csv");
        const auto b = run_hsnc("sweep '" + model + "' --param omega --from 2.4 --to 2.66 --points 14 " + bad +
                                " --quiet --out '" + out + "'");
        EXPECT_EQ(b.exit_code, 2) << bad << "\n" << b.err;
        EXPECT_NE(b.err.find("--start-periods"), std::string::npos) << b.err;
        EXPECT_FALSE(testing::file_exists(out));
    }
}

// --start-periods K on an orbit that repeats after fewer periods is no
// branch of K: at 2.64 rad/s the cascade's period-4 orbit given with K = 12
// is a failed row naming the period 4, and the period-12 orbit born at a
// fold at 2.63921 rad/s, continued down in steps too large to turn there,
// stops where the step lands on the period-4 orbit (exit 1, the reason
// said) instead of calling it an orbit of 12.
TEST(BranchSwitchCli, StartPeriodsStopsOnAnOrbitOfFewer) {
    const std::string model = std::string(HSNC_SOURCE_DIR) + "/examples/bilinear-cascade.toml";
    const std::string args = "sweep '" + model + "' --param omega --from 2.64 --to 2.62 --points 5 --continuation " +
                             "--start-periods 12 --quiet ";
    const std::string out = temp_path("start12.csv");
    const auto four = run_hsnc(args + "--x0 m=-0.70427984734482485 --v0 m=-0.84108335151402402 --out '" + out + "'");
    EXPECT_EQ(four.exit_code, 1) << four.err;
    EXPECT_NE(four.err.find("the orbit repeats after 4 forcing periods, not only after 12"), std::string::npos)
        << four.err;
    const std::string rows = slurp(out);
    EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 2) << rows;  // the header and the failed row

    const auto jump = run_hsnc(args + "--x0 m=-0.70917013206284707 --v0 m=-0.83619986957490522 --out '" + out + "'");
    EXPECT_EQ(jump.exit_code, 1) << jump.err;
    EXPECT_NE(jump.err.find("the orbit repeats after 4 forcing periods"), std::string::npos) << jump.err;
    const std::string kept = slurp(out);
    EXPECT_NE(kept.find("\n2.6400000000000001,down,true,0,12,"), std::string::npos) << kept;
    for (std::size_t at = kept.find('\n'); at + 1 < kept.size(); at = kept.find('\n', at + 1))
        EXPECT_EQ(kept.compare(at + 1, 18, "2.6400000000000001"), 0) << kept;  // only the start: no row of period 4
    // With steps that follow it, the period-12 branch turns at its fold (a row saying so), all of period 12.
    const auto fine = run_hsnc("sweep '" + model + "' --param omega --from 2.64 --to 2.63 --points 41 --continuation " +
                               "--start-periods 12 --quiet --x0 m=-0.70917013206284707 --v0 m=-0.83619986957490522 " +
                               "--out '" + out + "'");
    EXPECT_EQ(fine.exit_code, 0) << fine.err;
    const std::string followed = slurp(out);
    EXPECT_NE(followed.find(",fold\n"), std::string::npos) << followed;
    EXPECT_EQ(followed.find(",4,"), std::string::npos);
}

}  // namespace
}  // namespace hsnc
