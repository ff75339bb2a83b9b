// hsnc -- Jit: compile C++ source in-process and look up its symbols
// (Clang 14 -> LLVM IR -> ORC LLJIT). Used to build the kernel of each
// configuration a run visits (runtime/jit_solver_provider.h).
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
    /// diagnostics) and add it to the JIT. Throws RunError with Clang's
    /// diagnostics when it does not compile. Code is generated lazily, on the
    /// first lookup of one of its symbols.
    void add(const std::string& name, const std::string& source);

    /// Address of the (unmangled, C-linkage) symbol `symbol` of an added
    /// source; generates machine code on first use. Throws RunError when
    /// there is no such symbol.
    void* lookup(const std::string& symbol);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace hsnc
