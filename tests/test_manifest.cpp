// Tests of the kernel set of a model with more than 64 configurations
// (generator/kernel_set.h): the manifest lists the configurations of the
// model's default run, and `--kernels aot` runs that default run.
#include <gtest/gtest.h>

#include <set>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "kernel_set.h"
#include "model_reader.h"
#include "transitions.h"

namespace {

using hsnc::testing::model_path;
using hsnc::testing::run_hsnc;

TEST(KernelSet, InitialConfigurationIsTheEnteredOne) {
    for (const char* file : {"seed-scenario-1.toml", "seed-scenario-2.toml", "chain-8.toml", "coulomb-1dof.toml"}) {
        const hsnc::Model model = hsnc::read_model(model_path(file));
        std::vector<signed char> sgn;
        EXPECT_EQ(hsnc::initial_configuration(model),
                  hsnc::entered_configuration(model, model.t0, model.x0.data(), model.v0.data(), sgn))
            << file;
    }
}

TEST(KernelSet, Chain8ManifestHasTheDefaultRunsConfigurations) {
    const hsnc::Model model = hsnc::read_model(model_path("chain-8.toml"));
    const hsnc::KernelSet set = hsnc::generate_kernel_set(model);
    std::istringstream in(set.manifest);
    std::string line;
    std::vector<std::string> specs;
    int comments = 0;
    while (std::getline(in, line)) {
        if (line.rfind("#", 0) == 0) {
            ++comments;
            continue;
        }
        specs.push_back(line);
        hsnc::Configuration::parse(model, line);  // every line is a valid spec
    }
    EXPECT_EQ(comments, 3);
    EXPECT_TRUE(std::is_sorted(specs.begin(), specs.end()));
    EXPECT_EQ(specs.size(), set.kernels.size());
    EXPECT_LE(specs.size(), hsnc::kMaxManifestConfigurations);
    const std::set<std::string> listed(specs.begin(), specs.end());
    EXPECT_TRUE(listed.count("closed= stuck=m4,m5,m6,m7,m8"));  // reached by the default run
    EXPECT_TRUE(listed.count(hsnc::initial_configuration(model).spec(model)));
    EXPECT_NE(set.manifest.find("visited by its default run to t_end = 20"), std::string::npos) << set.manifest;
}

TEST(KernelSet, SmallModelManifestListsEveryConfiguration) {
    const hsnc::Model model = hsnc::read_model(model_path("seed-scenario-1.toml"));
    const hsnc::KernelSet set = hsnc::generate_kernel_set(model);
    EXPECT_NE(set.manifest.find("# all 8 configurations\n"), std::string::npos) << set.manifest;
    EXPECT_EQ(set.kernels.size(), 8u);
}

TEST(SimulateCli, Chain8DefaultRunWithAotKernelsOnly) {
    const auto r = run_hsnc(model_path("chain-8.toml").insert(0, "simulate ") + " --kernels aot");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("status=ok"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" t=20 "), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("generic solver for 0 configurations"), std::string::npos) << r.err;
}

}  // namespace
