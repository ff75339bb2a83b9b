#include "cached_kernel_provider.h"

#include <chrono>
#include <cstdio>
#include <cstdint>
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

std::string cached_kernel_problem(const void* address, const Model& model, const Configuration& cfg,
                                  const LoadedObject* object) {
    if (!address) return "no such symbol";
    if (reinterpret_cast<std::uintptr_t>(address) % alignof(hsnc_kernel) != 0) return "misaligned";
    const auto& k = *static_cast<const hsnc_kernel*>(address);
    if (k.abi_version != HSNC_KERNEL_ABI_VERSION)
        return "ABI version " + std::to_string(k.abi_version) + ", not " + std::to_string(HSNC_KERNEL_ABI_VERSION);
    if (k.n_switch < 0 || k.n_coef < 0 || k.n_dof < 0 || k.n_slider < 0 || k.n_param != 0) return "impossible sizes";
    if (object) {  // every pointer inside the object before anything is read through it
        for (const char* text : {k.model_name, k.config_spec, k.config_key, k.generator_version})
            if (!object->contains_string(text)) return "strings outside the object";
        if (!object->contains(k.switches, static_cast<std::size_t>(k.n_switch) * sizeof(hsnc_switch)) ||
            reinterpret_cast<std::uintptr_t>(k.switches) % alignof(hsnc_switch) != 0)
            return "a switch list outside the object";
        if (!object->contains_code(reinterpret_cast<const void*>(k.setup)) ||
            !object->contains_code(reinterpret_cast<const void*>(k.eval)))
            return "functions outside the code";
    }
    if (!k.setup || !k.eval || !k.config_key || !k.switches) return "null pointers";
    if (k.model_hash != model_hash(model) || k.n_dof != static_cast<int>(model.dof()) ||
        k.n_slider != static_cast<int>(model.jenkins.size()))
        return "built for another model";
    if (std::strcmp(k.config_key, cfg.key().c_str()) != 0)
        return std::string("built for configuration '") + k.config_key + "'";
    const std::vector<SwitchFunction> expected = switch_functions(model, cfg);
    bool same = expected.size() == static_cast<std::size_t>(k.n_switch);
    for (std::size_t f = 0; same && f < expected.size(); ++f)
        same = static_cast<int>(expected[f].kind) == k.switches[f].kind && expected[f].element == k.switches[f].element;
    if (!same) return "other switch functions";
    return "";
}

std::string cached_object_problem(const std::string& payload, const std::string& symbol, const Model& model,
                                  const Configuration& cfg) {
#if defined(__x86_64__)
    std::string why;
    const std::unique_ptr<LoadedObject> object = LoadedObject::load(payload, why);
    if (!object) return "not a loadable object: " + why;
    const std::string problem = cached_kernel_problem(object->symbol(symbol, sizeof(hsnc_kernel)), model, cfg,
                                                      object.get());
    return problem.empty() ? "" : "not the kernel " + symbol + " (" + problem + ")";
#else
    (void)payload, (void)symbol, (void)model, (void)cfg;
    return "";
#endif
}

CachedKernelProvider::CachedKernelProvider(const Model& model, JitSolverProvider::SourceFn source, JitOptions options,
                                           JitFactory make_jit)
    : model_(model),
      source_(std::move(source)),
      options_(std::move(options)),
      make_jit_(std::move(make_jit)),
      hash_(model_hash(model)),
      index_key_(model_canonical_text(model)) {
    const std::string distrust = KernelCache::trust_problem(options_.cache_dir);
    if (!distrust.empty()) {
        const std::string text = "kernel cache " + distrust + "; running without the cache";
        if (options_.warn)
            options_.warn(text);
        else
            std::fprintf(stderr, "hsnc: warning: %s\n", text.c_str());
        options_.cache_dir.clear();
        refused_ = true;
    }
}

CachedKernelProvider::~CachedKernelProvider() = default;

SegmentSolver* CachedKernelProvider::load_object(const Configuration& cfg, const std::string& key,
                                                 const std::string& symbol) {
    if (options_.cache_dir.empty()) return nullptr;
    const KernelCache::Entry entry = cache().load(key);
    if (entry.status != KernelCache::Status::hit) return nullptr;
    std::string why;
    std::unique_ptr<LoadedObject> object = LoadedObject::load(entry.payload, why);
    const void* kernel = object ? object->symbol(symbol, sizeof(hsnc_kernel)) : nullptr;
    // The kernel says what it was built for: it must be this model and
    // configuration. Else the JIT warns, recompiles and rewrites the entry.
    if (!object || !cached_kernel_problem(kernel, model_, cfg, object.get()).empty()) return nullptr;
    SegmentSolver* s =
        solvers_.emplace(cfg, std::make_unique<KernelSolver>(*static_cast<const hsnc_kernel*>(kernel))).first->second.get();
    objects_.emplace(cfg, std::move(object));
    return s;
}

void CachedKernelProvider::record_index(const std::string& index, const std::string& key,
                                        const std::string& symbol) const {
    if (!index.empty() && !options_.cache_dir.empty())
        cache().store(index, key + " " + symbol, kCacheIndexExtension);  // best effort
}

SegmentSolver* CachedKernelProvider::cached(const Configuration& cfg) {
    auto it = all_.find(cfg);
    return it != all_.end() ? it->second : load_by_index(cfg, index_key_(cfg.key()));
}

SegmentSolver* CachedKernelProvider::load_by_index(const Configuration& cfg, const std::string& index) {
    const auto start = std::chrono::steady_clock::now();
    if (index.empty() || options_.cache_dir.empty()) return nullptr;  // a refused cache has no directory
    // Its payload: "<object key> <kernel symbol>".
    const KernelCache::Entry by_index = cache().load(index, kCacheIndexExtension);
    const std::size_t space = by_index.payload.find(' ');
    if (by_index.status != KernelCache::Status::hit || space == std::string::npos) return nullptr;
    SegmentSolver* s = load_object(cfg, by_index.payload.substr(0, space), by_index.payload.substr(space + 1));
    if (!s) return nullptr;
    load_seconds_ += seconds_since(start);
    ++hits_;
    ++index_hits_;
    return all_.emplace(cfg, s).first->second;
}

SegmentSolver& CachedKernelProvider::solver(const Configuration& cfg) {
    auto it = all_.find(cfg);
    if (it != all_.end()) return *it->second;

    // 1. By the index: no derivation at all.
    const std::string index = index_key_(cfg.key());
    if (SegmentSolver* s = load_by_index(cfg, index)) return *s;

    // 2. By the source's key.
    auto start = std::chrono::steady_clock::now();
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
                  per_kernel(load, hits), refused_ ? "refused" : dir.empty() ? "unwritable" : dir.c_str(),
                  jit_ ? "" : " (LLVM not loaded)");
    return text;
}

}  // namespace hsnc
