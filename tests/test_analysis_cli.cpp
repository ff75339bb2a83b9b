// `hsnc periodic` and `hsnc lyapunov` as a user runs them (interface.md
// section 6): the stdout line, the CSV files, exit codes 0 / 1 / 2 and
// nothing written on failure or bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;

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

TEST(PeriodicCli, SeedScenario1OrbitMultipliersAndOnePeriod) {
    const std::string mult = temp_path("mult.csv"), out = temp_path("orbit.csv");
    const testing::CliRun r = run_hsnc("periodic '" + model_path("seed-scenario-1.toml") + "' --multipliers '" + mult +
                                       "' --out '" + out + "' --dt 0.001");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::regex line(
        "status=ok period=(\\S+) iterations=\\d+ residual=(\\S+) x_m1=\\S+ x_m2=\\S+ v_m1=(\\S+) v_m2=\\S+ "
        "stable=(true|false) max_multiplier=(\\S+) grazing=0\n");
    std::smatch m;
    ASSERT_TRUE(std::regex_match(r.out, m, line)) << r.out;
    const double period = std::stod(m[1]);
    EXPECT_NEAR(period, 2 * M_PI / 175.5151, 1e-15);
    EXPECT_LE(std::stod(m[2]), 1e-10);
    const double max_mu = std::stod(m[5]);
    EXPECT_EQ(m[4] == "true", max_mu < 1);

    const auto mu = csv_rows(slurp(mult));
    ASSERT_EQ(mu.size(), 5u);
    EXPECT_EQ(mu[0], (std::vector<std::string>{"index", "re", "im", "abs"}));
    double previous = INFINITY;
    for (std::size_t i = 1; i < mu.size(); ++i) {
        ASSERT_EQ(mu[i].size(), 4u);
        EXPECT_EQ(mu[i][0], std::to_string(i));
        const double re = std::stod(mu[i][1]), im = std::stod(mu[i][2]), abs = std::stod(mu[i][3]);
        EXPECT_NEAR(std::hypot(re, im), abs, 1e-15 * (1 + abs));
        EXPECT_LE(abs, previous);
        previous = abs;
    }
    EXPECT_EQ(std::stod(mu[1][3]), max_mu);

    // One period: t0 .. t0 + period every dt, ending where it started.
    const auto rows = csv_rows(slurp(out));
    ASSERT_GT(rows.size(), 30u);
    EXPECT_EQ(rows[0], (std::vector<std::string>{"t", "x_m1", "x_m2", "v_m1", "v_m2"}));
    EXPECT_EQ(std::stod(rows[1][0]), 0.0);
    EXPECT_NEAR(std::stod(rows.back()[0]), period, 1e-15);
    EXPECT_EQ(std::stod(rows[1][3]), std::stod(m[3]));
    for (int c = 1; c <= 4; ++c)
        EXPECT_NEAR(std::stod(rows.back()[c]), std::stod(rows[1][c]), 1e-9 * (1 + std::fabs(std::stod(rows[1][c]))));
}

