// The persistent cache of compiled kernels (runtime/kernel_cache.h), through
// `hsnc simulate --kernels jit` as a user runs it and through `hsnc cache`:
// a second run hits the cache for every kernel and gives the same result; a
// truncated, corrupt or foreign entry is rebuilt with a warning; two processes
// filling one cache at once leave it whole; --no-cache writes nothing.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "kernel_cache.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using testing::model_path;
using testing::run_hsnc;

// Scenario 2 with a friction coefficient of its own: not a bundled model any
// more (no ahead-of-time kernels), so every configuration is compiled. 50 s
// visit 3 configurations with 587 switches.
std::string jit_run_args(const std::string& cache_flags) {
    return "simulate '" + model_path("seed-scenario-2.toml") + "' --set mu_k=0.31 --t-end 50 --kernels jit " +
           cache_flags;
}

// "N kernels compiled" and "N cache hits" from the statistics line.
std::size_t count_of(const std::string& err, const std::string& what) {
    std::smatch m;
    if (!std::regex_search(err, m, std::regex("([0-9]+) " + what))) return static_cast<std::size_t>(-1);
    return std::stoul(m[1]);
}

// The files of `dir` with extension `ext` ("" for all), sorted.
std::vector<fs::path> entries(const std::string& dir, const std::string& ext = ".hsncobj") {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
        if (ext.empty() || e.path().extension() == ext) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

// What `command` (sh) prints on stdout; a failure to run it fails the test.
std::string shell_output(const std::string& command) {
    std::string text;
    std::FILE* p = ::popen(command.c_str(), "r");
    if (!p) ADD_FAILURE() << "cannot run " << command;
    if (!p) return text;
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
    EXPECT_EQ(::pclose(p), 0) << command << ": " << text;
    return text;
}

class CacheDir : public ::testing::Test {
protected:
    void TearDown() override { fs::remove_all(dir); }
    std::string dir = testing::temp_path("kernel-cache");
};

// ---- KernelCache: the file format -------------------------------------------

TEST_F(CacheDir, StoreThenLoadGivesThePayloadBack) {
    const KernelCache cache(dir + "/a/b");  // created on the first store
    EXPECT_EQ(cache.load("k1").status, KernelCache::Status::miss);
    const std::string payload("\x7f" "ELF\0\1\2 object bytes", 20);
    ASSERT_EQ(cache.store("k1", payload), "");
    const KernelCache::Entry e = cache.load("k1");
    ASSERT_EQ(e.status, KernelCache::Status::hit) << e.problem;
    EXPECT_EQ(e.payload, payload);
    EXPECT_EQ(entries(dir + "/a/b", "").size(), 1u) << "no temporary file left behind";
}

TEST_F(CacheDir, DamagedEntriesAreToldApartAndNeverLoaded) {
    const KernelCache cache(dir);
    const std::string payload(1000, 'x');
    ASSERT_EQ(cache.store("k1", payload), "");
    const std::string good = testing::slurp(cache.path_of("k1"));
    auto load_with = [&](const std::string& bytes) {
        std::ofstream(cache.path_of("k1"), std::ios::binary | std::ios::trunc) << bytes;
        return cache.load("k1");
    };
    KernelCache::Entry e = load_with(good.substr(0, good.size() - 1));
    EXPECT_EQ(e.status, KernelCache::Status::bad);
    EXPECT_NE(e.problem.find("truncated"), std::string::npos) << e.problem;
    e = load_with(good.substr(0, 10));
    EXPECT_EQ(e.status, KernelCache::Status::bad);
    EXPECT_NE(e.problem.find("truncated (10 bytes)"), std::string::npos) << e.problem;
    e = load_with(good + "z");
    EXPECT_NE(e.problem.find("too long"), std::string::npos) << e.problem;
    std::string flipped = good;
    flipped[flipped.size() - 7] ^= 1;
    e = load_with(flipped);
    EXPECT_EQ(e.status, KernelCache::Status::bad);
    EXPECT_NE(e.problem.find("checksum"), std::string::npos) << e.problem;
    e = load_with("#!/bin/sh\necho not a kernel, but long enough for a header\n");
    EXPECT_NE(e.problem.find("not an hsnc cache entry"), std::string::npos) << e.problem;
    // A whole entry, but of another key (copied, or a hash collision of names).
    ASSERT_EQ(cache.store("k2", payload), "");
    e = load_with(testing::slurp(cache.path_of("k2")));
    EXPECT_NE(e.problem.find("holds the kernel of key k2, not k1"), std::string::npos) << e.problem;
    EXPECT_TRUE(e.payload.empty());
}

TEST_F(CacheDir, StoreIntoAnImpossibleDirectorySaysWhy) {
    std::ofstream(dir) << "a file, not a directory";
    const std::string problem = KernelCache(dir + "/sub").store("k", "x");
    EXPECT_NE(problem.find("cannot create directory " + dir + "/sub"), std::string::npos) << problem;
    fs::remove(dir);
}

// ---- hsnc simulate --kernels jit with a cache ---------------------------------

TEST_F(CacheDir, SecondRunHitsTheCacheForEveryKernel) {
    const CliRun first = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(first.exit_code, 0) << first.err;
    EXPECT_EQ(count_of(first.err, "kernels compiled"), 3u) << first.err;
    EXPECT_EQ(count_of(first.err, "cache hits"), 0u) << first.err;
    EXPECT_EQ(entries(dir).size(), 3u);
    EXPECT_EQ(first.err.find("warning"), std::string::npos) << first.err;

    const CliRun second = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(count_of(second.err, "kernels compiled"), 0u) << second.err;
    EXPECT_EQ(count_of(second.err, "cache hits"), 3u) << second.err;
    // The same machine code: the same result, to the last digit.
    EXPECT_EQ(second.out, first.out);
    EXPECT_NE(first.out.find("status=ok method=hsnc t=50 events=587 "), std::string::npos) << first.out;

    EXPECT_NE(second.err.find("(LLVM not loaded)"), std::string::npos) << second.err;
    // Found by the index (this executable, the model's numbers, the
    // configuration): nothing derived or emitted.
    EXPECT_NE(second.err.find("3 cache hits (3 by index,"), std::string::npos) << second.err;
    EXPECT_NE(second.err.find("(derive+emit 0.000 s,"), std::string::npos) << second.err;
    EXPECT_EQ(entries(dir, ".hsncidx").size(), 3u);
    // A damaged index is only slower: the kernels are found by their source,
    // silently, and the index is written again.
    for (const fs::path& p : entries(dir, ".hsncidx")) std::ofstream(p) << "garbage";
    const CliRun by_source = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(by_source.exit_code, 0) << by_source.err;
    EXPECT_EQ(by_source.out, first.out);
    EXPECT_EQ(count_of(by_source.err, "cache hits"), 3u) << by_source.err;
    EXPECT_EQ(by_source.err.find("warning"), std::string::npos) << by_source.err;
    EXPECT_NE(by_source.err.find("3 cache hits (0 by index,"), std::string::npos) << by_source.err;
    const CliRun by_index = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    EXPECT_NE(by_index.err.find("3 cache hits (3 by index,"), std::string::npos) << by_index.err;
    EXPECT_EQ(by_index.out, first.out);
    // All hits: neither LLVM nor Clang is loaded (the dynamic loader's own account).
    const CliRun traced = run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'"), "LD_DEBUG=files");
    EXPECT_NE(traced.err.find("libm.so"), std::string::npos) << "the trace should list what is loaded";
    EXPECT_EQ(traced.err.find("libLLVM"), std::string::npos) << "LLVM loaded although every kernel was cached";
    EXPECT_EQ(traced.err.find("libclang-cpp"), std::string::npos) << "Clang loaded although every kernel was cached";

    // And the generic solver, an independent path, agrees on the switches.
    const CliRun generic = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") +
                                    "' --set mu_k=0.31 --t-end 50 --kernels generic");
    ASSERT_EQ(generic.exit_code, 0) << generic.err;
    EXPECT_EQ(generic.out.substr(0, generic.out.find(" x_")), first.out.substr(0, first.out.find(" x_")));
}

