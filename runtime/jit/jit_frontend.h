// hsnc -- the Clang half of the JIT (runtime/jit/jit.h): C++ source -> LLVM IR.
//
// It lives in its own shared library, libhsnc_jit_clang.so, which Jit loads
// on its first compile, so that a run whose kernels all come from the
// persistent cache never loads libclang-cpp (about 5 ms of start-up). Only
// jit.cpp and jit_frontend.cpp include this header.
#pragma once

#include <string>
#include <vector>

namespace llvm {
class LLVMContext;
class Module;
}  // namespace llvm

namespace hsnc {

/// cc1 arguments after the triple. No system or builtin include paths: a
/// kernel includes only kernel_abi.h and calls only __builtin_ math.
/// -ffp-contract=off keeps a*b+c two roundings, as the ahead-of-time kernels
/// and the generic solver compute it, so all three agree to the last bit
/// wherever they can. -O2, measured (2-core AMD EPYC, seed-scenario-2 to
/// t = 30000 s, 420k segments): its kernels step as fast as the ahead-of-time
/// ones (0.60 s); -O0 compiles in 11 instead of 18 ms per kernel but steps 23%
/// slower, -O1 and -O3 compile no faster and step no faster than -O2.
inline const std::vector<const char*>& jit_compile_flags() {
    static const std::vector<const char*> flags = {"-x", "c++", "-std=c++17", "-O2", "-ffp-contract=off",
                                                   "-nostdsysteminc", "-nobuiltininc", "-w"};
    return flags;
}

/// Compile `source`, named `name` in diagnostics, for `triple` into a new
/// module of `context`. Returns nullptr with the reason in `error` (Clang's
/// diagnostics) when it does not compile; throws nothing.
using JitFrontendFn = llvm::Module* (*)(llvm::LLVMContext* context, const std::string& triple, const std::string& name,
                                        const std::string& source, std::string& error);
inline constexpr const char* kJitFrontendSymbol = "hsnc_jit_frontend_compile";

}  // namespace hsnc
