// hsnc -- Jit: compile C++ source in-process and look up its symbols
// (Clang 14 -> LLVM IR -> ORC LLJIT). Used to build the kernel of each
// configuration a run visits (runtime/jit/jit_solver_provider.h).
//
// All LLVM and Clang headers stay inside jit.cpp; this header exposes none, so
// only the hsnc_jit library links against LLVM. Every LLVM Error/Expected is
// handled at this boundary and thrown as hsnc::RunError with Clang's
// diagnostics in the message. The source may `#include "kernel_abi.h"`, which
// is served from a copy embedded at build time (no file system access, no
// temporary files, no external compiler).
#pragma once

#include <memory>
#include <string>

namespace hsnc {

class Jit {
public:
    /// A JIT for the host. Throws RunError when LLVM cannot target the host.
    Jit();
    ~Jit();
    Jit(const Jit&) = delete;
    Jit& operator=(const Jit&) = delete;

    /// Compile `source` (C++17, -O2) under the name `name` (used in
    /// diagnostics) and add it to the JIT: add_object(name, compile(name, source)).
    void add(const std::string& name, const std::string& source);

    /// Compile `source` to an object file for this host (the bytes of a
    /// relocatable ELF object, what the JIT would generate itself). Throws
    /// RunError with Clang's diagnostics when it does not compile.
    std::string compile(const std::string& name, const std::string& source);

    /// Add an object file made by compile() (here or in an earlier process:
    /// a cached one) to the JIT. Throws RunError when `object` is not an
    /// object file for this host; the JIT is then unchanged.
    void add_object(const std::string& name, const std::string& object);

    /// The key of compile(source)'s result in a persistent cache:
    /// jit_cache_key(source) (runtime/jit/kernel_cache.h).
    std::string cache_key(const std::string& source) const;

    /// Address of the (unmangled, C-linkage) symbol `symbol` of an added
    /// source; generates machine code on first use. Throws RunError when
    /// there is no such symbol.
    void* lookup(const std::string& symbol);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace hsnc