TEST_F(CacheDir, TruncatedAndForeignEntriesAreRebuiltWithAWarning) {
    const CliRun first = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const std::vector<fs::path> files = entries(dir);
    ASSERT_EQ(files.size(), 3u);
    const std::string bytes0 = testing::slurp(files[0].string());

    // Entry 0 cut in half, entry 1 replaced by entry 2 (a whole entry of another key).
    fs::resize_file(files[0], fs::file_size(files[0]) / 2);
    fs::copy_file(files[2], files[1], fs::copy_options::overwrite_existing);
    const CliRun rebuilt = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.err;
    EXPECT_EQ(rebuilt.out, first.out);
    EXPECT_EQ(count_of(rebuilt.err, "kernels compiled"), 2u) << rebuilt.err;
    EXPECT_EQ(count_of(rebuilt.err, "cache hits"), 1u) << rebuilt.err;
    EXPECT_NE(rebuilt.err.find("hsnc: warning: kernel cache entry " + files[0].string() + " is unusable (truncated"),
              std::string::npos)
        << rebuilt.err;
    EXPECT_NE(rebuilt.err.find("hsnc: warning: kernel cache entry " + files[1].string() +
                               " is unusable (holds the kernel of key"),
              std::string::npos)
        << rebuilt.err;
    EXPECT_EQ(testing::slurp(files[0].string()), bytes0) << "rewritten whole";

    const CliRun again = run_hsnc(jit_run_args("--cache-dir '" + dir + "' --quiet"));
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.err, "") << "all hits, no warning";
    EXPECT_EQ(again.out, first.out);
}

