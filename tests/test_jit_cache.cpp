// The persistent cache of compiled kernels (runtime/jit/kernel_cache.h), through
// `hsnc simulate --kernels jit` as a user runs it and through `hsnc cache`:
// a second run hits the cache for every kernel and gives the same result; a
// truncated, corrupt or foreign entry is rebuilt with a warning; two processes
// filling one cache at once leave it whole; --no-cache writes nothing.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <chrono>
#include <regex>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "error.h"
#include "kernel_cache.h"

namespace hsnc {
namespace {

namespace fs = std::filesystem;

// An address-space limit for `hsnc`: were a device read without end, the
// process would stop at it instead of taking the machine's memory. Not under
// AddressSanitizer, whose shadow memory needs terabytes of address space.
#if defined(__SANITIZE_ADDRESS__)
constexpr const char* kMemoryLimit = "";
#else
constexpr const char* kMemoryLimit = " prlimit --as=8000000000";
#endif
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

    // generic interprets the programs the kernels were printed from: the same
    // bits; the Eigen solver, an independent path, agrees on the switches.
    const CliRun generic = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") +
                                    "' --set mu_k=0.31 --t-end 50 --kernels generic");
    ASSERT_EQ(generic.exit_code, 0) << generic.err;
    EXPECT_EQ(generic.out, first.out);
    const CliRun eigen = run_hsnc("simulate '" + model_path("seed-scenario-2.toml") +
                                  "' --set mu_k=0.31 --t-end 50 --kernels eigen");
    ASSERT_EQ(eigen.exit_code, 0) << eigen.err;
    EXPECT_EQ(eigen.out.substr(0, eigen.out.find(" x_")), first.out.substr(0, first.out.find(" x_")));
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
    EXPECT_NE(generic.err.find(", generic solver for 2 configurations (interpreted programs), "), std::string::npos)
        << generic.err;
    EXPECT_EQ(generic.err.find("JIT"), std::string::npos) << generic.err;
    EXPECT_FALSE(fs::exists(dir)) << "auto never compiles, so it never makes a cache";

    const CliRun jit = run_hsnc(edited + " --kernels jit --cache-dir '" + dir + "'");
    ASSERT_EQ(jit.exit_code, 0) << jit.err;
    EXPECT_NE(jit.err.find("JIT: 2 configurations visited"), std::string::npos) << jit.err;
    const auto events = [](const std::string& out) { return out.substr(out.find(" events="), out.find(" x_") - out.find(" events=")); };
    EXPECT_EQ(events(jit.out), events(generic.out)) << "the same switches of each kind";
    EXPECT_EQ(jit.out, generic.out) << "auto's generic path and the JIT: the same bits";

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

// ---- entries that are whole but wrong, or not files at all ------------------------

// The kernel symbol each object entry holds, from the index entries ("<key> <symbol>").
std::map<std::string, std::string> symbols_by_key(const std::string& dir) {
    std::map<std::string, std::string> symbols;
    for (const fs::path& p : entries(dir, ".hsncidx")) {
        const KernelCache::Entry e = KernelCache(dir).load(p.stem().string(), kCacheIndexExtension);
        const std::size_t space = e.payload.find(' ');
        if (e.status == KernelCache::Status::hit && space != std::string::npos)
            symbols[e.payload.substr(0, space)] = e.payload.substr(space + 1);
    }
    return symbols;
}

std::string payload_of(const std::string& dir, const std::string& key) {
    const KernelCache::Entry e = KernelCache(dir).load(key);
    EXPECT_EQ(e.status, KernelCache::Status::hit) << key << ": " << e.problem;
    return e.payload;
}

// A whole entry (header, key, checksum all fine) whose object is not the
// kernel of its key: the object of another configuration, the same
// configuration of another model (same symbol, other numbers), bytes that are
// no object. Each is rebuilt with a warning, and the next run hits them all.
TEST_F(CacheDir, WholeEntriesWithAWrongObjectAreRebuilt) {
    const CliRun first = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const std::map<std::string, std::string> symbol = symbols_by_key(dir);
    ASSERT_EQ(symbol.size(), 3u);
    const std::vector<std::string> keys = {symbol.begin()->first, std::next(symbol.begin())->first,
                                           symbol.rbegin()->first};
    // The kernels of a run with another friction coefficient: same symbols, another model hash.
    const std::string other = dir + "/other";
    ASSERT_EQ(run_hsnc("simulate '" + model_path("seed-scenario-2.toml") +
                       "' --set mu_k=0.32 --t-end 50 --kernels jit --quiet --cache-dir '" + other + "'")
                  .exit_code,
              0);
    std::string other_model;
    for (const auto& [key, sym] : symbols_by_key(other))
        if (sym == symbol.at(keys[1])) other_model = payload_of(other, key);
    ASSERT_FALSE(other_model.empty());
    fs::remove_all(other);

    const KernelCache cache(dir);
    ASSERT_EQ(cache.store(keys[0], payload_of(dir, keys[2])), "");  // another configuration's kernel
    ASSERT_EQ(cache.store(keys[1], other_model), "");                 // another model's kernel
    ASSERT_EQ(cache.store(keys[2], std::string(5000, '\x90')), "");   // no object at all
    for (const fs::path& p : entries(dir, ".hsncidx")) fs::remove(p);  // through the source keys

    const CliRun rebuilt = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.err;
    EXPECT_EQ(rebuilt.out, first.out);
    EXPECT_EQ(count_of(rebuilt.err, "kernels compiled"), 3u) << rebuilt.err;
    const std::string unusable = "hsnc: warning: kernel cache entry ";
    EXPECT_NE(rebuilt.err.find(unusable + cache.path_of(keys[0]) + " is unusable (not the kernel " + symbol.at(keys[0]) + " (no such symbol))"),
              std::string::npos)
        << rebuilt.err;
    EXPECT_NE(rebuilt.err.find(unusable + cache.path_of(keys[1]) + " is unusable (not the kernel " + symbol.at(keys[1]) + " (built for another model))"),
              std::string::npos)
        << rebuilt.err;
    EXPECT_NE(rebuilt.err.find(unusable + cache.path_of(keys[2]) + " is unusable (not a loadable object: not an ELF"),
              std::string::npos)
        << rebuilt.err;

    const CliRun again = run_hsnc(jit_run_args("--cache-dir '" + dir + "' --quiet"));
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.err, "") << "rewritten: all hits, no warning";
    EXPECT_EQ(again.out, first.out);
}