TEST(PeriodicCli, NotConvergedIsExitOneAndWritesNothing) {
    const std::string mult = temp_path("mult.csv"), out = temp_path("orbit.csv");
    // Scenario 2 from its initial state: the period map is far from a fixed point there.
    const testing::CliRun r = run_hsnc("periodic '" + model_path("seed-scenario-2.toml") + "' --max-iterations 1 --multipliers '" +
                                       mult + "' --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(r.out.rfind("status=not_converged period=", 0), 0u) << r.out;
    EXPECT_NE(r.out.find(" stable=false max_multiplier=nan grazing="), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("not converged"), std::string::npos) << r.err;
    EXPECT_FALSE(file_exists(mult));
    EXPECT_FALSE(file_exists(out));
}

TEST(PeriodicCli, SubharmonicAndTransient) {
    // chain-8 after 100 s: a stable period-1 orbit; with --harmonic 2 the same
    // orbit is found as a period-2 one, at a multiple of 2T.
    const testing::CliRun one = run_hsnc("periodic '" + model_path("chain-8.toml") + "' --transient 100");
    const testing::CliRun two = run_hsnc("periodic '" + model_path("chain-8.toml") + "' --transient 100 --harmonic 2");
    ASSERT_EQ(one.exit_code, 0) << one.err;
    ASSERT_EQ(two.exit_code, 0) << two.err;
    std::smatch a, b;
    const std::regex period("period=(\\S+) .* max_multiplier=(\\S+) grazing=0\n");
    ASSERT_TRUE(std::regex_search(one.out, a, period));
    ASSERT_TRUE(std::regex_search(two.out, b, period));
    EXPECT_EQ(std::stod(b[1]), 2 * std::stod(a[1]));
    // The multipliers of the doubled period are the squares.
    EXPECT_NEAR(std::stod(b[2]), std::stod(a[2]) * std::stod(a[2]), 1e-8);
}

TEST(PeriodicCli, BadInputIsExitTwoWithNothingWritten) {
    const std::string mult = temp_path("mult.csv");
    struct Case {
        std::string args, message;
    };
    const std::vector<Case> cases = {
        {"'" + model_path("coulomb-1dof.toml") + "'", "no harmonic forcing"},
        {"'" + model_path("seed-scenario-1.toml") + "' --harmonic 0", "--harmonic"},
        {"'" + model_path("seed-scenario-1.toml") + "' --period -1", "--period"},
        {"'" + model_path("seed-scenario-1.toml") + "' --transient nan", "--transient"},
        {"'" + model_path("seed-scenario-1.toml") + "' --out '" + ::testing::TempDir() + "'", "--out"},
        {"'" + model_path("seed-scenario-1.toml") + "' --kernels fast", "--kernels"},
        {"'" + model_path("seed-scenario-1.toml") + "' --set k1=1 --kernels aot", "--kernels"},
        {"'" + model_path("seed-scenario-1.toml") + "' --set nope=1", "nope"},
    };
    for (const Case& c : cases) {
        const testing::CliRun r = run_hsnc("periodic " + c.args + " --multipliers '" + mult + "'");
        EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_TRUE(r.out.empty()) << c.args;
        EXPECT_FALSE(file_exists(mult)) << c.args;
    }
}

TEST(LyapunovCli, SeedScenario2SpectrumAndConvergenceCsv) {
    const std::string out = temp_path("lyap.csv");
    const testing::CliRun r =
        run_hsnc("lyapunov '" + model_path("seed-scenario-2.toml") + "' --t-end 30 --out '" + out + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::regex line(
        "status=ok t=(\\S+) lambda_1=(\\S+) lambda_2=(\\S+) lambda_3=(\\S+) lambda_4=(\\S+) sum=(\\S+) grazing=0\n");
    std::smatch m;
    ASSERT_TRUE(std::regex_match(r.out, m, line)) << r.out;
    EXPECT_EQ(std::stod(m[1]), 30.0);
    for (int k = 2; k < 5; ++k) EXPECT_GE(std::stod(m[k]), std::stod(m[k + 1]));  // largest first
    const auto rows = csv_rows(slurp(out));
    EXPECT_EQ(rows[0], (std::vector<std::string>{"t", "lambda_1", "lambda_2", "lambda_3", "lambda_4"}));
    // A row per forcing period (omega = 17.5515), and one at the end.
    const double T = 2 * M_PI / 17.5515;
    ASSERT_EQ(rows.size(), 1 + static_cast<std::size_t>(std::floor(30 / T)) + 1);
    EXPECT_NEAR(std::stod(rows[1][0]), T, 1e-12);
    EXPECT_NEAR(std::stod(rows[2][0]), 2 * T, 1e-12);
    EXPECT_EQ(std::stod(rows.back()[0]), 30.0);
    for (int k = 1; k <= 4; ++k) EXPECT_EQ(rows.back()[k], m[k + 1].str());
}

TEST(LyapunovCli, StickCollapsesADirectionToMinusInfinity) {
    // coulomb-1dof decays and sticks (between t = 3 and 4 s): its velocity direction collapses.
    const std::string out = temp_path("lyap.csv");
    const testing::CliRun r = run_hsnc("lyapunov '" + model_path("coulomb-1dof.toml") + "' --t-end 5 --out '" + out + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(" lambda_2=-inf sum=-inf grazing=0\n"), std::string::npos) << r.out;
    const auto rows = csv_rows(slurp(out));
    ASSERT_EQ(rows.size(), 6u);  // header and a row per second (no forcing)
    EXPECT_EQ(rows[1][0], "1");
    EXPECT_NE(rows[1][2], "-inf");  // still sliding at t = 1
    EXPECT_EQ(rows[5][2], "-inf");
}

TEST(LyapunovCli, BadInputIsExitTwo) {
    const std::string out = temp_path("lyap.csv");
    for (const std::string& args : {std::string("'") + model_path("seed-scenario-2.toml") + "'",
                                    "'" + model_path("seed-scenario-2.toml") + "' --t-end -3",
                                    "'" + model_path("seed-scenario-2.toml") + "' --t-end 3 --transient -1",
                                    "'" + model_path("seed-scenario-2.toml") + "' --t-end inf"}) {
        const testing::CliRun r = run_hsnc("lyapunov " + args + " --out '" + out + "'");
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
        EXPECT_TRUE(r.out.empty()) << args;
        EXPECT_FALSE(file_exists(out)) << args;
    }
}

}  // namespace
}  // namespace hsnc
