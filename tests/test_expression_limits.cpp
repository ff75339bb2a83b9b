// The cost of reading a model is bounded (model/expression_evaluator.h):
// expressions that would overflow the stack (deep nesting) or compute exact
// numbers of billions of digits are refused with exit code 2 and a message
// naming file, line and key, and reading is linear in the number of
// parameters. Each case runs the built `hsnc check` under a generous time
// limit (`timeout`), so a regression shows as a failed exit code, not as a
// hung test; no wall-clock time is asserted.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "cli_runner.h"

namespace hsnc {
namespace {

using testing::CliRun;
using testing::slurp;
using testing::temp_path;
using testing::write_temp;

/// `hsnc ARGS` killed after `seconds` (exit code 137 then): a hang or a stack
/// overflow shows as an exit code other than the one expected.
CliRun run_bounded(const std::string& args, int seconds = 120) {
    const std::string out = temp_path("stdout"), err = temp_path("stderr");
    const std::string command = std::string("XDG_CACHE_HOME='") + HSNC_TEST_CACHE_HOME + "' timeout -s KILL " +
                                std::to_string(seconds) + " '" + HSNC_BINARY + "' " + args + " >'" + out + "' 2>'" +
                                err + "'";
    const int status = std::system(command.c_str());
    CliRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    std::remove(out.c_str());
    std::remove(err.c_str());
    return r;
}

/// A one-mass model whose parameter k (line 3) is `expression`.
std::string model_with_k(const std::string& expression) {
    return "name = \"t\"\n[parameters]\nk = \"" + expression +
           "\"\n[[mass]]\nname = \"m1\"\nm = 1\n[[spring]]\nbetween = [\"ground\", \"m1\"]\nk = \"k\"\n";
}

/// `hsnc check` of model_with_k(expression) exits 2 with one line naming
/// file, line 3 and key parameters.k, and containing `reason`.
void expect_refused(const std::string& expression, const std::string& reason) {
    SCOPED_TRACE(expression.substr(0, 60));
    const std::string path = write_temp("limit.toml", model_with_k(expression));
    const CliRun r = run_bounded("check '" + path + "'");
    EXPECT_EQ(r.exit_code, 2) << r.err.substr(0, 400);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err.rfind("hsnc: " + path + ":3: key 'parameters.k': expression '", 0), 0u) << r.err.substr(0, 400);
    EXPECT_NE(r.err.find(reason), std::string::npos) << r.err.substr(0, 400);
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line";
    EXPECT_LT(r.err.size(), 600u) << "the expression is shown as an excerpt";
}

std::string repeat(const std::string& s, int n) {
    std::string out;
    for (int i = 0; i < n; ++i) out += s;
    return out;
}

TEST(ExpressionLimits, DeepNestingIsRefusedNotACrash) {
    const std::string deep = "nests parentheses, function calls and signs more than 200 levels deep";
    expect_refused(repeat("(", 8000) + "1" + repeat(")", 8000), deep);
    expect_refused(repeat("-", 8000) + "1", deep);
    expect_refused(repeat("sin(", 8000) + "1" + repeat(")", 8000), deep);
    expect_refused(repeat("-(", 8000) + "1" + repeat(")", 8000), deep);
}

TEST(ExpressionLimits, HugeExactNumbersAreRefusedBeforeTheyAreComputed) {
    const std::string range = "is refused before evaluating it: a value in it is about 10^";
    expect_refused("10^(10^10)", range + "10000000000,");
    expect_refused("2^(2^40)", range + "330985980541,");
    expect_refused("(1/3)^(10^9)", range + "-477121255,");
    expect_refused("factorial(10^7)", range + "65657059,");
    expect_refused("exp(10^10)", range + "4342944819,");
    expect_refused("(2*I)^(10^9)", range + "301029995,");
    // Close to 1, so within range, but exact: billions of digits.
    expect_refused("(1000001/1000000)^(10^9)", "an exact number in it would have about 14602059991 digits");
    expect_refused("1" + std::string(1200, '0'), "has a number of more than 1000 characters");
}

TEST(ExpressionLimits, ReadingIsLinearInTheNumberOfParameters) {
    // 80000 parameters, each the one before plus 1, then an error on the last
    // line: the reader must get through all of them (quadratic reading took
    // 27 s for 20000 on the development machine, so many minutes for 80000).
    const int n = 80000;
    std::string text = "name = \"t\"\n[parameters]\np0 = 1\n";
    for (int i = 1; i < n; ++i) text += "p" + std::to_string(i) + " = \"p" + std::to_string(i - 1) + " + 1\"\n";
    text += "[[mass]]\nname = \"m1\"\nm = \"-p" + std::to_string(n - 1) + "\"\n";
    const std::string path = write_temp("chain.toml", text);
    const CliRun r = run_bounded("check '" + path + "'");
    EXPECT_EQ(r.exit_code, 2) << r.err.substr(0, 400);
    EXPECT_EQ(r.err, "hsnc: " + path + ":" + std::to_string(n + 5) + ": key 'mass[1].m': mass must be > 0, got -80000\n");
}

}  // namespace
}  // namespace hsnc
