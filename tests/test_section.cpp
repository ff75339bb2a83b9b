// Poincare sections at a switch kind (output/section.h; `hsnc simulate
// --section`, `hsnc lyapunov --section`):
//  - an undamped bilinear oscillator (a spring and a one-sided stop with a
//    gap): every contact_close is at x = gap with the closed-form entry
//    velocity, at the closed-form instants t_1 + k P;
//  - Den Hartog's forced Coulomb oscillator on its non-sticking orbit (found
//    by hsnc::periodic): the section at its reversals is +-X (his amplitude),
//    each point repeating the one a period before to 1e-9;
//  - the command lines: the section CSV is the events CSV's rows of that kind,
//    after the transient for lyapunov; the PNG is drawn; bad flags exit 2
//    with nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "hsnc/periodic.h"
#include "hsnc/simulate.h"
#include "section.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> cells;
        std::istringstream l(line);
        for (std::string c; std::getline(l, c, ',');) cells.push_back(c);
        rows.push_back(cells);
    }
    return rows;
}

// m = 1, k = 4 (omega_1 = 2) to the ground, a stop of stiffness kc = 5 at gap
// d = 0.6 (closed while x >= d), no damping, from x = 0 with v = 2: the free
// motion is x = sin(2 t) (amplitude A = 1).
constexpr double kD = 0.6, kK = 4.0, kKc = 5.0, kV0 = 2.0;
const char* const kBilinear = R"(
name = "bilinear-section"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 4
[[contact]]
name = "stop"
between = ["m1", "ground"]
gap = 0.6
k = 5
[initial]
v = { m1 = 2.0 }
)";

struct BilinearClosedForm {
    double t1, v_in, contact_time, period;
};

BilinearClosedForm bilinear_closed_form() {
    const double w1 = std::sqrt(kK), A = kV0 / w1, phi = std::asin(kD / A);
    BilinearClosedForm c;
    c.t1 = phi / w1;
    c.v_in = w1 * std::sqrt(A * A - kD * kD);
    // In contact: x oscillates about xc = kc d / (k + kc) at wc; it leaves
    // x = d after s with tan(wc s / 2) = v_in / (wc (d - xc)).
    const double wc = std::sqrt(kK + kKc), xc = kKc * kD / (kK + kKc);
    c.contact_time = 2 / wc * std::atan(c.v_in / (wc * (kD - xc)));
    // Free: from x = d going down (phase pi - phi) round to x = d going up (2 pi + phi).
    c.period = c.contact_time + (M_PI + 2 * phi) / w1;
    return c;
}

TEST(PoincareSection, BilinearOscillatorClosedForm) {
    const BilinearClosedForm c = bilinear_closed_form();
    const std::string model = write_temp("bilinear.toml", kBilinear);
    for (const char* kind : {"contact_close", "contact_open:stop"}) {
        const std::string out = temp_path("section.csv");
        const testing::CliRun r = run_hsnc("simulate '" + model + "' --t-end 50 --section " + kind +
                                           " --section-out '" + out + "'");
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const auto rows = csv_rows(slurp(out));
        ASSERT_GE(rows.size(), 2u) << kind;
        EXPECT_EQ(rows[0], (std::vector<std::string>{"t", "x_m1", "v_m1"}));
        const bool close = std::string(kind) == "contact_close";
        const double first = close ? c.t1 : c.t1 + c.contact_time;
        const std::size_t want = static_cast<std::size_t>(std::floor((50 - first) / c.period)) + 1;
        ASSERT_EQ(rows.size() - 1, want) << kind;
        double worst_t = 0, worst_v = 0;
        for (std::size_t k = 1; k < rows.size(); ++k) {
            const double t = std::stod(rows[k][0]), x = std::stod(rows[k][1]), v = std::stod(rows[k][2]);
            const double t_want = first + static_cast<double>(k - 1) * c.period;
            worst_t = std::max(worst_t, std::fabs(t - t_want));
            worst_v = std::max(worst_v, std::fabs(v - (close ? c.v_in : -c.v_in)));
            EXPECT_NEAR(t, t_want, 1e-12 * (1 + t)) << kind << " point " << k;
            EXPECT_NEAR(x, kD, 1e-14) << kind << " point " << k;
            EXPECT_NEAR(v, close ? c.v_in : -c.v_in, 1e-12) << kind << " point " << k;
        }
        std::printf("%s: %zu section points, worst |t - closed form| %.3g s, |v - closed form| %.3g m/s\n", kind,
                    rows.size() - 1, worst_t, worst_v);
    }
}

