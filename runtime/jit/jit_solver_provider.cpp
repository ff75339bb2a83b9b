#include "jit_solver_provider.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "cached_kernel_provider.h"  // cached_object_problem
#include "error.h"
#include "kernel_solver.h"
#include "model_hash.h"

namespace hsnc {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

JitSolverProvider::JitSolverProvider(const Model& model, SourceFn source, JitOptions options)
    : model_(model),
      source_(std::move(source)),
      options_(std::move(options)),
      cache_dir_(options_.cache_dir),
      hash_(model_hash(model)),
      jit_(std::make_unique<Jit>()) {
    const std::string distrust = KernelCache::trust_problem(cache_dir_);
    if (!cache_dir_.empty() && !distrust.empty()) {
        warn("kernel cache " + distrust + "; running without the cache");
        cache_dir_.clear();
    }
}

JitSolverProvider::~JitSolverProvider() = default;

void JitSolverProvider::warn(const std::string& text) const {
    if (options_.warn)
        options_.warn(text);
    else
        std::fprintf(stderr, "hsnc: warning: %s\n", text.c_str());
}

SegmentSolver& JitSolverProvider::solver(const Configuration& cfg) {
    auto it = cache_.find(cfg);
    if (it != cache_.end()) return *it->second;

    auto start = std::chrono::steady_clock::now();
    const JitKernelSource unit = source_(cfg);
    emit_seconds_ += seconds_since(start);

    // The persistent cache first: a hit skips Clang and code generation.
    start = std::chrono::steady_clock::now();
    const std::string name = unit.symbol + ".cpp";
    const std::string key = jit_->cache_key(unit.source);
    bool loaded = false;
    const hsnc_kernel* kernel = nullptr;
    if (!cache_dir_.empty()) {
        const KernelCache cache(cache_dir_, options_.cache_max_bytes);
        KernelCache::Entry entry = cache.load(key);
        // Whole, but is it this kernel? Checked before LLVM sees it: symbols a
        // wrong object defined in the JIT could not be defined again.
        if (entry.status == KernelCache::Status::hit) entry.problem = cached_object_problem(entry.payload, unit.symbol, model_, cfg);
        if (entry.status == KernelCache::Status::hit && entry.problem.empty()) {
            try {
                jit_->add_object(name, entry.payload);
                kernel = static_cast<const hsnc_kernel*>(jit_->lookup(unit.symbol));
                const std::string problem = cached_kernel_problem(kernel, model_, cfg, nullptr);
                if (!problem.empty()) entry.problem = "not the kernel " + unit.symbol + " (" + problem + ")";
                loaded = entry.problem.empty();
            } catch (const RunError& e) {
                entry.problem = e.what();
            }
        }
        if (!entry.problem.empty()) entry.status = KernelCache::Status::bad;
        if (entry.status == KernelCache::Status::bad) {
            ++rebuilt_;
            warn("kernel cache entry " + cache.path_of(key) + " is unusable (" + entry.problem +
                 "); recompiling it");
        }
    }
    if (loaded) {
        ++hits_;
    } else {
        // The object names its key, so that `hsnc cache --stats` can tell it
        // from another kernel's object without the model.
        const std::string object = jit_->compile(name, unit.source + jit_key_definition(key));
        jit_->add_object(name, object);
        ++compiled_;
        if (!cache_dir_.empty()) {
            const std::string problem = KernelCache(cache_dir_, options_.cache_max_bytes).store(key, object);
            if (!problem.empty()) {
                warn("kernel cache: " + problem + "; running without the cache");
                cache_dir_.clear();
            }
        }
    }
    if (!loaded) kernel = static_cast<const hsnc_kernel*>(jit_->lookup(unit.symbol));
    (loaded ? load_seconds_ : compile_seconds_) += seconds_since(start);

    // The kernel says what it was built for: it must be this model and configuration.
    if (kernel->abi_version == HSNC_KERNEL_ABI_VERSION &&
        (kernel->model_hash != hash_ || std::strcmp(kernel->config_key, cfg.key().c_str()) != 0))
        throw RunError("JitSolverProvider::solver(): kernel '" + unit.symbol + "' is for configuration '" +
                       kernel->config_key + "', not '" + cfg.key() + "' of model '" + model_.name + "'");
    return *cache_.emplace(cfg, std::make_unique<KernelSolver>(*kernel)).first->second;
}

std::string JitSolverProvider::describe() const {
    auto per_kernel = [](double seconds, std::size_t n) { return n ? 1e3 * seconds / static_cast<double>(n) : 0.0; };
    char text[600];
    std::snprintf(text, sizeof text,
                  "JIT: %zu configurations visited, %zu kernels compiled (derive+emit %.3f s, compile %.3f s, "
                  "%.1f ms per kernel), %zu cache hits (load %.3f s, %.2f ms per kernel), %s%s",
                  cache_.size(), compiled_, emit_seconds_, compile_seconds_, per_kernel(compile_seconds_, compiled_),
                  hits_, load_seconds_, per_kernel(load_seconds_, hits_),
                  options_.cache_dir.empty() ? "no cache" : "cache ",
                  options_.cache_dir.empty() ? "" : (cache_dir_.empty() ? "unwritable" : cache_dir_.c_str()));
    return text;
}

}  // namespace hsnc

extern "C" __attribute__((visibility("default"))) hsnc::SolverProvider* hsnc_jit_create_provider(
    const hsnc::Model& model, hsnc::JitSolverProvider::SourceFn source, const hsnc::JitOptions& options) {
    return new hsnc::JitSolverProvider(model, std::move(source), options);
}
