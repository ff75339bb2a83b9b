// Front-end defects of issue 11 around reading a model and its flags:
// `--t-end` replacing an end time before t0, `generate -o ""`.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_runner.h"
#include "model_reader.h"

namespace hsnc {
namespace {

using testing::CliRun;
using testing::model_path;
using testing::run_hsnc;
using testing::write_temp;

const char* const kEndBeforeStart = R"toml(name = "end-before-start"
[parameters]
k = 100
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["ground", "m1"]
k = "k"
[initial]
t0 = 5
x = { m1 = 0.1 }
[simulate]
t_end = 1
)toml";

TEST(ReaderCli, TEndFlagReplacesAnEndTimeBeforeT0) {
    const std::string path = write_temp("end_before_start.toml", kEndBeforeStart);
    const CliRun ok = run_hsnc("simulate '" + path + "' --t-end 6 --quiet");
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(ok.err, "");
    // Without the flag the file's end time is used, and it is still an error.
    const CliRun bad = run_hsnc("simulate '" + path + "' --quiet");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_EQ(bad.err, "hsnc: " + path + ":14: key 'simulate.t_end': must be > t0 = 5, got 1\n");
    // And the flag is checked in its turn.
    const CliRun early = run_hsnc("simulate '" + path + "' --t-end 4 --quiet");
    EXPECT_EQ(early.exit_code, 2);
    EXPECT_EQ(early.err, "hsnc: --t-end 4: must be finite and after t0 = 5\n");
}

TEST(ReaderCli, GenerateRefusesAnEmptyOutputDirectory) {
    // Run from an empty directory, so that anything written there shows.
    const std::string dir = testing::temp_path("generate_cwd");
    std::filesystem::create_directories(dir);
    const std::filesystem::path cwd = std::filesystem::current_path();
    std::filesystem::current_path(dir);
    const CliRun r = run_hsnc("generate '" + model_path("coulomb-1dof.toml") + "' -o ''");
    std::filesystem::current_path(cwd);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "hsnc: generate: -o '': empty output directory (write -o . for the current directory)\n");
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hsnc