TEST_F(CacheDir, TwoProcessesFillingOneCacheAtOnceLeaveItWhole) {
    // Both start cold on the same keys and race to write the same 3 files.
    const std::string out1 = testing::temp_path("out1"), out2 = testing::temp_path("out2");
    const std::string run = std::string("XDG_CACHE_HOME=/nonexistent '") + HSNC_BINARY + "' " +
                            jit_run_args("--cache-dir '" + dir + "' --quiet");
    const std::string both = "(" + run + " >'" + out1 + "' 2>&1 & " + run + " >'" + out2 + "' 2>&1 & wait)";
    ASSERT_EQ(std::system(both.c_str()), 0);
    const std::string text1 = testing::slurp(out1), text2 = testing::slurp(out2);
    std::remove(out1.c_str());
    std::remove(out2.c_str());
    EXPECT_NE(text1.find("status=ok method=hsnc t=50 events=587 "), std::string::npos) << text1;
    EXPECT_EQ(text1, text2);

    EXPECT_EQ(entries(dir).size(), 3u);
    EXPECT_EQ(entries(dir, "").size(), 6u) << "three entries, their index entries, and no temporary files";
    const CliRun third = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(third.exit_code, 0) << third.err;
    EXPECT_EQ(count_of(third.err, "cache hits"), 3u) << third.err;
    EXPECT_EQ(third.err.find("warning"), std::string::npos) << third.err;
    EXPECT_EQ(third.out, text1);
}

TEST_F(CacheDir, NoCacheWritesNothingAndAnUnwritableCacheIsAWarning) {
    const CliRun none = run_hsnc(jit_run_args("--no-cache"), "XDG_CACHE_HOME='" + dir + "'");
    ASSERT_EQ(none.exit_code, 0) << none.err;
    EXPECT_EQ(count_of(none.err, "kernels compiled"), 3u) << none.err;
    EXPECT_NE(none.err.find("no cache"), std::string::npos) << none.err;
    EXPECT_FALSE(fs::exists(dir));

    std::ofstream(dir) << "a file where the cache directory should be";
    const CliRun blocked = run_hsnc(jit_run_args("--cache-dir '" + dir + "/hsnc'"));
    ASSERT_EQ(blocked.exit_code, 0) << blocked.err;
    EXPECT_EQ(blocked.out, none.out);
    EXPECT_NE(blocked.err.find("hsnc: warning: kernel cache: cannot create directory " + dir +
                               "/hsnc: Not a directory; running without the cache"),
              std::string::npos)
        << blocked.err;
    EXPECT_EQ(blocked.err.find("warning", blocked.err.find("warning") + 1), std::string::npos) << "warned once";

    const CliRun both = run_hsnc(jit_run_args("--no-cache --cache-dir /tmp"));
    EXPECT_EQ(both.exit_code, 2) << both.err;
    EXPECT_NE(both.err.find("excludes"), std::string::npos) << both.err;
}

TEST_F(CacheDir, DefaultDirectoryFollowsXdgThenHome) {
    const CliRun xdg = run_hsnc(jit_run_args("--quiet"), "XDG_CACHE_HOME='" + dir + "/xdg'");
    ASSERT_EQ(xdg.exit_code, 0) << xdg.err;
    EXPECT_EQ(entries(dir + "/xdg/hsnc").size(), 3u);
    // An empty (or relative) XDG_CACHE_HOME is ignored, as the XDG spec says.
    const CliRun home = run_hsnc(jit_run_args("--quiet"), "XDG_CACHE_HOME= HOME='" + dir + "/home'");
    ASSERT_EQ(home.exit_code, 0) << home.err;
    EXPECT_EQ(entries(dir + "/home/.cache/hsnc").size(), 3u);
    EXPECT_EQ(home.out, xdg.out);
}

// ---- --kernels auto -----------------------------------------------------------

