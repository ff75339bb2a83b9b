// The README's quick start is what CI runs: two ```sh blocks right under
// "## Quick start", the main job first, and .ci/run calls the test command verbatim.
#include <gtest/gtest.h>

#include <regex>

#include "cli_runner.h"

namespace hsnc {
namespace {

TEST(Readme, QuickStartHasTwoCommandsAndCiRunsTheSecond) {
    const std::string readme = testing::slurp(std::string(HSNC_SOURCE_DIR) + "/README.md");
    const auto start = readme.find("## Quick start");
    ASSERT_NE(start, std::string::npos);
    const auto end = readme.find("\n## ", start + 1);
    const std::string section = readme.substr(start, end - start);
    const std::regex block("```sh\n([^\n]*)\n```");
    std::vector<std::string> commands;
    for (std::sregex_iterator it(section.begin(), section.end(), block), e; it != e; ++it)
        commands.push_back((*it)[1]);
    ASSERT_EQ(commands.size(), 2u);
    EXPECT_NE(commands[0].find("hsnc simulate models/seed-scenario-2.toml"), std::string::npos);
    EXPECT_NE(commands[1].find("ctest"), std::string::npos);
    const std::string ci = testing::slurp(std::string(HSNC_SOURCE_DIR) + "/.ci/run");
    EXPECT_NE(ci.find("\n" + commands[1] + "\n"), std::string::npos) << ".ci/run must run: " << commands[1];
}

}  // namespace
}  // namespace hsnc
