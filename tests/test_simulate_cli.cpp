// `hsnc simulate` against the interface contract (sections 3 and 4): flags,
// CSV headers and kinds, exit codes, the summary line, nothing written on
// bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <vector>

#include "cli_runner.h"

namespace hsnc {
namespace {

using testing::file_exists;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::temp_path;

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
}

std::vector<std::string> fields(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string f; std::getline(in, f, ',');) out.push_back(f);
    return out;
}

TEST(SimulateCli, WritesTheContractsCsvFiles) {
    const std::string out = temp_path("traj.csv"), ev = temp_path("events.csv");
    const auto r = run_hsnc("simulate '" + model_path("seed-scenario-1.toml") + "' --t-end 0.5 --dt 0.01 --out '" +
                            out + "' --events '" + ev + "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");  // --quiet
    const auto traj = lines(slurp(out));
    ASSERT_EQ(traj.size(), 1u + 51u);  // header + t = 0, 0.01, ..., 0.5
    EXPECT_EQ(traj[0], "t,x_m1,x_m2,v_m1,v_m2");
    EXPECT_EQ(fields(traj[1])[0], "0");
    EXPECT_EQ(fields(traj.back())[0], "0.5");
    // 17 significant digits: the initial x1 = 0.2 round-trips exactly.
    EXPECT_EQ(std::stod(fields(traj[1])[1]), 0.2);
    const auto events = lines(slurp(ev));
    ASSERT_GT(events.size(), 2u);
    EXPECT_EQ(events[0], "t,kind,element,x_m1,x_m2,v_m1,v_m2");
    double last_t = 0;
    for (std::size_t k = 1; k < events.size(); ++k) {
        const auto f = fields(events[k]);
        ASSERT_EQ(f.size(), 7u);
        const double t = std::stod(f[0]);
        EXPECT_GE(t, last_t);
        last_t = t;
        EXPECT_TRUE(f[1] == "contact_close" || f[1] == "contact_open" || f[1] == "stick" || f[1] == "release" ||
                    f[1] == "reversal")
            << f[1];
        if (f[1].rfind("contact", 0) == 0)
            EXPECT_EQ(f[2], "contact1");
        else
            EXPECT_TRUE(f[2] == "m1" || f[2] == "m2");
    }
    // Summary line: status, number of events, end state.
    EXPECT_NE(r.out.find("status=ok"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("events=" + std::to_string(events.size() - 1)), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("x_m1="), std::string::npos);
    EXPECT_NE(r.out.find("v_m2="), std::string::npos);
}

TEST(SimulateCli, TEndOffTheGridGetsItsOwnRow) {
    const std::string out = temp_path("traj.csv");
    const auto r = run_hsnc("simulate '" + model_path("coulomb-1dof.toml") + "' --t-end 0.25 --dt 0.1 --out '" + out +
                            "' --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto traj = lines(slurp(out));
    ASSERT_EQ(traj.size(), 5u);
    EXPECT_EQ(fields(traj[3])[0], "0.20000000000000001");  // 2*0.1 printed with 17 digits
    EXPECT_EQ(fields(traj[4])[0], "0.25");
}

TEST(SimulateCli, OverridesApply) {
    const auto r = run_hsnc("simulate '" + model_path("coulomb-1dof.toml") +
                            "' --t-end 0.1 --set k=400 --x0 m1=0.1 --v0 m1=0 --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // x = xe + (0.1 - xe) cos(20 t), xe = mu g / omega^2 (sliding towards -x).
    const double xe = 0.1 * 9.81 / 400, x = xe + (0.1 - xe) * std::cos(2.0);
    const auto at = r.out.find("x_m1=");
    ASSERT_NE(at, std::string::npos);
    EXPECT_NEAR(std::stod(r.out.substr(at + 5)), x, 1e-15);
}

struct BadFlag {
    const char* args;
    const char* message;
};

class SimulateBadFlags : public ::testing::TestWithParam<BadFlag> {};

TEST_P(SimulateBadFlags, ExitTwoWithOneMessageAndNoFile) {
    const std::string out = temp_path("never.csv");
    const auto r = run_hsnc("simulate '" + model_path("coulomb-1dof.toml") + "' --out '" + out + "' " +
                            GetParam().args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(GetParam().message), std::string::npos) << r.err;
    EXPECT_FALSE(file_exists(out));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, SimulateBadFlags,
    ::testing::Values(BadFlag{"--t-end -1", "--t-end"}, BadFlag{"--t-end abc", "--t-end"},
                      BadFlag{"--dt 0", "--dt"}, BadFlag{"--method euler", "--method 'euler'"},
                      BadFlag{"--method ab4", "--h: method ab4 needs a fixed step"}, BadFlag{"--set k", "--set"},
                      BadFlag{"--set nope=1", "nope"}, BadFlag{"--x0 m9=1", "m9"},
                      BadFlag{"--kernels fast", "--kernels 'fast'"}, BadFlag{"--frobnicate", "frobnicate"},
                      BadFlag{"--method cvode --rtol 0", "--rtol 0: must be finite and > 0"},
                      BadFlag{"--method cvode --atol -1e-9", "--atol -1e-09: must be finite and > 0"},
                      BadFlag{"--method cvode --rtol abc", "--rtol"}));

TEST(SimulateCli, MissingModelIsBadInput) {
    const auto r = run_hsnc("simulate /nonexistent/model.toml --t-end 1");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("/nonexistent/model.toml"), std::string::npos) << r.err;
}

TEST(SimulateCli, BaselinesRunThroughTheSameOutput) {
    for (const char* method : {"--method ab4 --h 1e-4", "--method rk45 --rtol 1e-10", "--method cvode --rtol 1e-10"}) {
        const std::string ev = temp_path("events.csv");
        const auto r = run_hsnc("simulate '" + model_path("coulomb-1dof.toml") + "' --t-end 5 --events '" + ev +
                                "' --quiet " + method);
        ASSERT_EQ(r.exit_code, 0) << method << r.err;
        const auto events = lines(slurp(ev));
        // Nine reversals and the final stick, as the exact solution has.
        ASSERT_EQ(events.size(), 11u) << method;
        EXPECT_EQ(fields(events.back())[1], "stick") << method;
        const bool fixed_step = std::string(method).find("ab4") != std::string::npos;
        EXPECT_NEAR(std::stod(fields(events.back())[0]), 3.14159265358979, fixed_step ? 2e-4 : 1e-6) << method;
    }
}


// The ahead-of-time kernels and the Eigen solver are two independent
// implementations of the same closed forms: same events, times to rounding.
TEST(SimulateCli, AotKernelsAgreeWithTheEigenSolver) {
    std::vector<std::vector<std::string>> rows[2];
    const char* modes[2] = {"aot", "eigen"};
    for (int k = 0; k < 2; ++k) {
        const std::string ev = temp_path("events.csv");
        const auto r = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") + "' --t-end 20 --quiet --events '" +
                                ev + "' --kernels " + modes[k]);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        for (const std::string& l : lines(slurp(ev))) rows[k].push_back(fields(l));
    }
    ASSERT_EQ(rows[0].size(), rows[1].size());
    ASSERT_GT(rows[0].size(), 200u);
    for (std::size_t i = 1; i < rows[0].size(); ++i) {
        EXPECT_EQ(rows[0][i][1], rows[1][i][1]) << i;
        EXPECT_EQ(rows[0][i][2], rows[1][i][2]) << i;
        const double ta = std::stod(rows[0][i][0]), tb = std::stod(rows[1][i][0]);
        EXPECT_NEAR(ta, tb, 1e-9 * std::max(1.0, ta)) << i;
    }
}

TEST(SimulateCli, KernelsAotRefusesAModelItHasNoKernelsFor) {
    const auto r = run_hsnc("simulate '" + model_path("coulomb-1dof.toml") + "' --t-end 1 --set k=99 --kernels aot");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("no ahead-of-time kernels"), std::string::npos) << r.err;
}

TEST(SimulateCli, PlotWritesAPng) {
    const std::string out = temp_path("traj.csv"), png = temp_path("plot.png");
    const auto r = run_hsnc("simulate '" + model_path("bilinear-1dof.toml") + "' --quiet --out '" + out +
                            "' --plot '" + png + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string bytes = slurp(png);
    ASSERT_GT(bytes.size(), 1000u);
    EXPECT_EQ(bytes.substr(1, 3), "PNG");
}

}  // namespace
}  // namespace hsnc
