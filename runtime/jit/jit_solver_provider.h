// hsnc -- JitSolverProvider: a kernel compiled in-process (runtime/jit/jit.h) for
// each configuration a run enters, the first time it enters it (--kernels jit),
// or loaded from a persistent cache of compiled kernels (runtime/jit/kernel_cache.h)
// when an earlier run compiled the same source with the same compiler.
//
// The kernel source comes from a callback, so that the runtime needs neither
// GiNaC nor the generator: the command line passes one that derives and emits
// (generator/derivation.h, generator/emitter.h). Lives in the hsnc_jit library
// with jit.cpp; hsnc_runtime stays free of LLVM.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "jit.h"
#include "kernel_cache.h"
#include "solver_provider.h"

namespace hsnc {

/// What the callback gives for one configuration.
struct JitKernelSource {
    std::string symbol;  ///< name of its extern "C" hsnc_kernel object
    std::string source;  ///< the translation unit (includes only "kernel_abi.h")
};

/// Where compiled kernels persist, and where warnings go.
struct JitOptions {
    /// Directory of the persistent cache; "" for none (every kernel compiled).
    std::string cache_dir;
    /// Its size limit: storing a kernel evicts the least recently used
    /// entries beyond it (KernelCache::store); 0 for none.
    std::uint64_t cache_max_bytes = kDefaultCacheMaxBytes;
    /// Receives one line per problem that does not stop the run (a damaged
    /// cache entry, an unwritable cache); default: "hsnc: warning: ..." on stderr.
    std::function<void(const std::string&)> warn;
};

class JitSolverProvider : public SolverProvider {
public:
    using SourceFn = std::function<JitKernelSource(const Configuration&)>;

    /// `model` must outlive the provider. Throws RunError when LLVM cannot
    /// target the host.
    JitSolverProvider(const Model& model, SourceFn source, JitOptions options = {});
    JitSolverProvider(const Model&& model, SourceFn source, JitOptions options = {}) = delete;  ///< would dangle
    ~JitSolverProvider() override;

    /// The kernel of `cfg`, on first use emitted, then loaded from the
    /// persistent cache or compiled (and stored there). A cache entry that is
    /// truncated, corrupt, foreign, not loadable or not the kernel asked for
    /// (cached_object_problem) is reported through JitOptions::warn,
    /// recompiled and rewritten; a cache that cannot be written, or whose
    /// directory others can write to, is reported once and not used. Throws RunError when the
    /// source does not compile (Clang's diagnostics in the message) or the
    /// kernel is not the one asked for.
    SegmentSolver& solver(const Configuration& cfg) override;

    /// "JIT: 5 configurations visited, 3 kernels compiled (derive+emit 0.004 s,
    /// compile 0.060 s, 20.0 ms per kernel), 2 cache hits (load 0.002 s, 1.0 ms
    /// per kernel), cache /home/u/.cache/hsnc".
    std::string describe() const override;

    std::size_t configurations() const { return cache_.size(); }
    std::size_t kernels_compiled() const { return compiled_; }
    std::size_t cache_hits() const { return hits_; }
    std::size_t cache_rebuilt() const { return rebuilt_; }  ///< damaged entries recompiled
    double emit_seconds() const { return emit_seconds_; }        ///< in the callback
    double compile_seconds() const { return compile_seconds_; }  ///< Clang + LLVM code generation + JIT link
    double load_seconds() const { return load_seconds_; }        ///< cache hits: read, check, JIT link
    /// The cache directory in use ("" when none or disabled after a failure).
    const std::string& cache_dir() const { return cache_dir_; }

private:
    void warn(const std::string& text) const;

    const Model& model_;
    SourceFn source_;
    JitOptions options_;
    std::string cache_dir_;
    std::uint64_t hash_;
    std::unique_ptr<Jit> jit_;  // owns the kernels' code: declared before cache_ so it outlives the solvers
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;
    std::size_t compiled_ = 0, hits_ = 0, rebuilt_ = 0;
    double emit_seconds_ = 0, compile_seconds_ = 0, load_seconds_ = 0;
};

/// The entry point `hsnc` looks up after dlopen()ing libhsnc_jit.so; returns a
/// new JitSolverProvider (the caller owns it). Exceptions propagate.
using JitProviderFactory = SolverProvider* (*)(const Model& model, JitSolverProvider::SourceFn source,
                                               const JitOptions& options);
inline constexpr const char* kJitProviderFactorySymbol = "hsnc_jit_create_provider";

}  // namespace hsnc