// A whole entry holding another kernel's object (header, key and checksum
// fine) was counted as a good entry by `cache --stats`, which has no model to
// check it against as a run does: the object names the key it was compiled
// for, and stats checks that name.
TEST_F(CacheDir, StatsCountsAnEntryHoldingAnotherKernelsObjectAsDamaged) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    const std::vector<fs::path> objects = entries(dir);
    ASSERT_EQ(objects.size(), 3u);
    const std::string key0 = objects[0].stem().string(), key2 = objects[2].stem().string();
    const CliRun good = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    EXPECT_NE(good.out.find("\nentries: 3\ndamaged: 0\n"), std::string::npos) << good.out;

    ASSERT_EQ(KernelCache(dir).store(key0, payload_of(dir, key2)), "");
    const CliRun stats = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    ASSERT_EQ(stats.exit_code, 0) << stats.err;
    EXPECT_NE(stats.out.find("\nentries: 2\ndamaged: 1\n"), std::string::npos) << stats.out;
    EXPECT_NE(stats.out.find("damaged: " + objects[0].string() + ": holds the object of key " + key2 + ", not " +
                             key0 + "\n"),
              std::string::npos)
        << stats.out;
}

// A FIFO (open would wait for a writer) and a link to /dev/zero (read would
// never end) in place of entries and index entries: refused unread, the
// kernels rebuilt and the files replaced by whole entries. Bounded by
// `timeout` and an address-space limit, so that the old behaviour fails the
// test instead of hanging it or exhausting memory.
TEST_F(CacheDir, FifoAndDeviceEntriesAreRebuiltNotRead) {
    const CliRun first = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const std::vector<fs::path> objects = entries(dir), index = entries(dir, ".hsncidx");
    ASSERT_EQ(objects.size(), 3u);
    ASSERT_EQ(index.size(), 3u);
    fs::remove(objects[0]);
    ASSERT_EQ(::mkfifo(objects[0].c_str(), 0600), 0);
    fs::remove(objects[1]);
    fs::create_symlink("/dev/zero", objects[1]);
    for (const fs::path& p : index) {
        fs::remove(p);
        ASSERT_EQ(::mkfifo(p.c_str(), 0600), 0);
    }
    const std::string bounded = std::string("timeout 60") + kMemoryLimit;
    const CliRun rebuilt = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"), bounded);
    ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.err << " (124: it hung)";
    EXPECT_EQ(rebuilt.out, first.out);
    EXPECT_EQ(count_of(rebuilt.err, "kernels compiled"), 2u) << rebuilt.err;
    for (int k : {0, 1})
        EXPECT_NE(rebuilt.err.find("hsnc: warning: kernel cache entry " + objects[k].string() +
                                   " is unusable (not a regular file); recompiling it"),
                  std::string::npos)
            << rebuilt.err;
    for (const fs::path& p : entries(dir, "")) EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(p))) << p;
    const CliRun again = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"), bounded);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_NE(again.err.find("3 cache hits (3 by index,"), std::string::npos) << "index entries rewritten: " << again.err;
    EXPECT_EQ(again.err.find("warning"), std::string::npos) << again.err;
}

