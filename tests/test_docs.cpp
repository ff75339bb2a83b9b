// The documentation says what runs. Every relative link of README.md,
// CONTRIBUTING.md and docs/ resolves (a file, and a heading when it names one);
// every command of their ```sh blocks runs and exits 0, and prints the ```text
// block that follows it when there is one (numbers to 1e-9); the ```python
// blocks of a file run as one script. Commands run from a scratch directory
// that sees the checkout's models/ and examples/ and the build as build/, so
// what they write stays there. Not run: the development scripts (.ci/, bench/,
// build/hsnc_* check programs, ctest), which CI runs itself or which write into
// the checkout; docs/development.md says so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>

#include "cli_runner.h"
#include "temp_dir.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;

const std::string source_dir = HSNC_SOURCE_DIR;

struct Block {
    int line = 0;  // of the opening fence
    std::string lang, text;
};

/// README.md, CONTRIBUTING.md and every Markdown file under docs/, relative to the checkout.
std::vector<std::string> doc_files() {
    std::vector<std::string> files = {"README.md", "CONTRIBUTING.md"};
    for (const auto& entry : fs::recursive_directory_iterator(source_dir + "/docs"))
        if (entry.is_regular_file() && entry.path().extension() == ".md")
            files.push_back(fs::relative(entry.path(), source_dir).string());
    std::sort(files.begin() + 2, files.end());
    return files;
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

/// The fenced blocks of a Markdown file, in order; the prose between them is dropped.
std::vector<Block> blocks_of(const std::string& rel) {
    std::vector<Block> blocks;
    const auto lines = lines_of(testing::slurp(source_dir + "/" + rel));
    for (std::size_t i = 0; i < lines.size(); ++i) {
        if (lines[i].rfind("```", 0) != 0) continue;
        Block b{static_cast<int>(i + 1), lines[i].substr(3), ""};
        for (++i; i < lines.size() && lines[i].rfind("```", 0) != 0; ++i) b.text += lines[i] + "\n";
        blocks.push_back(b);
    }
    return blocks;
}

/// The prose of a Markdown file: every line outside fenced blocks.
std::string prose_of(const std::string& rel) {
    std::string prose;
    bool fenced = false;
    for (const auto& line : lines_of(testing::slurp(source_dir + "/" + rel))) {
        if (line.rfind("```", 0) == 0)
            fenced = !fenced;
        else if (!fenced)
            prose += line + "\n";
    }
    return prose;
}

std::string trim(std::string s) {
    s.erase(0, s.find_first_not_of(" \t"));
    s.erase(s.find_last_not_of(" \t") + 1);
    return s;
}

/// GitHub's anchor of a heading: lower case, punctuation but '-' and '_' dropped, spaces to '-'.
std::string slug(const std::string& heading) {
    std::string s;
    for (const char c : heading) {
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')
            s += static_cast<char>(std::tolower(c));
        else if (c == ' ')
            s += '-';
    }
    return s;
}

std::set<std::string> anchors_of(const std::string& path) {
    std::set<std::string> anchors;
    bool fenced = false;
    for (const auto& line : lines_of(testing::slurp(path))) {
        if (line.rfind("```", 0) == 0) fenced = !fenced;
        if (fenced || line.empty() || line[0] != '#') continue;
        anchors.insert(slug(trim(line.substr(line.find_first_not_of('#')))));
    }
    return anchors;
}

TEST(Docs, EveryRelativeLinkResolves) {
    const std::regex link(R"(\]\(([^)\s]+)\))");
    int checked = 0;
    for (const auto& rel : doc_files()) {
        const std::string prose = prose_of(rel);
        const fs::path dir = fs::path(source_dir + "/" + rel).parent_path();
        for (std::sregex_iterator it(prose.begin(), prose.end(), link), e; it != e; ++it) {
            const std::string target = (*it)[1];
            if (target.find("://") != std::string::npos || target.rfind("mailto:", 0) == 0) continue;
            const auto hash = target.find('#');
            const std::string file = target.substr(0, hash);
            const fs::path resolved = file.empty() ? fs::path(source_dir + "/" + rel) : dir / file;
            ++checked;
            ASSERT_TRUE(fs::exists(resolved)) << rel << ": link to a missing file: " << target;
            if (hash == std::string::npos || resolved.extension() != ".md") continue;
            EXPECT_TRUE(anchors_of(resolved.string()).count(target.substr(hash + 1)))
                << rel << ": link to a missing heading: " << target;
        }
    }
    EXPECT_GT(checked, 50);  // the README alone links every guide page
}

// ---- commands ----

/// The commands of one ```sh block, run in order in one directory (a later one may read
/// what an earlier one wrote), and the ```text block right after it (empty when none).
struct DocCommand {
    std::string file;
    int line = 0;
    std::vector<std::string> commands;
    std::string expected;
};

// gtest looks the printer up by this name.
// NOLINTNEXTLINE(readability-identifier-naming)
void PrintTo(const DocCommand& c, std::ostream* os) {
    *os << c.file << ":" << c.line;
}

/// What a documented command line means here: "./build.sh && " is the set-up (the
/// suite runs after it), an aligned "  # ..." is a comment; empty when not run.
std::string runnable(std::string command) {
    const auto comment = command.find("  #");
    if (comment != std::string::npos) command = command.substr(0, comment);
    command = trim(command);
    const std::string setup = "./build.sh && ";
    if (command.rfind(setup, 0) == 0) command = command.substr(setup.size());
    for (const char* dev : {"ctest", ".ci/", "bench/", "build/hsnc_", "./build.sh"})
        if (command.rfind(dev, 0) == 0) return "";
    return command;
}

std::vector<DocCommand> doc_commands() {
    std::vector<DocCommand> commands;
    for (const auto& rel : doc_files()) {
        const auto blocks = blocks_of(rel);
        for (std::size_t b = 0; b < blocks.size(); ++b) {
            if (blocks[b].lang != "sh") continue;
            const auto lines = lines_of(blocks[b].text);
            DocCommand block{rel, blocks[b].line, {}, ""};
            for (std::size_t i = 0; i < lines.size(); ++i) {
                std::string command = lines[i];
                while (!command.empty() && command.back() == '\\' && i + 1 < lines.size())
                    command = command.substr(0, command.size() - 1) + " " + trim(lines[++i]);
                command = runnable(command);
                if (!command.empty()) block.commands.push_back(command);
            }
            if (block.commands.empty()) continue;
            if (b + 1 < blocks.size() && blocks[b + 1].lang == "text") block.expected = blocks[b + 1].text;
            commands.push_back(block);
        }
    }
    return commands;
}

/// A scratch directory seeing models/, examples/ and the build; docs/ is its own (commands draw into it).
struct Scratch {
    testing::TempDir dir;
    Scratch() {
        for (const char* name : {"models", "examples"})
            fs::create_directory_symlink(source_dir + "/" + name, dir / name);
        fs::create_directory_symlink(fs::path(HSNC_BINARY).parent_path(), dir / "build");
        fs::create_directory(dir / "docs");
    }
    testing::CliRun run(const std::string& command) const {
        const std::string env = std::string("XDG_CACHE_HOME='") + HSNC_TEST_CACHE_HOME + "' PYTHONPATH='" +
                                fs::path(HSNC_BINARY).parent_path().string() +
                                "/python' PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg";
        const std::string script = dir / "command.sh";
        std::ofstream(script) << "cd '" << dir.path() << "' || exit 99\n" << env << " timeout 300 " << command << "\n";
        const std::string out = dir / "stdout", err = dir / "stderr";
        const int status = std::system(("bash '" + script + "' >'" + out + "' 2>'" + err + "'").c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, testing::slurp(out), testing::slurp(err)};
    }
};

bool as_number(const std::string& s, double& value) {
    char* end = nullptr;
    value = std::strtod(s.c_str(), &end);
    return !s.empty() && end == s.c_str() + s.size();
}

/// Each key=value of the documented output against the printed one: text equal, numbers to 1e-9.
void expect_output(const std::string& expected, const std::string& printed) {
    const auto want = lines_of(expected), got = lines_of(printed);
    ASSERT_EQ(want.size(), got.size()) << "printed:\n" << printed;
    for (std::size_t i = 0; i < want.size(); ++i) {
        std::istringstream w(want[i]), g(got[i]);
        for (std::string a, b; w >> a;) {
            ASSERT_TRUE(static_cast<bool>(g >> b)) << "printed less than documented: " << got[i];
            const auto eq_a = a.find('='), eq_b = b.find('=');
            ASSERT_EQ(a.substr(0, eq_a), b.substr(0, eq_b)) << got[i];
            double x = 0, y = 0;
            const bool numbers =
                eq_a != std::string::npos && as_number(a.substr(eq_a + 1), x) && as_number(b.substr(eq_b + 1), y);
            if (numbers && std::isfinite(x))
                EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(x))) << a << " documented, " << b << " printed";
            else
                EXPECT_EQ(a, b);
        }
    }
}

