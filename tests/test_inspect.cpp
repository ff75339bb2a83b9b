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

TEST(Inspect, CppFormatIsTheKernel) {
    const auto r = run_hsnc("inspect " + kSeed1 + " --config \"closed=contact1 stuck=m2\" --format cpp");
    ASSERT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("extern \"C\" const hsnc_kernel hsnc_kernel_seed_scenario_1_c1_s01"), std::string::npos);
}

TEST(Inspect, BadConfigIsInputError) {
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --config closed=nope").exit_code, 2);
    EXPECT_EQ(run_hsnc("inspect " + kSeed1 + " --format pdf").exit_code, 2);
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
