// Tests of `hsnc inspect` and `hsnc generate` through the real binary.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "cli_runner.h"

namespace {

using hsnc::testing::run_hsnc;

const std::string kSeed1 = std::string(HSNC_SOURCE_DIR) + "/models/seed-scenario-1.toml";

// The number printed right after `key` ("omega = 10.72...") on the line of mode 1.
double number_after(const std::string& text, const std::string& key) {
    const auto p = text.find(key, text.find("mode 1:"));
    if (p == std::string::npos) return NAN;
    return std::strtod(text.c_str() + p + key.size(), nullptr);
}

TEST(Inspect, SeedScenario1ClosedContactStuckM2) {
    // One free DOF m1: K = k1 + k2 + k* = 5 + 10 + 100, M = 1, C = beta K.
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\"");
    ASSERT_EQ(r.exit_code, 0);
    const double k = 5.0 + 10.0 + 100.0, beta = 0.1, omega = std::sqrt(k), c = beta * k, xi = c / (2 * omega);
    EXPECT_NE(r.out.find("M = [1]"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("K = [115]"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("C = [11.5]"), std::string::npos) << r.out;
    EXPECT_NEAR(number_after(r.out, "lambda = "), k, 1e-13 * k);
    EXPECT_NEAR(number_after(r.out, "omega = "), omega, 1e-15 * omega);
    EXPECT_NEAR(number_after(r.out, ", c = "), c, 1e-15 * c);
    EXPECT_NEAR(number_after(r.out, "xi = "), xi, 1e-15 * xi);
    EXPECT_NE(r.out.find("underdamped"), std::string::npos);
    EXPECT_NE(r.out.find("x_m1(tau) = "), std::string::npos);
    EXPECT_NE(r.out.find("x_m2(tau) = x0_m2"), std::string::npos);  // stuck
    EXPECT_NE(r.out.find("g_4 (-A - mu_s N of m2)"), std::string::npos);
}

TEST(Inspect, LatexIsBalancedAndHasNoCTokens) {
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --format latex");
    ASSERT_EQ(r.exit_code, 0);
    int depth = 0;
    bool never_negative = true;
    for (char ch : r.out) {
        depth += ch == '{' ? 1 : ch == '}' ? -1 : 0;
        never_negative = never_negative && depth >= 0;
    }
    EXPECT_EQ(depth, 0);
    EXPECT_TRUE(never_negative);
    for (const char* token : {"*", "__builtin", "pow(", "std::", "==", "double"})
        EXPECT_EQ(r.out.find(token), std::string::npos) << token;
    EXPECT_NE(r.out.find("\\omega_{1} = 10.723805294763608"), std::string::npos);
}

TEST(Inspect, TwoProcessesPrintTheSameView) {
    // The expressions are printed in sorted term order (expression_printer.h):
    // GiNaC's own order follows symbol serial numbers and hashes, and the
    // numeric view of the same configuration differed from run to run.
    const std::string chain = std::string(HSNC_SOURCE_DIR) + "/models/chain-8.toml";
    for (const char* format : {"text", "latex"}) {
        const auto a = run_hsnc("inspect " + chain + " --format " + format),
                   b = run_hsnc("inspect " + chain + " --format " + format);
        ASSERT_EQ(a.exit_code, 0) << a.err;
        EXPECT_NE(a.out.find(std::string(format) == "text" ? "x_m3(tau) = " : "x_{m3}"), std::string::npos) << format;
        EXPECT_EQ(a.out, b.out) << format;
    }
}

TEST(Inspect, CppFormatIsTheKernel) {
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --format cpp");
    ASSERT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("extern \"C\" const hsnc_kernel hsnc_kernel_seed_scenario_1_c1_s01"), std::string::npos);
}

TEST(Inspect, BadConfigIsInputError) {
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --config closed=nope").exit_code, 2);
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --format pdf").exit_code, 2);
}

// stuck=m1,m1 was taken as stuck=m1: a name given twice in one list is most
// likely a typo for another one.
TEST(Inspect, ConfigNamingAnElementTwiceIsRefused) {
    const std::string jenkins = std::string(HSNC_SOURCE_DIR) + "/examples/jenkins/friction_damper.toml";
    const std::pair<std::string, std::string> cases[] = {
        {kSeed1 + " --config stuck=m1,m1", "--config: stuck=m1,m1: 'm1'"},
        {kSeed1 + " --config 'closed=contact1,contact1 stuck=m2'", "--config: closed=contact1,contact1: 'contact1'"},
        {jenkins + " --config slip=damper+,damper-", "--config: slip=damper+,damper-: 'damper'"},
    };
    for (const auto& [args, message] : cases) {
        const auto r = run_hsnc("inspect " + args);
        EXPECT_EQ(r.exit_code, 2) << args;
        EXPECT_EQ(r.out, "") << args;
        EXPECT_EQ(r.err, "hsnc: " + message + " names an element given before in the list\n") << args;
    }
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --config stuck=m1,m2").exit_code, 0);
}

// `generate --bogus M` said "--out-dir is required" (CLI11 checks required
// options before the arguments it did not take): the unknown flag is named,
// on every subcommand.
TEST(Generate, AnUnknownFlagIsNamedBeforeAMissingRequiredOne) {
    for (const char* sub : {"check", "simulate", "inspect", "generate", "cache", "tradeoff", "sweep", "sweep-merge",
                            "periodic", "lyapunov"}) {
        for (const std::string& args : {std::string(sub) + " --bogus", std::string(sub) + " --bogus " + kSeed1}) {
            if (args == "cache --bogus " + kSeed1) continue;  // cache takes no file: two arguments not expected
            const auto r = run_hsnc(args);
            EXPECT_EQ(r.exit_code, 2) << args;
            EXPECT_EQ(r.out, "") << args;
            EXPECT_EQ(r.err, "hsnc: The following argument was not expected: --bogus\n") << args;
        }
    }
    // Two of them: named as when nothing required is missing (CLI11's message).
    const auto two = run_hsnc("generate --bogus " + kSeed1 + " --frob");
    EXPECT_NE(two.err.find("hsnc: The following arguments were not expected: "), std::string::npos) << two.err;
    EXPECT_EQ(two.err, run_hsnc("generate --bogus " + kSeed1 + " --frob -o never-created").err);
    EXPECT_FALSE(std::filesystem::exists("never-created"));
    // Without an unknown flag the missing one is still what is said.
    const auto missing = run_hsnc("generate " + kSeed1);
    EXPECT_EQ(missing.exit_code, 2);
    EXPECT_NE(missing.err.find("--out-dir is required"), std::string::npos) << missing.err;
}

std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(Generate, TwoProcessesWriteIdenticalBytes) {
    namespace fs = std::filesystem;
    const fs::path base = fs::temp_directory_path() / ("hsnc_generate_test_" + std::to_string(::getpid()));
    fs::remove_all(base);
    ASSERT_EQ(run_hsnc("generate " + kSeed1 + " -o " + (base / "a").string()).exit_code, 0);
    ASSERT_EQ(run_hsnc("generate " + kSeed1 + " -o " + (base / "b").string()).exit_code, 0);
    int files = 0;
    for (const auto& e : fs::directory_iterator(base / "a")) {
        EXPECT_EQ(slurp(e.path()), slurp(base / "b" / e.path().filename())) << e.path();
        ++files;
    }
    EXPECT_EQ(files, 8 + 2);  // 2^(1 contact + 2 friction masses) kernels, the manifest and the registry
    fs::remove_all(base);
}

}  // namespace