// auto: the ahead-of-time kernels when the model has them, else the generic
// solver; it never compiles, never touches the cache and does not need
// libhsnc_jit.so. Only --kernels jit loads the JIT module.
TEST_F(CacheDir, AutoUsesAotKernelsElseGenericAndNeverTheJit) {
    const CliRun bundled = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") + "' --t-end 5 --cache-dir '" +
                                    dir + "'");
    ASSERT_EQ(bundled.exit_code, 0) << bundled.err;
    EXPECT_NE(bundled.err.find("ahead-of-time kernels"), std::string::npos) << bundled.err;
    EXPECT_FALSE(fs::exists(dir));

    const std::string edited = "simulate '" + model_path("seed-scenario-2.toml") + "' --set mu_k=0.31 --t-end 5";
    const CliRun generic = run_hsnc(edited + " --cache-dir '" + dir + "'");
    ASSERT_EQ(generic.exit_code, 0) << generic.err;
    EXPECT_NE(generic.err.find(", generic solver for 2 configurations, "), std::string::npos) << generic.err;
    EXPECT_EQ(generic.err.find("JIT"), std::string::npos) << generic.err;
    EXPECT_FALSE(fs::exists(dir)) << "auto never compiles, so it never makes a cache";

    const CliRun jit = run_hsnc(edited + " --kernels jit --cache-dir '" + dir + "'");
    ASSERT_EQ(jit.exit_code, 0) << jit.err;
    EXPECT_NE(jit.err.find("JIT: 2 configurations visited"), std::string::npos) << jit.err;
    const auto events = [](const std::string& out) { return out.substr(out.find(" events="), out.find(" x_") - out.find(" events=")); };
    EXPECT_EQ(events(jit.out), events(generic.out)) << "the same switches of each kind";

    // An hsnc without libhsnc_jit.so beside it: auto runs as before, without
    // a word about the JIT; --kernels jit is a failure that says why.
    fs::create_directories(dir + "/bin");
    fs::copy_file(HSNC_BINARY, dir + "/bin/hsnc");
    const std::string lone = "'" + dir + "/bin/hsnc' " + edited;
    EXPECT_EQ(shell_output(lone + " --quiet"), generic.out);
    EXPECT_EQ(shell_output(lone + " 2>&1 >/dev/null | grep -c -e note -e JIT; true"), "0\n");
    const std::string failed = shell_output(lone + " --kernels jit --cache-dir '" + dir + "' 2>&1; echo exit=$?");
    EXPECT_NE(failed.find("hsnc: hsnc::simulate(): kernels = jit: cannot load the JIT module: "), std::string::npos)
        << failed;
    EXPECT_NE(failed.find("exit=1"), std::string::npos) << failed;
}

// ---- hsnc cache ------------------------------------------------------------------

TEST_F(CacheDir, CacheStatsAndClear) {
    const CliRun empty = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    ASSERT_EQ(empty.exit_code, 0) << empty.err;
    EXPECT_EQ(empty.out, "cache: " + dir + "\nentries: 0\ndamaged: 0\nbytes: 0\n");

    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    std::ofstream(dir + "/notes.txt") << "not ours";
    std::uint64_t bytes = 0;
    for (const fs::path& p : entries(dir))
        if (p.extension() == ".hsncobj") bytes += fs::file_size(p);
    const CliRun stats = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    ASSERT_EQ(stats.exit_code, 0) << stats.err;
    EXPECT_NE(stats.out.find("entries: 3\ndamaged: 0\nbytes: " + std::to_string(bytes) + "\noldest: "),
              std::string::npos)
        << stats.out;
    EXPECT_NE(stats.out.find(" UTC\nnewest: "), std::string::npos) << stats.out;

    fs::resize_file(entries(dir)[0], 10);
    const CliRun damaged = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    EXPECT_NE(damaged.out.find("entries: 2\ndamaged: 1\n"), std::string::npos) << damaged.out;

    const CliRun clear = run_hsnc("cache --clear --cache-dir '" + dir + "'");
    ASSERT_EQ(clear.exit_code, 0) << clear.err;
    EXPECT_EQ(clear.out, "cache: " + dir + "\nremoved: 6 files\n") << "3 kernels and their index entries";
    EXPECT_EQ(entries(dir, "").size(), 1u) << "notes.txt stays";
    EXPECT_TRUE(fs::exists(dir + "/notes.txt"));

    // The default directory is the one simulate uses.
    const CliRun xdg = run_hsnc("cache --stats", "XDG_CACHE_HOME='" + dir + "'");
    EXPECT_EQ(xdg.out.substr(0, xdg.out.find('\n')), "cache: " + dir + "/hsnc");
}

TEST(CacheCli, HelpAndBadFlags) {
    const CliRun help = run_hsnc("cache --help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("--stats"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("--clear"), std::string::npos) << help.out;
    for (const char* args : {"cache", "cache --stats --clear", "cache --frobnicate", "cache --stats extra"}) {
        const CliRun r = run_hsnc(args);
        EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
        EXPECT_EQ(r.out, "") << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n') <= 2, true) << args << ": " << r.err;
    }
    EXPECT_NE(run_hsnc("cache").err.find("cache: give --stats or --clear"), std::string::npos);
}

}  // namespace
}  // namespace hsnc
