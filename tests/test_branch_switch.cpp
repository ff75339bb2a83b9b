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
}

}  // namespace
}  // namespace hsnc
