#include "cached_kernel_provider.h"

#include <chrono>
#include <cstdio>
#include <cstring>

#include "kernel_cache.h"
#include "kernel_solver.h"
#include "model_hash.h"

namespace hsnc {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

CachedKernelProvider::CachedKernelProvider(const Model& model, JitSolverProvider::SourceFn source, JitOptions options,
                                           JitFactory make_jit)
    : model_(model),
      source_(std::move(source)),
      options_(std::move(options)),
      make_jit_(std::move(make_jit)),
      hash_(model_hash(model)),
      model_text_(model_canonical_text(model)) {}

CachedKernelProvider::~CachedKernelProvider() = default;

SegmentSolver* CachedKernelProvider::load_object(const Configuration& cfg, const std::string& key,
                                                 const std::string& symbol) {
    const KernelCache::Entry entry = KernelCache(options_.cache_dir).load(key);
    if (entry.status != KernelCache::Status::hit) return nullptr;
    std::string why;
    std::unique_ptr<LoadedObject> object = LoadedObject::load(entry.payload, why);
    const auto* kernel =
        object ? static_cast<const hsnc_kernel*>(object->symbol(symbol, sizeof(hsnc_kernel))) : nullptr;
    // The kernel says what it was built for: it must be this model and configuration.
    if (!kernel || kernel->abi_version != HSNC_KERNEL_ABI_VERSION || kernel->model_hash != hash_ ||
        std::strcmp(kernel->config_key, cfg.key().c_str()) != 0)
        return nullptr;
    SegmentSolver* s = solvers_.emplace(cfg, std::make_unique<KernelSolver>(*kernel)).first->second.get();
    objects_.emplace(cfg, std::move(object));
    return s;
}

void CachedKernelProvider::record_index(const std::string& index, const std::string& key,
                                        const std::string& symbol) const {
    if (!index.empty()) KernelCache(options_.cache_dir).store(index, key + " " + symbol, kCacheIndexExtension);  // best effort
}

SegmentSolver& CachedKernelProvider::solver(const Configuration& cfg) {
    auto it = all_.find(cfg);
    if (it != all_.end()) return *it->second;

    // 1. By the index: no derivation at all.
    auto start = std::chrono::steady_clock::now();
    const std::string index = jit_index_key(model_text_, cfg.key());
    if (!index.empty()) {
        // Its payload: "<object key> <kernel symbol>".
        const KernelCache::Entry by_index = KernelCache(options_.cache_dir).load(index, kCacheIndexExtension);
        const std::size_t space = by_index.payload.find(' ');
        if (by_index.status == KernelCache::Status::hit && space != std::string::npos) {
            if (SegmentSolver* s =
                    load_object(cfg, by_index.payload.substr(0, space), by_index.payload.substr(space + 1))) {
                load_seconds_ += seconds_since(start);
                ++hits_;
                ++index_hits_;
                return *all_.emplace(cfg, s).first->second;
            }
        }
    }

    // 2. By the source's key.
    start = std::chrono::steady_clock::now();
    JitKernelSource unit = source_(cfg);
    emit_seconds_ += seconds_since(start);
    start = std::chrono::steady_clock::now();
    const std::string key = jit_cache_key(unit.source);
    if (SegmentSolver* s = load_object(cfg, key, unit.symbol)) {
        load_seconds_ += seconds_since(start);
        ++hits_;
        record_index(index, key, unit.symbol);
        return *all_.emplace(cfg, s).first->second;
    }

    // 3. Missing, damaged, or not for this loader: the JIT decides (and
    // warns, compiles, rewrites as it does on its own).
    if (!jit_) {
        jit_ = make_jit_(
            [this](const Configuration& c) {
                auto e = emitted_.find(c);
                return e != emitted_.end() ? e->second : source_(c);
            },
            options_);
    }
    const std::string symbol = unit.symbol;
    emitted_[cfg] = std::move(unit);
    SegmentSolver& s = jit_->solver(cfg);
    emitted_.erase(cfg);
    if (!jit_->cache_dir().empty()) record_index(index, key, symbol);  // the JIT has stored the object
    return *all_.emplace(cfg, &s).first->second;
}

std::string CachedKernelProvider::describe() const {
    auto per_kernel = [](double seconds, std::size_t n) { return n ? 1e3 * seconds / static_cast<double>(n) : 0.0; };
    const std::size_t compiled = kernels_compiled(), hits = cache_hits();
    const double compile = jit_ ? jit_->compile_seconds() : 0.0;
    const double load = load_seconds_ + (jit_ ? jit_->load_seconds() : 0.0);
    const double emit = emit_seconds_ + (jit_ ? jit_->emit_seconds() : 0.0);
    const std::string dir = jit_ ? jit_->cache_dir() : options_.cache_dir;
    char text[600];
    std::snprintf(text, sizeof text,
                  "JIT: %zu configurations visited, %zu kernels compiled (derive+emit %.3f s, compile %.3f s, "
                  "%.1f ms per kernel), %zu cache hits (%zu by index, load %.3f s, %.2f ms per kernel), cache %s%s",
                  all_.size(), compiled, emit, compile, per_kernel(compile, compiled), hits, index_hits_, load,
                  per_kernel(load, hits), dir.empty() ? "unwritable" : dir.c_str(),
                  jit_ ? "" : " (LLVM not loaded)");
    return text;
}

}  // namespace hsnc
