#include "jit_module.h"

#include <utility>

#include "plugin_module.h"

namespace hsnc::api {

#ifdef HSNC_JIT_MODULE
std::string jit_module_path() { return plugin_module_path(HSNC_JIT_MODULE); }

std::unique_ptr<JitSolverProvider> load_jit_provider(const Model& model, JitSolverProvider::SourceFn source,
                                                     const JitOptions& options) {
    const std::string path = jit_module_path();
    std::string problem;
    auto factory = reinterpret_cast<JitProviderFactory>(
        plugin_module_symbol(path, kJitProviderFactorySymbol, SymbolScope::kLocal, problem));
    if (!factory) throw JitUnavailable("cannot load the JIT module: " + problem);
    // The factory makes a JitSolverProvider (runtime/jit/jit_solver_provider.cpp).
    return std::unique_ptr<JitSolverProvider>(
        static_cast<JitSolverProvider*>(factory(model, std::move(source), options)));
}

#else  // built with HSNC_WITH_JIT=OFF
std::string jit_module_path() { return ""; }
std::unique_ptr<JitSolverProvider> load_jit_provider(const Model&, JitSolverProvider::SourceFn, const JitOptions&) {
    throw JitUnavailable("this hsnc was built without the JIT (HSNC_WITH_JIT=OFF)");
}
#endif

}  // namespace hsnc::api
