// Running the built `hsnc` binary from tests, as a user would.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace hsnc::testing {

struct CliRun {
    int exit_code = -1;
    std::string out, err;
};

inline std::string slurp(const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

/// A fresh path in the test's temporary directory (unique per process and call,
/// so `ctest -j` runs never share files).
/// A fresh path in the test temp directory. Process ids come back (pid_max is
/// 32768 here), so a file an earlier run left under the same name is removed:
/// a "no file written" check must never see a stale one.
inline std::string temp_path(const std::string& name) {
    static int counter = 0;
    const std::string path =
        ::testing::TempDir() + "hsnc_" + std::to_string(::getpid()) + "_" + std::to_string(++counter) + "_" + name;
    std::remove(path.c_str());
    return path;
}

/// Run `hsnc ARGS` (ARGS already shell-quoted), capturing stdout and stderr.
/// `env` (e.g. "HOME=/x") is set for the process. The persistent kernel cache
/// defaults to the build tree's test-cache/ (XDG_CACHE_HOME), never the user's.
inline CliRun run_hsnc(const std::string& args, const std::string& env = "") {
    const std::string out = temp_path("stdout"), err = temp_path("stderr");
    const std::string command = std::string("XDG_CACHE_HOME='") + HSNC_TEST_CACHE_HOME + "' " + env + " '" +
                                HSNC_BINARY + "' " + args + " >'" + out + "' 2>'" + err + "'";
    const int status = std::system(command.c_str());
    CliRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    std::remove(out.c_str());
    std::remove(err.c_str());
    return r;
}

/// Start `hsnc ARGS` (one argument each, no shell) in the background with
/// stdout to `out` and stderr to `err` ("/dev/null" for none), SIGINT and
/// SIGTERM at their defaults as from an interactive shell; its pid (the
/// caller signals and waits for it), or -1.
inline pid_t spawn_hsnc(const std::vector<std::string>& args, const std::string& out, const std::string& err) {
    const pid_t pid = ::fork();
    if (pid != 0) return pid;
    ::setenv("XDG_CACHE_HOME", HSNC_TEST_CACHE_HOME, 1);
    const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(o, 1);
    ::dup2(e, 2);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    std::vector<char*> argv{const_cast<char*>("hsnc")};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(HSNC_BINARY, argv.data());
    ::_exit(127);
}

inline std::string model_path(const std::string& file) { return std::string(HSNC_SOURCE_DIR) + "/models/" + file; }

inline std::string write_temp(const std::string& name, const std::string& text) {
    const std::string path = temp_path(name);
    std::ofstream(path) << text;
    return path;
}

inline bool file_exists(const std::string& path) { return std::ifstream(path).good(); }

/// The events CSV of `hsnc simulate MODEL FLAGS --events FILE`, as bytes; ""
/// (with a test failure) when the run does not exit 0.
inline std::string events_csv(const std::string& model, const std::string& flags) {
    const std::string out = temp_path("events.csv");
    const CliRun r = run_hsnc("simulate " + model + " " + flags + " --events " + out);
    EXPECT_EQ(r.exit_code, 0) << flags << ": " << r.err;
    const std::string bytes = r.exit_code == 0 ? slurp(out) : "";
    std::remove(out.c_str());
    return bytes;
}

}  // namespace hsnc::testing