// Index entries damaged in every way the cache can see (not an entry, whole
// but naming a key that does not exist, whole but naming another
// configuration's object): each run still finds every kernel, and rewrites
// them, so that the next run goes by the index again.
TEST_F(CacheDir, DamagedIndexEntriesAreRewritten) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    const std::vector<fs::path> index = entries(dir, ".hsncidx");
    ASSERT_EQ(index.size(), 3u);
    const KernelCache cache(dir);
    const std::string other = KernelCache(dir).load(index[2].stem().string(), kCacheIndexExtension).payload;
    std::ofstream(index[0]) << "garbage";
    ASSERT_EQ(cache.store(index[1].stem().string(), std::string(32, 'f') + " hsnc_kernel_x", kCacheIndexExtension), "");
    ASSERT_EQ(cache.store(index[2].stem().string(), other.substr(0, other.find(' ')) + " hsnc_kernel_y",
                          kCacheIndexExtension),
              "");
    const CliRun by_source = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(by_source.exit_code, 0) << by_source.err;
    EXPECT_NE(by_source.err.find("3 cache hits (0 by index,"), std::string::npos) << by_source.err;
    EXPECT_EQ(by_source.err.find("warning"), std::string::npos) << by_source.err;
    const CliRun by_index = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    EXPECT_NE(by_index.err.find("3 cache hits (3 by index,"), std::string::npos) << by_index.err;
}

// ---- trust: permissions, ownership; the size limit -----------------------------------

mode_t mode_of(const std::string& path) {
    struct stat st;
    return ::stat(path.c_str(), &st) == 0 ? st.st_mode & 07777 : 0;
}

TEST_F(CacheDir, TheCacheIsCreatedPrivate) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "/a/hsnc'"), "umask 000;").exit_code, 0);
    EXPECT_EQ(mode_of(dir + "/a/hsnc"), 0700u);
    for (const fs::path& p : entries(dir + "/a/hsnc", "")) EXPECT_EQ(mode_of(p.string()), 0600u) << p;
    EXPECT_EQ(entries(dir + "/a/hsnc", "").size(), 6u);
}

// A directory others can write to could hold a planted kernel that passes
// every header check: refused as a whole, with one warning; nothing read or written.
TEST_F(CacheDir, ADirectoryOthersCanWriteIsRefused) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    for (mode_t mode : {0777, 0720, 0702}) {
        ASSERT_EQ(::chmod(dir.c_str(), mode), 0);
        const std::vector<fs::path> before = entries(dir, "");
        const CliRun r = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        char octal[8];
        std::snprintf(octal, sizeof octal, "%04o", static_cast<unsigned>(mode));
        EXPECT_NE(r.err.find("hsnc: warning: kernel cache " + dir + " is group- or world-writable (mode " + octal +
                             "); running without the cache\n"),
                  std::string::npos)
            << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 2) << "one warning, one statistics line: " << r.err;
        EXPECT_EQ(count_of(r.err, "kernels compiled"), 3u) << "nothing read: " << r.err;
        EXPECT_EQ(entries(dir, ""), before) << "nothing written";
        const CliRun stats = run_hsnc("cache --stats --cache-dir '" + dir + "'");
        EXPECT_NE(stats.out.find("refused: " + dir + " is group- or world-writable"), std::string::npos) << stats.out;
    }
}

