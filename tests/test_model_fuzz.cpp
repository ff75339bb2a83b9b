// Randomly mutated model files (from the bundled models/*.toml: truncation,
// byte flips, duplicated lines and so keys, huge numbers, deep nesting in
// expressions and in TOML) fed to parse_model in-process: each must give a
// Model or an InputError, never a crash, a hang or another exception type.
// Fixed seed, so a failure is reproducible; the failing text is printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "error.h"
#include "model_reader.h"

namespace hsnc {
namespace {

std::vector<std::string> bundled_models() {
    std::vector<std::string> texts;
    std::vector<std::filesystem::path> paths;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(HSNC_SOURCE_DIR) + "/models"))
        if (entry.path().extension() == ".toml") paths.push_back(entry.path());
    std::sort(paths.begin(), paths.end());  // directory order is not fixed; the seed's sequence must be
    for (const auto& p : paths) texts.push_back(testing::slurp(p.string()));
    return texts;
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t end = text.find('\n', start);
        lines.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
    std::string out;
    for (std::size_t i = 0; i < lines.size(); ++i) out += lines[i] + (i + 1 < lines.size() ? "\n" : "");
    return out;
}

std::string repeat(const std::string& s, std::size_t n) {
    std::string out;
    for (std::size_t i = 0; i < n; ++i) out += s;
    return out;
}

/// Values that stress the expression reader and the TOML parser.
std::vector<std::string> evil_values() {
    return {"1e400", "-1e400", "1e-400", "4.9e-324", "1e-310", "9223372036854775807", "-9223372036854775808",
            "99999999999999999999999999", "0x7fffffffffffffff", "nan", "-inf", "\"10^(10^10)\"",
            "\"2^(2^40)\"", "\"(1/3)^(10^9)\"", "\"factorial(10^7)\"", "\"sin(1e300)\"", "\"exp(1e6)\"",
            "\"1/0\"", "\"log(0)\"", "\"sqrt(-1)\"", "\"zeta(3)\"", "\"\"", "\"#\"", "\"((1)\"", "\"2^3^4\"",
            "\"" + repeat("(", 5000) + "1" + repeat(")", 5000) + "\"", "\"" + repeat("-", 5000) + "1\"",
            "\"" + repeat("sin(", 3000) + "1" + repeat(")", 3000) + "\"", "\"" + repeat("1+", 30000) + "1\"",
            repeat("[", 3000) + repeat("]", 3000), repeat("{a=", 3000) + "1" + repeat("}", 3000),
            "\"\xff\xfe\"", "\"\xc3\"", "[\"ground\", \"ground\"]", "{ m1 = \"1e999\" }", "true", "{}", "[]"};
}

std::string mutate(std::string text, std::mt19937& rng, const std::vector<std::string>& evil) {
    auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
    const int mutations = 1 + static_cast<int>(pick(3));
    for (int m = 0; m < mutations; ++m) {
        std::vector<std::string> lines = lines_of(text);
        switch (pick(6)) {
            case 0:  // truncate
                text = text.substr(0, pick(text.size() + 1));
                break;
            case 1:  // flip bits of a few bytes
                for (std::size_t k = 0, n = 1 + pick(4); k < n && !text.empty(); ++k)
                    text[pick(text.size())] ^= static_cast<char>(1 + pick(255));
                break;
            case 2: {  // duplicate a line (a key twice, a table header twice)
                const std::size_t i = pick(lines.size());
                lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size() + 1)), lines[i]);
                text = join_lines(lines);
                break;
            }
            case 3: {  // replace the value of an assignment with an evil one
                std::vector<std::size_t> assignments;
                for (std::size_t i = 0; i < lines.size(); ++i)
                    if (lines[i].find(" = ") != std::string::npos && lines[i][0] != '#') assignments.push_back(i);
                if (assignments.empty()) break;
                std::string& line = lines[assignments[pick(assignments.size())]];
                line = line.substr(0, line.find(" = ") + 3) + evil[pick(evil.size())];
                text = join_lines(lines);
                break;
            }
            case 4: {  // a new parameter or key with an evil value somewhere
                const std::string line = "fuzz" + std::to_string(pick(3)) + " = " + evil[pick(evil.size())];
                lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size() + 1)), line);
                text = join_lines(lines);
                break;
            }
            default: {  // delete a line
                if (lines.size() > 1) lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size())));
                text = join_lines(lines);
                break;
            }
        }
    }
    return text;
}

TEST(ModelFuzz, MutatedModelsGiveAModelOrAnInputError) {
    const std::vector<std::string> models = bundled_models();
    ASSERT_GE(models.size(), 5u);
    const std::vector<std::string> evil = evil_values();
    std::mt19937 rng(11);
    int models_read = 0, input_errors = 0;
    for (int i = 0; i < 400; ++i) {
        const std::string text = mutate(models[static_cast<std::size_t>(i) % models.size()], rng, evil);
        try {
            parse_model(text, "fuzz.toml");
            ++models_read;
        } catch (const InputError& e) {
            ++input_errors;
            const std::string message = e.what();
            EXPECT_EQ(message.rfind("fuzz.toml", 0), 0u) << "names the file: " << message.substr(0, 300);
            EXPECT_LT(message.size(), 2000u) << message.substr(0, 300);
        } catch (const std::exception& e) {
            ADD_FAILURE() << "iteration " << i << ": " << typeid(e).name() << ": " << e.what()
                          << "\nfor the text:\n" << text.substr(0, 2000);
        } catch (...) {
            ADD_FAILURE() << "iteration " << i << ": a non-standard exception\nfor the text:\n" << text.substr(0, 2000);
        }
    }
    // Both outcomes occur, so the mutations neither all break nor all miss.
    EXPECT_GT(models_read, 20);
    EXPECT_GT(input_errors, 100);
}

}  // namespace
}  // namespace hsnc
