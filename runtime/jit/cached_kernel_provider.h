// hsnc -- CachedKernelProvider: JIT kernels (--kernels jit, or auto without
// ahead-of-time kernels) taken from the persistent cache without loading LLVM.
//
// For each configuration the run enters: look its kernel up by the index key
// (jit_index_key: the build ID of the object holding this code, the model's numbers and the
// configuration), which needs no derivation; else emit the kernel source
// (callback) and look it up by its key (jit_cache_key). When the cache holds a
// whole entry, map its object with LoadedObject (runtime/jit/object_loader.h) and
// record the index entry for the next run. Only when a
// kernel is missing, damaged or not loadable that way does it ask `make_jit`
// for a JitSolverProvider (which loads libhsnc_jit.so, that is LLVM) and hand
// that configuration to it: it warns about damage, compiles, rewrites the
// entry. So a run whose kernels are all cached never loads LLVM or Clang.
//
// A cache directory that others could write to (KernelCache::trust_problem)
// is not used at all: one warning, and every kernel is compiled.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "jit_solver_provider.h"
#include "kernel_cache.h"
#include "object_loader.h"
#include "solver_provider.h"

namespace hsnc {

/// Why `kernel` (the address of a symbol in a cached object, or null) cannot
/// serve configuration `cfg` of `model`: "" when it can, else e.g. "no such
/// symbol", "built for another model", "built for configuration 'c1_s00'". Checks everything a
/// kernel says about itself (ABI version, model hash, configuration key,
/// masses, switch functions, a folded kernel). With `object` (the loader's
/// mapping of that object), every pointer the kernel holds is first checked
/// to lie inside the object, its functions inside its code, so that a wrong
/// object is never read outside itself.
std::string cached_kernel_problem(const void* kernel, const Model& model, const Configuration& cfg,
                                  const LoadedObject* object);

/// Why the cached object `payload` cannot be the kernel `symbol` of `cfg`:
/// "" when the loader maps it and cached_kernel_problem finds nothing, else
/// "not a loadable object: REASON" or "not the kernel SYMBOL (PROBLEM)". On
/// x86-64 the loader takes every object the JIT makes, so a refusal is a
/// wrong object; elsewhere (no loader) "" (LLVM alone decides).
std::string cached_object_problem(const std::string& payload, const std::string& symbol, const Model& model,
                                  const Configuration& cfg);

class CachedKernelProvider : public SolverProvider {
public:
    /// Creates the JIT on the first kernel the cache cannot serve; throws
    /// RunError when it cannot (the run stops with that message).
    using JitFactory =
        std::function<std::unique_ptr<JitSolverProvider>(JitSolverProvider::SourceFn source, const JitOptions& options)>;

    /// `model` must outlive the provider; options.cache_dir must not be empty.
    CachedKernelProvider(const Model& model, JitSolverProvider::SourceFn source, JitOptions options,
                         JitFactory make_jit);
    CachedKernelProvider(const Model&& model, JitSolverProvider::SourceFn source, JitOptions options,
                         JitFactory make_jit) = delete;  ///< would dangle
    ~CachedKernelProvider() override;

    SegmentSolver& solver(const Configuration& cfg) override;

    /// The kernel of `cfg` when the cache's index holds it (no derivation, no
    /// compiler), else null; what solver() would load first.
    SegmentSolver* cached(const Configuration& cfg);

    /// The JIT's line (JitSolverProvider::describe) with this provider's cache
    /// hits added: "JIT: 5 configurations visited, 1 kernels compiled (...), 4
    /// cache hits (3 by index, load ...), cache DIR".
    std::string describe() const override;

    std::size_t configurations() const { return all_.size(); }
    std::size_t cache_hits() const { return hits_ + (jit_ ? jit_->cache_hits() : 0); }
    std::size_t kernels_compiled() const { return jit_ ? jit_->kernels_compiled() : 0; }
    /// Whether the JIT (LLVM) had to be loaded.
    bool jit_loaded() const { return jit_ != nullptr; }
    /// Whether the cache directory was refused (others can write to it): no
    /// kernel is read from it or stored in it.
    bool refused() const { return refused_; }

private:
    const Model& model_;
    JitSolverProvider::SourceFn source_;
    JitOptions options_;  // cache_dir cleared when the directory is refused
    JitFactory make_jit_;
    std::uint64_t hash_;
    JitIndexKeys index_key_;  // jit_index_key(model_canonical_text(model), .)
    std::map<Configuration, std::unique_ptr<LoadedObject>> objects_;  // the code: outlives solvers_
    std::map<Configuration, std::unique_ptr<SegmentSolver>> solvers_;
    std::map<Configuration, SegmentSolver*> all_;
    std::map<Configuration, JitKernelSource> emitted_;  // handed to the JIT, not emitted twice
    std::unique_ptr<JitSolverProvider> jit_;            // declared last: destroyed first
    /// The kernel the cache's index entry `index` names, mapped, or null.
    SegmentSolver* load_by_index(const Configuration& cfg, const std::string& index);
    /// The kernel in the object stored under `key`, mapped without LLVM, or null.
    SegmentSolver* load_object(const Configuration& cfg, const std::string& key, const std::string& symbol);
    void record_index(const std::string& index, const std::string& key, const std::string& symbol) const;
    KernelCache cache() const { return KernelCache(options_.cache_dir, options_.cache_max_bytes); }
    bool refused_ = false;  // the cache directory is not trustworthy: not used

    std::size_t hits_ = 0, index_hits_ = 0;
    double emit_seconds_ = 0, load_seconds_ = 0;
};

}  // namespace hsnc