TEST_F(CacheDir, EntriesOthersCanWriteOrOwnAreRebuilt) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    const std::vector<fs::path> objects = entries(dir);
    ASSERT_EQ(objects.size(), 3u);
    ASSERT_EQ(::chmod(objects[0].c_str(), 0666), 0);
    const bool root = ::geteuid() == 0;
    if (root) ASSERT_EQ(::chown(objects[1].c_str(), 4242, 4242), 0);
    const CliRun r = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("kernel cache entry " + objects[0].string() +
                         " is unusable (group- or world-writable (mode 0666)); recompiling it"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(count_of(r.err, "kernels compiled"), root ? 2u : 1u) << r.err;
    EXPECT_EQ(mode_of(objects[0].string()), 0600u) << "rewritten as our own file";
    if (!root) GTEST_SKIP() << "ownership by another user is tested only as root (chown)";
    EXPECT_NE(r.err.find("kernel cache entry " + objects[1].string() + " is unusable (owned by uid 4242, not by this user"),
              std::string::npos)
        << r.err;
    struct stat st;
    ASSERT_EQ(::stat(objects[1].c_str(), &st), 0);
    EXPECT_EQ(st.st_uid, ::geteuid());
    // A directory of another user is refused as a whole.
    ASSERT_EQ(::chown(dir.c_str(), 4242, 4242), 0);
    const CliRun foreign = run_hsnc(jit_run_args("--cache-dir '" + dir + "'"));
    EXPECT_NE(foreign.err.find("hsnc: warning: kernel cache " + dir + " is owned by uid 4242, not by this user"),
              std::string::npos)
        << foreign.err;
    EXPECT_EQ(count_of(foreign.err, "kernels compiled"), 3u) << foreign.err;
}

TEST_F(CacheDir, StoreEvictsTheLeastRecentlyUsedBeyondTheLimit) {
    const KernelCache cache(dir, 3500);  // room for three entries of about 1000 bytes, not four
    const std::string payload(1000, 'p');
    for (const char* key : {"k1", "k2", "k3"}) ASSERT_EQ(cache.store(key, payload), "");
    // Last uses 300, 200 and 100 s ago (file times are too coarse to order stores made now).
    const auto now = std::chrono::system_clock::now();
    auto set_used = [&](const char* key, int seconds_ago) {
        const struct timespec t = {std::chrono::system_clock::to_time_t(now) - seconds_ago, 0};
        const struct timespec times[2] = {t, t};
        ASSERT_EQ(::utimensat(AT_FDCWD, cache.path_of(key).c_str(), times, 0), 0);
    };
    set_used("k1", 300);
    set_used("k2", 200);
    set_used("k3", 100);
    ASSERT_EQ(cache.load("k1").status, KernelCache::Status::hit);  // k1: used now
    ASSERT_EQ(cache.store("k4", payload), "");
    EXPECT_EQ(cache.load("k2").status, KernelCache::Status::miss) << "least recently used: evicted";
    for (const char* key : {"k1", "k3", "k4"}) EXPECT_EQ(cache.load(key).status, KernelCache::Status::hit) << key;
    // A limit below one entry keeps only the one just stored; 0 is no limit.
    ASSERT_EQ(KernelCache(dir, 10).store("k5", payload), "");
    EXPECT_EQ(entries(dir, "").size(), 1u);
    for (const char* key : {"k6", "k7", "k8", "k9"}) ASSERT_EQ(KernelCache(dir, 0).store(key, payload), "");
    EXPECT_EQ(entries(dir, "").size(), 5u);
    EXPECT_EQ(KernelCache::evict(dir, 2500), 3u);
}

TEST_F(CacheDir, SimulateKeepsTheCacheUnderItsSizeLimit) {
    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    std::uint64_t largest = 0, total = 0;
    for (const fs::path& p : entries(dir, "")) {
        largest = std::max<std::uint64_t>(largest, fs::file_size(p));
        total += fs::file_size(p);
    }
    fs::remove_all(dir);
    const std::uint64_t limit = total - largest / 2;  // not all of them
    const CliRun r = run_hsnc(jit_run_args("--cache-dir '" + dir + "' --cache-max-size " + std::to_string(limit)));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::uint64_t kept = 0;
    for (const fs::path& p : entries(dir, "")) kept += fs::file_size(p);
    EXPECT_LE(kept, limit);
    EXPECT_GT(kept, 0u);
    const CliRun stats = run_hsnc("cache --stats --cache-max-size 64M --cache-dir '" + dir + "'");
    EXPECT_NE(stats.out.find("\nbytes: " + std::to_string(kept) + "\nmax bytes: 67108864\n"), std::string::npos)
        << stats.out;
    const CliRun bad = run_hsnc(jit_run_args("--cache-dir '" + dir + "' --cache-max-size 12X"));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_EQ(bad.err, "hsnc: --cache-max-size: '12X' is not a size (a number of bytes, or with K, M or G: 256M)\n");
}