// 1 mass (m = 1), spring k = 1 (omega_n = 1), Coulomb friction beta (g = 1),
// forcing sin(r t): as tests/test_periodic.cpp.
Model den_hartog(double r, double beta) {
    Model m;
    m.name = "den_hartog";
    m.g = 1.0;
    m.masses.push_back({"m1", 1.0});
    m.set_friction(m.masses.size() - 1) = {true, beta, beta};
    m.springs.push_back({kGround, 0, 1.0});
    m.forcing.push_back({r, 0.0, {1.0}});
    m.load = {0.0};
    m.x0 = {0.0};
    m.v0 = {0.0};
    return m;
}

TEST(PoincareSection, DenHartogReversalsRepeatAtHisAmplitude) {
    for (auto [r, beta] : {std::pair{1.5, 0.3}, std::pair{0.8, 0.1}, std::pair{2.0, 0.5}}) {
        const std::string what = "r = " + std::to_string(r) + ", beta = " + std::to_string(beta);
        const double U = std::tan(M_PI / (2 * r)) / r, V = 1 / (1 - r * r);
        const double X = std::sqrt(V * V - beta * beta * U * U);
        Model m = den_hartog(r, beta);
        m.x0 = {X};
        PeriodicOptions po;
        po.kernels = KernelChoice::generic;
        const PeriodicResult p = periodic(m, po);
        ASSERT_EQ(p.status, PeriodicStatus::ok) << what << ": " << p.message;
        // 20 periods from the orbit's state, the section at the reversals of m1.
        Model on = m;
        on.t0 = p.t;
        on.x0 = p.x;
        on.v0 = p.v;
        SectionRecorder section(on, parse_section(on, "reversal:m1", "--section"), nullptr, true);
        SimulateOptions so;
        so.t_end = p.t + 20 * p.period;
        so.samples = false;
        so.kernels = KernelChoice::generic;
        const SimulateSummary s = simulate(on, so, section);
        ASSERT_EQ(s.status, RunStatus::ok) << what;
        const std::vector<double>& rows = section.rows();  // t, x, v
        ASSERT_EQ(section.points(), 40u) << what;  // two reversals a period
        double worst = 0;
        for (std::size_t k = 0; k < section.points(); ++k) {
            const double t = rows[3 * k], x = rows[3 * k + 1], v = rows[3 * k + 2];
            EXPECT_NEAR(v, 0.0, 1e-12 * X) << what;  // a reversal: the velocity passes through 0
            EXPECT_NEAR(std::fabs(x), X, 1e-9 * X) << what << " point " << k;
            if (k >= 2) {  // the point a period before
                worst = std::max(worst, std::fabs(x - rows[3 * (k - 2) + 1]));
                EXPECT_NEAR(x, rows[3 * (k - 2) + 1], 1e-9 * X) << what << " point " << k;
                EXPECT_NEAR(t - rows[3 * (k - 2)], p.period, 1e-9) << what << " point " << k;
            }
            if (k >= 1) EXPECT_NEAR(x, -rows[3 * (k - 1) + 1], 1e-9 * X) << what << " point " << k;
        }
        std::printf("%s: 40 reversals at +-%.12f (Den Hartog X %.12f), repeat a period later within %.3g\n",
                    what.c_str(), std::fabs(rows[1]), X, worst);
    }
}

