// hsnc -- JitSolverProvider: a kernel compiled in-process (runtime/jit.h) for
// each configuration a run enters, the first time it enters it (--kernels jit).
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

#include "engine.h"
#include "jit.h"

namespace hsnc {

/// What the callback gives for one configuration.
struct JitKernelSource {
    std::string symbol;  ///< name of its extern "C" hsnc_kernel object
    std::string source;  ///< the translation unit (includes only "kernel_abi.h")
};

class JitSolverProvider : public SolverProvider {
public:
    using SourceFn = std::function<JitKernelSource(const Configuration&)>;

    /// `model` must outlive the provider. Throws RunError when LLVM cannot
    /// target the host.
    JitSolverProvider(const Model& model, SourceFn source);
    ~JitSolverProvider() override;

    /// The cached kernel of `cfg`, emitted and compiled on first use. Throws
    /// RunError when the source does not compile (Clang's diagnostics in the
    /// message) or the kernel is not the one asked for.
    SegmentSolver& solver(const Configuration& cfg) override;

    /// "JIT: 5 configurations visited, 5 kernels compiled (derive+emit 0.1 s,
    /// compile 0.2 s, 40 ms per kernel)".
    std::string describe() const override;

    std::size_t configurations() const { return cache_.size(); }
    std::size_t kernels_compiled() const { return compiled_; }
    double emit_seconds() const { return emit_seconds_; }     ///< in the callback
    double compile_seconds() const { return compile_seconds_; }  ///< Clang + LLVM code generation

private:
    const Model& model_;
    SourceFn source_;
    std::uint64_t hash_;
    std::unique_ptr<Jit> jit_;  // owns the kernels' code: declared before cache_ so it outlives the solvers
    std::map<Configuration, std::unique_ptr<SegmentSolver>> cache_;
    std::size_t compiled_ = 0;
    double emit_seconds_ = 0, compile_seconds_ = 0;
};

/// The entry point `hsnc` looks up after dlopen()ing libhsnc_jit.so; returns a
/// new JitSolverProvider (the caller owns it). Exceptions propagate.
using JitProviderFactory = SolverProvider* (*)(const Model& model, JitSolverProvider::SourceFn source);
inline constexpr const char* kJitProviderFactorySymbol = "hsnc_jit_create_provider";

}  // namespace hsnc