class DocCommands : public ::testing::TestWithParam<DocCommand> {};

TEST_P(DocCommands, RunsAndPrintsWhatTheDocsShow) {
    const DocCommand& c = GetParam();
    const Scratch scratch;
    std::string printed;
    for (const auto& command : c.commands) {
        if (command.find("python3") != std::string::npos && !HSNC_WITH_PYTHON) GTEST_SKIP() << "built without Python";
        const auto r = scratch.run(command);
        ASSERT_EQ(r.exit_code, 0) << c.file << ":" << c.line << ": " << command << "\n" << r.err;
        printed += r.out;
    }
    if (!c.expected.empty()) expect_output(c.expected, printed);
}

std::string test_name(const ::testing::TestParamInfo<DocCommand>& info) {
    std::string name = info.param.file + "_" + std::to_string(info.param.line);
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return name;
}

INSTANTIATE_TEST_SUITE_P(Docs, DocCommands, ::testing::ValuesIn(doc_commands()), test_name);

TEST(Docs, CommandsAreFoundInEveryGuide) {
    std::set<std::string> files;
    for (const auto& c : doc_commands()) files.insert(c.file);
    for (const char* f : {"README.md", "docs/guide/analyses.md", "docs/guide/models.md", "docs/guide/simulate.md"})
        EXPECT_TRUE(files.count(f)) << f << " shows no command the suite runs";
}

