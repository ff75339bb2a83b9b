// `hsnc periodic` and `hsnc lyapunov` as a user runs them (interface.md
// section 6): the stdout line, the CSV files, exit codes 0 / 1 / 2 and
// nothing written on failure or bad input.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
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
        // A period over which every state repeats to the tolerance: not `status=ok` at the initial state.
        {"'" + model_path("seed-scenario-1.toml") + "' --period 1e-300", "--period: too short for this model"},
        {"'" + model_path("seed-scenario-1.toml") + "' --period 1e-300 --harmonic 3", "--period: too short"},
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

// The output guard of `hsnc simulate` (1e7 rows or 1 GB, --allow-large-output)
// before the run: one period of the orbit every --dt, the convergence rows
// every --row-interval (or every forcing period of a very long --t-end).
TEST(PeriodicCli, ALargeOrbitOutputIsRefusedBeforeTheRun) {
    const std::string out = temp_path("orbit.csv");
    const testing::CliRun r =
        run_hsnc("periodic '" + model_path("seed-scenario-1.toml") + "' --dt 1e-12 --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--dt 9.9999999999999998e-13: one period"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--allow-large-output"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
    EXPECT_FALSE(file_exists(out));
    // A --dt that gives a modest file (3580 rows) runs.
    const testing::CliRun ok = run_hsnc("periodic '" + model_path("seed-scenario-1.toml") +
                                        "' --quiet --dt 1e-5 --out '" + out + "'");
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST(LyapunovCli, ALargeConvergenceOutputIsRefusedBeforeTheRun) {
    const std::string out = temp_path("lyap.csv");
    const std::string model = "'" + model_path("seed-scenario-2.toml") + "'";
    for (const std::string& args : {std::string("--t-end 100 --row-interval 1e-9"), std::string("--t-end 1e12")}) {
        const testing::CliRun r = run_hsnc("lyapunov " + model + " " + args + " --out '" + out + "'");
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
        EXPECT_NE(r.err.find(args.find("row") != std::string::npos ? "--row-interval 1.0000000000000001e-09: the "
                                                                      "convergence --out would have 1e+11 rows"
                                                                    : "--t-end 1000000000000 (a row every "),
                  std::string::npos)
            << r.err;
        EXPECT_NE(r.err.find("--allow-large-output"), std::string::npos) << r.err;
        EXPECT_TRUE(r.out.empty()) << args;
        EXPECT_FALSE(file_exists(out)) << args;
    }
}

// `simulate --plot` alone samples for the figure on a bounded grid: a --dt of
// 1e-300 ran forever (1e300 samples for a figure of 2000 buckets).
TEST(SimulateCli, APlotAloneWithATinyDtFinishes) {
    const std::string png = temp_path("tiny-dt.png");
    const auto start = std::chrono::steady_clock::now();
    const testing::CliRun r =
        run_hsnc("simulate '" + model_path("coulomb-1dof.toml") + "' --t-end 1 --dt 1e-300 --quiet --plot '" + png + "'");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
    EXPECT_LT(seconds, 60.0);
}

// A friction damper stuck all period: a linear orbit with a neutral
// multiplier (a family of orbits: its slider at any offset) is stable, with
// `neutral=1` (it was `stable=false` at a multiplier 0.99999999999999978).
TEST(PeriodicCli, AFullyStuckOrbitIsStableWithItsNeutralMultiplier) {
    const std::string model = "'" + std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml'";
    const testing::CliRun r = run_hsnc("periodic " + model + " --set omega=12 --transient 40 --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::regex line(".* stable=true max_multiplier=(\\S+) grazing=0 neutral=1\n");
    std::smatch m;
    ASSERT_TRUE(std::regex_match(r.out, m, line)) << r.out;
    EXPECT_NEAR(std::stod(m[1]), 1.0, 1e-12);
    // A slipping orbit has none: the line ends as before.
    const testing::CliRun slip = run_hsnc("periodic " + model + " --transient 30 --quiet");
    ASSERT_EQ(slip.exit_code, 0) << slip.err;
    EXPECT_NE(slip.out.find(" stable=true max_multiplier="), std::string::npos) << slip.out;
    EXPECT_EQ(slip.out.find("neutral="), std::string::npos) << slip.out;
}

// A long command says it is alive on stderr when stderr is not a terminal: a
// line every 10 s (a measurement of hours here, stopped once it has spoken).
TEST(LyapunovCli, ALongRunSaysItsProgressEveryTenSeconds) {
    const std::string err = temp_path("stderr");
    const pid_t pid =
        testing::spawn_hsnc({"lyapunov", model_path("seed-scenario-2.toml"), "--t-end", "1e8"}, "/dev/null", err);
    ASSERT_GE(pid, 0);
    std::string text;
    for (int i = 0; i < 600 && text.find('\n') == std::string::npos; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        text = slurp(err);
    }
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    std::remove(err.c_str());
    const std::regex line("hsnc lyapunov: t = \\S+ s, \\S+% of the measurement, 1\\d s, about \\d+ s left\n");
    EXPECT_TRUE(std::regex_match(text, line)) << text;
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
