// Tests of `hsnc check` (cli/check.cpp): the built binary is run as a user
// would run it, and its output and exit code are checked. Natural frequencies
// are compared with closed forms computed here, not with earlier output.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::CliRun;
using testing::model_path;
using testing::run_hsnc;
using testing::slurp;
using testing::write_temp;

/// One row of the frequency table: omega_n (0 for a rigid-body mode), f, xi.
struct Mode {
    double omega = 0, f = 0, xi = 0;
    bool rigid = false;
};

/// The rows after the "mode  omega_n" header, up to the next line that does not start with a mode number.
std::vector<Mode> modes_of(const std::string& out) {
    std::vector<Mode> modes;
    std::istringstream in(out);
    std::string line;
    bool in_table = false;
    while (std::getline(in, line)) {
        if (line.find("mode  omega_n") != std::string::npos) {
            in_table = true;
            continue;
        }
        if (!in_table) continue;
        std::istringstream row(line);
        int number = 0;
        if (!(row >> number) || number != static_cast<int>(modes.size()) + 1) break;
        Mode m;
        if (line.find("0 (rigid-body mode)") != std::string::npos) {
            m.rigid = true;
        } else {
            row >> m.omega >> m.f >> m.xi;
        }
        modes.push_back(m);
    }
    return modes;
}

void expect_relative(double actual, double expected, double tolerance = 1e-10) {
    EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << "expected " << expected;
}

TEST(Check, SeedScenarioFrequenciesMatchTheCharacteristicPolynomial) {
    // M = diag(1, 2), K = [[k1+k2, -k2], [-k2, k2+k3]] = [[15, -10], [-10, 50]]:
    // det(K - lambda M) = 2 (lambda^2 - 40 lambda + 325), lambda = 20 -+ sqrt(75).
    const double w1 = std::sqrt(20.0 - std::sqrt(75.0)), w2 = std::sqrt(20.0 + std::sqrt(75.0));
    for (const auto& [file, beta] : {std::pair<const char*, double>{"seed-scenario-1.toml", 0.1},
                                     std::pair<const char*, double>{"seed-scenario-2.toml", 0.0}}) {
        SCOPED_TRACE(file);
        const CliRun r = run_hsnc("check '" + model_path(file) + "'");
        EXPECT_EQ(r.exit_code, 0);
        EXPECT_EQ(r.err, "");
        const auto modes = modes_of(r.out);
        ASSERT_EQ(modes.size(), 2u) << r.out;
        expect_relative(modes[0].omega, w1);
        expect_relative(modes[1].omega, w2);
        expect_relative(modes[0].f, w1 / (2.0 * M_PI));
        expect_relative(modes[1].f, w2 / (2.0 * M_PI));
        // C = beta*K: xi = beta*omega/2.
        EXPECT_NEAR(modes[0].xi, beta * w1 / 2.0, 1e-10);
        EXPECT_NEAR(modes[1].xi, beta * w2 / 2.0, 1e-10);
    }
}