TEST(ByteSize, ParsesBytesAndBinarySuffixes) {
    EXPECT_EQ(parse_byte_size("0", "x"), 0u);
    EXPECT_EQ(parse_byte_size("1000", "x"), 1000u);
    EXPECT_EQ(parse_byte_size("64k", "x"), 65536u);
    EXPECT_EQ(parse_byte_size("256M", "x"), 268435456u);
    EXPECT_EQ(parse_byte_size("2G", "x"), 2147483648u);
    for (const char* bad : {"", "M", "-1", "1.5G", "12X", "1e9", "9999999999999"}) {
        try {
            parse_byte_size(bad, "--opt");
            ADD_FAILURE() << bad;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), "--opt: '" + std::string(bad) + "' is not a size (a number of bytes, or with K, M or G: 256M)");
        }
    }
}

// 17179869184G is 2^64 bytes: shifted, it wrapped to 0, which means "no limit".
TEST(ByteSize, SizesBeyondTwoToTheSixtyFourAreRefusedNotWrapped) {
    EXPECT_EQ(parse_byte_size("17179869183G", "x"), std::uint64_t{17179869183} << 30);
    EXPECT_EQ(parse_byte_size("999999999999", "x"), 999999999999u);
    for (const char* big : {"17179869184G", "999999999999G", "17179869184GiB"}) {
        try {
            parse_byte_size(big, "--opt");
            ADD_FAILURE() << big;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("--opt: '" + std::string(big) + "' is too large (at most "),
                      std::string::npos)
                << e.what();
        }
    }
    const std::string flag = " --cache-max-size 17179869184G";
    for (const std::string& args : {"cache --stats" + flag, "simulate '" + model_path("seed-scenario-2.toml") + "'" + flag}) {
        const CliRun r = run_hsnc(args);
        EXPECT_EQ(r.exit_code, 2) << args << ": " << r.out;
        EXPECT_EQ(r.err, "hsnc: --cache-max-size: '17179869184G' is too large (at most 17179869183G)\n") << args;
    }
}

// ---- hsnc cache ------------------------------------------------------------------

TEST_F(CacheDir, CacheStatsAndClear) {
    const CliRun empty = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    ASSERT_EQ(empty.exit_code, 0) << empty.err;
    EXPECT_EQ(empty.out, "cache: " + dir +
                             "\nentries: 0\ndamaged: 0\nindex entries: 0 (0 damaged)\nbytes: 0\nmax bytes: 268435456\n");

    ASSERT_EQ(run_hsnc(jit_run_args("--quiet --cache-dir '" + dir + "'")).exit_code, 0);
    std::ofstream(dir + "/notes.txt") << "not ours";
    std::uint64_t bytes = 0;
    for (const fs::path& p : entries(dir, ""))
        if (p.extension() != ".txt") bytes += fs::file_size(p);
    const CliRun stats = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    ASSERT_EQ(stats.exit_code, 0) << stats.err;
    EXPECT_NE(stats.out.find("entries: 3\ndamaged: 0\nindex entries: 3 (0 damaged)\nbytes: " +
                             std::to_string(bytes) + "\nmax bytes: 268435456\noldest use: "),
              std::string::npos)
        << stats.out;
    EXPECT_NE(stats.out.find(" UTC\nnewest use: "), std::string::npos) << stats.out;

    // Damaged as load() sees it: cut short; whole but with bytes that are
    // no object (header and checksum fine); an index entry that names nothing.
    const std::vector<fs::path> objects = entries(dir);
    fs::resize_file(objects[0], 10);
    ASSERT_EQ(KernelCache(dir).store(objects[1].stem().string(), std::string(3000, 'x')), "");
    std::ofstream(entries(dir, ".hsncidx")[0]) << "garbage";
    const CliRun damaged = run_hsnc("cache --stats --cache-dir '" + dir + "'");
    EXPECT_NE(damaged.out.find("entries: 1\ndamaged: 2\nindex entries: 2 (1 damaged)\n"), std::string::npos)
        << damaged.out;
    EXPECT_NE(damaged.out.find("damaged: " + objects[0].string() + ": truncated (10 bytes)\n"), std::string::npos)
        << damaged.out;
    EXPECT_NE(damaged.out.find("damaged: " + objects[1].string() + ": not a loadable object: not an ELF file\n"),
              std::string::npos)
        << damaged.out;

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