// The section CSV holds the events CSV's rows of that kind (one per instant), with the trajectory's header.
TEST(SimulateCli, SectionIsTheEventsOfThatKind) {
    const std::string events = temp_path("events.csv"), out = temp_path("section.csv"), png = temp_path("section.png");
    const testing::CliRun r = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") + "' --t-end 40 --events '" +
                                       events + "' --section reversal:m2 --section-out '" + out + "' --section-plot '" +
                                       png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("Poincare section at reversal:m2: "), std::string::npos) << r.err;
    const auto ev = csv_rows(slurp(events)), sec = csv_rows(slurp(out));
    EXPECT_EQ(sec[0], (std::vector<std::string>{"t", "x_m1", "x_m2", "v_m1", "v_m2"}));
    std::vector<std::vector<std::string>> want;
    for (std::size_t i = 1; i < ev.size(); ++i)
        if (ev[i][1] == "reversal" && ev[i][2] == "m2") {
            std::vector<std::string> row = {ev[i][0]};
            row.insert(row.end(), ev[i].begin() + 3, ev[i].end());
            want.push_back(row);
        }
    ASSERT_GT(want.size(), 10u);
    ASSERT_EQ(sec.size(), want.size() + 1);
    for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(sec[i + 1], want[i]) << i;
    const std::string image = slurp(png);
    ASSERT_GT(image.size(), 8u);
    EXPECT_EQ(image.substr(1, 3), "PNG");
}

// lyapunov --section: the same points as simulate's events of that kind, from t0 + transient on.
TEST(LyapunovCli, SectionOverTheMeasurement) {
    const std::string events = temp_path("events.csv"), out = temp_path("section.csv");
    const testing::CliRun sim = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") + "' --t-end 40 --events '" +
                                         events + "'");
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const testing::CliRun r = run_hsnc("lyapunov '" + model_path("seed-scenario-2.toml") +
                                       "' --transient 10 --t-end 30 --section contact_close:contact1 --section-out '" +
                                       out + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto ev = csv_rows(slurp(events)), sec = csv_rows(slurp(out));
    std::vector<std::vector<std::string>> want;
    for (std::size_t i = 1; i < ev.size(); ++i)
        if (ev[i][1] == "contact_close" && std::stod(ev[i][0]) >= 10.0) {
            std::vector<std::string> row = {ev[i][0]};
            row.insert(row.end(), ev[i].begin() + 3, ev[i].end());
            want.push_back(row);
        }
    ASSERT_GT(want.size(), 10u);
    ASSERT_EQ(sec.size(), want.size() + 1);
    for (std::size_t i = 0; i < want.size(); ++i) {
        EXPECT_EQ(sec[i + 1], want[i]) << i;
        // On the section: G = x1 - x2 - phi1 = 0 to the engine's location of
        // the switch (measured: up to 1.3e-12 here, |G'| about 10 m/s at t = 10..40 s).
        EXPECT_NEAR(std::stod(sec[i + 1][1]) - std::stod(sec[i + 1][2]), 0.2, 1e-11) << i;
    }
}

TEST(SimulateCli, SectionBadFlagsExitTwoWithNothingWritten) {
    const std::string out = temp_path("section.csv"), traj = temp_path("traj.csv");
    struct Case {
        std::string command, message;
    };
    const std::string s2 = "'" + model_path("seed-scenario-2.toml") + "' --t-end 1 ";
    const std::vector<Case> cases = {
        {"simulate " + s2 + "--section-out '" + out + "'", "--section-out: needs --section"},
        {"simulate " + s2 + "--section contact_close", "needs --section-out CSV, --section-plot PNG or --h5 FILE"},
        {"simulate " + s2 + "--section closing --section-out '" + out + "'", "--section 'closing': expected KIND"},
        {"simulate " + s2 + "--section contact_close:nope --section-out '" + out + "'", "no contact named 'nope'"},
        {"simulate " + s2 + "--section stick:nope --section-out '" + out + "'", "no mass with friction named 'nope'"},
        {"simulate '" + model_path("bilinear-1dof.toml") + "' --t-end 1 --section stick --section-out '" + out + "'",
         "has no mass with friction"},
        {"simulate " + s2 + "--out '" + traj + "' --section stick --section-out '" + traj + "'", "--section-out"},
        {"lyapunov " + s2 + "--section-plot '" + out + "'", "--section-plot: needs --section"},
        {"lyapunov " + s2 + "--section release:m3 --section-out '" + out + "'", "no mass with friction named 'm3'"},
    };
    for (const Case& c : cases) {
        const testing::CliRun r = run_hsnc(c.command);
        EXPECT_EQ(r.exit_code, 2) << c.command << "\n" << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.command << "\n" << r.err;
        EXPECT_TRUE(r.out.empty()) << c.command;
        EXPECT_FALSE(file_exists(out)) << c.command;
        EXPECT_FALSE(file_exists(traj)) << c.command;
    }
}

}  // namespace
}  // namespace hsnc
