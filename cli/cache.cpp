// `hsnc cache [--cache-dir DIR] --stats|--clear`: the persistent cache of
// compiled kernels (runtime/jit/kernel_cache.h). Plain file operations: LLVM is
// not loaded.
#include <ctime>
#include <iostream>
#include <memory>

#include "commands.h"
#include "error.h"
#include "kernel_cache.h"

namespace hsnc::cli {
namespace {

struct CacheOptions {
    std::string dir;
    bool stats = false, clear = false;
    std::uint64_t max_bytes = kDefaultCacheMaxBytes;
};

std::string utc_text(std::int64_t seconds) {
    const std::time_t t = static_cast<std::time_t>(seconds);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char text[40];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
    return text;
}

int cache(const CacheOptions& o) {
    const std::string dir = o.dir.empty() ? default_cache_dir() : o.dir;
    if (dir.empty()) throw InputError("--cache-dir: no cache directory: HOME and XDG_CACHE_HOME are unset; give --cache-dir");
    if (o.clear) {
        std::string problem;
        const std::size_t removed = KernelCache::clear(dir, problem);
        std::cout << "cache: " << dir << "\nremoved: " << removed << " files\n";
        if (!problem.empty()) throw RunError("cache --clear: " + problem);
        return 0;
    }
    const KernelCache::Stats s = KernelCache::stats(dir);
    const std::string distrust = KernelCache::trust_problem(dir);
    std::cout << "cache: " << dir << "\n";
    if (!distrust.empty()) std::cout << "refused: " << distrust << " (simulate does not use it)\n";
    std::cout << "entries: " << s.entries << "\n"
              << "damaged: " << s.damaged << "\n"
              << "index entries: " << s.index_entries << " (" << s.index_damaged << " damaged)\n"
              << "bytes: " << s.bytes << "\n"
              << "max bytes: " << o.max_bytes << (o.max_bytes ? "" : " (no limit)") << "\n";
    if (s.entries) std::cout << "oldest use: " << utc_text(s.oldest) << "\nnewest use: " << utc_text(s.newest) << "\n";
    for (const std::string& p : s.problems) std::cout << "damaged: " << p << "\n";
    return 0;
}

}  // namespace

void add_cache(CLI::App& app, int& exit_code) {
    auto o = std::make_shared<CacheOptions>();
    auto* sub = app.add_subcommand("cache", "the persistent cache of compiled kernels (--kernels jit)");
    sub->add_option("--cache-dir", o->dir, "the cache (default $XDG_CACHE_HOME/hsnc, else ~/.cache/hsnc)");
    sub->add_option_function<std::string>(
        "--cache-max-size", [o](const std::string& t) { o->max_bytes = parse_byte_size(t, "--cache-max-size"); },
        "the size limit --stats reports (give what simulate gets as --cache-max-size; default 256M)");
    auto* stats = sub->add_flag("--stats", o->stats, "directory, entries, damaged entries, bytes, oldest and newest");
    auto* clear = sub->add_flag("--clear", o->clear,
                                "remove the cached kernels and their index (only hsnc's *.hsncobj and *.hsncidx files)");
    stats->excludes(clear);
    sub->callback([o, &exit_code] {
        if (!o->stats && !o->clear) throw InputError("cache: give --stats or --clear");
        exit_code = cache(*o);
    });
}

}  // namespace hsnc::cli
