// hsnc -- loading the JIT module (libhsnc_jit.so, which links LLVM) at run
// time, only for KernelChoice::jit, so that nothing else ever loads LLVM.
// Private to the facade (not installed).
#pragma once

#include <memory>
#include <string>

#include "error.h"
#include "jit_solver_provider.h"

namespace hsnc::api {

/// The JIT module cannot be found or loaded.
struct JitUnavailable : RunError {
    using RunError::RunError;
};

/// Where libhsnc_jit.so is: beside the object this code is linked into (the
/// shared libhsnc.so, found with dladdr), or beside the executable when that
/// object is the executable itself (hsnc links the facade statically).
std::string jit_module_path();

/// A JitSolverProvider made by the module's factory. Throws JitUnavailable
/// when the module cannot be loaded; the module stays loaded (kernels live in it).
std::unique_ptr<JitSolverProvider> load_jit_provider(const Model& model, JitSolverProvider::SourceFn source,
                                                     const JitOptions& options);

}  // namespace hsnc::api