TEST(Check, SeedScenarioSummary) {
    const CliRun r = run_hsnc("check '" + model_path("seed-scenario-1.toml") + "'");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("model: seed-scenario-1\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("source: " + model_path("seed-scenario-1.toml") + "\n"), std::string::npos);
    EXPECT_NE(r.out.find("degrees of freedom: 2\n  1  m1  m = 1\n  2  m2  m = 2\n"), std::string::npos);
    EXPECT_NE(r.out.find("contact1  between m1 and m2  gap = 0.2  k = 100\n"), std::string::npos);
    EXPECT_NE(r.out.find("  m1  mu_k = 0.6  mu_s = 0.75\n  m2  mu_k = 0.6  mu_s = 0.75\n"), std::string::npos);
    ASSERT_GE(r.out.size(), 3u);
    EXPECT_EQ(r.out.substr(r.out.size() - 3), "ok\n");
}

TEST(Check, OneDofModelsGiveSqrtKOverM) {
    for (const char* file : {"bilinear-1dof.toml", "coulomb-1dof.toml"}) {
        SCOPED_TRACE(file);
        // All contacts open: only the springs count.
        const Model model = read_model(model_path(file));
        ASSERT_EQ(model.dof(), 1u);
        double k = 0;
        for (const Spring& s : model.springs) k += s.k;
        const CliRun r = run_hsnc("check '" + model_path(file) + "'");
        EXPECT_EQ(r.exit_code, 0);
        const auto modes = modes_of(r.out);
        ASSERT_EQ(modes.size(), 1u) << r.out;
        expect_relative(modes[0].omega, std::sqrt(k / model.masses[0].m));
    }
}

TEST(Check, ChainFrequenciesMatchTheFixedFixedChain) {
    // n equal masses m between n+1 equal springs k, both ends to ground:
    // omega_j = 2 sqrt(k/m) sin(j pi / (2 (n+1))).
    const Model model = read_model(model_path("chain-8.toml"));
    const double k = model.springs[0].k, m = model.masses[0].m;
    const CliRun r = run_hsnc("check '" + model_path("chain-8.toml") + "'");
    EXPECT_EQ(r.exit_code, 0);
    const auto modes = modes_of(r.out);
    ASSERT_EQ(modes.size(), 8u) << r.out;
    for (int j = 1; j <= 8; ++j) {
        const double w = 2.0 * std::sqrt(k / m) * std::sin(j * M_PI / 18.0);
        expect_relative(modes[j - 1].omega, w);
        EXPECT_NEAR(modes[j - 1].xi, 0.5 * (model.alpha / w + model.beta * w), 1e-10);
    }
}

TEST(Check, RigidBodyModeIsNamed) {
    // Two masses joined by one spring, nothing to ground: omega = 0 and
    // sqrt(k (1/m1 + 1/m2)).
    const std::string path = write_temp("hsnc_free_pair.toml", R"toml(name = "free-pair"
[[mass]]
name = "a"
m = 1
[[mass]]
name = "b"
m = 3
[[spring]]
between = ["a", "b"]
k = 12
)toml");
    const CliRun r = run_hsnc("check '" + path + "'");
    EXPECT_EQ(r.exit_code, 0);
    const auto modes = modes_of(r.out);
    ASSERT_EQ(modes.size(), 2u) << r.out;
    EXPECT_TRUE(modes[0].rigid);
    EXPECT_FALSE(modes[1].rigid);
    expect_relative(modes[1].omega, std::sqrt(12.0 * (1.0 + 1.0 / 3.0)));
    EXPECT_NE(r.out.find("1 rigid-body mode(s)"), std::string::npos) << r.out;
}

TEST(Check, StiffnessRatioAbove1e10IsNoRigidBodyMode) {
    // m1 on a stiff spring k1 to ground, m2 hung from m1 on a soft k2: both
    // are anchored, so no mode is rigid, however small lambda_1 is next to
    // max K_ii/M_ii (the old eigenvalue threshold, 1e-10 of it, called it
    // rigid). lambda = roots of lambda^2 - (k1 + 2 k2) lambda + k1 k2 (m = 1).
    const double k1 = 1e12, k2 = 1.0;
    const std::string path = write_temp("hsnc_stiff.toml", R"toml(name = "stiff"
[[mass]]
name = "m1"
m = 1
[[mass]]
name = "m2"
m = 1
[[spring]]
between = ["ground", "m1"]
k = 1e12
[[spring]]
between = ["m1", "m2"]
k = 1
)toml");
    const CliRun r = run_hsnc("check '" + path + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const auto modes = modes_of(r.out);
    ASSERT_EQ(modes.size(), 2u) << r.out;
    EXPECT_FALSE(modes[0].rigid) << r.out;
    EXPECT_FALSE(modes[1].rigid) << r.out;
    EXPECT_EQ(r.out.find("rigid-body"), std::string::npos) << r.out;
    const double sum = k1 + 2 * k2, product = k1 * k2;
    const double big = 0.5 * (sum + std::sqrt(sum * sum - 4 * product)), small = product / big;
    // A symmetric eigensolver's absolute error in lambda is a few eps * |K| =
    // 1e-4 here, so lambda_1 ~ 1 has a relative error of that order.
    const double tolerance = 8 * 2.22e-16 * k1;
    EXPECT_NEAR(modes[0].omega * modes[0].omega, small, tolerance);
    expect_relative(modes[1].omega, std::sqrt(big));
}

TEST(Check, BadModelGivesExitCode2AndOneMessage) {
    const std::string path = write_temp("hsnc_bad.toml", "name = \"bad\"\n[[mass]]\nname = \"m1\"\nm = -1\n");
    const CliRun r = run_hsnc("check '" + path + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.out, "");  // nothing printed on stdout
    EXPECT_EQ(r.err, "hsnc: " + path + ":4: key 'mass[1].m': mass must be > 0, got -1\n");
}

// Stiffness over mass beyond the double range (k = 1e300 on m = 1e-300):
// check printed "inf -nan" and ok, simulate ran to status=ok with NaN states
// on every kernel kind. Both refuse the model, naming the element, for
// [[mass]]/[[spring]] models and [structure] ones.
TEST(Check, StiffnessOverMassBeyondTheDoubleRangeIsRefused) {
    const std::string lumped = write_temp("hsnc_overflow.toml",
                                          "name = \"overflow\"\n[[mass]]\nname = \"m1\"\nm = 1e-300\n"
                                          "[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = 1e300\n"
                                          "[initial]\nx = { m1 = 0.1 }\n[simulate]\nt_end = 1\n");
    const std::filesystem::path dir = testing::temp_path("overflow-structure");
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "M.mtx") << "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 1e-300\n";
    std::ofstream(dir / "K.mtx") << "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2e300\n2 1 -1e300\n2 2 1e300\n";
    const std::string structure = (dir / "s.toml").string();
    std::ofstream(structure) << "name = \"overflow-structure\"\n[structure]\ndofs = [\"u1\", \"u2\"]\n"
                                "mass = \"M.mtx\"\nstiffness = \"K.mtx\"\n[initial]\nx = { u2 = 0.1 }\n"
                                "[simulate]\nt_end = 1\n";
    const std::string lumped_why = lumped + ":7: key 'spring[1].k': the spring: stiffness 1e+300 over "
                                            "mass 'm1' (m = 1e-300) is beyond the double "
                                            "range: the natural frequency sqrt(k/m) would not be finite";
    const std::string structure_why = structure + ":5: key 'structure.stiffness': K.mtx: -K(u1, u2): stiffness "
                                                  "1e+300 over dof 'u2'";
    for (const char* command : {"check", "simulate"}) {
        const CliRun a = run_hsnc(std::string(command) + " '" + lumped + "'");
        EXPECT_EQ(a.exit_code, 2) << command << ": " << a.out;
        EXPECT_EQ(a.out, "") << command;
        EXPECT_EQ(a.err, "hsnc: " + lumped_why + "\n") << command;
        const CliRun b = run_hsnc(std::string(command) + " '" + structure + "'");
        EXPECT_EQ(b.exit_code, 2) << command << ": " << b.out;
        EXPECT_EQ(b.out, "") << command;
        EXPECT_NE(b.err.find(structure_why), std::string::npos) << command << ": " << b.err;
        EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
    }
    std::filesystem::remove_all(dir);
}

TEST(Check, MissingFileGivesExitCode2) {
    const CliRun r = run_hsnc("check /nonexistent/model.toml");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "hsnc: cannot read model file '/nonexistent/model.toml': No such file or directory\n");
}

TEST(Check, MissingArgumentGivesExitCode2) {
    const CliRun r = run_hsnc("check");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("MODEL is required"), std::string::npos) << r.err;
}

TEST(Check, HelpWorks) {
    const CliRun r = run_hsnc("check --help");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("MODEL"), std::string::npos);
    EXPECT_NE(r.out.find("natural frequencies"), std::string::npos);
}

}  // namespace
}  // namespace hsnc