TEST(Docs, PythonBlocksOfEachFileRunAsOneScript) {
    if (!HSNC_WITH_PYTHON) GTEST_SKIP() << "built without Python";
    int files = 0;
    for (const auto& rel : doc_files()) {
        std::string script;
        for (const auto& b : blocks_of(rel))
            if (b.lang == "python") script += b.text + "\n";
        if (script.empty()) continue;
        ++files;
        const Scratch scratch;
        std::ofstream(scratch.dir / "doc.py") << script;
        const auto r = scratch.run("/usr/bin/python3 doc.py");
        EXPECT_EQ(r.exit_code, 0) << rel << "'s Python blocks:\n" << r.err;
    }
    EXPECT_GE(files, 2);  // the README's tour and the library guide
}

// The tour's model is examples/hardening-stop.toml as it is, less its header comment.
TEST(Docs, ReadmeTourShowsTheExampleModel) {
    std::string file;
    for (const auto& line : lines_of(testing::slurp(source_dir + "/examples/hardening-stop.toml")))
        if (line.rfind("#", 0) != 0) file += line + "\n";
    bool shown = false;
    for (const auto& b : blocks_of("README.md")) shown = shown || (b.lang == "toml" && b.text == file);
    EXPECT_TRUE(shown) << "README's model block differs from examples/hardening-stop.toml";
}

}  // namespace
}  // namespace hsnc
